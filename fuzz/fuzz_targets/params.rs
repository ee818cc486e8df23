//! Arbitrary parameter files: parsing and validation must reject what is
//! invalid; a tracker built from accepted parameters must run a frame.
#![no_main]

use libfuzzer_sys::fuzz_target;
use upetrack::{CameraIntrinsics, Frame, HsvRange, Params, Tracker};

fuzz_target!(|data: &[u8]| {
    let Ok(params) = serde_json::from_slice::<Params>(data) else {
        return;
    };
    if params.validate().is_err() {
        return;
    }
    let cam = CameraIntrinsics {
        width: 8,
        height: 8,
        fx: 10.0,
        fy: 10.0,
        cx: 4.0,
        cy: 4.0,
    };
    let Ok(mut tracker) = Tracker::new(params, cam, HsvRange::default()) else {
        return;
    };
    let color = [30u8, 60, 150].repeat(64);
    let depth = [600u16; 64];
    let frame = Frame::new(8, 8, &color, &depth, 0.001).expect("valid frame");
    let out = tracker.process(&frame, &[]).expect("sizes match");
    assert!(out.nodes.iter().all(|p| p.iter().all(|c| c.is_finite())));
});
