//! Visible nodes reported on their bend's arc (this project's addition
//! after the M-step, Eq. 5): EM puts a node at the mean of the rope points
//! it explains, about one node spacing of rope centred on it. On a bend
//! those points lie on an arc, and an arc's centroid lies inside it: a
//! node on a bend of radius `R` explaining an arc of length `s` sits
//! `R (1 - sin(theta) / theta)` inside it, `theta = s / (2 R)`, about
//! `s^2 / (24 R)` (1 mm for a 35 mm spacing on a bend of 5 cm). The
//! reported nodes are moved back out by that much; the tracker's state
//! stays EM's, so the move never feeds the next frame (moved in the state,
//! it grew a zigzag of alternate nodes and shifted the anchors of hidden
//! runs: `docs/algorithm-notes.md`, "Nodes on their bends").

use alloc::vec::Vec;

use crate::math::{self, Vec3};

/// How far the centroid of a circular arc of radius `radius` and length
/// `length` lies inside the arc's midpoint, towards the centre.
pub fn arc_centroid_depth(radius: f64, length: f64) -> f64 {
    let theta = 0.5 * length / radius;
    if !(theta > 1e-9) {
        return 0.0;
    }
    radius * (1.0 - libm::sin(theta) / theta)
}

/// The circle through three points: its centre and radius, `None` for
/// points (nearly) on a line.
pub fn circle_through(a: &Vec3, b: &Vec3, c: &Vec3) -> Option<(Vec3, f64)> {
    let (u, v) = (a - b, c - b);
    let w = u.cross(&v);
    let w2 = w.dot(&w);
    if !(w2 > math::LENGTH_EPSILON * math::LENGTH_EPSILON * u.dot(&u).max(v.dot(&v))) {
        return None;
    }
    // Circumcentre relative to b.
    let centre = (v * u.dot(&u) - u * v.dot(&v)).cross(&w) / (2.0 * w2);
    let radius = math::norm(&centre);
    Some((b + centre, radius))
}

/// Moves each node that is flagged in `registered` (placed by EM this
/// frame) and has two neighbours outwards from the circle through the
/// three, by the depth of the centroid of the arc it explains (half of
/// each chord to a neighbour). A hidden neighbour's estimate tells the
/// bend as well as a seen one's. The moves are measured on the nodes as
/// given, not on nodes already moved. Returns how many nodes moved.
pub fn onto_arcs(nodes: &mut [Vec3], registered: &[bool]) -> usize {
    let m = nodes.len();
    if m < 3 || registered.len() != m || !nodes.iter().all(math::is_finite) {
        return 0;
    }
    let chord = |k: usize| math::norm(&(nodes[k + 1] - nodes[k]));
    let moves: Vec<(usize, Vec3)> = (1..m - 1)
        .filter(|&i| registered[i])
        .filter_map(|i| {
            let (centre, radius) = circle_through(&nodes[i - 1], &nodes[i], &nodes[i + 1])?;
            // Chords no longer than the circle's diameter: `theta` stays
            // under a radian, however tight the bend.
            let explained = 0.5 * (chord(i - 1) + chord(i));
            let out = (nodes[i] - centre) / radius;
            Some((i, nodes[i] + out * arc_centroid_depth(radius, explained)))
        })
        .collect();
    let moved = moves.len();
    for (i, p) in moves {
        if math::is_finite(&p) {
            nodes[i] = p;
        }
    }
    moved
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;

    /// `count` points `step` radians apart from angle 0 on a circle of
    /// radius `r - inset` about the origin, in the plane z = 0.6.
    fn on_circle(r: f64, count: usize, step: f64, inset: f64) -> Vec<Vec3> {
        (0..count)
            .map(|k| {
                let a = step * k as f64;
                Vec3::new((r - inset) * libm::cos(a), (r - inset) * libm::sin(a), 0.6)
            })
            .collect()
    }

    fn radius_of(p: &Vec3) -> f64 {
        libm::hypot(p.x, p.y)
    }

    #[test]
    fn an_arc_s_centroid_lies_inside_it_by_the_known_depth() {
        // A half circle of radius 1: centroid at 2 / pi from the centre.
        let depth = arc_centroid_depth(1.0, core::f64::consts::PI);
        assert!((depth - (1.0 - 2.0 / core::f64::consts::PI)).abs() < 1e-12);
        // Small angles: about s^2 / (24 R) (1.021 mm; exactly 1.015 mm).
        let d = arc_centroid_depth(0.05, 0.035);
        assert!((d - 0.035 * 0.035 / (24.0 * 0.05)).abs() < 2e-5, "{d}");
        assert!((d - 0.001_015).abs() < 1e-6, "{d}");
        assert_eq!(arc_centroid_depth(0.05, 0.0), 0.0);
    }

    #[test]
    fn the_centroids_of_arcs_of_a_bend_are_moved_back_onto_it() {
        // Nodes 35 mm apart on a bend of 5 cm, each at the centroid of the
        // arc it explains (1 mm inside).
        let (r, s) = (0.05, 0.035);
        let depth = arc_centroid_depth(r, s);
        let mut nodes = on_circle(r, 5, s / r, depth);
        assert_eq!(onto_arcs(&mut nodes, &[true; 5]), 3);
        for p in &nodes[1..4] {
            // Back on the bend within a tenth of the move (the circle
            // through the inset nodes is a little tighter than the bend).
            assert!((radius_of(p) - r).abs() < 0.1 * depth, "{}", radius_of(p));
        }
        // The ends have one neighbour: not moved.
        assert!((radius_of(&nodes[0]) - (r - depth)).abs() < 1e-12);
        assert!((radius_of(&nodes[4]) - (r - depth)).abs() < 1e-12);
    }

    #[test]
    fn only_registered_nodes_with_two_neighbours_move() {
        let before = on_circle(0.05, 5, 0.7, 0.0);
        let mut nodes = before.clone();
        // Nodes 1 and 2 placed by EM (node 1 beside a hidden node 0); 3
        // hidden, 0 and 4 at the ends.
        assert_eq!(onto_arcs(&mut nodes, &[true, true, true, false, true]), 2);
        assert!(radius_of(&nodes[1]) > 0.05);
        assert!(radius_of(&nodes[2]) > 0.05);
        assert_eq!(nodes[3], before[3]);
        assert_eq!(nodes[0], before[0]);
        assert_eq!(nodes[4], before[4]);
    }

    #[test]
    fn straight_lines_and_bad_input_are_left_and_a_hairpin_moves_less_than_its_radius() {
        let mut line: Vec<Vec3> = (0..5)
            .map(|k| Vec3::new(0.01 * k as f64, 0.0, 0.6))
            .collect();
        let before = line.clone();
        assert_eq!(onto_arcs(&mut line, &[true; 5]), 0);
        assert_eq!(line, before);
        let mut bend = on_circle(0.05, 5, 0.7, 0.0);
        assert_eq!(
            onto_arcs(&mut bend, &[true; 3]),
            0,
            "flags of another length"
        );
        let mut bad = vec![Vec3::new(f64::NAN, 0.0, 0.6); 4];
        assert_eq!(onto_arcs(&mut bad, &[true; 4]), 0);
        let mut doubled = vec![Vec3::new(0.0, 0.0, 0.6); 3];
        assert_eq!(onto_arcs(&mut doubled, &[true; 3]), 0, "coincident nodes");
        // A hairpin narrower than a spacing (nodes 3 rad apart on a 1 cm
        // circle): moved out by less than the bend's radius.
        let mut hairpin = on_circle(0.01, 3, 3.0, 0.0);
        assert_eq!(onto_arcs(&mut hairpin, &[true; 3]), 1);
        assert!(radius_of(&hairpin[1]) < 0.02, "{}", radius_of(&hairpin[1]));
    }
}
