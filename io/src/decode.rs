//! Image decoding with maintained pure-Rust decoders (`png`, `zune-jpeg`).
//! Sizes are checked from the header before the pixel buffer is allocated.

use upetrack::perception::camera::MAX_IMAGE_SIDE;

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

fn check_size(path: &str, width: u32, height: u32) -> Result<(), SequenceError> {
    if width == 0 || height == 0 {
        return Err(SequenceError::invalid(
            path,
            format!("image is {width}x{height}"),
        ));
    }
    let side = width.max(height);
    if side > MAX_IMAGE_SIDE {
        return Err(SequenceError::too_large(
            path.to_string(),
            "image side in pixels",
            side as u64,
            MAX_IMAGE_SIDE as u64,
        ));
    }
    Ok(())
}

fn decode_err(path: &str, e: impl std::fmt::Display) -> SequenceError {
    SequenceError::Decode {
        path: path.to_string(),
        message: e.to_string(),
    }
}

/// `true` when the bytes start like a PNG file.
pub fn is_png(bytes: &[u8]) -> bool {
    bytes.starts_with(b"\x89PNG\r\n\x1a\n")
}

/// `true` when the bytes start like a JPEG file.
pub fn is_jpeg(bytes: &[u8]) -> bool {
    bytes.starts_with(&[0xFF, 0xD8, 0xFF])
}

fn png_reader<'a>(
    bytes: &'a [u8],
    path: &str,
    transformations: png::Transformations,
) -> Result<png::Reader<std::io::Cursor<&'a [u8]>>, SequenceError> {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(transformations);
    decoder.set_limits(png::Limits {
        bytes: (MAX_IMAGE_SIDE as usize) * (MAX_IMAGE_SIDE as usize) * 8,
    });
    let reader = decoder.read_info().map_err(|e| decode_err(path, e))?;
    let info = reader.info();
    check_size(path, info.width, info.height)?;
    Ok(reader)
}

/// Decodes a colour frame (PNG of any colour type, or baseline/progressive JPEG) to RGB8.
pub fn decode_color(bytes: &[u8], path: &str) -> Result<RgbImage, SequenceError> {
    if is_png(bytes) {
        let mut reader = png_reader(bytes, path, png::Transformations::normalize_to_color8())?;
        let size = reader
            .output_buffer_size()
            .ok_or_else(|| decode_err(path, "image too large"))?;
        let mut buf = vec![0u8; size];
        let info = reader
            .next_frame(&mut buf)
            .map_err(|e| decode_err(path, e))?;
        let samples = info.color_type.samples();
        let buf = &buf[..info.buffer_size()];
        let data: Vec<u8> = match samples {
            1 | 2 => buf
                .chunks_exact(samples)
                .flat_map(|p| [p[0], p[0], p[0]])
                .collect(),
            _ => buf
                .chunks_exact(samples)
                .flat_map(|p| [p[0], p[1], p[2]])
                .collect(),
        };
        Ok(RgbImage {
            width: info.width,
            height: info.height,
            data,
        })
    } else if is_jpeg(bytes) {
        use zune_core::colorspace::ColorSpace;
        use zune_core::options::DecoderOptions;
        // Strict: a truncated or corrupt file is an error, not a grey tail.
        let options = DecoderOptions::default()
            .set_strict_mode(true)
            .jpeg_set_out_colorspace(ColorSpace::RGB)
            .set_max_width(MAX_IMAGE_SIDE as usize)
            .set_max_height(MAX_IMAGE_SIDE as usize);
        let mut decoder =
            zune_jpeg::JpegDecoder::new_with_options(std::io::Cursor::new(bytes), options);
        decoder.decode_headers().map_err(|e| decode_err(path, e))?;
        let (w, h) = decoder
            .dimensions()
            .ok_or_else(|| decode_err(path, "no image dimensions in the header"))?;
        check_size(path, w as u32, h as u32)?;
        let data = decoder.decode().map_err(|e| decode_err(path, e))?;
        if data.len() != w * h * 3 {
            return Err(decode_err(
                path,
                format!("decoded {} bytes for {w}x{h} RGB", data.len()),
            ));
        }
        Ok(RgbImage {
            width: w as u32,
            height: h as u32,
            data,
        })
    } else {
        Err(SequenceError::invalid(path, "not a PNG or JPEG file"))
    }
}

/// Decodes a depth frame: a 16-bit single-channel PNG, nothing else.
pub fn decode_depth(bytes: &[u8], path: &str) -> Result<DepthImage, SequenceError> {
    if !is_png(bytes) {
        return Err(SequenceError::invalid(
            path,
            "depth must be a 16-bit single-channel PNG; this is not a PNG file",
        ));
    }
    let mut reader = png_reader(bytes, path, png::Transformations::IDENTITY)?;
    let info = reader.info();
    if info.color_type != png::ColorType::Grayscale || info.bit_depth != png::BitDepth::Sixteen {
        return Err(SequenceError::invalid(
            path,
            format!(
                "depth must be a 16-bit single-channel PNG, found {:?} with {} bits",
                info.color_type, info.bit_depth as u8
            ),
        ));
    }
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| decode_err(path, "image too large"))?;
    let mut buf = vec![0u8; size];
    let frame = reader
        .next_frame(&mut buf)
        .map_err(|e| decode_err(path, e))?;
    let data = buf[..frame.buffer_size()]
        .chunks_exact(2)
        .map(|b| u16::from_be_bytes([b[0], b[1]]))
        .collect();
    Ok(DepthImage {
        width: frame.width,
        height: frame.height,
        data,
    })
}
