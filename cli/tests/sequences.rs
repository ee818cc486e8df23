//! Integration tests on synthetic sequences with ground truth: the written
//! sequence loads through the reader and matches its ground truth, and the
//! tracker follows the rope within bounds.

use std::path::PathBuf;

use upetrack::math::Vec3;
use upetrack::perception::segmentation::segment;
use upetrack::upe::bends::circle_through;
use upetrack::{Algorithm, Frame, Params, Tracker};
use upetrack_io::eval::{frame_errors, summarise};
use upetrack_io::run::track_sequence;
use upetrack_io::{FolderSource, Sequence};
use upetrack_synth::{RenderSettings, Scenario, ScenarioKind, SynthFrame, Variant};

mod common;
use common::scenes::{hidden_length_errors, max, mean, track_scenario, track_scenario_in};
use common::{run, synth};

fn temp_dir(name: &str) -> PathBuf {
    common::temp_dir("test", name)
}

#[test]
fn written_sequence_loads_and_matches_its_ground_truth() {
    let dir = temp_dir("gt");
    synth("dynamic-pull", 12, &dir);
    let seq = Sequence::open(FolderSource::new(&dir)).expect("sequence opens");
    assert_eq!(seq.len(), 12);
    assert_eq!(seq.occlusions_at(0).len(), 0);
    assert_eq!(seq.occlusions_at(11).len(), 1);
    let cam = seq.camera;
    for i in [0, 11] {
        let d = seq.frame(i).expect("frame decodes");
        let frame = d.frame(seq.depth_scale).expect("frame");
        let mask = segment(&frame, &seq.hsv, &[]);
        let gt = seq.groundtruth[i].as_ref().expect("ground truth");
        // The rope's length is kept by the simulation within 2 %.
        let len = upetrack::polyline::polyline_length(gt);
        assert!((len - 0.8).abs() < 0.016, "rope length {len}");
        let mut on_rope = 0;
        let mut depth_err = Vec::new();
        for p in gt {
            let q = cam.project(p).expect("in front");
            let (u, v) = (q.x.round() as i64, q.y.round() as i64);
            if mask.get(u, v) {
                on_rope += 1;
            }
            let k = (v * cam.width as i64 + u) as usize;
            let z = d.depth[k];
            if z > 0 {
                // The camera sees the top of the rope: one radius in front of the axis.
                let expected_mm = (p.z - 0.0075) * 1000.0;
                depth_err.push(z as f64 - expected_mm);
            }
        }
        // The projected centre line lies on rope pixels (JPEG and edges may miss a few).
        assert!(
            on_rope as f64 >= 0.95 * gt.len() as f64,
            "{on_rope} of {} on the rope",
            gt.len()
        );
        // Depth at those pixels: noise sigma about 1 mm at 0.6 m, plus the
        // cylinder's slope within a pixel; the median must be within 1.5 mm.
        depth_err.sort_by(f64::total_cmp);
        assert!(depth_err.len() > gt.len() / 2);
        let median = depth_err[depth_err.len() / 2];
        assert!(median.abs() < 1.5, "median depth error {median} mm");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn tracker_follows_a_fast_pull_and_a_dragged_rope_with_a_hidden_tip() {
    // (scenario, bound on the clear mean, bound on the occluded mean), mm:
    // 1.3-1.5x the figures docs/testing.md reports for these 60 frames
    // (fast-pull 3.22, no occluder; tip-drag 0.74 clear, 0.99 hidden).
    for (kind, clear_bound, occluded_bound) in [
        (ScenarioKind::FastPull, 4.2, None),
        (ScenarioKind::TipDrag, 1.1, Some(1.5)),
    ] {
        let (clear, occluded) = track_scenario(kind, 60, Params::default());
        assert_eq!(!occluded.is_empty(), occluded_bound.is_some(), "{kind:?}");
        let all: Vec<f64> = clear.iter().chain(&occluded).copied().collect();
        eprintln!(
            "{kind:?}: clear mean {:.2} mm, occluded mean {}, all frames max {:.2} mm",
            mean(&clear),
            if occluded.is_empty() {
                "-".to_string()
            } else {
                format!("{:.2}", mean(&occluded))
            },
            max(&all)
        );
        assert!(
            mean(&clear) < clear_bound,
            "{kind:?}: clear mean {:.2} mm",
            mean(&clear)
        );
        if let Some(bound) = occluded_bound {
            assert!(
                mean(&occluded) < bound,
                "{kind:?}: occluded mean {:.2} mm",
                mean(&occluded)
            );
        }
        // The tables' failure threshold: no frame above 20 mm.
        assert!(max(&all) < 20.0, "{kind:?}: max error {:.2} mm", max(&all));
    }
}

#[test]
fn track_command_writes_every_frame_of_the_contract() {
    let dir = temp_dir("cli");
    synth("static-s", 8, &dir);
    let out_json = dir.join("result.json");
    let out = run(&[
        "track",
        dir.to_str().expect("utf-8"),
        "--out",
        out_json.to_str().expect("utf-8"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&out_json).expect("result")).expect("json");
    assert_eq!(v["algorithm"], "upetrack");
    assert_eq!(v["params"]["node_count"], 24);
    let frames = v["frames"].as_array().expect("frames");
    assert_eq!(frames.len(), 8);
    for (i, f) in frames.iter().enumerate() {
        assert_eq!(f["frame"], i);
        assert_eq!(f["nodes"].as_array().expect("nodes").len(), 24);
        assert_eq!(f["visible"].as_array().expect("visible").len(), 24);
        assert!(f["track_ms"].as_f64().expect("track_ms") >= 0.0);
        assert!(
            f["total_ms"].as_f64().expect("total_ms") >= f["track_ms"].as_f64().expect("track_ms")
        );
    }
    // And the result evaluates against the ground truth.
    let seq = Sequence::open(FolderSource::new(&dir)).expect("open");
    let result = track_sequence(&seq, Params::default(), &mut || 0.0).expect("track");
    let errs = frame_errors(&result, &seq.groundtruth, &seq.camera);
    assert_eq!(errs.len(), 8);
    let s = summarise(
        "static-s",
        &result,
        &seq.groundtruth,
        &seq.camera,
        seq.first_occluded_frame(),
    );
    // docs/testing.md: 0.96 mm, 0.64 px on these 8 frames (seed 3).
    assert!(s.mm.mean < 1.45 && s.px.mean < 0.95, "{s:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_sequences_fail_with_the_file_named_and_a_nonzero_exit() {
    let dir = temp_dir("bad");
    synth("static-s", 3, &dir);
    // Truncate one depth frame.
    let depth = dir.join("depth/000001.png");
    let bytes = std::fs::read(&depth).expect("read");
    std::fs::write(&depth, &bytes[..bytes.len() / 2]).expect("write");
    let out = run(&["track", dir.to_str().expect("utf-8"), "--out", "/dev/null"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("000001.png"),
        "message does not name the file: {err}"
    );

    // Zero focal length.
    std::fs::write(
        dir.join("camera_intrinsic.json"),
        r#"{"width":640,"height":480,"intrinsic_matrix":[0,0,0,0,615,0,320,240,1]}"#,
    )
    .expect("write");
    let out = run(&["track", dir.to_str().expect("utf-8"), "--out", "/dev/null"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("camera_intrinsic.json") && err.contains("fx"),
        "{err}"
    );

    // Missing folder.
    let out = run(&["track", "/nonexistent/seq", "--out", "/dev/null"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/seq"));

    // Parameters out of range.
    let p = dir.join("params.json");
    std::fs::write(&p, r#"{"node_count": 2}"#).expect("write");
    let out = run(&[
        "eval",
        dir.to_str().expect("utf-8"),
        "--params",
        p.to_str().expect("utf-8"),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("node_count"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn tracker_never_panics_on_degenerate_frames() {
    let cam = upetrack::CameraIntrinsics::D435I_640X480;
    let mut s = Scenario::new(ScenarioKind::StaticS, 2, 1, RenderSettings::default());
    let good = s.next_frame().expect("frame");
    let mut tracker = Tracker::new(Params::default(), cam, s.hsv()).expect("tracker");
    let empty_rgb = vec![255u8; 640 * 480 * 3];
    let zero_depth = vec![0u16; 640 * 480];
    // Nothing in view before initialisation: lost, not a panic.
    let f = Frame::new(640, 480, &empty_rgb, &zero_depth, 0.001).expect("frame");
    assert!(tracker.process(&f, &[]).expect("ok").is_lost());
    // The rope, but all depth zero: cannot initialise (no depth).
    let f = Frame::new(640, 480, &good.rgb, &zero_depth, 0.001).expect("frame");
    assert!(tracker.process(&f, &[]).expect("ok").is_lost());
    // Good frame initialises.
    let f = Frame::new(640, 480, &good.rgb, &good.depth, 0.001).expect("frame");
    let out = tracker.process(&f, &[]).expect("ok");
    assert!(!out.is_lost());
    let before = out.nodes.clone();
    // Everything hidden (whole image occluded): lost, state held.
    let all = upetrack::Rect {
        x: 0,
        y: 0,
        w: 640,
        h: 480,
    };
    let out = tracker.process(&f, &[all]).expect("ok");
    assert!(out.is_lost());
    assert_eq!(out.nodes, before);
    // A single rope pixel with depth.
    let mut one = empty_rgb.clone();
    let k = 240 * 640 + 320;
    one[3 * k..3 * k + 3].copy_from_slice(&good.rgb[3 * k..3 * k + 3]);
    let f1 = Frame::new(640, 480, &one, &good.depth, 0.001).expect("frame");
    // Almost nothing in view: no node keeps its neighbours, the rope cannot
    // be found again, the frame is lost and the nodes are held.
    let out = tracker.process(&f1, &[]).expect("ok");
    assert!(out.is_lost(), "{:?}", out.status);
    assert_eq!(out.nodes, before);
    // Then the good frame again: tracking resumes near the rope.
    let out = tracker.process(&f, &[]).expect("ok");
    assert!(!out.is_lost(), "{:?}", out.status);
    let e = upetrack::metrics::frame_error(&out.nodes, &good.groundtruth).expect("error");
    assert!(e < 0.01, "after recovery {e}");
    assert!(out
        .nodes
        .iter()
        .all(|p: &Vec3| p.iter().all(|c| c.is_finite())));
    // Mismatched frame size is a typed error, not a panic.
    let small = Frame::new(2, 2, &[0; 12], &[0; 4], 0.001).expect("frame");
    assert!(tracker.process(&small, &[]).is_err());
}

/// Regression for the "hidden bend relaxes to a chord" gap: with the
/// relative visibility test (default 0.5), nodes at the occlusion's edge
/// count as hidden at once, and the paper's two scenarios are tracked
/// well within its accuracy (mean over occluded frames under 2 mm, 1.5x
/// docs/testing.md's figures) with the paper's r_vis = 20 mm and V_lim = 3.
#[test]
fn paper_scenarios_keep_the_hidden_bend_with_default_parameters() {
    for kind in [ScenarioKind::StaticS, ScenarioKind::DynamicPull] {
        let (clear, errors) = track_scenario(kind, 60, Params::default());
        assert!(
            self::mean(&clear) < 2.0,
            "{kind:?}: unoccluded mean {:.2} mm",
            self::mean(&clear)
        );
        let (mean, max) = (mean(&errors), max(&errors));
        eprintln!("{kind:?} defaults: occluded mean {mean:.2} max {max:.2} mm");
        assert!(mean < 2.0, "{kind:?}: occluded mean {mean:.2} mm");
        assert!(max < 20.0, "{kind:?}: occluded max {max:.2} mm");
    }
}

/// A rope at rest under an occluder: its hidden bend stayed put only once
/// the hidden nodes stopped following the known nodes' slide along the
/// rope under EM (`across_rope_displacement`) and resampling stopped cutting
/// the bend's corners (`smooth_resampling`). Either off, the bend creeps
/// and flattens (`docs/algorithm-notes.md`, "A resting hidden run").
#[test]
fn a_resting_hidden_bend_does_not_creep_along_the_rope_or_flatten() {
    let occluded = |across, smooth| {
        let mut params = Params::default();
        params.upetrack.across_rope_displacement = across;
        params.upetrack.smooth_resampling = smooth;
        mean(&track_scenario(ScenarioKind::StaticS, 60, params).1)
    };
    let (both, no_across, no_smooth) = (
        occluded(true, true),
        occluded(false, true),
        occluded(true, false),
    );
    eprintln!("static-s occluded mean: defaults {both:.2}, D_k along too {no_across:.2}, polyline resampling {no_smooth:.2} mm");
    assert!(both < 1.25, "defaults: {both:.2} mm");
    assert!(
        both < 0.8 * no_across && both < 0.95 * no_smooth,
        "{both:.2} vs {no_across:.2} / {no_smooth:.2} mm"
    );
}

/// The paper's claim on its two scenarios, on the shared pipeline: UPETrack's
/// mean error over the occluded frames is below both baselines'.
#[test]
fn upetrack_beats_both_baselines_under_occlusion_on_the_paper_scenarios() {
    for kind in [ScenarioKind::StaticS, ScenarioKind::DynamicPull] {
        let occluded_mean = |algorithm| {
            let params = Params {
                algorithm,
                ..Params::default()
            };
            mean(&track_scenario(kind, 60, params).1)
        };
        let ours = occluded_mean(Algorithm::Upetrack);
        let cpd = occluded_mean(Algorithm::Cpd);
        let trackdlo = occluded_mean(Algorithm::Trackdlo);
        eprintln!(
            "{kind:?}: occluded mean upetrack {ours:.2}, cpd {cpd:.2}, trackdlo {trackdlo:.2} mm"
        );
        assert!(
            ours < cpd && ours < trackdlo,
            "{kind:?}: {ours:.2} vs {cpd:.2} / {trackdlo:.2}"
        );
    }
}

#[test]
fn algorithm_option_names_the_algorithm_and_eval_tables_every_pair() {
    let dir = temp_dir("algorithms");
    synth("static-s", 6, &dir);
    let seq = dir.to_string_lossy().to_string();
    let out = dir.join("trackdlo.json");
    let track = |algorithm: &str| {
        run(&[
            "track",
            &seq,
            "--algorithm",
            algorithm,
            "--out",
            &out.to_string_lossy(),
        ])
    };
    let o = track("trackdlo");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).expect("result")).expect("json");
    assert_eq!(v["algorithm"], "trackdlo");
    assert_eq!(v["params"]["algorithm"], "trackdlo");
    assert_eq!(v["frames"].as_array().map(Vec::len), Some(6));

    let o = track("gltp");
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("invalid value 'gltp'") && err.contains("cdcpd2"),
        "{err}"
    );

    let json = dir.join("eval.json");
    let o = run(&[
        "eval",
        &seq,
        "--algorithm",
        "upetrack,cpd,trackdlo",
        "--json",
        &json.to_string_lossy(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("eval")).expect("json");
    let names: Vec<&str> = rows
        .as_array()
        .expect("rows")
        .iter()
        .map(|r| r["algorithm"].as_str().expect("name"))
        .collect();
    assert_eq!(names, ["upetrack", "cpd", "trackdlo"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn compare_writes_both_tables_into_a_page_between_its_markers() {
    let dir = temp_dir("compare");
    std::fs::create_dir_all(&dir).expect("dir");
    let page = dir.join("results.md");
    std::fs::write(
        &page,
        "# Results\n\nbefore\n<!-- compare:begin -->\nold tables\n<!-- compare:end -->\nafter\n",
    )
    .expect("page");
    let data = dir.join("data");
    let compare = || {
        run(&[
            "compare",
            "--frames",
            "12",
            "--data",
            &data.to_string_lossy(),
            "--update",
            &page.to_string_lossy(),
        ])
    };
    let o = compare();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&page).expect("page");
    assert!(text.starts_with("# Results\n\nbefore\n<!-- compare:begin -->\n"));
    assert!(text.ends_with("<!-- compare:end -->\nafter\n"));
    assert!(!text.contains("old tables"));
    for needle in [
        "| static-s | trackdlo |",
        "| sweep-50 | cpd |",
        "| 30 % |",
        "every scenario at 12 frames",
    ] {
        assert!(text.contains(needle), "missing {needle}");
    }
    // Regression: a cached sequence from another simulator was reused. A
    // stale fingerprint makes the command write that sequence again.
    let cached = data.join("static-s-12f-seed1");
    let print = cached.join("synth-fingerprint.txt");
    assert!(print.is_file(), "no fingerprint beside the cached sequence");
    std::fs::write(&print, "simulator 0, first frame 0\n").expect("stale");
    std::fs::write(cached.join("color/000000.jpg"), b"stale").expect("stale frame");
    let o = compare();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("written by another simulator"));
    assert_ne!(
        std::fs::read(cached.join("color/000000.jpg")).expect("frame"),
        b"stale"
    );
    // Without the markers the page is left alone and the command fails.
    std::fs::write(&page, "no markers\n").expect("page");
    assert!(!compare().status.success());
    assert_eq!(
        std::fs::read_to_string(&page).expect("page"),
        "no markers\n"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Regression for "a hidden tip straightens" (TrackDLO's protocol, 30 % of
/// the rope hidden from one end while the other end is pulled): with the
/// defaults (the hidden tip slides along its curve with the rope) it stays
/// on the rope; with the paper's rules it straightens out of the occluder.
#[test]
fn a_hidden_tip_moves_with_the_pulled_rope_instead_of_straightening() {
    let kind = ScenarioKind::OcclusionSweep { percent: 30 };
    let ours = mean(&track_scenario(kind, 60, Params::default()).1);
    let papers = mean(&track_scenario(kind, 60, Params::paper()).1);
    eprintln!(
        "sweep-30: occluded mean {ours:.2} mm (defaults), {papers:.2} mm (the paper's rules)"
    );
    // docs/testing.md: 0.90 mm with the defaults on these 60 frames.
    assert!(ours < 1.35, "occluded mean {ours:.2} mm");
    assert!(ours < 0.5 * papers, "{ours:.2} vs {papers:.2}");
}

/// The image of `f` moved right by `dx` pixels (the rope jumped).
fn shifted(rgb: &[u8], depth: &[u16], dx: usize) -> (Vec<u8>, Vec<u16>) {
    let (w, h) = (640, 480);
    let mut rgb2 = vec![200u8; w * h * 3];
    let mut depth2 = vec![0u16; w * h];
    for y in 0..h {
        for x in dx..w {
            let (from, to) = (y * w + x - dx, y * w + x);
            rgb2[3 * to..3 * to + 3].copy_from_slice(&rgb[3 * from..3 * from + 3]);
            depth2[to] = depth[from];
        }
    }
    (rgb2, depth2)
}

/// A jump: frame 0 of static-s (seed 1), its image moved right by `dx`
/// pixels, and the scene (for its camera and colour range).
fn a_rope_and_its_jump(dx: usize) -> (Scenario, SynthFrame, Vec<u8>, Vec<u16>) {
    let mut s = Scenario::new(ScenarioKind::StaticS, 2, 1, RenderSettings::default());
    let f = s.next_frame().expect("frame");
    let (rgb2, depth2) = shifted(&f.rgb, &f.depth, dx);
    (s, f, rgb2, depth2)
}

/// `reinit_visible_fraction`: when fewer than that fraction of the nodes
/// keep points nearby but a full-length rope is in view, the tracker starts
/// again from it; 0 turns the rule off and the step tracks on.
#[test]
fn a_jumped_rope_re_initialises_when_few_nodes_stay_visible() {
    let (s, f, rgb2, depth2) = a_rope_and_its_jump(30);
    let a = Frame::new(640, 480, &f.rgb, &f.depth, 0.001).expect("frame");
    let b = Frame::new(640, 480, &rgb2, &depth2, 0.001).expect("frame");
    let mut statuses = Vec::new();
    for fraction in [0.5, 0.0] {
        let p = Params {
            reinit_visible_fraction: fraction,
            ..Params::default()
        };
        let mut t = Tracker::new(p, s.camera(), s.hsv()).expect("tracker");
        assert!(!t.process(&a, &[]).expect("a").is_lost());
        let obs = t.observe(&b, &[]).expect("observe");
        let visible = upetrack::visibility::visible_nodes_relative(
            t.nodes(),
            &obs.cloud,
            p.visibility_radius,
            p.visibility_min_points as usize,
            p.visibility_min_fraction,
        );
        let seen = visible.iter().filter(|&&v| v).count();
        let out = t.update(&b, &obs);
        eprintln!(
            "fraction {fraction}: {seen} of 24 visible after the jump, {:?}",
            out.status
        );
        assert!(
            seen > 0 && seen < 12,
            "{seen} visible: not the case under test"
        );
        statuses.push(out.status);
    }
    assert_eq!(statuses[0], upetrack::tracker::FrameStatus::Initialised);
    assert_eq!(statuses[1], upetrack::tracker::FrameStatus::Tracked);
}

/// Mean distance of the end nodes to the rope's tips over frames 5-29 of
/// static-s (all in view), millimetres.
fn end_node_error(params: Params) -> f64 {
    let mut s = Scenario::new(ScenarioKind::StaticS, 30, 1, RenderSettings::default());
    let camera = s.camera();
    let mut t = Tracker::new(params, camera, s.hsv()).expect("tracker");
    let (mut sum, mut n) = (0.0, 0);
    while let Some(f) = s.next_frame() {
        let frame =
            Frame::new(camera.width, camera.height, &f.rgb, &f.depth, 0.001).expect("frame");
        let out = t.process(&frame, &[]).expect("process");
        if f.index < 5 {
            continue;
        }
        let (a, b) = (out.nodes[0], out.nodes[out.nodes.len() - 1]);
        let (g0, g1) = (f.groundtruth[0], f.groundtruth[f.groundtruth.len() - 1]);
        // Either way round: the tracker orders its nodes by image x.
        sum += ((a - g0).norm() + (b - g1).norm()).min((a - g1).norm() + (b - g0).norm());
        n += 2;
    }
    1000.0 * sum / n as f64
}

/// Regression for "EM draws the end nodes in": each end node sat at the
/// middle of the points nearest it, about a third of a spacing short of
/// the tip, and the tracked rope was 3 % short (static-s 0.777 m against
/// 0.800) before anything was hidden; `extend_short_ends` gives the
/// length back over the rope's pixels. The reported tips
/// (`report_seen_tips`, `cli/tests/ends.rs`) are off in both runs: this
/// pins the state's own extension.
#[test]
fn the_end_nodes_reach_the_rope_s_tips() {
    let mut state = Params::default();
    state.upetrack.report_seen_tips = false;
    let ours = end_node_error(state);
    let mut off = state;
    off.upetrack.extend_short_ends = false;
    let before = end_node_error(off);
    eprintln!("end nodes to the tips: {ours:.2} mm, {before:.2} mm without the rule");
    assert!(ours < 4.0, "{ours:.2} mm");
    assert!(ours < 0.5 * before, "{ours:.2} vs {before:.2} mm");
}

/// `JUMP_RETRY_GROWTH`: a refused jump re-initialisation (the rope jumped
/// but most of it is hidden, so too short to start from) is not attempted
/// again every frame, which cost a whole initialisation each (sweep-50@hd
/// 1.08 ms a step against 0.09 without); once the rope comes back into view
/// the cloud grows and the attempt is made, and succeeds.
#[test]
fn a_refused_jump_re_initialisation_is_retried_only_once_the_cloud_grows() {
    let (s, f, rgb2, depth2) = a_rope_and_its_jump(30);
    let a = Frame::new(640, 480, &f.rgb, &f.depth, 0.001).expect("frame");
    let b = Frame::new(640, 480, &rgb2, &depth2, 0.001).expect("frame");
    // The left two thirds of the image hidden: most of the rope.
    let hide = [upetrack::Rect {
        x: 0,
        y: 0,
        w: 430,
        h: 480,
    }];
    let refused = |t: &Tracker| {
        serde_json::to_value(t.snapshot()).expect("snapshot")["refused_jump_cloud"].clone()
    };
    let mut t = Tracker::new(Params::default(), s.camera(), s.hsv()).expect("tracker");
    assert!(!t.process(&a, &[]).expect("a").is_lost());
    let first = t.process(&b, &hide).expect("b hidden");
    assert_eq!(first.status, upetrack::tracker::FrameStatus::Tracked);
    let at = refused(&t);
    assert!(at.as_u64().is_some_and(|n| n > 0), "refused at {at}");
    // A little more hidden: no new attempt (it would record the smaller
    // cloud), the refusal stands.
    let more = [upetrack::Rect { w: 440, ..hide[0] }];
    let again = t.process(&b, &more).expect("b hidden again");
    assert_eq!(again.status, upetrack::tracker::FrameStatus::Tracked);
    assert_eq!(refused(&t), at);
    // The rope jumps again, and all of it is in view: more points, tried,
    // accepted.
    let (rgb3, depth3) = shifted(&f.rgb, &f.depth, 90);
    let c = Frame::new(640, 480, &rgb3, &depth3, 0.001).expect("frame");
    let seen = t.process(&c, &[]).expect("c");
    assert_eq!(seen.status, upetrack::tracker::FrameStatus::Initialised);
    assert!(refused(&t).is_null());
}

/// A state the images contradict is dropped: with the jump rule off
/// (`reinit_visible_fraction` 0) a rope moved 6 cm leaves most of the cloud
/// far from every node after the step, and the tracker finds the rope
/// again, reporting the frame as recovered.
#[test]
fn a_state_far_from_the_rope_in_view_is_recovered_from_the_images() {
    let (s, f, rgb2, depth2) = a_rope_and_its_jump(60);
    let a = Frame::new(640, 480, &f.rgb, &f.depth, 0.001).expect("frame");
    let b = Frame::new(640, 480, &rgb2, &depth2, 0.001).expect("frame");
    let p = Params {
        reinit_visible_fraction: 0.0,
        ..Params::default()
    };
    let mut t = Tracker::new(p, s.camera(), s.hsv()).expect("tracker");
    assert!(!t.process(&a, &[]).expect("a").is_lost());
    let out = t.process(&b, &[]).expect("b");
    let upetrack::tracker::FrameStatus::Recovered(against) = out.status else {
        panic!("not recovered: {:?}", out.status);
    };
    // The nodes left where the rope was explain none of it where it is.
    assert_eq!(
        against.fired().collect::<Vec<_>>(),
        ["unexplained"],
        "{against:?}"
    );
    // The nodes are on the moved rope: the truth moved by 60 px at 0.6 m.
    let dx = 60.0 * f.groundtruth[0].z / 615.0;
    let moved: Vec<Vec3> = f
        .groundtruth
        .iter()
        .map(|p| p + Vec3::new(dx, 0.0, 0.0))
        .collect();
    let e = upetrack::metrics::frame_error(&out.nodes, &moved).expect("error");
    assert!(e < 0.006, "{e}");
}

/// Regression for "the gripper's fingers hide the held end and the hidden
/// end nodes run off along its arm": seen by a tilted 1280x720 camera, the
/// hidden end stays at the rope's length and out of free space.
#[test]
fn a_gripper_hiding_the_held_end_does_not_drag_it_off_along_its_arm() {
    let v = Variant::parse("hd-tilted-red").expect("variant");
    let (_, ours) = track_scenario_in(ScenarioKind::GripperSwing, v, 90, Params::default());
    // The rules before the fix: hidden ends carried by Eq. 6-7 alone (with
    // the paper's D_k, which hands EM's slide along the arm to the hidden
    // end), no length cap, no free-space check, polyline resampling, EM's
    // whole move of the anchors, hidden nodes out of EM, a fixed alpha, and
    // the voxel grid's cloud the issue was reported with.
    let mut before = Params {
        downsampling: upetrack::perception::point_cloud::Downsampling::VoxelGrid,
        ..Params::default()
    };
    before.upetrack.hidden_motion = upetrack::upe::occlusion::HiddenMotion::Paper;
    before.upetrack.conserve_length = false;
    before.upetrack.free_space = false;
    before.upetrack.across_rope_displacement = false;
    before.upetrack.smooth_resampling = false;
    before.upetrack.anchor_across_only = false;
    before.upetrack.hidden_nodes_absorb = false;
    before.upetrack.rest_speed_m_per_s = 0.0;
    let (_, theirs) = track_scenario_in(ScenarioKind::GripperSwing, v, 90, before);
    eprintln!(
        "gripper@hd-tilted-red: occluded mean {:.2} mm, max {:.2} mm; before the fix {:.2} mm, max {:.2} mm",
        mean(&ours),
        max(&ours),
        mean(&theirs),
        max(&theirs)
    );
    assert!(max(&ours) < 20.0, "max {:.2} mm", max(&ours));
    // 2.77 mm since the visible end goes on under the gripper along its
    // tangent (the held end turns into the jaws; `extend_under_occluders`),
    // against 1.78 before: the price of keeping the hidden length.
    assert!(mean(&ours) < 3.6, "occluded mean {:.2} mm", mean(&ours));
    assert!(
        mean(&ours) < 0.7 * mean(&theirs),
        "{:.2} vs {:.2}",
        mean(&ours),
        mean(&theirs)
    );
}

/// Regression for "the gripper's hidden end is 5-8 % short": about 4 cm
/// of the held end lies in the gripper's jaws with no rope pixel, so the
/// tracked rope was that much short, and resampling the whole rope evenly
/// took the same share from every hidden run (gripper-swing 5.5 %,
/// @hd-tilted-red 7.9 %). The visible end now goes on under the gripper
/// (`extend_under_occluders`) and the hidden ends keep the rest spacing
/// (`keep_end_run_spacing`).
#[test]
fn a_held_end_hidden_in_the_gripper_keeps_its_length() {
    let kind = ScenarioKind::GripperSwing;
    let ours = hidden_length_errors(kind, Variant::BASE, 90, Params::default());
    let mut before = Params::default();
    before.upetrack.extend_under_occluders = false;
    before.upetrack.keep_end_run_spacing = false;
    let theirs = hidden_length_errors(kind, Variant::BASE, 90, before);
    eprintln!(
        "gripper-swing: worst hidden-run length error {:.1} %, {:.1} % before ({} / {} frames)",
        100.0 * max(&ours),
        100.0 * max(&theirs),
        ours.len(),
        theirs.len()
    );
    assert!(ours.len() > 30, "{} frames with a hidden run", ours.len());
    assert!(max(&ours) < 0.025, "{:.1} %", 100.0 * max(&ours));
    assert!(max(&theirs) > 0.05, "{:.1} %", 100.0 * max(&theirs));
}

/// Regression for "50 % of the rope hidden (TrackDLO's protocol)": the
/// hidden half slides with the rope instead of straightening or translating.
#[test]
fn half_the_rope_hidden_stays_on_the_rope() {
    let kind = ScenarioKind::OcclusionSweep { percent: 50 };
    let (_, ours) = track_scenario(kind, 60, Params::default());
    let (_, papers) = track_scenario(kind, 60, Params::paper());
    eprintln!(
        "sweep-50: occluded mean {:.2} mm, the paper's rules {:.2} mm",
        mean(&ours),
        mean(&papers)
    );
    assert!(mean(&ours) < 1.55, "occluded mean {:.2} mm", mean(&ours));
    assert!(max(&ours) < 20.0, "max {:.2} mm", max(&ours));
    assert!(mean(&ours) < 0.7 * mean(&papers));
}

/// Regression for "the nodes sit behind the rope's axis": the voxel grid
/// put the cloud 1-2 mm too deep (cubes cut by the silhouette hold only
/// the far side), so every visible node sat 1.6-1.8 mm behind the axis;
/// the ray columns keep each point at its pixels' mean depth.
#[test]
fn visible_nodes_sit_on_the_axis_not_behind_it() {
    let clear = |downsampling| {
        let p = Params {
            downsampling,
            ..Params::default()
        };
        mean(&track_scenario(ScenarioKind::StaticS, 30, p).0)
    };
    use upetrack::perception::point_cloud::Downsampling;
    let (columns, voxels) = (
        clear(Downsampling::RayColumns),
        clear(Downsampling::VoxelGrid),
    );
    eprintln!(
        "static-s before the occlusion: ray columns {columns:.2} mm, voxel grid {voxels:.2} mm"
    );
    assert!(columns < 0.6 * voxels, "{columns:.2} vs {voxels:.2} mm");
}

/// Regression for "3D error 4 mm with a 0.7 px image error" on thin ropes:
/// the radius is measured, so a 6 mm cable is pushed to its own axis.
#[test]
fn a_thin_cable_is_placed_on_its_axis_in_depth() {
    let v = Variant::parse("near-thin-green").expect("variant");
    let (clear, _) = track_scenario_in(ScenarioKind::TipDrag, v, 30, Params::default());
    let fixed = Params {
        estimate_radius: false,
        ..Params::default()
    };
    let (clear_fixed, _) = track_scenario_in(ScenarioKind::TipDrag, v, 30, fixed);
    eprintln!(
        "thin cable: {:.2} mm measured radius, {:.2} mm with the 7.5 mm default",
        mean(&clear),
        mean(&clear_fixed)
    );
    assert!(mean(&clear) < 0.6, "{:.2} mm", mean(&clear));
    assert!(mean(&clear) < 0.5 * mean(&clear_fixed));
}

/// Mean offset (mm) of the reported visible nodes towards the centre of
/// the true rope's bend, over the nodes with both neighbours visible on
/// bends tighter than `max_radius`: the true curve's circle through its
/// points a node spacing apart around the node's nearest truth point.
fn inward_offset_on_bends(
    kind: ScenarioKind,
    frames: usize,
    params: Params,
    max_radius: f64,
) -> f64 {
    let mut offsets = Vec::new();
    common::scenes::each_frame(kind, Variant::BASE, frames, params, |f, out, _| {
        let truth = &f.groundtruth;
        let n = &out.nodes;
        let spacing = upetrack::polyline::polyline_length(n) / (n.len() - 1) as f64;
        let step =
            (spacing / upetrack::polyline::polyline_length(truth) * truth.len() as f64) as usize;
        for i in 1..n.len() - 1 {
            if !(out.visible[i - 1] && out.visible[i] && out.visible[i + 1]) {
                continue;
            }
            let j = (0..truth.len())
                .min_by(|&a, &b| {
                    (truth[a] - n[i])
                        .norm()
                        .total_cmp(&(truth[b] - n[i]).norm())
                })
                .expect("truth");
            if j < step || j + step >= truth.len() {
                continue;
            }
            let b = truth[j];
            let Some((centre, radius)) = circle_through(&truth[j - step], &b, &truth[j + step])
            else {
                continue;
            };
            if radius > max_radius {
                continue;
            }
            let inward: Vec3 = (centre - b) / radius;
            offsets.push((n[i] - b).dot(&inward) * 1000.0);
        }
    });
    mean(&offsets)
}

/// Regression for "visible nodes sit inside every bend" (randomised tuning
/// range: 1.7 mm on bends under 3 cm, 1.0 mm on 3-6 cm, 0.7 mm on 6-12 cm):
/// EM places a node at the centroid of the arc of rope it explains, which
/// lies inside the bend; the reported nodes are moved back onto the arc
/// (`report_on_arcs`).
#[test]
fn visible_nodes_on_a_bend_are_reported_on_it_not_inside() {
    let on = inward_offset_on_bends(ScenarioKind::StaticS, 20, Params::default(), 0.08);
    let mut params = Params::default();
    params.upetrack.report_on_arcs = false;
    let off = inward_offset_on_bends(ScenarioKind::StaticS, 20, params, 0.08);
    eprintln!("static-s, bends under 8 cm: {on:.2} mm inside with the readout, {off:.2} without");
    assert!(off > 0.4, "{off:.2}");
    assert!(on.abs() < 0.5 * off, "{on:.2} of {off:.2}");
}
