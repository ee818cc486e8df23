//! A sequence made of arbitrary files: intrinsics, dlo.json, ground truth,
//! one colour and one depth frame, split from the input at `\xff\x00\xff`.
//! Opening, decoding and tracking must return errors, never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use upetrack_io::{MemorySource, Sequence};

const NAMES: [&str; 5] = [
    "camera_intrinsic.json",
    "dlo.json",
    "groundtruth.json",
    "color/000000.png",
    "depth/000000.png",
];

fuzz_target!(|data: &[u8]| {
    let mut source = MemorySource::new("fuzz");
    let mut parts = Vec::new();
    let mut start = 0;
    let mut i = 0;
    while i + 3 <= data.len() {
        if &data[i..i + 3] == b"\xff\x00\xff" {
            parts.push(&data[start..i]);
            start = i + 3;
            i += 3;
        } else {
            i += 1;
        }
    }
    parts.push(&data[start..]);
    for (name, part) in NAMES.iter().zip(parts) {
        source.insert(name, part.to_vec());
    }
    let Ok(seq) = Sequence::open(source) else {
        return;
    };
    let _ = seq.frame(0);
    let _ = upetrack_io::run::track_sequence(&seq, upetrack::Params::default(), &mut || 0.0);
});
