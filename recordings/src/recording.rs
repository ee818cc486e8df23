//! A recording opened as the tracker sees it: the colour stream, the depth
//! stream aligned to it, their intrinsics and the depth units, frames paired
//! by time. Two layouts are recognised from the topic names: librealsense's
//! own (`/device_0/sensor_<n>/<Stream>_<i>/...`: 2.55's ROS1 bags with raw
//! images and typed metadata, 2.59's `.db3` with compressed images and
//! metadata as `key=value` strings; depth in the depth imager's frame,
//! aligned here) and realsense-ros's (`.../color/image_raw` with
//! `.../aligned_depth_to_color/image_raw`, raw or compressed, already aligned).

use crate::align::{AlignArithmetic, Aligner, Distortion, Extrinsics, Intrinsics};
use crate::bytes::ByteSource;
use crate::error::RecordingError;
use crate::pairing::{fps_from_times, half_period_ns, pair_by_time, FramePair};
use crate::pixels::{self, Expect, Payload};
use crate::ros_msgs::{self, CameraInfo, Wire};
use crate::store::{Msg, Store};

// The project's one definition of each: the largest image side, the depth
// units of a recording that does not say (metres) and the frame rate
// assumed when neither the recording nor its timestamps give one.
pub use upetrack::perception::camera::{
    DEFAULT_DEPTH_SCALE as DEFAULT_DEPTH_UNITS, DEFAULT_FPS, MAX_IMAGE_SIDE,
};
const IMAGE_TYPE: &str = "sensor_msgs/Image";
const COMPRESSED_TYPE: &str = "sensor_msgs/CompressedImage";
const STRING_TYPE: &str = "std_msgs/String";

/// Which topics to read; `None` finds them from the names.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RecordingOptions {
    /// The colour image topic.
    pub color_topic: Option<String>,
    /// The depth image topic.
    pub depth_topic: Option<String>,
    /// The alignment arithmetic; `None` takes the one of the recording's
    /// librealsense era (x86 SSE for ROS1 bags, portable for `.db3`).
    pub align: Option<AlignArithmetic>,
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
    /// Raw or compressed images.
    pub payload: Payload,
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
    /// Colour frame's recording time, nanoseconds from the first message.
    pub time_ns: u64,
}

/// An opened recording.
pub struct Recording<R: ByteSource> {
    store: Store<R>,
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
    /// Which librealsense aligner's arithmetic aligns the depth.
    pub align: AlignArithmetic,
    /// Paired frames, in time order.
    pub pairs: Vec<FramePair>,
    /// Colour frames without a depth frame within half a period.
    pub unpaired_color: usize,
    /// Depth frames without a colour frame.
    pub unpaired_depth: usize,
    /// Every image topic with its message type and count, for `info`.
    pub topics: Vec<(String, String, usize)>,
    color_msgs: Vec<Msg>,
    depth_msgs: Vec<Msg>,
    start_ns: u64,
    aligner: Option<Aligner>,
}

fn expect(s: &Stream) -> Expect<'_> {
    Expect {
        topic: &s.topic,
        width: s.intrinsics.width,
        height: s.intrinsics.height,
    }
}

/// librealsense's stream prefix of an image topic: `/device_0/sensor_1/Color_0`.
fn librealsense_prefix(topic: &str) -> Option<&str> {
    let (prefix, rest) = topic.split_once("/image/data")?;
    if !matches!(rest, "" | "/compressed" | "/compressedDepth") {
        return None;
    }
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

/// `key=value;key=value` of librealsense 2.59's metadata strings.
fn key_values(text: &str) -> Vec<(&str, &str)> {
    text.split(';')
        .filter_map(|kv| kv.split_once('='))
        .map(|(k, v)| (k.trim(), v.trim()))
        .collect()
}

fn numbers(text: &str) -> Vec<f64> {
    text.split(',')
        .filter_map(|v| v.trim().parse().ok())
        .collect()
}

fn distortion(name: &str, topic: &str) -> Result<Distortion, RecordingError> {
    Distortion::from_name(name).ok_or_else(|| {
        RecordingError::message(
            topic,
            format!("distortion model `{name}` is not supported (none, brown conrady, modified/inverse brown conrady, plumb_bob)"),
        )
    })
}

fn checked(i: Intrinsics, topic: &str) -> Result<Intrinsics, RecordingError> {
    if i.width > MAX_IMAGE_SIDE || i.height > MAX_IMAGE_SIDE {
        return Err(RecordingError::TooLarge {
            what: "image side in pixels",
            size: u64::from(i.width.max(i.height)),
            max: u64::from(MAX_IMAGE_SIDE),
        });
    }
    i.check(topic)?;
    Ok(i)
}

fn intrinsics_from(info: &CameraInfo, topic: &str) -> Result<Intrinsics, RecordingError> {
    let mut coeffs = [0.0f32; 5];
    for (c, d) in coeffs.iter_mut().zip(&info.d) {
        *c = *d as f32;
    }
    checked(
        Intrinsics {
            width: info.width,
            height: info.height,
            fx: info.k[0] as f32,
            fy: info.k[4] as f32,
            ppx: info.k[2] as f32,
            ppy: info.k[5] as f32,
            model: distortion(&info.distortion_model, topic)?,
            coeffs,
        },
        topic,
    )
}

/// librealsense 2.59's `width=..;height=..;fx=..;ppx=..;fy=..;ppy=..;model=..;coeffs=..`.
fn intrinsics_from_text(text: &str, topic: &str) -> Result<Intrinsics, RecordingError> {
    let kv = key_values(text);
    let get = |k: &str| kv.iter().find(|(n, _)| *n == k).map(|(_, v)| *v);
    let bad = |k: &str| {
        RecordingError::message(topic, format!("intrinsics without a usable `{k}`: {text}"))
    };
    let num = |k: &str| {
        get(k)
            .and_then(|v| v.parse::<f64>().ok())
            .ok_or_else(|| bad(k))
    };
    let mut coeffs = [0.0f32; 5];
    for (c, v) in coeffs.iter_mut().zip(numbers(get("coeffs").unwrap_or(""))) {
        *c = v as f32;
    }
    let side = |k: &str| {
        num(k)
            .ok()
            .filter(|v| v.fract() == 0.0 && *v >= 0.0 && *v <= f64::from(MAX_IMAGE_SIDE))
            .ok_or_else(|| bad(k))
    };
    checked(
        Intrinsics {
            width: side("width")? as u32,
            height: side("height")? as u32,
            fx: num("fx")? as f32,
            fy: num("fy")? as f32,
            ppx: num("ppx")? as f32,
            ppy: num("ppy")? as f32,
            model: distortion(get("model").unwrap_or("none"), topic)?,
            coeffs,
        },
        topic,
    )
}

/// The f32 `v` as its shortest decimal: 0.001, not 0.0010000000474974513.
fn shortest(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(f64::from(v))
}

impl<R: ByteSource> Recording<R> {
    /// Opens a recording (ROS1 bag or rosbag2 `.db3`), finding its colour and depth streams.
    pub fn open(src: R, options: &RecordingOptions) -> Result<Self, RecordingError> {
        let mut store = Store::open(src)?;
        let mut topics: Vec<(String, String, usize)> = store
            .topics
            .iter()
            .filter(|t| t.msg_type == IMAGE_TYPE || t.msg_type == COMPRESSED_TYPE)
            .map(|t| (t.name.clone(), t.msg_type.clone(), store.on(&t.name).len()))
            .collect();
        topics.sort();
        let list = || {
            if topics.is_empty() {
                match store.warnings().first() {
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
        // The first topic `want` accepts, raw images before compressed ones.
        let pick = |chosen: &Option<String>, want: &dyn Fn(&str) -> bool, what: &str| match chosen {
            Some(t) if topics.iter().any(|(n, _, _)| n == t) => Ok(t.clone()),
            Some(t) => Err(RecordingError::MissingStream {
                what: format!("topic {t} is not in the recording"),
                topics: list(),
            }),
            None => {
                let mut found: Vec<&(String, String, usize)> =
                    topics.iter().filter(|(t, _, _)| want(t)).collect();
                found.sort_by_key(|(_, ty, _)| ty != IMAGE_TYPE);
                found.first().map(|(t, _, _)| t.clone()).ok_or_else(|| {
                    RecordingError::MissingStream {
                        what: format!("no {what} stream found"),
                        topics: list(),
                    }
                })
            }
        };
        let rs_kind = |kind: &'static str| {
            move |t: &str| librealsense_prefix(t).is_some_and(|p| stream_kind(p) == kind)
        };
        let (color_topic, depth_topic) = match layout {
            Layout::Librealsense => (
                pick(&options.color_topic, &rs_kind("Color"), "colour")?,
                pick(&options.depth_topic, &rs_kind("Depth"), "depth")?,
            ),
            Layout::Ros => (
                pick(
                    &options.color_topic,
                    &|t| {
                        let l = t.to_ascii_lowercase();
                        l.contains("color")
                            && !l.contains("depth")
                            && (l.ends_with("image_raw") || l.ends_with("image_raw/compressed"))
                    },
                    "colour (…/color/image_raw)",
                )?,
                pick(
                    &options.depth_topic,
                    &|t| {
                        let l = t.to_ascii_lowercase();
                        l.contains("aligned_depth_to_color")
                            && (l.ends_with("image_raw")
                                || l.ends_with("image_raw/compresseddepth"))
                    },
                    "depth aligned to colour (…/aligned_depth_to_color/image_raw)",
                )?,
            ),
        };
        let color = Self::stream(&mut store, layout, &color_topic)?;
        let depth = Self::stream(&mut store, layout, &depth_topic)?;
        let (depth_to_color, depth_units) = match layout {
            Layout::Librealsense => {
                let d = Self::reference_to_stream(&mut store, &depth_topic)?;
                let c = Self::reference_to_stream(&mut store, &color_topic)?;
                let units = Self::read_depth_units(&mut store, &depth_topic)?;
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
        let color_msgs = store.on(&color_topic);
        let depth_msgs = store.on(&depth_topic);
        let ct: Vec<u64> = color_msgs.iter().map(|m| m.time_ns).collect();
        let dt: Vec<u64> = depth_msgs.iter().map(|m| m.time_ns).collect();
        let pairing = pair_by_time(&ct, &dt, half_period_ns(color.fps.max(depth.fps)));
        let start_ns = store.messages.first().map_or(0, |m| m.time_ns);
        // A recording aligns as the librealsense of its format does.
        let align = options.align.unwrap_or(match store.wire {
            Wire::Ros1 => AlignArithmetic::X86Sse,
            Wire::Cdr => AlignArithmetic::Portable,
        });
        // Set up at once, so an implausible calibration or a depth stream too
        // large to align is refused when the file is opened.
        let aligner = match depth_to_color {
            Some(ex) => Some(Aligner::new(depth.intrinsics, color.intrinsics, ex, align)?),
            None => None,
        };
        Ok(Self {
            store,
            layout,
            color,
            depth,
            depth_to_color,
            depth_units,
            align,
            pairs: pairing.pairs,
            unpaired_color: pairing.unpaired_color,
            unpaired_depth: pairing.unpaired_depth,
            topics,
            color_msgs,
            depth_msgs,
            start_ns,
            aligner,
        })
    }

    /// The stream of image topic `topic`: payload, intrinsics, rate.
    fn stream(store: &mut Store<R>, layout: Layout, topic: &str) -> Result<Stream, RecordingError> {
        let payload = match store.topic(topic).map(|t| t.msg_type.as_str()) {
            Some(IMAGE_TYPE) => Payload::Raw,
            Some(COMPRESSED_TYPE) => Payload::Compressed,
            other => {
                return Err(RecordingError::UnsupportedEncoding {
                    topic: topic.to_string(),
                    encoding: other.unwrap_or("?").to_string(),
                    supported: "image topics of sensor_msgs/Image or sensor_msgs/CompressedImage",
                })
            }
        };
        let wire = store.wire;
        let missing = |it: &str| RecordingError::MissingStream {
            what: format!("no intrinsics for {topic}: topic {it} is missing"),
            topics: String::new(),
        };
        let (intrinsics, nominal) = match layout {
            Layout::Librealsense => {
                let prefix = librealsense_prefix(topic).unwrap_or(topic);
                let typed = format!("{prefix}/info/camera_info");
                let text = format!("{prefix}/camera_info");
                let intrinsics = if let Some(raw) = store.first(&typed)? {
                    intrinsics_from(&ros_msgs::camera_info(&raw, wire, &typed)?, &typed)?
                } else if let Some(raw) = store.first(&text)? {
                    intrinsics_from_text(&ros_msgs::string(&raw, wire, &text)?, &text)?
                } else {
                    return Err(missing(&typed));
                };
                let si = format!("{prefix}/info");
                let is_text = store.topic(&si).is_some_and(|t| t.msg_type == STRING_TYPE);
                let fps = match store.first(&si)? {
                    Some(raw) if is_text => {
                        let s = ros_msgs::string(&raw, wire, &si)?;
                        key_values(&s)
                            .iter()
                            .find(|(k, _)| *k == "fps")
                            .and_then(|(_, v)| v.parse().ok())
                    }
                    Some(raw) => Some(f64::from(ros_msgs::stream_info(&raw, &si)?.0)),
                    None => None,
                };
                (intrinsics, fps)
            }
            Layout::Ros => {
                let image = topic
                    .trim_end_matches("/compressedDepth")
                    .trim_end_matches("/compressed");
                let dir = image.rsplit_once('/').map_or("", |(d, _)| d);
                let it = format!("{dir}/camera_info");
                let raw = store.first(&it)?.ok_or_else(|| missing(&it))?;
                (
                    intrinsics_from(&ros_msgs::camera_info(&raw, wire, &it)?, &it)?,
                    None,
                )
            }
        };
        let msgs = store.on(topic);
        let times: Vec<u64> = msgs.iter().map(|m| m.time_ns).collect();
        let fps = nominal
            .filter(|f: &f64| f.is_finite() && *f > 0.0)
            .or_else(|| fps_from_times(&times))
            .unwrap_or(DEFAULT_FPS);
        Ok(Stream {
            topic: topic.to_string(),
            intrinsics,
            fps,
            frames: msgs.len(),
            payload,
        })
    }

    /// The transform from librealsense's reference stream to the stream of
    /// `topic`: a `geometry_msgs/Transform` at `tf/<n>` (2.55) or a
    /// `rotation=..;translation=..` string at `tf/ref_<n>` (2.59).
    fn reference_to_stream(
        store: &mut Store<R>,
        topic: &str,
    ) -> Result<Extrinsics, RecordingError> {
        let prefix = librealsense_prefix(topic).unwrap_or(topic);
        let tf_prefix = format!("{prefix}/tf/");
        let (tf_topic, ty) = store
            .topics
            .iter()
            .find(|t| t.name.starts_with(&tf_prefix))
            .map(|t| (t.name.clone(), t.msg_type.clone()))
            .ok_or_else(|| RecordingError::MissingStream {
                what: format!("no extrinsics for {topic} ({tf_prefix}<n> is missing)"),
                topics: String::new(),
            })?;
        let wire = store.wire;
        // librealsense 2.59 also writes each stream's pose in /tf_static, at
        // full precision (the `tf/ref_<n>` strings keep six decimals): the
        // transform from the stream (child) to its reference (parent).
        if ty == STRING_TYPE {
            let reference = tf_topic.rsplit('/').next().unwrap_or("");
            let kind = stream_kind(prefix);
            let mut found = None;
            for m in store.on("/tf_static") {
                let raw = store.read(&m)?;
                for t in ros_msgs::tf_message(&raw, wire, "/tf_static")? {
                    if t.child_frame_id == kind && t.frame_id == reference {
                        found = Some(t.transform);
                    }
                }
            }
            if let Some(t) = found {
                return Ok(Extrinsics::from_quaternion(t.rotation, t.translation).inverse());
            }
        }
        let raw = store
            .first(&tf_topic)?
            .ok_or_else(|| RecordingError::message(&tf_topic, "no transform message"))?;
        if ty == STRING_TYPE {
            let text = ros_msgs::string(&raw, wire, &tf_topic)?;
            let kv = key_values(&text);
            let get = |k: &str| numbers(kv.iter().find(|(n, _)| *n == k).map_or("", |(_, v)| v));
            let (r, t) = (get("rotation"), get("translation"));
            if r.len() != 9 || t.len() != 3 {
                return Err(RecordingError::message(
                    &tf_topic,
                    format!("not a rotation and a translation: {text}"),
                ));
            }
            let mut e = Extrinsics::IDENTITY;
            for (o, v) in e.rotation.iter_mut().zip(&r) {
                *o = *v as f32;
            }
            for (o, v) in e.translation.iter_mut().zip(&t) {
                *o = *v as f32;
            }
            return Ok(e);
        }
        let t = ros_msgs::transform(&raw, wire, &tf_topic)?;
        Ok(Extrinsics::from_quaternion(t.rotation, t.translation))
    }

    /// The depth sensor's `Depth_Units` option, or the default.
    fn read_depth_units(store: &mut Store<R>, depth_topic: &str) -> Result<f64, RecordingError> {
        let sensor = depth_topic
            .splitn(4, '/')
            .take(3)
            .collect::<Vec<_>>()
            .join("/");
        let topic = format!("{sensor}/option/Depth_Units/value");
        let wire = store.wire;
        let is_text = store
            .topic(&topic)
            .is_some_and(|t| t.msg_type == STRING_TYPE);
        let units = match store.first(&topic)? {
            Some(raw) if is_text => {
                let s = ros_msgs::string(&raw, wire, &topic)?;
                s.trim().parse().map_err(|_| {
                    RecordingError::message(&topic, format!("depth units `{s}` are not a number"))
                })?
            }
            Some(raw) => shortest(ros_msgs::float32(&raw, wire, &topic)?),
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
        self.store.warnings()
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
        let wire = self.store.wire;
        let raw = self.store.read(&cm)?;
        let color = pixels::color(&raw, wire, self.color.payload, &expect(&self.color))?;
        let raw = self.store.read(&dm)?;
        let depth = pixels::depth(
            &raw,
            wire,
            self.depth.payload,
            &expect(&self.depth),
            self.depth_units,
        )?;
        let depth = match self.depth_to_color {
            Some(ex) => {
                let (d, c, arithmetic) = (self.depth.intrinsics, self.color.intrinsics, self.align);
                // Set up once; set up again if a caller changed the cameras or the arithmetic.
                let stale = self
                    .aligner
                    .as_ref()
                    .is_none_or(|a| !a.is_for(&d, &c, &ex, arithmetic));
                if stale {
                    self.aligner = Some(Aligner::new(d, c, ex, arithmetic)?);
                }
                match &self.aligner {
                    Some(a) => a.align(&depth, self.depth_units as f32)?,
                    None => depth,
                }
            }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn librealsense_prefixes_of_raw_and_compressed_topics() {
        assert_eq!(
            librealsense_prefix("/device_0/sensor_1/Color_0/image/data"),
            Some("/device_0/sensor_1/Color_0")
        );
        assert_eq!(
            librealsense_prefix("/device_0/sensor_0/Depth_0/image/data/compressedDepth"),
            Some("/device_0/sensor_0/Depth_0")
        );
        assert_eq!(
            librealsense_prefix("/device_0/sensor_0/Depth_0/image/metadata"),
            None
        );
        assert_eq!(librealsense_prefix("/camera/color/image_raw"), None);
        assert_eq!(stream_kind("/device_0/sensor_1/Color_0"), "Color");
    }

    #[test]
    fn intrinsics_from_librealsense_259_text() {
        let i = intrinsics_from_text(
            "width=64;height=48;fx=40;ppx=31.5;fy=41;ppy=24.2000008;model=Inverse Brown Conrady;coeffs=0.1,0,0,0,0",
            "/t",
        )
        .expect("parses");
        assert_eq!(
            (i.width, i.height, i.fx, i.fy, i.ppx),
            (64, 48, 40.0, 41.0, 31.5)
        );
        assert_eq!(i.model, Distortion::InverseBrownConrady);
        assert_eq!(i.coeffs[0], 0.1);
        assert!(intrinsics_from_text("width=64;height=-3;fx=40;ppx=1;fy=1;ppy=1", "/t").is_err());
        assert!(intrinsics_from_text("width=64;height=48;fx=0;ppx=1;fy=1;ppy=1", "/t").is_err());
    }
}
