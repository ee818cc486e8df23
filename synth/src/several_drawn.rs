//! Scenes of several ropes drawn whole from a seed (the randomised
//! benchmark's option of several ropes): how many, of which colours, how
//! long and thick, where they lie and which over which, what moves them,
//! and whether a box passes over them.

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use upetrack::math::Vec3;
use upetrack::rng::SplitMix64;

use crate::events::{BoxPath, MovingBox};
use crate::plan::{bowed, Grasp, Laid, Plan, BLUE, GREEN, RED};
use crate::render::OccluderBox;

/// Mixed into a seed for the drawn scenes of several ropes, so that they
/// share no numbers with the single-rope scenes of the same seed.
pub(crate) const DRAWN_STREAM: u64 = 0x5E7E_8A1D_0000_0032;

/// Ropes' lengths, metres (all of them in view at 0.6 m).
const LENGTH_M: (f64, f64) = (0.30, 0.48);
/// Ropes' diameters, metres.
const DIAMETER_M: (f64, f64) = (0.006, 0.014);
/// How far a rope's middle lies from the view's centre, metres.
const CENTRE_M: f64 = 0.10;
/// Chance that a later rope is laid across an earlier one.
const CROSSING_CHANCE: f64 = 0.7;
/// Chance that every rope has one colour (told apart by their states).
const ONE_COLOUR_CHANCE: f64 = 0.5;
/// Chance of a box passing over the ropes.
const BOX_CHANCE: f64 = 0.5;
/// How far a grasped end moves, metres.
const MOVE_M: (f64, f64) = (0.05, 0.12);

/// A drawn plan of `frames` frames from `rng`: 2 or 3 ropes laid one after
/// the other (each over the ropes before it where they cross), one or two
/// of them moved at an end, sideways or along their axis.
pub(crate) fn drawn_plan(rng: &mut SplitMix64, frames: usize) -> Plan {
    let count = if rng.uniform() < 0.6 { 2 } else { 3 };
    let one_colour = rng.uniform() < ONE_COLOUR_CHANCE;
    let palette = [BLUE, RED, GREEN];
    let names = ["blue", "red", "green"];
    let mut laid: Vec<Laid> = Vec::new();
    let mut middles: Vec<(Vec3, f64)> = Vec::new();
    for k in 0..count {
        let length = rng.range(LENGTH_M.0, LENGTH_M.1);
        let thickness = rng.range(DIAMETER_M.0, DIAMETER_M.1);
        // Across an earlier rope (through a point near its middle, at least
        // 30 degrees off its direction), or anywhere.
        let (centre, angle) = match middles.as_slice() {
            [] => (
                Vec3::new(
                    rng.range(-CENTRE_M, CENTRE_M),
                    rng.range(-CENTRE_M, CENTRE_M),
                    0.0,
                ),
                rng.range(0.0, core::f64::consts::PI),
            ),
            earlier if rng.uniform() < CROSSING_CHANCE => {
                let (c, a) =
                    earlier[(rng.uniform() * earlier.len() as f64) as usize % earlier.len()];
                let along = rng.range(-0.08, 0.08);
                let through = c + Vec3::new(libm::cos(a), libm::sin(a), 0.0) * along;
                let turn = rng.range(0.52, core::f64::consts::PI - 0.52);
                (through, a + turn)
            }
            _ => (
                Vec3::new(
                    rng.range(-CENTRE_M, CENTRE_M),
                    rng.range(-CENTRE_M, CENTRE_M),
                    0.0,
                ),
                rng.range(0.0, core::f64::consts::PI),
            ),
        };
        middles.push((centre, angle));
        let half = 0.5 * length;
        let dir = Vec3::new(libm::cos(angle), libm::sin(angle), 0.0);
        let (a, b) = (centre - dir * half, centre + dir * half);
        let colour = if one_colour { 0 } else { k };
        let name = if one_colour {
            format!("{}-{}", names[0], (b'a' + k as u8) as char)
        } else {
            String::from(names[colour])
        };
        laid.push(Laid {
            shape: bowed(
                [a.x, a.y],
                [b.x, b.y],
                rng.range(-0.04, 0.04),
                Vec3::zeros(),
            ),
            color: palette[colour],
            name,
            over: (0..k).collect(),
            length,
            thickness,
        });
    }
    // One or two ropes moved at an end.
    let moved = if rng.uniform() < 0.5 { 1 } else { 2 };
    let mut grasps = Vec::new();
    for _ in 0..moved {
        let rope = (rng.uniform() * count as f64) as usize % count;
        let (_, angle) = middles[rope];
        let along = Vec3::new(libm::cos(angle), libm::sin(angle), 0.0);
        let across = Vec3::new(-along.y, along.x, 0.0);
        let last_end = rng.uniform() < 0.5;
        let outwards = if last_end { along } else { -along };
        let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
        let distance = rng.range(MOVE_M.0, MOVE_M.1);
        let offset = if rng.uniform() < 0.5 {
            across * (sign * distance)
        } else {
            outwards * distance
        };
        let start = rng.range(0.2, 0.4);
        grasps.push(Grasp {
            rope,
            particle: if last_end { usize::MAX } else { 0 },
            offset,
            start,
            end: start + rng.range(0.3, 0.5),
            from: Vec3::zeros(),
        });
    }
    let mut boxes = Vec::new();
    if rng.uniform() < BOX_CHANCE {
        let at = |f: f64| ((frames as f64 * f) as usize).min(frames.saturating_sub(1));
        let (w, h) = (rng.range(0.05, 0.10), rng.range(0.05, 0.10));
        let z = rng.range(0.06, 0.10);
        let y = rng.range(-CENTRE_M, CENTRE_M);
        let first = rng.range(0.2, 0.4);
        boxes.push(MovingBox {
            first: at(first),
            last: at(first + rng.range(0.3, 0.5)),
            shape: OccluderBox {
                min: Vec3::new(-0.28, y - 0.5 * h, z),
                max: Vec3::new(-0.28 + w, y + 0.5 * h, z + 0.03),
                color: None,
            },
            path: BoxPath::Linear {
                travel: Vec3::new(0.5, 0.0, 0.0),
                bob: 0.0,
                dwell: true,
            },
        });
    }
    Plan {
        laid,
        grasps,
        boxes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::several::SeveralRopes;

    #[test]
    fn a_drawn_scene_of_several_ropes_is_the_same_for_a_seed_and_its_draws_cover_their_ranges() {
        let (a, b) = (SeveralRopes::random(7, 3), SeveralRopes::random(7, 3));
        assert_eq!(a.names, b.names);
        assert_eq!(
            a.ropes.iter().map(|r| r.x.clone()).collect::<Vec<_>>(),
            b.ropes.iter().map(|r| r.x.clone()).collect::<Vec<_>>()
        );
        let (mut counts, mut one_colour, mut several, mut boxed, mut lengths, mut diameters) =
            ([0usize; 4], 0, 0, 0, Vec::new(), Vec::new());
        for seed in 0..200 {
            let mut rng = SplitMix64::new(seed ^ DRAWN_STREAM);
            let plan = drawn_plan(&mut rng, 48);
            counts[plan.laid.len()] += 1;
            if plan.laid.iter().all(|l| l.color == plan.laid[0].color) {
                one_colour += 1;
            } else {
                several += 1;
            }
            boxed += usize::from(!plan.boxes.is_empty());
            assert!(!plan.grasps.is_empty() && plan.grasps.len() <= 2);
            lengths.extend(plan.laid.iter().map(|l| l.length));
            diameters.extend(plan.laid.iter().map(|l| l.thickness));
        }
        assert!(counts[2] > 50 && counts[3] > 30, "{counts:?}");
        assert!(one_colour > 60 && several > 60, "{one_colour} / {several}");
        assert!(boxed > 60 && boxed < 140, "{boxed}");
        let span = |v: &[f64]| {
            (
                v.iter().copied().fold(f64::INFINITY, f64::min),
                v.iter().copied().fold(0.0, f64::max),
            )
        };
        let (lo, hi) = span(&lengths);
        assert!(
            lo < LENGTH_M.0 + 0.02 && hi > LENGTH_M.1 - 0.02,
            "{lo}..{hi}"
        );
        let (lo, hi) = span(&diameters);
        assert!(
            lo < DIAMETER_M.0 + 0.001 && hi > DIAMETER_M.1 - 0.001,
            "{lo}..{hi}"
        );
    }
}
