//! The baselines' tracking steps (CPD, TrackDLO, CDCPD2) on arbitrary node sets and
//! clouds: no panic, and the nodes that come out are finite.
#![no_main]

use libfuzzer_sys::fuzz_target;
use upetrack::math::Vec3;
use upetrack::step::{Algorithm, StepInput};
use upetrack::tracker::Stepper;
use upetrack::{CameraIntrinsics, Params};

fuzz_target!(|data: &[u8]| {
    if data.len() < 3 {
        return;
    }
    let algorithm = [Algorithm::Cpd, Algorithm::Trackdlo, Algorithm::Cdcpd2][data[0] as usize % 3];
    let m = 4 + (data[1] as usize % 30);
    let values: Vec<f64> = data[2..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
        .collect();
    let points: Vec<Vec3> = values
        .chunks_exact(3)
        .take(m + 300)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    if points.len() < m || !points.iter().all(|p| p.iter().all(|c| c.is_finite())) {
        return;
    }
    let (prev, cloud) = points.split_at(m);
    let params = Params {
        algorithm,
        node_count: m,
        ..Params::default()
    };
    let camera = CameraIntrinsics::D435I_640X480;
    let visible = vec![true; m];
    let mut stepper = Stepper::new(algorithm);
    stepper.start(prev);
    let out = stepper.step(
        &StepInput {
            previous: prev,
            cloud,
            visible: &visible,
            partly_seen: &[],
            camera: &camera,
            evidence: None,
            rest_length: None,
            frame_interval: 1.0 / upetrack::perception::camera::DEFAULT_FPS,
            not_rope: &[],
        },
        &params,
    );
    assert_eq!(out.nodes.len(), m);
    assert!(out.nodes.iter().all(|q| q.iter().all(|c| c.is_finite())));
});
