//! What a camera recording holds (streams, intrinsics, pairing, warnings),
//! as `upetrack info` prints it and the page shows it.

use serde::Serialize;

/// What a recording holds, as `upetrack info` shows it.
#[derive(Debug, Clone, Default, Serialize)]
pub struct RecordingInfo {
    /// The file.
    pub path: String,
    /// `librealsense` or `ros`.
    pub layout: String,
    /// The colour stream.
    pub color: StreamInfo,
    /// The depth stream.
    pub depth: StreamInfo,
    /// Depth is in the depth imager's frame and is aligned to colour on reading.
    pub aligned_on_reading: bool,
    /// Metres per depth unit.
    pub depth_units: f64,
    /// Colour frames with a depth frame within half a period.
    pub paired_frames: usize,
    /// Colour frames left without depth.
    pub unpaired_color: usize,
    /// Depth frames left without colour.
    pub unpaired_depth: usize,
    /// Every image topic: name, message type, messages.
    pub image_topics: Vec<(String, String, usize)>,
    /// What the reader could not read.
    pub warnings: Vec<String>,
}

/// One stream of [`RecordingInfo`].
#[derive(Debug, Clone, Default, Serialize)]
pub struct StreamInfo {
    /// Topic.
    pub topic: String,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Frame rate.
    pub fps: f64,
    /// Messages.
    pub frames: usize,
    /// `fx, fy, ppx, ppy`.
    pub intrinsics: [f32; 4],
    /// Distortion model.
    pub distortion: String,
}
