//! Rigid motions (a rotation and a translation): the camera's own motion
//! between two frames, and the motion the visible rope shares.

use nalgebra::Matrix3;

use crate::math::Vec3;

/// How far from orthonormal a given rotation may be, per entry of `R^T R - I`:
/// a rotation written out to six decimals passes, a scaling does not.
pub const ROTATION_TOLERANCE: f64 = 1e-5;

/// A rigid motion `p -> rotation * p + translation`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidMotion {
    /// Rotation.
    pub rotation: Matrix3<f64>,
    /// Translation, metres.
    pub translation: Vec3,
}

impl RigidMotion {
    /// No motion.
    pub fn identity() -> Self {
        Self {
            rotation: Matrix3::identity(),
            translation: Vec3::zeros(),
        }
    }

    /// Where `p` goes.
    pub fn apply(&self, p: &Vec3) -> Vec3 {
        self.rotation * p + self.translation
    }
}

impl RigidMotion {
    /// The motion of points fixed in the world as seen from a camera that
    /// moved from pose `(from_rows, from_centre)` to `(to_rows, to_centre)`
    /// (rows: the camera's axes in world coordinates; centre: its position):
    /// a point's coordinates in the first camera's frame to those in the
    /// second's.
    pub fn between_camera_poses(
        from_rows: &Matrix3<f64>,
        from_centre: &Vec3,
        to_rows: &Matrix3<f64>,
        to_centre: &Vec3,
    ) -> Self {
        let rotation = to_rows * from_rows.transpose();
        Self {
            rotation,
            translation: to_rows * (from_centre - to_centre),
        }
    }

    /// The motion of the 3 x 4 matrix `[R | t]` given row by row (the
    /// layout the Python and JavaScript bindings take).
    pub fn from_rows(m: &[f64; 12]) -> Self {
        Self {
            rotation: Matrix3::new(m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]),
            translation: Vec3::new(m[3], m[7], m[11]),
        }
    }

    /// `true` when the rotation is one: orthonormal (within
    /// [`ROTATION_TOLERANCE`] per entry of `R^T R - I`) with determinant 1,
    /// not a mirror.
    pub fn is_rotation(&self) -> bool {
        let r = &self.rotation;
        let off = r.transpose() * r - Matrix3::identity();
        off.iter().all(|v| v.abs() <= ROTATION_TOLERANCE)
            && (r.determinant() - 1.0).abs() <= 3.0 * ROTATION_TOLERANCE
    }

    /// `true` when every entry is finite.
    pub fn is_finite(&self) -> bool {
        self.rotation.iter().all(|v| v.is_finite())
            && self.translation.iter().all(|v| v.is_finite())
    }
}

/// The rotation of rotation vector `omega` (Rodrigues).
pub fn rotation_of(omega: &Vec3) -> Matrix3<f64> {
    let angle = omega.norm();
    if angle < 1e-12 {
        return Matrix3::identity();
    }
    let k = omega / angle;
    let kx = Matrix3::new(0.0, -k.z, k.y, k.z, 0.0, -k.x, -k.y, k.x, 0.0);
    Matrix3::identity() + kx * libm::sin(angle) + kx * kx * (1.0 - libm::cos(angle))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_motion_reads_its_rows_as_rotation_then_translation() {
        let m = RigidMotion::from_rows(&[1., 2., 3., 4., 5., 6., 7., 8., 9., 10., 11., 12.]);
        assert_eq!(
            m.rotation,
            Matrix3::new(1., 2., 3., 5., 6., 7., 9., 10., 11.)
        );
        assert_eq!(m.translation, Vec3::new(4., 8., 12.));
    }

    #[test]
    fn a_camera_that_moved_sees_a_world_point_where_its_new_pose_puts_it() {
        let from_rows = rotation_of(&Vec3::new(0.1, -0.2, 0.05));
        let to_rows = rotation_of(&Vec3::new(0.12, -0.15, 0.0));
        let (c0, c1) = (Vec3::new(0.0, -0.3, 0.8), Vec3::new(0.03, -0.28, 0.79));
        let world = Vec3::new(0.2, 0.1, 0.0);
        let seen0 = from_rows * (world - c0);
        let seen1 = to_rows * (world - c1);
        let motion = RigidMotion::between_camera_poses(&from_rows, &c0, &to_rows, &c1);
        assert!((motion.apply(&seen0) - seen1).norm() < 1e-12);
    }
}
