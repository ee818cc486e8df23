//! Camera recordings read as sequences of colour frames with depth aligned
//! to colour: ROS1 bag 2.0 files (the RealSense Viewer and `rs-record` of
//! librealsense 2.55 and earlier, realsense-ros) and rosbag2 SQLite files
//! (`.db3`: librealsense 2.59, ROS 2's realsense-ros).
//!
//! The pipeline of this crate, in order: [`bytes`] (random access to a file,
//! never read whole), the containers [`rosbag1`] (index, chunks, lz4 and
//! bz2) and [`rosbag2`] (over [`sqlite`], a read-only page reader), seen as
//! one by [`store`]; [`ros_msgs`] (ROS1 and CDR messages), [`pixels`] (raw
//! and compressed images, decoded by [`images`], the project's one PNG and
//! JPEG path), [`recording`] (which topics are the colour and
//! depth streams, their intrinsics and extrinsics), [`pairing`] (colour and
//! depth by time) and [`align`] (depth into the colour camera, as
//! librealsense's `rs2::align`). The tracker's core knows none of this.

pub mod align;
pub mod bytes;
pub mod chunks;
pub mod error;
pub mod images;
pub mod mcap;
pub mod pairing;
pub mod pixels;
pub mod recording;
pub mod ros_msgs;
pub mod rosbag1;
pub mod rosbag2;
pub mod sqlite;
pub mod store;

pub use bytes::{ByteSource, FileBytes};
pub use error::RecordingError;
pub use recording::{RecordedFrame, Recording, RecordingOptions};

/// `true` when `head` (the first bytes of a file) is a recording this crate reads.
pub fn is_recording(head: &[u8]) -> bool {
    store::is_container(head)
}
