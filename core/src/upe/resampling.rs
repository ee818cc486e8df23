//! Node distance uniformisation (Eq. 12-15): resample the polyline through
//! the nodes into `count` nodes evenly spaced by arc length, first node kept;
//! or, this project's default, the smooth curve through the nodes.

use alloc::vec::Vec;

use crate::curve::RopeCurve;
use crate::math::Vec3;
use crate::polyline::{resample_uniform, spread};

pub use crate::curve::SMOOTH_PIECES;

/// [`resample_uniform`] along the centripetal Catmull-Rom curve through
/// `points` instead of their polyline (`crate::curve::RopeCurve`): the
/// curve passes through every node, so a node that resampling leaves in
/// place stays where it was, and one it moves along a bend stays on the
/// bend instead of on a chord, which repeated every frame would straighten
/// the bend (`docs/algorithm-notes.md`, "Resampling"). The ends are
/// continued straight for the curve's first and last pieces. Fewer than
/// three points, or a curve that is not finite, fall back to the polyline.
pub fn resample_smooth(points: &[Vec3], count: usize) -> Vec<Vec3> {
    if points.len() < 3 {
        return resample_uniform(points, count);
    }
    let curve = RopeCurve::smooth(points);
    spread(curve.pieces(), count, |q, t| curve.on_piece(q, t))
        .unwrap_or_else(|| resample_uniform(points, count))
}

/// [`resample_smooth`] when `smooth` (this project's default), else the
/// paper's [`resample_uniform`].
pub fn resample(points: &[Vec3], count: usize, smooth: bool) -> Vec<Vec3> {
    if smooth {
        resample_smooth(points, count)
    } else {
        resample_uniform(points, count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math;

    /// Nodes on a circle, resampled while the first node moves back and
    /// forth a quarter spacing along it (as EM moves an end node): on the
    /// polyline the nodes fall inside the circle by the chords' sagitta
    /// every time and the bend shrinks; on the smooth curve the nodes away
    /// from the moving end stay within a tenth of that.
    #[test]
    fn smooth_resampling_keeps_a_bend_that_the_polyline_cuts() {
        let radius = 0.1;
        let on_circle = |a: f64| Vec3::new(radius * libm::cos(a), radius * libm::sin(a), 0.6);
        let nodes: Vec<Vec3> = (0..12).map(|k| on_circle(0.35 * k as f64)).collect();
        // Largest distance from the circle of nodes 4.. (away from the moved end).
        let off = |ps: &[Vec3]| {
            ps[4..]
                .iter()
                .map(|p| (libm::hypot(p.x, p.y) - radius).abs())
                .fold(0.0, f64::max)
        };
        let (mut flat, mut smooth) = (nodes.clone(), nodes.clone());
        for step in 0..30 {
            let a = 0.35 * if step % 2 == 0 { 0.25 } else { -0.25 };
            flat[0] = on_circle(a);
            smooth[0] = on_circle(a);
            flat = resample_uniform(&flat, 12);
            smooth = resample_smooth(&smooth, 12);
        }
        let sagitta = radius * (1.0 - libm::cos(0.35 / 2.0));
        assert!(
            off(&flat) > 5.0 * sagitta,
            "polyline: {} m off the circle",
            off(&flat)
        );
        assert!(
            off(&smooth) < 0.1 * off(&flat),
            "smooth: {} m off, polyline {} m",
            off(&smooth),
            off(&flat)
        );
        // Nodes already evenly spaced on a straight line stay where they are.
        let line: Vec<Vec3> = (0..6)
            .map(|k| Vec3::new(0.01 * k as f64, 0.0, 0.5))
            .collect();
        for (a, b) in resample_smooth(&line, 6).iter().zip(&line) {
            assert!((a - b).norm() < 1e-12, "{a:?} vs {b:?}");
        }
    }

    /// One resampling of nodes on a bend, the first moved a little along
    /// it (as EM moves a visible node): the nodes must land on the curve,
    /// not on the chords of its pieces, which lie inside a bend by up to
    /// their sagitta (9.5 um here). Repeated every frame that shrank a
    /// hidden bend: 0.01 px a frame on static-s.
    #[test]
    fn smooth_resampling_puts_nodes_on_the_curve_not_on_its_chords() {
        let radius = 0.05;
        let on_circle = |a: f64| Vec3::new(radius * libm::cos(a), radius * libm::sin(a), 0.6);
        let mut nodes: Vec<Vec3> = (0..12).map(|k| on_circle(0.3 * k as f64)).collect();
        nodes[0] = on_circle(0.03);
        let out = resample_smooth(&nodes, 12);
        let inside = out[2..10]
            .iter()
            .map(|p| radius - libm::hypot(p.x, p.y))
            .fold(0.0, f64::max);
        assert!(inside < 2e-6, "nodes {inside} m inside the circle");
    }

    #[test]
    fn smooth_resampling_of_degenerate_inputs_does_not_panic() {
        assert!(resample_smooth(&[], 4).is_empty());
        assert_eq!(resample_smooth(&[Vec3::zeros()], 3).len(), 3);
        let repeated = [
            Vec3::zeros(),
            Vec3::zeros(),
            Vec3::zeros(),
            Vec3::new(0.1, 0.0, 0.0),
        ];
        let out = resample_smooth(&repeated, 5);
        assert!(out.len() == 5 && out.iter().all(math::is_finite), "{out:?}");
        let nan = [
            Vec3::zeros(),
            Vec3::new(f64::NAN, 0.0, 0.0),
            Vec3::new(0.1, 0.0, 0.0),
        ];
        assert_eq!(resample_smooth(&nan, 4).len(), 4);
    }
}
