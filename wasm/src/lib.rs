//! Thin wasm-bindgen bindings over the UPETrack core for the web page:
//! a tracker built from an options object, a per-frame call returning flat
//! typed arrays, image and .zip decoding, and sequence metadata parsing.
#![warn(missing_docs)]

use ropes::{flat_truth, RopeFrame, RopeInfo, RopeOptions};
use serde::{Deserialize, Serialize};
use upetrack::metrics::{frame_error, frame_error_px};
use upetrack::perception::initialisation::InitReport;
use upetrack::perception::segmentation::Mask;
use upetrack::tracker::{FrameOutput, FrameStatus, Observation};
use upetrack::{CameraIntrinsics, Frame, HsvRange, MultiTracker, Params, Rect, Tracker, Vec3};
use upetrack_io::decode::{decode_color, decode_depth};
use upetrack_io::result::FrameRecord;
use upetrack_io::run::{frame_record, run_frame};
use upetrack_io::sequence::{DloConfig, OcclusionConfig, RopeConfig, Sequence};
use upetrack_io::source::{MemorySource, Source};
use wasm_bindgen::prelude::*;

mod browser;
mod contract;
mod explain;
mod recording;
mod ropes;
mod scene;

fn js_err(e: impl std::fmt::Display) -> JsError {
    JsError::new(&e.to_string())
}

/// The largest pixel coordinate a rectangle may give (2^53: every whole
/// number up to it is exact in a JS number).
const MAX_RECT_COORDINATE: f64 = 9_007_199_254_740_992.0;

/// Flat `[x, y, w, h, ...]` as rectangles; each value must be a whole number.
fn rects_of(flat: &[f64]) -> Result<Vec<Rect>, JsError> {
    if flat.len() % 4 != 0 {
        return Err(JsError::new(&format!(
            "occlusion rectangles need 4 values each, got {}",
            flat.len()
        )));
    }
    let whole = |v: f64| {
        if v.fract() == 0.0 && v.abs() <= MAX_RECT_COORDINATE {
            Ok(v as i64)
        } else {
            Err(JsError::new(&format!(
                "occlusion rectangle value {v} is not a whole number of pixels"
            )))
        }
    };
    flat.chunks_exact(4)
        .map(|r| {
            Ok(Rect {
                x: whole(r[0])?,
                y: whole(r[1])?,
                w: whole(r[2])?,
                h: whole(r[3])?,
            })
        })
        .collect()
}

/// Points projected with `camera`, flat `[u, v, ...]`, NaN where a point
/// cannot be projected (behind the camera, not finite).
fn project_all(camera: &CameraIntrinsics, points: &[Vec3]) -> Vec<f32> {
    points
        .iter()
        .flat_map(|p| match camera.project(p) {
            Some(q) => [q.x as f32, q.y as f32],
            None => [f32::NAN, f32::NAN],
        })
        .collect()
}

/// RGB8 as opaque RGBA8, for an `ImageData`.
fn rgba_of(rgb: &[u8]) -> Vec<u8> {
    rgb.chunks_exact(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect()
}

/// Flat `[x, y, z, ...]` as points.
fn points_of(flat: &[f64]) -> Vec<Vec3> {
    flat.chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect()
}

/// Milliseconds from the page's (or worker's) `performance.now()`, or 0.
fn now_ms() -> f64 {
    let global = js_sys::global();
    js_sys::Reflect::get(&global, &JsValue::from_str("performance"))
        .ok()
        .and_then(|perf| {
            let now = js_sys::Reflect::get(&perf, &JsValue::from_str("now")).ok()?;
            let f: js_sys::Function = now.dyn_into().ok()?;
            f.call0(&perf).ok()?.as_f64()
        })
        .unwrap_or(0.0)
}

/// Options of a tracker: `{ camera: {width, height, fx, fy, cx, cy},
/// fps?, params?, hsv?, rope?, ropes? }`.
#[derive(Deserialize)]
struct TrackerOptions {
    camera: CameraIntrinsics,
    /// Frames per second (`dlo.json`'s `fps`; 30 when absent).
    #[serde(default)]
    fps: Option<f64>,
    #[serde(default)]
    params: Option<Params>,
    #[serde(default)]
    hsv: Option<HsvRange>,
    /// `dlo.json`'s `rope`.
    #[serde(default)]
    rope: Option<RopeConfig>,
    /// Several ropes (`dlo.json`'s `ropes`): each with its colour range and
    /// prior (`hsv` and `rope` for those it does not give).
    #[serde(default)]
    ropes: Option<Vec<RopeOptions>>,
}

/// A value as plain JS objects (maps too: `Params` flattens UPETrack's
/// fields into the top level, which serde writes as a map).
fn to_js<T: serde::Serialize>(value: &T) -> Result<JsValue, JsError> {
    value
        .serialize(&serde_wasm_bindgen::Serializer::new().serialize_maps_as_objects(true))
        .map_err(js_err)
}

/// Every parameter as the page's panel shows it: `[{path, group, symbol,
/// meaning, kind, min?, max?, step?, choices?, unit, scale}]`
/// (`upetrack_io::params_schema`).
#[wasm_bindgen(js_name = parameterSchema)]
pub fn parameter_schema() -> Result<JsValue, JsError> {
    to_js(&upetrack_io::params_schema::PARAMETERS)
}

/// The default parameters as a plain object (documented in `core/src/params.rs`).
#[wasm_bindgen(js_name = defaultParams)]
pub fn default_params() -> Result<JsValue, JsError> {
    to_js(&Params::default())
}

/// The tracker of one sequence.
#[wasm_bindgen]
pub struct WasmTracker {
    /// Every rope's tracker (one, unless `ropes` was given).
    ropes: MultiTracker,
    /// Each rope's name.
    names: Vec<String>,
    /// The first rope's last observation (one rope).
    last_obs: Option<Observation>,
    /// The ropes' colour masks of the last frame (several).
    last_masks: Option<Vec<Mask>>,
    /// Every rope's last output.
    last: Vec<FrameOutput>,
}

/// The result of one frame; arrays are copied out as typed arrays.
#[wasm_bindgen]
pub struct FrameResult {
    nodes: Vec<f64>,
    nodes_px: Vec<f32>,
    visible: Vec<u8>,
    status: String,
    reason: Option<String>,
    /// Segmentation time, ms.
    pub segment_ms: f64,
    /// Point cloud time, ms.
    pub cloud_ms: f64,
    /// Tracking step time, ms.
    pub track_ms: f64,
    /// Segmentation, point cloud and tracking step, ms.
    pub total_ms: f64,
    /// Points in the cloud.
    pub cloud_points: u32,
    init: Option<InitReport>,
    record: FrameRecord,
    /// Every rope's result, with several ropes (empty for one).
    ropes: Vec<RopeFrame>,
}

#[wasm_bindgen]
impl FrameResult {
    /// Nodes, metres, flat `[x0, y0, z0, x1, ...]`.
    #[wasm_bindgen(getter)]
    pub fn nodes(&self) -> js_sys::Float64Array {
        js_sys::Float64Array::from(&self.nodes[..])
    }
    /// Nodes projected to pixels, flat `[u0, v0, u1, ...]` (NaN where not projectable).
    #[wasm_bindgen(getter, js_name = nodesPx)]
    pub fn nodes_px(&self) -> js_sys::Float32Array {
        js_sys::Float32Array::from(&self.nodes_px[..])
    }
    /// Visibility per node (1 visible, 0 hidden).
    #[wasm_bindgen(getter)]
    pub fn visible(&self) -> js_sys::Uint8Array {
        js_sys::Uint8Array::from(&self.visible[..])
    }
    /// `initialised`, `tracked` or `lost`.
    #[wasm_bindgen(getter)]
    pub fn status(&self) -> String {
        self.status.clone()
    }
    /// Why the frame was lost, if it was.
    #[wasm_bindgen(getter)]
    pub fn reason(&self) -> Option<String> {
        self.reason.clone()
    }
    /// On a frame where the rope was found: `{candidates, chosen, rule,
    /// set_aside, set_aside_count, hint_missed, prior_length_ratio}` (the
    /// result JSON's `init`), else `null`.
    #[wasm_bindgen(getter)]
    pub fn init(&self) -> Result<JsValue, JsError> {
        match &self.init {
            Some(r) => r
                .serialize(&serde_wasm_bindgen::Serializer::json_compatible())
                .map_err(js_err),
            None => Ok(JsValue::NULL),
        }
    }
    /// The frame's entry of the result JSON (`frame` is renumbered when the
    /// file is made by `resultFile`).
    #[wasm_bindgen(getter)]
    pub fn record(&self) -> Result<JsValue, JsError> {
        self.record
            .serialize(&serde_wasm_bindgen::Serializer::json_compatible())
            .map_err(js_err)
    }
    /// The rope-finding report in words, on a frame where the rope was found.
    #[wasm_bindgen(getter, js_name = initText)]
    pub fn init_text(&self) -> Option<String> {
        self.init.as_ref().map(|r| r.to_string())
    }
    /// With several ropes, each one's `{name, nodes, nodes_px, visible,
    /// status, reason, record}` (the first's also as this result's own
    /// fields); an empty array for one rope.
    #[wasm_bindgen(getter)]
    pub fn ropes(&self) -> Result<JsValue, JsError> {
        self.ropes
            .serialize(&serde_wasm_bindgen::Serializer::json_compatible())
            .map_err(js_err)
    }
}

/// `initialised`, `tracked`, `recovered` or `lost`, and why when lost or
/// recovered (the recovery tests that fired).
fn status_of(out: &FrameOutput) -> (&'static str, Option<String>) {
    match &out.status {
        FrameStatus::Initialised => ("initialised", None),
        FrameStatus::Tracked => ("tracked", None),
        FrameStatus::Recovered(c) => ("recovered", Some(upetrack_io::result::recovery_causes(c))),
        FrameStatus::Lost(r) => ("lost", Some(r.to_string())),
    }
}

#[wasm_bindgen]
impl WasmTracker {
    /// A tracker from `{ camera, fps?, params?, hsv?, rope?, ropes? }`;
    /// missing parameters take their defaults, a missing `fps` 30 frames
    /// per second. `ropes` (`[{name?, hsv?, rope?}]`,
    /// 1 to 8) tracks several ropes at once.
    #[wasm_bindgen(constructor)]
    pub fn new(options: JsValue) -> Result<WasmTracker, JsError> {
        let o: TrackerOptions = serde_wasm_bindgen::from_value(options).map_err(js_err)?;
        let params = o.params.unwrap_or_default();
        let specs = o.ropes.unwrap_or_else(|| {
            vec![RopeOptions {
                name: None,
                hsv: None,
                rope: None,
            }]
        });
        let mut trackers = Vec::with_capacity(specs.len());
        let mut names = Vec::with_capacity(specs.len());
        for (k, spec) in specs.iter().enumerate() {
            let hsv = spec.hsv.or(o.hsv).unwrap_or_default();
            let mut tracker = Tracker::new(params, o.camera, hsv).map_err(js_err)?;
            if let Some(fps) = o.fps {
                tracker.set_frame_rate(fps).map_err(js_err)?;
            }
            if let Some(rope) = spec.rope.or(o.rope) {
                tracker.set_rope_prior(rope.prior()).map_err(js_err)?;
            }
            trackers.push(tracker);
            names.push(spec.name.clone().unwrap_or_else(|| format!("rope-{k}")));
        }
        Ok(Self {
            ropes: MultiTracker::new(trackers).map_err(js_err)?,
            names,
            last_obs: None,
            last_masks: None,
            last: Vec::new(),
        })
    }

    /// Number of ropes tracked.
    #[wasm_bindgen(getter, js_name = ropeCount)]
    pub fn rope_count(&self) -> usize {
        self.ropes.ropes().len()
    }

    /// Replaces the parameters (a full or partial object); effective next frame.
    #[wasm_bindgen(js_name = setParams)]
    pub fn set_params(&mut self, params: JsValue) -> Result<(), JsError> {
        let p: Params = serde_wasm_bindgen::from_value(params).map_err(js_err)?;
        for t in self.ropes.ropes_mut() {
            t.set_params(p).map_err(js_err)?;
        }
        Ok(())
    }

    /// The parameters in force.
    pub fn params(&self) -> Result<JsValue, JsError> {
        to_js(self.ropes.first().params())
    }

    /// Replaces the (first rope's) HSV range: `{ lower: [h, s, v], upper:
    /// [h, s, v] }`, OpenCV convention. A value outside 0..=255 is
    /// refused, never wrapped.
    #[wasm_bindgen(js_name = setHsv)]
    pub fn set_hsv(&mut self, range: JsValue) -> Result<(), JsError> {
        let range: HsvRange = serde_wasm_bindgen::from_value(range).map_err(js_err)?;
        self.ropes.first_mut().set_hsv(range).map_err(js_err)
    }

    /// What the user knows of the rope, as `dlo.json`'s `rope`
    /// (`{length_m?, diameter_m?}`, or `null` for nothing); checked as the
    /// command checks it. Takes effect at the next initialisation.
    #[wasm_bindgen(js_name = setRopePrior)]
    pub fn set_rope_prior(&mut self, rope: JsValue) -> Result<(), JsError> {
        let rope: Option<RopeConfig> = serde_wasm_bindgen::from_value(rope).map_err(js_err)?;
        self.ropes
            .first_mut()
            .set_rope_prior(rope.unwrap_or_default().prior())
            .map_err(js_err)
    }

    /// A pixel on the rope the user clicked: initialisations take the
    /// rope-shaped candidate through it (NaN forgets it). `reset` or
    /// `restore(null)` to initialise again at the next frame.
    #[wasm_bindgen(js_name = setRopeHint)]
    pub fn set_rope_hint(&mut self, u: f64, v: f64) {
        self.ropes.first_mut().set_rope_hint(Some([u, v]));
    }

    /// [`WasmTracker::set_rope_hint`] for rope `k` of several (a `k` past
    /// the last rope is refused).
    #[wasm_bindgen(js_name = setRopeHintOf)]
    pub fn set_rope_hint_of(&mut self, k: usize, u: f64, v: f64) -> Result<(), JsError> {
        let count = self.rope_count();
        let rope = self
            .ropes
            .rope_mut(k)
            .ok_or_else(|| JsError::new(&format!("setRopeHintOf: rope {k} of {count}")))?;
        rope.set_rope_hint(Some([u, v]));
        Ok(())
    }

    /// The camera moved since the last frame (a robot arm's kinematics, an
    /// IMU): `motion` the 12 numbers of a rigid transform `[R | t]`, row
    /// by row, from the last frame's camera coordinates to this frame's
    /// (metres). The tracked rope is moved with it before the next frame.
    #[wasm_bindgen(js_name = moveCamera)]
    pub fn move_camera(&mut self, motion: &[f64]) -> Result<(), JsError> {
        let Ok(m) = <&[f64; 12]>::try_from(motion) else {
            return Err(JsError::new(&format!(
                "moveCamera: {} numbers, expected the 12 of [R | t] row by row",
                motion.len()
            )));
        };
        let rigid = upetrack::motion::RigidMotion::from_rows(m);
        for t in self.ropes.ropes_mut() {
            t.move_camera(&rigid).map_err(js_err)?;
        }
        Ok(())
    }

    /// The state after the last frame, to return to it with `restore`:
    /// the rope's snapshot, or with several ropes an array of them.
    pub fn snapshot(&self) -> Result<JsValue, JsError> {
        match self.ropes.ropes() {
            [only] => to_js(&only.snapshot()),
            ropes => to_js(&ropes.iter().map(Tracker::snapshot).collect::<Vec<_>>()),
        }
    }

    /// Goes back to a state from `snapshot` (`null`: the initial state).
    pub fn restore(&mut self, snapshot: JsValue) -> Result<(), JsError> {
        if snapshot.is_null() || snapshot.is_undefined() {
            self.ropes.reset();
            return Ok(());
        }
        type Snapshot = upetrack::tracker::TrackerSnapshot;
        if self.rope_count() == 1 {
            let s: Snapshot = serde_wasm_bindgen::from_value(snapshot).map_err(js_err)?;
            return self.ropes.first_mut().restore(s).map_err(js_err);
        }
        let all: Vec<Snapshot> = serde_wasm_bindgen::from_value(snapshot).map_err(js_err)?;
        if all.len() != self.rope_count() {
            return Err(JsError::new(&format!(
                "restore: a snapshot of {} ropes for a tracker of {}",
                all.len(),
                self.rope_count()
            )));
        }
        for (t, s) in self.ropes.ropes_mut().iter_mut().zip(all) {
            t.restore(s).map_err(js_err)?;
        }
        Ok(())
    }

    /// Forgets the state; the next frame initialises.
    pub fn reset(&mut self) {
        self.ropes.reset();
    }

    /// Tracks one frame. `rgb` is RGB8, `depth` 16-bit units, `occlusions`
    /// flat `[x, y, w, h, ...]` rectangles blacked out before segmentation
    /// (whole numbers of pixels; anything else is refused, never wrapped).
    pub fn track(
        &mut self,
        width: u32,
        height: u32,
        rgb: &[u8],
        depth: &[u16],
        depth_scale: f64,
        occlusions: &[f64],
    ) -> Result<FrameResult, JsError> {
        let frame = Frame::new(width, height, rgb, depth, depth_scale).map_err(js_err)?;
        let rects = rects_of(occlusions)?;
        if self.rope_count() > 1 {
            return self.track_several(&frame, &rects);
        }
        let timed =
            run_frame(self.ropes.first_mut(), &frame, &rects, &mut now_ms).map_err(js_err)?;
        let record = frame_record(0, &timed);
        let (obs, out) = (timed.observation, timed.output);
        let nodes_px = project_all(self.ropes.first().camera(), &out.nodes);
        let (status, reason) = status_of(&out);
        let result = FrameResult {
            nodes: out.nodes.iter().flat_map(|p| [p.x, p.y, p.z]).collect(),
            nodes_px,
            visible: out.visible.iter().map(|&v| v as u8).collect(),
            status: status.into(),
            reason,
            segment_ms: timed.segment_ms,
            cloud_ms: timed.cloud_ms,
            track_ms: timed.track_ms,
            total_ms: timed.total_ms,
            cloud_points: obs.cloud.len() as u32,
            init: out.init.clone(),
            record,
            ropes: Vec::new(),
        };
        self.last_obs = Some(obs);
        self.last = vec![out];
        Ok(result)
    }

    /// Tracks a frame decoded by `decodeFrame` without copying its images
    /// out of and back into WebAssembly memory.
    #[wasm_bindgen(js_name = trackDecoded)]
    pub fn track_decoded(
        &mut self,
        frame: &DecodedFrame,
        depth_scale: f64,
        occlusions: &[f64],
    ) -> Result<FrameResult, JsError> {
        self.track(
            frame.width,
            frame.height,
            &frame.rgb,
            &frame.depth,
            depth_scale,
            occlusions,
        )
    }

    /// The last frame's mask, one byte per pixel (1 rope; with several,
    /// every rope's colour).
    #[wasm_bindgen(js_name = lastMask)]
    pub fn last_mask(&self) -> Vec<u8> {
        if let Some(masks) = &self.last_masks {
            // Every rope's colour, made only when the page asks for it.
            let mut union = masks.first().cloned().unwrap_or_else(|| Mask::new(0, 0));
            masks.iter().skip(1).for_each(|m| union.include(m));
            return union.data.iter().map(|&b| b as u8).collect();
        }
        self.last_obs
            .as_ref()
            .map_or_else(Vec::new, |o| o.mask.data.iter().map(|&b| b as u8).collect())
    }

    /// Frame error of the last frame (the first rope's) against ground
    /// truth (flat metres): `[mm, px]`, or an empty array when there is
    /// nothing to compare.
    #[wasm_bindgen(js_name = lastError)]
    pub fn last_error(&self, truth: &[f64]) -> Vec<f64> {
        self.last_error_of(0, truth)
    }

    /// [`WasmTracker::last_error`] of rope `k`.
    #[wasm_bindgen(js_name = lastErrorOf)]
    pub fn last_error_of(&self, k: usize, truth: &[f64]) -> Vec<f64> {
        let Some(out) = self.last.get(k) else {
            return Vec::new();
        };
        let gt = points_of(truth);
        match (
            frame_error(&out.nodes, &gt),
            frame_error_px(&out.nodes, &gt, self.ropes.first().camera()),
        ) {
            (Some(mm), Some(px)) => vec![mm * 1000.0, px],
            _ => Vec::new(),
        }
    }
}

/// A decoded colour/depth pair.
#[wasm_bindgen]
pub struct DecodedFrame {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    rgb: Vec<u8>,
    /// The colour as RGBA8 when the browser decoded it so, kept for display.
    rgba: Option<Vec<u8>>,
    depth: Vec<u16>,
}

impl DecodedFrame {
    /// RGB8 colour of `width` x `height` with its depth image, which must
    /// have the same size.
    fn paired(
        width: u32,
        height: u32,
        rgb: Vec<u8>,
        depth: upetrack_io::decode::DepthImage,
        color_name: &str,
        depth_name: &str,
    ) -> Result<Self, JsError> {
        if (width, height) != (depth.width, depth.height) {
            return Err(JsError::new(&format!(
                "{depth_name}: depth is {}x{} but {color_name} is {width}x{height}",
                depth.width, depth.height
            )));
        }
        Ok(Self {
            width,
            height,
            rgb,
            rgba: None,
            depth: depth.data,
        })
    }

    /// As `paired`, from RGBA8 colour; alpha is dropped (made opaque), as
    /// the wasm decoder drops it.
    fn from_rgba(
        width: u32,
        height: u32,
        mut rgba: Vec<u8>,
        depth: upetrack_io::decode::DepthImage,
        color_name: &str,
        depth_name: &str,
    ) -> Result<Self, JsError> {
        let rgb = rgba
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        rgba.chunks_exact_mut(4).for_each(|p| p[3] = u8::MAX);
        let mut frame = Self::paired(width, height, rgb, depth, color_name, depth_name)?;
        frame.rgba = Some(rgba);
        Ok(frame)
    }
}

#[wasm_bindgen]
impl DecodedFrame {
    /// RGB8 bytes.
    #[wasm_bindgen(getter)]
    pub fn rgb(&self) -> js_sys::Uint8Array {
        js_sys::Uint8Array::from(&self.rgb[..])
    }
    /// RGBA8 bytes, for an ImageData.
    #[wasm_bindgen(getter)]
    pub fn rgba(&self) -> js_sys::Uint8ClampedArray {
        match &self.rgba {
            Some(rgba) => js_sys::Uint8ClampedArray::from(&rgba[..]),
            None => js_sys::Uint8ClampedArray::from(&rgba_of(&self.rgb)[..]),
        }
    }
    /// Depth units.
    #[wasm_bindgen(getter)]
    pub fn depth(&self) -> js_sys::Uint16Array {
        js_sys::Uint16Array::from(&self.depth[..])
    }
}

/// Decodes a colour file (PNG or JPEG) and a depth file (16-bit PNG); the
/// names are used in error messages. Both must have the same size.
#[wasm_bindgen(js_name = decodeFrame)]
pub fn decode_frame(
    color: &[u8],
    color_name: &str,
    depth: &[u8],
    depth_name: &str,
) -> Result<DecodedFrame, JsError> {
    let c = decode_color(color, color_name).map_err(js_err)?;
    let d = decode_depth(depth, depth_name).map_err(js_err)?;
    DecodedFrame::paired(c.width, c.height, c.data, d, color_name, depth_name)
}

/// A .zip unpacked in memory; frames are read from it on demand.
#[wasm_bindgen]
pub struct Archive {
    source: MemorySource,
}

#[wasm_bindgen]
impl Archive {
    /// Unpacks `bytes`; `name` appears in error messages.
    #[wasm_bindgen(constructor)]
    pub fn new(bytes: &[u8], name: &str) -> Result<Archive, JsError> {
        Ok(Self {
            source: upetrack_io::archive::unpack_zip(bytes, name).map_err(js_err)?,
        })
    }

    /// Every file path inside.
    pub fn names(&self) -> Vec<String> {
        self.source.paths().map(str::to_string).collect()
    }

    /// The bytes of one file.
    pub fn read(&self, path: &str) -> Result<Vec<u8>, JsError> {
        self.source.read(path).map_err(js_err)
    }
}

/// What the page needs to know about a sequence.
#[derive(Serialize)]
struct SequenceInfo {
    camera: CameraIntrinsics,
    depth_scale: f64,
    fps: f64,
    hsv: HsvRange,
    occlusions: Vec<OcclusionConfig>,
    /// `dlo.json`'s `rope`, or null.
    rope: Option<RopeConfig>,
    color_files: Vec<String>,
    depth_files: Vec<String>,
    /// Flat metres per frame, or null.
    groundtruth: Vec<Option<Vec<f64>>>,
    /// With several ropes (`dlo.json`'s `ropes`), each one's `{name, hsv,
    /// rope, groundtruth}`; empty for one rope.
    ropes: Vec<RopeInfo>,
}

/// Reads a sequence's metadata. `json` maps file names (`camera_intrinsic.json`,
/// `intrinsic.json`, `dlo.json`, `groundtruth.json`...) to their bytes;
/// `images` lists every image path (`color/000000.jpg`, `depth/...`), whose
/// bytes are not needed yet. Returns `{camera, depth_scale, fps, hsv,
/// occlusions, rope, color_files, depth_files, groundtruth}`.
#[wasm_bindgen(js_name = readSequenceInfo)]
pub fn read_sequence_info(
    name: &str,
    json: JsValue,
    images: Vec<String>,
) -> Result<JsValue, JsError> {
    let files: std::collections::BTreeMap<String, serde_bytes_compat::Bytes> =
        serde_wasm_bindgen::from_value(json).map_err(js_err)?;
    let mut source = MemorySource::new(name);
    for (k, v) in files {
        source.insert(&k, v.0);
    }
    for img in &images {
        source.insert(img, Vec::new());
    }
    let seq = Sequence::open(source).map_err(js_err)?;
    sequence_info(&seq)
}
/// The page's view of an opened sequence (a folder's or a recording's).
fn sequence_info<S: Source>(seq: &Sequence<S>) -> Result<JsValue, JsError> {
    let info = SequenceInfo {
        camera: seq.camera,
        depth_scale: seq.depth_scale,
        fps: seq.fps,
        hsv: seq.hsv,
        occlusions: seq.config.occlusions.clone(),
        rope: seq.config.rope,
        color_files: seq.color_files.clone(),
        depth_files: seq.depth_files.clone(),
        groundtruth: flat_truth(&seq.groundtruth),
        ropes: if seq.ropes.len() > 1 {
            seq.ropes.iter().map(RopeInfo::of).collect()
        } else {
            Vec::new()
        },
    };
    info.serialize(&serde_wasm_bindgen::Serializer::json_compatible())
        .map_err(js_err)
}

/// Points (flat metres) projected to pixels with `camera`
/// (`{width, height, fx, fy, cx, cy}`): flat `[u, v, ...]`, NaN where a
/// point is behind the camera or not finite.
#[wasm_bindgen(js_name = projectPoints)]
pub fn project_points(camera: JsValue, points: &[f64]) -> Result<Vec<f32>, JsError> {
    let camera: CameraIntrinsics = serde_wasm_bindgen::from_value(camera).map_err(js_err)?;
    Ok(project_all(&camera, &points_of(points)))
}

/// OpenCV's 8-bit HSV of one RGB pixel (the core's conversion).
#[wasm_bindgen(js_name = rgbToHsv)]
pub fn rgb_to_hsv(r: u8, g: u8, b: u8) -> Vec<u8> {
    upetrack::perception::segmentation::rgb_to_hsv([r, g, b]).to_vec()
}

/// The HSV range picked around a clicked pixel's colour: `{lower, upper}`.
#[wasm_bindgen(js_name = hsvRangeAround)]
pub fn hsv_range_around(r: u8, g: u8, b: u8) -> Result<JsValue, JsError> {
    to_js(&HsvRange::around([r, g, b]))
}

/// Mean, median and quartiles of a series (as `upetrack eval` computes
/// them): `{mean, median, q1, q3}`, NaN for an empty series.
#[wasm_bindgen(js_name = errorStats)]
pub fn error_stats(values: &[f64]) -> Result<JsValue, JsError> {
    to_js(&upetrack_io::eval::ErrorStats::of(values))
}

/// The folders above a sequence's layout that every path shares (`myseq`
/// of `myseq/color/0.jpg`), or `undefined`: strip `root + "/"` from each.
#[wasm_bindgen(js_name = commonRoot)]
pub fn common_root(paths: Vec<String>) -> Option<String> {
    upetrack_io::source::common_root(paths.iter().map(String::as_str))
}

/// Checks `dlo.json` text as the command does (same messages) and returns
/// `{hsv: {lower, upper}, occlusions, rope}`.
#[wasm_bindgen(js_name = checkDlo)]
pub fn check_dlo(text: &str) -> Result<JsValue, JsError> {
    let config = DloConfig::parse(text.as_bytes(), "dlo.json").map_err(js_err)?;
    let hsv = config.check("dlo.json").map_err(js_err)?;
    #[derive(Serialize)]
    struct Checked {
        hsv: HsvRange,
        occlusions: Vec<OcclusionConfig>,
        rope: Option<RopeConfig>,
    }
    to_js(&Checked {
        hsv,
        occlusions: config.occlusions,
        rope: config.rope,
    })
}

/// Parses and checks parameters given as JSON text (any subset of the
/// fields), as the command's `--params` does; returns every field.
#[wasm_bindgen(js_name = parseParams)]
pub fn parse_params(text: &str) -> Result<JsValue, JsError> {
    to_js(&upetrack_io::params_file::parse_params(text, "parameters").map_err(js_err)?)
}

/// Depth as RGBA8 for display, with the command's `overlay --depth` ramp.
#[wasm_bindgen(js_name = depthRgba)]
pub fn depth_rgba(depth: &[u16]) -> js_sys::Uint8ClampedArray {
    js_sys::Uint8ClampedArray::from(&rgba_of(&upetrack_io::display::depth_to_rgb(depth))[..])
}

mod serde_bytes_compat {
    //! A `Uint8Array` (or array of numbers) read into bytes.
    use serde::{Deserialize, Deserializer};

    /// Owned bytes.
    pub struct Bytes(pub Vec<u8>);

    impl<'de> Deserialize<'de> for Bytes {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            struct V;
            impl<'de> serde::de::Visitor<'de> for V {
                type Value = Bytes;
                fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                    f.write_str("bytes")
                }
                fn visit_bytes<E>(self, v: &[u8]) -> Result<Bytes, E> {
                    Ok(Bytes(v.to_vec()))
                }
                fn visit_byte_buf<E>(self, v: Vec<u8>) -> Result<Bytes, E> {
                    Ok(Bytes(v))
                }
                fn visit_seq<A: serde::de::SeqAccess<'de>>(
                    self,
                    mut s: A,
                ) -> Result<Bytes, A::Error> {
                    let mut out = Vec::new();
                    while let Some(b) = s.next_element::<u8>()? {
                        out.push(b);
                    }
                    Ok(Bytes(out))
                }
            }
            d.deserialize_bytes(V)
        }
    }
}
