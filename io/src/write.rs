//! Encoding images and writing sequences in the contract's layout.

use std::path::Path;

use crate::error::SequenceError;

/// JPEG quality of written colour frames.
pub const JPEG_QUALITY: u8 = 92;

fn io_err(path: &Path, source: std::io::Error) -> SequenceError {
    SequenceError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// Encodes RGB8 as JPEG.
pub fn encode_jpeg(
    width: u32,
    height: u32,
    rgb: &[u8],
    quality: u8,
) -> Result<Vec<u8>, SequenceError> {
    let mut out = Vec::new();
    let (w, h) = (u16::try_from(width), u16::try_from(height));
    let (Ok(w), Ok(h)) = (w, h) else {
        return Err(SequenceError::invalid("jpeg", "image too large for JPEG"));
    };
    jpeg_encoder::Encoder::new(&mut out, quality)
        .encode(rgb, w, h, jpeg_encoder::ColorType::Rgb)
        .map_err(|e| SequenceError::invalid("jpeg", e.to_string()))?;
    Ok(out)
}

fn encode_png(
    width: u32,
    height: u32,
    color: png::ColorType,
    depth: png::BitDepth,
    data: &[u8],
) -> Result<Vec<u8>, SequenceError> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, width, height);
        enc.set_color(color);
        enc.set_depth(depth);
        enc.set_compression(png::Compression::Fast);
        let err = |e: png::EncodingError| SequenceError::invalid("png", e.to_string());
        enc.write_header()
            .map_err(err)?
            .write_image_data(data)
            .map_err(err)?;
    }
    Ok(out)
}

/// Encodes RGB8 as PNG.
pub fn encode_rgb_png(width: u32, height: u32, rgb: &[u8]) -> Result<Vec<u8>, SequenceError> {
    encode_png(
        width,
        height,
        png::ColorType::Rgb,
        png::BitDepth::Eight,
        rgb,
    )
}

/// Encodes 16-bit depth as a single-channel PNG.
pub fn encode_depth_png(width: u32, height: u32, depth: &[u16]) -> Result<Vec<u8>, SequenceError> {
    let bytes: Vec<u8> = depth.iter().flat_map(|d| d.to_be_bytes()).collect();
    encode_png(
        width,
        height,
        png::ColorType::Grayscale,
        png::BitDepth::Sixteen,
        &bytes,
    )
}

/// Writes `bytes` to `path`, creating parent folders.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), SequenceError> {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).map_err(|e| io_err(parent, e))?;
    }
    std::fs::write(path, bytes).map_err(|e| io_err(path, e))
}

/// Writes `value` as pretty JSON to `path`.
pub fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> Result<(), SequenceError> {
    let text = serde_json::to_string_pretty(value).map_err(|e| SequenceError::Json {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    write_file(path, text.as_bytes())
}
