//! Helpers the command's integration tests share.
// Each test file uses a part of these.
#![allow(dead_code)]

use std::path::PathBuf;

use upetrack::math::Vec3;
use upetrack::{Params, Tracker};
use upetrack_io::{FolderSource, Sequence};

pub mod scenes;

/// A fresh temporary folder for one test (`prefix` names the test file).
pub fn temp_dir(prefix: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("upetrack-{prefix}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// Runs the command with `args` and returns its output.
pub fn run(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_upetrack"))
        .args(args)
        .output()
        .expect("run upetrack")
}

/// Runs the command with `args`, which must succeed (else its error is
/// the failure), and returns its output.
pub fn run_ok(args: &[&str]) -> std::process::Output {
    let out = run(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Writes `frames` frames of `scenario` (seed 3) into `dir` with `upetrack synth`.
pub fn synth(scenario: &str, frames: usize, dir: &std::path::Path) {
    let dir = dir.to_str().expect("utf-8");
    run_ok(&[
        "synth",
        scenario,
        dir,
        "--frames",
        &frames.to_string(),
        "--seed",
        "3",
    ]);
}

/// Drawn scene `seed` of the randomised benchmark written with
/// `upetrack synth random` (colour as JPEG, as users' recordings are):
/// its sequence and the drawn rope's length.
pub fn written_drawn_scene(seed: u64, frames: usize) -> (Sequence<FolderSource>, f64) {
    let dir = temp_dir("drawn", &seed.to_string());
    let (seed, frames) = (seed.to_string(), frames.to_string());
    let path = dir.to_str().expect("utf-8");
    run_ok(&[
        "synth", "random", path, "--seed", &seed, "--frames", &frames,
    ]);
    let scene = std::fs::read_to_string(dir.join("scene.json")).expect("scene.json");
    let draw: serde_json::Value = serde_json::from_str(&scene).expect("json");
    let length = draw["rope"]["length_m"].as_f64().expect("rope length");
    (
        Sequence::open(FolderSource::new(&dir)).expect("opens"),
        length,
    )
}

/// Every frame's error (mm) of `seq` tracked with the default parameters
/// from its files.
pub fn frame_errors(seq: &Sequence<FolderSource>) -> Vec<f64> {
    frame_errors_with(seq, Params::default())
}

/// Every frame's error (mm) of `seq` tracked with `params` from its files.
pub fn frame_errors_with(seq: &Sequence<FolderSource>, params: Params) -> Vec<f64> {
    each_tracked_frame(seq, params, |nodes, truth| {
        upetrack::metrics::frame_error(nodes, truth).expect("error") * 1000.0
    })
}

/// `measure(nodes, true centre line)` of every frame of `seq` tracked with
/// `params` from its files.
pub fn each_tracked_frame<T>(
    seq: &Sequence<FolderSource>,
    params: Params,
    mut measure: impl FnMut(&[Vec3], &[Vec3]) -> T,
) -> Vec<T> {
    let mut tracker = Tracker::new(params, seq.camera, seq.hsv).expect("tracker");
    (0..seq.groundtruth.len())
        .map(|k| {
            let decoded = seq.frame(k).expect("frame");
            let frame = decoded.frame(seq.depth_scale).expect("frame");
            let out = tracker
                .process(&frame, &seq.occlusions_at(k))
                .expect("frame");
            let truth = seq.groundtruth[k].as_ref().expect("ground truth");
            measure(&out.nodes, truth)
        })
        .collect()
}
