//! The rope's curve through its nodes, with arc coordinates: the
//! centripetal Catmull-Rom curve (or, when asked, the polyline). Hidden
//! nodes that slide along the rope or are re-spaced are put on this one
//! curve, so that doing it every frame keeps a hidden bend instead of
//! cutting it by its chords' sagitta until the rope lies straight
//! (`docs/algorithm-notes.md`, "Hidden nodes move on the rope's curve").

use alloc::vec::Vec;

use crate::math::{self, Vec3};
use crate::polyline::arc_coordinates;

/// Pieces each node-to-node segment of the smooth curve is cut into to
/// measure its arc length: at the node spacing of a rope (3-4 cm) and a
/// bend radius of 5 cm or more, the chords of eight pieces are within
/// 0.1 mm of the curve's length there. Points are put on the curve itself.
pub const SMOOTH_PIECES: usize = 8;

/// A curve through `points` (in order) with its arc coordinate: the
/// centripetal Catmull-Rom curve, or the polyline. Within the points a
/// coordinate gives a point on the curve; past its ends the curve goes on
/// straight along its end pieces.
#[derive(Debug, Clone)]
pub struct RopeCurve<'a> {
    points: &'a [Vec3],
    /// Pieces per segment: [`SMOOTH_PIECES`], or 1 for the polyline.
    pieces: usize,
    /// The curve's points at the pieces' ends (the polyline: `points`).
    dense: Vec<Vec3>,
    /// Arc coordinate of each of `dense`, measured on the pieces' chords.
    s: Vec<f64>,
}

impl<'a> RopeCurve<'a> {
    /// The centripetal Catmull-Rom curve through `points`; the polyline
    /// when there are fewer than three or the curve is not finite.
    pub fn smooth(points: &'a [Vec3]) -> Self {
        let n = points.len();
        if n < 3 {
            return Self::polyline(points);
        }
        let mut dense = Vec::with_capacity((n - 1) * SMOOTH_PIECES + 1);
        for i in 0..n - 1 {
            for k in 0..SMOOTH_PIECES {
                dense.push(catmull_rom(points, i, k as f64 / SMOOTH_PIECES as f64));
            }
        }
        dense.push(points[n - 1]);
        if !dense.iter().all(math::is_finite) {
            return Self::polyline(points);
        }
        Self::with_pieces(points, SMOOTH_PIECES, dense)
    }

    /// The polyline through `points`.
    pub fn polyline(points: &'a [Vec3]) -> Self {
        Self::with_pieces(points, 1, points.to_vec())
    }

    /// [`Self::smooth`] when `smooth`, else [`Self::polyline`].
    pub fn new(points: &'a [Vec3], smooth: bool) -> Self {
        if smooth {
            Self::smooth(points)
        } else {
            Self::polyline(points)
        }
    }

    fn with_pieces(points: &'a [Vec3], pieces: usize, dense: Vec<Vec3>) -> Self {
        let s = arc_coordinates(&dense);
        Self {
            points,
            pieces,
            dense,
            s,
        }
    }

    /// The curve's length.
    pub fn length(&self) -> f64 {
        self.s.last().copied().unwrap_or(0.0)
    }

    /// The arc coordinate of `points[i]` (the last point's past the end).
    pub fn arc_of(&self, i: usize) -> f64 {
        let k = (i * self.pieces).min(self.s.len().saturating_sub(1));
        self.s.get(k).copied().unwrap_or(0.0)
    }

    /// The curve's points at the ends of its pieces, whose chords measure
    /// its arc length.
    pub fn pieces(&self) -> &[Vec3] {
        &self.dense
    }

    /// The point a fraction `t` along piece `q`: on the curve for `t` in
    /// `[0, 1]`, straight along the piece outside it (past an end).
    pub fn on_piece(&self, q: usize, t: f64) -> Vec3 {
        let (a, b) = (self.dense[q], self.dense[q + 1]);
        let straight = a + (b - a) * t;
        if self.pieces == 1 || !(0.0..=1.0).contains(&t) {
            return straight;
        }
        let y = catmull_rom(
            self.points,
            q / self.pieces,
            ((q % self.pieces) as f64 + t) / self.pieces as f64,
        );
        if math::is_finite(&y) {
            y
        } else {
            straight
        }
    }

    /// The point at arc coordinate `sigma`; before 0 and past the length,
    /// straight on along the end pieces.
    pub fn at(&self, sigma: f64) -> Vec3 {
        let n = self.dense.len();
        if n < 2 {
            return self.dense.first().copied().unwrap_or_else(Vec3::zeros);
        }
        // The piece holding sigma, the end ones extended to infinity.
        let q = self.s.partition_point(|&x| x <= sigma).clamp(1, n - 1) - 1;
        let len = self.s[q + 1] - self.s[q];
        if !(len > math::LENGTH_EPSILON) {
            return self.dense[q];
        }
        self.on_piece(q, (sigma - self.s[q]) / len)
    }

    /// The arc coordinate of the point of the curve's pieces nearest `p`,
    /// among the pieces within `reach` of arc length from `near` (`near`
    /// itself when none is).
    pub fn project(&self, p: &Vec3, near: f64, reach: f64) -> f64 {
        let mut best = (f64::INFINITY, near);
        for k in 0..self.dense.len().saturating_sub(1) {
            if self.s[k] > near + reach || self.s[k + 1] < near - reach {
                continue;
            }
            let (a, b) = (self.dense[k], self.dense[k + 1]);
            let t = math::nearest_on_segment(p, &a, &b);
            let d = (p - (a + (b - a) * t)).norm_squared();
            if d < best.0 {
                best = (d, self.s[k] + t * (self.s[k + 1] - self.s[k]));
            }
        }
        best.1
    }
}

/// The centripetal Catmull-Rom curve through `points` between points `i`
/// and `i + 1`, at `u` in `[0, 1]`; the ends are continued by mirroring
/// the neighbour, so the curve leaves them along their first and last
/// chords.
fn catmull_rom(points: &[Vec3], i: usize, u: f64) -> Vec3 {
    let n = points.len() as isize;
    let at = |i: isize| -> Vec3 {
        if i < 0 {
            points[0] * 2.0 - points[1]
        } else if i >= n {
            points[(n - 1) as usize] * 2.0 - points[(n - 2) as usize]
        } else {
            points[i as usize]
        }
    };
    // Centripetal parameterisation: knots spaced by the square root of the
    // chord, which keeps the curve from looping or overshooting at uneven
    // spacing (Yuksel et al.). A zero chord is given a tiny knot step.
    let knot = |a: &Vec3, b: &Vec3| libm::sqrt(math::norm(&(b - a))).max(math::LENGTH_EPSILON);
    let lerp = |p: Vec3, q: Vec3, ta: f64, tb: f64, t: f64| {
        p * ((tb - t) / (tb - ta)) + q * ((t - ta) / (tb - ta))
    };
    let i = i as isize;
    let (p0, p1, p2, p3) = (at(i - 1), at(i), at(i + 1), at(i + 2));
    let t1 = knot(&p0, &p1);
    let t2 = t1 + knot(&p1, &p2);
    let t3 = t2 + knot(&p2, &p3);
    let t = t1 + (t2 - t1) * u;
    // Barry-Goldman's pyramid for the curve between p1 and p2.
    let (a1, a2, a3) = (
        lerp(p0, p1, 0.0, t1, t),
        lerp(p1, p2, t1, t2, t),
        lerp(p2, p3, t2, t3, t),
    );
    let (b1, b2) = (lerp(a1, a2, 0.0, t2, t), lerp(a2, a3, t1, t3, t));
    lerp(b1, b2, t1, t2, t)
}

/// Shapes the tests of the curve and of the stages that move nodes on it
/// share.
#[cfg(test)]
pub(crate) mod fixture {
    use alloc::vec::Vec;

    use crate::math::Vec3;

    /// A U of unit sides, (0,0) -> (1,0) -> (1,1) -> (0,1) -> (0,2), moved
    /// by `x0` in x.
    pub fn u_points(x0: f64) -> Vec<Vec3> {
        alloc::vec![
            Vec3::new(x0, 0.0, 0.0),
            Vec3::new(x0 + 1.0, 0.0, 0.0),
            Vec3::new(x0 + 1.0, 1.0, 0.0),
            Vec3::new(x0, 1.0, 0.0),
            Vec3::new(x0, 2.0, 0.0),
        ]
    }

    /// The point `s` along a circle of `radius` about the optical axis,
    /// 0.6 m from the camera.
    pub fn on_circle(radius: f64, s: f64) -> Vec3 {
        let a = s / radius;
        Vec3::new(radius * libm::cos(a), radius * libm::sin(a), 0.6)
    }

    /// The largest distance of `points` from that circle.
    pub fn off_circle(points: &[Vec3], radius: f64) -> f64 {
        points
            .iter()
            .map(|p| (libm::hypot(p.x, p.y) - radius).abs())
            .fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::fixture::{on_circle, u_points};
    use super::*;

    #[test]
    fn projection_looks_only_within_its_reach_of_arc_length() {
        let points = u_points(0.0);
        let c = RopeCurve::polyline(&points);
        let p = |x: f64, y: f64| Vec3::new(x, y, 0.0);
        // Nearest overall is the far side of the U (s = 2.9), outside the reach.
        assert_eq!(c.project(&p(0.1, 0.6), 0.05, 0.5), 0.1);
        assert_eq!(c.project(&p(0.1, 0.6), 0.05, 5.0), 2.9);
        // A segment starting exactly at near + reach is still looked at,
        // as is one ending exactly at near - reach.
        assert_eq!(c.project(&p(1.2, 0.5), 0.5, 0.5), 1.5);
        assert_eq!(c.project(&p(0.5, -0.1), 1.5, 0.5), 0.5);
        // Of the segments in reach, the nearest wins; on a tie the first.
        assert_eq!(c.project(&p(1.2, 0.5), 1.0, 2.0), 1.5);
        assert_eq!(c.project(&p(0.5, 0.5), 1.5, 5.0), 0.5);
        // Nothing in reach: where it started.
        assert_eq!(c.project(&p(0.5, 0.5), 10.0, 0.5), 10.0);
    }

    #[test]
    fn a_polyline_is_evaluated_along_its_segments_and_straight_on_past_its_ends() {
        let points = u_points(0.0);
        let c = RopeCurve::polyline(&points);
        let at = |s: f64| {
            let q = c.at(s);
            (q.x, q.y)
        };
        assert_eq!(at(0.25), (0.25, 0.0));
        assert_eq!(at(1.5), (1.0, 0.5));
        assert_eq!(at(2.75), (0.25, 1.0));
        assert_eq!(at(-0.5), (-0.5, 0.0));
        assert_eq!(at(4.5), (0.0, 2.5));
        assert_eq!((c.length(), c.arc_of(2), c.arc_of(9)), (4.0, 2.0, 4.0));
        let one = [Vec3::new(1.0, 2.0, 3.0)];
        assert_eq!(RopeCurve::smooth(&one).at(5.0), one[0]);
        assert_eq!(RopeCurve::smooth(&[]).at(5.0), Vec3::zeros());
        assert_eq!(RopeCurve::smooth(&[]).length(), 0.0);
    }

    /// Points at any arc coordinate of a smooth curve through nodes on a
    /// circle lie on the circle (to the curve's own error),
    /// where the polyline's lie inside it by up to the chords' sagitta.
    #[test]
    fn the_smooth_curve_keeps_to_the_bend_between_its_nodes() {
        let radius = 0.05;
        let nodes: Vec<Vec3> = (0..10)
            .map(|k| on_circle(radius, 0.6 * radius * k as f64))
            .collect();
        // Between the second and the second last node (the end segments
        // leave along their chords, off the circle).
        let inside = |c: &RopeCurve<'_>| {
            let (from, to) = (c.arc_of(1), c.arc_of(8));
            (0..=60)
                .map(|k| c.at(from + (to - from) * k as f64 / 60.0))
                .map(|p| radius - libm::hypot(p.x, p.y))
                .fold(0.0, f64::max)
        };
        let sagitta = radius * (1.0 - libm::cos(0.3));
        let (smooth, flat) = (RopeCurve::smooth(&nodes), RopeCurve::polyline(&nodes));
        assert!(inside(&flat) > 0.9 * sagitta, "{}", inside(&flat));
        assert!(inside(&smooth) < 0.1 * sagitta, "{}", inside(&smooth));
        // Its arc coordinate is the arc length (0.6 rad a segment), and each
        // node is at its own coordinate.
        let arc = smooth.arc_of(5) - smooth.arc_of(1);
        let circle = 4.0 * 0.6 * radius;
        assert!(
            (arc / circle - 1.0).abs() < 3e-3,
            "{arc} m against {circle}"
        );
        for (i, p) in nodes.iter().enumerate() {
            assert!((smooth.at(smooth.arc_of(i)) - p).norm() < 1e-12, "node {i}");
        }
        // Past the ends it goes on straight.
        let past = smooth.at(smooth.length() + 0.01);
        let end = nodes[9];
        assert!(((past - end).norm() - 0.01).abs() < 1e-9);
    }

    #[test]
    fn a_curve_through_repeated_or_unknown_points_stays_finite() {
        let repeated = [Vec3::zeros(), Vec3::zeros(), Vec3::new(0.1, 0.0, 0.0)];
        let c = RopeCurve::smooth(&repeated);
        assert!(math::is_finite(&c.at(0.05)) && (c.length() - 0.1).abs() < 1e-9);
        let nan = [Vec3::zeros(), Vec3::new(f64::NAN, 0.0, 0.0), Vec3::zeros()];
        // Falls back to the polyline, which carries the NaN but does not panic.
        let c = RopeCurve::smooth(&nan);
        let _ = (c.at(0.5), c.project(&Vec3::zeros(), 0.0, 1.0), c.arc_of(2));
    }
}
