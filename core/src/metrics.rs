//! The frame error of Eq. 16-18: the mean distance from each node to the
//! piecewise-linear curve through the other set, averaged both ways; in
//! metres in 3D, and in pixels after projection with the colour intrinsics.

use alloc::vec::Vec;

use nalgebra::SVector;

use crate::math::{Vec2, Vec3};
use crate::perception::camera::CameraIntrinsics;

pub use crate::polyline::distance_to_polyline;

/// `eps(A, B)` of Eq. 17: the mean over the nodes of `a` of their distance to
/// PWL(`b`). `None` when either set is empty.
pub fn one_sided_error<const D: usize>(
    a: &[SVector<f64, D>],
    b: &[SVector<f64, D>],
) -> Option<f64> {
    if a.is_empty() {
        return None;
    }
    let mut sum = 0.0;
    for p in a {
        sum += distance_to_polyline(p, b)?;
    }
    Some(sum / a.len() as f64)
}

/// The frame error of Eq. 18: `(eps(Y, Y_true) + eps(Y_true, Y)) / 2`.
pub fn frame_error<const D: usize>(
    nodes: &[SVector<f64, D>],
    truth: &[SVector<f64, D>],
) -> Option<f64> {
    Some(0.5 * (one_sided_error(nodes, truth)? + one_sided_error(truth, nodes)?))
}

/// The frame error in pixels: both sets projected with `camera` first.
/// Points that do not project (behind the camera, not finite) are left out.
pub fn frame_error_px(nodes: &[Vec3], truth: &[Vec3], camera: &CameraIntrinsics) -> Option<f64> {
    let project =
        |s: &[Vec3]| -> Vec<Vec2> { s.iter().filter_map(|p| camera.project(p)).collect() };
    frame_error(&project(nodes), &project(truth))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distance_to_a_polyline_is_to_its_nearest_segment_point() {
        use nalgebra::Vector2;
        let curve = [
            Vector2::new(1.0, 1.0),
            Vector2::new(5.0, 1.0),
            Vector2::new(5.0, 1.0),
            Vector2::new(5.0, 7.0),
        ];
        // Above the middle of the first segment, 2 away.
        let d = distance_to_polyline(&Vector2::new(3.0, 3.0), &curve).expect("curve");
        assert!((d - 2.0).abs() < 1e-12, "{d}");
        // Beside the last segment, 1.5 away (past the repeated vertex).
        let d = distance_to_polyline(&Vector2::new(3.5, 5.0), &curve).expect("curve");
        assert!((d - 1.5).abs() < 1e-12, "{d}");
        // Beyond the first end: the distance to the end point.
        let d = distance_to_polyline(&Vector2::new(-2.0, 5.0), &curve).expect("curve");
        assert!((d - 5.0).abs() < 1e-12, "{d}");
        assert_eq!(
            distance_to_polyline::<2>(&Vector2::new(0.0, 0.0), &[]),
            None
        );
    }
    use alloc::vec;

    #[test]
    fn distance_to_segment_interior_and_ends() {
        let curve = vec![Vec2::new(0.0, 0.0), Vec2::new(10.0, 0.0)];
        assert_eq!(
            distance_to_polyline(&Vec2::new(5.0, 3.0), &curve),
            Some(3.0)
        );
        assert_eq!(
            distance_to_polyline(&Vec2::new(13.0, 4.0), &curve),
            Some(5.0)
        );
        assert_eq!(distance_to_polyline(&Vec2::new(1.0, 1.0), &[]), None);
        // A one-point curve is that point.
        assert_eq!(
            distance_to_polyline(&Vec2::new(4.0, 3.0), &[Vec2::new(1.0, -1.0)]),
            Some(5.0)
        );
    }

    #[test]
    fn frame_error_of_a_shifted_line() {
        // Truth along x from 0 to 1; nodes the same line shifted by 0.01 in y:
        // every node is 0.01 from the other curve both ways.
        let truth: Vec<Vec3> = (0..=10)
            .map(|i| Vec3::new(i as f64 * 0.1, 0.0, 1.0))
            .collect();
        let nodes: Vec<Vec3> = truth
            .iter()
            .map(|p| p + Vec3::new(0.0, 0.01, 0.0))
            .collect();
        let e = frame_error(&nodes, &truth).expect("error");
        assert!((e - 0.01).abs() < 1e-12);
    }

    #[test]
    fn frame_error_is_symmetric_and_sees_a_short_track() {
        // Nodes cover only the first half of the truth: eps(Y, T) = 0 and
        // eps(T, Y) is the mean distance of truth points past the end.
        let truth: Vec<Vec3> = (0..=4).map(|i| Vec3::new(i as f64, 0.0, 1.0)).collect();
        let nodes = vec![Vec3::new(0.0, 0.0, 1.0), Vec3::new(2.0, 0.0, 1.0)];
        let e = frame_error(&nodes, &truth).expect("error");
        // eps(T, Y) = (0 + 0 + 0 + 1 + 2) / 5 = 0.6, so E = 0.3.
        assert!((e - 0.3).abs() < 1e-12);
        assert_eq!(frame_error(&truth, &nodes), Some(e));
    }

    #[test]
    fn frame_error_in_pixels_projects_first() {
        let cam = CameraIntrinsics::D435I_640X480;
        let truth = vec![Vec3::new(0.0, 0.0, 0.615), Vec3::new(0.1, 0.0, 0.615)];
        // Shift by 1 mm at 0.615 m: exactly one pixel.
        let nodes: Vec<Vec3> = truth
            .iter()
            .map(|p| p + Vec3::new(0.0, 0.001, 0.0))
            .collect();
        let e = frame_error_px(&nodes, &truth, &cam).expect("error");
        assert!((e - 1.0).abs() < 1e-9);
        assert_eq!(frame_error_px(&[], &truth, &cam), None);
    }
}
