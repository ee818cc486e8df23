//! The ROS messages a camera recording carries, decoded from their
//! serialised form: ROS1's (little-endian, `u32`-prefixed strings and
//! arrays, no padding) or ROS 2's CDR (a 4-byte encapsulation header, each
//! primitive aligned to its size, strings counted with their NUL, no `seq`
//! in the header). Trailing bytes after the known fields are ignored:
//! librealsense's writer leaves some after `sensor_msgs/Image`.

use crate::bytes::Cursor;
use crate::error::RecordingError;

/// Most distortion coefficients read from a `CameraInfo`.
pub const MAX_DISTORTION_COEFFS: usize = 16;

/// `std_msgs/Header`.
#[derive(Debug, Clone, PartialEq)]
pub struct Header {
    /// Capture time, nanoseconds.
    pub stamp_ns: u64,
    /// Frame id.
    pub frame_id: String,
}

/// `sensor_msgs/Image`, borrowing its pixels.
#[derive(Debug, Clone)]
pub struct Image<'a> {
    /// Header.
    pub header: Header,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// Pixel encoding, as `rgb8` or `16UC1`.
    pub encoding: String,
    /// Multi-byte pixels are big-endian.
    pub big_endian: bool,
    /// Bytes per row.
    pub step: u32,
    /// Pixels.
    pub data: &'a [u8],
}

/// `sensor_msgs/CompressedImage`, borrowing its bytes.
#[derive(Debug, Clone)]
pub struct CompressedImage<'a> {
    /// Header.
    pub header: Header,
    /// Format, as `jpeg`, `png` or `16UC1; compressedDepth png`.
    pub format: String,
    /// The compressed bytes.
    pub data: &'a [u8],
}

/// The fields of `sensor_msgs/CameraInfo` a tracker needs.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraInfo {
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// Distortion model name, as written by the recorder.
    pub distortion_model: String,
    /// Distortion coefficients.
    pub d: Vec<f64>,
    /// The 3x3 camera matrix, row-major.
    pub k: [f64; 9],
}

/// `geometry_msgs/Transform`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transform {
    /// Translation, metres.
    pub translation: [f64; 3],
    /// Rotation quaternion `x, y, z, w`.
    pub rotation: [f64; 4],
}

/// How a message is serialised.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wire {
    /// ROS1.
    Ros1,
    /// ROS 2's CDR, little-endian.
    Cdr,
}

/// Reads fields in order, aligning them as the wire format does.
struct Reader<'a> {
    c: Cursor<'a>,
    wire: Wire,
}

impl<'a> Reader<'a> {
    fn new(data: &'a [u8], wire: Wire) -> Result<Self, RecordingError> {
        let mut c = Cursor::new(data, 0);
        if wire == Wire::Cdr {
            let head = c.take(4, "CDR encapsulation header")?;
            if head[..2] != [0, 1] {
                return Err(RecordingError::corrupt(
                    0,
                    format!(
                        "CDR representation {:02x}{:02x} (only little-endian CDR, 0001, is read)",
                        head[0], head[1]
                    ),
                ));
            }
            // Alignment counts from after the header.
            c = Cursor::new(&data[4..], 4);
        }
        Ok(Self { c, wire })
    }

    fn align(&mut self, n: usize) -> Result<(), RecordingError> {
        if self.wire == Wire::Cdr {
            let pos = (self.c.offset() - 4) as usize;
            let pad = (n - pos % n) % n;
            self.c.take(pad, "padding")?;
        }
        Ok(())
    }

    fn u8(&mut self, what: &str) -> Result<u8, RecordingError> {
        self.c.u8(what)
    }

    fn u32(&mut self, what: &str) -> Result<u32, RecordingError> {
        self.align(4)?;
        self.c.u32(what)
    }

    fn f32(&mut self, what: &str) -> Result<f32, RecordingError> {
        self.align(4)?;
        self.c.f32(what)
    }

    fn f64(&mut self, what: &str) -> Result<f64, RecordingError> {
        self.align(8)?;
        self.c.f64(what)
    }

    fn bytes(&mut self, what: &str) -> Result<&'a [u8], RecordingError> {
        self.align(4)?;
        self.c.bytes(what)
    }

    fn string(&mut self, what: &str) -> Result<String, RecordingError> {
        let offset = self.c.offset();
        let mut b = self.bytes(what)?;
        if self.wire == Wire::Cdr {
            b = b.strip_suffix(&[0]).unwrap_or(b);
        }
        String::from_utf8(b.to_vec())
            .map_err(|_| RecordingError::corrupt(offset, format!("{what}: not UTF-8")))
    }

    fn header(&mut self) -> Result<Header, RecordingError> {
        if self.wire == Wire::Ros1 {
            let _seq = self.u32("header seq")?;
        }
        let sec = u64::from(self.u32("header stamp")?);
        let nsec = u64::from(self.u32("header stamp")?);
        let frame_id = self.string("header frame_id")?;
        Ok(Header {
            stamp_ns: sec * 1_000_000_000 + nsec,
            frame_id,
        })
    }
}

fn wrap<T>(topic: &str, r: Result<T, RecordingError>) -> Result<T, RecordingError> {
    r.map_err(|e| RecordingError::message(topic, e.to_string()))
}

/// Decodes a `sensor_msgs/Image`.
pub fn image<'a>(data: &'a [u8], wire: Wire, topic: &str) -> Result<Image<'a>, RecordingError> {
    wrap(
        topic,
        (|| {
            let mut c = Reader::new(data, wire)?;
            Ok(Image {
                header: c.header()?,
                height: c.u32("height")?,
                width: c.u32("width")?,
                encoding: c.string("encoding")?,
                big_endian: c.u8("is_bigendian")? != 0,
                step: c.u32("step")?,
                data: c.bytes("data")?,
            })
        })(),
    )
}

/// Decodes a `sensor_msgs/CompressedImage`.
pub fn compressed_image<'a>(
    data: &'a [u8],
    wire: Wire,
    topic: &str,
) -> Result<CompressedImage<'a>, RecordingError> {
    wrap(
        topic,
        (|| {
            let mut c = Reader::new(data, wire)?;
            Ok(CompressedImage {
                header: c.header()?,
                format: c.string("format")?,
                data: c.bytes("data")?,
            })
        })(),
    )
}

/// Decodes a `sensor_msgs/CameraInfo` (`D` / `d`, then `K` / `k`).
pub fn camera_info(data: &[u8], wire: Wire, topic: &str) -> Result<CameraInfo, RecordingError> {
    wrap(
        topic,
        (|| {
            let mut c = Reader::new(data, wire)?;
            c.header()?;
            let height = c.u32("height")?;
            let width = c.u32("width")?;
            let distortion_model = c.string("distortion_model")?;
            let n = c.u32("D length")? as usize;
            if n > MAX_DISTORTION_COEFFS {
                return Err(RecordingError::TooLarge {
                    what: "distortion coefficients",
                    size: n as u64,
                    max: MAX_DISTORTION_COEFFS as u64,
                });
            }
            let d = (0..n).map(|_| c.f64("D")).collect::<Result<Vec<_>, _>>()?;
            let mut k = [0.0; 9];
            for v in &mut k {
                *v = c.f64("K")?;
            }
            Ok(CameraInfo {
                height,
                width,
                distortion_model,
                d,
                k,
            })
        })(),
    )
}

/// Decodes a `geometry_msgs/Transform`.
pub fn transform(data: &[u8], wire: Wire, topic: &str) -> Result<Transform, RecordingError> {
    wrap(
        topic,
        Reader::new(data, wire).and_then(|mut c| transform_fields(&mut c)),
    )
}

fn transform_fields(c: &mut Reader<'_>) -> Result<Transform, RecordingError> {
    let mut translation = [0.0; 3];
    for v in &mut translation {
        *v = c.f64("translation")?;
    }
    let mut rotation = [0.0; 4];
    for v in &mut rotation {
        *v = c.f64("rotation")?;
    }
    Ok(Transform {
        translation,
        rotation,
    })
}

/// One `geometry_msgs/TransformStamped` of a `tf2_msgs/TFMessage`.
#[derive(Debug, Clone, PartialEq)]
pub struct StampedTransform {
    /// The parent frame.
    pub frame_id: String,
    /// The child frame.
    pub child_frame_id: String,
    /// The transform from child to parent coordinates.
    pub transform: Transform,
}

/// Decodes a `tf2_msgs/TFMessage` (`/tf_static`).
pub fn tf_message(
    data: &[u8],
    wire: Wire,
    topic: &str,
) -> Result<Vec<StampedTransform>, RecordingError> {
    wrap(
        topic,
        (|| {
            let mut c = Reader::new(data, wire)?;
            let n = c.u32("transforms length")? as usize;
            // Each transform takes at least 60 bytes: a count past that is corrupt.
            if n > data.len() / 60 {
                return Err(RecordingError::corrupt(
                    0,
                    format!("{n} transforms in {} bytes", data.len()),
                ));
            }
            let mut out = Vec::with_capacity(n);
            for _ in 0..n {
                let header = c.header()?;
                let child_frame_id = c.string("child_frame_id")?;
                let transform = transform_fields(&mut c)?;
                out.push(StampedTransform {
                    frame_id: header.frame_id,
                    child_frame_id,
                    transform,
                });
            }
            Ok(out)
        })(),
    )
}

/// Decodes a `std_msgs/String`.
pub fn string(data: &[u8], wire: Wire, topic: &str) -> Result<String, RecordingError> {
    wrap(
        topic,
        Reader::new(data, wire).and_then(|mut c| c.string("data")),
    )
}

/// Decodes a `std_msgs/Float32`.
pub fn float32(data: &[u8], wire: Wire, topic: &str) -> Result<f32, RecordingError> {
    wrap(
        topic,
        Reader::new(data, wire).and_then(|mut c| c.f32("value")),
    )
}

/// Decodes librealsense's `realsense_msgs/StreamInfo`: the nominal frame rate and the encoding.
pub fn stream_info(data: &[u8], topic: &str) -> Result<(u32, String), RecordingError> {
    wrap(
        topic,
        (|| {
            let mut c = Reader::new(data, Wire::Ros1)?;
            Ok((c.u32("fps")?, c.string("encoding")?))
        })(),
    )
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Serialises a `sensor_msgs/Image` the way ROS1 does.
    pub fn image_bytes(w: u32, h: u32, encoding: &str, step: u32, data: &[u8]) -> Vec<u8> {
        let mut b = Vec::new();
        b.extend(7u32.to_le_bytes());
        b.extend(1u32.to_le_bytes());
        b.extend(500u32.to_le_bytes());
        b.extend(1u32.to_le_bytes());
        b.push(b'1');
        b.extend(h.to_le_bytes());
        b.extend(w.to_le_bytes());
        b.extend((encoding.len() as u32).to_le_bytes());
        b.extend(encoding.as_bytes());
        b.push(0);
        b.extend(step.to_le_bytes());
        b.extend((data.len() as u32).to_le_bytes());
        b.extend(data);
        b
    }

    #[test]
    fn image_fields_in_order_and_trailing_bytes_ignored() {
        let mut b = image_bytes(2, 1, "mono16", 4, &[1, 0, 2, 0]);
        b.extend([0, 0, 0, 0]);
        let im = image(&b, Wire::Ros1, "/d").expect("image");
        assert_eq!((im.width, im.height, im.step), (2, 1, 4));
        assert_eq!(im.encoding, "mono16");
        assert_eq!(im.header.stamp_ns, 1_000_000_500);
        assert_eq!(im.data, &[1, 0, 2, 0]);
    }

    #[test]
    fn truncated_image_names_its_topic() {
        let b = image_bytes(2, 1, "mono16", 4, &[1, 0, 2, 0]);
        let e = image(&b[..b.len() - 1], Wire::Ros1, "/camera/depth").expect_err("truncated");
        assert!(e.to_string().contains("/camera/depth"), "{e}");
    }

    #[test]
    fn cdr_aligns_each_field_and_drops_the_strings_nul() {
        // std_msgs/Header then a u8, a padded u32 and a padded f64.
        let mut b = vec![0u8, 1, 0, 0];
        b.extend(3u32.to_le_bytes()); // sec
        b.extend(7u32.to_le_bytes()); // nanosec
        b.extend(3u32.to_le_bytes());
        b.extend(b"ab\0");
        b.push(9); // u8 at 15
        b.extend([0xee; 0]); // already at 16: no pad for the u32
        b.extend(5u32.to_le_bytes()); // at 16..20
        b.extend([0xee; 4]); // pad to 24 for the f64
        b.extend(2.5f64.to_le_bytes());
        let mut r = Reader::new(&b, Wire::Cdr).expect("header");
        let h = r.header().expect("header");
        assert_eq!((h.stamp_ns, h.frame_id.as_str()), (3_000_000_007, "ab"));
        assert_eq!(r.u8("x").ok(), Some(9));
        assert_eq!(r.u32("y").ok(), Some(5));
        assert_eq!(r.f64("z").ok(), Some(2.5));
        let mut be = b.clone();
        be[1] = 0;
        assert!(
            Reader::new(&be, Wire::Cdr).is_err(),
            "big-endian CDR refused"
        );
    }

    #[test]
    fn camera_info_refuses_a_huge_distortion_array() {
        // A whole message, its D and K arrays present: only the cap refuses it.
        let info = |n: u32| {
            let mut b = Vec::new();
            b.extend([0u8; 12]);
            b.extend(0u32.to_le_bytes());
            b.extend(48u32.to_le_bytes());
            b.extend(64u32.to_le_bytes());
            b.extend(0u32.to_le_bytes());
            b.extend(n.to_le_bytes());
            for _ in 0..n + 9 {
                b.extend(1.0f64.to_le_bytes());
            }
            b
        };
        let at_cap = camera_info(&info(MAX_DISTORTION_COEFFS as u32), Wire::Ros1, "/info");
        assert_eq!(at_cap.expect("at the cap").d.len(), MAX_DISTORTION_COEFFS);
        let e = camera_info(&info(MAX_DISTORTION_COEFFS as u32 + 1), Wire::Ros1, "/info")
            .expect_err("over the cap");
        assert!(e.to_string().contains("distortion coefficients"), "{e}");
    }
}
