//! Integration test of where the tracked rope's ends are reported: at the
//! tips the images show, not where EM leaves the end nodes.

use upetrack::Params;
use upetrack_io::eval::end_offsets;
use upetrack_synth::{ScenarioKind, Variant};

mod common;
use common::scenes::{each_frame, mean};

/// The mean distance and the mean centre line short of the tip, mm, of
/// the end nodes in view over a scenario's frames.
fn ends_of(kind: ScenarioKind, params: Params) -> (f64, f64) {
    let (mut distance, mut short) = (Vec::new(), Vec::new());
    each_frame(kind, Variant::BASE, 60, params, |f, out, _| {
        for e in end_offsets(&out.nodes, &out.visible, &f.groundtruth) {
            distance.push(1000.0 * e.distance);
            short.push(1000.0 * e.arc);
        }
    });
    (mean(&distance), mean(&short))
}

/// Regression for "an end node in view stops short of the rope's tip"
/// (EM draws it in: its Gaussian has points on one side only; on the
/// drawn tuning range the ends seen stopped 6.9 mm short of the tips on
/// the median sequence, 1.2 mm once reported where the mask ends).
#[test]
fn the_ends_in_view_are_reported_at_the_rope_s_tips() {
    // Dynamic-pull: the rope pulled across the table, both ends in view.
    let (at_tips, short_of_tips) = ends_of(ScenarioKind::DynamicPull, Params::default());
    let mut em = Params::default();
    em.upetrack.report_seen_tips = false;
    let (em_ends, em_short) = ends_of(ScenarioKind::DynamicPull, em);
    eprintln!(
        "dynamic-pull: ends {at_tips:.2} mm ({short_of_tips:.2} short of the tips); \
         where EM leaves them {em_ends:.2} ({em_short:.2})"
    );
    // Measured: 2.48 mm (0.60 short); 3.94 (2.78) where EM leaves them.
    assert!(at_tips < 3.0, "ends {at_tips:.2} mm from the tips");
    assert!(short_of_tips < 1.2, "ends {short_of_tips:.2} mm short");
    assert!(
        em_short > short_of_tips + 1.0,
        "{em_short:.2} against {short_of_tips:.2}"
    );
}
