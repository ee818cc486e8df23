//! Node visibility (Fig. 3): a node is visible when at least `V_lim` points
//! of the current cloud lie within `r_vis` of its previous position.

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
    counts.iter().map(|&q| q as f64 >= threshold).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;

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
        // Three nodes on a line of points spaced 1 mm; the last line stops at
        // the third node, which sees half as many points as the others.
        let cloud: Vec<Vec3> = (0..=60)
            .map(|i| Vec3::new(i as f64 * 0.001, 0.0, 0.0))
            .collect();
        let nodes = vec![
            Vec3::new(0.015, 0.0, 0.0),
            Vec3::new(0.035, 0.0, 0.0),
            Vec3::new(0.060, 0.0, 0.0),
        ];
        // q = 19, 19, 10 within 10 mm.
        assert_eq!(
            visible_nodes_relative(&nodes, &cloud, 0.01, 3, 0.0),
            vec![true, true, true]
        );
        assert_eq!(
            visible_nodes_relative(&nodes, &cloud, 0.01, 3, 0.75),
            vec![true, true, false]
        );
        assert_eq!(
            visible_nodes_relative(&nodes, &[], 0.01, 3, 0.75),
            vec![false, false, false]
        );
    }
}
