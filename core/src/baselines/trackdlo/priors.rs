//! TrackDLO's correspondence priors: which of its five occlusion cases
//! holds, then walks along the pre-registered visible ("guide") nodes at the
//! rest spacing (pure pursuit), from one or both ends.

use alloc::vec;
use alloc::vec::Vec;

use crate::math::{self, Vec3};

/// A crossing this far (in segment fractions) past a segment's end still
/// counts as on it, so that rounding cannot stop a walk at a guide node.
const ROOT_SLACK: f64 = 1e-9;
/// Which part of the rope is hidden: TrackDLO's five cases. The first node
/// is the head, the last the tail.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OcclusionCase {
    /// Every node visible (after short gaps are filled).
    None,
    /// Both ends visible, a middle part hidden.
    MidSection,
    /// The head visible, the tail hidden.
    Tail,
    /// The tail visible, the head hidden.
    Head,
    /// Both ends hidden.
    BothEnds,
}

/// The case of a visibility pattern, `None` when no node is visible.
pub fn occlusion_case(visible: &[bool]) -> Option<OcclusionCase> {
    let (&head, &tail) = (visible.first()?, visible.last()?);
    if !visible.iter().any(|&v| v) {
        return None;
    }
    Some(match (head, tail) {
        _ if visible.iter().all(|&v| v) => OcclusionCase::None,
        (true, true) => OcclusionCase::MidSection,
        (true, false) => OcclusionCase::Tail,
        (false, true) => OcclusionCase::Head,
        (false, false) => OcclusionCase::BothEnds,
    })
}

/// A correspondence prior: node `node` should be at `position`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prior {
    /// Node index.
    pub node: usize,
    /// Where the walk along the guide nodes placed it, metres.
    pub position: Vec3,
}

/// Where the sphere of radius `r` around `c` leaves the segment `a -> b`
/// going forward, if it does.
fn sphere_exit(a: &Vec3, b: &Vec3, c: &Vec3, r: f64) -> Option<Vec3> {
    let d = b - a;
    let f = a - c;
    let qa = d.norm_squared();
    if !(qa > math::LENGTH_EPSILON) {
        return None;
    }
    let qb = 2.0 * f.dot(&d);
    let qc = f.norm_squared() - r * r;
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 {
        return None;
    }
    let root = math::sqrt(disc);
    let t = [(-qb + root) / (2.0 * qa), (-qb - root) / (2.0 * qa)]
        .into_iter()
        .filter(|t| (-ROOT_SLACK..=1.0 + ROOT_SLACK).contains(t))
        .fold(None, |best: Option<f64>, t| {
            Some(best.map_or(t, |b| b.max(t)))
        })?
        .clamp(0.0, 1.0);
    let q = a + d * t;
    // A crossing behind the current centre is not progress.
    (math::norm(&(b - q)) <= math::norm(&(b - c)) + math::LENGTH_EPSILON).then_some(q)
}

/// Walks from guide node `start` along the run of consecutive guide nodes
/// in one direction, placing nodes one rest spacing apart (pure pursuit on
/// the guide polyline): the priors of TrackDLO's `traverse_euclidean`.
/// `guide_nodes[k]` is the node index of guide position `guide[k]`.
pub fn walk_priors(
    guide: &[Vec3],
    guide_nodes: &[usize],
    rest: &[f64],
    start: usize,
    forward: bool,
) -> Vec<Prior> {
    let Some(&first) = guide_nodes.get(start) else {
        return Vec::new();
    };
    // The run of consecutive nodes from `start`, in walking order.
    let mut run = vec![guide[start]];
    let mut k = start;
    loop {
        let next = if forward {
            k.checked_add(1)
        } else {
            k.checked_sub(1)
        };
        let Some(next) = next.filter(|&n| n < guide.len()) else {
            break;
        };
        let step_ok = if forward {
            guide_nodes[next] == guide_nodes[k] + 1
        } else {
            guide_nodes[next] + 1 == guide_nodes[k]
        };
        if !step_ok {
            break;
        }
        run.push(guide[next]);
        k = next;
    }
    let m = rest.len();
    let mut priors = vec![Prior {
        node: first,
        position: guide[start],
    }];
    let mut centre = guide[start];
    let mut node = first;
    let mut segment = 0;
    while segment + 1 < run.len() {
        let next = if forward {
            if node + 1 >= m {
                break;
            }
            node + 1
        } else {
            let Some(n) = node.checked_sub(1) else {
                break;
            };
            n
        };
        let spacing = (rest[next] - rest[node]).abs();
        let found = (segment..run.len() - 1)
            .find_map(|i| sphere_exit(&run[i], &run[i + 1], &centre, spacing).map(|q| (i, q)));
        let Some((i, q)) = found else {
            break;
        };
        segment = i;
        centre = q;
        node = next;
        priors.push(Prior { node, position: q });
    }
    priors
}

/// Averages priors given twice for one node; returns them by node index.
fn merge_priors(m: usize, lists: &[Vec<Prior>]) -> Vec<Prior> {
    let mut sum = vec![Vec3::zeros(); m];
    let mut count = vec![0u32; m];
    for p in lists.iter().flatten() {
        if p.node < m {
            sum[p.node] += p.position;
            count[p.node] += 1;
        }
    }
    (0..m)
        .filter(|&i| count[i] > 0)
        .map(|i| Prior {
            node: i,
            position: sum[i] / f64::from(count[i]),
        })
        .collect()
}

/// The correspondence priors of one frame. `guide` are the pre-registered
/// positions of the nodes marked in `extended`; `previous` the nodes before
/// it (to find the node that moved least when both ends are hidden).
pub fn correspondence_priors(
    extended: &[bool],
    guide: &[Vec3],
    previous: &[Vec3],
    rest: &[f64],
) -> (Option<OcclusionCase>, Vec<Prior>) {
    let m = extended.len();
    let guide_nodes: Vec<usize> = (0..m).filter(|&i| extended[i]).collect();
    let case = occlusion_case(extended);
    let Some(last) = guide_nodes.len().checked_sub(1) else {
        return (case, Vec::new());
    };
    let walk = |start, forward| walk_priors(guide, &guide_nodes, rest, start, forward);
    let lists = match case {
        None => Vec::new(),
        Some(OcclusionCase::None | OcclusionCase::MidSection) => {
            vec![walk(0, true), walk(last, false)]
        }
        Some(OcclusionCase::Tail) => vec![walk(0, true)],
        Some(OcclusionCase::Head) => vec![walk(last, false)],
        Some(OcclusionCase::BothEnds) => {
            let moved = |k: usize| math::norm(&(previous[guide_nodes[k]] - guide[k]));
            let anchor = (0..guide_nodes.len())
                .min_by(|&a, &b| moved(a).total_cmp(&moved(b)))
                .unwrap_or(0);
            vec![walk(anchor, true), walk(anchor, false)]
        }
    };
    (case, merge_priors(m, &lists))
}

#[cfg(test)]
mod tests {
    use super::super::testing::{line, mask};
    use super::*;

    #[test]
    fn the_five_occlusion_cases_are_told_apart() {
        assert_eq!(occlusion_case(&mask(6, &[])), Some(OcclusionCase::None));
        assert_eq!(
            occlusion_case(&mask(6, &[2, 3])),
            Some(OcclusionCase::MidSection)
        );
        assert_eq!(occlusion_case(&mask(6, &[4, 5])), Some(OcclusionCase::Tail));
        assert_eq!(occlusion_case(&mask(6, &[0, 1])), Some(OcclusionCase::Head));
        assert_eq!(
            occlusion_case(&mask(6, &[0, 5])),
            Some(OcclusionCase::BothEnds)
        );
        assert_eq!(occlusion_case(&[false; 6]), None);
        assert_eq!(occlusion_case(&[]), None);
    }

    /// Priors of a hand-made case: 10 nodes at 2 cm rest spacing; the
    /// visible part has been pre-registered to `guide` (given for the nodes
    /// marked visible).
    fn priors_for(hidden: &[usize], guide_of: impl Fn(usize) -> Vec3) -> Vec<Prior> {
        let m = 10;
        let rest: Vec<f64> = (0..m).map(|i| i as f64 * 0.02).collect();
        let ext = mask(m, hidden);
        let previous = line(m, 0.02);
        let guide: Vec<Vec3> = (0..m).filter(|&i| ext[i]).map(&guide_of).collect();
        correspondence_priors(&ext, &guide, &previous, &rest).1
    }

    #[test]
    fn no_occlusion_priors_respace_a_slid_rope_at_rest_spacing() {
        // The visible rope moved 5 mm along itself and got 1 cm longer at
        // the tail: the walks from both ends place nodes 2 cm apart and
        // the merge averages them.
        let priors = priors_for(&[], |i| {
            Vec3::new(0.005 + i as f64 * 0.02 * (1.0 + 0.01 / 0.18), 0.0, 0.6)
        });
        assert_eq!(priors.len(), 10);
        // Head walk: 0.005 + 0.02 i; tail walk: 0.195 - 0.02 (9 - i).
        let head = priors[0].position.x;
        let tail = priors[9].position.x;
        assert!((head - 0.01).abs() < 1e-9 && (tail - 0.19).abs() < 1e-9);
        for w in priors.windows(2) {
            let gap = (w[1].position - w[0].position).norm();
            assert!((gap - 0.02).abs() < 1e-9, "gap {gap}");
        }
    }

    #[test]
    fn mid_section_priors_come_from_both_ends_and_stop_at_the_gap() {
        let priors = priors_for(&[4, 5, 6], |i| Vec3::new(i as f64 * 0.02, 0.01, 0.6));
        let nodes: Vec<usize> = priors.iter().map(|p| p.node).collect();
        assert_eq!(nodes, vec![0, 1, 2, 3, 7, 8, 9]);
        for p in &priors {
            assert!((p.position - Vec3::new(p.node as f64 * 0.02, 0.01, 0.6)).norm() < 1e-9);
        }
    }

    #[test]
    fn tail_occluded_priors_walk_from_the_head_only() {
        let priors = priors_for(&[6, 7, 8, 9], |i| Vec3::new(0.0, i as f64 * 0.02, 0.6));
        let nodes: Vec<usize> = priors.iter().map(|p| p.node).collect();
        assert_eq!(nodes, vec![0, 1, 2, 3, 4, 5]);
        assert!((priors[5].position.y - 0.10).abs() < 1e-9);
    }

    #[test]
    fn head_occluded_priors_walk_from_the_tail_only() {
        // The visible part is compressed (nodes 1.5 cm apart): walking at
        // the 2 cm rest spacing from the tail yields fewer priors than
        // visible nodes, none of them at a compressed spacing.
        let priors = priors_for(&[0, 1, 2, 3], |i| Vec3::new(i as f64 * 0.015, 0.0, 0.6));
        let nodes: Vec<usize> = priors.iter().map(|p| p.node).collect();
        assert_eq!(nodes, vec![6, 7, 8, 9]);
        assert!((priors[0].position.x - 0.075).abs() < 1e-9);
        for w in priors.windows(2) {
            assert!(((w[1].position - w[0].position).norm() - 0.02).abs() < 1e-9);
        }
    }

    #[test]
    fn both_ends_occluded_priors_grow_from_the_node_that_moved_least() {
        // Nodes 2..=7 visible; the guide moved 1 cm in y except node 4, which stayed.
        let priors = priors_for(&[0, 1, 8, 9], |i| {
            let dy = if i == 4 { 0.0 } else { 0.01 };
            Vec3::new(i as f64 * 0.02, dy, 0.6)
        });
        let nodes: Vec<usize> = priors.iter().map(|p| p.node).collect();
        assert!(nodes.contains(&4) && nodes.contains(&2) && nodes.contains(&7));
        let anchor = priors.iter().find(|p| p.node == 4).map(|p| p.position);
        assert_eq!(anchor, Some(Vec3::new(0.08, 0.0, 0.6)));
        assert!(nodes.iter().all(|&n| (2..=7).contains(&n)));
    }
}
