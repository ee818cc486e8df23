//! Helpers the command's integration tests share.
// Each test file uses a part of these.
#![allow(dead_code)]

use std::path::PathBuf;

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

/// Writes `frames` frames of `scenario` (seed 3) into `dir` with `upetrack synth`.
pub fn synth(scenario: &str, frames: usize, dir: &std::path::Path) {
    let dir = dir.to_str().expect("utf-8");
    let out = run(&[
        "synth",
        scenario,
        dir,
        "--frames",
        &frames.to_string(),
        "--seed",
        "3",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
