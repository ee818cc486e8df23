//! A sequence's frame files decoded, through the project's one PNG and JPEG
//! path ([`upetrack_recordings::images`]): sizes checked from the header
//! before the pixel buffer is allocated.

use upetrack::perception::camera::MAX_IMAGE_SIDE;
use upetrack_recordings::images::{self, ImageError, SizeLimit};
pub use upetrack_recordings::images::{is_jpeg, is_png};

use crate::error::SequenceError;

/// A decoded 8-bit RGB image.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RgbImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major RGB.
    pub data: Vec<u8>,
}

/// A decoded 16-bit depth image.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DepthImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major depth units.
    pub data: Vec<u16>,
}

/// An image refused by the shared decoder, as the sequence's error naming `path`.
fn image_error(path: &str, e: ImageError) -> SequenceError {
    match e {
        ImageError::TooLarge { width, height, .. } => SequenceError::too_large(
            path.to_string(),
            "image side in pixels",
            u64::from(width.max(height)),
            u64::from(MAX_IMAGE_SIDE),
        ),
        ImageError::Empty { .. } => SequenceError::invalid(path, e.to_string()),
        ImageError::Decode { .. } => SequenceError::Decode {
            path: path.to_string(),
            message: e.to_string(),
        },
    }
}

/// Decodes a colour frame (PNG of any colour type, or baseline/progressive JPEG) to RGB8.
pub fn decode_color(bytes: &[u8], path: &str) -> Result<RgbImage, SequenceError> {
    let pixels = if is_png(bytes) {
        images::decode_png(bytes, SizeLimit::ANY)
    } else if is_jpeg(bytes) {
        images::decode_jpeg(bytes, SizeLimit::ANY)
    } else {
        return Err(SequenceError::invalid(path, "not a PNG or JPEG file"));
    }
    .map_err(|e| image_error(path, e))?;
    Ok(RgbImage {
        width: pixels.width,
        height: pixels.height,
        data: pixels.into_rgb8(),
    })
}

/// Decodes a depth frame: a 16-bit single-channel PNG, nothing else.
pub fn decode_depth(bytes: &[u8], path: &str) -> Result<DepthImage, SequenceError> {
    if !is_png(bytes) {
        return Err(SequenceError::invalid(
            path,
            "depth must be a 16-bit single-channel PNG; this is not a PNG file",
        ));
    }
    let pixels = images::decode_png(bytes, SizeLimit::ANY).map_err(|e| image_error(path, e))?;
    let data = pixels.to_u16().ok_or_else(|| {
        SequenceError::invalid(
            path,
            format!(
                "depth must be a 16-bit single-channel PNG, found {} channel(s) of {} bits",
                pixels.channels,
                if pixels.sixteen { 16 } else { 8 }
            ),
        )
    })?;
    Ok(DepthImage {
        width: pixels.width,
        height: pixels.height,
        data,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png_of(
        width: u32,
        height: u32,
        color: png::ColorType,
        depth: png::BitDepth,
        data: &[u8],
    ) -> Vec<u8> {
        crate::write::encode_png(width, height, color, depth, data).expect("encoded")
    }

    #[test]
    fn depth_is_a_16_bit_grey_png_and_nothing_else() {
        let depth = png_of(
            2,
            1,
            png::ColorType::Grayscale,
            png::BitDepth::Sixteen,
            &[1, 2, 3, 4],
        );
        let d = decode_depth(&depth, "d.png").expect("depth");
        assert_eq!((d.width, d.height, d.data), (2, 1, vec![0x0102, 0x0304]));
        let grey8 = png_of(
            2,
            1,
            png::ColorType::Grayscale,
            png::BitDepth::Eight,
            &[1, 2],
        );
        let e = decode_depth(&grey8, "g.png")
            .expect_err("8-bit")
            .to_string();
        assert!(
            e.contains("g.png") && e.contains("16-bit single-channel"),
            "{e}"
        );
        let e = decode_depth(&[0xff, 0xd8, 0xff, 0xe0], "j.jpg")
            .expect_err("a JPEG")
            .to_string();
        assert!(e.contains("not a PNG file"), "{e}");
    }

    #[test]
    fn colour_of_any_png_kind_is_rgb8() {
        let rgb = png_of(
            1,
            1,
            png::ColorType::Rgb,
            png::BitDepth::Eight,
            &[10, 20, 30],
        );
        assert_eq!(decode_color(&rgb, "c.png").expect("rgb").data, [10, 20, 30]);
        let rgb16 = png_of(
            1,
            1,
            png::ColorType::Rgb,
            png::BitDepth::Sixteen,
            &[10, 1, 20, 2, 30, 3],
        );
        assert_eq!(
            decode_color(&rgb16, "c.png").expect("rgb16").data,
            [10, 20, 30]
        );
        let grey = png_of(1, 1, png::ColorType::Grayscale, png::BitDepth::Eight, &[7]);
        assert_eq!(decode_color(&grey, "c.png").expect("grey").data, [7, 7, 7]);
        let e = decode_color(b"GIF89a", "c.gif")
            .expect_err("a GIF")
            .to_string();
        assert!(e.contains("not a PNG or JPEG"), "{e}");
    }
}
