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
    previous
        .iter()
        .map(|y| neighbour_count(y, cloud, radius) >= min_points)
        .collect()
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
}
