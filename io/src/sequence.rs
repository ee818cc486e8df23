//! A sequence in the contract's layout: intrinsics, optional `dlo.json` and
//! ground truth, and colour/depth frame pairs decoded on demand.

use std::cell::RefCell;

use serde::{Deserialize, Serialize};
use upetrack::math::Vec3;
use upetrack::perception::initialisation::RopePrior;
use upetrack::several::MAX_ROPES;
use upetrack::tracker::TrackerError;
use upetrack::{CameraIntrinsics, Frame, HsvRange, MultiTracker, Params, Rect, Tracker};

use crate::decode::{decode_color, decode_depth, DepthImage, RgbImage};
use crate::error::SequenceError;
use crate::recording_info::RecordingInfo;
use crate::ropes::Truth;
pub use crate::ropes::{RopeConfig, RopeEntry, SegmentationConfig, SequenceRope};
use crate::source::{is_inside_name, Source};

/// Most frames accepted in one sequence.
pub const MAX_FRAMES: usize = 100_000;
/// Most ground-truth points per frame.
pub const MAX_GROUNDTRUTH_POINTS: usize = 100_000;
/// Most occlusion entries in `dlo.json`.
pub const MAX_OCCLUSIONS: usize = 10_000;
/// Largest JSON file read, bytes.
pub const MAX_JSON_BYTES: usize = 64 * 1024 * 1024;

use upetrack::perception::camera::is_frame_rate;
pub use upetrack::perception::camera::{DEFAULT_DEPTH_SCALE, DEFAULT_FPS, MAX_FPS};
/// Colour folder names accepted, in order of preference.
pub const COLOR_DIRS: [&str; 3] = ["color", "rgb", "image"];

/// `camera_intrinsic.json` / `intrinsic.json` (Open3D's PinholeCameraIntrinsic).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct IntrinsicsFile {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Column-major 3x3: `[fx, 0, 0, 0, fy, 0, cx, cy, 1]`.
    pub intrinsic_matrix: Vec<f64>,
    /// Depth units per metre (Open3D's newer file), e.g. 1000.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth_scale: Option<f64>,
    /// Frames per second (Open3D's newer file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fps: Option<f64>,
}

impl IntrinsicsFile {
    /// The file for `camera`.
    pub fn from_camera(camera: &CameraIntrinsics) -> Self {
        Self {
            width: camera.width,
            height: camera.height,
            intrinsic_matrix: vec![
                camera.fx, 0.0, 0.0, 0.0, camera.fy, 0.0, camera.cx, camera.cy, 1.0,
            ],
            depth_scale: None,
            fps: None,
        }
    }
}

/// One occlusion entry of `dlo.json`: colour pixels of `rect` blacked out
/// for frames `frames[0]..=frames[1]`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct OcclusionConfig {
    /// Inclusive frame range.
    pub frames: [u64; 2],
    /// `[x, y, w, h]` in pixels.
    pub rect: [i64; 4],
}

impl OcclusionConfig {
    /// The rectangle.
    pub fn rect(&self) -> Rect {
        let [x, y, w, h] = self.rect;
        Rect { x, y, w, h }
    }

    /// `true` when it applies to frame `index`.
    pub fn active_at(&self, index: usize) -> bool {
        (self.frames[0]..=self.frames[1]).contains(&(index as u64))
    }
}

/// `dlo.json`: what this project adds to a recording. Unknown keys are ignored.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, Default)]
pub struct DloConfig {
    /// Metres per depth unit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth_scale: Option<f64>,
    /// Frames per second.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fps: Option<f64>,
    /// HSV thresholds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub segmentation: Option<SegmentationConfig>,
    /// Occlusion rectangles.
    #[serde(
        default,
        deserialize_with = "crate::capped::vec::<_, _, MAX_OCCLUSIONS>"
    )]
    pub occlusions: Vec<OcclusionConfig>,
    /// Ground-truth file name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub groundtruth: Option<String>,
    /// What the user knows of the rope.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rope: Option<RopeConfig>,
    /// Several ropes, each with what is its own (an extension; absent or
    /// empty: the one rope the keys above describe).
    #[serde(
        default,
        skip_serializing_if = "Vec::is_empty",
        deserialize_with = "crate::capped::vec::<_, _, MAX_ROPES>"
    )]
    pub ropes: Vec<RopeEntry>,
}

impl DloConfig {
    /// Parses `dlo.json`'s bytes (`path` names it in errors) and checks it.
    pub fn parse(bytes: &[u8], path: &str) -> Result<Self, SequenceError> {
        let config: Self = parse_json(bytes, path)?;
        config.check(path)?;
        Ok(config)
    }

    /// Checks the HSV range, the occlusions and the ground-truth name, and
    /// returns the HSV range in force (the default when absent).
    pub fn check(&self, path: &str) -> Result<HsvRange, SequenceError> {
        let hsv = match &self.segmentation {
            Some(s) => {
                let r = s.range();
                r.validate()
                    .map_err(|e| SequenceError::invalid(path, format!("segmentation: {e}")))?;
                r
            }
            None => HsvRange::default(),
        };
        if self.occlusions.len() > MAX_OCCLUSIONS {
            return Err(SequenceError::too_large(
                path,
                "number of occlusions",
                self.occlusions.len() as u64,
                MAX_OCCLUSIONS as u64,
            ));
        }
        for (i, o) in self.occlusions.iter().enumerate() {
            if o.frames[0] > o.frames[1] {
                return Err(SequenceError::invalid(
                    path,
                    format!("occlusions[{i}]: frames {:?} run backwards", o.frames),
                ));
            }
            if o.rect[2] < 0 || o.rect[3] < 0 {
                return Err(SequenceError::invalid(
                    path,
                    format!("occlusions[{i}]: negative width or height in {:?}", o.rect),
                ));
            }
        }
        if let Some(rope) = &self.rope {
            rope.prior()
                .validate()
                .map_err(|e| SequenceError::invalid(path, format!("rope: {e}")))?;
        }
        crate::ropes::check_ropes(&self.ropes, path)?;
        if let Some(gt) = &self.groundtruth {
            if !is_inside_name(gt) {
                return Err(SequenceError::invalid(
                    path,
                    format!(
                        "groundtruth {gt:?} must name a file inside the sequence folder \
                         (a relative path without `..`)"
                    ),
                ));
            }
        }
        Ok(hsv)
    }
}

/// One frame of `groundtruth.json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct GroundTruthFrame {
    /// Frame index.
    pub frame: usize,
    /// Ordered centre-line points, metres, colour camera frame.
    #[serde(deserialize_with = "crate::capped::vec::<_, _, MAX_GROUNDTRUTH_POINTS>")]
    pub points: Vec<[f64; 3]>,
    /// Optional: for each point, whether an occluder hides it from the
    /// camera (written by `upetrack synth`; evaluation counts the frames
    /// from the first such one as occluded when no rectangle says so).
    #[serde(
        default,
        skip_serializing_if = "Vec::is_empty",
        deserialize_with = "crate::capped::vec::<_, _, MAX_GROUNDTRUTH_POINTS>"
    )]
    pub occluded: Vec<bool>,
}

/// `groundtruth.json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, Default)]
pub struct GroundTruthFile {
    /// Frames with a reference (any may be missing).
    #[serde(deserialize_with = "crate::capped::vec::<_, _, MAX_FRAMES>")]
    pub frames: Vec<GroundTruthFrame>,
}

/// Reads the ground truth `name` for a sequence of `frames` frames: the
/// points per frame and whether an occluder hides some of them. A missing
/// file is an error only when `named` (by `dlo.json`).
pub(crate) fn read_groundtruth<S: Source>(
    source: &S,
    name: &str,
    named: bool,
    frames: usize,
) -> Result<Truth, SequenceError> {
    let mut groundtruth = vec![None; frames];
    let mut groundtruth_occluded = vec![false; frames];
    if source.is_file(name) {
        let gt: GroundTruthFile = read_json(source, name)?;
        let gt_path = source.display(name);
        for f in gt.frames {
            if f.points.len() > MAX_GROUNDTRUTH_POINTS {
                return Err(SequenceError::too_large(
                    gt_path,
                    "ground-truth points in one frame",
                    f.points.len() as u64,
                    MAX_GROUNDTRUTH_POINTS as u64,
                ));
            }
            if f.points.iter().flatten().any(|c| !c.is_finite()) {
                return Err(SequenceError::invalid(
                    &gt_path,
                    format!("frame {}: non-finite point", f.frame),
                ));
            }
            if let Some(slot) = groundtruth_occluded.get_mut(f.frame) {
                *slot = f.occluded.iter().any(|&o| o);
            }
            if let Some(slot) = groundtruth.get_mut(f.frame) {
                *slot = Some(
                    f.points
                        .iter()
                        .map(|p| Vec3::new(p[0], p[1], p[2]))
                        .collect(),
                );
            }
        }
    } else if named {
        return Err(SequenceError::Missing {
            path: source.display(name),
            what: "ground truth named in dlo.json",
        });
    }
    Ok(Truth {
        points: groundtruth,
        occluded: groundtruth_occluded,
    })
}

/// A decoded colour/depth pair.
#[derive(Debug, Clone)]
pub struct DecodedFrame {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// RGB8.
    pub color: Vec<u8>,
    /// Depth units.
    pub depth: Vec<u16>,
}

impl DecodedFrame {
    /// The core's borrowed view.
    pub fn frame(
        &self,
        depth_scale: f64,
    ) -> Result<Frame<'_>, upetrack::perception::frame::FrameError> {
        Frame::new(
            self.width,
            self.height,
            &self.color,
            &self.depth,
            depth_scale,
        )
    }
}

/// Frames read from something other than image files: a camera recording.
pub trait FrameReader {
    /// Decodes frame `index`.
    fn frame(&mut self, index: usize) -> Result<DecodedFrame, SequenceError>;
    /// What the recording holds, for `upetrack info` and the page.
    fn info(&self) -> RecordingInfo;
    /// When frame `index` was taken, seconds from the recording's first message.
    fn time_s(&self, index: usize) -> Option<f64>;
}

/// An opened sequence: metadata read and checked, frames decoded on demand.
pub struct Sequence<S: Source> {
    source: S,
    /// Colour intrinsics.
    pub camera: CameraIntrinsics,
    /// Metres per depth unit in force.
    pub depth_scale: f64,
    /// Frames per second.
    pub fps: f64,
    /// HSV range in force (the `dlo.json` one, or the default).
    pub hsv: HsvRange,
    /// `dlo.json` as read (defaults when absent).
    pub config: DloConfig,
    /// Ground truth per frame index, when available.
    pub groundtruth: Vec<Option<Vec<Vec3>>>,
    /// Per frame index: the ground truth says an occluder hides part of the rope.
    pub groundtruth_occluded: Vec<bool>,
    /// Every rope to track: the one of `dlo.json`'s top-level keys, or
    /// those of its `ropes` (the first's colour, ground truth and prior
    /// are then also `hsv`, `groundtruth` and `rope_prior`'s).
    pub ropes: Vec<SequenceRope>,
    /// Relative paths of colour frames, name-sorted.
    pub color_files: Vec<String>,
    /// Relative paths of depth frames, name-sorted.
    pub depth_files: Vec<String>,
    /// Where the frames come from when they are not image files (a recording).
    reader: Option<RefCell<Box<dyn FrameReader>>>,
}

/// A frame's colour and depth images decoded, or why not.
type Decoded = (
    Result<RgbImage, SequenceError>,
    Result<DepthImage, SequenceError>,
);

/// Decodes a frame's colour and depth files at once where there are
/// threads: the depth on a second thread (the two take about as long), so
/// a frame is ready in the time of the slower one.
#[cfg(not(target_arch = "wasm32"))]
fn decode_pair(color: (&[u8], &str), depth: (&[u8], &str)) -> Decoded {
    std::thread::scope(|scope| {
        let helper = std::thread::Builder::new()
            .name("depth decoder".into())
            .spawn_scoped(scope, || decode_depth(depth.0, depth.1));
        let rgb = decode_color(color.0, color.1);
        let depth = match helper {
            Ok(h) => h.join().unwrap_or_else(|_| {
                Err(SequenceError::invalid(depth.1, "the depth decoder stopped"))
            }),
            // No thread to be had: in turn.
            Err(_) => decode_depth(depth.0, depth.1),
        };
        (rgb, depth)
    })
}

/// Decodes a frame's colour and depth files in turn (no threads here).
#[cfg(target_arch = "wasm32")]
fn decode_pair(color: (&[u8], &str), depth: (&[u8], &str)) -> Decoded {
    (
        decode_color(color.0, color.1),
        decode_depth(depth.0, depth.1),
    )
}

fn read_json<T: serde::de::DeserializeOwned, S: Source>(
    source: &S,
    path: &str,
) -> Result<T, SequenceError> {
    parse_json(&source.read(path)?, &source.display(path))
}

/// JSON of at most [`MAX_JSON_BYTES`] parsed into `T`; `path` names it in errors.
pub(crate) fn parse_json<T: serde::de::DeserializeOwned>(
    bytes: &[u8],
    path: &str,
) -> Result<T, SequenceError> {
    if bytes.len() > MAX_JSON_BYTES {
        return Err(SequenceError::too_large(
            path,
            "JSON size in bytes",
            bytes.len() as u64,
            MAX_JSON_BYTES as u64,
        ));
    }
    serde_json::from_slice(bytes).map_err(|e| SequenceError::Json {
        path: path.to_string(),
        message: e.to_string(),
    })
}

fn sorted_files<S: Source>(
    source: &S,
    dir: &str,
    exts: &[&str],
) -> Result<Vec<String>, SequenceError> {
    let mut names: Vec<String> = source
        .list(dir)?
        .into_iter()
        .filter(|n| {
            let lower = n.to_ascii_lowercase();
            !n.starts_with('.') && exts.iter().any(|e| lower.ends_with(e))
        })
        .collect();
    check_frame_count(source.display(dir), names.len())?;
    names.sort();
    Ok(names.into_iter().map(|n| format!("{dir}/{n}")).collect())
}

/// An error when a sequence of `n` frames (a folder's listing, a
/// recording's pairs) is above [`MAX_FRAMES`]; `path` names it.
pub(crate) fn check_frame_count(path: String, n: usize) -> Result<(), SequenceError> {
    if n > MAX_FRAMES {
        return Err(SequenceError::too_large(
            path,
            "number of frames",
            n as u64,
            MAX_FRAMES as u64,
        ));
    }
    Ok(())
}

/// `dlo.json` of `source`, or the defaults when there is none.
fn read_config<S: Source>(source: &S) -> Result<DloConfig, SequenceError> {
    if source.is_file("dlo.json") {
        DloConfig::parse(&source.read("dlo.json")?, &source.display("dlo.json"))
    } else {
        Ok(DloConfig::default())
    }
}

/// Depth scale (metres per unit) and frame rate: `dlo.json`'s, else the
/// intrinsics' or recording's (`units_per_metre`, `fps`), else the defaults.
fn rates<S: Source>(
    source: &S,
    config: &DloConfig,
    units_per_metre: Option<f64>,
    fps: Option<f64>,
) -> Result<(f64, f64), SequenceError> {
    let dlo_path = source.display("dlo.json");
    let depth_scale = match (config.depth_scale, units_per_metre) {
        (Some(s), _) => s,
        (None, Some(units_per_metre)) if units_per_metre != 0.0 => 1.0 / units_per_metre,
        _ => DEFAULT_DEPTH_SCALE,
    };
    if !(depth_scale.is_finite() && depth_scale > 0.0 && depth_scale < 1.0) {
        return Err(SequenceError::invalid(
            &dlo_path,
            format!("depth_scale {depth_scale} must be finite and in (0, 1) metres per unit"),
        ));
    }
    let fps = config.fps.or(fps).unwrap_or(DEFAULT_FPS);
    if !is_frame_rate(fps) {
        return Err(SequenceError::invalid(
            &dlo_path,
            format!("fps {fps} must be in (0, {MAX_FPS}]"),
        ));
    }
    Ok((depth_scale, fps))
}

/// Parses and checks an intrinsics file.
pub fn camera_from_file(
    file: &IntrinsicsFile,
    path: &str,
) -> Result<CameraIntrinsics, SequenceError> {
    let m = &file.intrinsic_matrix;
    if m.len() != 9 {
        return Err(SequenceError::invalid(
            path,
            format!("intrinsic_matrix has {} values, expected 9", m.len()),
        ));
    }
    let camera = CameraIntrinsics {
        width: file.width,
        height: file.height,
        fx: m[0],
        fy: m[4],
        cx: m[6],
        cy: m[7],
    };
    camera
        .validate()
        .map_err(|e| SequenceError::invalid(path, e.to_string()))?;
    Ok(camera)
}

impl<S: Source> Sequence<S> {
    /// Reads and checks the metadata and lists the frames. No image is decoded.
    pub fn open(source: S) -> Result<Self, SequenceError> {
        let intr_path = ["camera_intrinsic.json", "intrinsic.json"]
            .into_iter()
            .find(|p| source.is_file(p))
            .ok_or_else(|| SequenceError::Missing {
                path: source.display("camera_intrinsic.json"),
                what: "colour intrinsics (camera_intrinsic.json or intrinsic.json)",
            })?;
        let intr: IntrinsicsFile = read_json(&source, intr_path)?;
        let camera = camera_from_file(&intr, &source.display(intr_path))?;

        let config = read_config(&source)?;
        let (depth_scale, fps) = rates(&source, &config, intr.depth_scale, intr.fps)?;
        let color_dir = COLOR_DIRS
            .into_iter()
            .find(|d| source.is_dir(d))
            .ok_or_else(|| SequenceError::Missing {
                path: source.display("color"),
                what: "colour frames folder (color/, rgb/ or image/)",
            })?;
        if !source.is_dir("depth") {
            return Err(SequenceError::Missing {
                path: source.display("depth"),
                what: "depth frames folder",
            });
        }
        let color_files = sorted_files(&source, color_dir, &[".jpg", ".jpeg", ".png"])?;
        let depth_files = sorted_files(&source, "depth", &[".png"])?;
        if color_files.is_empty() {
            return Err(SequenceError::invalid(
                &source.display(color_dir),
                "no .jpg or .png frames",
            ));
        }
        if color_files.len() != depth_files.len() {
            return Err(SequenceError::invalid(
                &source.display(""),
                format!(
                    "{} colour frames but {} depth frames: frames pair by position, so the counts must match",
                    color_files.len(),
                    depth_files.len()
                ),
            ));
        }

        Self::assemble(
            source,
            camera,
            (depth_scale, fps),
            config,
            (color_files, depth_files),
            None,
        )
    }

    /// A sequence whose frames come from `reader` (`len` of them, named
    /// `names`), with `source` giving its `dlo.json` (and the ground truth it
    /// names) in place of a folder's. The reader's depth units and frame
    /// rate stand unless `dlo.json` sets them.
    pub(crate) fn with_reader(
        source: S,
        camera: CameraIntrinsics,
        (units_per_metre, fps): (f64, f64),
        names: Vec<String>,
        reader: Box<dyn FrameReader>,
    ) -> Result<Self, SequenceError> {
        let config = read_config(&source)?;
        let rates = rates(&source, &config, Some(units_per_metre), Some(fps))?;
        Self::assemble(
            source,
            camera,
            rates,
            config,
            (names.clone(), names),
            Some(RefCell::new(reader)),
        )
    }

    fn assemble(
        source: S,
        camera: CameraIntrinsics,
        (depth_scale, fps): (f64, f64),
        config: DloConfig,
        (color_files, depth_files): (Vec<String>, Vec<String>),
        reader: Option<RefCell<Box<dyn FrameReader>>>,
    ) -> Result<Self, SequenceError> {
        check_frame_count(source.display(""), color_files.len())?;
        let hsv = config.check(&source.display("dlo.json"))?;
        let gt_name = config
            .groundtruth
            .clone()
            .unwrap_or_else(|| "groundtruth.json".to_string());
        let frames = color_files.len();
        let truth = read_groundtruth(&source, &gt_name, config.groundtruth.is_some(), frames)?;
        let read = |name: &str| read_groundtruth(&source, name, true, frames);
        let ropes =
            crate::ropes::sequence_ropes(&config.ropes, (hsv, config.rope), frames, &read, |k| {
                (k == 0).then(|| truth.clone())
            })?;
        // The first rope's are the sequence's (readers of one rope).
        let hsv = ropes.first().map_or(hsv, |r| r.hsv);
        let (groundtruth, groundtruth_occluded) = match ropes.first() {
            Some(r) => (r.groundtruth.clone(), r.groundtruth_occluded.clone()),
            None => (truth.points, truth.occluded),
        };
        Ok(Self {
            source,
            camera,
            depth_scale,
            fps,
            hsv,
            config,
            groundtruth,
            groundtruth_occluded,
            ropes,
            color_files,
            depth_files,
            reader,
        })
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.color_files.len()
    }

    /// `true` when there are no frames (never, once opened).
    pub fn is_empty(&self) -> bool {
        self.color_files.is_empty()
    }

    /// The occlusion rectangles active at frame `index`.
    pub fn occlusions_at(&self, index: usize) -> Vec<Rect> {
        self.config
            .occlusions
            .iter()
            .filter(|o| o.active_at(index))
            .map(OcclusionConfig::rect)
            .collect()
    }

    /// The first frame any occlusion applies to: a rectangle of `dlo.json`,
    /// or a frame whose ground truth marks points hidden by an occluder.
    pub fn first_occluded_frame(&self) -> Option<usize> {
        let rect = self.config.occlusions.iter().map(|o| o.frames[0] as usize);
        let truth = self.groundtruth_occluded.iter().position(|&o| o);
        rect.chain(truth).min()
    }

    /// [`Sequence::first_occluded_frame`] for rope `k`: a rectangle, or a
    /// frame whose ground truth of that rope marks points hidden.
    pub fn first_occluded_frame_of(&self, k: usize) -> Option<usize> {
        let rect = self.config.occlusions.iter().map(|o| o.frames[0] as usize);
        let truth = self.ropes.get(k).and_then(|r| r.first_occluded_frame());
        rect.chain(truth).min()
    }

    /// What `dlo.json` says of the rope (nothing when absent).
    pub fn rope_prior(&self) -> RopePrior {
        self.ropes.first().map(|r| r.prior).unwrap_or_default()
    }

    /// A tracker for this sequence: its camera, frame rate, colour range
    /// and rope prior (of the first rope, when `dlo.json` lists several).
    pub fn tracker(&self, params: Params) -> Result<Tracker, TrackerError> {
        let mut t = Tracker::new(params, self.camera, self.hsv)?;
        t.set_rope_prior(self.rope_prior())?;
        t.set_frame_rate(self.fps)?;
        Ok(t)
    }

    /// A tracker of every rope of this sequence at its frame rate, each
    /// with its colour range and prior (one rope: [`Sequence::tracker`]'s,
    /// alone).
    pub fn multi_tracker(&self, params: Params) -> Result<MultiTracker, TrackerError> {
        let trackers = self
            .ropes
            .iter()
            .map(|r| {
                let mut t = Tracker::new(params, self.camera, r.hsv)?;
                t.set_rope_prior(r.prior)?;
                t.set_rope_hint(r.hint);
                t.set_frame_rate(self.fps)?;
                Ok(t)
            })
            .collect::<Result<Vec<_>, TrackerError>>()?;
        MultiTracker::new(trackers)
    }

    /// When frame `index` was taken, seconds: a recording's own colour
    /// time from its first message, else the index over the frame rate
    /// (a folder's frames are evenly spaced at `dlo.json`'s `fps`).
    pub fn time_s(&self, index: usize) -> f64 {
        self.reader
            .as_ref()
            .and_then(|r| r.borrow().time_s(index))
            .unwrap_or(index as f64 / self.fps)
    }

    /// How messages name frame `index`: its colour file.
    pub fn frame_name(&self, index: usize) -> String {
        self.color_files
            .get(index)
            .cloned()
            .unwrap_or_else(|| format!("frame {index}"))
    }

    /// Reads and decodes frame `index`, checking both images against the intrinsics.
    pub fn frame(&self, index: usize) -> Result<DecodedFrame, SequenceError> {
        if let Some(reader) = &self.reader {
            return reader.borrow_mut().frame(index);
        }
        let (Some(cpath), Some(dpath)) = (self.color_files.get(index), self.depth_files.get(index))
        else {
            return Err(SequenceError::invalid(
                &self.source.display(""),
                format!("no frame {index}"),
            ));
        };
        let color_bytes = self.source.read(cpath)?;
        let depth_bytes = self.source.read(dpath)?;
        let (color, depth) = decode_pair(
            (&color_bytes, &self.source.display(cpath)),
            (&depth_bytes, &self.source.display(dpath)),
        );
        let (color, depth) = (color?, depth?);
        for (path, w, h) in [
            (cpath, color.width, color.height),
            (dpath, depth.width, depth.height),
        ] {
            if (w, h) != (self.camera.width, self.camera.height) {
                return Err(SequenceError::invalid(
                    &self.source.display(path),
                    format!(
                        "image is {w}x{h} but the intrinsics say {}x{}",
                        self.camera.width, self.camera.height
                    ),
                ));
            }
        }
        Ok(DecodedFrame {
            width: color.width,
            height: color.height,
            color: color.data,
            depth: depth.data,
        })
    }

    /// The recording the frames come from, if any: its streams and what was paired.
    pub fn recording_info(&self) -> Option<RecordingInfo> {
        self.reader.as_ref().map(|r| r.borrow().info())
    }

    /// The underlying source.
    pub fn source(&self) -> &S {
        &self.source
    }
}
