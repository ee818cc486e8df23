//! A drawn scene made real: the rope laid and settled, its end grasped,
//! the occluder and the clutter placed where the settled rope leaves room.

use alloc::format;
use alloc::vec::Vec;

use upetrack::math::Vec3;
use upetrack::rng::SplitMix64;

use crate::layout::lift_upper_strand;
use crate::random::{MotionKind, OccluderKind, RandomScene, ShapeDraw};
use crate::render::{OccluderBox, RenderSettings};
use crate::scenario::{
    gripper_holding, rect_over, still, BoxPath, Events, MovingBox, Pull, Scenario, SynthOcclusion,
    GRIPPER_APPROACH_FRAMES, SETTLING_FRAMES,
};

/// Clear space kept between clutter and the rope, metres.
const CLUTTER_CLEARANCE: f64 = 0.03;
/// Tries at placing one clutter object.
const CLUTTER_TRIES: usize = 40;
/// How far a box starts from its place before sliding in, metres.
const BOX_ENTRY: f64 = 0.35;
/// How high a hand starts above its place before coming down, metres.
const HAND_ENTRY: f64 = 0.3;

fn corners(b: &OccluderBox) -> [[f64; 3]; 2] {
    [[b.min.x, b.min.y, b.min.z], [b.max.x, b.max.y, b.max.z]]
}

/// Distance in the table plane from `p` to the rectangle `[min, max]`.
fn to_rect(p: &Vec3, min: &Vec3, max: &Vec3) -> f64 {
    let dx = (min.x - p.x).max(p.x - max.x).max(0.0);
    let dy = (min.y - p.y).max(p.y - max.y).max(0.0);
    libm::sqrt(dx * dx + dy * dy)
}

/// The render settings at frame `f` (where a moving camera is then).
fn render_at(draw: &RandomScene, f: usize) -> RenderSettings {
    let mut r = draw.render();
    if let Some(path) = &draw.camera.motion {
        (r.camera_shift, r.camera_turn) = path.at(f as f64, draw.fps);
    }
    r
}

/// The scenario of `draw`, its placements recorded in it.
fn scenario(mut draw: RandomScene) -> Scenario {
    let settings = draw.rope_settings();
    let mut rope = draw.laid(settings);
    if draw.shape == ShapeDraw::Loop {
        lift_upper_strand(&mut rope);
    }
    for _ in 0..SETTLING_FRAMES {
        rope.step(1.0 / crate::SIMULATED_FPS);
    }
    // Durations drawn in frames at the default rate, in this draw's frames;
    // and as many substeps a second at any rate: the same rope.
    let rate = draw.frames_per_default_frame();
    let in_frames = |n: f64| libm::round(n * rate).max(1.0) as usize;
    rope.settings.substeps = libm::round(rope.settings.substeps as f64 / rate).max(1.0) as usize;
    let mut rng = SplitMix64::new(draw.seed ^ 0x0CC1_0DE5_0000_0002);
    let frames = draw.frames;
    let n = rope.x.len();
    let last = n - 1;
    let d = draw.rope.diameter_m;

    // The rope's motion: the moved end, out along its own direction or across it.
    let m = draw.motion;
    let moved = if m.last_end { last } else { 0 };
    let inner = if m.last_end { last - 5 } else { 5 };
    let mut out = rope.x[moved] - rope.x[inner];
    out.z = 0.0;
    let out = out / upetrack::math::norm(&out).max(1e-9);
    let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
    let side = Vec3::new(-out.y, out.x, 0.0) * sign;
    let offset = match m.kind {
        MotionKind::Rest => None,
        MotionKind::DragSideways | MotionKind::Fast => Some(side * m.distance_m),
        MotionKind::PullAlongAxis => Some(out * m.distance_m),
        MotionKind::Lift => Some(Vec3::new(0.0, 0.0, m.distance_m) + side * (0.3 * m.distance_m)),
    };
    let mut pulls = Vec::new();
    if let Some(offset) = offset {
        pulls.push(Pull {
            particle: moved,
            start: m.start_frame,
            end: m.end_frame.max(m.start_frame + 1),
            offset,
            circular: false,
        });
    }

    // The occluder, over the run of the rope it was drawn for.
    let o = draw.occluder;
    let i0 = (libm::round(o.run_start * last as f64) as usize).min(last);
    let i1 = (i0 + libm::round(o.share * last as f64) as usize).min(last);
    let run = &rope.x[i0..=i1];
    let mid = rope.x[(i0 + i1) / 2];
    let (first, until) = (o.first_frame, o.last_frame.max(o.first_frame));
    let mut occlusions = Vec::new();
    let mut boxes = Vec::new();
    let colour = Some(o.rgb);
    match o.kind {
        OccluderKind::None => {}
        OccluderKind::Rect => {
            let r = render_at(&draw, first);
            let px = d * r.camera.fx / draw.camera.distance_m;
            occlusions.push(SynthOcclusion {
                first,
                last: until,
                rect: rect_over(&r, run, 2.0 * px + 4.0, 1.0),
            });
        }
        OccluderKind::Box => {
            let margin = (2.0 * d).max(0.01);
            let (mut lo, mut hi) = (Vec3::repeat(f64::MAX), Vec3::repeat(f64::MIN));
            for p in run {
                lo = lo.inf(p);
                hi = hi.sup(p);
            }
            let z0 = d + rng.range(0.01, 0.08);
            let shape = OccluderBox {
                min: Vec3::new(lo.x - margin, lo.y - margin, z0),
                max: Vec3::new(hi.x + margin, hi.y + margin, z0 + rng.range(0.01, 0.03)),
                color: colour,
            };
            let a = rng.range(0.0, core::f64::consts::TAU);
            let from = Vec3::new(libm::cos(a), libm::sin(a), 0.0) * BOX_ENTRY;
            let frames = in_frames(libm::floor(rng.range(5.0, 12.0)));
            draw.placed.occluder_boxes.push(corners(&shape));
            boxes.push(MovingBox {
                first,
                last: until,
                shape,
                path: BoxPath::Enter { from, frames },
            });
        }
        OccluderKind::Hand => {
            let z0 = d + rng.range(0.03, 0.10);
            let along_x = rng.uniform() < 0.5;
            let dir = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
            let frames = in_frames(libm::floor(rng.range(6.0, 12.0)));
            for shape in hand(mid, z0, along_x, dir, o.rgb) {
                draw.placed.occluder_boxes.push(corners(&shape));
                boxes.push(MovingBox {
                    first,
                    last: until,
                    shape,
                    path: BoxPath::Enter {
                        from: Vec3::new(0.0, 0.0, HAND_ENTRY),
                        frames,
                    },
                });
            }
        }
        OccluderKind::Gripper => {
            // It holds the moved end; a resting rope's end is held still.
            if pulls.is_empty() {
                let start = (first + in_frames(12.0)).min(frames.saturating_sub(2));
                pulls.push(Pull {
                    particle: moved,
                    start,
                    end: start + 1,
                    offset: Vec3::zeros(),
                    circular: false,
                });
            }
            let start = pulls[0].start;
            let approach = in_frames(GRIPPER_APPROACH_FRAMES as f64);
            draw.occluder.first_frame = start - start.min(approach);
            draw.occluder.last_frame = frames - 1;
            let r = draw.rope.diameter_m * 0.5;
            boxes.extend(gripper_holding(r, Some(o.rgb), start, frames, approach));
        }
    }

    // Clutter, where the settled rope and the moved end's path leave room.
    let r0 = render_at(&draw, 0);
    let target = pulls.first().map(|p| rope.x[p.particle] + p.offset);
    let (mut lo, mut hi) = (Vec3::repeat(f64::MAX), Vec3::repeat(f64::MIN));
    for p in &rope.x {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let mut taken: Vec<(Vec3, Vec3)> = boxes
        .iter()
        .filter(|b| !matches!(b.path, BoxPath::Gripper { .. }))
        .map(|b| (b.shape.min, b.shape.max))
        .collect();
    for c in draw.clutter.clone() {
        for _ in 0..CLUTTER_TRIES {
            let centre = Vec3::new(
                rng.range(lo.x - 0.2, hi.x + 0.2),
                rng.range(lo.y - 0.2, hi.y + 0.2),
                0.0,
            );
            let [a, b] = if rng.uniform() < 0.5 {
                c.size_m
            } else {
                [c.size_m[1], c.size_m[0]]
            };
            let min = Vec3::new(centre.x - 0.5 * a, centre.y - 0.5 * b, 0.0);
            let max = Vec3::new(centre.x + 0.5 * a, centre.y + 0.5 * b, c.height_m);
            let clear = rope
                .x
                .iter()
                .chain(target.iter())
                .all(|p| to_rect(p, &min, &max) >= CLUTTER_CLEARANCE + d)
                && taken
                    .iter()
                    .all(|(tmin, tmax)| to_rect(&centre, tmin, tmax) > 0.5 * (a + b) + 0.01);
            let cam = r0.camera;
            let in_view = [
                min,
                max,
                Vec3::new(min.x, max.y, 0.0),
                Vec3::new(max.x, min.y, 0.0),
            ]
            .iter()
            .all(|p| {
                cam.project(&r0.world_to_camera(p)).is_some_and(|q| {
                    q.x >= 0.0 && q.y >= 0.0 && q.x < cam.width as f64 && q.y < cam.height as f64
                })
            });
            if clear && in_view {
                let shape = OccluderBox {
                    min,
                    max,
                    color: Some(c.rgb),
                };
                draw.placed.clutter.push(corners(&shape));
                taken.push((min, max));
                boxes.push(still(shape, frames));
                break;
            }
        }
    }

    let events = Events {
        occlusions,
        pulls,
        boxes,
        camera_path: draw.camera.motion,
    };
    let render = draw.render();
    let mut s = Scenario::assemble(
        format!("random-{}", draw.seed),
        frames,
        render,
        rope,
        events,
        SplitMix64::new(draw.seed),
    );
    s.draw = Some(draw);
    s
}

/// A hand hovering at height `z0` over `at`: a palm and four fingers
/// pointing along x (or y) in direction `dir`.
fn hand(at: Vec3, z0: f64, along_x: bool, dir: f64, rgb: [f64; 3]) -> Vec<OccluderBox> {
    // In the hand's own frame: u along the fingers, v across.
    let mut parts = Vec::new();
    let mut put = |u0: f64, u1: f64, v0: f64, v1: f64, dz: f64| {
        let (u0, u1) = if dir > 0.0 { (u0, u1) } else { (-u1, -u0) };
        let (x0, x1, y0, y1) = if along_x {
            (u0, u1, v0, v1)
        } else {
            (v0, v1, u0, u1)
        };
        parts.push(OccluderBox {
            min: Vec3::new(at.x + x0, at.y + y0, z0 + dz),
            max: Vec3::new(at.x + x1, at.y + y1, z0 + dz + 0.02),
            color: Some(rgb),
        });
    };
    put(-0.045, 0.045, -0.04, 0.04, 0.0);
    for k in 0..4 {
        let v = -0.036 + 0.024 * k as f64;
        put(0.045, 0.11, v - 0.0085, v + 0.0085, -0.005);
    }
    parts
}

impl Scenario {
    /// The scene drawn from `seed` ([`RandomScene::draw`]), settled and
    /// ready to record; its draw (and where things were placed) is in
    /// [`Scenario::draw`].
    pub fn random(seed: u64, frames: usize) -> Self {
        scenario(RandomScene::draw(seed, frames))
    }

    /// [`Scenario::random`] filmed at `fps` frames per second
    /// ([`RandomScene::draw_at`]).
    pub fn random_at(seed: u64, frames: usize, fps: f64) -> Self {
        scenario(RandomScene::draw_at(seed, frames, fps))
    }
}
