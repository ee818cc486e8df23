//! The project's one PNG and JPEG decoding path (`png`, `zune-jpeg`, pure
//! Rust): frames of sequence folders (`upetrack-io`) and images inside
//! recordings both decode here, with the same limits. The size is read from
//! the header and refused above the caller's largest before any pixel
//! buffer is allocated.

use upetrack::perception::camera::MAX_IMAGE_SIDE;

/// The first bytes of every PNG file.
pub const PNG_MAGIC: &[u8] = b"\x89PNG\r\n\x1a\n";
/// The first bytes of every JPEG file.
pub const JPEG_MAGIC: &[u8] = &[0xff, 0xd8, 0xff];

/// `true` when the bytes start like a PNG file.
pub fn is_png(bytes: &[u8]) -> bool {
    bytes.starts_with(PNG_MAGIC)
}

/// `true` when the bytes start like a JPEG file.
pub fn is_jpeg(bytes: &[u8]) -> bool {
    bytes.starts_with(JPEG_MAGIC)
}

/// The largest image a caller takes, pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SizeLimit {
    /// Most columns.
    pub width: u32,
    /// Most rows.
    pub height: u32,
}

impl SizeLimit {
    /// Any image up to [`MAX_IMAGE_SIDE`] on each side.
    pub const ANY: Self = Self {
        width: MAX_IMAGE_SIDE,
        height: MAX_IMAGE_SIDE,
    };
}

/// Why an image was not decoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ImageError {
    /// The header gives a size above the limit; nothing was allocated.
    #[error("image is {width}x{height}, above the largest taken here ({max_width}x{max_height})")]
    TooLarge {
        /// Columns in the header.
        width: u32,
        /// Rows in the header.
        height: u32,
        /// The limit's columns.
        max_width: u32,
        /// The limit's rows.
        max_height: u32,
    },
    /// A side of zero.
    #[error("image is {width}x{height}")]
    Empty {
        /// Columns.
        width: u32,
        /// Rows.
        height: u32,
    },
    /// The decoder refused the bytes.
    #[error("{format}: {message}")]
    Decode {
        /// `PNG` or `JPEG`.
        format: &'static str,
        /// The decoder's words.
        message: String,
    },
}

/// Decoded pixels: `channels` interleaved samples of 8 or 16 bits
/// (16-bit samples big-endian, as PNG stores them).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pixels {
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Samples per pixel: 1 grey, 2 grey and alpha, 3 RGB, 4 RGBA.
    pub channels: usize,
    /// `true` for 16-bit samples.
    pub sixteen: bool,
    /// Row-major samples.
    pub data: Vec<u8>,
}

impl Pixels {
    /// RGB8: grey spread to three channels, alpha dropped, 16-bit samples
    /// cut to their high byte.
    pub fn to_rgb8(&self) -> Vec<u8> {
        let bytes = if self.sixteen { 2 } else { 1 };
        let stride = self.channels * bytes;
        let mut out = Vec::with_capacity(self.data.len() / stride.max(1) * 3);
        for px in self.data.chunks_exact(stride.max(1)) {
            let sample = |c: usize| px[c * bytes];
            match self.channels {
                1 | 2 => out.extend([sample(0); 3]),
                _ => out.extend([sample(0), sample(1), sample(2)]),
            }
        }
        out
    }

    /// [`Pixels::to_rgb8`], without a copy when the pixels already are RGB8.
    pub fn into_rgb8(self) -> Vec<u8> {
        if self.channels == 3 && !self.sixteen {
            self.data
        } else {
            self.to_rgb8()
        }
    }

    /// The values of a 16-bit single-channel image (depth), or `None` for
    /// any other kind.
    pub fn to_u16(&self) -> Option<Vec<u16>> {
        (self.sixteen && self.channels == 1).then(|| {
            // Into a buffer of known length, so that the byte swap vectorises.
            let mut out = vec![0u16; self.data.len() / 2];
            for (o, b) in out.iter_mut().zip(self.data.chunks_exact(2)) {
                *o = u16::from_be_bytes([b[0], b[1]]);
            }
            out
        })
    }
}

fn check(width: u32, height: u32, limit: SizeLimit) -> Result<(), ImageError> {
    if width == 0 || height == 0 {
        return Err(ImageError::Empty { width, height });
    }
    if width > limit.width || height > limit.height {
        return Err(ImageError::TooLarge {
            width,
            height,
            max_width: limit.width,
            max_height: limit.height,
        });
    }
    Ok(())
}

/// A PNG of any colour type, palettes and low bit depths expanded.
pub fn decode_png(bytes: &[u8], limit: SizeLimit) -> Result<Pixels, ImageError> {
    let err = |e: png::DecodingError| ImageError::Decode {
        format: "PNG",
        message: e.to_string(),
    };
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND);
    // The decoder's own cap, as a second guard: four 16-bit samples a pixel.
    decoder.set_limits(png::Limits {
        bytes: (limit.width as usize) * (limit.height as usize) * 8,
    });
    let mut reader = decoder.read_info().map_err(err)?;
    let info = reader.info();
    check(info.width, info.height, limit)?;
    let size = reader.output_buffer_size().ok_or(ImageError::Decode {
        format: "PNG",
        message: "image too large".into(),
    })?;
    let mut data = vec![0u8; size];
    let frame = reader.next_frame(&mut data).map_err(err)?;
    data.truncate(frame.buffer_size());
    Ok(Pixels {
        width: frame.width,
        height: frame.height,
        channels: frame.color_type.samples(),
        sixteen: frame.bit_depth == png::BitDepth::Sixteen,
        data,
    })
}

/// A baseline or progressive JPEG as RGB8; strict, so a truncated or
/// corrupt file is an error rather than a grey tail.
pub fn decode_jpeg(bytes: &[u8], limit: SizeLimit) -> Result<Pixels, ImageError> {
    use zune_core::colorspace::ColorSpace;
    use zune_core::options::DecoderOptions;
    let err = |message: String| ImageError::Decode {
        format: "JPEG",
        message,
    };
    let options = DecoderOptions::default()
        .set_strict_mode(true)
        .jpeg_set_out_colorspace(ColorSpace::RGB)
        .set_max_width(limit.width as usize)
        .set_max_height(limit.height as usize);
    let mut d = zune_jpeg::JpegDecoder::new_with_options(std::io::Cursor::new(bytes), options);
    d.decode_headers().map_err(|e| err(e.to_string()))?;
    let (w, h) = d
        .dimensions()
        .ok_or_else(|| err("no image dimensions in the header".into()))?;
    let (width, height) = (
        u32::try_from(w).unwrap_or(u32::MAX),
        u32::try_from(h).unwrap_or(u32::MAX),
    );
    check(width, height, limit)?;
    let data = d.decode().map_err(|e| err(e.to_string()))?;
    if data.len() != w * h * 3 {
        return Err(err(format!("decoded {} bytes for {w}x{h} RGB", data.len())));
    }
    Ok(Pixels {
        width,
        height,
        channels: 3,
        sixteen: false,
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
        let mut out = Vec::new();
        let mut e = png::Encoder::new(&mut out, width, height);
        e.set_color(color);
        e.set_depth(depth);
        let mut w = e.write_header().expect("header");
        w.write_image_data(data).expect("data");
        w.finish().expect("finish");
        out
    }

    #[test]
    fn a_png_larger_than_the_limit_is_refused_from_its_header() {
        let png = png_of(
            4,
            3,
            png::ColorType::Grayscale,
            png::BitDepth::Eight,
            &[0; 12],
        );
        let small = SizeLimit {
            width: 3,
            height: 3,
        };
        assert!(matches!(
            decode_png(&png, small),
            Err(ImageError::TooLarge {
                width: 4,
                height: 3,
                ..
            })
        ));
        let ok = decode_png(&png, SizeLimit::ANY).expect("decoded");
        assert_eq!(
            (ok.width, ok.height, ok.channels, ok.sixteen),
            (4, 3, 1, false)
        );
    }

    #[test]
    fn an_image_at_the_limit_decodes_and_a_side_of_zero_is_empty() {
        // 64x64 RGBA of 16 bits: 32 KB, exactly what a 64x64 limit allows.
        let png = png_of(
            64,
            64,
            png::ColorType::Rgba,
            png::BitDepth::Sixteen,
            &[7; 64 * 64 * 8],
        );
        let limit = SizeLimit {
            width: 64,
            height: 64,
        };
        assert_eq!(
            decode_png(&png, limit).expect("at the limit").data.len(),
            64 * 64 * 8
        );
        assert!(matches!(
            check(0, 5, SizeLimit::ANY),
            Err(ImageError::Empty { .. })
        ));
        assert!(matches!(
            check(5, 0, SizeLimit::ANY),
            Err(ImageError::Empty { .. })
        ));
        assert!(check(5, 5, SizeLimit::ANY).is_ok());
    }

    #[test]
    fn a_jpeg_decodes_to_rgb_within_its_limit() {
        let rgb: Vec<u8> = (0..8 * 6 * 3).map(|i| (i * 5 % 256) as u8).collect();
        let mut jpeg = Vec::new();
        jpeg_encoder::Encoder::new(&mut jpeg, 90)
            .encode(&rgb, 8, 6, jpeg_encoder::ColorType::Rgb)
            .expect("encoded");
        assert!(is_jpeg(&jpeg) && !is_png(&jpeg));
        let p = decode_jpeg(&jpeg, SizeLimit::ANY).expect("decoded");
        assert_eq!(
            (p.width, p.height, p.channels, p.data.len()),
            (8, 6, 3, 8 * 6 * 3)
        );
        let small = SizeLimit {
            width: 8,
            height: 5,
        };
        assert!(decode_jpeg(&jpeg, small).is_err());
        assert!(
            decode_jpeg(&jpeg[..jpeg.len() / 2], SizeLimit::ANY).is_err(),
            "strict: a cut file is refused"
        );
    }

    #[test]
    fn sixteen_bit_samples_give_depth_and_their_high_byte_as_colour() {
        let data = [0x12, 0x34, 0xab, 0xcd];
        let png = png_of(
            2,
            1,
            png::ColorType::Grayscale,
            png::BitDepth::Sixteen,
            &data,
        );
        let p = decode_png(&png, SizeLimit::ANY).expect("decoded");
        assert_eq!(p.to_u16(), Some(vec![0x1234, 0xabcd]));
        assert_eq!(p.to_rgb8(), [0x12, 0x12, 0x12, 0xab, 0xab, 0xab]);
        let rgba = png_of(
            1,
            1,
            png::ColorType::Rgba,
            png::BitDepth::Eight,
            &[1, 2, 3, 4],
        );
        let p = decode_png(&rgba, SizeLimit::ANY).expect("decoded");
        assert_eq!(p.to_rgb8(), [1, 2, 3]);
        assert_eq!(p.to_u16(), None);
        // Eight-bit grey is no depth either.
        let grey = png_of(
            2,
            1,
            png::ColorType::Grayscale,
            png::BitDepth::Eight,
            &[9, 10],
        );
        assert_eq!(
            decode_png(&grey, SizeLimit::ANY).expect("decoded").to_u16(),
            None
        );
    }
}
