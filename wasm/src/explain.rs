//! The explain mode's view of one frame: every stage of the tracker's
//! update (`Tracker::explain`), projected to pixels for drawing.

use serde::Serialize;
use upetrack::perception::point_cloud::deproject_mask;
use upetrack::tracker::{
    MIN_NODES_IN_FREE_SPACE, STRETCH_LIMIT, UNEXPLAINED_LIMIT, UNEXPLAINED_REACH,
};
use upetrack::upe::registration::responsibilities;
use upetrack::{CameraIntrinsics, Frame, Vec3};
use upetrack_io::result::ChecksRecord;
use wasm_bindgen::prelude::*;

use crate::{js_err, project_all, rects_of, to_js, DecodedFrame, WasmTracker};

/// Responsibilities below this are not drawn as lines.
pub const MIN_DRAWN_RESPONSIBILITY: f64 = 0.05;

/// One EM iteration for drawing.
#[derive(Serialize)]
struct EmView {
    /// `sigma^2`, square millimetres.
    variance_mm2: f64,
    /// Nodes at the iteration's start, pixels.
    nodes_px: Vec<f32>,
    /// Lines from cloud points to nodes: point index, node index, `P(m|x)`.
    line_point: Vec<u32>,
    line_node: Vec<u32>,
    line_p: Vec<f32>,
}

/// Every stage, projected. Absent nodes (a sweep that did not reach one) are NaN.
#[derive(Serialize)]
struct ExplainView {
    status: String,
    mask_pixels: usize,
    deprojected_points: usize,
    cloud_px: Vec<f32>,
    previous_px: Vec<f32>,
    /// `r_vis` around each previous node, pixels.
    radius_px: Vec<f32>,
    counts: Vec<u32>,
    visible: Vec<bool>,
    visibility_min_points: u32,
    em: Vec<EmView>,
    registered_px: Vec<f32>,
    forward_px: Vec<f32>,
    backward_px: Vec<f32>,
    slid_px: Vec<f32>,
    end_runs: Vec<bool>,
    estimated_px: Vec<f32>,
    before_resampling_px: Vec<f32>,
    resampled_px: Vec<f32>,
    output_px: Vec<f32>,
    /// Rope length before and after resampling, millimetres.
    length_before_mm: f64,
    length_after_mm: f64,
    /// What the recovery tests read after the step and what came of it
    /// (as the result file's `checks`), when a step ran.
    checks: Option<ChecksRecord>,
    /// The tests' thresholds.
    limits: CheckLimits,
}

/// The recovery tests' thresholds, for the explanation's text.
#[derive(Serialize)]
struct CheckLimits {
    /// Tracked length over rest length beyond which the state is stretched.
    stretch: f64,
    /// Hidden nodes left in free space that contradict the state.
    nodes_in_free_space: usize,
    /// Share of the cloud left unexplained that contradicts the state.
    unexplained: f64,
    /// How far from the nodes' axis a point is unexplained, millimetres.
    unexplained_reach_mm: f64,
}

fn length_mm(nodes: &[Vec3]) -> f64 {
    1000.0 * upetrack::polyline::polyline_length(nodes)
}

fn optional_px(camera: &CameraIntrinsics, points: &[Option<Vec3>]) -> Vec<f32> {
    let nan = Vec3::new(f64::NAN, f64::NAN, f64::NAN);
    project_all(
        camera,
        &points.iter().map(|p| p.unwrap_or(nan)).collect::<Vec<_>>(),
    )
}

#[wasm_bindgen]
impl WasmTracker {
    /// Explains the update of a decoded frame from the present state
    /// (restore the previous frame's snapshot first), without changing the
    /// tracker. Returns every stage projected to pixels: the cloud, the
    /// visibility test, each EM iteration with its responsibilities, both
    /// sweeps of the occlusion estimate, and resampling. The frame's mask
    /// is then `lastMask()`.
    pub fn explain(
        &mut self,
        frame: &DecodedFrame,
        depth_scale: f64,
        occlusions: &[f64],
    ) -> Result<JsValue, JsError> {
        self.explain_rope(0, frame, depth_scale, occlusions)
    }

    /// [`WasmTracker::explain`] for rope `k` of several: its update from
    /// its share of the frame beside the other ropes as they stand.
    #[wasm_bindgen(js_name = explainRope)]
    pub fn explain_rope(
        &mut self,
        k: usize,
        frame: &DecodedFrame,
        depth_scale: f64,
        occlusions: &[f64],
    ) -> Result<JsValue, JsError> {
        let f = Frame::new(
            frame.width,
            frame.height,
            &frame.rgb,
            &frame.depth,
            depth_scale,
        )
        .map_err(js_err)?;
        let rects = rects_of(occlusions)?;
        let count = self.rope_count();
        let obs = self
            .ropes
            .observe_rope(k, &f, &rects)
            .map_err(js_err)?
            .ok_or_else(|| JsError::new(&format!("explainRope: rope {k} of {count}")))?;
        let tracker = &self.ropes.ropes()[k];
        let e = tracker.explain(&f, &obs);
        let camera = *tracker.camera();
        let params = tracker.params();
        let px = |points: &[Vec3]| project_all(&camera, points);
        let radius_px = e
            .previous
            .iter()
            .map(|y| (params.visibility_radius * camera.fx / y.z) as f32)
            .collect();
        let visible_nodes: Vec<usize> = (0..e.visible.len()).filter(|&m| e.visible[m]).collect();
        let em = e
            .step
            .as_ref()
            .map(|s| {
                s.em.iter()
                    .map(|it| {
                        let active: Vec<Vec3> =
                            visible_nodes.iter().map(|&m| it.nodes[m]).collect();
                        let mut view = EmView {
                            variance_mm2: it.variance * 1e6,
                            nodes_px: px(&it.nodes),
                            line_point: Vec::new(),
                            line_node: Vec::new(),
                            line_p: Vec::new(),
                        };
                        for (i, x) in obs.cloud.iter().enumerate() {
                            for (j, p) in responsibilities(x, &active, it.variance, it.outlier_term)
                            {
                                if p >= MIN_DRAWN_RESPONSIBILITY {
                                    view.line_point.push(i as u32);
                                    view.line_node.push(visible_nodes[j] as u32);
                                    view.line_p.push(p as f32);
                                }
                            }
                        }
                        view
                    })
                    .collect()
            })
            .unwrap_or_default();
        let status = match &e.output.status {
            upetrack::tracker::FrameStatus::Initialised => "initialised",
            upetrack::tracker::FrameStatus::Tracked => "tracked",
            upetrack::tracker::FrameStatus::Recovered(_) => "recovered",
            upetrack::tracker::FrameStatus::Lost(_) => "lost",
        };
        let empty: &[Vec3] = &[];
        let step = e.step.as_ref();
        let view = ExplainView {
            status: status.into(),
            mask_pixels: obs.mask.count(),
            deprojected_points: deproject_mask(&f, &obs.mask, &camera, &params.cloud()).len(),
            cloud_px: px(&obs.cloud),
            previous_px: px(&e.previous),
            radius_px,
            counts: e.neighbour_counts.iter().map(|&c| c as u32).collect(),
            visible: e.visible.clone(),
            visibility_min_points: params.visibility_min_points,
            em,
            registered_px: px(step.map_or(empty, |s| &s.registered)),
            forward_px: step.map_or_else(Vec::new, |s| optional_px(&camera, &s.sweeps.forward)),
            backward_px: step.map_or_else(Vec::new, |s| optional_px(&camera, &s.sweeps.backward)),
            slid_px: step.map_or_else(Vec::new, |s| optional_px(&camera, &s.sweeps.slid)),
            end_runs: step.map_or_else(Vec::new, |s| s.end_runs.clone()),
            estimated_px: px(step.map_or(empty, |s| &s.estimated)),
            before_resampling_px: px(step.map_or(empty, |s| &s.before_resampling)),
            resampled_px: px(step.map_or(empty, |s| &s.resampled)),
            output_px: px(&e.output.nodes),
            length_before_mm: step.map_or(f64::NAN, |s| length_mm(&s.before_resampling)),
            length_after_mm: step.map_or(f64::NAN, |s| length_mm(&s.resampled)),
            checks: e.output.judgement.as_ref().map(ChecksRecord::of),
            limits: CheckLimits {
                stretch: STRETCH_LIMIT,
                nodes_in_free_space: MIN_NODES_IN_FREE_SPACE,
                unexplained: UNEXPLAINED_LIMIT,
                unexplained_reach_mm: 1000.0 * UNEXPLAINED_REACH * params.visibility_radius,
            },
        };
        self.last_masks = None;
        self.last_obs = Some(obs);
        to_js(&view)
    }
}
