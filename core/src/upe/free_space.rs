//! Hidden nodes out of free space (this project's addition after Eq. 11):
//! a hidden run whose estimate puts nodes where no hidden rope may be is
//! moved back to where one may. Where it may is the caller's test
//! (`may_hide`): in the step, not where the images show nothing hiding the
//! node (`Sight::FreeSpace`) and not inside the table the visible rope
//! rests on (`Plane::hides_inside`).
//!
//! - A run at an end of the rope turns about its anchor (the last visible
//!   node), about the camera's optical axis, by the smallest angle that
//!   clears free space: its shape, length and depths stay, only its
//!   heading in the image changes, the way a hidden tip swings under the
//!   object that hides it. (About the ray through the anchor instead, an
//!   off-centre run would tilt in depth and could sink into the table,
//!   where the table in front of it would count as an occluder.) At most a
//!   quarter turn: a run turned further folds back alongside the rope it
//!   hangs from, which no rope does between two frames.
//! - A run in the middle is drawn towards the straight chord between its
//!   anchors, by the smallest share that clears free space.
//!
//! Where nothing clears every node, the choice with the fewest nodes in
//! free space is kept (ties: the smallest change).
//!
//! Turned about the optical axis a run keeps its depths, so on a tilted
//! table it sinks into the table on one side, where the window test alone
//! takes the table in front of it for an occluder (and a declared
//! rectangle says nothing about depth): hence the table in `may_hide`.

use alloc::vec::Vec;

use super::slide::{hidden_runs, HiddenRun};
use crate::math::{self, Vec3};

/// Turning angles tried for an end run, radians: 5 degree steps ...
const TURN_STEP: f64 = 5.0 * core::f64::consts::PI / 180.0;
/// ... up to a quarter turn each way.
const TURN_STEPS: usize = 18;
/// Shares of the way to the chord tried for a middle run.
const CHORD_SHARES: [f64; 4] = [0.25, 0.5, 0.75, 1.0];

/// What the stage did in one frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FreeSpaceReport {
    /// Hidden nodes found in free space before the correction.
    pub found: usize,
    /// Hidden nodes still in free space after it.
    pub left: usize,
    /// Runs moved.
    pub runs_moved: usize,
}

fn in_free_space(may_hide: &dyn Fn(&Vec3) -> bool, points: &[Vec3]) -> usize {
    points.iter().filter(|p| !may_hide(p)).count()
}

/// `p` turned by `angle` about the axis `axis` (unit) through `centre`
/// (Rodrigues' formula).
fn turn(p: &Vec3, centre: &Vec3, axis: &Vec3, angle: f64) -> Vec3 {
    let v = p - centre;
    let (s, c) = (libm::sin(angle), libm::cos(angle));
    centre + v * c + axis.cross(&v) * s + axis * (axis.dot(&v) * (1.0 - c))
}

/// The candidates for one run, the unchanged run first, then by growing change.
fn candidates(nodes: &[Vec3], run: HiddenRun) -> Vec<Vec<Vec3>> {
    let m = nodes.len();
    let points = nodes[run.start..run.end].to_vec();
    let mut out = alloc::vec![points.clone()];
    let left = run.start.checked_sub(1);
    let right = (run.end < m).then_some(run.end);
    match (left, right) {
        (Some(a), Some(b)) => {
            let span = (run.end - run.start + 1) as f64;
            for share in CHORD_SHARES {
                out.push(
                    points
                        .iter()
                        .enumerate()
                        .map(|(k, p)| {
                            let lambda = (k + 1) as f64 / span;
                            let chord = nodes[a] + (nodes[b] - nodes[a]) * lambda;
                            p + (chord - p) * share
                        })
                        .collect(),
                );
            }
        }
        (Some(anchor), None) | (None, Some(anchor)) => {
            let centre = nodes[anchor];
            let axis = Vec3::new(0.0, 0.0, 1.0);
            for step in 1..=TURN_STEPS {
                for sign in [1.0, -1.0] {
                    let angle = sign * step as f64 * TURN_STEP;
                    out.push(
                        points
                            .iter()
                            .map(|p| turn(p, &centre, &axis, angle))
                            .collect(),
                    );
                }
            }
        }
        (None, None) => {}
    }
    out
}

/// Moves hidden runs (`known[m] == false`) out of free space, in place:
/// `may_hide(p)` is `false` where no hidden rope may be.
pub fn clear_free_space(
    nodes: &mut [Vec3],
    known: &[bool],
    may_hide: &dyn Fn(&Vec3) -> bool,
) -> FreeSpaceReport {
    let mut report = FreeSpaceReport::default();
    if known.len() != nodes.len() {
        return report;
    }
    for run in hidden_runs(known) {
        let found = in_free_space(may_hide, &nodes[run.start..run.end]);
        report.found += found;
        if found == 0 {
            continue;
        }
        let mut best: Option<(usize, Vec<Vec3>)> = None;
        for candidate in candidates(nodes, run) {
            let count = in_free_space(may_hide, &candidate);
            if best.as_ref().is_none_or(|(c, _)| count < *c) {
                let done = count == 0;
                best = Some((count, candidate));
                if done {
                    break;
                }
            }
        }
        if let Some((count, points)) = best {
            if count < found && points.iter().all(math::is_finite) {
                nodes[run.start..run.end].copy_from_slice(&points);
                report.runs_moved += 1;
                report.left += count;
            } else {
                report.left += found;
            }
        }
    }
    report
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::evidence::fixture::Table;
    use crate::perception::evidence::OCCLUDER_MARGIN;
    use crate::perception::segmentation::Rect;
    use alloc::vec;

    /// A table at 0.6 m seen by a 64 x 48 camera.
    fn table() -> Table {
        Table::new(64, 48, 60.0, 600)
    }

    /// An occlusion rectangle over the right half of the image.
    const RIGHT_HALF: [Rect; 1] = [Rect {
        x: 32,
        y: 0,
        w: 32,
        h: 48,
    }];

    /// A point on the table plane (just above it) at pixel (u, v).
    fn at(u: f64, v: f64) -> Vec3 {
        table().at(u, v, 0.59)
    }

    /// Six nodes along row 24: 0-2 in from the right edge to the right
    /// half's border, 3-5 (the hidden tip) on over the left half.
    fn tip_over_free_table() -> Vec<Vec3> {
        table().tip_along_row_24()
    }

    #[test]
    fn a_hidden_end_is_not_turned_into_the_table_it_rests_on() {
        // The table tilts towards the camera up the image, 5 mm nearer per
        // row (1 cm at 0.6 m: a 27 degree slope); the rope lies on it along
        // row 24, its tip (nodes 3-5) hidden over the open left half.
        let mut t = table();
        for v in 0..48 {
            for u in 0..64 {
                t.depth[v * 64 + u] = (600 + 5 * (v as i64 - 24)) as u16;
            }
        }
        let frame = t.frame();
        let e = t.evidence(&frame, &RIGHT_HALF, 0.0075);
        let plane = crate::perception::table::fit_table(&e).expect("a plane");
        let before: Vec<Vec3> = [44.0, 40.0, 36.0, 30.0, 26.0, 22.0]
            .iter()
            .map(|&u| t.at(u, 24.0, 0.5925))
            .collect();
        let known = [true, true, true, false, false, false];
        assert!(plane.carries(&before[..3], 0.0075));
        let deepest = |nodes: &[Vec3]| {
            nodes[3..]
                .iter()
                .map(|p| -plane.height(p))
                .fold(f64::MIN, f64::max)
        };
        // Turned about the optical axis the tip keeps its depth: turned up
        // the image it sinks into the table, which then lies in front of it
        // as an occluder would.
        let mut blind = before.clone();
        let r = clear_free_space(&mut blind, &known, &|p| e.sight(p).allows_hidden());
        assert_eq!((r.runs_moved, r.left), (1, 0));
        assert!(deepest(&blind) > OCCLUDER_MARGIN, "{}", deepest(&blind));
        // Knowing the table, the stage does not take a place inside it.
        let mut seeing = before.clone();
        clear_free_space(&mut seeing, &known, &|p| {
            e.sight(p).allows_hidden() && !plane.hides_inside(&e, p)
        });
        assert!(deepest(&seeing) < OCCLUDER_MARGIN, "{}", deepest(&seeing));
        assert_eq!(&seeing[..3], &before[..3]);
    }

    /// [`tip_over_free_table`] with its tip (nodes 3-5) hidden, cleared
    /// under the occluders `rects`: the nodes before and after, and what
    /// the stage did.
    fn tip_cleared_under(rects: &[Rect]) -> (Vec<Vec3>, Vec<Vec3>, FreeSpaceReport) {
        let t = table();
        let frame = t.frame();
        let e = t.evidence(&frame, rects, 0.0075);
        let before = tip_over_free_table();
        let mut nodes = before.clone();
        let known = [true, true, true, false, false, false];
        let r = clear_free_space(&mut nodes, &known, &|p| e.sight(p).allows_hidden());
        (before, nodes, r)
    }

    #[test]
    fn a_hidden_end_that_sticks_out_over_free_table_turns_back_under_the_occluder() {
        let t = table();
        let frame = t.frame();
        let e = t.evidence(&frame, &RIGHT_HALF, 0.0075);
        let mut nodes = tip_over_free_table();
        let known = [true, true, true, false, false, false];
        let before = nodes.clone();
        let len = |p: &[Vec3]| p.windows(2).map(|w| (w[1] - w[0]).norm()).sum::<f64>();
        let r = clear_free_space(&mut nodes, &known, &|p| e.sight(p).allows_hidden());
        assert_eq!((r.found, r.left, r.runs_moved), (3, 0, 1), "{r:?}");
        for p in &nodes[3..] {
            assert!(e.sight(p).allows_hidden(), "{p:?}");
        }
        // Turned, not stretched: the run keeps its length from the anchor.
        assert!((len(&nodes[2..]) - len(&before[2..])).abs() < 1e-9);
        assert_eq!(&nodes[..3], &before[..3]);
    }

    #[test]
    fn turning_is_a_rotation_about_the_axis_through_the_centre() {
        let c = Vec3::new(1.0, 2.0, 3.0);
        let z = Vec3::new(0.0, 0.0, 1.0);
        let p = turn(
            &Vec3::new(2.0, 2.0, 3.5),
            &c,
            &z,
            core::f64::consts::FRAC_PI_2,
        );
        assert!((p - Vec3::new(1.0, 3.0, 3.5)).norm() < 1e-12, "{p:?}");
        // At 60 degrees: the component along the axis is kept.
        let p = turn(
            &Vec3::new(2.0, 2.0, 3.5),
            &c,
            &z,
            core::f64::consts::FRAC_PI_3,
        );
        let expected = Vec3::new(1.5, 2.0 + 0.75f64.sqrt(), 3.5);
        assert!((p - expected).norm() < 1e-12, "{p:?}");
        assert!((TURN_STEP - 5f64.to_radians()).abs() < 1e-15);
    }

    #[test]
    fn candidates_grow_from_no_change_to_the_chord_and_to_a_quarter_turn() {
        let nodes = vec![
            Vec3::new(0.0, 0.0, 0.6),
            Vec3::new(1.0, 1.0, 0.6),
            Vec3::new(2.0, 1.0, 0.6),
            Vec3::new(3.0, 0.0, 0.6),
        ];
        let middle = candidates(&nodes, HiddenRun { start: 1, end: 3 });
        assert_eq!(middle.len(), 1 + CHORD_SHARES.len());
        assert_eq!(middle[0], nodes[1..3].to_vec());
        // Share 1/4 of the way to the chord (y = 0), then all of it.
        assert!((middle[1][0] - Vec3::new(1.0, 0.75, 0.6)).norm() < 1e-12);
        assert!((middle[4][0] - Vec3::new(1.0, 0.0, 0.6)).norm() < 1e-12);
        assert!((middle[4][1] - Vec3::new(2.0, 0.0, 0.6)).norm() < 1e-12);
        let end = candidates(&nodes, HiddenRun { start: 2, end: 4 });
        assert_eq!(end.len(), 1 + 2 * TURN_STEPS);
        // +5 degrees, then -5, ..., the last: a quarter turn back about node 1.
        let first = end[1][0] - nodes[1];
        assert!((libm::atan2(first.y, first.x) - TURN_STEP).abs() < 1e-12);
        let second = end[2][0] - nodes[1];
        assert!((libm::atan2(second.y, second.x) + TURN_STEP).abs() < 1e-12);
        let last = end[2 * TURN_STEPS][0] - nodes[1];
        assert!((last - Vec3::new(0.0, -1.0, 0.0)).norm() < 1e-9, "{last:?}");
    }

    /// Regression for "a hidden tip at its occluder's corner folds back
    /// along the rope" (drawn scene 1025: the tip a pixel out of the
    /// rectangle's corner; no small turn clears it, and half a turn laid
    /// the run alongside the visible rope, 70 mm from the truth for the
    /// rest of the sequence). Only an occluder behind the anchor would hide
    /// this tip: it is left where it was, not folded back.
    #[test]
    fn a_hidden_end_is_not_folded_back_along_the_rope_to_clear_free_space() {
        // The occluder: columns 38-63 of rows 20-28, behind the anchor
        // (node 2 at column 36) as seen from the tip (columns 30-22).
        let rects = [Rect {
            x: 38,
            y: 20,
            w: 26,
            h: 9,
        }];
        let (before, nodes, r) = tip_cleared_under(&rects);
        assert_eq!((r.found, r.left, r.runs_moved), (3, 3, 0), "{r:?}");
        assert_eq!(nodes, before);
    }

    #[test]
    fn a_run_nothing_can_clear_stays_where_it_was_and_is_counted() {
        let t = table();
        let frame = t.frame();
        // No rectangle: the whole table is free space.
        let e = t.evidence(&frame, &[], 0.0075);
        let mut nodes = vec![
            at(40.0, 24.0),
            at(36.0, 24.0),
            at(30.0, 24.0),
            at(26.0, 24.0),
        ];
        let before = nodes.clone();
        let r = clear_free_space(&mut nodes, &[true, true, false, false], &|p| {
            e.sight(p).allows_hidden()
        });
        assert_eq!((r.found, r.left, r.runs_moved), (2, 2, 0));
        assert_eq!(nodes, before);
    }

    #[test]
    fn a_run_partly_cleared_takes_the_smallest_turn_and_counts_what_is_left() {
        // A 12 x 12 px occluder right of the anchor: no turn brings the
        // whole tip under it; 45 degrees (the smallest) brings in one node.
        let rects = [Rect {
            x: 32,
            y: 18,
            w: 12,
            h: 12,
        }];
        let (before, nodes, r) = tip_cleared_under(&rects);
        assert_eq!((r.found, r.left, r.runs_moved), (3, 2, 1), "{r:?}");
        let z = Vec3::new(0.0, 0.0, 1.0);
        for k in 3..6 {
            let expected = turn(&before[k], &before[2], &z, 9.0 * TURN_STEP);
            assert!((nodes[k] - expected).norm() < 1e-12, "node {k}");
        }
    }

    #[test]
    fn a_middle_run_bulging_over_free_table_is_drawn_to_its_chord() {
        // The occluder covers columns 26-37 of rows 20-28.
        let rects = [Rect {
            x: 26,
            y: 20,
            w: 12,
            h: 9,
        }];
        let t = table();
        let frame = t.frame();
        let e = t.evidence(&frame, &rects, 0.0075);
        // Anchors at rows 18 and 30 either side of the band; the hidden
        // middle bulges left into free table.
        let mut nodes = vec![
            at(32.0, 14.0),
            at(32.0, 18.0),
            at(20.0, 22.0),
            at(20.0, 26.0),
            at(32.0, 30.0),
            at(32.0, 34.0),
        ];
        let known = [true, true, false, false, true, true];
        let r = clear_free_space(&mut nodes, &known, &|p| e.sight(p).allows_hidden());
        assert_eq!((r.found, r.left, r.runs_moved), (2, 0, 1), "{r:?}");
        assert!(nodes[2..4].iter().all(|p| e.sight(p).allows_hidden()));
        // Nothing in free space: nothing moves.
        let mut again = nodes.clone();
        let r = clear_free_space(&mut again, &known, &|p| e.sight(p).allows_hidden());
        assert_eq!((r.found, r.runs_moved), (0, 0));
        assert_eq!(again, nodes);
    }
}
