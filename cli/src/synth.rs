//! `upetrack synth`: writes a scenario as a sequence folder in the contract's layout.

use std::path::Path;
use std::time::Instant;

use upetrack_io::sequence::{
    DloConfig, GroundTruthFile, GroundTruthFrame, IntrinsicsFile, OcclusionConfig,
    SegmentationConfig,
};
use upetrack_io::write::{encode_depth_png, encode_jpeg, write_file, write_json, JPEG_QUALITY};
use upetrack_synth::variant::D435I_1280X720;
use upetrack_synth::{Scenario, ScenarioKind, Variant};

use crate::{Args, CliError, USAGE};

/// Prints every scenario with its description.
pub fn list_scenarios() {
    for k in ScenarioKind::EXAMPLES {
        let name = match k {
            ScenarioKind::OcclusionSweep { .. } => {
                format!("sweep-<K> (K in 10..={})", ScenarioKind::MAX_SWEEP_PERCENT)
            }
            _ => k.name(),
        };
        println!("{name:28} {}", k.description());
    }
    println!("\nvariants (--variant):");
    for v in Variant::ALL {
        println!("{:28} {}", v.name, v.description);
    }
}

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
            occluded: if f.occluded.iter().any(|&o| o) {
                f.occluded.clone()
            } else {
                Vec::new()
            },
        });
        count += 1;
    }
    write_json(&dir.join("groundtruth.json"), &gt)?;
    Ok(count)
}

/// `upetrack synth <scenario> <dir> [--frames N] [--seed S] [--hd] [--variant V]`.
pub fn cmd_synth(raw: &[String]) -> Result<(), CliError> {
    let args = Args::parse(raw, &["hd"], &["frames", "seed", "variant"])?;
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
    let variant = match args.value("variant") {
        None => Variant::BASE,
        Some(v) => Variant::parse(v).ok_or_else(|| {
            CliError(format!(
                "unknown variant `{v}`; `upetrack scenarios` lists them"
            ))
        })?,
    };
    let mut render = variant.render();
    if args.flag("hd") {
        render.camera = D435I_1280X720;
    }
    let start = Instant::now();
    let scenario = Scenario::with_rope(kind, frames, seed, render, variant.rope());
    let n = write_scenario(scenario, Path::new(dir))?;
    eprintln!(
        "{}: {n} frames of {} written in {:.1} s",
        dir,
        kind.name(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
