//! One RGB-D frame as the tracker sees it: an 8-bit RGB image and a 16-bit
//! depth image aligned to it, borrowed from the caller.

use super::camera::{CameraIntrinsics, MAX_IMAGE_SIDE};

/// Errors in the images of one frame.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrameError {
    /// The frame's size differs from the camera's.
    #[error(
        "frame is {width}x{height} but the camera intrinsics say {camera_width}x{camera_height}"
    )]
    SizeMismatch {
        /// Frame width.
        width: u32,
        /// Frame height.
        height: u32,
        /// Intrinsics width.
        camera_width: u32,
        /// Intrinsics height.
        camera_height: u32,
    },
    /// A buffer's length does not match width x height (x 3 for colour).
    #[error("{buffer} buffer holds {actual} values, expected {expected}")]
    BufferLength {
        /// `colour` or `depth`.
        buffer: &'static str,
        /// Values found.
        actual: usize,
        /// Values expected.
        expected: usize,
    },
    /// Width or height is zero or above [`MAX_IMAGE_SIDE`].
    #[error("frame size {width}x{height} is not accepted (each side must be 1..={max})")]
    BadSize {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
        /// [`MAX_IMAGE_SIDE`].
        max: u32,
    },
    /// The depth scale is not a finite positive number.
    #[error("depth scale {value} must be finite and positive (metres per depth unit)")]
    BadDepthScale {
        /// The rejected value.
        value: f64,
    },
}

/// A borrowed RGB-D frame. Depth value 0 means "no measurement".
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major RGB, 3 bytes per pixel.
    pub color: &'a [u8],
    /// Row-major depth units, aligned to `color`.
    pub depth: &'a [u16],
    /// Metres per depth unit (0.001 for a D435i's default).
    pub depth_scale: f64,
}

impl<'a> Frame<'a> {
    /// Checks sizes and buffer lengths.
    pub fn new(
        width: u32,
        height: u32,
        color: &'a [u8],
        depth: &'a [u16],
        depth_scale: f64,
    ) -> Result<Self, FrameError> {
        if width == 0 || height == 0 || width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
            return Err(FrameError::BadSize {
                width,
                height,
                max: MAX_IMAGE_SIDE,
            });
        }
        let pixels = width as usize * height as usize;
        if color.len() != pixels * 3 {
            return Err(FrameError::BufferLength {
                buffer: "colour",
                actual: color.len(),
                expected: pixels * 3,
            });
        }
        if depth.len() != pixels {
            return Err(FrameError::BufferLength {
                buffer: "depth",
                actual: depth.len(),
                expected: pixels,
            });
        }
        if !(depth_scale.is_finite() && depth_scale > 0.0) {
            return Err(FrameError::BadDepthScale { value: depth_scale });
        }
        Ok(Self {
            width,
            height,
            color,
            depth,
            depth_scale,
        })
    }

    /// Checks that the frame has the camera's size.
    pub fn check_camera(&self, camera: &CameraIntrinsics) -> Result<(), FrameError> {
        if self.width != camera.width || self.height != camera.height {
            return Err(FrameError::SizeMismatch {
                width: self.width,
                height: self.height,
                camera_width: camera.width,
                camera_height: camera.height,
            });
        }
        Ok(())
    }

    /// Number of pixels.
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrong_buffer_lengths_are_errors() {
        let color = [0u8; 12];
        let depth = [0u16; 4];
        assert!(Frame::new(2, 2, &color, &depth, 0.001).is_ok());
        assert!(matches!(
            Frame::new(2, 2, &color[..11], &depth, 0.001),
            Err(FrameError::BufferLength {
                buffer: "colour",
                ..
            })
        ));
        assert!(matches!(
            Frame::new(2, 2, &color, &depth[..3], 0.001),
            Err(FrameError::BufferLength {
                buffer: "depth",
                ..
            })
        ));
        assert!(Frame::new(2, 2, &color, &depth, f64::NAN).is_err());
        assert!(Frame::new(0, 2, &[], &[], 0.001).is_err());
    }
}
