//! From an image path to 3D: the depth at each point (median of the rope's
//! pixels around it), the strand underneath at a crossing given the depth
//! of the strands beside it, gaps filled, deprojection, the push from the
//! surface to the axis, and smoothing.

use alloc::vec::Vec;

use crate::math::{Vec2, Vec3};
use crate::perception::camera::CameraIntrinsics;
use crate::perception::frame::Frame;
use crate::perception::point_cloud::{depth_at, median_around, push_along_rays, CloudSettings};
use crate::perception::segmentation::Mask;

/// Half side of the window searched for depth around a centre-line pixel.
const DEPTH_WINDOW_RADIUS: i64 = 3;
/// Half width (in path samples) of the moving average smoothing the 3D line.
pub(super) const SMOOTHING_HALF_WINDOW: usize = 4;
/// Marks a point outside any junction zone or gap.
pub(super) const NO_ZONE: u32 = u32::MAX;

/// The median valid depth of mask pixels around each point of `path`
/// (`None` where there is none).
pub(super) fn depths_along(
    path: &[Vec2],
    frame: &Frame<'_>,
    mask: &Mask,
    settings: &CloudSettings,
) -> Vec<Option<f64>> {
    let width = frame.width as i64;
    let mut window = Vec::new();
    let rope_depth = |x: i64, y: i64| {
        mask.get(x, y)
            .then(|| depth_at(frame, (y * width + x) as usize, settings))
            .flatten()
    };
    path.iter()
        .map(|p| {
            let pixel = (libm::round(p.x) as i64, libm::round(p.y) as i64);
            median_around(pixel, DEPTH_WINDOW_RADIUS, &mut window, rope_depth)
        })
        .collect()
}

/// A run of points in one junction zone.
struct Pass {
    zone: u32,
    start: usize,
    end: usize,
}

/// At each junction zone the path goes through more than once (a crossing
/// of the rope with itself), only the strand on top was measured there:
/// the pass whose depth expected from its two sides (linear between the
/// last depths before and after the zone) is nearest the depth measured in
/// the zone keeps it; the others are left to be interpolated.
pub(super) fn resolve_crossings(depths: &mut [Option<f64>], zones: &[u32]) {
    let mut passes: Vec<Pass> = Vec::new();
    let mut k = 0;
    while k < zones.len() {
        if zones[k] == NO_ZONE {
            k += 1;
            continue;
        }
        let start = k;
        while k < zones.len() && zones[k] == zones[start] {
            k += 1;
        }
        passes.push(Pass {
            zone: zones[start],
            start,
            end: k,
        });
    }
    // How far each pass's measured depth is from the depth its sides expect.
    let misfit: Vec<Option<f64>> = passes
        .iter()
        .map(|p| {
            let before = depths[..p.start].iter().rev().flatten().next()?;
            let after = depths[p.end..].iter().flatten().next()?;
            let mut inside: Vec<f64> = depths[p.start..p.end].iter().flatten().copied().collect();
            if inside.is_empty() {
                return None;
            }
            inside.sort_unstable_by(f64::total_cmp);
            Some((inside[inside.len() / 2] - 0.5 * (before + after)).abs())
        })
        .collect();
    for (a, pa) in passes.iter().enumerate() {
        let twice = passes.iter().filter(|p| p.zone == pa.zone).count() > 1;
        if !twice {
            continue;
        }
        let on_top = passes
            .iter()
            .enumerate()
            .filter(|(_, p)| p.zone == pa.zone)
            .filter_map(|(b, _)| misfit[b].map(|m| (b, m)))
            .min_by(|x, y| x.1.total_cmp(&y.1))
            .map(|(b, _)| b);
        if on_top != Some(a) {
            depths[pa.start..pa.end].fill(None);
        }
    }
}

/// Fills `None` entries by linear interpolation between the nearest known
/// neighbours (constant beyond the ends). `None` when nothing is known.
pub(super) fn fill_gaps(values: &mut [Option<f64>]) -> Option<()> {
    let known: Vec<usize> = (0..values.len()).filter(|&i| values[i].is_some()).collect();
    let (&first, &last) = (known.first()?, known.last()?);
    let (vf, vl) = (values[first]?, values[last]?);
    for v in values[..first].iter_mut() {
        *v = Some(vf);
    }
    for v in values[last + 1..].iter_mut() {
        *v = Some(vl);
    }
    for pair in known.windows(2) {
        let (i, j) = (pair[0], pair[1]);
        let (a, b) = (values[i]?, values[j]?);
        for (k, v) in values.iter_mut().enumerate().take(j).skip(i + 1) {
            let t = (k - i) as f64 / (j - i) as f64;
            *v = Some(a + (b - a) * t);
        }
    }
    Some(())
}

/// The 3D line through `path` at the filled `depths`, pushed `axis_offset`
/// along the viewing rays and smoothed. `None` when no depth is known.
pub(super) fn line_through(
    path: &[Vec2],
    depths: &[Option<f64>],
    camera: &CameraIntrinsics,
    axis_offset: f64,
) -> Option<Vec<Vec3>> {
    let mut filled = depths.to_vec();
    fill_gaps(&mut filled)?;
    let mut pts: Vec<Vec3> = path
        .iter()
        .zip(&filled)
        .map(|(p, z)| camera.deproject(p.x, p.y, z.unwrap_or(0.0)))
        .collect();
    push_along_rays(&mut pts, axis_offset);
    Some(smooth(&pts, SMOOTHING_HALF_WINDOW))
}

/// Centred moving average whose window shrinks near the ends, so both end
/// points stay where they are.
fn smooth(points: &[Vec3], half: usize) -> Vec<Vec3> {
    let n = points.len();
    (0..n)
        .map(|i| {
            let h = half.min(i).min(n - 1 - i);
            let sum: Vec3 = points[i - h..=i + h].iter().sum();
            sum / (2 * h + 1) as f64
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;

    #[test]
    fn gaps_in_depth_are_interpolated() {
        let mut v = [None, Some(1.0), None, None, Some(4.0), None];
        fill_gaps(&mut v).expect("some known");
        assert_eq!(
            v,
            [
                Some(1.0),
                Some(1.0),
                Some(2.0),
                Some(3.0),
                Some(4.0),
                Some(4.0)
            ]
        );
        assert!(fill_gaps(&mut [None, None]).is_none());
    }

    /// Depth rising 1 mm a pixel across the image and 3 mm a row: the
    /// median of the 7 x 7 window of rope pixels around a point is the
    /// depth at the point (the window is centred on it); off the mask or
    /// without depth, nothing.
    #[test]
    fn the_depth_at_a_point_is_the_median_of_its_window_of_rope_pixels() {
        let (w, h) = (40u32, 30u32);
        let depth: Vec<u16> = (0..w * h)
            .map(|i| (500 + (i % w) + 3 * (i / w)) as u16)
            .collect();
        let rgb = vec![0u8; (w * h * 3) as usize];
        let frame = Frame::new(w, h, &rgb, &depth, 0.001).expect("frame");
        let mut mask = Mask::new(w, h);
        mask.data.fill(true);
        let settings = crate::params::Params::default().cloud();
        let at = |u: f64, v: f64| depths_along(&[Vec2::new(u, v)], &frame, &mask, &settings)[0];
        for (u, v) in [(10.0, 10.0), (20.0, 12.0), (33.0, 20.0), (5.0, 22.0)] {
            let expected = (500.0 + u + 3.0 * v) / 1000.0;
            let got = at(u, v).expect("depth");
            assert!(
                (got - expected).abs() < 1e-9,
                "({u}, {v}): {got} not {expected}"
            );
        }
        // Only rope pixels count: with the mask's left half only, the window
        // at the edge takes its left columns, whose depths are smaller.
        let mut left = Mask::new(w, h);
        for (i, m) in left.data.iter_mut().enumerate() {
            *m = (i as u32 % w) < 20;
        }
        let edge = depths_along(&[Vec2::new(20.0, 10.0)], &frame, &left, &settings)[0];
        assert!(edge.expect("depth") < (500.0 + 20.0 + 30.0) / 1000.0);
        // And rows: with the top rows only, the window takes the rows above.
        let mut top = Mask::new(w, h);
        for (i, m) in top.data.iter_mut().enumerate() {
            *m = (i as u32 / w) < 10;
        }
        let edge = depths_along(&[Vec2::new(20.0, 10.0)], &frame, &top, &settings)[0];
        assert!(edge.expect("depth") < (500.0 + 20.0 + 30.0) / 1000.0);
        assert_eq!(
            depths_along(
                &[Vec2::new(30.0, 10.0)],
                &frame,
                &Mask::new(w, h),
                &settings
            ),
            [None]
        );
    }

    /// A loop crossing itself: the path passes zone 7 twice. The first pass
    /// lies at 0.60 m on both sides, the second at 0.585 m (the strand on
    /// top); 0.585 m is measured in the zone both times. The first pass's
    /// depths are dropped (interpolated later), the second's kept.
    #[test]
    fn the_strand_underneath_a_crossing_loses_the_top_strand_s_depth() {
        let (lo, hi) = (Some(0.600), Some(0.585));
        let mut depths = vec![lo, lo, hi, hi, lo, lo, hi, hi, hi, hi, hi];
        let z = NO_ZONE;
        let zones = [z, z, 7, 7, z, z, z, 7, 7, z, z];
        resolve_crossings(&mut depths, &zones);
        assert_eq!(depths[2..4], [None, None]);
        assert_eq!(depths[7..9], [hi, hi]);
        // A zone passed once keeps what it measured, even with no depth
        // before it.
        let mut once = vec![lo, hi, lo];
        resolve_crossings(&mut once, &[z, 3, z]);
        assert_eq!(once, [lo, hi, lo]);
        let mut first = vec![hi, hi, lo];
        resolve_crossings(&mut first, &[3, 3, z]);
        assert_eq!(first, [hi, hi, lo]);
    }

    /// The pass kept is the one whose measured depth is nearest the mean of
    /// its sides, whether the other's sides are nearer or farther.
    #[test]
    fn the_pass_kept_is_the_one_its_sides_predict() {
        let z = NO_ZONE;
        let zones = [z, 5, z, z, 5, z];
        for other_sides in [0.580, 0.620] {
            let (fit, other) = (Some(0.600), Some(other_sides));
            // The first pass fits its sides exactly; the second does not.
            let mut d = vec![fit, fit, fit, other, fit, other];
            resolve_crossings(&mut d, &zones);
            assert_eq!(
                d,
                [fit, fit, fit, other, None, other],
                "sides {other_sides}"
            );
            // The same two passes the other way round.
            let mut d = vec![other, fit, other, fit, fit, fit];
            resolve_crossings(&mut d, &zones);
            assert_eq!(
                d,
                [other, None, other, fit, fit, fit],
                "sides {other_sides}"
            );
        }
    }
}
