//! The ROS1 messages a camera recording carries, decoded from their
//! serialised form (little-endian, `u32`-prefixed strings and arrays).
//! Trailing bytes after the known fields are ignored: librealsense's writer
//! leaves some after `sensor_msgs/Image`.

use crate::bytes::Cursor;
use crate::error::RecordingError;
use crate::rosbag1::ros_time_ns;

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

fn header(c: &mut Cursor<'_>) -> Result<Header, RecordingError> {
    let _seq = c.u32("header seq")?;
    let stamp_ns = ros_time_ns(c, "header stamp")?;
    let frame_id = c.string("header frame_id")?;
    Ok(Header { stamp_ns, frame_id })
}

fn wrap<T>(topic: &str, r: Result<T, RecordingError>) -> Result<T, RecordingError> {
    r.map_err(|e| RecordingError::message(topic, e.to_string()))
}

/// Decodes a `sensor_msgs/Image`.
pub fn image<'a>(data: &'a [u8], topic: &str) -> Result<Image<'a>, RecordingError> {
    let mut c = Cursor::new(data, 0);
    wrap(
        topic,
        (|| {
            Ok(Image {
                header: header(&mut c)?,
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
    topic: &str,
) -> Result<CompressedImage<'a>, RecordingError> {
    let mut c = Cursor::new(data, 0);
    wrap(
        topic,
        (|| {
            Ok(CompressedImage {
                header: header(&mut c)?,
                format: c.string("format")?,
                data: c.bytes("data")?,
            })
        })(),
    )
}

/// Decodes a `sensor_msgs/CameraInfo` (ROS1 field names `D`, `K`).
pub fn camera_info(data: &[u8], topic: &str) -> Result<CameraInfo, RecordingError> {
    let mut c = Cursor::new(data, 0);
    wrap(
        topic,
        (|| {
            header(&mut c)?;
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
pub fn transform(data: &[u8], topic: &str) -> Result<Transform, RecordingError> {
    let mut c = Cursor::new(data, 0);
    wrap(
        topic,
        (|| {
            let mut t = [0.0; 3];
            for v in &mut t {
                *v = c.f64("translation")?;
            }
            let mut q = [0.0; 4];
            for v in &mut q {
                *v = c.f64("rotation")?;
            }
            Ok(Transform {
                translation: t,
                rotation: q,
            })
        })(),
    )
}

/// Decodes a `std_msgs/Float32`.
pub fn float32(data: &[u8], topic: &str) -> Result<f32, RecordingError> {
    wrap(topic, Cursor::new(data, 0).f32("value"))
}

/// Decodes librealsense's `realsense_msgs/StreamInfo`: the nominal frame rate and the encoding.
pub fn stream_info(data: &[u8], topic: &str) -> Result<(u32, String), RecordingError> {
    let mut c = Cursor::new(data, 0);
    wrap(topic, (|| Ok((c.u32("fps")?, c.string("encoding")?)))())
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
        let im = image(&b, "/d").expect("image");
        assert_eq!((im.width, im.height, im.step), (2, 1, 4));
        assert_eq!(im.encoding, "mono16");
        assert_eq!(im.header.stamp_ns, 1_000_000_500);
        assert_eq!(im.data, &[1, 0, 2, 0]);
    }

    #[test]
    fn truncated_image_names_its_topic() {
        let b = image_bytes(2, 1, "mono16", 4, &[1, 0, 2, 0]);
        let e = image(&b[..b.len() - 1], "/camera/depth").expect_err("truncated");
        assert!(e.to_string().contains("/camera/depth"), "{e}");
    }

    #[test]
    fn camera_info_refuses_a_huge_distortion_array() {
        let mut b = Vec::new();
        b.extend([0u8; 12]);
        b.extend(0u32.to_le_bytes());
        b.extend(48u32.to_le_bytes());
        b.extend(64u32.to_le_bytes());
        b.extend(0u32.to_le_bytes());
        b.extend(1_000_000u32.to_le_bytes());
        assert!(camera_info(&b, "/info").is_err());
    }
}
