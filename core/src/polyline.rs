//! Polyline geometry every stage shares: distance to a polyline, arc
//! length, arc coordinates, and
//! `count` points evenly spaced by arc length along a polyline (the paper's
//! Eq. 12-15 on the node polyline; initialisation places its nodes with it
//! too).

use alloc::vec::Vec;

use nalgebra::SVector;

use crate::math::{self, Vec3};

/// Distance from `p` to the polyline through `curve` (Eq. 16). A one-point
/// curve is that point; an empty curve gives `None`.
pub fn distance_to_polyline<const D: usize>(
    p: &SVector<f64, D>,
    curve: &[SVector<f64, D>],
) -> Option<f64> {
    let first = curve.first()?;
    let mut best = (p - first).norm_squared();
    for w in curve.windows(2) {
        let t = math::nearest_on_segment(p, &w[0], &w[1]);
        best = best.min((p - (w[0] + (w[1] - w[0]) * t)).norm_squared());
    }
    Some(math::sqrt(best))
}

/// Arc length of the polyline (Eq. 12-13, `L`).
pub fn polyline_length(points: &[Vec3]) -> f64 {
    points.windows(2).map(|w| math::norm(&(w[1] - w[0]))).sum()
}

/// Cumulative distance along the polyline through `points`, from the first
/// (each point's arc coordinate).
pub fn arc_coordinates(points: &[Vec3]) -> Vec<f64> {
    let mut s = Vec::with_capacity(points.len());
    let mut sum = 0.0;
    for (i, y) in points.iter().enumerate() {
        if i > 0 {
            sum += math::norm(&(y - points[i - 1]));
        }
        s.push(sum);
    }
    s
}

/// `count` nodes at spacing `l = L / (count - 1)` along the polyline
/// `points` (Eq. 14-15): the first and last points kept exactly, each node
/// between them `place(q, t)` for its segment `q` and how far along it, in
/// `[0, 1]`. `None` when the nodes cannot be spread: fewer than two points,
/// `count` below 2, or a length that is zero or not finite.
pub(crate) fn spread(
    points: &[Vec3],
    count: usize,
    place: impl Fn(usize, f64) -> Vec3,
) -> Option<Vec<Vec3>> {
    let length = polyline_length(points);
    if points.len() < 2 || count < 2 || !(length > math::LENGTH_EPSILON) || !length.is_finite() {
        return None;
    }
    let spacing = length / (count - 1) as f64;
    let mut out = Vec::with_capacity(count);
    out.push(points[0]);
    // `q` is the segment index, `walked` the geodesic distance to its start.
    let mut q = 0;
    let mut walked = 0.0;
    let mut seg = math::norm(&(points[1] - points[0]));
    for n in 1..count - 1 {
        let target = n as f64 * spacing;
        while walked + seg <= target && q + 2 < points.len() {
            walked += seg;
            q += 1;
            seg = math::norm(&(points[q + 1] - points[q]));
        }
        let t = if seg > math::LENGTH_EPSILON {
            ((target - walked) / seg).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push(place(q, t));
    }
    out.push(points[points.len() - 1]);
    Some(out)
}

/// Resamples `points` into `count` nodes at spacing `l = L / (count - 1)`
/// along the polyline (Eq. 14-15). The first node is kept exactly and the
/// last lands on the last point. A polyline of zero length (or one point)
/// gives `count` copies of its first point; an empty one gives nothing.
pub fn resample_uniform(points: &[Vec3], count: usize) -> Vec<Vec3> {
    let Some(&first) = points.first() else {
        return Vec::new();
    };
    spread(points, count, |q, t| {
        points[q] + (points[q + 1] - points[q]) * t
    })
    .unwrap_or_else(|| alloc::vec![first; count])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;
    use alloc::vec;

    #[test]
    fn nodes_land_at_exact_arc_lengths_across_segment_ends() {
        // Segments of 1, 2 and 1 (length 4): 5 nodes at 0, 1, 2, 3, 4.
        let pts = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(2.0, 2.0, 0.0),
        ];
        let out = resample_uniform(&pts, 5);
        let expect = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(2.0, 2.0, 0.0),
        ];
        for (a, b) in out.iter().zip(&expect) {
            assert!((a - b).norm() < 1e-12, "{a:?} vs {b:?}");
        }
        // A repeated point (zero-length segment) changes nothing.
        let with_repeat = [pts[0], pts[1], pts[1], pts[2], pts[3]];
        for (a, b) in resample_uniform(&with_repeat, 5).iter().zip(&expect) {
            assert!((a - b).norm() < 1e-12, "{a:?} vs {b:?}");
        }
        assert_eq!(resample_uniform(&pts, 1), vec![pts[0]]);
        assert_eq!(resample_uniform(&[pts[0], pts[0]], 3), vec![pts[0]; 3]);
    }

    #[test]
    fn straight_line_is_split_evenly() {
        let pts = vec![
            Vec3::zeros(),
            Vec3::new(0.1, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
        ];
        let out = resample_uniform(&pts, 5);
        for (i, p) in out.iter().enumerate() {
            assert!((p.x - 0.25 * i as f64).abs() < 1e-12, "{p:?}");
        }
    }

    #[test]
    fn corner_is_followed_geodesically() {
        // An L of total length 2: the middle of 3 nodes is the corner.
        let pts = vec![
            Vec3::zeros(),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
        ];
        let out = resample_uniform(&pts, 3);
        assert!((out[1] - Vec3::new(1.0, 0.0, 0.0)).norm() < 1e-12);
        let out = resample_uniform(&pts, 5);
        assert!((out[3] - Vec3::new(1.0, 0.5, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        assert!(resample_uniform(&[], 4).is_empty());
        let one = resample_uniform(&[Vec3::new(1.0, 2.0, 3.0)], 4);
        assert_eq!(one.len(), 4);
        let same = resample_uniform(&[Vec3::zeros(), Vec3::zeros()], 3);
        assert_eq!(same, vec![Vec3::zeros(); 3]);
        let nan = resample_uniform(&[Vec3::zeros(), Vec3::new(f64::NAN, 0.0, 0.0)], 3);
        assert_eq!(nan.len(), 3);
    }

    /// Property over seeded random polylines: the first node is kept, the
    /// spacing is equal (chords never exceed the arc spacing and are equal on
    /// straight pieces), and the resampled length stays within the original.
    #[test]
    fn random_polylines_keep_first_node_spacing_and_length() {
        let mut rng = SplitMix64::new(12);
        for case in 0..300 {
            let n = 2 + rng.below(40) as usize;
            let pts: Vec<Vec3> = (0..n)
                .map(|_| {
                    Vec3::new(
                        rng.range(-1.0, 1.0),
                        rng.range(-1.0, 1.0),
                        rng.range(0.2, 2.0),
                    )
                })
                .collect();
            let m = 4 + rng.below(60) as usize;
            let out = resample_uniform(&pts, m);
            assert_eq!(out.len(), m);
            assert_eq!(out[0], pts[0], "case {case}");
            let length = polyline_length(&pts);
            let spacing = length / (m - 1) as f64;
            for w in out.windows(2) {
                assert!(math::norm(&(w[1] - w[0])) <= spacing + 1e-9, "case {case}");
            }
            assert!(polyline_length(&out) <= length + 1e-9);
        }
        // Equal spacing and length kept exactly on a dense smooth curve.
        let arc: Vec<Vec3> = (0..=2000)
            .map(|i| {
                let t = i as f64 / 2000.0 * 2.0;
                Vec3::new(libm::cos(t), libm::sin(t), 1.0)
            })
            .collect();
        let out = resample_uniform(&arc, 24);
        let gaps: Vec<f64> = out.windows(2).map(|w| math::norm(&(w[1] - w[0]))).collect();
        let (lo, hi) = gaps
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), &g| (a.min(g), b.max(g)));
        assert!(hi - lo < 1e-6, "spacing spread {}", hi - lo);
        assert!((polyline_length(&out) - 2.0).abs() < 2e-3);
    }
}
