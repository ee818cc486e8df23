//! Arbitrary bytes as a .zip: unpacking and opening a sequence from it must
//! return errors (caps, unsafe names, corrupt data), never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(source) = upetrack_io::archive::unpack_zip(data, "fuzz.zip") {
        if let Ok(seq) = upetrack_io::Sequence::open(source) {
            let _ = seq.frame(0);
        }
    }
});
