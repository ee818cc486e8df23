//! Several ropes in the page: a tracker's ropes as given, each rope's
//! result in a frame, and each rope of an opened sequence.

use serde::{Deserialize, Serialize};
use upetrack::tracker::FrameOutput;
use upetrack::{Frame, HsvRange, Rect, Vec3};
use upetrack_io::result::FrameRecord;
use upetrack_io::run::{output_record, run_frame_several};
use upetrack_io::sequence::RopeConfig;
use wasm_bindgen::prelude::*;

use crate::{js_err, now_ms, project_all, status_of, FrameResult, WasmTracker};

/// One rope of a tracker of several: `{ name?, hsv?, rope? }`.
#[derive(Deserialize)]
pub(crate) struct RopeOptions {
    #[serde(default)]
    pub(crate) name: Option<String>,
    #[serde(default)]
    pub(crate) hsv: Option<HsvRange>,
    #[serde(default)]
    pub(crate) rope: Option<RopeConfig>,
}

/// One rope's result in a frame of several ropes.
#[derive(Serialize)]
pub(crate) struct RopeFrame {
    name: String,
    /// Flat metres.
    nodes: Vec<f64>,
    /// Flat pixels, NaN where not projectable.
    nodes_px: Vec<f32>,
    visible: Vec<bool>,
    status: String,
    reason: Option<String>,
    /// The result JSON's entry of this rope's frame.
    record: FrameRecord,
}

impl WasmTracker {
    /// One frame of several ropes: the first rope's result with every
    /// rope's in `ropes`, timed by `upetrack_io::run::run_frame_several`.
    pub(crate) fn track_several(
        &mut self,
        frame: &Frame<'_>,
        rects: &[Rect],
    ) -> Result<FrameResult, JsError> {
        let t = run_frame_several(&mut self.ropes, frame, rects, &mut now_ms).map_err(js_err)?;
        let record = |out: &FrameOutput| output_record(0, out, t.track_ms, t.total_ms);
        let camera = *self.ropes.first().camera();
        let ropes: Vec<RopeFrame> = t
            .outputs
            .iter()
            .zip(&self.names)
            .map(|(out, name)| {
                let (status, reason) = status_of(out);
                RopeFrame {
                    name: name.clone(),
                    nodes: out.nodes.iter().flat_map(|p| [p.x, p.y, p.z]).collect(),
                    nodes_px: project_all(&camera, &out.nodes),
                    visible: out.visible.clone(),
                    status: status.into(),
                    reason,
                    record: record(out),
                }
            })
            .collect();
        let first = t
            .outputs
            .first()
            .ok_or_else(|| JsError::new("no rope tracked"))?;
        let (status, reason) = status_of(first);
        let result = FrameResult {
            nodes: first.nodes.iter().flat_map(|p| [p.x, p.y, p.z]).collect(),
            nodes_px: project_all(&camera, &first.nodes),
            visible: first.visible.iter().map(|&v| v as u8).collect(),
            status: status.into(),
            reason,
            segment_ms: t.segment_ms,
            cloud_ms: t.cloud_ms,
            track_ms: t.track_ms,
            total_ms: t.total_ms,
            cloud_points: t.cloud_points.first().map_or(0, |&n| n as u32),
            init: first.init.clone(),
            record: record(first),
            ropes,
        };
        self.last_masks = Some(t.masks);
        self.last_obs = None;
        self.last = t.outputs;
        Ok(result)
    }
}

/// One rope of a sequence of several, for the page.
#[derive(Serialize)]
pub(crate) struct RopeInfo {
    name: String,
    hsv: HsvRange,
    /// What is known of it, as `dlo.json`'s `rope`.
    rope: RopeConfig,
    /// Flat metres per frame, or null.
    groundtruth: Vec<Option<Vec<f64>>>,
    /// A pixel on it in the first frame (`dlo.json`'s `hint`), or null.
    hint: Option<[f64; 2]>,
}

impl RopeInfo {
    /// The page's view of one rope of an opened sequence.
    pub(crate) fn of(rope: &upetrack_io::ropes::SequenceRope) -> Self {
        Self {
            name: rope.name.clone(),
            hsv: rope.hsv,
            rope: RopeConfig {
                length_m: rope.prior.length,
                diameter_m: rope.prior.diameter,
            },
            groundtruth: flat_truth(&rope.groundtruth),
            hint: rope.hint,
        }
    }
}

/// Ground truth per frame as flat metres.
pub(crate) fn flat_truth(truth: &[Option<Vec<Vec3>>]) -> Vec<Option<Vec<f64>>> {
    truth
        .iter()
        .map(|g| {
            g.as_ref()
                .map(|pts| pts.iter().flat_map(|p| [p.x, p.y, p.z]).collect())
        })
        .collect()
}
