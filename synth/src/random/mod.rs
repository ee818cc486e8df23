//! Randomised scenes: every property of a scene (rope, table, clutter,
//! camera and its motion, the rope's shape and motion, the occluder, how
//! much it hides and when) drawn from documented distributions by one
//! seed, for a benchmark whose tuning and report seeds never meet.
//!
//! The distributions are the constants below; `docs/synthetic.md` lists
//! them. A draw is pure parameters ([`RandomScene::draw`]); where the
//! settled rope decides a place (clutter, boxes), [`Scenario::random`](crate::Scenario::random)
//! places it and records it in [`RandomScene::placed`].

use alloc::vec::Vec;

use serde::{Deserialize, Serialize};
use upetrack::math::Vec3;
use upetrack::perception::segmentation::{rgb_to_hsv, HUE_MAX, PICK_VALUE_BELOW};
use upetrack::rng::SplitMix64;
use upetrack::{CameraIntrinsics, HsvRange};

pub use crate::camera_path::{CameraPath, Wobble};

use crate::layout::loop_shape;
use crate::render::RenderSettings;
use crate::render::{albedo_rgb8, rope_hsv};
use crate::rope::{Rope, RopeSettings};
use crate::variant::D435I_1280X720;

/// A named range of seeds: `tune` chooses rules and defaults, `report`
/// judges them; no seed is in both.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SeedRange {
    /// Name on the command line (`--random tune`).
    pub name: &'static str,
    /// First seed.
    pub first: u64,
    /// Number of seeds.
    pub count: u64,
}

impl SeedRange {
    /// The tuning range: rules and defaults are chosen on these seeds only.
    pub const TUNE: Self = Self {
        name: "tune",
        first: 1_000,
        count: 100,
    };
    /// The report range: results are quoted on these seeds, never tuned on.
    pub const REPORT: Self = Self {
        name: "report",
        first: 2_000,
        count: 100,
    };
    /// Both ranges.
    pub const ALL: [Self; 2] = [Self::TUNE, Self::REPORT];

    /// The range called `name`.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|r| r.name == name)
    }

    /// Its first `count` seeds (all of them when `count` is larger).
    pub fn seeds(&self, count: u64) -> core::ops::Range<u64> {
        self.first..self.first + count.min(self.count)
    }
}

/// Frames of a drawn scene unless asked otherwise (1.6 s at 30 fps).
pub const DEFAULT_RANDOM_FRAMES: usize = 48;
/// Share of drawn scenes seen at 1280x720 (the rest at 640x480).
pub const HD_SHARE: f64 = 0.35;
/// Rope length, metres (uniform).
pub const ROPE_LENGTH_M: (f64, f64) = (0.3, 1.5);
/// Rope diameter, metres (log-uniform), raised where needed so that the
/// rope is at least [`MIN_ROPE_WIDTH_PX`] wide in the image.
pub const ROPE_DIAMETER_M: (f64, f64) = (0.003, 0.020);
/// Narrowest rope in the image, pixels (a thread any thinner is not
/// something a D435i user would track at that distance).
pub const MIN_ROPE_WIDTH_PX: f64 = 3.0;
/// Camera distance to the table's centre, metres (uniform), raised where
/// needed so that the rope and its motion stay in view.
pub const CAMERA_DISTANCE_M: (f64, f64) = (0.45, 1.0);
/// Camera tilt from straight down, degrees (uniform).
pub const CAMERA_TILT_DEG: (f64, f64) = (0.0, 30.0);
/// Share of the image width kept clear at every side of the rope.
const VIEW_MARGIN: f64 = 0.06;
/// Share of the rope an occluder hides, when there is one (uniform).
pub const HIDDEN_SHARE: (f64, f64) = (0.1, 0.7);
/// Distance an end is dragged, pulled or lifted, metres (uniform).
pub const MOTION_DISTANCE_M: (f64, f64) = (0.05, 0.15);
/// Distance of a fast drag, metres, over a third of the sequence.
pub const FAST_DISTANCE_M: (f64, f64) = (0.15, 0.30);
/// Table texture contrast, times the default grain's (uniform).
pub const TABLE_TEXTURE: (f64, f64) = (0.5, 3.0);
/// Braid pitch, rope diameters (uniform).
pub const BRAID_PITCH_DIAMETERS: (f64, f64) = (0.5, 1.5);
/// Bending compliance of the rope (log-uniform; larger is softer).
pub const BENDING_COMPLIANCE: (f64, f64) = (1e-4, 6e-4);
/// Most clutter objects on the table (uniform from 0).
pub const MAX_CLUTTER: u64 = 3;
/// Chance that a clutter object has the rope's colour (a phone beside a
/// black cable).
pub const CLUTTER_LIKE_ROPE: f64 = 0.3;

/// Kinds of rope colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RopeColour {
    /// A saturated colour of any hue.
    Saturated,
    /// Black or nearly.
    Dark,
    /// Mid grey.
    Grey,
    /// White or off-white.
    White,
    /// Two shades of one hue, strand by strand.
    TwoTone,
}

/// Kinds of table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TableKind {
    /// White or off-white.
    Light,
    /// Wood, light to dark.
    Wood,
    /// Grey laminate.
    Grey,
    /// Dark laminate.
    Dark,
}

/// The shape the rope is laid in.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum ShapeDraw {
    /// A bow: half a sine, `depth` its height over its width.
    Arc {
        /// Height over width.
        depth: f64,
    },
    /// A wave of `periods` periods, `amplitude` over its width.
    Wave {
        /// Periods across.
        periods: f64,
        /// Amplitude over width.
        amplitude: f64,
    },
    /// A loop crossing itself once, the upper strand resting on the lower.
    Loop,
}

/// What the rope does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MotionKind {
    /// Lies still.
    Rest,
    /// One end dragged across its own direction.
    DragSideways,
    /// One end pulled out along its own direction: the rope slides along
    /// itself round its bends.
    PullAlongAxis,
    /// One end lifted and moved a little.
    Lift,
    /// One end dragged fast, over a third of the sequence.
    Fast,
}

/// Kinds of occluder.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OccluderKind {
    /// Nothing hides the rope.
    None,
    /// A rectangle declared in `dlo.json` (the contract's colour masking).
    Rect,
    /// A box held over the rope (seen in depth; declared nowhere).
    Box,
    /// A hand hovering over the rope.
    Hand,
    /// A gripper holding the moving end (or an end, for a resting rope).
    Gripper,
}

/// The camera.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CameraDraw {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Distance to the table's centre, metres (after fitting the view).
    pub distance_m: f64,
    /// The distance drawn before the rope was fitted into the view.
    pub drawn_distance_m: f64,
    /// Tilt from straight down, degrees.
    pub tilt_deg: f64,
    /// How it moves; `None` for a still camera.
    pub motion: Option<CameraPath>,
}

/// The rope.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RopeDraw {
    /// Length, metres.
    pub length_m: f64,
    /// Diameter, metres.
    pub diameter_m: f64,
    /// Kind of colour.
    pub colour: RopeColour,
    /// Albedo, RGB in [0, 1].
    pub rgb: [f64; 3],
    /// Every other strand's albedo, for a two-tone rope.
    pub second_rgb: Option<[f64; 3]>,
    /// Braid pitch, metres.
    pub braid_pitch_m: f64,
    /// Bending compliance.
    pub bending_compliance: f64,
}

/// The table.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TableDraw {
    /// Kind.
    pub kind: TableKind,
    /// Albedo, RGB in [0, 1].
    pub rgb: [f64; 3],
    /// Texture contrast, times the default grain's.
    pub texture: f64,
}

/// A flat thing lying on the table, placed away from the rope.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ClutterDraw {
    /// Length and width, metres.
    pub size_m: [f64; 2],
    /// Height, metres.
    pub height_m: f64,
    /// Albedo, RGB in [0, 1].
    pub rgb: [f64; 3],
    /// Has the rope's colour (passes the rope's colour range).
    pub like_rope: bool,
}

/// What the rope does.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MotionDraw {
    /// Kind.
    pub kind: MotionKind,
    /// The end moved: `false` the first, `true` the last.
    pub last_end: bool,
    /// Distance moved, metres.
    pub distance_m: f64,
    /// First frame of the motion.
    pub start_frame: usize,
    /// Last frame of the motion.
    pub end_frame: usize,
}

/// The occluder.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OccluderDraw {
    /// Kind.
    pub kind: OccluderKind,
    /// Share of the rope it is placed over (0 without an occluder; a hand
    /// and a gripper have their own size, placed over that run's middle
    /// or its end).
    pub share: f64,
    /// Where the run it hides starts, as a share of the rope (0 at the first end).
    pub run_start: f64,
    /// First frame it hides the rope.
    pub first_frame: usize,
    /// Last frame it is there.
    pub last_frame: usize,
    /// Albedo of a box or a hand, RGB in [0, 1].
    pub rgb: [f64; 3],
}

/// Where the settled rope put things, in the world frame (table at z = 0).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Placed {
    /// Each clutter object's corners, metres (objects that found no room
    /// are left out).
    pub clutter: Vec<[[f64; 3]; 2]>,
    /// Each occluder box's corners when in place, metres.
    pub occluder_boxes: Vec<[[f64; 3]; 2]>,
}

/// Everything drawn for one scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RandomScene {
    /// The seed everything was drawn from.
    pub seed: u64,
    /// Frames.
    pub frames: usize,
    /// Frames per second ([`crate::SIMULATED_FPS`] unless asked otherwise,
    /// [`RandomScene::draw_at`]): the simulator steps `1 / fps` seconds a
    /// frame and a hand's wobble is timed in seconds, while every event is
    /// drawn as a share of the sequence, so the same seed at twice the rate
    /// over twice the frames is the same scene filmed twice as often.
    /// Written only when not the default, so that earlier draws keep their
    /// text.
    #[serde(default = "simulated_fps", skip_serializing_if = "is_simulated_fps")]
    pub fps: f64,
    /// The camera.
    pub camera: CameraDraw,
    /// The rope.
    pub rope: RopeDraw,
    /// The table.
    pub table: TableDraw,
    /// Clutter.
    pub clutter: Vec<ClutterDraw>,
    /// The rope's shape.
    pub shape: ShapeDraw,
    /// Rotation of the shape on the table, degrees.
    pub rotation_deg: f64,
    /// The rope's motion.
    pub motion: MotionDraw,
    /// The occluder.
    pub occluder: OccluderDraw,
    /// What the settled rope decided ([`Scenario::random`](crate::Scenario::random) fills it).
    pub placed: Placed,
}

/// [`crate::SIMULATED_FPS`], for serde.
fn simulated_fps() -> f64 {
    crate::SIMULATED_FPS
}

/// Whether `fps` is the default (serde leaves it out then).
fn is_simulated_fps(fps: &f64) -> bool {
    *fps == crate::SIMULATED_FPS
}

/// Picks an index by weights.
fn pick(rng: &mut SplitMix64, weights: &[f64]) -> usize {
    let total: f64 = weights.iter().sum();
    let mut x = rng.uniform() * total;
    for (i, w) in weights.iter().enumerate() {
        if x < *w {
            return i;
        }
        x -= w;
    }
    weights.len() - 1
}

/// Log-uniform in `[lo, hi]`.
fn log_range(rng: &mut SplitMix64, lo: f64, hi: f64) -> f64 {
    libm::exp(rng.range(libm::log(lo), libm::log(hi.max(lo))))
}

/// RGB in [0, 1] from hue (degrees), saturation and value in [0, 1].
pub(crate) fn hsv_to_rgb(h: f64, s: f64, v: f64) -> [f64; 3] {
    let h = (h - 360.0 * libm::floor(h / 360.0)) / 60.0;
    let c = v * s;
    let x = c * (1.0 - libm::fabs(h % 2.0 - 1.0));
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [r + m, g + m, b + m]
}

/// Shading factors a flat surface's albedo is seen at (ambient, light,
/// texture and vignetting together), for testing it against a range.
const SHADES: [f64; 5] = [0.55, 0.7, 0.85, 1.0, 1.1];

/// Colour noise a surface is tested with, 8-bit levels per channel: twice
/// the renderer's standard deviation (2.5 levels), which JPEG's chroma
/// subsampling about doubles again at edges.
const NOISE_LEVELS: f64 = 5.0;

/// How far above a grey or white rope's saturation the colours the scene
/// keeps off its surfaces reach ([`kept_out_range`]).
const KEPT_OUT_GREY_SATURATION: u8 = 40;

/// The colours no table, clutter or skin of a scene may take: the rope's
/// range ([`rope_hsv`]) as simulator 2 picked it. Since simulator 3 a grey
/// or white rope's range allows for colour noise and reaches lower values
/// (`HsvRange::around`); the surfaces are still kept out of the earlier
/// box, so that every seed draws the same scene as before and the
/// benchmark's two ranges stay comparable across that change.
fn kept_out_range(rgb: [f64; 3]) -> HsvRange {
    let range = rope_hsv(rgb);
    if range.chroma_noise == 0 {
        return range;
    }
    let [_, s, v] = rgb_to_hsv(albedo_rgb8(rgb));
    HsvRange::new(
        [0, 0, v.saturating_sub(PICK_VALUE_BELOW)],
        [HUE_MAX, s.saturating_add(KEPT_OUT_GREY_SATURATION), 255],
    )
}

/// `true` when a surface of albedo `rgb` falls in `range` at some shade.
pub(crate) fn passes(range: &HsvRange, rgb: [f64; 3]) -> bool {
    passes_textured(range, rgb, 0.0)
}

/// `true` when some pixel of a surface of albedo `rgb` can fall in
/// `range`: at every shade, with its texture darkening or lightening it by
/// `grain` (a share), and colour noise of [`NOISE_LEVELS`] on each channel
/// either way.
pub(crate) fn passes_textured(range: &HsvRange, rgb: [f64; 3], grain: f64) -> bool {
    SHADES.iter().any(|k| {
        [1.0 - grain, 1.0 + grain].iter().any(|g| {
            (0..8).any(|signs: u32| {
                let px = [0, 1, 2].map(|c| {
                    let n = if signs & (1 << c) == 0 { -1.0 } else { 1.0 };
                    libm::round(rgb[c] * k * g * 255.0 + n * NOISE_LEVELS).clamp(0.0, 255.0) as u8
                });
                range.contains_rgb(px)
            })
        })
    })
}

/// How far the table's grain darkens or lightens it at `texture` times
/// the default contrast (the default grain spans about +-0.045 about 0.97).
fn table_grain(texture: f64) -> f64 {
    0.045 * texture / 0.97
}

/// A colour of `kind` (and a second one for a two-tone rope).
fn rope_colour(rng: &mut SplitMix64, kind: RopeColour) -> ([f64; 3], Option<[f64; 3]>) {
    let grey = |v: f64| [v, v, v * 1.05];
    match kind {
        RopeColour::Saturated => (
            hsv_to_rgb(
                rng.range(0.0, 360.0),
                rng.range(0.6, 0.92),
                rng.range(0.45, 0.85),
            ),
            None,
        ),
        RopeColour::Dark => (grey(rng.range(0.025, 0.07)), None),
        RopeColour::Grey => (grey(rng.range(0.3, 0.55)), None),
        RopeColour::White => (grey(rng.range(0.8, 0.9)), None),
        RopeColour::TwoTone => {
            let (h, s) = (rng.range(0.0, 360.0), rng.range(0.6, 0.92));
            let v = rng.range(0.6, 0.85);
            (
                hsv_to_rgb(h, s, v),
                Some(hsv_to_rgb(h, s, v * rng.range(0.45, 0.65))),
            )
        }
    }
}

/// A table colour of `kind`.
fn table_colour(rng: &mut SplitMix64, kind: TableKind) -> [f64; 3] {
    match kind {
        TableKind::Light => {
            let v = rng.range(0.82, 0.93);
            [v, v * rng.range(0.98, 1.01), v * rng.range(0.95, 1.0)]
        }
        TableKind::Wood => hsv_to_rgb(
            rng.range(25.0, 40.0),
            rng.range(0.3, 0.55),
            rng.range(0.45, 0.85),
        ),
        TableKind::Grey => {
            let v = rng.range(0.45, 0.65);
            [v, v, v * 1.03]
        }
        TableKind::Dark => {
            let v = rng.range(0.12, 0.3);
            [v, v, v * 1.05]
        }
    }
}

/// A colour for an occluder or clutter not in `range`: greys and muted or
/// saturated colours, drawn again while they pass; a mid grey last.
pub(crate) fn colour_outside(rng: &mut SplitMix64, range: &HsvRange) -> [f64; 3] {
    for _ in 0..16 {
        let c = match rng.below(3) {
            0 => {
                let v = rng.range(0.15, 0.85);
                [v, v, v]
            }
            1 => hsv_to_rgb(
                rng.range(0.0, 360.0),
                rng.range(0.15, 0.4),
                rng.range(0.3, 0.8),
            ),
            _ => hsv_to_rgb(
                rng.range(0.0, 360.0),
                rng.range(0.5, 0.9),
                rng.range(0.3, 0.8),
            ),
        };
        if !passes(range, c) {
            return c;
        }
    }
    [0.5, 0.5, 0.5]
}

/// Share of the rope within which an occluder's run counts as reaching an
/// end of it (a run drawn to the end has `run_start + share` one up to
/// rounding).
const END_SHARE_TOLERANCE: f64 = 1e-9;

impl RandomScene {
    /// Whether the end the motion moves lies under the occluder while it
    /// moves: the motion then shows only in the rope it pulls into view, or
    /// not at all when the visible rope does not move with it. Told only for
    /// a rectangle or a box, which cover the drawn run: a hand keeps its own
    /// size over the run's middle, and a gripper holds the moved end
    /// whatever the run and is seen moving it.
    pub fn moved_end_hidden(&self) -> bool {
        let (m, o) = (&self.motion, &self.occluder);
        if m.kind == MotionKind::Rest || !matches!(o.kind, OccluderKind::Rect | OccluderKind::Box) {
            return false;
        }
        let covers_end = if m.last_end {
            o.run_start + o.share >= 1.0 - END_SHARE_TOLERANCE
        } else {
            o.run_start <= END_SHARE_TOLERANCE
        };
        covers_end && o.first_frame <= m.end_frame && o.last_frame >= m.start_frame
    }

    /// Draws a scene of `frames` frames (at least 1) from `seed`. Pure
    /// parameters: the same seed gives the same scene on every platform.
    pub fn draw(seed: u64, frames: usize) -> Self {
        Self::draw_at(seed, frames, crate::SIMULATED_FPS)
    }

    /// [`RandomScene::draw`] filmed at `fps` frames per second (within
    /// [`crate::FPS_RANGE`]; the default rate for a value that is not a
    /// number). Its events stay at the same shares of the sequence: give it
    /// `frames` in proportion to keep their times in seconds.
    pub fn draw_at(seed: u64, frames: usize, fps: f64) -> Self {
        let frames = frames.clamp(1, crate::MAX_FRAMES);
        let (lo, hi) = crate::FPS_RANGE;
        let fps = if fps.is_finite() {
            fps.clamp(lo, hi)
        } else {
            crate::SIMULATED_FPS
        };
        let mut rng = SplitMix64::new(seed ^ 0x5CE7_E5EE_D000_0001);
        let at = |x: f64| ((frames as f64 * x) as usize).min(frames - 1);
        let hd = rng.uniform() < HD_SHARE;
        let length = rng.range(ROPE_LENGTH_M.0, ROPE_LENGTH_M.1);
        let shape = match pick(&mut rng, &[0.3, 0.45, 0.25]) {
            0 => ShapeDraw::Arc {
                depth: rng.range(0.2, 0.6),
            },
            1 => ShapeDraw::Wave {
                periods: rng.range(1.0, 2.5),
                amplitude: rng.range(0.15, 0.35),
            },
            _ => ShapeDraw::Loop,
        };
        let rotation_deg = rng.range(0.0, 360.0);

        let kind = match pick(&mut rng, &[0.2, 0.25, 0.2, 0.15, 0.2]) {
            0 => MotionKind::Rest,
            1 => MotionKind::DragSideways,
            2 => MotionKind::PullAlongAxis,
            3 => MotionKind::Lift,
            _ => MotionKind::Fast,
        };
        let last_end = rng.uniform() < 0.5;
        let (distance_m, start, span) = match kind {
            MotionKind::Rest => (0.0, 0.0, 0.0),
            MotionKind::Fast => (
                rng.range(FAST_DISTANCE_M.0, FAST_DISTANCE_M.1),
                rng.range(0.3, 0.55),
                1.0 / 3.0,
            ),
            _ => (
                rng.range(MOTION_DISTANCE_M.0, MOTION_DISTANCE_M.1),
                rng.range(0.3, 0.55),
                rng.range(0.3, 0.45),
            ),
        };
        let motion = MotionDraw {
            kind,
            last_end,
            distance_m,
            start_frame: at(start),
            end_frame: at((start + span).min(0.95)),
        };

        let okind = match pick(&mut rng, &[0.1, 0.3, 0.2, 0.2, 0.2]) {
            0 => OccluderKind::None,
            1 => OccluderKind::Rect,
            2 => OccluderKind::Box,
            3 => OccluderKind::Hand,
            _ => OccluderKind::Gripper,
        };
        let share = match okind {
            OccluderKind::None => 0.0,
            _ => rng.range(HIDDEN_SHARE.0, HIDDEN_SHARE.1),
        };
        let run_start = match rng.below(5) {
            0 | 1 => 0.0,
            2 => 1.0 - share,
            _ => rng.range(0.0, 1.0 - share),
        };
        let first = rng.range(0.2, 0.45);
        let leaves = rng.uniform() < 0.3;
        let last = if leaves { rng.range(0.7, 0.9) } else { 1.0 };
        let occluder = OccluderDraw {
            kind: okind,
            share,
            run_start,
            first_frame: at(first),
            last_frame: if leaves { at(last) } else { frames - 1 },
            rgb: [0.5; 3],
        };

        let tilt_deg = rng.range(CAMERA_TILT_DEG.0, CAMERA_TILT_DEG.1);
        let drawn_distance = rng.range(CAMERA_DISTANCE_M.0, CAMERA_DISTANCE_M.1);
        let camera_motion = match pick(&mut rng, &[0.5, 0.25, 0.25]) {
            0 => None,
            1 => Some(CameraPath::draw_arm(&mut rng, frames)),
            _ => Some(CameraPath::draw_handheld(&mut rng)),
        };
        let intrinsics = if hd {
            D435I_1280X720
        } else {
            CameraIntrinsics::D435I_640X480
        };
        let mut scene = Self {
            seed,
            frames,
            fps,
            camera: CameraDraw {
                width: intrinsics.width,
                height: intrinsics.height,
                distance_m: drawn_distance,
                drawn_distance_m: drawn_distance,
                tilt_deg,
                motion: camera_motion,
            },
            rope: RopeDraw {
                length_m: length,
                diameter_m: ROPE_DIAMETER_M.1,
                colour: RopeColour::Saturated,
                rgb: [0.5; 3],
                second_rgb: None,
                braid_pitch_m: 0.008,
                bending_compliance: 2e-4,
            },
            table: TableDraw {
                kind: TableKind::Light,
                rgb: [0.9; 3],
                texture: 1.0,
            },
            clutter: Vec::new(),
            shape,
            rotation_deg,
            motion,
            occluder,
            placed: Placed::default(),
        };
        scene.camera.distance_m = scene.fitted_distance(drawn_distance);

        // The rope's size, now that its distance is known.
        let focal = intrinsics.fx.min(intrinsics.fy);
        let thinnest = (MIN_ROPE_WIDTH_PX * scene.camera.distance_m / focal).max(ROPE_DIAMETER_M.0);
        let diameter = log_range(&mut rng, thinnest.min(ROPE_DIAMETER_M.1), ROPE_DIAMETER_M.1);
        let colour = match pick(&mut rng, &[0.4, 0.15, 0.15, 0.1, 0.2]) {
            0 => RopeColour::Saturated,
            1 => RopeColour::Dark,
            2 => RopeColour::Grey,
            3 => RopeColour::White,
            _ => RopeColour::TwoTone,
        };
        let (rgb, second_rgb) = rope_colour(&mut rng, colour);
        scene.rope = RopeDraw {
            length_m: length,
            diameter_m: diameter,
            colour,
            rgb,
            second_rgb,
            braid_pitch_m: diameter * rng.range(BRAID_PITCH_DIAMETERS.0, BRAID_PITCH_DIAMETERS.1),
            bending_compliance: log_range(&mut rng, BENDING_COMPLIANCE.0, BENDING_COMPLIANCE.1),
        };
        let range = kept_out_range(rgb);
        // A table whose pixels can fall in the rope's own colour range
        // leaves nothing to find by colour: drawn again (kind, colour and
        // grain) until none can.
        let mut table = None;
        for _ in 0..32 {
            let kind = match pick(&mut rng, &[0.35, 0.3, 0.2, 0.15]) {
                0 => TableKind::Light,
                1 => TableKind::Wood,
                2 => TableKind::Grey,
                _ => TableKind::Dark,
            };
            let c = table_colour(&mut rng, kind);
            let texture = rng.range(TABLE_TEXTURE.0, TABLE_TEXTURE.1);
            if !passes_textured(&range, c, table_grain(texture)) {
                table = Some((kind, c, texture));
                break;
            }
        }
        let (kind, table_rgb, texture) = table.unwrap_or_else(|| {
            if rgb.iter().sum::<f64>() > 1.5 {
                (TableKind::Dark, [0.15, 0.15, 0.16], 1.0)
            } else {
                (TableKind::Light, [0.9, 0.9, 0.88], 1.0)
            }
        });
        scene.table = TableDraw {
            kind,
            rgb: table_rgb,
            texture,
        };
        scene.occluder.rgb = match okind {
            OccluderKind::Hand => skin(&mut rng, &range),
            _ => colour_outside(&mut rng, &range),
        };
        for _ in 0..rng.below(MAX_CLUTTER + 1) {
            let like_rope = rng.uniform() < CLUTTER_LIKE_ROPE;
            let a = rng.range(0.03, 0.15);
            scene.clutter.push(ClutterDraw {
                size_m: [a, rng.range(0.01, a.min(0.08))],
                height_m: rng.range(0.005, 0.03),
                rgb: if like_rope {
                    rgb
                } else {
                    colour_outside(&mut rng, &range)
                },
                like_rope,
            });
        }
        scene
    }

    /// Frames of this draw to one frame at [`crate::SIMULATED_FPS`]: what
    /// turns a duration drawn in frames at the default rate into this
    /// draw's frames.
    pub(crate) fn frames_per_default_frame(&self) -> f64 {
        self.fps / crate::SIMULATED_FPS
    }

    /// The camera's intrinsics.
    pub fn intrinsics(&self) -> CameraIntrinsics {
        if self.camera.width == D435I_1280X720.width {
            D435I_1280X720
        } else {
            CameraIntrinsics::D435I_640X480
        }
    }

    /// How the scene is rendered at frame 0.
    pub fn render(&self) -> RenderSettings {
        let mut render = RenderSettings {
            camera: self.intrinsics(),
            camera_height: self.camera.distance_m,
            camera_tilt: self.camera.tilt_deg.to_radians(),
            rope_color: self.rope.rgb,
            rope_second_color: self.rope.second_rgb,
            table_color: self.table.rgb,
            table_texture: self.table.texture,
            braid_pitch: self.rope.braid_pitch_m,
            ..RenderSettings::default()
        };
        if let Some(path) = &self.camera.motion {
            (render.camera_shift, render.camera_turn) = path.at(0.0, self.fps);
        }
        render
    }

    /// The rope's physical settings: 10 mm particles (31 to 151 of them).
    pub fn rope_settings(&self) -> RopeSettings {
        RopeSettings {
            length: self.rope.length_m,
            thickness: self.rope.diameter_m,
            particles: (libm::round(self.rope.length_m / 0.01) as usize + 1).clamp(31, 151),
            bending_compliance: self.rope.bending_compliance,
            ..RopeSettings::default()
        }
    }

    /// The shape the rope is laid along, rotated.
    fn layout(&self) -> Vec<Vec3> {
        let raw: Vec<Vec3> = match self.shape {
            ShapeDraw::Arc { depth } => wave(0.5, depth),
            ShapeDraw::Wave { periods, amplitude } => wave(periods, amplitude),
            ShapeDraw::Loop => loop_shape(),
        };
        let n = raw.len().max(1) as f64;
        let c = raw.iter().sum::<Vec3>() / n;
        let a = self.rotation_deg.to_radians();
        let (s, co) = (libm::sin(a), libm::cos(a));
        raw.iter()
            .map(|p| {
                let d = p - c;
                Vec3::new(co * d.x - s * d.y, s * d.x + co * d.y, 0.0)
            })
            .collect()
    }

    /// A rope of `settings` laid along the drawn shape, the middle of its
    /// extent at the table's centre (under the camera).
    pub(crate) fn laid(&self, settings: RopeSettings) -> Rope {
        let mut rope = Rope::laid_along(&self.layout(), settings);
        let (mut lo, mut hi) = (Vec3::repeat(f64::MAX), Vec3::repeat(f64::MIN));
        for p in &rope.x {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        let c = (lo + hi) * 0.5;
        for p in rope.x.iter_mut() {
            p.x -= c.x;
            p.y -= c.y;
        }
        rope
    }

    /// The smallest distance from `drawn` up (by 4 % steps) at which the
    /// laid rope, the moved end's target and the camera's motion stay
    /// inside the image with a margin.
    fn fitted_distance(&self, drawn: f64) -> f64 {
        let rope = self.laid(self.rope_settings_for_fit());
        let mut points = rope.x.clone();
        let n = points.len();
        if self.motion.kind != MotionKind::Rest && n > 6 {
            let (end, inner) = if self.motion.last_end {
                (n - 1, n - 6)
            } else {
                (0, 5)
            };
            let out = (points[end] - points[inner]).normalize();
            let side = Vec3::new(-out.y, out.x, 0.0);
            for dir in [out, side, -side] {
                points.push(points[end] + dir * self.motion.distance_m);
            }
        }
        // Poses every tenth of a second (every third frame at the default rate).
        let rate = self.frames_per_default_frame();
        let poses: Vec<f64> = (0..)
            .map(|k| (3 * k) as f64 * rate)
            .take_while(|&f| f < self.frames as f64)
            .collect();
        let mut distance = drawn;
        for _ in 0..60 {
            let mut render = RenderSettings {
                camera: self.intrinsics(),
                camera_height: distance,
                camera_tilt: self.camera.tilt_deg.to_radians(),
                ..RenderSettings::default()
            };
            let cam = render.camera;
            let (mu, mv) = (
                VIEW_MARGIN * cam.width as f64,
                VIEW_MARGIN * cam.width as f64,
            );
            let fits = poses.iter().all(|&f| {
                if let Some(path) = &self.camera.motion {
                    (render.camera_shift, render.camera_turn) = path.at(f, self.fps);
                }
                points.iter().all(|p| {
                    cam.project(&render.world_to_camera(p)).is_some_and(|q| {
                        q.x >= mu
                            && q.x <= cam.width as f64 - mu
                            && q.y >= mv
                            && q.y <= cam.height as f64 - mv
                    })
                })
            });
            if fits {
                break;
            }
            distance *= 1.04;
        }
        distance
    }

    fn rope_settings_for_fit(&self) -> RopeSettings {
        RopeSettings {
            length: self.rope.length_m,
            ..RopeSettings::default()
        }
    }
}

/// `periods` periods of a sine across a unit width, `amplitude` high.
fn wave(periods: f64, amplitude: f64) -> Vec<Vec3> {
    (0..400)
        .map(|i| {
            let t = i as f64 / 399.0;
            Vec3::new(
                t,
                amplitude * libm::sin(core::f64::consts::TAU * periods * t),
                0.0,
            )
        })
        .collect()
}

/// Skin tones (albedo), light to dark.
const SKIN: [[f64; 3]; 4] = [
    [0.86, 0.68, 0.58],
    [0.76, 0.57, 0.45],
    [0.58, 0.40, 0.30],
    [0.36, 0.24, 0.18],
];
/// A glove, for a rope whose colour range takes every skin tone.
const GLOVE: [f64; 3] = [0.2, 0.3, 0.6];

/// A skin tone outside the rope's colour range (a glove if none is).
fn skin(rng: &mut SplitMix64, range: &HsvRange) -> [f64; 3] {
    let first = rng.below(SKIN.len() as u64) as usize;
    (0..SKIN.len())
        .map(|k| SKIN[(first + k) % SKIN.len()])
        .find(|c| !passes(range, *c))
        .unwrap_or(GLOVE)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::Scenario;

    /// Enough seeds that every kind of every draw turns up.
    const SEEDS: core::ops::Range<u64> = 0..400;

    #[test]
    fn a_seed_draws_the_same_scene_every_time_and_another_seed_another() {
        assert_eq!(RandomScene::draw(7, 48), RandomScene::draw(7, 48));
        assert_ne!(RandomScene::draw(7, 48), RandomScene::draw(8, 48));
        let (a, b) = (Scenario::random(7, 4), Scenario::random(7, 4));
        assert_eq!(a.draw, b.draw);
        assert_eq!(a.rope.x, b.rope.x);
        assert_eq!(a.occlusions, b.occlusions);
        assert!(a.draw.is_some() && a.name == "random-7");
    }

    /// The same seed filmed at half the rate over half the frames is the
    /// same scene: camera and rope where they were at the same second,
    /// within what they move in a frame of the slower rate (events start on
    /// whole frames) and 1.5 cm (a pulled end follows its path in straight
    /// pieces a frame long, coarser at the slower rate, so a fast pull
    /// takes up the slack at slightly other moments: 10 mm on seed 1002).
    /// Fails when the camera's fit or a hand's wobble ignores the rate (the
    /// camera 34 cm off on seed 1003).
    #[test]
    fn a_scene_filmed_at_another_rate_is_the_same_scene_at_the_same_seconds() {
        const SAME_SCENE_MARGIN_M: f64 = 0.015;
        // Arm, hand with a pull along the axis, a fast pull.
        for seed in [1013, 1003, 1002] {
            let mut fast = Scenario::random(seed, 48);
            let mut slow = Scenario::random_at(seed, 24, 15.0);
            assert_eq!((fast.fps(), slow.fps()), (30.0, 15.0));
            let (a, b) = (fast.draw.clone(), slow.draw.clone());
            assert_eq!(
                a.map(|d| d.camera.distance_m),
                b.map(|d| d.camera.distance_m)
            );
            // The camera's centre first, then the rope's centre line.
            let seen = |f: crate::scenario::SynthFrame| {
                let mut at = alloc::vec![f.camera_pose.centre];
                at.extend(f.groundtruth);
                at
            };
            let slow: Vec<Vec<Vec3>> = (0..24)
                .filter_map(|_| slow.next_frame())
                .map(seen)
                .collect();
            for (k, b) in slow.iter().enumerate() {
                let a = seen(fast.next_frame().expect("frame"));
                fast.next_frame();
                let (before, after) = (&slow[k.saturating_sub(1)], &slow[(k + 1).min(23)]);
                assert_eq!(a.len(), b.len(), "seed {seed}");
                for (i, (p, q)) in a.iter().zip(b).enumerate() {
                    let frame_move = (before[i] - q).norm().max((after[i] - q).norm());
                    let off = (p - q).norm();
                    assert!(
                        off <= frame_move + SAME_SCENE_MARGIN_M,
                        "seed {seed}, second {:.2}, point {i}: {:.1} mm off, {:.1} mm a frame",
                        k as f64 / 15.0,
                        off * 1000.0,
                        frame_move * 1000.0
                    );
                }
            }
        }
    }

    #[test]
    fn the_tuning_and_report_ranges_never_meet() {
        let (t, r) = (SeedRange::TUNE, SeedRange::REPORT);
        assert!(t.count >= 100 && r.count >= 100);
        assert!(t.seeds(u64::MAX).all(|s| !r.seeds(u64::MAX).contains(&s)));
        assert_eq!(SeedRange::parse("report"), Some(r));
        assert_eq!(r.seeds(3), 2000..2003);
    }

    #[test]
    fn draws_cover_the_stated_ranges() {
        let draws: Vec<RandomScene> = SEEDS.map(|s| RandomScene::draw(s, 48)).collect();
        let span = |f: &dyn Fn(&RandomScene) -> f64| {
            let v: Vec<f64> = draws.iter().map(f).collect();
            (
                v.iter().copied().fold(f64::MAX, f64::min),
                v.iter().copied().fold(f64::MIN, f64::max),
            )
        };
        let within = |(lo, hi): (f64, f64), (a, b): (f64, f64), reach: f64| {
            lo >= a && hi <= b && lo < a + reach * (b - a) && hi > b - reach * (b - a)
        };
        assert!(within(span(&|d| d.rope.length_m), ROPE_LENGTH_M, 0.05));
        assert!(within(span(&|d| d.rope.diameter_m), ROPE_DIAMETER_M, 0.1));
        assert!(within(span(&|d| d.camera.tilt_deg), CAMERA_TILT_DEG, 0.05));
        assert!(within(
            span(&|d| d.camera.drawn_distance_m),
            CAMERA_DISTANCE_M,
            0.05
        ));
        let shares: Vec<&RandomScene> = draws
            .iter()
            .filter(|d| d.occluder.kind != OccluderKind::None)
            .collect();
        let lo = shares.iter().map(|d| d.occluder.share).fold(1.0, f64::min);
        let hi = shares.iter().map(|d| d.occluder.share).fold(0.0, f64::max);
        assert!(
            (0.1..0.15).contains(&lo) && hi <= 0.7 && hi > 0.65,
            "{lo} {hi}"
        );
        for d in &draws {
            assert!(d.camera.distance_m >= d.camera.drawn_distance_m);
            let f = d.intrinsics().fx;
            assert!(d.rope.diameter_m * f / d.camera.distance_m >= MIN_ROPE_WIDTH_PX - 1e-9);
            assert!(d.clutter.len() as u64 <= MAX_CLUTTER);
            assert!(d.motion.start_frame <= d.motion.end_frame && d.motion.end_frame < 48);
        }
        let has = |p: &dyn Fn(&RandomScene) -> bool| draws.iter().any(p);
        for c in [
            RopeColour::Saturated,
            RopeColour::Dark,
            RopeColour::Grey,
            RopeColour::White,
            RopeColour::TwoTone,
        ] {
            assert!(has(&|d| d.rope.colour == c), "{c:?}");
        }
        for t in [
            TableKind::Light,
            TableKind::Wood,
            TableKind::Grey,
            TableKind::Dark,
        ] {
            assert!(has(&|d| d.table.kind == t), "{t:?}");
        }
        for m in [
            MotionKind::Rest,
            MotionKind::DragSideways,
            MotionKind::PullAlongAxis,
            MotionKind::Lift,
            MotionKind::Fast,
        ] {
            assert!(has(&|d| d.motion.kind == m), "{m:?}");
        }
        for o in [
            OccluderKind::None,
            OccluderKind::Rect,
            OccluderKind::Box,
            OccluderKind::Hand,
            OccluderKind::Gripper,
        ] {
            assert!(has(&|d| d.occluder.kind == o), "{o:?}");
        }
        assert!(has(&|d| matches!(d.shape, ShapeDraw::Loop)));
        assert!(has(&|d| matches!(d.shape, ShapeDraw::Arc { .. })));
        assert!(has(&|d| matches!(d.shape, ShapeDraw::Wave { .. })));
        assert!(has(&|d| d.camera.motion.is_none()));
        assert!(has(&|d| matches!(
            d.camera.motion,
            Some(CameraPath::Arm { .. })
        )));
        assert!(has(&|d| matches!(
            d.camera.motion,
            Some(CameraPath::Handheld { .. })
        )));
        assert!(has(&|d| d.camera.width == 1280) && has(&|d| d.camera.width == 640));
        for k in 0..=MAX_CLUTTER as usize {
            assert!(has(&|d| d.clutter.len() == k), "{k} clutter");
        }
        assert!(has(&|d| d.clutter.iter().any(|c| c.like_rope)));
    }

    #[test]
    fn no_table_passes_the_ropes_colour_range() {
        for s in SEEDS {
            let d = RandomScene::draw(s, 48);
            assert!(
                !passes(&kept_out_range(d.rope.rgb), d.table.rgb),
                "seed {s}: {d:?}"
            );
            assert!(passes(&rope_hsv(d.rope.rgb), d.rope.rgb), "seed {s}");
        }
    }

    #[test]
    fn a_moved_end_under_the_occluder_while_it_moves_is_told() {
        // Report seeds 2093 (the last end dragged under a rectangle over
        // the last 54 %) and 2027 (the first end moved under a box over the
        // first 49 %); 2066's rectangle stops short of the moved end. A hand
        // (2041) and a gripper (2065) drawn over the moved end's run do not
        // count: the run does not say what they cover.
        for (seed, hidden) in [
            (2093, true),
            (2027, true),
            (2066, false),
            (2041, false),
            (2065, false),
        ] {
            assert_eq!(
                RandomScene::draw(seed, 48).moved_end_hidden(),
                hidden,
                "seed {seed}"
            );
        }
        // Moved before the occluder comes, or at rest: not hidden.
        let mut d = RandomScene::draw(2093, 48);
        d.occluder.first_frame = d.motion.end_frame + 1;
        assert!(!d.moved_end_hidden());
        d.occluder.first_frame = 0;
        d.motion.kind = MotionKind::Rest;
        assert!(!d.moved_end_hidden());
    }

    #[test]
    fn the_settled_rope_starts_in_view_and_the_camera_path_starts_where_drawn() {
        for seed in 2000..2012 {
            let s = Scenario::random(seed, 48);
            let cam = s.render.camera;
            for p in &s.rope.x {
                let q = cam
                    .project(&s.render.world_to_camera(p))
                    .expect("in front of the camera");
                assert!(
                    q.x >= 0.0 && q.y >= 0.0 && q.x < cam.width as f64 && q.y < cam.height as f64,
                    "seed {seed}: {q:?}"
                );
            }
            if let Some(path) = s.draw.as_ref().and_then(|d| d.camera.motion) {
                assert_eq!(path.at(0.0, 30.0), ([0.0; 3], [0.0; 3]), "seed {seed}");
            }
        }
    }

    #[test]
    fn an_arm_ends_its_move_where_drawn() {
        let mut rng = SplitMix64::new(3);
        let path = CameraPath::draw_arm(&mut rng, 48);
        let CameraPath::Arm {
            shift, turn, end, ..
        } = path
        else {
            panic!("an arm");
        };
        assert_eq!(path.at(end as f64, 30.0), (shift, turn));
        let moved = libm::sqrt(shift.iter().map(|x| x * x).sum::<f64>());
        assert!(
            moved > 0.5 * crate::camera_path::ARM_SHIFT_M.0
                && moved <= crate::camera_path::ARM_SHIFT_M.1
        );
    }
}
