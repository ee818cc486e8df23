//! Pinhole camera intrinsics of the colour camera, deprojection of depth
//! pixels (depth aligned to colour) and projection of 3D points.

use crate::math::{Vec2, Vec3};

/// Largest accepted image width or height in pixels. Checked before any
/// per-pixel buffer is allocated (every reader of the project uses this one).
pub const MAX_IMAGE_SIDE: u32 = 8192;
/// Metres per depth unit when nothing says otherwise: a RealSense D4xx's
/// default depth units (1 mm).
pub const DEFAULT_DEPTH_SCALE: f64 = 0.001;
/// Frames per second when nothing says otherwise (a D435i's default rate).
pub const DEFAULT_FPS: f64 = 30.0;
/// Fastest frame rate accepted, frames per second.
pub const MAX_FPS: f64 = 10_000.0;
/// Depth noise of the D435i's stereo matching, as a disparity error in pixels.
pub const SUBPIXEL_DISPARITY: f64 = 0.08;
/// The D435i's stereo baseline, metres.
pub const STEREO_BASELINE: f64 = 0.050;

/// `true` for a frame rate a tracker and a sequence accept: a finite
/// number of frames per second in `(0, MAX_FPS]`.
pub fn is_frame_rate(fps: f64) -> bool {
    fps.is_finite() && fps > 0.0 && fps <= MAX_FPS
}

/// One deviation of the D435i's depth at `z` metres for a focal length of
/// `f` pixels: `z^2 e / (f b)` for a disparity error `e`
/// ([`SUBPIXEL_DISPARITY`]) and baseline `b` ([`STEREO_BASELINE`]). It grows
/// with the square of the distance: 0.9 mm at 0.6 m, 2.6 mm at 1 m and
/// 10 mm at 2 m for a 615 px focal length.
pub fn depth_noise(z: f64, f: f64) -> f64 {
    z * z * SUBPIXEL_DISPARITY / (f * STEREO_BASELINE)
}

/// Errors in camera intrinsics.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CameraError {
    /// Width or height is zero or above [`MAX_IMAGE_SIDE`].
    #[error("image size {width}x{height} is not accepted (each side must be 1..={max})")]
    BadSize {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
        /// [`MAX_IMAGE_SIDE`].
        max: u32,
    },
    /// A focal length is zero, negative or not finite.
    #[error("focal length {name} = {value} must be finite and positive")]
    BadFocalLength {
        /// `fx` or `fy`.
        name: &'static str,
        /// The rejected value.
        value: f64,
    },
    /// A principal point coordinate is not finite.
    #[error("principal point {name} = {value} must be finite")]
    BadPrincipalPoint {
        /// `cx` or `cy`.
        name: &'static str,
        /// The rejected value.
        value: f64,
    },
}

/// Colour camera intrinsics (pixels). Pixel centres sit at integer
/// coordinates, as in OpenCV and Open3D.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct CameraIntrinsics {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x, pixels.
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
}

impl CameraIntrinsics {
    /// Intrinsics of a RealSense D435i colour stream at 640x480 (typical values).
    pub const D435I_640X480: Self = Self {
        width: 640,
        height: 480,
        fx: 615.0,
        fy: 615.0,
        cx: 320.0,
        cy: 240.0,
    };

    /// Checks the values; every other method assumes they passed.
    pub fn validate(&self) -> Result<(), CameraError> {
        if self.width == 0
            || self.height == 0
            || self.width > MAX_IMAGE_SIDE
            || self.height > MAX_IMAGE_SIDE
        {
            return Err(CameraError::BadSize {
                width: self.width,
                height: self.height,
                max: MAX_IMAGE_SIDE,
            });
        }
        for (name, value) in [("fx", self.fx), ("fy", self.fy)] {
            if !(value.is_finite() && value > 0.0) {
                return Err(CameraError::BadFocalLength { name, value });
            }
        }
        for (name, value) in [("cx", self.cx), ("cy", self.cy)] {
            if !value.is_finite() {
                return Err(CameraError::BadPrincipalPoint { name, value });
            }
        }
        Ok(())
    }

    /// The 3D point seen at pixel `(u, v)` at depth `z` metres.
    #[inline]
    pub fn deproject(&self, u: f64, v: f64, z: f64) -> Vec3 {
        Vec3::new((u - self.cx) * z / self.fx, (v - self.cy) * z / self.fy, z)
    }

    /// The pixel where `p` is seen, or `None` when it is not in front of the
    /// camera (z not positive) or not finite.
    #[inline]
    pub fn project(&self, p: &Vec3) -> Option<Vec2> {
        if !(p.z > 0.0) || !crate::math::is_finite(p) {
            return None;
        }
        Some(Vec2::new(
            self.fx * p.x / p.z + self.cx,
            self.fy * p.y / p.z + self.cy,
        ))
    }

    /// Number of pixels in one image.
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deproject_then_project_returns_the_pixel() {
        let cam = CameraIntrinsics::D435I_640X480;
        let p = cam.deproject(100.0, 50.0, 0.6);
        let q = cam.project(&p).expect("in front");
        assert!((q.x - 100.0).abs() < 1e-9 && (q.y - 50.0).abs() < 1e-9);
        // Hand computation: x = (100 - 320) * 0.6 / 615.
        assert!((p.x - (-220.0 * 0.6 / 615.0)).abs() < 1e-12);
    }

    #[test]
    fn points_behind_or_nan_do_not_project() {
        let cam = CameraIntrinsics::D435I_640X480;
        assert!(cam.project(&Vec3::new(0.0, 0.0, -1.0)).is_none());
        assert!(cam.project(&Vec3::new(f64::NAN, 0.0, 1.0)).is_none());
    }

    #[test]
    fn invalid_intrinsics_are_rejected() {
        let mut cam = CameraIntrinsics::D435I_640X480;
        cam.fx = 0.0;
        assert!(matches!(
            cam.validate(),
            Err(CameraError::BadFocalLength { name: "fx", .. })
        ));
        cam.fx = 615.0;
        cam.fy = f64::NAN;
        assert!(cam.validate().is_err());
        cam.fy = 615.0;
        cam.width = 0;
        assert!(matches!(cam.validate(), Err(CameraError::BadSize { .. })));
        cam.width = MAX_IMAGE_SIDE + 1;
        assert!(cam.validate().is_err());
    }
}
