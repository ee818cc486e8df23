//! Node visibility (the paper's Fig. 3): a node is visible when at least
//! `V_lim` points of the current cloud lie within `r_vis` of its previous
//! position. Every algorithm shares it: the tracker's loss test, and the
//! hidden nodes UPETrack's step estimates. UPETrack also hides a node
//! lying under another stretch of the rope where it crosses itself.

use alloc::vec::Vec;

use crate::math::{Vec2, Vec3};
use crate::perception::camera::CameraIntrinsics;

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

/// `true` when more than half of the nodes are `visible`: the state sees
/// most of its rope and is mostly right where it sees it; a state that
/// sees less is a guess.
pub fn sees_most(visible: &[bool]) -> bool {
    2 * visible.iter().filter(|&&v| v).count() > visible.len()
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

/// Nodes that lie under another stretch of the rope where it crosses
/// itself. A node's disc in the image (the rope's radius at its depth)
/// overlaps a stretch far enough away along the rope to cross it
/// ([`MIN_STRAND_GAP_NODES`] nodes and [`MIN_LOOP_DIAMETERS`] diameters),
/// the two cross at an angle, and the rope measured along the node's own
/// stretch a little beyond the crossing (`rope_depth`, the depth of the
/// rope's pixels around an image point) lies more than a radius deeper
/// than along the other stretch: there the images show the other stretch
/// only. The tracked depths are not read: near a crossing EM has mixed
/// them.
pub fn under_other_strand(
    nodes: &[Vec3],
    camera: &CameraIntrinsics,
    radius: f64,
    rope_depth: &dyn Fn(Vec2) -> Option<f64>,
) -> Vec<bool> {
    let m = nodes.len();
    let mut under = alloc::vec![false; m];
    if !(radius > 0.0) || m < MIN_STRAND_GAP_NODES + 2 {
        return under;
    }
    let focal = 0.5 * (camera.fx + camera.fy);
    let projected: Vec<Option<Vec2>> = nodes.iter().map(|p| camera.project(p)).collect();
    let unit = |v: Vec2| (v.norm() > 0.0).then(|| v / v.norm());
    let direction = |i: usize| {
        let (a, b) = (
            projected[i.saturating_sub(1)]?,
            projected[(i + 1).min(m - 1)]?,
        );
        unit(b - a)
    };
    // Each segment's start, unit direction and length in the image.
    let segments: Vec<Option<(Vec2, Vec2, f64)>> = (0..m - 1)
        .map(|j| {
            let (b0, b1) = (projected[j]?, projected[j + 1]?);
            let d = unit(b1 - b0)?;
            Some((b0, d, (b1 - b0).norm()))
        })
        .collect();
    // The segments by the x of their middles, and the largest reach
    // across x a segment can have from a node's disc: half the longest
    // segment and the largest disc.
    let mut by_x: Vec<(f64, usize)> = segments
        .iter()
        .enumerate()
        .filter_map(|(j, s)| s.map(|(b0, d, l)| ((b0 + d * (0.5 * l)).x, j)))
        .collect();
    by_x.sort_unstable_by(|p, q| p.0.total_cmp(&q.0));
    let half_longest = segments
        .iter()
        .flatten()
        .fold(0.0, |h: f64, s| h.max(0.5 * s.2));
    let nearest = nodes
        .iter()
        .map(|p| p.z)
        .filter(|z| *z > 0.0)
        .fold(f64::INFINITY, f64::min);
    let r_max = radius * focal / nearest;
    // Arc length to each node, for the shortest loop between two stretches.
    let mut arc = Vec::with_capacity(m);
    arc.push(0.0);
    for w in nodes.windows(2) {
        arc.push(arc[arc.len() - 1] + (w[1] - w[0]).norm());
    }
    let loop_length = MIN_LOOP_DIAMETERS * 2.0 * radius;
    let mean_depth = |at: Vec2, d: Vec2, reach: f64| {
        let (sum, n) = [at + d * reach, at - d * reach]
            .into_iter()
            .filter_map(rope_depth)
            .fold((0.0, 0), |(s, n), z| (s + z, n + 1));
        (n > 0).then(|| sum / n as f64)
    };
    for i in 0..m {
        let (Some(a), Some(da)) = (projected[i], direction(i)) else {
            continue;
        };
        let r_i = radius * focal / nodes[i].z;
        let apart = |j: usize| {
            let nodes_apart = j + 1 + MIN_STRAND_GAP_NODES <= i || j >= i + MIN_STRAND_GAP_NODES;
            let along = if j < i {
                arc[i] - arc[j + 1]
            } else {
                arc[j] - arc[i]
            };
            nodes_apart && along >= loop_length
        };
        // Only the segments whose middles lie within reach across x.
        let reach_x = half_longest + r_i + r_max;
        let first = by_x.partition_point(|&(x, _)| x < a.x - reach_x);
        let near = by_x[first..]
            .iter()
            .take_while(|&&(x, _)| x <= a.x + reach_x);
        under[i] = near.map(|&(_, j)| j).filter(|&j| apart(j)).any(|j| {
            let Some((b0, db, length)) = segments[j] else {
                return false;
            };
            let t = (a - b0).dot(&db).clamp(0.0, length);
            let c = b0 + db * t;
            let z_c = nodes[j].z + (nodes[j + 1].z - nodes[j].z) * t / length;
            if !(z_c > 0.0) {
                return false;
            }
            let r_c = radius * focal / z_c;
            let sin = da.x * db.y - da.y * db.x;
            if (a - c).norm() >= r_i + r_c || libm::fabs(sin) < MIN_CROSSING_SINE {
                return false;
            }
            // Where the two stretches' lines meet.
            let s = ((c - a).x * db.y - (c - a).y * db.x) / sin;
            let x = a + da * s;
            let reach = CROSSING_PROBE_RADII * r_i.max(r_c);
            match (mean_depth(x, da, reach), mean_depth(x, db, reach)) {
                (Some(own), Some(other)) => own > other + radius,
                _ => false,
            }
        });
    }
    under
}

/// Fewest nodes between a node and a stretch of the rope that may lie
/// over it ([`under_other_strand`]): its neighbours' segments touch it.
pub const MIN_STRAND_GAP_NODES: usize = 2;

/// Shortest rope between two stretches that cross, in the rope's
/// diameters: to lie over itself a rope turns a whole loop, whose
/// perimeter is at least pi diameters (its bend at least a radius); closer
/// along the rope, nodes are one stretch however many there are (at 400
/// nodes every node's disc covered a dozen neighbours' segments).
pub const MIN_LOOP_DIAMETERS: f64 = core::f64::consts::PI;

/// Two stretches meeting at a smaller angle (sine) run side by side.
pub const MIN_CROSSING_SINE: f64 = 0.5;

/// How far from a crossing each stretch is measured, in the rope's
/// radius in the image: beyond the other stretch's half width.
pub const CROSSING_PROBE_RADII: f64 = 2.5;

/// Half side, pixels, of the window whose rope pixels give the depth at a
/// probe beside a crossing (their median).
pub const CROSSING_DEPTH_WINDOW_PX: i64 = 1;

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

    /// A rope crossing itself seen from 1 m: stretch A along x at depth
    /// `z_a`, a detour far from the crossing, stretch B along y at `z_b`;
    /// nodes 5 cm apart, A's and B's middle nodes both at the crossing.
    fn crossing(z_a: f64, z_b: f64) -> Vec<Vec3> {
        let mut nodes: Vec<Vec3> = (-2..=2)
            .map(|k| Vec3::new(0.05 * k as f64, 0.0, z_a))
            .collect();
        nodes.extend([
            Vec3::new(0.15, 0.05, 1.0),
            Vec3::new(0.15, 0.15, 1.0),
            Vec3::new(0.05, 0.15, 1.0),
        ]);
        nodes.extend((-2..=2).rev().map(|k| Vec3::new(0.0, 0.05 * k as f64, z_b)));
        nodes
    }

    fn camera() -> CameraIntrinsics {
        CameraIntrinsics {
            width: 640,
            height: 480,
            fx: 600.0,
            fy: 600.0,
            cx: 320.0,
            cy: 240.0,
        }
    }

    /// The depth of the rope's surface seen at an image point: A's where
    /// A covers it (within a radius of y = 0), else B's (within a radius
    /// of x = 0), else nothing.
    fn surface(z_a: f64, z_b: f64, radius: f64) -> impl Fn(Vec2) -> Option<f64> {
        let cam = camera();
        move |at: Vec2| {
            let z_a_surface = z_a - radius;
            let on_a = ((at.y - cam.cy) * z_a_surface / cam.fy).abs() < radius;
            let on_b = ((at.x - cam.cx) * (z_b - radius) / cam.fx).abs() < radius;
            if on_a {
                Some(z_a_surface)
            } else if on_b {
                Some(z_b - radius)
            } else {
                None
            }
        }
    }

    #[test]
    fn the_node_under_the_stretch_on_top_is_hidden_and_the_one_on_top_is_not() {
        let radius = 0.0075;
        // A on top (1.5 cm nearer): B's node at the crossing is under it.
        let nodes = crossing(0.985, 1.0);
        let under = under_other_strand(&nodes, &camera(), radius, &surface(0.985, 1.0, radius));
        let flagged: Vec<usize> = (0..nodes.len()).filter(|&i| under[i]).collect();
        assert_eq!(flagged, vec![10]);
        // B on top: A's middle node is.
        let nodes = crossing(1.0, 0.985);
        let under = under_other_strand(&nodes, &camera(), radius, &surface(1.0, 0.985, radius));
        let flagged: Vec<usize> = (0..nodes.len()).filter(|&i| under[i]).collect();
        assert_eq!(flagged, vec![2]);
    }

    #[test]
    fn the_images_not_the_tracked_depths_say_which_stretch_is_on_top() {
        let radius = 0.0075;
        // The tracked nodes say B is on top, the images say A is: B's node
        // is hidden (near a crossing EM mixes the tracked depths).
        let nodes = crossing(1.0, 0.99);
        let under = under_other_strand(&nodes, &camera(), radius, &surface(0.985, 1.0, radius));
        assert!(under[10] && !under[2]);
        // Stretches less than a radius apart in depth: neither.
        let under = under_other_strand(&nodes, &camera(), radius, &surface(0.996, 1.0, radius));
        assert!(!under.contains(&true));
    }

    #[test]
    fn nodes_closer_along_the_rope_than_a_loop_are_one_stretch() {
        // 18 nodes a quarter radius apart round half a bend of one and a
        // half radii, 1 m away, over a surface whose depth curves steeply:
        // nodes a few apart overlap and meet at an angle, but no rope
        // crosses itself in less than a loop.
        let radius = 0.0075;
        let bend = 1.5 * radius;
        let nodes: Vec<Vec3> = (0..18)
            .map(|k| {
                let angle = 0.25 * radius * k as f64 / bend;
                Vec3::new(bend * libm::cos(angle), bend * libm::sin(angle), 1.0)
            })
            .collect();
        let (cx, cy) = (camera().cx, camera().cy);
        // Deeper along x than along y: probes along a stretch that runs
        // closer to x read deeper.
        let steep = |at: Vec2| Some(1.0 + 1e-3 * ((at.x - cx).powi(2) - (at.y - cy).powi(2)));
        assert!(!under_other_strand(&nodes, &camera(), radius, &steep).contains(&true));
    }

    #[test]
    fn stretches_side_by_side_or_without_depth_hide_nothing() {
        let radius = 0.0075;
        // B turned to run beside A (20 degrees apart): no crossing.
        let mut nodes = crossing(0.985, 1.0);
        for (k, p) in nodes[8..].iter_mut().enumerate() {
            let t = 0.05 * (2.0 - k as f64);
            *p = Vec3::new(t * 0.94, t * 0.34, 1.0);
        }
        // Measured deeper along B's direction from where the two lines
        // meet, nearer along A's: at 20 degrees that is no crossing.
        let (cx, cy) = (camera().cx, camera().cy);
        let by_direction = |at: Vec2| {
            let angle = libm::atan2(at.y - cy, at.x - cx).abs();
            let along_b =
                (angle - 0.35).abs() < 0.1 || (angle - (core::f64::consts::PI - 0.35)).abs() < 0.1;
            Some(if along_b {
                1.0 - radius
            } else {
                0.985 - radius
            })
        };
        assert!(!under_other_strand(&nodes, &camera(), radius, &by_direction).contains(&true));
        let depth = surface(0.985, 1.0, radius);
        // No rope pixels with depth around the crossing.
        let nodes = crossing(0.985, 1.0);
        assert!(!under_other_strand(&nodes, &camera(), radius, &|_| None).contains(&true));
        // Bad input: nothing, and no panic.
        let mut bad = nodes.clone();
        bad[10] = Vec3::new(f64::NAN, 0.0, 1.0);
        bad[2].z = -1.0;
        let _ = under_other_strand(&bad, &camera(), radius, &depth);
        assert!(!under_other_strand(&nodes, &camera(), f64::NAN, &depth).contains(&true));
        assert!(under_other_strand(&[], &camera(), radius, &depth).is_empty());
    }
}
