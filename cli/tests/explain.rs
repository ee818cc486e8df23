//! The explain mode's account of a frame is the frame's own update: the
//! same nodes (the state, and what the frame reports of it), every EM
//! iteration, the hidden nodes left where EM found them and placed by the
//! sweeps.

use upetrack::tracker::{FrameStatus, Verdict};
use upetrack::{Frame, Params, Tracker};
use upetrack_synth::{RenderSettings, Scenario, ScenarioKind};

#[test]
fn an_explained_frame_is_the_update_itself_stage_by_stage() {
    let mut s = Scenario::new(ScenarioKind::DynamicPull, 30, 2, RenderSettings::default());
    let camera = s.camera();
    let mut tracker = Tracker::new(Params::default(), camera, s.hsv()).expect("tracker");
    let (mut stepped, mut with_hidden, mut tips) = (0, 0, 0);
    while let Some(f) = s.next_frame() {
        let frame =
            Frame::new(camera.width, camera.height, &f.rgb, &f.depth, 0.001).expect("frame");
        let rects = s.occlusions_at(f.index);
        let obs = tracker.observe(&frame, &rects).expect("observe");
        let e = tracker.explain(&frame, &obs);
        let out = tracker.update(&frame, &obs);
        assert_eq!(e.output.nodes, out.nodes, "frame {}", f.index);
        assert_eq!(e.output.status, out.status);
        assert_eq!(e.output.judgement, out.judgement);
        if out.status != FrameStatus::Tracked {
            continue;
        }
        let Some(step) = &e.step else {
            assert!(
                f.index == 0 || e.previous.is_empty(),
                "frame {} not explained",
                f.index
            );
            continue;
        };
        stepped += 1;
        // The step's last stage is the state; the frame reports it with
        // its visible nodes on their bends (`report_on_arcs`) and its end
        // nodes in view carried out along the state's end tangents to the
        // rope's tips (`report_seen_tips`).
        let mut reported = step.resampled.clone();
        upetrack::upe::bends::onto_arcs(&mut reported, &out.visible);
        let m = reported.len();
        assert_eq!(reported[1..m - 1], out.nodes[1..m - 1], "frame {}", f.index);
        for (end, inner) in [(0, 1), (m - 1, m - 2)] {
            if reported[end] == out.nodes[end] {
                continue;
            }
            assert!(
                out.visible[end],
                "frame {}: hidden end {end} moved",
                f.index
            );
            let state = step.resampled[end];
            let tangent = (state - step.resampled[inner]).normalize();
            let moved = out.nodes[end] - state;
            let along = moved.dot(&tangent);
            assert!(
                along > 0.0 && (moved - tangent * along).norm() < 1e-9,
                "frame {}: end {end} moved {moved:?}",
                f.index
            );
            tips += 1;
        }
        assert_ne!(
            step.resampled, out.nodes,
            "frame {}: nothing on a bend",
            f.index
        );
        let em = out.em.expect("UPETrack's EM report");
        assert_eq!(step.em.len(), em.iterations as usize);
        assert_eq!(
            step.em[0].nodes, e.previous,
            "EM starts from the previous nodes"
        );
        assert!(step
            .em
            .iter()
            .all(|it| it.variance > 0.0 && it.outlier_term > 0.0));
        assert_eq!(e.neighbour_counts.len(), e.previous.len());
        let hidden: Vec<usize> = (0..e.visible.len()).filter(|&m| !e.visible[m]).collect();
        for &m in &hidden {
            assert_eq!(
                step.registered[m], e.previous[m],
                "EM leaves hidden node {m}"
            );
            let placed = step.sweeps.forward[m]
                .or(step.sweeps.backward[m])
                .or(step.sweeps.slid[m]);
            assert!(
                placed.is_some(),
                "frame {} hidden node {m} placed by nothing",
                f.index
            );
        }
        if !hidden.is_empty() {
            with_hidden += 1;
        }
    }
    assert!(
        stepped >= 25 && with_hidden >= 10 && tips > 0,
        "{stepped} frames stepped, {with_hidden} with hidden nodes, {tips} ends carried to their tips"
    );
}

/// A frame whose step contradicted the images and was replaced by the rope
/// found again (drawn tuning scene 1032, frame 21) is explained with the
/// step that ran and the recovery tests that read it, not as a frame
/// without a step.
#[test]
fn a_frame_recovered_after_its_step_is_explained_with_the_step_and_its_tests() {
    let mut s = Scenario::random(1032, 48);
    let camera = s.camera();
    let mut tracker = Tracker::new(Params::default(), camera, s.hsv()).expect("tracker");
    tracker.set_frame_rate(s.fps()).expect("frame rate");
    let mut recovered = None;
    while let Some(f) = s.next_frame() {
        let frame =
            Frame::new(camera.width, camera.height, &f.rgb, &f.depth, 0.001).expect("frame");
        let obs = tracker
            .observe(&frame, &s.occlusions_at(f.index))
            .expect("observe");
        let e = tracker.explain(&frame, &obs);
        let out = tracker.update(&frame, &obs);
        assert_eq!(e.output.nodes, out.nodes, "frame {}", f.index);
        if matches!(out.status, FrameStatus::Recovered(_)) {
            recovered = Some((f.index, e));
            break;
        }
    }
    let (index, e) = recovered.expect("no frame recovered");
    let judgement = e.output.judgement.expect("the recovery tests' reading");
    assert_eq!(judgement.verdict, Verdict::Recovered, "frame {index}");
    assert!(judgement.measured.contradicts(), "frame {index}");
    let step = e.step.expect("the step that ran");
    assert_eq!(step.em[0].nodes, e.previous, "frame {index}");
    assert_ne!(
        step.resampled, e.output.nodes,
        "frame {index}: the state was replaced"
    );
}
