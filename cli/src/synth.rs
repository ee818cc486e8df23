//! `upetrack synth`: writes a scenario as a sequence folder in the contract's layout.

use std::path::Path;
use std::time::Instant;

use upetrack::CameraIntrinsics;
use upetrack_io::sequence::{
    DloConfig, GroundTruthFile, GroundTruthFrame, IntrinsicsFile, OcclusionConfig,
    SegmentationConfig,
};
use upetrack_io::write::{encode_depth_png, encode_jpeg, write_file, write_json, JPEG_QUALITY};
use upetrack_synth::{RenderSettings, Scenario, ScenarioKind};

use crate::{Args, CliError, USAGE};

/// Prints every scenario with its description.
pub fn list_scenarios() {
    for k in ScenarioKind::EXAMPLES {
        let name = match k {
            ScenarioKind::OcclusionSweep { .. } => "sweep-<K> (K in 10..=50)".to_string(),
            _ => k.name(),
        };
        println!("{name:28} {}", k.description());
    }
}

/// Camera for `--hd`: the D435i colour stream at 1280x720.
const D435I_1280X720: CameraIntrinsics = CameraIntrinsics {
    width: 1280,
    height: 720,
    fx: 922.5,
    fy: 922.5,
    cx: 640.0,
    cy: 360.0,
};

/// Writes `scenario` into `dir`; returns the number of frames written.
pub fn write_scenario(mut scenario: Scenario, dir: &Path) -> Result<usize, CliError> {
    let camera = scenario.camera();
    write_json(
        &dir.join("camera_intrinsic.json"),
        &IntrinsicsFile::from_camera(&camera),
    )?;
    let hsv = scenario.hsv();
    let dlo = DloConfig {
        depth_scale: Some(0.001),
        fps: Some(30.0),
        segmentation: Some(SegmentationConfig {
            hsv_lower: hsv.lower,
            hsv_upper: hsv.upper,
        }),
        occlusions: scenario
            .occlusions
            .iter()
            .map(|o| OcclusionConfig {
                frames: [o.first as u64, o.last as u64],
                rect: [o.rect.x, o.rect.y, o.rect.w, o.rect.h],
            })
            .collect(),
        groundtruth: Some("groundtruth.json".into()),
    };
    write_json(&dir.join("dlo.json"), &dlo)?;
    let mut gt = GroundTruthFile::default();
    let mut count = 0;
    while let Some(f) = scenario.next_frame() {
        let name = format!("{:06}", f.index);
        let jpg = encode_jpeg(camera.width, camera.height, &f.rgb, JPEG_QUALITY)?;
        write_file(&dir.join("color").join(format!("{name}.jpg")), &jpg)?;
        let png = encode_depth_png(camera.width, camera.height, &f.depth)?;
        write_file(&dir.join("depth").join(format!("{name}.png")), &png)?;
        gt.frames.push(GroundTruthFrame {
            frame: f.index,
            points: f.groundtruth.iter().map(|p| [p.x, p.y, p.z]).collect(),
        });
        count += 1;
    }
    write_json(&dir.join("groundtruth.json"), &gt)?;
    Ok(count)
}

/// `upetrack synth <scenario> <dir> [--frames N] [--seed S] [--hd]`.
pub fn cmd_synth(raw: &[String]) -> Result<(), CliError> {
    let args = Args::parse(raw, &["hd"], &["frames", "seed"])?;
    let [name, dir] = args.positional.as_slice() else {
        return Err(CliError(format!(
            "synth takes a scenario and a folder\n\n{USAGE}"
        )));
    };
    let kind = ScenarioKind::parse(name).ok_or_else(|| {
        CliError(format!(
            "unknown scenario `{name}`; `upetrack scenarios` lists them"
        ))
    })?;
    let frames: usize = args.number("frames", 150)?;
    if frames == 0 || frames > upetrack_synth::scenario::MAX_FRAMES {
        return Err(CliError(format!(
            "--frames must be in 1..={}",
            upetrack_synth::scenario::MAX_FRAMES
        )));
    }
    let seed: u64 = args.number("seed", 1)?;
    let mut render = RenderSettings::default();
    if args.flag("hd") {
        render.camera = D435I_1280X720;
    }
    let start = Instant::now();
    let n = write_scenario(Scenario::new(kind, frames, seed, render), Path::new(dir))?;
    eprintln!(
        "{}: {n} frames of {} written in {:.1} s",
        dir,
        kind.name(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
