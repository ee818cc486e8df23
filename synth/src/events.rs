//! What happens in a scene over time: grasps moving particles along paths,
//! and occluder boxes moving (or riding on a grasp), frame by frame.

use upetrack::math::Vec3;

use crate::ease::smoothstep;
use crate::render::OccluderBox;

/// A grasp moving a particle from its settled position by `offset` between two frames.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Pull {
    pub(crate) particle: usize,
    pub(crate) start: usize,
    pub(crate) end: usize,
    /// World-frame displacement, or the swing radius for a circular path.
    pub(crate) offset: Vec3,
    pub(crate) circular: bool,
}

impl Pull {
    /// Where the grasp holds its particle at frame `f` (from `origin`, the
    /// particle's settled position), or `None` before it starts.
    pub(crate) fn target(&self, origin: Vec3, f: usize) -> Option<Vec3> {
        if f < self.start {
            return None;
        }
        let x = smoothstep((f - self.start) as f64 / (self.end - self.start).max(1) as f64);
        Some(if self.circular {
            // Lift first, then swing around a circle in the table plane.
            let lift = smoothstep(x * 4.0);
            let a = core::f64::consts::TAU * x;
            origin
                + Vec3::new(
                    self.offset.x * (libm::cos(a) - 1.0) * lift,
                    self.offset.x * libm::sin(a) * lift,
                    self.offset.z * lift,
                )
        } else {
            origin + self.offset * x
        })
    }
}

/// How an occluder box moves while it is in the scene.
#[derive(Debug, Clone, Copy)]
pub(crate) enum BoxPath {
    /// From its corners at the first frame by `travel` at the last, lifted
    /// by `bob sin(pi x)` on the way; `dwell` slows it over the middle of
    /// its path (position `0.5 + 0.5 (2x - 1)^3` instead of `x`).
    Linear { travel: Vec3, bob: f64, dwell: bool },
    /// Rides on grasp `pull` (corners relative to the grasp's target), and
    /// comes down from `descent` above over the `approach` frames before
    /// the grasp starts.
    Gripper {
        pull: usize,
        descent: f64,
        approach: usize,
    },
    /// Comes in from `from` (an offset from its corners) over the first
    /// `frames` frames, then stays.
    Enter { from: Vec3, frames: usize },
}

/// An occluder box over a frame range (inclusive).
#[derive(Debug, Clone, Copy)]
pub(crate) struct MovingBox {
    pub(crate) first: usize,
    pub(crate) last: usize,
    /// Corners at the start (world frame; relative to the grasp target for
    /// a gripper).
    pub(crate) shape: OccluderBox,
    pub(crate) path: BoxPath,
}

impl MovingBox {
    /// The box at frame `f` (within its range), given the scene's grasps
    /// (`pulls`, with their origins) and where they hold their particles
    /// at `f` (`targets`), which a gripper rides on.
    pub(crate) fn at(&self, f: usize, pulls: &[(Pull, Vec3)], targets: &[Vec3]) -> OccluderBox {
        let shifted = |by: Vec3| OccluderBox {
            min: self.shape.min + by,
            max: self.shape.max + by,
            color: self.shape.color,
        };
        match self.path {
            BoxPath::Linear { travel, bob, dwell } => {
                let x = (f - self.first) as f64 / (self.last - self.first).max(1) as f64;
                let along = if dwell {
                    0.5 + 0.5 * libm::pow(2.0 * x - 1.0, 3.0)
                } else {
                    x
                };
                let lift = Vec3::new(0.0, 0.0, bob * libm::sin(core::f64::consts::PI * x));
                // Added in this order, as the scenes were always made.
                OccluderBox {
                    min: self.shape.min + travel * along + lift,
                    max: self.shape.max + travel * along + lift,
                    color: self.shape.color,
                }
            }
            BoxPath::Enter { from, frames } => {
                let x = (f - self.first) as f64 / frames.max(1) as f64;
                shifted(from * (1.0 - smoothstep(x)))
            }
            BoxPath::Gripper {
                pull,
                descent,
                approach,
            } => {
                let start = pulls.get(pull).map_or(0, |(p, _)| p.start);
                let target = targets.get(pull).copied().unwrap_or_default();
                let coming = if f < start {
                    1.0 - smoothstep((f + approach - start) as f64 / approach.max(1) as f64)
                } else {
                    0.0
                };
                shifted(target + Vec3::new(0.0, 0.0, descent * coming))
            }
        }
    }
}
