//! The tracking step on arbitrary point clouds and node sets: visibility,
//! registration, UPE and resampling must not panic, and finite inputs must
//! give finite nodes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use upetrack::math::Vec3;
use upetrack::Params;

fuzz_target!(|data: &[u8]| {
    if data.len() < 2 {
        return;
    }
    let m = 4 + (data[0] as usize % 40);
    let values: Vec<f64> = data[1..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
        .collect();
    let points: Vec<Vec3> = values
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    if points.len() < m {
        return;
    }
    let (prev, cloud) = points.split_at(m);
    let finite = points.iter().all(|p| p.iter().all(|c| c.is_finite()));
    let p = Params::default();
    let visible = upetrack::visibility::visible_nodes(prev, cloud, p.visibility_radius, 3);
    let mut nodes = prev.to_vec();
    upetrack::upe::registration::register(cloud, &mut nodes, &visible, &p.upetrack.em());
    upetrack::upe::occlusion::estimate_hidden(
        &mut nodes,
        &visible,
        prev,
        &p.upetrack
            .upe(1.0 / upetrack::perception::camera::DEFAULT_FPS),
    );
    let out = upetrack::polyline::resample_uniform(&nodes, m);
    assert_eq!(out.len(), m);
    // Finite in, finite out, for coordinates a camera can give (within a
    // kilometre; beyond, squared distances may overflow on the way). Judged
    // on the inputs alone, so a NaN coming out cannot excuse itself.
    let plausible = points.iter().all(|p| p.iter().all(|c| c.abs() < 1e3));
    if finite && plausible {
        assert!(
            nodes.iter().all(|q| q.iter().all(|c| c.is_finite())),
            "{nodes:?}"
        );
        assert!(
            out.iter().all(|q| q.iter().all(|c| c.is_finite())),
            "{out:?}"
        );
    }
});
