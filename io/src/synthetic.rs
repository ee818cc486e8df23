//! A synthetic scenario (`upetrack_synth`) written as the contract's
//! sequence files, one frame at a time, to wherever the caller keeps them:
//! a folder for `upetrack synth`, memory for the page's scene generator.

use upetrack_synth::{Scenario, SynthFrame};

use crate::error::SequenceError;
use crate::sequence::{
    DloConfig, GroundTruthFile, GroundTruthFrame, IntrinsicsFile, OcclusionConfig, RopeConfig,
    SegmentationConfig,
};
use crate::write::{compact_json_bytes, encode_depth_png, encode_jpeg, json_bytes, JPEG_QUALITY};

/// Frames per second of a synthetic sequence unless a drawn scene asks for
/// another rate (the simulator's).
pub const SYNTHETIC_FPS: f64 = upetrack_synth::SIMULATED_FPS;

/// Depth units of every synthetic sequence, metres.
pub const SYNTHETIC_DEPTH_SCALE: f64 = 0.001;

/// The file of a drawn scene (`upetrack synth random`) that records
/// everything drawn for it; readers of the contract ignore it.
pub const SCENE_FILE: &str = "scene.json";

/// One file of a sequence: its path inside the folder and its bytes.
pub type SequenceFile = (String, Vec<u8>);

fn json<T: serde::Serialize>(path: &str, value: &T) -> Result<SequenceFile, SequenceError> {
    Ok((path.to_string(), json_bytes(path, value)?))
}

/// Writes a scenario's files in order: [`SyntheticWriter::header`], then
/// [`SyntheticWriter::next_frame`] until it gives `None`, then
/// [`SyntheticWriter::groundtruth`].
pub struct SyntheticWriter {
    scenario: Scenario,
    groundtruth: GroundTruthFile,
    jpeg_quality: u8,
    rope_prior: bool,
}

impl SyntheticWriter {
    /// A writer of `scenario`'s frames.
    pub fn new(scenario: Scenario) -> Self {
        Self {
            scenario,
            groundtruth: GroundTruthFile::default(),
            jpeg_quality: JPEG_QUALITY,
            rope_prior: false,
        }
    }

    /// The same writer also writing the rope's length and diameter into
    /// `dlo.json` (`rope`), as a user who knows them would.
    pub fn with_rope_prior(mut self, on: bool) -> Self {
        self.rope_prior = on;
        self
    }

    /// The same writer encoding colour at JPEG `quality` (1..=100, clamped)
    /// instead of [`JPEG_QUALITY`]: smaller files for a bundled sample.
    pub fn with_jpeg_quality(mut self, quality: u8) -> Self {
        self.jpeg_quality = quality.clamp(1, 100);
        self
    }

    /// The scenario being written.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// `camera_intrinsic.json` and `dlo.json` (colour range, occlusion
    /// rectangles, depth scale, fps, the ground truth's file name), and for
    /// a drawn scene [`SCENE_FILE`].
    pub fn header(&self) -> Result<Vec<SequenceFile>, SequenceError> {
        let s = &self.scenario;
        let hsv = s.hsv();
        let dlo = DloConfig {
            depth_scale: Some(SYNTHETIC_DEPTH_SCALE),
            fps: Some(s.fps()),
            segmentation: Some(SegmentationConfig::of(&hsv)),
            occlusions: s
                .occlusions
                .iter()
                .map(|o| OcclusionConfig {
                    frames: [o.first as u64, o.last as u64],
                    rect: [o.rect.x, o.rect.y, o.rect.w, o.rect.h],
                })
                .collect(),
            groundtruth: Some("groundtruth.json".into()),
            rope: self.rope_prior.then_some(RopeConfig {
                length_m: Some(s.rope.settings.length),
                diameter_m: Some(s.rope.settings.thickness),
            }),
            ropes: Vec::new(),
        };
        let mut files = vec![
            json(
                "camera_intrinsic.json",
                &IntrinsicsFile::from_camera(&s.camera()),
            )?,
            json("dlo.json", &dlo)?,
        ];
        if let Some(draw) = &s.draw {
            files.push(json(SCENE_FILE, draw)?);
        }
        Ok(files)
    }

    /// Simulates and renders the next frame: its colour JPEG and depth PNG,
    /// or `None` after the last frame.
    pub fn next_frame(&mut self) -> Result<Option<[SequenceFile; 2]>, SequenceError> {
        self.next_frame_seen(&mut |_| Ok(()))
    }

    /// [`SyntheticWriter::next_frame`], showing `see` the rendered frame first
    /// (to write it elsewhere too, as a video).
    pub fn next_frame_seen(
        &mut self,
        see: &mut dyn FnMut(&SynthFrame) -> Result<(), SequenceError>,
    ) -> Result<Option<[SequenceFile; 2]>, SequenceError> {
        let camera = self.scenario.camera();
        let Some(f) = self.scenario.next_frame() else {
            return Ok(None);
        };
        see(&f)?;
        let files = frame_files(f.index, &camera, &f.rgb, &f.depth, self.jpeg_quality)?;
        self.groundtruth
            .frames
            .push(truth_frame(f.index, &f.groundtruth, f.occluded));
        Ok(Some(files))
    }

    /// `groundtruth.json` of the frames written so far, without
    /// indentation (half the size of pretty JSON for the same numbers).
    pub fn groundtruth(&self) -> Result<SequenceFile, SequenceError> {
        let path = "groundtruth.json";
        Ok((path.into(), compact_json_bytes(path, &self.groundtruth)?))
    }

    /// Frames written so far.
    pub fn written(&self) -> usize {
        self.groundtruth.frames.len()
    }
}

/// Frame `index`'s colour JPEG (at `quality`) and depth PNG.
pub(crate) fn frame_files(
    index: usize,
    camera: &upetrack::CameraIntrinsics,
    rgb: &[u8],
    depth: &[u16],
    quality: u8,
) -> Result<[SequenceFile; 2], SequenceError> {
    let name = format!("{index:06}");
    let jpg = encode_jpeg(camera.width, camera.height, rgb, quality)?;
    let png = encode_depth_png(camera.width, camera.height, depth)?;
    Ok([
        (format!("color/{name}.jpg"), jpg),
        (format!("depth/{name}.png"), png),
    ])
}

/// Frame `index` of a ground-truth file (`occluded` kept only when some
/// point is hidden).
pub(crate) fn truth_frame(
    index: usize,
    points: &[upetrack::Vec3],
    occluded: Vec<bool>,
) -> GroundTruthFrame {
    GroundTruthFrame {
        frame: index,
        points: points.iter().map(|p| [p.x, p.y, p.z]).collect(),
        occluded: if occluded.iter().any(|&o| o) {
            occluded
        } else {
            Vec::new()
        },
    }
}

/// Writes every file of `w`'s scenario through `put`, showing `see` each
/// rendered frame; returns the frame count.
pub fn write_scenario(
    mut w: SyntheticWriter,
    put: &mut dyn FnMut(SequenceFile) -> Result<(), SequenceError>,
    see: &mut dyn FnMut(&SynthFrame) -> Result<(), SequenceError>,
) -> Result<usize, SequenceError> {
    for f in w.header()? {
        put(f)?;
    }
    while let Some(files) = w.next_frame_seen(see)? {
        for f in files {
            put(f)?;
        }
    }
    put(w.groundtruth()?)?;
    Ok(w.written())
}
