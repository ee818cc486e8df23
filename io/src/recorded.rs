//! A camera recording (a ROS1 `.bag`) read as a sequence: the frames come from
//! the recording, the configuration (`dlo.json`, and the ground truth it
//! names) from a file beside it, given with `--dlo`.

use std::path::Path;

use upetrack::CameraIntrinsics;
use upetrack_recordings::{ByteSource, FileBytes, Recording, RecordingOptions};

use crate::error::SequenceError;
use crate::recording_info::{RecordingInfo, StreamInfo};
use crate::sequence::{DecodedFrame, FrameReader, Sequence};
use crate::source::{is_inside_name, FolderSource, MemorySource, Source};

/// `true` when the file at `path` starts like a recording this project reads.
pub fn is_recording_file(path: &Path) -> bool {
    crate::open::input_kind_of_file(path) == crate::open::InputKind::Recording
}

/// A recording opened for reading frames.
pub struct OpenRecording {
    rec: Recording<Box<dyn ByteSource>>,
    name: String,
}

fn stream_info(s: &upetrack_recordings::recording::Stream) -> StreamInfo {
    let i = s.intrinsics;
    StreamInfo {
        topic: s.topic.clone(),
        width: i.width,
        height: i.height,
        fps: s.fps,
        frames: s.frames,
        intrinsics: [i.fx, i.fy, i.ppx, i.ppy],
        distortion: format!("{:?}", i.model),
    }
}

impl OpenRecording {
    /// Opens the recording at `path`, seeking in it, never reading it whole.
    pub fn open(path: &Path, options: &RecordingOptions) -> Result<Self, SequenceError> {
        let name = path.display().to_string();
        let bytes = FileBytes::open(path).map_err(|source| SequenceError::Recording {
            path: name.clone(),
            source,
        })?;
        Self::from_source(Box::new(bytes), &name, options)
    }

    /// Opens a recording from any byte source (the page's `Blob` reader);
    /// `name` appears in messages.
    pub fn from_source(
        bytes: Box<dyn ByteSource>,
        name: &str,
        options: &RecordingOptions,
    ) -> Result<Self, SequenceError> {
        let name = name.to_string();
        let rec = Recording::open(bytes, options).map_err(|source| SequenceError::Recording {
            path: name.clone(),
            source,
        })?;
        if rec.is_empty() {
            return Err(SequenceError::invalid(
                &name,
                format!(
                    "no colour frame has a depth frame within half a frame period ({} colour, {} depth frames)",
                    rec.color.frames, rec.depth.frames
                ),
            ));
        }
        Ok(Self { rec, name })
    }

    /// The colour camera as the tracker sees it (pinhole; distortion is not modelled).
    pub fn camera(&self) -> Result<CameraIntrinsics, SequenceError> {
        let i = self.rec.color.intrinsics;
        let camera = CameraIntrinsics {
            width: i.width,
            height: i.height,
            fx: f64::from(i.fx),
            fy: f64::from(i.fy),
            cx: f64::from(i.ppx),
            cy: f64::from(i.ppy),
        };
        camera
            .validate()
            .map_err(|e| SequenceError::invalid(&self.name, e.to_string()))?;
        Ok(camera)
    }

    /// Metres per depth unit.
    pub fn depth_units(&self) -> f64 {
        self.rec.depth_units
    }

    /// The colour stream's frame rate.
    pub fn fps(&self) -> f64 {
        self.rec.color.fps
    }

    /// Paired frames.
    pub fn len(&self) -> usize {
        self.rec.len()
    }

    /// `true` when there are no paired frames (never, once opened).
    pub fn is_empty(&self) -> bool {
        self.rec.is_empty()
    }

    /// How frame `index` is named in messages.
    pub fn frame_name(&self, index: usize) -> String {
        let ms = self.rec.time_ns(index).unwrap_or(0) as f64 / 1e6;
        format!("{}: frame {index} ({ms:.1} ms)", self.name)
    }

    /// Decodes frame `index`, depth aligned to colour.
    pub fn frame(&mut self, index: usize) -> Result<DecodedFrame, SequenceError> {
        let f = self
            .rec
            .frame(index)
            .map_err(|source| SequenceError::Recording {
                path: self.name.clone(),
                source,
            })?;
        Ok(DecodedFrame {
            width: f.width,
            height: f.height,
            color: f.color,
            depth: f.depth,
        })
    }

    /// Streams, pairing and warnings.
    pub fn info(&self) -> RecordingInfo {
        let r = &self.rec;
        RecordingInfo {
            path: self.name.clone(),
            layout: match r.layout {
                upetrack_recordings::recording::Layout::Librealsense => "librealsense".into(),
                upetrack_recordings::recording::Layout::Ros => "ros".into(),
            },
            color: stream_info(&r.color),
            depth: stream_info(&r.depth),
            aligned_on_reading: r.depth_to_color.is_some(),
            depth_units: r.depth_units,
            paired_frames: r.len(),
            unpaired_color: r.unpaired_color,
            unpaired_depth: r.unpaired_depth,
            image_topics: r.topics.clone(),
            warnings: r.warnings().to_vec(),
        }
    }
}

impl FrameReader for OpenRecording {
    fn frame(&mut self, index: usize) -> Result<DecodedFrame, SequenceError> {
        OpenRecording::frame(self, index)
    }

    fn time_s(&self, index: usize) -> Option<f64> {
        self.rec.time_ns(index).map(|ns| ns as f64 / 1e9)
    }

    fn info(&self) -> RecordingInfo {
        OpenRecording::info(self)
    }
}

/// The sequence of `rec`, configured by the `dlo.json` (and the ground truth
/// it names) that `config` holds; an empty `config` takes the defaults.
pub fn recording_sequence<S: Source>(
    config: S,
    rec: OpenRecording,
) -> Result<Sequence<S>, SequenceError> {
    // Before a name is made for each frame.
    crate::sequence::check_frame_count(rec.name.clone(), rec.len())?;
    let camera = rec.camera()?;
    let names = (0..rec.len()).map(|i| rec.frame_name(i)).collect();
    let rates = (1.0 / rec.depth_units(), rec.fps());
    Sequence::with_reader(config, camera, rates, names, Box::new(rec))
}

/// A recording with its configuration: `dlo` is a `dlo.json` (any name); a
/// ground-truth file it names is read from beside it.
pub fn open_recording(
    path: &Path,
    dlo: Option<&Path>,
    options: &RecordingOptions,
) -> Result<Sequence<Box<dyn Source>>, SequenceError> {
    let rec = OpenRecording::open(path, options)?;
    let mut files = MemorySource::new(path.display().to_string());
    if let Some(dlo) = dlo {
        let shown = dlo.display().to_string();
        let dir = dlo.parent().unwrap_or(Path::new(""));
        let folder = FolderSource::new(dir);
        let file_name = dlo.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let bytes = folder.read(file_name)?;
        let config = crate::sequence::DloConfig::parse(&bytes, &shown)?;
        files = MemorySource::new(dir.display().to_string());
        if let Some(gt) = &config.groundtruth {
            if !is_inside_name(gt) {
                return Err(SequenceError::invalid(
                    &shown,
                    format!("groundtruth `{gt}` must be a path inside the configuration's folder"),
                ));
            }
            if folder.is_file(gt) {
                files.insert(gt, folder.read(gt)?);
            }
        }
        files.insert("dlo.json", bytes);
    }
    recording_sequence(Box::new(files) as Box<dyn Source>, rec)
}

/// Any sequence the command reads: a camera recording (with `dlo`, its
/// configuration), or a folder or `.zip` in the contract's layout (which
/// has its own `dlo.json`, so `dlo` must be `None`).
pub fn open_any(
    path: &Path,
    dlo: Option<&Path>,
    options: &RecordingOptions,
) -> Result<Sequence<Box<dyn Source>>, SequenceError> {
    if path.is_file() && is_recording_file(path) {
        return open_recording(path, dlo, options);
    }
    if dlo.is_some() {
        return Err(SequenceError::invalid(
            &path.display().to_string(),
            "a dlo.json is for recordings (.bag, .db3, .mcap); a sequence folder has its own",
        ));
    }
    Sequence::open(crate::open::open_path(path)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sequence::MAX_FRAMES;

    /// A reader that never decodes: only its length matters here.
    struct Endless;

    impl FrameReader for Endless {
        fn frame(&mut self, _: usize) -> Result<DecodedFrame, SequenceError> {
            Err(SequenceError::invalid("endless", "not decoded"))
        }

        fn info(&self) -> RecordingInfo {
            RecordingInfo::default()
        }

        fn time_s(&self, _: usize) -> Option<f64> {
            None
        }
    }

    #[test]
    fn a_recording_of_more_pairs_than_max_frames_is_refused() {
        let make = |n: usize| {
            Sequence::with_reader(
                MemorySource::new("rec"),
                CameraIntrinsics::D435I_640X480,
                (1000.0, 30.0),
                vec![String::new(); n],
                Box::new(Endless),
            )
        };
        assert!(make(MAX_FRAMES).is_ok());
        assert!(matches!(
            make(MAX_FRAMES + 1),
            Err(SequenceError::TooLarge { .. })
        ));
    }
}
