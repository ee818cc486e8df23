//! TrackDLO's node visibility: a cloud point within `tau_vis` and no nearer
//! part of the rope covering the node in the image (self-occlusion), then
//! short gaps along the rope filled.

use alloc::vec;
use alloc::vec::Vec;

use super::settings::{TrackDloParams, REFERENCE_IMAGE_WIDTH};
use crate::math::{self, Vec2, Vec3};
use crate::perception::camera::CameraIntrinsics;

/// Visibility of each node (`tau_vis` and the self-occlusion test): a node
/// is visible when a cloud point lies within `visibility_threshold` and no
/// part of the rope nearer the camera covers it in the image. Edges are
/// taken nearest first; a node is covered when its pixel lies within half
/// the projected rope width of an edge taken before its own nearer edge.
pub fn node_visibility(
    nodes: &[Vec3],
    cloud: &[Vec3],
    camera: &CameraIntrinsics,
    params: &TrackDloParams,
) -> Vec<bool> {
    let m = nodes.len();
    let t2 = params.visibility_threshold * params.visibility_threshold;
    let near: Vec<bool> = nodes
        .iter()
        .map(|y| cloud.iter().any(|x| (x - y).norm_squared() <= t2))
        .collect();
    let pixels: Vec<Option<Vec2>> = nodes.iter().map(|y| camera.project(y)).collect();
    let half_width = 0.5 * params.dlo_pixel_width * f64::from(camera.width) / REFERENCE_IMAGE_WIDTH;
    // Edges by distance of their midpoints from the camera, nearest first.
    let mut order: Vec<usize> = (0..m.saturating_sub(1)).collect();
    let depth = |e: usize| math::norm(&((nodes[e] + nodes[e + 1]) * 0.5));
    order.sort_by(|&a, &b| depth(a).total_cmp(&depth(b)).then(a.cmp(&b)));
    let mut checked = vec![false; m];
    let mut visible = vec![false; m];
    for (rank, &e) in order.iter().enumerate() {
        for node in [e, e + 1] {
            if checked[node] {
                continue;
            }
            checked[node] = true;
            let covered = pixels[node].is_some_and(|p| {
                order[..rank]
                    .iter()
                    .any(|&f| match (pixels[f], pixels[f + 1]) {
                        (Some(a), Some(b)) => point_segment_distance(&p, &a, &b) <= half_width,
                        _ => false,
                    })
            });
            visible[node] = near[node] && pixels[node].is_some() && !covered;
        }
    }
    if m == 1 {
        visible[0] = near[0];
    }
    visible
}

fn point_segment_distance(p: &Vec2, a: &Vec2, b: &Vec2) -> f64 {
    let t = math::nearest_on_segment(p, a, b);
    (p - (a + (b - a) * t)).norm()
}

/// Visible nodes with short gaps filled: the nodes between two visible nodes
/// at most `d_vis` apart along the rope (rest coordinates `rest`) count as visible.
pub fn extend_visible(visible: &[bool], rest: &[f64], d_vis: f64) -> Vec<bool> {
    let mut out = visible.to_vec();
    let seen: Vec<usize> = (0..visible.len()).filter(|&i| visible[i]).collect();
    for pair in seen.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        if b > a + 1 && (rest[b] - rest[a]).abs() <= d_vis {
            out[a..b].iter_mut().for_each(|v| *v = true);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::testing::mask;
    use super::*;

    #[test]
    fn short_gaps_are_filled_and_long_ones_kept() {
        let rest: Vec<f64> = (0..10).map(|i| i as f64 * 0.015).collect();
        let v = mask(10, &[3, 4, 7]);
        let e = extend_visible(&v, &rest, 0.06);
        assert_eq!(e, vec![true; 10]);
        let v = mask(10, &[2, 3, 4, 5, 6]);
        assert_eq!(extend_visible(&v, &rest, 0.06), v);
    }
    #[test]
    fn a_node_behind_a_nearer_part_of_the_rope_is_not_visible() {
        let camera = CameraIntrinsics::D435I_640X480;
        // A rope crossing over itself: the middle passes 5 cm nearer the
        // camera over the line of the first part.
        let mut nodes: Vec<Vec3> = (0..5)
            .map(|i| Vec3::new(-0.04 + i as f64 * 0.02, 0.0, 0.6))
            .collect();
        nodes.extend((0..5).map(|i| Vec3::new(0.0, -0.04 + i as f64 * 0.02, 0.55)));
        let cloud = nodes.clone();
        let v = node_visibility(&nodes, &cloud, &camera, &TrackDloParams::default());
        // Node 2 (0, 0, 0.6) lies under node 7 (0, 0, 0.55).
        assert!(!v[2]);
        assert!(v[7] && v[0] && v[9]);
        // Without the nearer part, node 2 is visible.
        let v = node_visibility(&nodes[..5], &cloud, &camera, &TrackDloParams::default());
        assert!(v.iter().all(|&b| b));
    }
}
