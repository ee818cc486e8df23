//! Node visibility (the paper's Fig. 3): a node is visible when at least
//! `V_lim` points of the current cloud lie within `r_vis` of its previous
//! position. Every algorithm shares it: the tracker's loss test, and the
//! hidden nodes UPETrack's step estimates.

use alloc::vec::Vec;

use crate::math::Vec3;

/// Number of points strictly within `radius` of `node` (`q` in the paper).
pub fn neighbour_count(node: &Vec3, cloud: &[Vec3], radius: f64) -> usize {
    let r2 = radius * radius;
    cloud
        .iter()
        .filter(|x| (*x - node).norm_squared() < r2)
        .count()
}

/// Visibility of each node: `q >= V_lim` for `q` points within `r_vis`
/// (`radius`) of its previous position.
pub fn visible_nodes(
    previous: &[Vec3],
    cloud: &[Vec3],
    radius: f64,
    min_points: usize,
) -> Vec<bool> {
    visible_nodes_relative(previous, cloud, radius, min_points, 0.0)
}

/// Visibility with a relative test added: `q >= V_lim` and
/// `q >= min_fraction * median(q)`, the median over the nodes with
/// `q >= V_lim`. A node at the edge of an occlusion sees only part of its
/// usual neighbourhood and fails the second test; `min_fraction = 0` is the
/// paper's rule alone.
pub fn visible_nodes_relative(
    previous: &[Vec3],
    cloud: &[Vec3],
    radius: f64,
    min_points: usize,
    min_fraction: f64,
) -> Vec<bool> {
    classify_nodes(previous, cloud, radius, min_points, min_fraction).visible
}

/// The nodes by what the cloud shows of them.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct NodeVisibility {
    /// Cloud points within `r_vis` of each node (`q`).
    pub counts: Vec<usize>,
    /// Visible under [`visible_nodes_relative`]'s two tests.
    pub visible: Vec<bool>,
    /// Hidden by the relative test alone: `q >= V_lim`, but below the
    /// fraction of the median.
    pub partly_seen: Vec<bool>,
}

/// [`visible_nodes_relative`], also telling which hidden nodes passed the
/// paper's test (`q >= V_lim`) and failed only the relative one.
pub fn classify_nodes(
    previous: &[Vec3],
    cloud: &[Vec3],
    radius: f64,
    min_points: usize,
    min_fraction: f64,
) -> NodeVisibility {
    let counts: Vec<usize> = previous
        .iter()
        .map(|y| neighbour_count(y, cloud, radius))
        .collect();
    let mut seen: Vec<usize> = counts
        .iter()
        .copied()
        .filter(|&q| q >= min_points)
        .collect();
    let threshold = if seen.is_empty() || !(min_fraction > 0.0) {
        min_points as f64
    } else {
        seen.sort_unstable();
        (min_fraction * seen[seen.len() / 2] as f64).max(min_points as f64)
    };
    let visible: Vec<bool> = counts.iter().map(|&q| q as f64 >= threshold).collect();
    let partly_seen = counts
        .iter()
        .zip(&visible)
        .map(|(&q, &v)| !v && q >= min_points)
        .collect();
    NodeVisibility {
        counts,
        visible,
        partly_seen,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;

    #[test]
    fn a_node_hidden_by_the_relative_test_alone_is_partly_seen() {
        let nodes = vec![
            Vec3::zeros(),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(3.0, 0.0, 0.0),
        ];
        let mut cloud = Vec::new();
        for (node, count) in [(0.0, 10), (1.0, 10), (2.0, 3)] {
            cloud.extend((0..count).map(|i| Vec3::new(node + 0.001 * i as f64, 0.0, 0.0)));
        }
        let c = classify_nodes(&nodes, &cloud, 0.02, 3, 0.5);
        assert_eq!(c.visible, [true, true, false, false]);
        // Three points pass the paper's test; no points at all do not.
        assert_eq!(c.partly_seen, [false, false, true, false]);
        assert_eq!(
            c.visible,
            visible_nodes_relative(&nodes, &cloud, 0.02, 3, 0.5)
        );
    }

    #[test]
    fn counts_against_the_threshold() {
        let cloud = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.01, 0.0, 0.0),
            Vec3::new(0.019, 0.0, 0.0),
            Vec3::new(0.02, 0.0, 0.0), // on the radius: not within
            Vec3::new(1.0, 0.0, 0.0),
        ];
        let nodes = vec![Vec3::zeros(), Vec3::new(1.0, 0.0, 0.0)];
        assert_eq!(neighbour_count(&nodes[0], &cloud, 0.02), 3);
        assert_eq!(visible_nodes(&nodes, &cloud, 0.02, 3), vec![true, false]);
        assert_eq!(visible_nodes(&nodes, &cloud, 0.02, 1), vec![true, true]);
        assert_eq!(visible_nodes(&nodes, &[], 0.02, 1), vec![false, false]);
    }

    #[test]
    fn relative_test_hides_nodes_with_a_partial_neighbourhood() {
        // The defaults: r_vis 20 mm, V_lim 3, relative fraction 0.5.
        let p = crate::params::Params::default();
        let (r, v, f) = (
            p.visibility_radius,
            p.visibility_min_points as usize,
            p.visibility_min_fraction,
        );
        assert_eq!((r, v, f), (0.020, 3, 0.5));
        // Points every 1 mm up to x = 0.100 m (an occluder beyond), nodes on
        // the line: q = 40 for the nodes in full view, 24 for the node
        // 4 mm inside the edge, 5 for the node 15.5 mm past it.
        let cloud: Vec<Vec3> = (0..=100)
            .map(|i| Vec3::new(i as f64 * 0.001, 0.0, 0.0))
            .collect();
        let nodes: Vec<Vec3> = [0.026, 0.061, 0.096, 0.1155, 0.150]
            .iter()
            .map(|&x| Vec3::new(x, 0.0, 0.0))
            .collect();
        let q: Vec<usize> = nodes
            .iter()
            .map(|y| neighbour_count(y, &cloud, r))
            .collect();
        assert_eq!(q, vec![40, 40, 24, 5, 0]);
        // The paper's rule keeps the node past the edge visible (5 >= V_lim) ...
        assert_eq!(
            visible_nodes_relative(&nodes, &cloud, r, v, 0.0),
            vec![true, true, true, true, false]
        );
        // ... the relative test at its default hides it (5 < 0.5 x 40) and
        // keeps the one still mostly in view (24 >= 20).
        assert_eq!(
            visible_nodes_relative(&nodes, &cloud, r, v, f),
            vec![true, true, true, false, false]
        );
        assert_eq!(visible_nodes_relative(&nodes, &[], r, v, f), vec![false; 5]);
    }
}
