//! Regression tests for two ways a hidden run moved when the rope did not
//! (`docs/algorithm-notes.md`, "Anchors keep EM's move across the rope" and
//! "A resting rope keeps its hidden shape"), and one way it did not change
//! when the rope slid through it ("The whole rope does not stretch"), and
//! the node under the top stretch where the rope crosses itself.

use upetrack::polyline::polyline_length;
use upetrack::{Algorithm, Params};
use upetrack_synth::{ScenarioKind, Variant};

mod common;
use common::scenes::{each_frame, max, mean, track_scenario};
use common::{frame_errors, frame_errors_with, written_drawn_scene};

/// Regression for "a hidden tip creeps out of its occluder while the rope
/// rests" (TrackDLO's protocol with 40 and 60 % of the rope hidden): EM
/// pulled the visible node at the occlusion's edge along the rope, away
/// from the edge, by about a third of a node spacing every frame, and the
/// occlusion estimate passed that on to the hidden tip, which slid out past
/// the rope's end or bent off its curve: 2.45 and 2.35 mm. The anchors
/// keeping only their move across the rope (`anchor_across_only`) stopped
/// it (1.23 and 1.03 mm); since hidden nodes slide on the rope's smooth
/// curve the pull no longer cuts the tip's bend either, and the rule is no
/// longer what holds it (1.06 mm with it, 1.15 without on sweep-40). Both
/// must stay below the creep's figures.
#[test]
fn a_hidden_tip_does_not_creep_out_of_its_occluder_while_the_rope_rests() {
    for percent in [40, 60] {
        let kind = ScenarioKind::OcclusionSweep { percent };
        let (_, held) = track_scenario(kind, 60, Params::default());
        let mut params = Params::default();
        params.upetrack.anchor_across_only = false;
        let (_, pulled) = track_scenario(kind, 60, params);
        let (held, pulled) = (mean(&held), mean(&pulled));
        eprintln!(
            "sweep-{percent}: occluded mean {held:.2} mm, anchors moved along too {pulled:.2} mm"
        );
        assert!(held < 1.5, "sweep-{percent}: {held:.2} mm");
        assert!(
            pulled < 1.8,
            "sweep-{percent}, anchors moved along: {pulled:.2} mm"
        );
    }
}

/// Regression for "a rope at rest under an occluder drifts": with its known
/// neighbours still, a hidden node keeps its place (`alpha` rises to 1
/// below `rest_speed_m_per_s`) instead of being pulled towards Eq. 8-10's straighter
/// continuation of the bend every frame.
#[test]
fn a_hidden_bend_beside_resting_nodes_is_not_pulled_straighter() {
    let (_, resting) = track_scenario(ScenarioKind::StaticS, 60, Params::default());
    let mut params = Params::default();
    params.upetrack.rest_speed_m_per_s = 0.0;
    let (_, fixed_alpha) = track_scenario(ScenarioKind::StaticS, 60, params);
    eprintln!(
        "static-s: occluded mean {:.2} mm (max {:.2}), fixed alpha {:.2} mm (max {:.2})",
        mean(&resting),
        max(&resting),
        mean(&fixed_alpha),
        max(&fixed_alpha)
    );
    assert!(mean(&resting) < 2.6, "{:.2} mm", mean(&resting));
    assert!(mean(&resting) < 0.93 * mean(&fixed_alpha));
}

/// Whole-rope length error of each frame (0.05 = 5 %) and the error of
/// each frame after the occlusion begins, mm, of `pulled-through`.
fn pulled_through(params: Params) -> (Vec<f64>, Vec<f64>) {
    let (mut lengths, mut occluded) = (Vec::new(), Vec::new());
    let kind = ScenarioKind::PulledThrough;
    each_frame(kind, Variant::BASE, 90, params, |f, out, is_occluded| {
        let truth = polyline_length(&f.groundtruth);
        lengths.push((polyline_length(&out.nodes) - truth).abs() / truth);
        if is_occluded {
            let e = upetrack::metrics::frame_error(&out.nodes, &f.groundtruth).expect("error");
            occluded.push(e * 1000.0);
        }
    });
    (lengths, occluded)
}

/// Regression for "a rope pulled along its axis through an occluder grows":
/// a U's bend hidden while one arm is pulled out 10 cm, so the rope slides
/// round the hidden bend. The hidden bend kept its size while the true one
/// tightened, and the tracked rope grew by the length pulled out (6.6 %
/// over its rest length, 3.9 mm after the occlusion began). With the
/// hidden middle runs giving up what the visible rope took
/// (`conserve_middle_lengths`, under `conserve_length`) it keeps its length.
#[test]
fn a_rope_pulled_through_an_occluder_keeps_its_length_and_tightens_the_hidden_bend() {
    let (lengths, kept) = pulled_through(Params::default());
    let mut params = Params::default();
    params.upetrack.conserve_length = false;
    let (grown_lengths, grown) = pulled_through(params);
    let (_, trackdlo) = pulled_through(Params {
        algorithm: Algorithm::Trackdlo,
        ..Params::default()
    });
    eprintln!(
        "pulled-through: length error max {:.1} % (conserve_length off {:.1} %), \
         after occlusion {:.2} mm (off {:.2}, TrackDLO {:.2})",
        100.0 * max(&lengths),
        100.0 * max(&grown_lengths),
        mean(&kept),
        mean(&grown),
        mean(&trackdlo)
    );
    // Within issue 28's 3 % on every frame: 2.3 % since a run gives up
    // what a seen pull slid out of it on each frame; 4.4 % when it waits
    // for half a spacing of excess, which this bound refuses (figures with
    // the simulator's inextensible rope, version 4: against the rope that
    // stretched 2 % under the pull they were 1.2 and 3.1 %).
    assert!(max(&lengths) < 0.03, "{:.3}", max(&lengths));
    // Straightened from the pulled arm (session 42): 1.68 mm against 3.85
    // off and 5.47 for TrackDLO (1.46 mm against 3.96 and 3.76 since the
    // simulator's version 4); scaled as a whole towards the chord it was
    // 3.10 with version 3, which these bounds refused.
    assert!(mean(&kept) < 0.6 * mean(&grown));
    assert!(mean(&kept) < 0.4 * mean(&trackdlo));
}

/// Regression for "a hidden wave unrolls while the rope rests" (drawn
/// scene 1072 of the tuning range, written as users' files are: a 1.02 m
/// rope in a wave of two periods, a box sliding over 69 % of it, its hidden
/// end lifted 9 cm, a handheld camera). Only six nodes stay visible; the
/// hidden eighteen were slid and re-spaced every frame along the chords
/// between them, each move cutting the wave's bends, until the run lay
/// straight and its tip was 20 cm out of place: 80 mm at the last frame.
/// On the smooth curve through the nodes it keeps the wave (18.8 mm at
/// worst, at the lift's height).
#[test]
fn a_hidden_wave_does_not_unroll_when_its_nodes_slide_and_are_re_spaced() {
    let worst = worst_drawn_frame(1072);
    assert!(worst < 30.0, "worst frame {worst:.1} mm");
}

/// The worst frame's error (mm) of drawn scene `seed` (48 frames) tracked
/// with the defaults.
fn worst_drawn_frame(seed: u64) -> f64 {
    let (seq, _) = written_drawn_scene(seed, 48);
    max(&frame_errors(&seq))
}

/// Every frame's error (mm) of drawn scene `seed` (48 frames) tracked with
/// the defaults, and with the defaults as `off` changes them.
fn drawn_with_and_without(seed: u64, off: impl FnOnce(&mut Params)) -> (Vec<f64>, Vec<f64>) {
    let (seq, _) = written_drawn_scene(seed, 48);
    let mut params = Params::default();
    off(&mut params);
    (frame_errors(&seq), frame_errors_with(&seq, params))
}

/// Regression for "a lifted end that came out is not taken" (drawn scene
/// 1028 of the tuning range: a 1.08 m rope in a wave, a box over most of
/// it from frame 10, its first end lifted 13 cm over frames 18-36, the
/// camera on an arm). The lifted end came out of the box into view in the
/// air, and the rope that came out was refused for not lying on the
/// table (the gate that keeps a box's dark lower edge out): the hidden
/// end stayed under the box, 11 mm from frame 35 on, the worst frame
/// 11.1 mm. A piece with a surface well behind it on both sides stands
/// free and is taken (`Evidence::stands_free`): 5.5-6.4 mm, the worst
/// frame 7.4 mm (before the end came out).
#[test]
fn a_lifted_end_that_came_out_from_under_its_occluder_is_followed() {
    let worst = worst_drawn_frame(1028);
    eprintln!("drawn scene 1028: worst frame {worst:.1} mm");
    assert!(worst < 9.0, "worst frame {worst:.1} mm");
}

/// Regression for "a hidden end pulled out from under its occluder stays
/// behind" (drawn scene 1010 of the tuning range: a 0.52 m two-tone rope in
/// a wave, a hand over its last 15 % from frame 12, that end pulled 21.5 cm
/// out sideways over frames 17-33, a handheld camera). The end came out
/// into view and the hidden nodes stayed under the hand, nothing taking the
/// rope in view that no node explained: 25 mm at frame 31. Laid onto that
/// rope (`follow_emerged_ends`) the worst frame is 5 mm.
#[test]
fn a_hidden_end_pulled_out_from_under_its_occluder_follows_the_rope_that_came_out() {
    let (on, off) = drawn_with_and_without(1010, |p| p.upetrack.follow_emerged_ends = false);
    let (followed, left) = (max(&on), max(&off));
    eprintln!("drawn scene 1010: worst frame {followed:.1} mm, {left:.1} mm left behind");
    assert!(followed < 10.0, "worst frame {followed:.1} mm");
    assert!(
        left > 20.0,
        "the scene no longer pulls the end out: {left:.1} mm"
    );
}

/// Regression for "a short rope leaves the rope past its end to a thing
/// beside it" (drawn scene 1016 of the tuning range: a 0.36 m grey loop, a
/// box over its first quarter from frame 16, the first end pulled 12 cm
/// along the rope over frames 18-36). The pulled end's rope lay in view
/// past the tracked end while the state, bunched, was 2-3 spacings short;
/// the tracker remembered it, frame after frame, as a rope-coloured thing
/// beside the rope (out of every hidden run's reach), and the hidden loop
/// folded along the box's edge: 15.1 mm at worst. With the length the
/// state holds nowhere counted in that reach and a short rope's end
/// following rope in view past it (`emerging::follow_rope_past_ends`):
/// 9.7 mm.
#[test]
fn a_short_ropes_end_follows_rope_in_view_past_it() {
    let worst = worst_drawn_frame(1016);
    eprintln!("drawn scene 1016: worst frame {worst:.1} mm");
    assert!(worst < 12.0, "worst frame {worst:.1} mm");
}
