//! Image messages to pixels: raw `sensor_msgs/Image` in the encodings a
//! camera writes, and `sensor_msgs/CompressedImage` (PNG or JPEG colour;
//! `compressedDepth` PNG depth behind its 12-byte header), each checked
//! against its stream's size before decoding.

use crate::error::RecordingError;
use crate::ros_msgs::{self, Wire};

const COLOR_ENCODINGS: &str =
    "colour streams: rgb8, bgr8, rgba8, bgra8, mono8, or PNG / JPEG compressed";
const DEPTH_ENCODINGS: &str = "depth streams: mono16, 16UC1, 32FC1, or compressedDepth PNG";
/// Bytes before the PNG of a `compressedDepth` message (format and two depth parameters).
pub const COMPRESSED_DEPTH_HEADER: usize = 12;
const PNG_MAGIC: &[u8] = b"\x89PNG\r\n\x1a\n";
const JPEG_MAGIC: &[u8] = &[0xff, 0xd8, 0xff];

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

/// A PNG's pixels as 8-bit channels (`channels` each) or 16-bit values.
struct Png {
    channels: usize,
    sixteen: bool,
    data: Vec<u8>,
}

fn decode_png(bytes: &[u8], e: &Expect<'_>) -> Result<Png, RecordingError> {
    let err = |m: String| RecordingError::message(e.topic, format!("PNG: {m}"));
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(|x| err(x.to_string()))?;
    let info = reader.info();
    e.size(info.width, info.height)?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| err("too large".into()))?;
    let mut data = vec![0u8; size];
    let frame = reader
        .next_frame(&mut data)
        .map_err(|x| err(x.to_string()))?;
    data.truncate(frame.buffer_size());
    Ok(Png {
        channels: frame.color_type.samples(),
        sixteen: frame.bit_depth == png::BitDepth::Sixteen,
        data,
    })
}

fn decode_jpeg(bytes: &[u8], e: &Expect<'_>) -> Result<Vec<u8>, RecordingError> {
    use zune_core::colorspace::ColorSpace;
    use zune_core::options::DecoderOptions;
    let err = |m: String| RecordingError::message(e.topic, format!("JPEG: {m}"));
    let options = DecoderOptions::default()
        .jpeg_set_out_colorspace(ColorSpace::RGB)
        .set_strict_mode(true)
        .set_max_width(e.width as usize)
        .set_max_height(e.height as usize);
    let mut d = zune_jpeg::JpegDecoder::new_with_options(std::io::Cursor::new(bytes), options);
    d.decode_headers().map_err(|x| err(format!("{x:?}")))?;
    let (w, h) = d.dimensions().ok_or_else(|| err("no size".into()))?;
    e.size(w as u32, h as u32)?;
    let data = d.decode().map_err(|x| err(format!("{x:?}")))?;
    if data.len() != e.pixels() * 3 {
        return Err(err(format!("decoded {} bytes for {w}x{h} RGB", data.len())));
    }
    Ok(data)
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
        if im.data.starts_with(JPEG_MAGIC) {
            return decode_jpeg(im.data, e);
        }
        if !im.data.starts_with(PNG_MAGIC) {
            return Err(RecordingError::UnsupportedEncoding {
                topic: e.topic.to_string(),
                encoding: im.format,
                supported: COLOR_ENCODINGS,
            });
        }
        let png = decode_png(im.data, e)?;
        if png.sixteen {
            return Err(RecordingError::UnsupportedEncoding {
                topic: e.topic.to_string(),
                encoding: format!("{} (16-bit PNG)", im.format),
                supported: COLOR_ENCODINGS,
            });
        }
        let c = png.channels;
        let mut out = Vec::with_capacity(e.pixels() * 3);
        for px in png.data.chunks_exact(c) {
            match c {
                1 | 2 => out.extend([px[0]; 3]),
                _ => out.extend(&px[..3]),
            }
        }
        return Ok(out);
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
        let png_bytes = if im.data.starts_with(PNG_MAGIC) {
            im.data
        } else if im.format.starts_with("16UC1") || im.format.starts_with("mono16") {
            im.data
                .get(COMPRESSED_DEPTH_HEADER..)
                .filter(|b| b.starts_with(PNG_MAGIC))
                .ok_or_else(unsupported)?
        } else {
            return Err(unsupported());
        };
        let png = decode_png(png_bytes, e)?;
        if !png.sixteen || png.channels != 1 {
            return Err(unsupported());
        }
        return Ok(png
            .data
            .chunks_exact(2)
            .map(|b| u16::from_be_bytes([b[0], b[1]]))
            .collect());
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
