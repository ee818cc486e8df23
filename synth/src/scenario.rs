//! The named scenarios: a settled rope, grasp paths, occlusion rectangles
//! (the contract's colour masking) or real occluder boxes, rendered frame
//! by frame with the ground-truth centre line in the camera frame.

use alloc::string::String;
use alloc::vec::Vec;

use upetrack::math::Vec3;
use upetrack::rng::SplitMix64;
use upetrack::{CameraIntrinsics, HsvRange, Rect};

use crate::camera_path::CameraPath;
pub(crate) use crate::events::{BoxPath, MovingBox, Pull};
use crate::layout::{
    arc_shape, bends_shape, gripper, hairpin_shape, lift_upper_strand, loop_shape, lying, s_shape,
};
use crate::random::RandomScene;
use crate::render::{hidden_by_boxes, render, rope_hsv, CameraPose, OccluderBox, RenderSettings};
use crate::rope::{Rope, RopeSettings};
use crate::variant::Variant;
use crate::MAX_FRAMES;

/// Frames of physics run before recording starts.
pub const SETTLING_FRAMES: usize = 45;

/// Version of what the scenarios produce: bump it whenever a change to the
/// simulator, the renderer or a scenario changes their frames, so that
/// cached sequences (`upetrack compare`) are written again.
pub const SIMULATOR_VERSION: u32 = 4;
/// Margin added around the projected rope segment that an occlusion hides, pixels.
const OCCLUSION_MARGIN_PX: f64 = 14.0;

/// How far `pulled-through` pulls its arm out along its axis, metres.
const PULL_THROUGH_M: f64 = 0.10;

/// Which scenario.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScenarioKind {
    /// The paper's scenario I: a static S whose lower bend is hidden after a settling period.
    StaticS,
    /// The paper's scenario II: a bend hidden, then one end pulled.
    DynamicPull,
    /// A tip hidden while the rope is dragged by its other end.
    TipDrag,
    /// TrackDLO's sweep: a rectangle covering the first `percent` % of the rope (10..=50) while it is pulled.
    OcclusionSweep {
        /// Share of the rope hidden, percent.
        percent: u8,
    },
    /// One end lifted and swung in 3D while a real box passes in front of the rope.
    LiftedSwing,
    /// A fast pull (about 0.3 m/s) without occlusion.
    FastPull,
    /// A gripper comes down on one end, lifts it 10 cm and swings it; its
    /// palm and arm (real boxes) hide the held end from the camera.
    GripperSwing,
    /// A box travels low over one end of the rope, rising and sinking as
    /// it goes (an occluder in depth, no rectangle) while the far end is dragged.
    BoxOverEnd,
    /// The same box over the middle of the rope.
    BoxOverMiddle,
    /// A thin black cable in several bends on a desk beside dark flat
    /// things (a phone, a pen, a USB stick) that pass the same colour range.
    CableDesk,
    /// A rope lying in a loop that crosses over itself, one tail pulled.
    CrossingLoop,
    /// A rope under two strips (a ruler and a pen) lying across it: its
    /// mask is in three pieces.
    InPieces,
    /// A U whose bend is hidden while one arm is pulled out along its own
    /// axis: the rope slides round the hidden bend, which tightens.
    PulledThrough,
}

impl ScenarioKind {
    /// One of each scenario (the sweep at 30 %).
    pub const EXAMPLES: [Self; 13] = [
        Self::StaticS,
        Self::DynamicPull,
        Self::TipDrag,
        Self::OcclusionSweep { percent: 30 },
        Self::LiftedSwing,
        Self::FastPull,
        Self::GripperSwing,
        Self::BoxOverEnd,
        Self::BoxOverMiddle,
        Self::CableDesk,
        Self::CrossingLoop,
        Self::InPieces,
        Self::PulledThrough,
    ];

    /// Every scenario's command-line name.
    pub const NAMES: [&'static str; 13] = [
        "static-s",
        "dynamic-pull",
        "tip-drag",
        "sweep-<K>",
        "lifted-swing",
        "fast-pull",
        "gripper-swing",
        "box-over-end",
        "box-over-middle",
        "cable-desk",
        "crossing-loop",
        "in-pieces",
        "pulled-through",
    ];

    /// Largest share of the rope a sweep may hide, percent.
    pub const MAX_SWEEP_PERCENT: u8 = 70;

    /// Parses a command-line name (`sweep-30` for a 30 % sweep).
    pub fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "static-s" => Self::StaticS,
            "dynamic-pull" => Self::DynamicPull,
            "tip-drag" => Self::TipDrag,
            "lifted-swing" => Self::LiftedSwing,
            "fast-pull" => Self::FastPull,
            "gripper-swing" => Self::GripperSwing,
            "box-over-end" => Self::BoxOverEnd,
            "box-over-middle" => Self::BoxOverMiddle,
            "cable-desk" => Self::CableDesk,
            "crossing-loop" => Self::CrossingLoop,
            "in-pieces" => Self::InPieces,
            "pulled-through" => Self::PulledThrough,
            other => {
                let k: u8 = other.strip_prefix("sweep-")?.parse().ok()?;
                if !(10..=Self::MAX_SWEEP_PERCENT).contains(&k) {
                    return None;
                }
                Self::OcclusionSweep { percent: k }
            }
        })
    }

    /// The command-line name.
    pub fn name(&self) -> String {
        match self {
            Self::StaticS => "static-s".into(),
            Self::DynamicPull => "dynamic-pull".into(),
            Self::TipDrag => "tip-drag".into(),
            Self::OcclusionSweep { percent } => alloc::format!("sweep-{percent}"),
            Self::LiftedSwing => "lifted-swing".into(),
            Self::FastPull => "fast-pull".into(),
            Self::GripperSwing => "gripper-swing".into(),
            Self::BoxOverEnd => "box-over-end".into(),
            Self::BoxOverMiddle => "box-over-middle".into(),
            Self::CableDesk => "cable-desk".into(),
            Self::CrossingLoop => "crossing-loop".into(),
            Self::InPieces => "in-pieces".into(),
            Self::PulledThrough => "pulled-through".into(),
        }
    }

    /// One sentence on what it shows.
    pub fn description(&self) -> &'static str {
        match self {
            Self::StaticS => "static S-shaped rope; from 30 % of the frames on, its lower bend is hidden (paper scenario I)",
            Self::DynamicPull => "S-shaped rope; its lower bend is hidden from 30 % of the frames on, and from 40 % its nearer end is pulled 12 cm (paper scenario II)",
            Self::TipDrag => "one tip (15 % of the rope) hidden from 30 % of the frames on while the other end drags the rope 12 cm",
            Self::OcclusionSweep { .. } => "TrackDLO's protocol: a rectangle hides the first K % (10-70) of the rope from 30 % of the frames on while the far end is pulled 8 cm",
            Self::LiftedSwing => "one end lifted 12 cm and swung in a circle; a grey box passes between camera and rope",
            Self::FastPull => "one end pulled 25 cm in a third of the sequence (about 0.3 m/s at 30 fps), no occlusion",
            Self::GripperSwing => "a gripper comes down on one end, lifts it 10 cm and swings it in a circle; its palm and arm hide the held end in depth",
            Self::BoxOverEnd => "a box travels 6-10 cm above the table over one end (an occluder in depth, no rectangle) while the other end is dragged 10 cm",
            Self::BoxOverMiddle => "a box travels 6-10 cm above the table over the middle of the rope while one end is dragged 10 cm",
            Self::CableDesk => "a thin black cable in several bends on a desk beside a black phone, a pen and a USB stick, all in a black colour range; one end dragged 8 cm",
            Self::CrossingLoop => "a rope lying in a loop that crosses over itself (the upper strand resting on the lower); one tail pulled 6 cm, tightening the loop",
            Self::InPieces => "a rope under a ruler and a pen lying across it (its mask in three pieces) while one end is dragged 10 cm",
            Self::PulledThrough => "a U whose bend is hidden from 30 % of the frames on; from 40 % one arm is pulled 10 cm along its own axis, so the rope slides round the hidden bend",
        }
    }

    /// The scene variant this scenario is seen in when none is asked for:
    /// the black cable's own for `cable-desk`, else the base variant.
    pub fn default_variant(&self) -> Variant {
        match self {
            Self::CableDesk => Variant::DESK_BLACK_CABLE,
            _ => Variant::BASE,
        }
    }
}

/// An occlusion rectangle over a frame range (inclusive), as in `dlo.json`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SynthOcclusion {
    /// First frame.
    pub first: usize,
    /// Last frame.
    pub last: usize,
    /// Rectangle, pixels.
    pub rect: Rect,
}

/// One rendered frame with its ground truth.
#[derive(Debug, Clone)]
pub struct SynthFrame {
    /// Frame index.
    pub index: usize,
    /// RGB8.
    pub rgb: Vec<u8>,
    /// Depth, millimetres.
    pub depth: Vec<u16>,
    /// Centre line, ordered, metres, colour camera frame.
    pub groundtruth: Vec<Vec3>,
    /// For each ground-truth point: hidden by an occluder (a box between it
    /// and the camera, or an occlusion rectangle over its pixel).
    pub occluded: Vec<bool>,
    /// Where the camera was (the ground truth of its own motion).
    pub camera_pose: CameraPose,
}

/// Scales applied to a scenario's events, for scenes made to order (the
/// page's generator). The default, 1 and 1, is the scenario as named, bit
/// for bit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneKnobs {
    /// Size of the occlusion rectangle and of the occluder boxes (across
    /// the view; a box keeps its height), times the scenario's.
    pub occluder_scale: f64,
    /// Distance every pull moves its end over the same frames (so also its
    /// speed), times the scenario's; 0 leaves the rope where it settled.
    pub pull_scale: f64,
}

impl Default for SceneKnobs {
    fn default() -> Self {
        Self {
            occluder_scale: 1.0,
            pull_scale: 1.0,
        }
    }
}

/// What happens in a scene once the rope has settled.
pub(crate) struct Events {
    /// Occlusion rectangles.
    pub(crate) occlusions: Vec<SynthOcclusion>,
    /// Grasps moving particles.
    pub(crate) pulls: Vec<Pull>,
    /// Occluder boxes.
    pub(crate) boxes: Vec<MovingBox>,
    /// How the camera moves, if it does.
    pub(crate) camera_path: Option<CameraPath>,
}

/// The rectangle over the projection of `points` (world frame), `margin`
/// pixels wider on every side, its size times `scale` about its centre.
pub(crate) fn rect_over(render: &RenderSettings, points: &[Vec3], margin: f64, scale: f64) -> Rect {
    let cam = render.camera;
    let (mut u0, mut v0, mut u1, mut v1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for p in points {
        if let Some(q) = cam.project(&render.world_to_camera(p)) {
            u0 = u0.min(q.x);
            v0 = v0.min(q.y);
            u1 = u1.max(q.x);
            v1 = v1.max(q.y);
        }
    }
    if scale != 1.0 {
        let (cu, cv) = (0.5 * (u0 + u1), 0.5 * (v0 + v1));
        let (hu, hv) = (0.5 * (u1 - u0) * scale, 0.5 * (v1 - v0) * scale);
        (u0, u1, v0, v1) = (cu - hu, cu + hu, cv - hv, cv + hv);
    }
    Rect {
        x: libm::floor(u0 - margin) as i64,
        y: libm::floor(v0 - margin) as i64,
        w: libm::ceil(u1 - u0 + 2.0 * margin) as i64,
        h: libm::ceil(v1 - v0 + 2.0 * margin) as i64,
    }
}

/// Largest scale a [`SceneKnobs`] field accepts (the page clamps to it).
pub const MAX_KNOB_SCALE: f64 = 3.0;

/// A scenario being recorded.
pub struct Scenario {
    /// Its command-line name (`static-s`; `random-<seed>` for a drawn scene).
    pub name: String,
    /// For a drawn scene, everything that was drawn (`None` for a named one).
    pub draw: Option<RandomScene>,
    /// Number of frames to record.
    pub frames: usize,
    /// Rendering settings.
    pub render: RenderSettings,
    /// The rope.
    pub rope: Rope,
    /// Occlusion rectangles (the contract's colour masking).
    pub occlusions: Vec<SynthOcclusion>,
    rng: SplitMix64,
    next: usize,
    pulls: Vec<(Pull, Vec3)>,
    boxes: Vec<MovingBox>,
    camera_path: Option<CameraPath>,
}

/// Frames a gripper takes to come down onto the end it holds (fewer when
/// its pull starts sooner).
pub(crate) const GRIPPER_APPROACH_FRAMES: usize = 15;

/// A gripper's three boxes ([`gripper`]) coming down onto the end that
/// pull 0 moves from frame `start` on, and holding it to the last frame,
/// in at most `approach` frames; `r` the rope's radius, `color` `None` for
/// the occluders' colour.
pub(crate) fn gripper_holding(
    r: f64,
    color: Option<[f64; 3]>,
    start: usize,
    frames: usize,
    approach: usize,
) -> impl Iterator<Item = MovingBox> {
    let approach = start.min(approach);
    gripper(r, color).into_iter().map(move |shape| MovingBox {
        first: start - approach,
        last: frames - 1,
        shape,
        path: BoxPath::Gripper {
            pull: 0,
            descent: 0.15,
            approach,
        },
    })
}

/// A box that stays where it is for the whole scene.
pub(crate) fn still(shape: OccluderBox, frames: usize) -> MovingBox {
    MovingBox {
        first: 0,
        last: frames - 1,
        shape,
        path: BoxPath::Linear {
            travel: Vec3::zeros(),
            bob: 0.0,
            dwell: false,
        },
    }
}

impl Scenario {
    /// Frames per second it is filmed at: a drawn scene's
    /// ([`RandomScene::fps`]), else [`crate::SIMULATED_FPS`].
    pub fn fps(&self) -> f64 {
        self.draw.as_ref().map_or(crate::SIMULATED_FPS, |d| d.fps)
    }

    /// Sets up `kind` with `frames` frames (at least 1) and a seed; the rope
    /// is settled before recording starts.
    pub fn new(kind: ScenarioKind, frames: usize, seed: u64, render: RenderSettings) -> Self {
        Self::with_rope(kind, frames, seed, render, RopeSettings::default())
    }

    /// [`Scenario::new`] with a rope of its own (thickness, length, stiffness).
    pub fn with_rope(
        kind: ScenarioKind,
        frames: usize,
        seed: u64,
        render: RenderSettings,
        rope_settings: RopeSettings,
    ) -> Self {
        Self::with_knobs(
            kind,
            frames,
            seed,
            render,
            rope_settings,
            SceneKnobs::default(),
        )
    }

    /// [`Scenario::with_rope`] with the occluders and pulls scaled by `knobs`.
    pub fn with_knobs(
        kind: ScenarioKind,
        frames: usize,
        seed: u64,
        render: RenderSettings,
        rope_settings: RopeSettings,
        knobs: SceneKnobs,
    ) -> Self {
        let frames = frames.clamp(1, MAX_FRAMES);
        let mut rng = SplitMix64::new(seed);
        let shape = match kind {
            ScenarioKind::StaticS
            | ScenarioKind::DynamicPull
            | ScenarioKind::OcclusionSweep { .. } => s_shape(),
            ScenarioKind::CableDesk => bends_shape(),
            ScenarioKind::CrossingLoop => loop_shape(),
            ScenarioKind::PulledThrough => hairpin_shape(),
            _ => arc_shape(),
        };
        // Small seeded variation of the layout: a rotation and a shift.
        let angle = rng.range(-0.08, 0.08);
        let shift = Vec3::new(rng.range(-0.01, 0.01), rng.range(-0.01, 0.01), 0.0);
        let (c, s) = (libm::cos(angle), libm::sin(angle));
        let shape: Vec<Vec3> = shape
            .iter()
            .map(|p| Vec3::new(c * p.x - s * p.y, s * p.x + c * p.y, 0.0) + shift)
            .collect();
        let mut rope = Rope::laid_along(&shape, rope_settings);
        if kind == ScenarioKind::CrossingLoop {
            lift_upper_strand(&mut rope);
        }
        for _ in 0..SETTLING_FRAMES {
            rope.step(1.0 / crate::SIMULATED_FPS);
        }
        let n = rope.x.len();
        let last = n - 1;
        let at = |f: f64| ((frames as f64 * f) as usize).min(frames - 1);
        let mut pulls = Vec::new();
        let mut hidden: Option<(usize, usize)> = None;
        let mut boxes = Vec::new();
        let frac = |f: f64| libm::round((last as f64) * f) as usize;
        match kind {
            ScenarioKind::StaticS => hidden = Some((frac(0.64), frac(0.86))),
            ScenarioKind::DynamicPull => {
                hidden = Some((frac(0.64), frac(0.86)));
                pulls.push(Pull {
                    particle: last,
                    start: at(0.4),
                    end: at(0.9),
                    offset: Vec3::new(0.06, -0.10, 0.0),
                    circular: false,
                });
            }
            ScenarioKind::TipDrag => {
                hidden = Some((0, frac(0.15)));
                pulls.push(Pull {
                    particle: last,
                    start: at(0.35),
                    end: at(0.9),
                    offset: Vec3::new(0.04, 0.11, 0.0),
                    circular: false,
                });
            }
            ScenarioKind::OcclusionSweep { percent } => {
                hidden = Some((0, frac(percent as f64 / 100.0)));
                pulls.push(Pull {
                    particle: last,
                    start: at(0.4),
                    end: at(0.9),
                    offset: Vec3::new(0.03, -0.075, 0.0),
                    circular: false,
                });
            }
            ScenarioKind::LiftedSwing => {
                pulls.push(Pull {
                    particle: last,
                    start: at(0.1),
                    end: at(0.95),
                    offset: Vec3::new(0.05, 0.0, 0.12),
                    circular: true,
                });
                // Halfway between the rope's ends and its apex, so that the
                // box crosses both legs as it travels along x.
                let y0 = 0.5 * (rope.x[frac(0.5)].y + rope.x[0].y);
                boxes.push(MovingBox {
                    first: at(0.35),
                    last: at(0.8),
                    shape: OccluderBox {
                        min: Vec3::new(-0.45, y0 - 0.04, 0.20),
                        max: Vec3::new(-0.40, y0 + 0.04, 0.22),
                        color: None,
                    },
                    path: BoxPath::Linear {
                        travel: Vec3::new(0.75, 0.0, 0.0),
                        bob: 0.0,
                        dwell: false,
                    },
                });
            }
            ScenarioKind::GripperSwing => {
                let start = at(0.3);
                // The first end, swung towards the middle of the view.
                pulls.push(Pull {
                    particle: 0,
                    start,
                    end: at(0.95),
                    offset: Vec3::new(-0.05, 0.0, 0.10),
                    circular: true,
                });
                // Palm over the held end, arm up from it, forearm away to +y.
                boxes.extend(gripper_holding(
                    rope.settings.thickness * 0.5,
                    None,
                    start,
                    frames,
                    GRIPPER_APPROACH_FRAMES,
                ));
            }
            ScenarioKind::BoxOverEnd | ScenarioKind::BoxOverMiddle => {
                let over_end = kind == ScenarioKind::BoxOverEnd;
                // Over the last end, kept 3 cm inside the view.
                let target = if over_end {
                    rope.x[last] - Vec3::new(0.03, 0.0, 0.0)
                } else {
                    rope.x[frac(0.5)]
                };
                pulls.push(Pull {
                    particle: if over_end { 0 } else { last },
                    start: at(0.35),
                    end: at(0.9),
                    offset: if over_end {
                        Vec3::new(-0.06, 0.08, 0.0)
                    } else {
                        Vec3::new(0.06, 0.08, 0.0)
                    },
                    circular: false,
                });
                // A 10 x 10 x 3 cm box passing along y over the target,
                // 6 cm above the table, rising 4 cm on the way, slowest over it.
                boxes.push(MovingBox {
                    first: at(0.3),
                    last: at(0.85),
                    shape: OccluderBox {
                        min: Vec3::new(target.x - 0.05, target.y - 0.25, 0.06),
                        max: Vec3::new(target.x + 0.05, target.y - 0.15, 0.09),
                        color: None,
                    },
                    path: BoxPath::Linear {
                        travel: Vec3::new(0.0, 0.40, 0.0),
                        bob: 0.04,
                        dwell: true,
                    },
                });
            }
            ScenarioKind::CableDesk => {
                pulls.push(Pull {
                    particle: last,
                    start: at(0.35),
                    end: at(0.9),
                    offset: Vec3::new(0.05, -0.06, 0.0),
                    circular: false,
                });
                // A phone 3 cm from the cable's first end, a pen below it,
                // a USB stick 3 cm below the cable's first trough: all
                // nearly black.
                for shape in [
                    lying(-0.26, -0.03, -0.19, 0.115, 0.008, [0.025, 0.025, 0.03]),
                    lying(-0.215, -0.21, -0.205, -0.07, 0.009, [0.05, 0.05, 0.10]),
                    lying(-0.05, -0.165, 0.0, -0.147, 0.008, [0.06, 0.06, 0.06]),
                ] {
                    boxes.push(still(shape, frames));
                }
            }
            ScenarioKind::CrossingLoop => {
                pulls.push(Pull {
                    particle: last,
                    start: at(0.35),
                    end: at(0.9),
                    offset: Vec3::new(0.06, 0.0, 0.0),
                    circular: false,
                });
            }
            ScenarioKind::InPieces => {
                pulls.push(Pull {
                    particle: last,
                    start: at(0.35),
                    end: at(0.9),
                    offset: Vec3::new(0.04, 0.09, 0.0),
                    circular: false,
                });
                // A ruler 3 cm wide and a pen 1.2 cm wide across the rope,
                // resting just above it.
                let h = rope.settings.thickness;
                for (x, w, top, color) in [
                    (-0.08, 0.03, 0.004, [0.90, 0.88, 0.78]),
                    (0.10, 0.012, 0.012, [0.10, 0.10, 0.10]),
                ] {
                    let shape = OccluderBox {
                        min: Vec3::new(x - 0.5 * w, -0.25, h + 0.001),
                        max: Vec3::new(x + 0.5 * w, 0.25, h + 0.001 + top),
                        color: Some(color),
                    };
                    boxes.push(still(shape, frames));
                }
            }
            ScenarioKind::PulledThrough => {
                // The bend and a few centimetres of each arm.
                hidden = Some((frac(0.30), frac(0.70)));
                pulls.push(Pull {
                    particle: last,
                    start: at(0.4),
                    end: at(0.9),
                    offset: Vec3::new(PULL_THROUGH_M, 0.0, 0.0),
                    circular: false,
                });
            }
            ScenarioKind::FastPull => {
                pulls.push(Pull {
                    particle: last,
                    start: at(0.3),
                    end: at(0.63),
                    offset: Vec3::new(0.10, 0.23, 0.0),
                    circular: false,
                });
            }
        }
        for p in &mut pulls {
            p.offset *= knobs.pull_scale;
        }
        if knobs.occluder_scale != 1.0 {
            for b in &mut boxes {
                let c = (b.shape.min + b.shape.max) * 0.5;
                let half = (b.shape.max - b.shape.min) * (0.5 * knobs.occluder_scale);
                b.shape.min.x = c.x - half.x;
                b.shape.min.y = c.y - half.y;
                b.shape.max.x = c.x + half.x;
                b.shape.max.y = c.y + half.y;
            }
        }
        let mut occlusions = Vec::new();
        if let Some((i0, i1)) = hidden {
            occlusions.push(SynthOcclusion {
                first: at(0.3),
                last: frames - 1,
                rect: rect_over(
                    &render,
                    &rope.x[i0..=i1.min(last)],
                    OCCLUSION_MARGIN_PX,
                    knobs.occluder_scale,
                ),
            });
        }
        Self::assemble(
            kind.name(),
            frames,
            render,
            rope,
            Events {
                occlusions,
                pulls,
                boxes,
                camera_path: None,
            },
            rng,
        )
    }

    /// A scenario of a settled `rope` and its `events`, seen with `render`.
    pub(crate) fn assemble(
        name: String,
        frames: usize,
        render: RenderSettings,
        rope: Rope,
        events: Events,
        rng: SplitMix64,
    ) -> Self {
        let pulls = events
            .pulls
            .into_iter()
            .map(|p| (p, rope.x[p.particle]))
            .collect();
        Self {
            name,
            draw: None,
            frames,
            render,
            rope,
            occlusions: events.occlusions,
            rng,
            next: 0,
            pulls,
            boxes: events.boxes,
            camera_path: events.camera_path,
        }
    }

    /// HSV thresholds that fit the rope's colour ([`rope_hsv`]).
    pub fn hsv(&self) -> HsvRange {
        rope_hsv(self.render.rope_color)
    }

    /// The occlusion rectangles over frame `index`.
    pub fn occlusions_at(&self, index: usize) -> Vec<Rect> {
        self.occlusions
            .iter()
            .filter(|o| (o.first..=o.last).contains(&index))
            .map(|o| o.rect)
            .collect()
    }

    /// The camera.
    pub fn camera(&self) -> CameraIntrinsics {
        self.render.camera
    }

    /// Simulates and renders the next frame, or `None` after the last.
    pub fn next_frame(&mut self) -> Option<SynthFrame> {
        if self.next >= self.frames {
            return None;
        }
        let f = self.next;
        self.next += 1;
        if let Some(path) = &self.camera_path {
            (self.render.camera_shift, self.render.camera_turn) = path.at(f as f64, self.fps());
        }
        let mut targets: Vec<Vec3> = self.pulls.iter().map(|(_, origin)| *origin).collect();
        if f > 0 {
            for (k, (p, origin)) in self.pulls.iter().enumerate() {
                if let Some(target) = p.target(*origin, f) {
                    targets[k] = target;
                    self.rope.grasp(p.particle, target);
                }
            }
            self.rope.step(1.0 / self.fps());
        }
        let boxes: Vec<OccluderBox> = self
            .boxes
            .iter()
            .filter(|b| (b.first..=b.last).contains(&f))
            .map(|b| b.at(f, &self.pulls, &targets))
            .collect();
        let r = render(
            &self.render,
            &self.rope.x,
            self.rope.radius(),
            &boxes,
            &mut self.rng,
        );
        let pose = self.render.pose();
        let to_camera = |p: &Vec3| pose.world_to_camera(p);
        let groundtruth: Vec<Vec3> = self.rope.x.iter().map(to_camera).collect();
        let cam = self.render.camera;
        let rects = self.occlusions_at(f);
        let occluded = self
            .rope
            .x
            .iter()
            .zip(&groundtruth)
            .map(|(world, p)| {
                let in_rect = cam.project(p).is_some_and(|q| {
                    rects.iter().any(|r| {
                        q.x >= r.x as f64
                            && q.x < (r.x + r.w) as f64
                            && q.y >= r.y as f64
                            && q.y < (r.y + r.h) as f64
                    })
                });
                in_rect || hidden_by_boxes(&self.render, world, self.rope.radius(), &boxes)
            })
            .collect();
        Some(SynthFrame {
            index: f,
            rgb: r.rgb,
            depth: r.depth,
            groundtruth,
            occluded,
            camera_pose: pose,
        })
    }

    /// Length of the simulated rope now, metres.
    pub fn rope_length(&self) -> f64 {
        self.rope.current_length()
    }

    /// Frames not yet rendered.
    pub fn remaining(&self) -> usize {
        self.frames - self.next
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use upetrack::perception::segmentation::rgb_to_hsv;

    #[test]
    fn names_round_trip() {
        for k in ScenarioKind::EXAMPLES {
            assert_eq!(ScenarioKind::parse(&k.name()), Some(k));
        }
        assert_eq!(ScenarioKind::parse("sweep-80"), None);
        assert_eq!(
            ScenarioKind::parse("sweep-70"),
            Some(ScenarioKind::OcclusionSweep { percent: 70 })
        );
        assert_eq!(ScenarioKind::parse("nope"), None);
    }

    #[test]
    fn knobs_scale_the_occluder_and_the_pull_and_leave_the_default_alone() {
        let make = |knobs| {
            Scenario::with_knobs(
                ScenarioKind::DynamicPull,
                20,
                2,
                RenderSettings::default(),
                RopeSettings::default(),
                knobs,
            )
        };
        let mut plain = Scenario::new(ScenarioKind::DynamicPull, 20, 2, RenderSettings::default());
        let mut same = make(SceneKnobs::default());
        for _ in 0..3 {
            let (a, b) = (
                plain.next_frame().expect("frame"),
                same.next_frame().expect("frame"),
            );
            assert!(a.rgb == b.rgb && a.depth == b.depth && a.groundtruth == b.groundtruth);
        }
        let rect = |s: &Scenario| s.occlusions[0].rect;
        let base = rect(&plain);
        let big = rect(&make(SceneKnobs {
            occluder_scale: 2.0,
            ..SceneKnobs::default()
        }));
        assert!(
            big.w > 2 * base.w - 3 * OCCLUSION_MARGIN_PX as i64 && big.h > base.h,
            "{base:?} {big:?}"
        );
        let tip = |knobs| {
            let mut s = make(knobs);
            let mut last = Vec3::zeros();
            while let Some(f) = s.next_frame() {
                last = f.groundtruth[f.groundtruth.len() - 1];
            }
            last
        };
        let still = tip(SceneKnobs {
            pull_scale: 0.0,
            ..SceneKnobs::default()
        });
        let pulled = tip(SceneKnobs::default());
        let farther = tip(SceneKnobs {
            pull_scale: 2.0,
            ..SceneKnobs::default()
        });
        let moved = |p: Vec3| (p - still).norm();
        assert!(
            moved(pulled) > 0.08 && moved(farther) > 1.6 * moved(pulled),
            "{} {}",
            moved(pulled),
            moved(farther)
        );
    }

    #[test]
    fn hsv_range_contains_the_rope_colour_and_not_the_table() {
        let s = Scenario::new(ScenarioKind::StaticS, 1, 1, RenderSettings::default());
        let hsv = s.hsv();
        assert!(hsv.validate().is_ok());
        let rope = s.render.rope_color.map(|x| (x * 255.0 * 0.8) as u8);
        assert!(hsv.contains(rgb_to_hsv(rope)));
        let table = s.render.table_color.map(|x| (x * 255.0) as u8);
        assert!(!hsv.contains(rgb_to_hsv(table)));
    }
}
