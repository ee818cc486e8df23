//! Arbitrary bytes as a ROS1 bag: opening it as a recording (index or scan,
//! lz4 and bz2 chunks, topic discovery, intrinsics) and decoding its frames
//! (pixel conversion, alignment) must return errors, never panic or allocate
//! past the documented caps.
#![no_main]

use libfuzzer_sys::fuzz_target;
use upetrack_recordings::{Recording, RecordingOptions};

fuzz_target!(|data: &[u8]| {
    if let Ok(mut bag) = upetrack_recordings::rosbag1::Bag::open(data) {
        let refs: Vec<_> = bag.messages.iter().take(16).copied().collect();
        for m in refs {
            let _ = bag.read(&m);
        }
    }
    if let Ok(mut rec) = Recording::open(data, &RecordingOptions::default()) {
        for i in 0..rec.len().min(3) {
            let _ = rec.frame(i);
        }
    }
});
