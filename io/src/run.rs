//! Running the tracker over a whole sequence, frame by frame, with a clock
//! supplied by the caller (the core has none; the browser's differs).

use upetrack::tracker::FrameStatus;
use upetrack::{Params, Tracker};

use crate::error::SequenceError;
use crate::result::{FrameRecord, TrackResult};
use crate::sequence::Sequence;
use crate::source::Source;

/// Tracks one decoded frame and returns its record. `now_ms` is read around
/// the stages to fill `track_ms` and `total_ms`.
pub fn track_frame(
    tracker: &mut Tracker,
    index: usize,
    frame: &upetrack::Frame<'_>,
    occlusions: &[upetrack::Rect],
    now_ms: &mut dyn FnMut() -> f64,
) -> Result<FrameRecord, upetrack::tracker::TrackerError> {
    let t0 = now_ms();
    let obs = tracker.observe(frame, occlusions)?;
    let t1 = now_ms();
    let out = tracker.update(frame, &obs);
    let t2 = now_ms();
    let reason = match &out.status {
        FrameStatus::Lost(r) => Some(r.to_string()),
        _ => None,
    };
    Ok(FrameRecord {
        frame: index,
        nodes: out.nodes.iter().map(|p| [p.x, p.y, p.z]).collect(),
        visible: out.visible,
        track_ms: t2 - t1,
        total_ms: t2 - t0,
        lost: reason.is_some(),
        reason,
    })
}

/// Tracks every frame of `seq` with `params`. A frame whose images cannot
/// be decoded is an error naming the file; nothing is skipped silently.
pub fn track_sequence<S: Source>(
    seq: &Sequence<S>,
    params: Params,
    now_ms: &mut dyn FnMut() -> f64,
) -> Result<TrackResult, SequenceError> {
    let mut tracker = Tracker::new(params, seq.camera, seq.hsv)
        .map_err(|e| SequenceError::invalid("parameters", e.to_string()))?;
    let mut frames = Vec::with_capacity(seq.len());
    for i in 0..seq.len() {
        let decoded = seq.frame(i)?;
        let frame = decoded
            .frame(seq.depth_scale)
            .map_err(|e| SequenceError::invalid(&seq.color_files[i], e.to_string()))?;
        let record = track_frame(&mut tracker, i, &frame, &seq.occlusions_at(i), now_ms)
            .map_err(|e| SequenceError::invalid(&seq.color_files[i], e.to_string()))?;
        frames.push(record);
    }
    Ok(TrackResult {
        algorithm: params.algorithm.name().to_string(),
        params,
        frames,
    })
}
