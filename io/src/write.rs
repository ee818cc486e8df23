//! Encoding images and writing sequences in the contract's layout.

use std::path::Path;

use crate::error::SequenceError;

/// JPEG quality of written colour frames.
pub const JPEG_QUALITY: u8 = 92;

pub(crate) fn io_err(path: &Path, source: std::io::Error) -> SequenceError {
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

/// Encodes `data` as a PNG of `color` and `depth`.
pub(crate) fn encode_png(
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

/// The header of a YUV4MPEG2 video (`.y4m`) of 4:2:0 frames, full-range
/// BT.601 (`C420jpeg`): what Chromium's fake camera plays
/// (`--use-file-for-fake-video-capture`).
pub fn y4m_header(width: u32, height: u32, fps: u32) -> Vec<u8> {
    format!("YUV4MPEG2 W{width} H{height} F{fps}:1 Ip A1:1 C420jpeg\n").into_bytes()
}

/// One RGB8 frame of a `.y4m` video: `FRAME`, the Y plane, then U and V
/// averaged over each 2x2 block (JPEG's full-range BT.601 conversion).
/// `width` and `height` must be even.
pub fn y4m_frame(width: u32, height: u32, rgb: &[u8]) -> Result<Vec<u8>, SequenceError> {
    let (w, h) = (width as usize, height as usize);
    if w % 2 != 0 || h % 2 != 0 || rgb.len() != 3 * w * h {
        return Err(SequenceError::invalid(
            "y4m",
            format!(
                "{width}x{height} RGB8 with even sides needed, got {} bytes",
                rgb.len()
            ),
        ));
    }
    let px = |i: usize| {
        (
            rgb[3 * i] as f64,
            rgb[3 * i + 1] as f64,
            rgb[3 * i + 2] as f64,
        )
    };
    let byte = |v: f64| v.round().clamp(0.0, 255.0) as u8;
    let mut out = Vec::with_capacity(6 + w * h * 3 / 2);
    out.extend_from_slice(b"FRAME\n");
    out.extend((0..w * h).map(|i| {
        let (r, g, b) = px(i);
        byte(0.299 * r + 0.587 * g + 0.114 * b)
    }));
    let (mut u, mut v) = (Vec::with_capacity(w * h / 4), Vec::with_capacity(w * h / 4));
    for y in (0..h).step_by(2) {
        for x in (0..w).step_by(2) {
            let (mut cb, mut cr) = (0.0, 0.0);
            for i in [
                y * w + x,
                y * w + x + 1,
                (y + 1) * w + x,
                (y + 1) * w + x + 1,
            ] {
                let (r, g, b) = px(i);
                cb += 128.0 - 0.168_736 * r - 0.331_264 * g + 0.5 * b;
                cr += 128.0 + 0.5 * r - 0.418_688 * g - 0.081_312 * b;
            }
            u.push(byte(cb / 4.0));
            v.push(byte(cr / 4.0));
        }
    }
    out.extend(u);
    out.extend(v);
    Ok(out)
}

/// Writes `bytes` to `path`, creating parent folders.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), SequenceError> {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).map_err(|e| io_err(parent, e))?;
    }
    std::fs::write(path, bytes).map_err(|e| io_err(path, e))
}

/// `value` as pretty JSON (the layout of the files people read: settings,
/// results); `path` names the file in errors.
pub fn json_bytes<T: serde::Serialize>(path: &str, value: &T) -> Result<Vec<u8>, SequenceError> {
    serde_json::to_vec_pretty(value).map_err(|e| json_error(path, e))
}

/// `value` as JSON without indentation (for files of many numbers).
pub fn compact_json_bytes<T: serde::Serialize>(
    path: &str,
    value: &T,
) -> Result<Vec<u8>, SequenceError> {
    serde_json::to_vec(value).map_err(|e| json_error(path, e))
}

pub(crate) fn json_error(path: &str, e: serde_json::Error) -> SequenceError {
    SequenceError::Json {
        path: path.to_string(),
        message: e.to_string(),
    }
}

/// Writes `value` as pretty JSON to `path`.
pub fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> Result<(), SequenceError> {
    write_file(path, &json_bytes(&path.display().to_string(), value)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// JPEG's full-range BT.601: white is (255, 128, 128), pure red
    /// (76, 85, 255), pure blue (29, 255, 107); chroma is the mean of each
    /// 2x2 block, laid out after the whole Y plane.
    #[test]
    fn y4m_frames_hold_full_range_bt601_planes() {
        let (w, h) = (4u32, 2u32);
        let mut rgb = Vec::new();
        for _ in 0..h {
            rgb.extend_from_slice(&[255, 255, 255, 255, 255, 255, 255, 0, 0, 0, 0, 255]);
        }
        let f = y4m_frame(w, h, &rgb).expect("frame");
        assert_eq!(&f[..6], b"FRAME\n");
        assert_eq!(&f[6..14], &[255, 255, 76, 29, 255, 255, 76, 29]);
        // Block 0 is white; block 1 averages red and blue.
        let (u, v) = (&f[14..16], &f[16..18]);
        assert_eq!((u[0], v[0]), (128, 128));
        assert_eq!((u[1], v[1]), (170, 181));
        assert_eq!(f.len(), 6 + 8 + 2 + 2);
        assert!(y4m_frame(3, 2, &[0; 18]).is_err());
        assert!(y4m_frame(4, 2, &[0; 5]).is_err());
        assert_eq!(
            y4m_header(640, 480, 30),
            b"YUV4MPEG2 W640 H480 F30:1 Ip A1:1 C420jpeg\n"
        );
    }
}
