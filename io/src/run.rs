//! Running the tracker over a whole sequence, frame by frame, with a clock
//! supplied by the caller (the core has none; the browser's differs).

use upetrack::tracker::{FrameOutput, FrameStatus, Observation};
use upetrack::{MultiTracker, Params, Tracker};

use crate::error::SequenceError;
use crate::result::{ChecksRecord, FrameRecord, RecoveryRecord, RopeResult, TrackResult};
use crate::sequence::{DecodedFrame, Sequence};
use crate::source::Source;

/// One frame through the tracker with the stages timed.
#[derive(Debug, Clone)]
pub struct TimedFrame {
    /// The mask and cloud.
    pub observation: Observation,
    /// The tracker's output.
    pub output: FrameOutput,
    /// Segmentation alone, ms.
    pub segment_ms: f64,
    /// The point cloud alone (deprojection, voxel grid, offset), ms.
    pub cloud_ms: f64,
    /// The tracking step alone, ms.
    pub track_ms: f64,
    /// Segmentation, point cloud and tracking step, ms.
    pub total_ms: f64,
}

/// Observes and updates one decoded frame, reading `now_ms` around the
/// stages (the one definition of `track_ms` and `total_ms`).
pub fn run_frame(
    tracker: &mut Tracker,
    frame: &upetrack::Frame<'_>,
    occlusions: &[upetrack::Rect],
    now_ms: &mut dyn FnMut() -> f64,
) -> Result<TimedFrame, upetrack::tracker::TrackerError> {
    let t0 = now_ms();
    let mask = tracker.segment(frame, occlusions)?;
    let t1 = now_ms();
    let cloud = tracker.cloud(frame, &mask);
    let t2 = now_ms();
    let observation = Observation::new(mask, cloud, occlusions);
    let output = tracker.update(frame, &observation);
    let t3 = now_ms();
    Ok(TimedFrame {
        observation,
        output,
        segment_ms: t1 - t0,
        cloud_ms: t2 - t1,
        track_ms: t3 - t2,
        total_ms: t3 - t0,
    })
}

/// Tracks one decoded frame and returns its record.
pub fn track_frame(
    tracker: &mut Tracker,
    index: usize,
    frame: &upetrack::Frame<'_>,
    occlusions: &[upetrack::Rect],
    now_ms: &mut dyn FnMut() -> f64,
) -> Result<FrameRecord, upetrack::tracker::TrackerError> {
    let t = run_frame(tracker, frame, occlusions, now_ms)?;
    Ok(frame_record(index, &t))
}

/// The result JSON's record of frame `index` (the one definition of it:
/// the command writes it, the page keeps it per frame).
pub fn frame_record(index: usize, t: &TimedFrame) -> FrameRecord {
    output_record(index, &t.output, t.track_ms, t.total_ms)
}

/// The record of frame `index` from a tracker's `output` and its times.
pub fn output_record(
    index: usize,
    output: &FrameOutput,
    track_ms: f64,
    total_ms: f64,
) -> FrameRecord {
    let reason = match &output.status {
        FrameStatus::Lost(r) => Some(r.to_string()),
        _ => None,
    };
    FrameRecord {
        frame: index,
        nodes: output.nodes.iter().map(|p| [p.x, p.y, p.z]).collect(),
        visible: output.visible.clone(),
        track_ms,
        total_ms,
        lost: reason.is_some(),
        reason,
        recovered: matches!(output.status, FrameStatus::Recovered(_)),
        recovery: match &output.status {
            FrameStatus::Recovered(c) => Some(RecoveryRecord::of(c)),
            _ => None,
        },
        init: output.init.clone(),
        checks: output.judgement.as_ref().map(ChecksRecord::of),
    }
}

/// A whole result from its frames' records, numbered by position.
pub fn track_result(params: Params, mut frames: Vec<FrameRecord>) -> TrackResult {
    for (k, f) in frames.iter_mut().enumerate() {
        f.frame = k;
    }
    TrackResult {
        algorithm: params.algorithm.name().to_string(),
        params,
        frames,
        ropes: Vec::new(),
    }
}

/// A whole result of several ropes from each one's name and frames'
/// records (numbered by position): `frames` the first's, `ropes` every
/// one's; with one rope, [`track_result`]'s.
pub fn several_result(params: Params, ropes: Vec<(String, Vec<FrameRecord>)>) -> TrackResult {
    let several = ropes.len() > 1;
    let mut ropes: Vec<RopeResult> = ropes
        .into_iter()
        .map(|(name, frames)| RopeResult {
            name,
            frames: track_result(params, frames).frames,
        })
        .collect();
    let first = ropes.first().map(|r| r.frames.clone()).unwrap_or_default();
    let mut result = track_result(params, first);
    if several {
        result.ropes = core::mem::take(&mut ropes);
    }
    result
}

/// One frame of several ropes with the stages timed (as [`TimedFrame`]
/// for one): segmentation (one mask per colour range), the sharing of
/// pixels with every tracked rope's cloud, and every rope's step (with
/// the initialisation of ropes not tracked).
#[derive(Debug, Clone)]
pub struct TimedFrames {
    /// Each rope's colour mask.
    pub masks: Vec<upetrack::perception::segmentation::Mask>,
    /// Each rope's output, in order.
    pub outputs: Vec<FrameOutput>,
    /// Each rope's cloud as shared out to it (0 for a rope not tracked at
    /// the frame's start).
    pub cloud_points: Vec<usize>,
    /// Segmentation, ms.
    pub segment_ms: f64,
    /// The sharing of pixels and the clouds, ms.
    pub cloud_ms: f64,
    /// Every rope's step, ms.
    pub track_ms: f64,
    /// All of it, ms.
    pub total_ms: f64,
}

/// [`run_frame`] for several ropes (the one definition of their times).
pub fn run_frame_several(
    ropes: &mut MultiTracker,
    frame: &upetrack::Frame<'_>,
    occlusions: &[upetrack::Rect],
    now_ms: &mut dyn FnMut() -> f64,
) -> Result<TimedFrames, upetrack::tracker::TrackerError> {
    let t0 = now_ms();
    let masks = ropes.segment(frame, occlusions)?;
    let t1 = now_ms();
    let observations = ropes.observe(frame, &masks, occlusions);
    let cloud_points = observations
        .iter()
        .map(|o| o.as_ref().map_or(0, |o| o.cloud.len()))
        .collect();
    let t2 = now_ms();
    let outputs = ropes.step(frame, &masks, observations, occlusions);
    let t3 = now_ms();
    Ok(TimedFrames {
        masks,
        outputs,
        cloud_points,
        segment_ms: t1 - t0,
        cloud_ms: t2 - t1,
        track_ms: t3 - t2,
        total_ms: t3 - t0,
    })
}

/// Several ropes' records of one frame, timed as one: `total_ms` from the
/// decoded images to every rope's step, `track_ms` every rope's step from
/// the shared pixels' clouds (with the initialisation of ropes not
/// tracked), the same on each rope's record.
pub fn track_frame_several(
    ropes: &mut MultiTracker,
    index: usize,
    frame: &upetrack::Frame<'_>,
    occlusions: &[upetrack::Rect],
    now_ms: &mut dyn FnMut() -> f64,
) -> Result<Vec<FrameRecord>, upetrack::tracker::TrackerError> {
    let t = run_frame_several(ropes, frame, occlusions, now_ms)?;
    Ok(t.outputs
        .iter()
        .map(|output| output_record(index, output, t.track_ms, t.total_ms))
        .collect())
}

/// What tracks a sequence: one rope, or several.
enum Runner {
    One(Box<Tracker>),
    Several {
        ropes: Box<MultiTracker>,
        names: Vec<String>,
    },
}

/// The tracking half of a run over a sequence: decoded frames in, in
/// order, the result out. [`track_sequence`] feeds it from the same
/// thread; the command feeds it from a thread that decodes ahead.
pub struct SequenceRun {
    runner: Runner,
    params: Params,
    depth_scale: f64,
    /// Each rope's records, in the sequence's order of ropes.
    records: Vec<Vec<FrameRecord>>,
}

impl SequenceRun {
    /// A run of `params` over `seq` (its camera, and each rope's colour
    /// range and prior).
    pub fn new<S: Source>(seq: &Sequence<S>, params: Params) -> Result<Self, SequenceError> {
        let invalid = |e: upetrack::tracker::TrackerError| {
            SequenceError::invalid("parameters", e.to_string())
        };
        let runner = if seq.ropes.len() > 1 {
            Runner::Several {
                ropes: Box::new(seq.multi_tracker(params).map_err(invalid)?),
                names: seq.ropes.iter().map(|r| r.name.clone()).collect(),
            }
        } else {
            Runner::One(Box::new(seq.tracker(params).map_err(invalid)?))
        };
        Ok(Self {
            runner,
            params,
            depth_scale: seq.depth_scale,
            records: vec![Vec::with_capacity(seq.len()); seq.ropes.len().max(1)],
        })
    }

    /// Tracks the next frame; `name` (its colour file) names it in errors.
    pub fn push(
        &mut self,
        decoded: &DecodedFrame,
        occlusions: &[upetrack::Rect],
        name: &str,
        now_ms: &mut dyn FnMut() -> f64,
    ) -> Result<(), SequenceError> {
        let frame = decoded
            .frame(self.depth_scale)
            .map_err(|e| SequenceError::invalid(name, e.to_string()))?;
        let index = self.records[0].len();
        let records = match &mut self.runner {
            Runner::One(tracker) => {
                track_frame(tracker, index, &frame, occlusions, now_ms).map(|r| vec![r])
            }
            Runner::Several { ropes, .. } => {
                track_frame_several(ropes, index, &frame, occlusions, now_ms)
            }
        }
        .map_err(|e| SequenceError::invalid(name, e.to_string()))?;
        for (kept, record) in self.records.iter_mut().zip(records) {
            kept.push(record);
        }
        Ok(())
    }

    /// The result of the frames pushed so far.
    pub fn finish(self) -> TrackResult {
        match self.runner {
            Runner::Several { names, .. } => {
                several_result(self.params, names.into_iter().zip(self.records).collect())
            }
            Runner::One(_) => track_result(
                self.params,
                self.records.into_iter().next().unwrap_or_default(),
            ),
        }
    }
}

/// Tracks every frame of `seq` with `params`. A frame whose images cannot
/// be decoded is an error naming the file; nothing is skipped silently.
pub fn track_sequence<S: Source>(
    seq: &Sequence<S>,
    params: Params,
    now_ms: &mut dyn FnMut() -> f64,
) -> Result<TrackResult, SequenceError> {
    let mut run = SequenceRun::new(seq, params)?;
    for i in 0..seq.len() {
        let decoded = seq.frame(i)?;
        run.push(&decoded, &seq.occlusions_at(i), &seq.frame_name(i), now_ms)?;
    }
    Ok(run.finish())
}
