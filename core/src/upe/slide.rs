//! The displacement of a hidden run as the rope carries it (this project's
//! estimate in place of Eq. 6-7, `HiddenMotion::Slide`): a rope dragged
//! along itself slides along its own path, so the part of an anchor's
//! displacement along the rope moves the hidden nodes *along the run's
//! previous curve*, and only the part across the rope translates them.
//!
//! A rope at rest stays where it was last seen (no displacement, no
//! motion), the hidden run keeps its arc length (nodes move along a curve
//! of fixed length; past a free end the curve is continued straight along
//! its last tangent), and a sideways push translates the run as Eq. 6-7 do.
//! The curve is the smooth one through the previous nodes
//! ([`RopeCurve::smooth`]), the one resampling puts nodes on: slid along
//! its polyline, a node at a bend would cut it by the chord's sagitta, and
//! a hidden bend slid a little every frame lay straight within a second.

use alloc::vec::Vec;

use crate::curve::RopeCurve;
use crate::math::{self, Vec3};

/// A maximal run of hidden nodes `start..end` (end exclusive).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HiddenRun {
    /// First hidden node.
    pub start: usize,
    /// One past the last hidden node.
    pub end: usize,
}

/// The maximal runs of `false` in `known`.
pub fn hidden_runs(known: &[bool]) -> Vec<HiddenRun> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < known.len() {
        if known[i] {
            i += 1;
            continue;
        }
        let start = i;
        while i < known.len() && !known[i] {
            i += 1;
        }
        out.push(HiddenRun { start, end: i });
    }
    out
}

/// How many nodes are hidden at each end of the rope: the leading and the
/// trailing `false` of `known` (both `known.len()` when every node is
/// hidden).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HiddenEnds {
    /// Hidden nodes from node 0 on.
    pub head: usize,
    /// Hidden nodes up to node `M - 1`.
    pub tail: usize,
}

impl HiddenEnds {
    /// The hidden ends of `known`.
    pub fn of(known: &[bool]) -> Self {
        Self {
            head: known.iter().take_while(|&&k| !k).count(),
            tail: known.iter().rev().take_while(|&&k| !k).count(),
        }
    }
}

/// Nodes of visible rope behind an anchor that the sliding curve may
/// borrow when a run is pulled out past its anchor.
const BORROWED_NODES: usize = 3;

/// How one anchor moved: the slide along the previous curve (its new
/// position projected onto the curve, in the direction of increasing node
/// index) and what is left across the curve. Exact for a rope sliding along
/// itself, curved or not.
struct AnchorMotion {
    slide: f64,
    across: Vec3,
}

fn anchor_motion(curve: &RopeCurve<'_>, sigma: f64, moved_to: &Vec3) -> AnchorMotion {
    // Along the curve, no farther than the anchor's own displacement allows.
    let reach = math::norm(&(moved_to - curve.at(sigma))) + math::LENGTH_EPSILON;
    let s_new = curve.project(moved_to, sigma, reach);
    AnchorMotion {
        slide: s_new - sigma,
        across: moved_to - curve.at(s_new),
    }
}

/// The estimate of every hidden node (`None` for known nodes) by sliding
/// each hidden run along its previous curve. `now` holds this frame's
/// positions of the known nodes, `prev` the previous frame's nodes. The
/// motion across the rope fades along the run by `decay` (Eq. 6's
/// `gamma`) per node from its anchor, as friction on the table makes it:
/// the far part of a long hidden run stays where it lay.
pub fn slide_estimates(
    now: &[Vec3],
    known: &[bool],
    prev: &[Vec3],
    decay: f64,
) -> Vec<Option<Vec3>> {
    let m = now.len();
    let mut out = alloc::vec![None; m];
    if known.len() != m || prev.len() != m {
        return out;
    }
    for run in hidden_runs(known) {
        let left = run.start.checked_sub(1);
        let right = (run.end < m).then_some(run.end);
        if left.is_none() && right.is_none() {
            continue;
        }
        // The previous curve through the run and its anchors, with a few
        // visible nodes borrowed behind a lone anchor (a run pulled out
        // past it follows the rope's previous path there).
        let from = match (left, right) {
            (Some(a), None) => a.saturating_sub(BORROWED_NODES),
            (Some(a), Some(_)) => a,
            (None, _) => 0,
        };
        let to = match (left, right) {
            (None, Some(b)) => (b + BORROWED_NODES).min(m - 1),
            (_, Some(b)) => b,
            (_, None) => m - 1,
        };
        let curve = RopeCurve::smooth(&prev[from..=to]);
        let sigma = |i: usize| curve.arc_of(i - from);
        let ma = left.map(|a| anchor_motion(&curve, sigma(a), &now[a]));
        let mb = right.map(|b| anchor_motion(&curve, sigma(b), &now[b]));
        let slide = match (&ma, &mb) {
            (Some(a), Some(b)) => 0.5 * (a.slide + b.slide),
            (Some(a), None) => a.slide,
            (None, Some(b)) => b.slide,
            (None, None) => 0.0,
        };
        for i in run.start..run.end {
            let across = match (left, right, &ma, &mb) {
                (Some(_), Some(b), Some(ma), Some(mb)) => {
                    // A middle run's curve starts at its left anchor (sigma 0).
                    let span = sigma(b);
                    let lambda = if span > math::LENGTH_EPSILON {
                        sigma(i) / span
                    } else {
                        0.5
                    };
                    ma.across * (1.0 - lambda) + mb.across * lambda
                }
                (Some(a), _, Some(ma), None) => ma.across * libm::pow(decay, (i - a - 1) as f64),
                (_, Some(b), None, Some(mb)) => mb.across * libm::pow(decay, (b - i - 1) as f64),
                _ => Vec3::zeros(),
            };
            let y = curve.at(sigma(i) + slide) + across;
            if math::is_finite(&y) {
                out[i] = Some(y);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::fixture::{off_circle, on_circle, u_points};
    use alloc::vec;

    /// An arc of radius 0.1 m, nodes 2 cm apart along it.
    fn arc(n: usize, shift: f64) -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let t = (i as f64 * 0.02 + shift) / 0.1;
                Vec3::new(0.1 * libm::cos(t), 0.1 * libm::sin(t), 0.6)
            })
            .collect()
    }

    #[test]
    fn runs_are_found_in_order() {
        let known = [false, true, false, false, true, false];
        assert_eq!(
            hidden_runs(&known),
            vec![
                HiddenRun { start: 0, end: 1 },
                HiddenRun { start: 2, end: 4 },
                HiddenRun { start: 5, end: 6 }
            ]
        );
        assert!(hidden_runs(&[true; 3]).is_empty());
    }

    #[test]
    fn a_rope_at_rest_stays_where_it_was_seen() {
        let prev = arc(12, 0.0);
        let known: Vec<bool> = (0..12).map(|i| !(i < 3 || (6..8).contains(&i))).collect();
        let est = slide_estimates(&prev, &known, &prev, 0.8);
        for i in 0..12 {
            match est[i] {
                Some(y) => assert!((y - prev[i]).norm() < 1e-12, "node {i}"),
                None => assert!(known[i]),
            }
        }
    }

    #[test]
    fn a_rope_dragged_along_itself_moves_its_hidden_tip_along_its_path() {
        // The whole rope slides 1 cm along its own arc (towards lower index):
        // the visible nodes show it, and the hidden tip (nodes 8-11) must
        // land on the arc 1 cm further along, not 1 cm translated.
        let prev = arc(12, 0.0);
        let now = arc(12, -0.01);
        let known: Vec<bool> = (0..12).map(|i| i < 8).collect();
        let est = slide_estimates(&now, &known, &prev, 0.8);
        for i in 8..12 {
            let y = est[i].expect("estimated");
            // Within the chords' sagitta (2 cm chords of a 10 cm arc: 0.5 mm).
            assert!(
                (y - now[i]).norm() < 6e-4,
                "node {i}: {}",
                (y - now[i]).norm()
            );
            // A plain translation by the anchor's displacement errs more.
            let translated = prev[i] + (now[7] - prev[7]);
            assert!((translated - now[i]).norm() > 1e-3);
        }
        // The run keeps its length.
        let len = |p: &[Vec3]| p.windows(2).map(|w| (w[1] - w[0]).norm()).sum::<f64>();
        let mut nodes = now.clone();
        for i in 8..12 {
            nodes[i] = est[i].expect("estimated");
        }
        assert!((len(&nodes[7..]) - len(&prev[7..])).abs() < 1e-3);
    }

    #[test]
    fn a_sideways_push_translates_and_a_middle_run_blends_its_anchors() {
        let prev: Vec<Vec3> = (0..10)
            .map(|i| Vec3::new(i as f64 * 0.02, 0.0, 0.6))
            .collect();
        let known: Vec<bool> = (0..10).map(|i| !(4..7).contains(&i)).collect();
        // Left part pushed 1 cm in y, right part not at all.
        let mut now = prev.clone();
        for p in now.iter_mut().take(4) {
            p.y += 0.01;
        }
        let est = slide_estimates(&now, &known, &prev, 0.8);
        let y: Vec<f64> = (4..7).map(|i| est[i].expect("estimated").y).collect();
        // Anchors at nodes 3 (pushed) and 7 (still): 3/4, 2/4, 1/4 of the push.
        for (k, expect) in [0.0075, 0.005, 0.0025].iter().enumerate() {
            assert!((y[k] - expect).abs() < 1e-12, "node {}: {}", k + 4, y[k]);
        }
    }

    #[test]
    fn an_anchor_slides_no_farther_than_it_moved() {
        // The anchor at s = 0.5 moves to 0.9 above it: the far side of the U
        // (0.1 away) is beyond its reach of 0.9; the near side (0.5 away) is
        // within it. Far from the origin, so the reach must come from the
        // anchor's displacement and not its position.
        let points = u_points(10.0);
        let c = RopeCurve::polyline(&points);
        let m = anchor_motion(&c, 0.5, &Vec3::new(10.5, 0.9, 0.0));
        assert!((m.slide - 1.4).abs() < 1e-12, "{}", m.slide);
        assert!((m.across - Vec3::new(-0.5, 0.0, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn a_middle_run_slides_by_its_anchors_mean_and_blends_what_is_across() {
        let prev: Vec<Vec3> = (0..10)
            .map(|i| Vec3::new(i as f64 * 0.02, 0.0, 0.6))
            .collect();
        let known: Vec<bool> = (0..10).map(|i| !(4..7).contains(&i)).collect();
        // Left part: 1 cm along and 1 cm across; right part 0.5 cm back,
        // -0.4 cm across (each anchor slides into the run, within its curve).
        let mut now = prev.clone();
        for (i, p) in now.iter_mut().enumerate() {
            let d = if i < 4 {
                (0.01, 0.01)
            } else {
                (-0.005, -0.004)
            };
            p.x += d.0;
            p.y += d.1;
        }
        let est = slide_estimates(&now, &known, &prev, 0.8);
        for i in 4..7 {
            let y = est[i].expect("estimated");
            let lambda = (i - 3) as f64 / 4.0;
            let expected = Vec3::new(
                i as f64 * 0.02 + 0.0025,
                0.01 * (1.0 - lambda) - 0.004 * lambda,
                0.6,
            );
            assert!((y - expected).norm() < 1e-12, "node {i}: {y:?}");
        }
    }

    #[test]
    fn an_end_run_moved_across_fades_by_gamma_per_node_from_its_anchor() {
        let prev: Vec<Vec3> = (0..10)
            .map(|i| Vec3::new(i as f64 * 0.02, 0.0, 0.6))
            .collect();
        let mut now = prev.clone();
        for p in &mut now {
            p.y += 0.01;
        }
        // Head hidden (0-2, anchor 3) and tail hidden (7-9, anchor 6).
        let known: Vec<bool> = (0..10).map(|i| (3..7).contains(&i)).collect();
        let est = slide_estimates(&now, &known, &prev, 0.8);
        for (i, share) in [(2, 1.0), (1, 0.8), (0, 0.64), (7, 1.0), (8, 0.8), (9, 0.64)] {
            let y = est[i].expect("estimated");
            let expected = Vec3::new(i as f64 * 0.02, 0.01 * share, 0.6);
            assert!((y - expected).norm() < 1e-12, "node {i}: {y:?}");
        }
    }

    #[test]
    fn a_hidden_head_pulled_along_follows_the_path_of_three_borrowed_nodes() {
        // Only node 0 hidden; the rope is pulled 5 cm (2.5 node spacings)
        // along its arc towards the tail. The head lands on the arc, which
        // it can only do if the curve reaches three nodes past its anchor.
        let prev = arc(12, 0.0);
        let now = arc(12, 0.05);
        let known: Vec<bool> = (0..12).map(|i| i > 0).collect();
        let est = slide_estimates(&now, &known, &prev, 0.8);
        let y = est[0].expect("estimated");
        // Within the chords' sagitta (0.5 mm).
        assert!((y - now[0]).norm() < 6e-4, "{}", (y - now[0]).norm());
    }

    /// Regression for "a hidden wave unrolls while the rope rests" (drawn
    /// scene 1072: a wave under a box, its tip 20 cm out of place 30
    /// frames later): the visible nodes jitter along the rope as EM's noise
    /// moves them, and each jitter slides the hidden run. Slid along its
    /// polyline, each node at the bend cut it by the chord's sagitta; on the
    /// curve the run stays on the bend.
    #[test]
    fn a_hidden_bend_slid_back_and_forth_keeps_its_shape() {
        // A tight bend: nodes 1 cm apart on a circle of 2 cm radius, the
        // first four visible, the other eight hidden.
        let radius = 0.02;
        let on_circle = |s: f64| on_circle(radius, s);
        let known: Vec<bool> = (0..12).map(|i| i < 4).collect();
        let mut nodes: Vec<Vec3> = (0..12).map(|i| on_circle(0.01 * i as f64)).collect();
        for frame in 0..40 {
            // EM's noise: the visible nodes 1 mm one way, then back.
            let jitter = if frame % 2 == 0 { 0.001 } else { 0.0 };
            let mut now = nodes.clone();
            for (i, p) in now.iter_mut().enumerate().take(4) {
                *p = on_circle(0.01 * i as f64 + jitter);
            }
            let est = slide_estimates(&now, &known, &nodes, 0.8);
            for i in 4..12 {
                now[i] = est[i].expect("estimated");
            }
            nodes = now;
        }
        let off = off_circle(&nodes[4..], radius);
        // Slid along the polyline the run unrolled: 10.7 mm off at its
        // middle; on the curve 0.6 mm at its tip (the Catmull-Rom curve is
        // not exactly a circle at 0.5 rad a node).
        assert!(
            off < 1.5e-3,
            "hidden nodes {:.2} mm off the bend",
            off * 1e3
        );
    }

    #[test]
    fn mismatched_lengths_give_no_estimates() {
        let prev = arc(6, 0.0);
        let known = [true, false, true, true, true, true];
        assert!(slide_estimates(&prev, &known, &prev[..5], 0.8)
            .iter()
            .all(Option::is_none));
        assert!(slide_estimates(&prev, &known[..5], &prev, 0.8)
            .iter()
            .all(Option::is_none));
    }
}
