//! How a drawn scene's camera moves: still, on an arm (one smooth move),
//! or in a hand (a slow drift and a tremor).

use serde::{Deserialize, Serialize};

use upetrack::rng::SplitMix64;

use crate::ease::smoothstep;

/// Largest move of a camera on an arm, metres, and its largest turn, degrees.
pub const ARM_SHIFT_M: (f64, f64) = (0.02, 0.08);
/// Range of an arm's turn, degrees.
pub const ARM_TURN_DEG: (f64, f64) = (1.0, 5.0);
/// Range of a hand's slow drift, metres.
pub const HAND_DRIFT_M: (f64, f64) = (0.01, 0.03);
/// Range of a hand's slow turn, degrees.
pub const HAND_TURN_DEG: (f64, f64) = (0.5, 3.0);
/// Range of a hand's drift frequency, hertz (a person re-aiming).
pub const HAND_DRIFT_HZ: (f64, f64) = (0.15, 0.5);
/// Range of a hand's tremor, metres (physiological tremor is 4-12 Hz,
/// sub-millimetre to a few millimetres at the wrist).
pub const TREMOR_M: (f64, f64) = (0.0005, 0.002);
/// Range of a hand's tremor turn, degrees.
pub const TREMOR_DEG: (f64, f64) = (0.05, 0.3);
/// Range of the tremor's frequency, hertz.
pub const TREMOR_HZ: (f64, f64) = (4.0, 8.0);

/// One sinusoid per axis: amplitude, frequency (Hz) and phase.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Wobble {
    /// Amplitude per axis (metres for a shift, radians for a turn).
    pub amplitude: [f64; 3],
    /// Frequency, hertz.
    pub hz: f64,
    /// Phase per axis, radians.
    pub phase: [f64; 3],
}

impl Wobble {
    fn draw(rng: &mut SplitMix64, size: f64, hz: (f64, f64), flat: bool) -> Self {
        let mut amplitude = [0.0; 3];
        for (k, a) in amplitude.iter_mut().enumerate() {
            // A hand moves less along the line of sight than across it.
            let scale = if flat && k == 2 { 0.5 } else { 1.0 };
            *a = size * scale * rng.range(0.5, 1.0);
        }
        Self {
            amplitude,
            hz: rng.range(hz.0, hz.1),
            phase: [(); 3].map(|_| rng.range(0.0, core::f64::consts::TAU)),
        }
    }

    fn at(&self, t: f64) -> [f64; 3] {
        let w = core::f64::consts::TAU * self.hz * t;
        [0, 1, 2]
            .map(|k| self.amplitude[k] * (libm::sin(w + self.phase[k]) - libm::sin(self.phase[k])))
    }
}

/// How the camera moves; every position is relative to where the draw put it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum CameraPath {
    /// On a robot arm: one smooth move by `shift` (world, metres) and
    /// `turn` (camera axes, radians) between two frames, then still.
    Arm {
        /// Translation at the end of the move, metres.
        shift: [f64; 3],
        /// Turn about the camera's x, y, z at the end of the move, radians.
        turn: [f64; 3],
        /// Frame the move starts.
        start: usize,
        /// Frame the move ends.
        end: usize,
    },
    /// In a hand: a slow drift and a tremor, in position and in angle.
    Handheld {
        /// Slow drift of the position.
        drift: Wobble,
        /// Slow turn.
        drift_turn: Wobble,
        /// Tremor of the position.
        tremor: Wobble,
        /// Tremor of the angle.
        tremor_turn: Wobble,
    },
}

impl CameraPath {
    /// An arm's move over part of `frames` frames.
    pub(crate) fn draw_arm(rng: &mut SplitMix64, frames: usize) -> Self {
        let dir = unit(rng);
        let size = rng.range(ARM_SHIFT_M.0, ARM_SHIFT_M.1);
        let turn = rng.range(ARM_TURN_DEG.0, ARM_TURN_DEG.1).to_radians();
        let tdir = unit(rng);
        let start = (frames as f64 * rng.range(0.1, 0.5)) as usize;
        let end =
            (start + (frames as f64 * rng.range(0.2, 0.45)) as usize).min(frames.saturating_sub(1));
        Self::Arm {
            shift: [dir[0] * size, dir[1] * size, dir[2] * size * 0.5],
            turn: tdir.map(|d| d * turn),
            start,
            end: end.max(start + 1),
        }
    }

    /// A hand's drift and tremor.
    pub(crate) fn draw_handheld(rng: &mut SplitMix64) -> Self {
        let drift = rng.range(HAND_DRIFT_M.0, HAND_DRIFT_M.1);
        let turn = rng.range(HAND_TURN_DEG.0, HAND_TURN_DEG.1).to_radians();
        let tremor = rng.range(TREMOR_M.0, TREMOR_M.1);
        let tremor_turn = rng.range(TREMOR_DEG.0, TREMOR_DEG.1).to_radians();
        Self::Handheld {
            drift: Wobble::draw(rng, drift, HAND_DRIFT_HZ, true),
            drift_turn: Wobble::draw(rng, turn, HAND_DRIFT_HZ, false),
            tremor: Wobble::draw(rng, tremor, TREMOR_HZ, true),
            tremor_turn: Wobble::draw(rng, tremor_turn, TREMOR_HZ, false),
        }
    }

    /// The camera's shift (metres) and turn (radians) at frame `f` (or
    /// between frames) of a sequence at `fps` frames per second (a hand's
    /// wobble is timed in seconds, an arm's move in frames of the sequence).
    pub fn at(&self, f: f64, fps: f64) -> ([f64; 3], [f64; 3]) {
        match self {
            Self::Arm {
                shift,
                turn,
                start,
                end,
            } => {
                let x = smoothstep((f - *start as f64) / (end - start).max(1) as f64);
                (shift.map(|s| s * x), turn.map(|t| t * x))
            }
            Self::Handheld {
                drift,
                drift_turn,
                tremor,
                tremor_turn,
            } => {
                let t = f / fps;
                let add = |a: [f64; 3], b: [f64; 3]| [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
                (
                    add(drift.at(t), tremor.at(t)),
                    add(drift_turn.at(t), tremor_turn.at(t)),
                )
            }
        }
    }
}

/// A random unit vector.
fn unit(rng: &mut SplitMix64) -> [f64; 3] {
    loop {
        let v = [(); 3].map(|_| rng.range(-1.0, 1.0));
        let n = libm::sqrt(v.iter().map(|x| x * x).sum::<f64>());
        if n > 0.1 && n <= 1.0 {
            return v.map(|x| x / n);
        }
    }
}
