//! Finding the rope where users have it (issue 27): a thin black cable
//! beside a phone, a pen and a USB stick that pass the same colour range; a
//! rope in a loop crossing itself; a rope cut into pieces by two strips
//! lying across it. On each, the whole rope is found on the first frame
//! (its centre line within 5 % of the true length) and tracked without a
//! frame above 20 mm, by UPETrack and by the baselines that share the
//! initialisation; a scene with nothing rope-shaped is refused; a tracker
//! that lost the rope finds it again though part of it is hidden.

use upetrack::perception::initialisation::Candidate;
use upetrack::polyline::polyline_length;
use upetrack::{Algorithm, Frame, Params, Tracker};
use upetrack_synth::{RenderSettings, Scenario, ScenarioKind, Variant};

mod common;
use common::scenes::{each_frame, max, mean};
use common::{each_tracked_frame, frame_errors, run, written_drawn_scene};

/// The candidate taken on the first frame, the true length there, and
/// every frame's error in millimetres.
fn found_and_tracked(
    kind: ScenarioKind,
    variant: Variant,
    frames: usize,
    algorithm: Algorithm,
) -> (Candidate, f64, Vec<f64>) {
    let params = Params {
        algorithm,
        ..Params::default()
    };
    let mut first = None;
    let mut errors = Vec::new();
    each_frame(kind, variant, frames, params, |f, out, _| {
        if f.index == 0 {
            let init = out.init.as_ref().expect("the first frame initialises");
            first = Some((
                init.candidates[init.chosen],
                polyline_length(&f.groundtruth),
            ));
        }
        errors.push(
            upetrack::metrics::frame_error(&out.nodes, &f.groundtruth).expect("error") * 1000.0,
        );
    });
    let (candidate, truth) = first.expect("a first frame");
    (candidate, truth, errors)
}

fn assert_whole(kind: ScenarioKind, c: &Candidate, truth: f64) {
    assert!(
        (c.length / truth - 1.0).abs() < 0.05,
        "{kind:?}: centre line {:.3} m of {truth:.3} m: {c:?}",
        c.length
    );
}

#[test]
fn a_black_cable_beside_a_phone_is_found_and_tracked() {
    let kind = ScenarioKind::CableDesk;
    for algorithm in [Algorithm::Upetrack, Algorithm::Cpd, Algorithm::Trackdlo] {
        let (c, truth, errors) = found_and_tracked(kind, kind.default_variant(), 40, algorithm);
        assert_whole(kind, &c, truth);
        // The cable (5 mm), not the phone (7 cm).
        assert!(c.diameter < 0.008, "{c:?}");
        assert!(
            max(&errors) < 20.0,
            "{algorithm:?}: worst frame {:.1} mm",
            max(&errors)
        );
    }
}

/// UPETrack on `kind` in the base variant and `other`: the whole rope
/// found, `check` holding of what was found, no frame above 20 mm.
fn found_whole_in_two_variants(
    kind: ScenarioKind,
    other: &str,
    check: impl Fn(&Candidate) -> bool,
) {
    for variant in [Variant::BASE, Variant::parse(other).expect("variant")] {
        let (c, truth, errors) = found_and_tracked(kind, variant, 40, Algorithm::Upetrack);
        assert_whole(kind, &c, truth);
        assert!(check(&c), "{}: {c:?}", variant.name);
        assert!(
            max(&errors) < 20.0,
            "{}: worst frame {:.1} mm",
            variant.name,
            max(&errors)
        );
    }
}

#[test]
fn a_loop_crossing_itself_is_found_round_the_loop() {
    found_whole_in_two_variants(ScenarioKind::CrossingLoop, "hd-thin-blue", |c| {
        c.crossings == 1
    });
}

#[test]
fn a_rope_in_three_pieces_of_mask_is_one_rope() {
    found_whole_in_two_variants(ScenarioKind::InPieces, "near-thin-green", |c| {
        c.fragments == 3
    });
}

/// `upetrack synth cable-desk` (with `synth_args`) into a fresh folder,
/// `edit` applied to its `dlo.json`, then `upetrack track` on it: the
/// track's exit, its stderr and the result JSON (null when not written).
fn synth_edit_track(
    name: &str,
    synth_args: &[&str],
    edit: impl FnOnce(&mut serde_json::Value),
) -> (bool, String, serde_json::Value) {
    let dir = common::temp_dir("finding", name);
    let d = dir.to_str().expect("utf-8");
    let out = run(&[&["synth", "cable-desk", d][..], synth_args].concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let dlo_path = dir.join("dlo.json");
    let mut dlo: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&dlo_path).expect("dlo.json")).expect("json");
    edit(&mut dlo);
    std::fs::write(&dlo_path, dlo.to_string()).expect("write dlo.json");
    let result = dir.join("result.json");
    let out = run(&["track", d, "--out", result.to_str().expect("utf-8")]);
    let r = std::fs::read(&result)
        .ok()
        .and_then(|b| serde_json::from_slice(&b).ok())
        .unwrap_or(serde_json::Value::Null);
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
        r,
    )
}

#[test]
fn a_scene_with_nothing_rope_shaped_is_refused_by_the_command() {
    // Black rectangles over the cable, the USB stick and the pen: every
    // shape in the black range is compact.
    let (ok, stderr, r) = synth_edit_track("nothing", &["--frames", "2"], |dlo| {
        dlo["occlusions"] = serde_json::json!([
            { "frames": [0, 1], "rect": [120, 60, 520, 400] },
            { "frames": [0, 1], "rect": [30, 300, 70, 180] }
        ]);
    });
    assert!(!ok, "tracked: {stderr}");
    assert!(stderr.contains("nothing rope-shaped"), "{stderr}");
    // No data lost: every frame is in the result, lost with its reason.
    let frames = r["frames"].as_array().expect("the result is written");
    assert_eq!(frames.len(), 2);
    assert!(frames.iter().all(|f| f["lost"] == true));
}

#[test]
fn the_command_says_which_rope_it_took_and_why() {
    let (ok, stderr, r) = synth_edit_track("said", &["--frames", "3", "--rope-prior"], |_| {});
    assert!(ok, "{stderr}");
    assert!(stderr.contains("frame 0: rope found: 1.0"), "{stderr}");
    assert!(stderr.contains("of the rope's known length"), "{stderr}");
    assert!(stderr.contains("set aside"), "{stderr}");
    let init = &r["frames"][0]["init"];
    assert!(
        init["candidates"].as_array().is_some_and(|c| !c.is_empty()),
        "{init}"
    );
    assert!(r["frames"][1].get("init").is_none());
}

/// Regression: a dark blue cord beside a dark blue pen, of which only thin
/// slivers fall in the cord's colour range, 7 cm from its end. The slivers
/// raised EM's first variance to its cap and the end nodes were pulled onto
/// them from the second frame on (12-18 mm a frame, 16.9 mm mean over 60).
#[test]
fn a_thin_distractor_beside_the_rope_does_not_pull_its_end_nodes() {
    let variant = Variant::parse("hd-thin-blue").expect("variant");
    let (c, truth, errors) =
        found_and_tracked(ScenarioKind::CableDesk, variant, 20, Algorithm::Upetrack);
    assert_whole(ScenarioKind::CableDesk, &c, truth);
    assert!(max(&errors) < 4.0, "worst frame {:.1} mm", max(&errors));
}

/// The length of the candidate taken on frame 0 of drawn scene `seed`
/// (written as the tuning range writes it: the draw depends on the frame
/// count, 48) and the true rope's length, metres.
fn found_on_first_frame(seed: u64) -> (f64, f64) {
    let (seq, truth) = written_drawn_scene(seed, 48);
    let decoded = seq.frame(0).expect("frame 0");
    let frame = decoded.frame(seq.depth_scale).expect("frame");
    let mut tracker = Tracker::new(Params::default(), seq.camera, seq.hsv).expect("tracker");
    let out = tracker
        .process(&frame, &seq.occlusions_at(0))
        .expect("first frame");
    let init = out.init.expect("initialised");
    (init.candidates[init.chosen].length, truth)
}

/// Regression for "a white twisted rope in a JPEG frame is found in six
/// pieces" (drawn scene 1015 of the tuning range: a 0.87 m rope in a tight
/// wave at 1280x720): the mask is one shape, but its ragged edges leave
/// junctions with two branches at the wave's peaks, where the crossing-turn
/// limit ended the walk; 0.25 m of it was taken, 0.59 m now.
#[test]
fn a_twisted_white_rope_in_a_jpeg_frame_is_found_round_its_tight_bends() {
    let (found, truth) = found_on_first_frame(1015);
    assert!(found > 0.6 * truth, "{found:.2} m of {truth:.2} m");
}

/// Regression for "a grey rope is found in two pieces cut at its bend"
/// (drawn scene 1009 of the tuning range: a 0.76 m striped grey rope in a
/// Z): its texture's dark stripes leave slivers along the mask's edge, and
/// the skeleton's junctions follow each other round the bend so closely
/// that their zones touch with no branch between them, which cut the walk
/// there; 0.54 m of it was taken, the rest lost until frame 10. Touching
/// zones are one zone now.
#[test]
fn a_grey_rope_with_a_ragged_edge_is_found_whole_round_its_bend() {
    let (found, truth) = found_on_first_frame(1009);
    assert!(found > 0.9 * truth, "{found:.2} m of {truth:.2} m");
}

/// Regression for "a loop is cut where its strand kinks against itself"
/// (drawn scenes 1082 of the tuning range and 2061 of the report range:
/// 1.0 and 1.42 m ropes settled in a loop): where the loop's strand meets
/// the rope it turns a right angle beside it, the walk through that
/// junction stops, and the two ends left there point past each other at
/// the kink, so the straight join refused them; 0.95 m of 2061's 1.42 was
/// taken. Ends whose rays meet at one corner ahead of both are joined now,
/// after every straight join.
#[test]
fn a_loop_kinked_where_its_strand_meets_the_rope_is_found_whole() {
    for seed in [1082, 2061] {
        let (found, truth) = found_on_first_frame(seed);
        assert!(found > 0.9 * truth, "{seed}: {found:.2} m of {truth:.2} m");
    }
}

/// Regression for "a recovery takes a box's dark edge for the rope" (drawn
/// scene 1032: a 0.30 m dark rope, 4.4 mm as measured, a box floating over
/// a third of it). Twice: at frame 28 the box's lower edge, 8.2 mm thick,
/// walked on into the rope's loop (refused since by thickness); on the
/// simulator's version 4, at frame 30, the loop and the box's dark lower
/// face joined as one candidate 5.5 mm thick, within one rope's factor,
/// while the state saw the rope coming out above the box: taken, frames
/// 30-40 were above 20 mm (68 mm at worst). A recovery now keeps the state
/// when the rope found leaves out rope the state sees (six seen nodes
/// 11 cm from it); worst frame 5.7 mm.
#[test]
fn a_recovery_does_not_take_a_boxs_dark_edge_for_the_rope() {
    let (seq, _) = written_drawn_scene(1032, 48);
    let worst = max(&frame_errors(&seq));
    assert!(worst < 20.0, "worst frame {worst:.1} mm");
}

/// Regression for "a lost tracker with most of the rope in view stays
/// lost" (drawn scene 4046: a rectangle over a fifth of the rope, every
/// re-initialisation refused as "only partly in view" for 18 frames, its
/// held nodes 25-48 cm off). The rope is hidden whole (lost), then all but
/// the left third of its width shows: less than `reinit_length_fraction` of
/// its length, which the tracker, once lost, takes
/// (`LOST_REINIT_LENGTH_FRACTION`); and the regression for "a
/// re-initialisation on part of the rope leaves the rest out": the nodes
/// were spread over the part in view, each spacing short by the part
/// hidden. The missing length now goes on from the end that meets the
/// rectangle, under it.
#[test]
fn a_lost_tracker_takes_the_rope_in_view_and_lays_the_rest_under_what_hides_it() {
    let laid = re_initialised_with_a_third_hidden(Params::default());
    let mut spread = Params::default();
    spread.upetrack.extend_short_ends = false;
    let spread = re_initialised_with_a_third_hidden(spread);
    eprintln!("laid: {laid:?}\nover the part in view alone: {spread:?}");
    assert!(
        laid.found < Params::default().reinit_length_fraction,
        "not the case under test: {:.2} of the length in view",
        laid.found
    );
    assert!(
        laid.laid > 0.95,
        "nodes over {:.2} of the length",
        laid.laid
    );
    // The missing share of the 24 nodes, laid straight on from the end
    // into the rectangle and out of the image above it (the hidden third
    // is a bend: the frame's error is 33 mm laid, 18 mm spread over the
    // part in view alone).
    let missing = (1.0 - laid.found) * 24.0;
    assert!(
        laid.under as f64 > missing - 2.0,
        "{} nodes under the rectangle for {missing:.1} missing",
        laid.under
    );
    // Spread over the part in view, only the end node at the edge.
    assert!(spread.under <= 1, "the case under test has changed");
}

/// A re-initialisation on part of the rope, as shares of the rope's length:
/// `found` in view, `laid` under the nodes; `under` nodes project into the
/// hiding rectangle or out of the image; `error_mm` the frame error.
#[derive(Debug)]
#[allow(dead_code)] // `error_mm` is printed
struct ReInitialised {
    found: f64,
    laid: f64,
    under: usize,
    error_mm: f64,
}

/// Static-s tracked, hidden whole (lost), then with the left third of its
/// width hidden by a rectangle, re-initialised.
fn re_initialised_with_a_third_hidden(params: Params) -> ReInitialised {
    let mut s = Scenario::new(ScenarioKind::StaticS, 1, 1, RenderSettings::default());
    let f = s.next_frame().expect("frame");
    let a = Frame::new(640, 480, &f.rgb, &f.depth, 0.001).expect("frame");
    let mut t = Tracker::new(params, s.camera(), s.hsv()).expect("tracker");
    assert!(!t.process(&a, &[]).expect("a").is_lost());
    let known = t.current_length();
    let mask = t.observe(&a, &[]).expect("observe").mask;
    let columns: Vec<usize> = (0..640)
        .filter(|&u| (0..480).any(|v| mask.data[v * 640 + u]))
        .collect();
    let (first, last) = (columns[0], columns[columns.len() - 1]);
    let whole = upetrack::Rect {
        x: 0,
        y: 0,
        w: 640,
        h: 480,
    };
    let third = upetrack::Rect {
        w: (first + (last - first) / 3) as i64,
        ..whole
    };
    assert!(t.process(&a, &[whole]).expect("hidden").is_lost());
    let out = t.process(&a, &[third]).expect("a third hidden");
    assert_eq!(out.status, upetrack::tracker::FrameStatus::Initialised);
    let init = out.init.as_ref().expect("an initialisation");
    let found = init.candidates[init.chosen].length / known;
    let laid = upetrack::polyline::polyline_length(&out.nodes) / known;
    let error = upetrack::metrics::frame_error(&out.nodes, &f.groundtruth).expect("error");
    let camera = s.camera();
    let in_view = |q: &upetrack::math::Vec2| q.x >= 0.0 && q.y >= 0.0 && q.x < 640.0 && q.y < 480.0;
    let under = out
        .nodes
        .iter()
        .filter_map(|p| camera.project(p))
        .filter(|q| !in_view(q) || third.contains(q.x as i64, q.y as i64))
        .count();
    ReInitialised {
        found,
        laid,
        under,
        error_mm: error * 1000.0,
    }
}

/// Regression for "a long thin rope is cut short at its bends" (drawn scene
/// 1075: a 1.40 m rope 6.4 mm thick in a two-period wave, at rest): the
/// paper's 24 nodes lie 61 mm apart on bends a few centimetres across and
/// cut them, so the tracked rope was 17 % short on its worst frame and 4.1
/// mm off the centre line on average over the first 16 frames. The node
/// count is set from the rope found now (nodes four diameters apart, at
/// most 48): 0.8 mm, within 5 %.
#[test]
fn a_long_thin_rope_is_not_cut_short_at_its_bends() {
    let (seq, truth) = written_drawn_scene(1075, 16);
    // Per frame: the error (mm), the length over the true one, the nodes.
    let track = |params: Params| {
        let frames = each_tracked_frame(&seq, params, |nodes, centre| {
            let error = upetrack::metrics::frame_error(nodes, centre).expect("error");
            (error * 1000.0, polyline_length(nodes) / truth, nodes.len())
        });
        let errors: Vec<f64> = frames.iter().map(|f| f.0).collect();
        let shortest = frames.iter().map(|f| f.1).fold(f64::INFINITY, f64::min);
        let count = frames.last().map_or(0, |f| f.2);
        (mean(&errors), shortest, count)
    };
    let fixed = Params {
        node_spacing_diameters: 0.0,
        ..Params::default()
    };
    let (error, shortest, count) = track(Params::default());
    assert!(count > 40, "{count} nodes");
    assert!(error < 1.5, "mean {error:.2} mm");
    assert!(shortest > 0.95, "{:.1} % short", 100.0 * (1.0 - shortest));
    // The paper's fixed count on the same rope, as the test's yardstick.
    let (error, _, count) = track(fixed);
    assert_eq!(count, 24);
    assert!(error > 3.0, "mean {error:.2} mm with 24 nodes");
}
