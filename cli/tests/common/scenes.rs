//! Scenarios tracked in memory from the simulator, and the statistics the
//! accuracy tests bound.

use upetrack::tracker::FrameOutput;
use upetrack::{Frame, Params, Tracker};
use upetrack_synth::{Scenario, ScenarioKind, SynthFrame, Variant};

/// Frame errors (mm) of a scenario tracked in memory from the simulator (no
/// JPEG round trip), split into frames before and from the first occlusion.
pub fn track_scenario(kind: ScenarioKind, frames: usize, params: Params) -> (Vec<f64>, Vec<f64>) {
    track_scenario_in(kind, Variant::BASE, frames, params)
}

/// [`track_scenario`] in a scene variant; frames count as occluded from the
/// first with a rectangle or with ground truth hidden by an occluder.
pub fn track_scenario_in(
    kind: ScenarioKind,
    variant: Variant,
    frames: usize,
    params: Params,
) -> (Vec<f64>, Vec<f64>) {
    let (mut clear, mut occluded) = (Vec::new(), Vec::new());
    each_frame(kind, variant, frames, params, |f, out, is_occluded| {
        let e = upetrack::metrics::frame_error(&out.nodes, &f.groundtruth).expect("error") * 1000.0;
        if is_occluded {
            occluded.push(e);
        } else {
            clear.push(e);
        }
    });
    (clear, occluded)
}

/// The worst hidden run's length error of each frame with a hidden run
/// (`upetrack_io::eval::hidden_length_error`: against the true rope's
/// length for as many node spacings; 0.05 = 5 %).
pub fn hidden_length_errors(
    kind: ScenarioKind,
    variant: Variant,
    frames: usize,
    params: Params,
) -> Vec<f64> {
    let mut errors = Vec::new();
    each_frame(kind, variant, frames, params, |f, out, _| {
        let truth = upetrack::polyline::polyline_length(&f.groundtruth);
        errors.extend(upetrack_io::eval::hidden_length_error(
            &out.nodes,
            &out.visible,
            truth,
        ));
    });
    errors
}

/// Tracks a scenario in memory, handing each frame, its output and whether
/// it counts as occluded to `on`; a lost frame fails the test.
pub fn each_frame(
    kind: ScenarioKind,
    variant: Variant,
    frames: usize,
    params: Params,
    on: impl FnMut(&SynthFrame, &FrameOutput, bool),
) {
    let s = Scenario::with_rope(kind, frames, 4, variant.render(), variant.rope());
    each_frame_of(s, params, on);
}

/// [`each_frame`] of any scenario (a drawn one, say).
pub fn each_frame_of(
    mut s: Scenario,
    params: Params,
    mut on: impl FnMut(&SynthFrame, &FrameOutput, bool),
) {
    let name = s.name.clone();
    let camera = s.camera();
    let mut tracker = Tracker::new(params, s.camera(), s.hsv()).expect("tracker");
    let occlusions = s.occlusions.clone();
    let mut first_occluded = occlusions.first().map(|o| o.first);
    while let Some(f) = s.next_frame() {
        if first_occluded.is_none() && f.occluded.iter().any(|&o| o) {
            first_occluded = Some(f.index);
        }
        let frame =
            Frame::new(camera.width, camera.height, &f.rgb, &f.depth, 0.001).expect("frame");
        let rects = s.occlusions_at(f.index);
        let out = tracker.process(&frame, &rects).expect("process");
        assert!(
            !out.is_lost(),
            "{name} frame {} lost: {:?}",
            f.index,
            out.status
        );
        on(&f, &out, first_occluded.is_some_and(|o| f.index >= o));
    }
}

/// Mean of a series that must have frames and finite errors (an empty
/// series or a NaN would otherwise pass any bound).
pub fn mean(v: &[f64]) -> f64 {
    assert!(!v.is_empty(), "no frames in the series");
    assert!(v.iter().all(|e| e.is_finite()), "non-finite error in {v:?}");
    v.iter().sum::<f64>() / v.len() as f64
}

/// Largest of a series, under the same conditions as [`mean`].
pub fn max(v: &[f64]) -> f64 {
    assert!(!v.is_empty(), "no frames in the series");
    assert!(v.iter().all(|e| e.is_finite()), "non-finite error in {v:?}");
    v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
}
