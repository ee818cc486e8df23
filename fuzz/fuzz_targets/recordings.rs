//! Arbitrary bytes as a recording (ROS1 bag, rosbag2 SQLite, MCAP): opening
//! it (indexes or scans, lz4 / bz2 / zstd chunks, SQLite pages and overflow
//! chains, topic discovery, intrinsics, extrinsics) and decoding its frames
//! (ROS1 and CDR messages, raw and compressed images, alignment) must return
//! errors, never panic or allocate past the documented caps.
#![no_main]

use libfuzzer_sys::fuzz_target;
use upetrack_recordings::{Recording, RecordingOptions};

fuzz_target!(|data: &[u8]| {
    if let Ok(mut store) = upetrack_recordings::store::Store::open(data) {
        let refs: Vec<_> = store.messages.iter().take(16).copied().collect();
        for m in refs {
            let _ = store.read(&m);
        }
    }
    if let Ok(mut rec) = Recording::open(data, &RecordingOptions::default()) {
        for i in 0..rec.len().min(3) {
            let _ = rec.frame(i);
        }
    }
});
