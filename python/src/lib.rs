//! Python bindings of the upetrack core (`import upetrack`): a tracker that
//! steps on numpy arrays as pyrealsense2 gives them, and the sequences and
//! recordings the command reads. Nothing is implemented twice: every rule
//! is the core's or `upetrack-io`'s.

use std::path::PathBuf;
use std::time::Instant;

use numpy::{
    PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray2, PyReadonlyArray3,
    PyUntypedArrayMethods,
};
use pyo3::create_exception;
use pyo3::exceptions::{PyIndexError, PyValueError};
use pyo3::prelude::*;
use upetrack::motion::RigidMotion;
use upetrack::tracker::FrameStatus;
use upetrack::{Algorithm, CameraIntrinsics, Frame, FrameOutput, HsvRange, Params, Rect};
use upetrack_io::result::recovery_causes;
use upetrack_io::run::{output_record, run_frame, run_frame_several};
use upetrack_io::{Sequence as IoSequence, SequenceError as IoSequenceError, Source};

create_exception!(
    upetrack,
    TrackerError,
    PyValueError,
    "The tracker refused its settings or a frame (the core's message)."
);
create_exception!(
    upetrack,
    SequenceError,
    PyValueError,
    "A sequence or recording that cannot be read (the reader's message, naming the file)."
);

/// A timed frame's stage times: segmentation, cloud, step, total (ms).
macro_rules! times {
    ($t:expr) => {
        [$t.segment_ms, $t.cloud_ms, $t.track_ms, $t.total_ms]
    };
}

fn tracker_error(e: impl std::fmt::Display) -> PyErr {
    TrackerError::new_err(e.to_string())
}

fn sequence_error(e: IoSequenceError) -> PyErr {
    SequenceError::new_err(e.to_string())
}

/// A pinhole camera: image size and focal lengths and principal point in pixels.
#[pyclass(module = "upetrack", frozen, get_all)]
#[derive(Clone, Copy)]
struct Intrinsics {
    /// Image width, pixels.
    width: u32,
    /// Image height, pixels.
    height: u32,
    /// Focal length along x, pixels.
    fx: f64,
    /// Focal length along y, pixels.
    fy: f64,
    /// Principal point x, pixels.
    cx: f64,
    /// Principal point y, pixels.
    cy: f64,
}

impl From<CameraIntrinsics> for Intrinsics {
    fn from(c: CameraIntrinsics) -> Self {
        Self {
            width: c.width,
            height: c.height,
            fx: c.fx,
            fy: c.fy,
            cx: c.cx,
            cy: c.cy,
        }
    }
}

/// A clock in milliseconds since now (the core has none).
fn clock_ms() -> impl FnMut() -> f64 {
    let start = Instant::now();
    move || start.elapsed().as_secs_f64() * 1000.0
}

impl Intrinsics {
    fn camera(&self) -> CameraIntrinsics {
        CameraIntrinsics {
            width: self.width,
            height: self.height,
            fx: self.fx,
            fy: self.fy,
            cx: self.cx,
            cy: self.cy,
        }
    }
}

#[pymethods]
impl Intrinsics {
    #[new]
    #[pyo3(signature = (width, height, fx, fy, cx, cy))]
    fn new(width: u32, height: u32, fx: f64, fy: f64, cx: f64, cy: f64) -> PyResult<Self> {
        let i = Self {
            width,
            height,
            fx,
            fy,
            cx,
            cy,
        };
        i.camera().validate().map_err(tracker_error)?;
        Ok(i)
    }

    /// The intrinsics of a pyrealsense2 stream profile
    /// (`profile.as_video_stream_profile().get_intrinsics()`: `width`,
    /// `height`, `fx`, `fy`, `ppx`, `ppy`).
    #[staticmethod]
    fn from_realsense(intrinsics: &Bound<'_, PyAny>) -> PyResult<Self> {
        Self::new(
            intrinsics.getattr("width")?.extract()?,
            intrinsics.getattr("height")?.extract()?,
            intrinsics.getattr("fx")?.extract()?,
            intrinsics.getattr("fy")?.extract()?,
            intrinsics.getattr("ppx")?.extract()?,
            intrinsics.getattr("ppy")?.extract()?,
        )
    }

    fn __repr__(&self) -> String {
        format!(
            "Intrinsics(width={}, height={}, fx={}, fy={}, cx={}, cy={})",
            self.width, self.height, self.fx, self.fy, self.cx, self.cy
        )
    }
}

/// Parameters from `None` (the defaults), a preset name (`"default"`,
/// `"paper"`) or a dict of any subset of the fields (the parameter file's
/// rules and messages).
fn params_of(params: Option<&Bound<'_, PyAny>>) -> PyResult<Params> {
    let Some(params) = params else {
        return Ok(Params::default());
    };
    if let Ok(name) = params.extract::<String>() {
        return Params::preset(&name).ok_or_else(|| {
            PyValueError::new_err(format!("params: no preset named `{name}` (default, paper)"))
        });
    }
    let json = params.py().import("json")?;
    let text: String = json.call_method1("dumps", (params,))?.extract()?;
    upetrack_io::params_file::parse_params(&text, "params")
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

fn algorithm_of(name: Option<&str>, params: Params) -> PyResult<Params> {
    let Some(name) = name else {
        return Ok(params);
    };
    let algorithm = Algorithm::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Algorithm::ALL.iter().map(|a| a.name()).collect();
        PyValueError::new_err(format!(
            "algorithm: `{name}` is not one of {}",
            names.join(", ")
        ))
    })?;
    Ok(Params {
        algorithm,
        ..params
    })
}

/// An HSV box as Python gives it: `((h, s, v), (h, s, v))`, lower then upper.
type HsvTuple = ((u8, u8, u8), (u8, u8, u8));

/// A decoded frame as numpy arrays: colour H x W x 3, depth H x W.
type FrameArrays<'py> = (Bound<'py, PyArray3<u8>>, Bound<'py, PyArray2<u16>>);

/// Rectangles `(x, y, w, h)` as the core's.
fn rects(r: Vec<(i64, i64, i64, i64)>) -> Vec<Rect> {
    r.into_iter()
        .map(|(x, y, w, h)| Rect { x, y, w, h })
        .collect()
}

/// What one step gives: the nodes (M x 3, metres, camera frame), which
/// are visible, whether the rope is lost and why, and the stages' times.
#[pyclass(module = "upetrack", frozen, get_all)]
struct StepResult {
    /// M x 3 float64, metres, in the colour camera's frame.
    nodes: Py<PyArray2<f64>>,
    /// M bool: the node is on rope points in this frame.
    visible: Py<PyArray1<bool>>,
    /// The rope could not be tracked on this frame (the nodes are the last known).
    lost: bool,
    /// Why it is lost, or why the state was replaced when recovered, else None.
    reason: Option<String>,
    /// The state was found again from the images on this frame.
    recovered: bool,
    /// What came of the recovery tests after this frame's step: "agreed",
    /// "waited", "nothing_found", "other_thickness", "beside_the_rope",
    /// "leaves_seen_rope_out", "recovered"; None when no step ran.
    verdict: Option<String>,
    /// The recovery tests that fired after the step: "stretched",
    /// "free_space", "unexplained" (empty when none did).
    fired: Vec<String>,
    /// Segmentation, ms.
    segment_ms: f64,
    /// Point cloud, ms.
    cloud_ms: f64,
    /// Tracking step, ms.
    track_ms: f64,
    /// Segmentation, cloud and step, ms.
    total_ms: f64,
}

#[pymethods]
impl StepResult {
    fn __repr__(&self, py: Python<'_>) -> String {
        let n = self.visible.bind(py).len();
        format!(
            "StepResult({n} nodes, lost={}, total_ms={:.3})",
            if self.lost { "True" } else { "False" },
            self.total_ms
        )
    }
}

/// Tracks one rope in aligned colour and depth frames of one camera.
///
/// `Tracker(intrinsics, params=None, algorithm=None, depth_scale=0.001,
/// hsv=((90, 90, 30), (130, 255, 255)), occlusions=(), chroma_noise=0,
/// fps=30.0)`: `params` a dict of any subset of the parameters or a preset
/// name; `algorithm` one of "upetrack", "cpd", "trackdlo", "cdcpd2";
/// `depth_scale` metres per depth unit; `fps` the camera's frames per
/// second (speeds in the parameters become moves per frame with it); `hsv` the rope's colour range in OpenCV's convention and
/// `chroma_noise` the colour noise its saturation test allows for (levels of
/// chroma, 0 is OpenCV's `inRange`; docs/sequence-format.md); `occlusions`
/// rectangles `(x, y, w, h)` blacked out on every frame.
#[pyclass(module = "upetrack")]
struct Tracker {
    inner: upetrack::Tracker,
    depth_scale: f64,
    occlusions: Vec<Rect>,
}

#[pymethods]
impl Tracker {
    #[new]
    #[pyo3(signature = (intrinsics, params=None, algorithm=None, depth_scale=0.001, hsv=None, occlusions=Vec::new(), chroma_noise=0, fps=30.0))]
    // `fps`'s default is the core's `DEFAULT_FPS`, written out so the
    // signature (and so the stub check) shows it.
    #[allow(clippy::too_many_arguments)]
    fn new(
        intrinsics: &Intrinsics,
        params: Option<&Bound<'_, PyAny>>,
        algorithm: Option<&str>,
        depth_scale: f64,
        hsv: Option<HsvTuple>,
        occlusions: Vec<(i64, i64, i64, i64)>,
        chroma_noise: u8,
        fps: f64,
    ) -> PyResult<Self> {
        let params = algorithm_of(algorithm, params_of(params)?)?;
        if !(depth_scale > 0.0 && depth_scale.is_finite()) {
            return Err(PyValueError::new_err(format!(
                "depth_scale: {depth_scale} is not a positive number of metres per unit"
            )));
        }
        let bounds = hsv.map_or_else(HsvRange::default, |((a, b, c), (d, e, f))| {
            HsvRange::new([a, b, c], [d, e, f])
        });
        let hsv = HsvRange {
            chroma_noise,
            ..bounds
        };
        let mut inner =
            upetrack::Tracker::new(params, intrinsics.camera(), hsv).map_err(tracker_error)?;
        inner.set_frame_rate(fps).map_err(tracker_error)?;
        Ok(Self {
            inner,
            depth_scale,
            occlusions: rects(occlusions),
        })
    }

    /// Tracks one frame: `color` uint8 H x W x 3 RGB, `depth` uint16 H x W in
    /// depth units, aligned to colour (pyrealsense2's `rs.align`);
    /// `occlusions`, rectangles `(x, y, w, h)` for this frame only, replace
    /// the tracker's. The GIL is released while the frame is tracked.
    #[pyo3(signature = (color, depth, occlusions=None))]
    fn step(
        &mut self,
        py: Python<'_>,
        color: PyReadonlyArray3<'_, u8>,
        depth: PyReadonlyArray2<'_, u16>,
        occlusions: Option<Vec<(i64, i64, i64, i64)>>,
    ) -> PyResult<StepResult> {
        let frame = frame_of(self.inner.camera(), &color, &depth, self.depth_scale)?;
        let these: Option<Vec<Rect>> = occlusions.map(rects);
        let (inner, occlusions) = (&mut self.inner, these.as_ref().unwrap_or(&self.occlusions));
        let timed = py
            .detach(|| run_frame(inner, &frame, occlusions, &mut clock_ms()))
            .map_err(tracker_error)?;
        step_result(py, &timed.output, times!(timed))
    }

    /// The camera moved since the last frame (an arm's kinematics, an
    /// IMU): `motion`, a 4 x 4 or 3 x 4 float64 rigid transform taking a
    /// point's coordinates in the last frame's camera to this frame's
    /// (metres). The tracked rope is moved with it before the next step.
    fn move_camera(&mut self, motion: PyReadonlyArray2<'_, f64>) -> PyResult<()> {
        self.inner
            .move_camera(&rigid_of(&motion)?)
            .map_err(tracker_error)
    }

    /// Forgets the rope: the next frame finds it again.
    fn reset(&mut self) {
        self.inner.reset();
    }
}

/// The core's view of `color` (uint8 H x W x 3 RGB) and `depth` (uint16
/// H x W) for `camera`, refused with the reason when they do not fit it.
fn frame_of<'a>(
    camera: &CameraIntrinsics,
    color: &'a PyReadonlyArray3<'_, u8>,
    depth: &'a PyReadonlyArray2<'_, u16>,
    depth_scale: f64,
) -> PyResult<Frame<'a>> {
    let (w, h) = (camera.width as usize, camera.height as usize);
    if color.shape() != [h, w, 3] {
        return Err(PyValueError::new_err(format!(
            "color: shape {:?}, expected ({h}, {w}, 3) uint8 RGB",
            color.shape()
        )));
    }
    if depth.shape() != [h, w] {
        return Err(PyValueError::new_err(format!(
            "depth: shape {:?}, expected ({h}, {w}) uint16",
            depth.shape()
        )));
    }
    // `as_slice` takes Fortran order too, which would be read transposed.
    let c_order = color.is_c_contiguous() && depth.is_c_contiguous();
    let (true, Ok(rgb), Ok(z)) = (c_order, color.as_slice(), depth.as_slice()) else {
        return Err(PyValueError::new_err(
            "color and depth must be C-contiguous (numpy.ascontiguousarray)",
        ));
    };
    Frame::new(camera.width, camera.height, rgb, z, depth_scale).map_err(tracker_error)
}

/// A rope's [`StepResult`] from its `output` and the frame's `times`
/// (segmentation, cloud, step, total, ms).
fn step_result(py: Python<'_>, output: &FrameOutput, times: [f64; 4]) -> PyResult<StepResult> {
    let record = output_record(0, output, times[2], times[3]);
    let nodes: Vec<Vec<f64>> = record.nodes.iter().map(|p| p.to_vec()).collect();
    Ok(StepResult {
        nodes: PyArray2::from_vec2(py, &nodes)?.unbind(),
        visible: PyArray1::from_slice(py, &record.visible).unbind(),
        lost: record.lost,
        reason: match &output.status {
            FrameStatus::Recovered(c) => Some(recovery_causes(c)),
            _ => record.reason,
        },
        recovered: record.recovered,
        verdict: record.checks.as_ref().map(|c| c.verdict.clone()),
        fired: record.checks.map(|c| c.tests.fired).unwrap_or_default(),
        segment_ms: times[0],
        cloud_ms: times[1],
        track_ms: times[2],
        total_ms: times[3],
    })
}

/// A 4 x 4 or 3 x 4 float64 rigid transform as the core's motion.
fn rigid_of(motion: &PyReadonlyArray2<'_, f64>) -> PyResult<RigidMotion> {
    let shape = motion.shape();
    if !(shape == [4, 4] || shape == [3, 4]) {
        return Err(PyValueError::new_err(format!(
            "motion: shape {shape:?}, expected (4, 4) or (3, 4) float64"
        )));
    }
    let m = motion.as_array();
    if shape[0] == 4 && [m[[3, 0]], m[[3, 1]], m[[3, 2]], m[[3, 3]]] != [0.0, 0.0, 0.0, 1.0] {
        return Err(PyValueError::new_err(
            "motion: a rigid transform's last row is (0, 0, 0, 1)",
        ));
    }
    let rows: [f64; 12] = core::array::from_fn(|k| m[[k / 4, k % 4]]);
    Ok(RigidMotion::from_rows(&rows))
}

/// Tracks every rope of a sequence of several together, as `upetrack
/// track` does (`seq.multi_tracker()`): each frame is segmented once per
/// colour, the pixels several ropes' colours accept are shared out to the
/// nearest tracked rope, and the camera's motion is followed once.
#[pyclass(module = "upetrack")]
struct MultiTracker {
    inner: upetrack::MultiTracker,
    names: Vec<String>,
    depth_scale: f64,
}

#[pymethods]
impl MultiTracker {
    /// The ropes' names, in the order of `step`'s results.
    #[getter]
    fn ropes(&self) -> Vec<String> {
        self.names.clone()
    }

    /// Tracks one frame (as `Tracker.step`): one `StepResult` per rope, in
    /// order; the times in each are the whole frame's (every rope's).
    #[pyo3(signature = (color, depth, occlusions=Vec::new()))]
    fn step(
        &mut self,
        py: Python<'_>,
        color: PyReadonlyArray3<'_, u8>,
        depth: PyReadonlyArray2<'_, u16>,
        occlusions: Vec<(i64, i64, i64, i64)>,
    ) -> PyResult<Vec<StepResult>> {
        let camera = *self.inner.first().camera();
        let frame = frame_of(&camera, &color, &depth, self.depth_scale)?;
        let (inner, occlusions) = (&mut self.inner, rects(occlusions));
        let timed = py
            .detach(|| run_frame_several(inner, &frame, &occlusions, &mut clock_ms()))
            .map_err(tracker_error)?;
        timed
            .outputs
            .iter()
            .map(|output| step_result(py, output, times!(timed)))
            .collect()
    }

    /// The camera moved since the last frame (as `Tracker.move_camera`):
    /// every rope is moved with it.
    fn move_camera(&mut self, motion: PyReadonlyArray2<'_, f64>) -> PyResult<()> {
        let rigid = rigid_of(&motion)?;
        self.inner
            .ropes_mut()
            .iter_mut()
            .try_for_each(|rope| rope.move_camera(&rigid))
            .map_err(tracker_error)
    }

    /// Forgets every rope: the next frame finds them again.
    fn reset(&mut self) {
        self.inner.reset();
    }

    fn __repr__(&self) -> String {
        format!("MultiTracker(ropes={:?})", self.names)
    }
}

/// A sequence folder, a `.zip` of one, or a camera recording (`.bag`,
/// `.db3`, `.mcap`, with `dlo` its configuration), opened as the command
/// opens it. `len(seq)` frames; `seq[i]` is `(color, depth)` as numpy
/// arrays; `seq.tracker()` a tracker with its camera, colour range and rope.
#[pyclass(module = "upetrack", unsendable)]
struct Sequence {
    inner: IoSequence<Box<dyn Source>>,
    path: String,
}

#[pymethods]
impl Sequence {
    fn __len__(&self) -> usize {
        self.inner.len()
    }

    fn __getitem__<'py>(&self, py: Python<'py>, index: isize) -> PyResult<FrameArrays<'py>> {
        let n = self.inner.len() as isize;
        let i = if index < 0 { index + n } else { index };
        if !(0..n).contains(&i) {
            return Err(PyIndexError::new_err(format!("frame {index} of {n}")));
        }
        let d = self.inner.frame(i as usize).map_err(sequence_error)?;
        let (h, w) = (d.height as usize, d.width as usize);
        let color = PyArray1::from_vec(py, d.color).reshape([h, w, 3])?;
        let depth = PyArray1::from_vec(py, d.depth).reshape([h, w])?;
        Ok((color, depth))
    }

    /// When frame `index` was taken, seconds: a recording's own colour
    /// time from its first message; a folder's frames at its frame rate
    /// from 0.
    fn time(&self, index: usize) -> PyResult<f64> {
        if index >= self.inner.len() {
            return Err(PyIndexError::new_err(format!(
                "frame {index} of {}",
                self.inner.len()
            )));
        }
        Ok(self.inner.time_s(index))
    }

    /// Frames per second (`dlo.json`'s, or the recording's).
    #[getter]
    fn fps(&self) -> f64 {
        self.inner.fps
    }

    /// Every frame in order as `(time, (color, depth))`: seconds, then
    /// uint8 H x W x 3 RGB and uint16 H x W.
    fn frames(slf: Py<Self>) -> Frames {
        Frames { seq: slf, next: 0 }
    }

    /// The camera's intrinsics.
    #[getter]
    fn intrinsics(&self) -> Intrinsics {
        self.inner.camera.into()
    }

    /// Metres per depth unit.
    #[getter]
    fn depth_scale(&self) -> f64 {
        self.inner.depth_scale
    }

    /// The rope's colour range, `((h, s, v), (h, s, v))` (OpenCV's convention).
    #[getter]
    fn hsv(&self) -> HsvTuple {
        let ([a, b, c], [d, e, f]) = (self.inner.hsv.lower, self.inner.hsv.upper);
        ((a, b, c), (d, e, f))
    }

    /// The colour noise the range's saturation test allows for, levels of
    /// chroma (0: OpenCV's `inRange`).
    #[getter]
    fn chroma_noise(&self) -> u8 {
        self.inner.hsv.chroma_noise
    }

    /// The occluder rectangles `(x, y, w, h)` in force on frame `index`:
    /// what a tracker's `step(..., occlusions=...)` takes for that frame
    /// (a tracker does not know which frame it is given).
    fn occlusions_at(&self, index: usize) -> Vec<(i64, i64, i64, i64)> {
        self.inner
            .occlusions_at(index)
            .into_iter()
            .map(|r| (r.x, r.y, r.w, r.h))
            .collect()
    }

    /// The names of the ropes `dlo.json` lists (`ropes`; one name for a
    /// sequence of one rope).
    #[getter]
    fn ropes(&self) -> Vec<String> {
        self.inner.ropes.iter().map(|r| r.name.clone()).collect()
    }

    /// A tracker for this sequence (its camera, frame rate, colour range and the rope
    /// `dlo.json` describes), as the command builds it; with several ropes,
    /// of rope `rope` alone (its colour, prior and hint: the other ropes'
    /// pixels are not shared out, as `track` shares them).
    #[pyo3(signature = (params=None, algorithm=None, rope=0))]
    fn tracker(
        &self,
        params: Option<&Bound<'_, PyAny>>,
        algorithm: Option<&str>,
        rope: usize,
    ) -> PyResult<Tracker> {
        let params = algorithm_of(algorithm, params_of(params)?)?;
        let count = self.inner.ropes.len();
        let inner = match self.inner.ropes.get(rope) {
            _ if count <= 1 && rope == 0 => self.inner.tracker(params).map_err(tracker_error)?,
            Some(r) => {
                let mut t = upetrack::Tracker::new(params, self.inner.camera, r.hsv)
                    .map_err(tracker_error)?;
                t.set_rope_prior(r.prior).map_err(tracker_error)?;
                t.set_rope_hint(r.hint);
                t.set_frame_rate(self.inner.fps).map_err(tracker_error)?;
                t
            }
            None => {
                return Err(PyValueError::new_err(format!(
                    "rope={rope}: the sequence has {count} rope(s), 0 to {}",
                    count.saturating_sub(1)
                )))
            }
        };
        Ok(Tracker {
            inner,
            depth_scale: self.inner.depth_scale,
            occlusions: Vec::new(),
        })
    }

    /// A tracker of every rope `dlo.json` lists, together (their colours,
    /// priors and hints), as `upetrack track` tracks them; one rope's is
    /// that rope's `tracker()` in a list of one.
    #[pyo3(signature = (params=None, algorithm=None))]
    fn multi_tracker(
        &self,
        params: Option<&Bound<'_, PyAny>>,
        algorithm: Option<&str>,
    ) -> PyResult<MultiTracker> {
        let params = algorithm_of(algorithm, params_of(params)?)?;
        let inner = self.inner.multi_tracker(params).map_err(tracker_error)?;
        Ok(MultiTracker {
            inner,
            names: self.ropes(),
            depth_scale: self.inner.depth_scale,
        })
    }

    fn __repr__(&self) -> String {
        format!("Sequence({:?}, {} frames)", self.path, self.inner.len())
    }
}

/// The frames of a [`Sequence`] in order, as `(time, (color, depth))`.
#[pyclass(module = "upetrack", unsendable)]
struct Frames {
    seq: Py<Sequence>,
    next: usize,
}

#[pymethods]
impl Frames {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__<'py>(&mut self, py: Python<'py>) -> PyResult<Option<(f64, FrameArrays<'py>)>> {
        let seq = self.seq.borrow(py);
        if self.next >= seq.inner.len() {
            return Ok(None);
        }
        let i = self.next;
        self.next += 1;
        Ok(Some((
            seq.inner.time_s(i),
            seq.__getitem__(py, i as isize)?,
        )))
    }
}

/// Opens a sequence folder, a `.zip`, or a recording (`dlo`: its `dlo.json`).
#[pyfunction]
#[pyo3(signature = (path, dlo=None))]
fn open(path: PathBuf, dlo: Option<PathBuf>) -> PyResult<Sequence> {
    let inner = upetrack_io::recorded::open_any(&path, dlo.as_deref(), &Default::default())
        .map_err(sequence_error)?;
    Ok(Sequence {
        inner,
        path: path.display().to_string(),
    })
}

/// Tracks every frame of a sequence as `upetrack track` does and returns
/// the result JSON's text (written to `out` too when given).
#[pyfunction]
#[pyo3(signature = (path, out=None, params=None, algorithm=None, dlo=None))]
fn track(
    path: PathBuf,
    out: Option<PathBuf>,
    params: Option<&Bound<'_, PyAny>>,
    algorithm: Option<&str>,
    dlo: Option<PathBuf>,
) -> PyResult<String> {
    let params = algorithm_of(algorithm, params_of(params)?)?;
    let seq = upetrack_io::recorded::open_any(&path, dlo.as_deref(), &Default::default())
        .map_err(sequence_error)?;
    let result =
        upetrack_io::run::track_sequence(&seq, params, &mut clock_ms()).map_err(sequence_error)?;
    if let Some(out) = out {
        upetrack_io::write::write_json(&out, &result).map_err(sequence_error)?;
    }
    serde_json::to_string_pretty(&result).map_err(|e| SequenceError::new_err(e.to_string()))
}

/// The names of the tracking algorithms.
#[pyfunction]
fn algorithms() -> Vec<&'static str> {
    Algorithm::ALL.iter().map(|a| a.name()).collect()
}

/// The extension module, `upetrack._upetrack` (`import upetrack` re-exports it).
#[pymodule]
#[pyo3(name = "_upetrack")]
fn upetrack_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<Intrinsics>()?;
    m.add_class::<Tracker>()?;
    m.add_class::<MultiTracker>()?;
    m.add_class::<StepResult>()?;
    m.add_class::<Sequence>()?;
    m.add_class::<Frames>()?;
    m.add_function(wrap_pyfunction!(open, m)?)?;
    m.add_function(wrap_pyfunction!(track, m)?)?;
    m.add_function(wrap_pyfunction!(algorithms, m)?)?;
    m.add("TrackerError", m.py().get_type::<TrackerError>())?;
    m.add("SequenceError", m.py().get_type::<SequenceError>())?;
    Ok(())
}
