//! Camera recordings read as sequences of colour frames with depth aligned
//! to colour: ROS1 bag 2.0 files as the RealSense Viewer, `rs-record`
//! (librealsense 2.55 and earlier) and realsense-ros recordings write them.
//!
//! The pipeline of this crate, in order: [`bytes`] (random access to a file,
//! never read whole), [`rosbag1`] (the container: index, chunks, lz4 and bz2),
//! [`ros_msgs`] (the messages), [`recording`] (which topics are the colour and
//! depth streams, their intrinsics and extrinsics), [`pairing`] (colour and
//! depth by time) and [`align`] (depth into the colour camera, as
//! librealsense's `rs2::align`). The tracker's core knows none of this.

pub mod align;
pub mod bytes;
pub mod error;
pub mod pairing;
pub mod recording;
pub mod ros_msgs;
pub mod rosbag1;

pub use bytes::{ByteSource, FileBytes};
pub use error::RecordingError;
pub use recording::{RecordedFrame, Recording, RecordingOptions};

/// `true` when `head` (the first bytes of a file) is a recording this crate reads.
pub fn is_recording(head: &[u8]) -> bool {
    rosbag1::is_bag(head)
}
