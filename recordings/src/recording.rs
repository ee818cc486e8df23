//! A recording opened as the tracker sees it: the colour stream, the depth
//! stream aligned to it, their intrinsics and the depth units, frames paired
//! by time. Two layouts are recognised from the topic names: librealsense's
//! own (`/device_0/sensor_<n>/<Stream>_<i>/...`, depth in the depth imager's
//! frame, aligned here) and realsense-ros's (`/camera/color/image_raw` with
//! `/camera/aligned_depth_to_color/image_raw`, already aligned).

use crate::align::{align_depth_to_color, Distortion, Extrinsics, Intrinsics};
use crate::bytes::ByteSource;
use crate::error::RecordingError;
use crate::pairing::{fps_from_times, half_period_ns, pair_by_time, FramePair};
use crate::ros_msgs::{self, CameraInfo};
use crate::rosbag1::{Bag, MessageRef};

/// Largest image side, pixels (a D435i streams at most 1920x1080).
pub const MAX_IMAGE_SIDE: u32 = 8192;
/// Depth units of a recording that does not say, metres (the D435i's default).
pub const DEFAULT_DEPTH_UNITS: f64 = 0.001;
/// Frame rate assumed when neither the recording nor its timestamps give one.
pub const DEFAULT_FPS: f64 = 30.0;
const IMAGE_TYPE: &str = "sensor_msgs/Image";
const COMPRESSED_TYPE: &str = "sensor_msgs/CompressedImage";
const COLOR_ENCODINGS: &str = "colour streams: rgb8, bgr8, rgba8, bgra8, mono8";
const DEPTH_ENCODINGS: &str = "depth streams: mono16, 16UC1, 32FC1";

/// Which topics to read; `None` finds them from the names.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RecordingOptions {
    /// The colour image topic.
    pub color_topic: Option<String>,
    /// The depth image topic.
    pub depth_topic: Option<String>,
}

/// Who wrote the recording, as told by its topic names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// librealsense (RealSense Viewer, `rs-record`): depth in the depth imager's frame.
    Librealsense,
    /// realsense-ros or any other ROS recording of image topics.
    Ros,
}

/// One image stream of the recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Stream {
    /// Topic.
    pub topic: String,
    /// Its intrinsics.
    pub intrinsics: Intrinsics,
    /// Frame rate, from the recording or the message times.
    pub fps: f64,
    /// Messages on the topic.
    pub frames: usize,
}

/// One paired frame, decoded: RGB8 colour and depth aligned to it.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordedFrame {
    /// Columns (the colour stream's).
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// RGB8, row-major.
    pub color: Vec<u8>,
    /// Depth in units of [`Recording::depth_units`], aligned to colour, 0 = none.
    pub depth: Vec<u16>,
    /// Colour frame's bag time, nanoseconds from the first message.
    pub time_ns: u64,
}

/// An opened recording.
pub struct Recording<R: ByteSource> {
    bag: Bag<R>,
    /// Who wrote it.
    pub layout: Layout,
    /// The colour stream.
    pub color: Stream,
    /// The depth stream.
    pub depth: Stream,
    /// Depth to colour transform; `None` when depth is already aligned.
    pub depth_to_color: Option<Extrinsics>,
    /// Metres per depth unit.
    pub depth_units: f64,
    /// Paired frames, in time order.
    pub pairs: Vec<FramePair>,
    /// Colour frames without a depth frame within half a period.
    pub unpaired_color: usize,
    /// Depth frames without a colour frame.
    pub unpaired_depth: usize,
    /// Every image topic with its message type and count, for `info`.
    pub topics: Vec<(String, String, usize)>,
    color_msgs: Vec<MessageRef>,
    depth_msgs: Vec<MessageRef>,
    start_ns: u64,
}

fn messages_on(bag: &Bag<impl ByteSource>, topic: &str) -> Vec<MessageRef> {
    let ids: Vec<u32> = bag
        .connections
        .values()
        .filter(|c| c.topic == topic)
        .map(|c| c.id)
        .collect();
    bag.messages
        .iter()
        .filter(|m| ids.contains(&m.conn))
        .copied()
        .collect()
}

fn first_message<R: ByteSource>(
    bag: &mut Bag<R>,
    topic: &str,
) -> Result<Option<Vec<u8>>, RecordingError> {
    match messages_on(bag, topic).first() {
        Some(m) => Ok(Some(bag.read(m)?)),
        None => Ok(None),
    }
}

/// librealsense's stream prefix of an image topic: `/device_0/sensor_1/Color_0`.
fn librealsense_prefix(topic: &str) -> Option<&str> {
    let prefix = topic.strip_suffix("/image/data")?;
    let parts: Vec<&str> = prefix.split('/').collect();
    let ok = parts.len() == 4
        && parts[0].is_empty()
        && parts[1].starts_with("device_")
        && parts[2].starts_with("sensor_");
    ok.then_some(prefix)
}

/// The stream kind of a librealsense prefix: `Color`, `Depth`, `Infrared`.
fn stream_kind(prefix: &str) -> &str {
    let last = prefix.rsplit('/').next().unwrap_or("");
    last.rsplit_once('_').map_or(last, |(k, _)| k)
}

fn intrinsics_from(info: &CameraInfo, topic: &str) -> Result<Intrinsics, RecordingError> {
    let model = Distortion::from_name(&info.distortion_model).ok_or_else(|| {
        RecordingError::message(
            topic,
            format!(
                "distortion model `{}` is not supported (none, brown conrady, modified/inverse brown conrady, plumb_bob)",
                info.distortion_model
            ),
        )
    })?;
    let mut coeffs = [0.0f32; 5];
    for (c, d) in coeffs.iter_mut().zip(&info.d) {
        *c = *d as f32;
    }
    if info.width > MAX_IMAGE_SIDE || info.height > MAX_IMAGE_SIDE {
        return Err(RecordingError::TooLarge {
            what: "image side in pixels",
            size: u64::from(info.width.max(info.height)),
            max: u64::from(MAX_IMAGE_SIDE),
        });
    }
    let i = Intrinsics {
        width: info.width,
        height: info.height,
        fx: info.k[0] as f32,
        fy: info.k[4] as f32,
        ppx: info.k[2] as f32,
        ppy: info.k[5] as f32,
        model,
        coeffs,
    };
    i.check(topic)?;
    Ok(i)
}

impl<R: ByteSource> Recording<R> {
    /// Opens a ROS1 bag recording, finding its colour and depth streams.
    pub fn open(src: R, options: &RecordingOptions) -> Result<Self, RecordingError> {
        let mut bag = Bag::open(src)?;
        let mut topics: Vec<(String, String, usize)> = Vec::new();
        for c in bag.connections.values() {
            if c.msg_type == IMAGE_TYPE || c.msg_type == COMPRESSED_TYPE {
                if topics.iter().any(|(t, _, _)| *t == c.topic) {
                    continue;
                }
                let n = messages_on(&bag, &c.topic).len();
                topics.push((c.topic.clone(), c.msg_type.clone(), n));
            }
        }
        topics.sort();
        let list = || {
            if topics.is_empty() {
                match bag.warnings.first() {
                    Some(w) => format!(" (the recording has no image topics: {w})"),
                    None => " (the recording has no image topics)".to_string(),
                }
            } else {
                let names: Vec<String> = topics
                    .iter()
                    .map(|(t, ty, n)| format!("{t} [{ty}, {n}]"))
                    .collect();
                format!("; image topics: {}", names.join(", "))
            }
        };
        let is_rs = topics
            .iter()
            .any(|(t, _, _)| librealsense_prefix(t).is_some());
        let layout = if is_rs {
            Layout::Librealsense
        } else {
            Layout::Ros
        };
        let pick = |chosen: &Option<String>, want: &dyn Fn(&str) -> bool, what: &str| match chosen {
            Some(t) if topics.iter().any(|(n, _, _)| n == t) => Ok(t.clone()),
            Some(t) => Err(RecordingError::MissingStream {
                what: format!("topic {t} is not in the recording"),
                topics: list(),
            }),
            None => topics
                .iter()
                .map(|(t, _, _)| t)
                .find(|t| want(t))
                .cloned()
                .ok_or_else(|| RecordingError::MissingStream {
                    what: format!("no {what} stream found"),
                    topics: list(),
                }),
        };
        let (color_topic, depth_topic) = match layout {
            Layout::Librealsense => (
                pick(
                    &options.color_topic,
                    &|t| librealsense_prefix(t).is_some_and(|p| stream_kind(p) == "Color"),
                    "colour",
                )?,
                pick(
                    &options.depth_topic,
                    &|t| librealsense_prefix(t).is_some_and(|p| stream_kind(p) == "Depth"),
                    "depth",
                )?,
            ),
            Layout::Ros => {
                let color = pick(
                    &options.color_topic,
                    &|t| {
                        let l = t.to_ascii_lowercase();
                        l.contains("color") && !l.contains("depth") && l.ends_with("image_raw")
                    },
                    "colour (…/color/image_raw)",
                )?;
                let depth = pick(
                    &options.depth_topic,
                    &|t| {
                        t.to_ascii_lowercase().contains("aligned_depth_to_color")
                            && t.ends_with("image_raw")
                    },
                    "depth aligned to colour (…/aligned_depth_to_color/image_raw)",
                )?;
                (color, depth)
            }
        };
        for (topic, kind) in [(&color_topic, "colour"), (&depth_topic, "depth")] {
            let ty = topics
                .iter()
                .find(|(t, _, _)| t == topic)
                .map(|(_, ty, _)| ty.as_str());
            if ty != Some(IMAGE_TYPE) {
                return Err(RecordingError::UnsupportedEncoding {
                    topic: topic.clone(),
                    encoding: ty.unwrap_or("?").to_string(),
                    supported: if kind == "colour" {
                        "colour topics of sensor_msgs/Image"
                    } else {
                        "depth topics of sensor_msgs/Image"
                    },
                });
            }
        }

        let info_topic = |image_topic: &str| match layout {
            Layout::Librealsense => format!(
                "{}/info/camera_info",
                librealsense_prefix(image_topic).unwrap_or(image_topic)
            ),
            Layout::Ros => {
                let dir = image_topic.rsplit_once('/').map_or("", |(d, _)| d);
                format!("{dir}/camera_info")
            }
        };
        let stream = |bag: &mut Bag<R>, topic: &str| -> Result<Stream, RecordingError> {
            let it = info_topic(topic);
            let raw = first_message(bag, &it)?.ok_or_else(|| RecordingError::MissingStream {
                what: format!("no intrinsics for {topic}: topic {it} is missing"),
                topics: String::new(),
            })?;
            let intrinsics = intrinsics_from(&ros_msgs::camera_info(&raw, &it)?, &it)?;
            let msgs = messages_on(bag, topic);
            let times: Vec<u64> = msgs.iter().map(|m| m.time_ns).collect();
            let nominal = match layout {
                Layout::Librealsense => {
                    let si = format!("{}/info", librealsense_prefix(topic).unwrap_or(topic));
                    match first_message(bag, &si)? {
                        Some(raw) => Some(f64::from(ros_msgs::stream_info(&raw, &si)?.0)),
                        None => None,
                    }
                }
                Layout::Ros => None,
            };
            let fps = nominal
                .filter(|f| *f > 0.0)
                .or_else(|| fps_from_times(&times))
                .unwrap_or(DEFAULT_FPS);
            Ok(Stream {
                topic: topic.to_string(),
                intrinsics,
                fps,
                frames: msgs.len(),
            })
        };
        let color = stream(&mut bag, &color_topic)?;
        let depth = stream(&mut bag, &depth_topic)?;

        let (depth_to_color, depth_units) = match layout {
            Layout::Librealsense => {
                let d = Self::stream_to_reference(&mut bag, &depth_topic)?;
                let c = Self::stream_to_reference(&mut bag, &color_topic)?;
                let units = Self::read_depth_units(&mut bag, &depth_topic)?;
                // Each stream's tf is the reference-to-stream transform.
                (Some(d.inverse().then(&c)), units)
            }
            Layout::Ros => {
                if (depth.intrinsics.width, depth.intrinsics.height)
                    != (color.intrinsics.width, color.intrinsics.height)
                {
                    return Err(RecordingError::message(
                        &depth_topic,
                        "depth aligned to colour must have the colour stream's size",
                    ));
                }
                (None, DEFAULT_DEPTH_UNITS)
            }
        };
        let color_msgs = messages_on(&bag, &color_topic);
        let depth_msgs = messages_on(&bag, &depth_topic);
        let ct: Vec<u64> = color_msgs.iter().map(|m| m.time_ns).collect();
        let dt: Vec<u64> = depth_msgs.iter().map(|m| m.time_ns).collect();
        let pairing = pair_by_time(&ct, &dt, half_period_ns(color.fps.max(depth.fps)));
        let start_ns = bag.messages.first().map_or(0, |m| m.time_ns);
        Ok(Self {
            bag,
            layout,
            color,
            depth,
            depth_to_color,
            depth_units,
            pairs: pairing.pairs,
            unpaired_color: pairing.unpaired_color,
            unpaired_depth: pairing.unpaired_depth,
            topics,
            color_msgs,
            depth_msgs,
            start_ns,
        })
    }

    /// The transform from librealsense's reference stream to the stream of `topic`.
    fn stream_to_reference(bag: &mut Bag<R>, topic: &str) -> Result<Extrinsics, RecordingError> {
        let prefix = librealsense_prefix(topic).unwrap_or(topic);
        let tf_prefix = format!("{prefix}/tf/");
        let tf_topic = bag
            .connections
            .values()
            .find(|c| c.topic.starts_with(&tf_prefix))
            .map(|c| c.topic.clone())
            .ok_or_else(|| RecordingError::MissingStream {
                what: format!("no extrinsics for {topic} ({tf_prefix}<n> is missing)"),
                topics: String::new(),
            })?;
        let raw = first_message(bag, &tf_topic)?
            .ok_or_else(|| RecordingError::message(&tf_topic, "no transform message"))?;
        let t = ros_msgs::transform(&raw, &tf_topic)?;
        Ok(Extrinsics::from_quaternion(t.rotation, t.translation))
    }

    /// The depth sensor's `Depth_Units` option, or the default.
    fn read_depth_units(bag: &mut Bag<R>, depth_topic: &str) -> Result<f64, RecordingError> {
        let sensor = depth_topic
            .splitn(4, '/')
            .take(3)
            .collect::<Vec<_>>()
            .join("/");
        let topic = format!("{sensor}/option/Depth_Units/value");
        // The f32 option read as its shortest decimal: 0.001, not 0.0010000000474974513.
        let units = match first_message(bag, &topic)? {
            Some(raw) => {
                let v = ros_msgs::float32(&raw, &topic)?;
                v.to_string().parse().unwrap_or(f64::from(v))
            }
            None => DEFAULT_DEPTH_UNITS,
        };
        if !(units.is_finite() && units > 0.0 && units < 1.0) {
            return Err(RecordingError::message(
                &topic,
                format!("depth units {units} must be in (0, 1) metres"),
            ));
        }
        Ok(units)
    }

    /// Paired frames.
    pub fn len(&self) -> usize {
        self.pairs.len()
    }

    /// `true` when no colour frame has a depth frame.
    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// What the container reader could not read (a truncated tail, a broken chunk).
    pub fn warnings(&self) -> &[String] {
        &self.bag.warnings
    }

    /// Colour time of pair `index`, nanoseconds from the recording's first message.
    pub fn time_ns(&self, index: usize) -> Option<u64> {
        let p = self.pairs.get(index)?;
        Some(self.color_msgs[p.color].time_ns - self.start_ns)
    }

    /// Decodes pair `index`: colour as RGB8, depth aligned to colour.
    pub fn frame(&mut self, index: usize) -> Result<RecordedFrame, RecordingError> {
        let pair = *self.pairs.get(index).ok_or(RecordingError::NoFrame {
            index,
            len: self.pairs.len(),
        })?;
        let cm = self.color_msgs[pair.color];
        let dm = self.depth_msgs[pair.depth];
        let raw = self.bag.read(&cm)?;
        let color = decode_color(&raw, &self.color)?;
        let raw = self.bag.read(&dm)?;
        let depth = decode_depth(&raw, &self.depth, self.depth_units)?;
        let depth = match &self.depth_to_color {
            Some(ex) => align_depth_to_color(
                &depth,
                &self.depth.intrinsics,
                &self.color.intrinsics,
                ex,
                self.depth_units as f32,
            )?,
            None => depth,
        };
        Ok(RecordedFrame {
            width: self.color.intrinsics.width,
            height: self.color.intrinsics.height,
            color,
            depth,
            time_ns: cm.time_ns - self.start_ns,
        })
    }
}

/// The rows of an image message as `bpp`-byte pixels, checked against its stream.
fn rows<'a>(
    im: &ros_msgs::Image<'a>,
    stream: &Stream,
    bpp: usize,
) -> Result<impl Iterator<Item = &'a [u8]>, RecordingError> {
    let (w, h) = (stream.intrinsics.width, stream.intrinsics.height);
    if (im.width, im.height) != (w, h) {
        return Err(RecordingError::message(
            &stream.topic,
            format!(
                "image is {}x{} but its camera_info says {w}x{h}",
                im.width, im.height
            ),
        ));
    }
    let row = w as usize * bpp;
    let step = im.step as usize;
    let needed = step.saturating_mul(h as usize);
    if step < row || im.data.len() < needed {
        return Err(RecordingError::message(
            &stream.topic,
            format!(
                "{} bytes of pixels for {w}x{h} at step {step} ({bpp} bytes a pixel)",
                im.data.len()
            ),
        ));
    }
    let data = im.data;
    Ok((0..h as usize).map(move |y| &data[y * step..y * step + row]))
}

fn decode_color(raw: &[u8], stream: &Stream) -> Result<Vec<u8>, RecordingError> {
    let im = ros_msgs::image(raw, &stream.topic)?;
    // Source channel of R, G, B and the bytes a pixel.
    let (order, bpp): ([usize; 3], usize) = match im.encoding.as_str() {
        "rgb8" => ([0, 1, 2], 3),
        "bgr8" => ([2, 1, 0], 3),
        "rgba8" => ([0, 1, 2], 4),
        "bgra8" => ([2, 1, 0], 4),
        "mono8" => ([0, 0, 0], 1),
        other => {
            return Err(RecordingError::UnsupportedEncoding {
                topic: stream.topic.clone(),
                encoding: other.to_string(),
                supported: COLOR_ENCODINGS,
            })
        }
    };
    let mut out = Vec::with_capacity(
        stream.intrinsics.width as usize * stream.intrinsics.height as usize * 3,
    );
    for row in rows(&im, stream, bpp)? {
        for px in row.chunks_exact(bpp) {
            out.extend(order.iter().map(|&c| px[c]));
        }
    }
    Ok(out)
}

fn decode_depth(raw: &[u8], stream: &Stream, units: f64) -> Result<Vec<u16>, RecordingError> {
    let im = ros_msgs::image(raw, &stream.topic)?;
    let mut out =
        Vec::with_capacity(stream.intrinsics.width as usize * stream.intrinsics.height as usize);
    match im.encoding.as_str() {
        "mono16" | "16UC1" => {
            for row in rows(&im, stream, 2)? {
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
            for row in rows(&im, stream, 4)? {
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
                topic: stream.topic.clone(),
                encoding: other.to_string(),
                supported: DEPTH_ENCODINGS,
            })
        }
    }
    Ok(out)
}
