//! Image messages to pixels: raw `sensor_msgs/Image` in the encodings a
//! camera writes, and `sensor_msgs/CompressedImage` (PNG or JPEG colour;
//! `compressedDepth` PNG depth behind its 12-byte header), each checked
//! against its stream's size before decoding.

use crate::error::RecordingError;
use crate::images::{self, is_jpeg, is_png, ImageError, Pixels, SizeLimit};
use crate::ros_msgs::{self, Wire};

const COLOR_ENCODINGS: &str =
    "colour streams: rgb8, bgr8, rgba8, bgra8, mono8, or PNG / JPEG compressed";
const DEPTH_ENCODINGS: &str = "depth streams: mono16, 16UC1, 32FC1, or compressedDepth PNG";
/// Bytes before the PNG of a `compressedDepth` message (format and two depth parameters).
pub const COMPRESSED_DEPTH_HEADER: usize = 12;

/// How an image topic's messages carry their pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Payload {
    /// `sensor_msgs/Image`.
    Raw,
    /// `sensor_msgs/CompressedImage`.
    Compressed,
}

/// What an image must be: its topic (for messages) and size.
#[derive(Debug, Clone, Copy)]
pub struct Expect<'a> {
    /// Topic.
    pub topic: &'a str,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
}

impl Expect<'_> {
    fn size(&self, w: u32, h: u32) -> Result<(), RecordingError> {
        if (w, h) != (self.width, self.height) {
            return Err(RecordingError::message(
                self.topic,
                format!(
                    "image is {w}x{h} but its camera_info says {}x{}",
                    self.width, self.height
                ),
            ));
        }
        Ok(())
    }

    fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

/// The rows of an image message as `bpp`-byte pixels, checked against `e`.
fn rows<'a>(
    im: &ros_msgs::Image<'a>,
    e: &Expect<'_>,
    bpp: usize,
) -> Result<impl Iterator<Item = &'a [u8]>, RecordingError> {
    e.size(im.width, im.height)?;
    let row = e.width as usize * bpp;
    let step = im.step as usize;
    if step < row || im.data.len() < step.saturating_mul(e.height as usize) {
        return Err(RecordingError::message(
            e.topic,
            format!(
                "{} bytes of pixels for {}x{} at step {step} ({bpp} bytes a pixel)",
                im.data.len(),
                e.width,
                e.height
            ),
        ));
    }
    let data = im.data;
    Ok((0..e.height as usize).map(move |y| &data[y * step..y * step + row]))
}

/// `bytes` decoded by [`images`], required to be `e`'s size.
fn decode(
    bytes: &[u8],
    e: &Expect<'_>,
    decode: fn(&[u8], SizeLimit) -> Result<Pixels, ImageError>,
) -> Result<Pixels, RecordingError> {
    let limit = SizeLimit {
        width: e.width,
        height: e.height,
    };
    let p = decode(bytes, limit).map_err(|x| RecordingError::message(e.topic, x.to_string()))?;
    e.size(p.width, p.height)?;
    Ok(p)
}

/// RGB8 pixels of a colour message.
pub fn color(
    raw: &[u8],
    wire: Wire,
    payload: Payload,
    e: &Expect<'_>,
) -> Result<Vec<u8>, RecordingError> {
    if payload == Payload::Compressed {
        let im = ros_msgs::compressed_image(raw, wire, e.topic)?;
        if is_jpeg(im.data) {
            return Ok(decode(im.data, e, images::decode_jpeg)?.data);
        }
        if !is_png(im.data) {
            return Err(RecordingError::UnsupportedEncoding {
                topic: e.topic.to_string(),
                encoding: im.format,
                supported: COLOR_ENCODINGS,
            });
        }
        return Ok(decode(im.data, e, images::decode_png)?.into_rgb8());
    }
    let im = ros_msgs::image(raw, wire, e.topic)?;
    // Source channel of R, G, B and the bytes a pixel.
    let (order, bpp): ([usize; 3], usize) = match im.encoding.as_str() {
        "rgb8" => ([0, 1, 2], 3),
        "bgr8" => ([2, 1, 0], 3),
        "rgba8" => ([0, 1, 2], 4),
        "bgra8" => ([2, 1, 0], 4),
        "mono8" => ([0, 0, 0], 1),
        other => {
            return Err(RecordingError::UnsupportedEncoding {
                topic: e.topic.to_string(),
                encoding: other.to_string(),
                supported: COLOR_ENCODINGS,
            })
        }
    };
    let mut out = vec![0u8; e.pixels() * 3];
    let row_len = e.width as usize * 3;
    for (row, dst) in rows(&im, e, bpp)?.zip(out.chunks_exact_mut(row_len)) {
        if order == [0, 1, 2] && bpp == 3 {
            dst.copy_from_slice(row);
            continue;
        }
        for (px, o) in row.chunks_exact(bpp).zip(dst.chunks_exact_mut(3)) {
            o[0] = px[order[0]];
            o[1] = px[order[1]];
            o[2] = px[order[2]];
        }
    }
    Ok(out)
}

/// Depth in units of `units` metres of a depth message.
pub fn depth(
    raw: &[u8],
    wire: Wire,
    payload: Payload,
    e: &Expect<'_>,
    units: f64,
) -> Result<Vec<u16>, RecordingError> {
    if payload == Payload::Compressed {
        let im = ros_msgs::compressed_image(raw, wire, e.topic)?;
        let unsupported = || RecordingError::UnsupportedEncoding {
            topic: e.topic.to_string(),
            encoding: im.format.clone(),
            supported: DEPTH_ENCODINGS,
        };
        // compressedDepth puts its parameters before the PNG; 32-bit depth
        // there is quantised inverse depth, which is not read.
        let png_bytes = if is_png(im.data) {
            im.data
        } else if im.format.starts_with("16UC1") || im.format.starts_with("mono16") {
            im.data
                .get(COMPRESSED_DEPTH_HEADER..)
                .filter(|b| is_png(b))
                .ok_or_else(unsupported)?
        } else {
            return Err(unsupported());
        };
        return decode(png_bytes, e, images::decode_png)?
            .to_u16()
            .ok_or_else(unsupported);
    }
    let im = ros_msgs::image(raw, wire, e.topic)?;
    let mut out = Vec::with_capacity(e.pixels());
    match im.encoding.as_str() {
        "mono16" | "16UC1" => {
            for row in rows(&im, e, 2)? {
                out.extend(row.chunks_exact(2).map(|b| {
                    if im.big_endian {
                        u16::from_be_bytes([b[0], b[1]])
                    } else {
                        u16::from_le_bytes([b[0], b[1]])
                    }
                }));
            }
        }
        "32FC1" => {
            // Metres; NaN and out-of-range values are no measurement.
            for row in rows(&im, e, 4)? {
                out.extend(row.chunks_exact(4).map(|b| {
                    let bytes = [b[0], b[1], b[2], b[3]];
                    let m = if im.big_endian {
                        f32::from_be_bytes(bytes)
                    } else {
                        f32::from_le_bytes(bytes)
                    };
                    let u = f64::from(m) / units;
                    if u.is_finite() && u >= 0.5 && u < f64::from(u16::MAX) {
                        u.round() as u16
                    } else {
                        0
                    }
                }));
            }
        }
        other => {
            return Err(RecordingError::UnsupportedEncoding {
                topic: e.topic.to_string(),
                encoding: other.to_string(),
                supported: DEPTH_ENCODINGS,
            })
        }
    }
    Ok(out)
}
