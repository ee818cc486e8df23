//! `upetrack bench`: per-frame cost of the tracker, as medians over frames,
//! on synthetic D435i-like 640x480 frames (or given sequences). Decoding is
//! excluded, as in the contract's `total_ms`.

use std::time::Instant;

use upetrack::{Frame, Tracker};
use upetrack_io::eval::quantile;
use upetrack_io::run::track_frame;
use upetrack_synth::{RenderSettings, Scenario, ScenarioKind};

use crate::{algorithms, load_params, open_sequence, with_algorithm, Args, CliError};

/// Frames decoded or rendered, then timed.
struct Prepared {
    name: String,
    camera: upetrack::CameraIntrinsics,
    hsv: upetrack::HsvRange,
    depth_scale: f64,
    frames: Vec<(Vec<u8>, Vec<u16>, Vec<upetrack::Rect>)>,
}

fn timed(
    p: &Prepared,
    params: upetrack::Params,
    repeats: usize,
) -> Result<(Vec<f64>, Vec<f64>), CliError> {
    let mut track = Vec::new();
    let mut total = Vec::new();
    for _ in 0..repeats {
        let mut tracker =
            Tracker::new(params, p.camera, p.hsv).map_err(|e| CliError(e.to_string()))?;
        let start = Instant::now();
        let mut now = move || start.elapsed().as_secs_f64() * 1000.0;
        for (i, (rgb, depth, occ)) in p.frames.iter().enumerate() {
            let frame = Frame::new(p.camera.width, p.camera.height, rgb, depth, p.depth_scale)
                .map_err(|e| CliError(e.to_string()))?;
            let rec = track_frame(&mut tracker, i, &frame, occ, &mut now)
                .map_err(|e| CliError(e.to_string()))?;
            track.push(rec.track_ms);
            total.push(rec.total_ms);
        }
    }
    Ok((track, total))
}

/// `upetrack bench [<sequence>...] [--frames N] [--repeat R] [--algorithm A,B,..]`.
pub fn cmd_bench(raw: &[String]) -> Result<(), CliError> {
    let args = Args::parse(
        raw,
        &[],
        &crate::with_recording_options(&["frames", "repeat", "algorithm", "params"]),
    )?;
    let frames: usize = args.number("frames", 90)?;
    let repeats: usize = args.number("repeat", 3)?.max(1);
    let mut sets = Vec::new();
    if args.positional.is_empty() {
        for kind in [ScenarioKind::StaticS, ScenarioKind::DynamicPull] {
            let mut s = Scenario::new(kind, frames, 1, RenderSettings::default());
            let mut fr = Vec::new();
            while let Some(f) = s.next_frame() {
                let occ = s
                    .occlusions
                    .iter()
                    .filter(|o| (o.first..=o.last).contains(&f.index))
                    .map(|o| o.rect)
                    .collect();
                fr.push((f.rgb, f.depth, occ));
            }
            sets.push(Prepared {
                name: format!("synthetic {}", kind.name()),
                camera: s.camera(),
                hsv: s.hsv(),
                depth_scale: 0.001,
                frames: fr,
            });
        }
    } else {
        for path in &args.positional {
            let seq = open_sequence(path, &crate::RecordingArgs::from(&args)?)?;
            let mut fr = Vec::new();
            for i in 0..seq.len().min(frames) {
                let d = seq.frame(i)?;
                fr.push((d.color, d.depth, seq.occlusions_at(i)));
            }
            sets.push(Prepared {
                name: path.clone(),
                camera: seq.camera,
                hsv: seq.hsv,
                depth_scale: seq.depth_scale,
                frames: fr,
            });
        }
    }
    let params = load_params(args.value("params"))?;
    let algorithms = algorithms(&args, &params)?;
    println!("| data | algorithm | size | frames x runs | median track_ms | p90 track_ms | median total_ms | p90 total_ms |");
    println!("|---|---|---|---:|---:|---:|---:|---:|");
    for p in &sets {
        for &a in &algorithms {
            let (track, total) = timed(p, with_algorithm(params, a), repeats)?;
            println!(
                "| {} | {} | {}x{} | {} x {} | {:.3} | {:.3} | {:.3} | {:.3} |",
                p.name,
                a.name(),
                p.camera.width,
                p.camera.height,
                p.frames.len(),
                repeats,
                quantile(&track, 0.5),
                quantile(&track, 0.9),
                quantile(&total, 0.5),
                quantile(&total, 0.9)
            );
        }
    }
    Ok(())
}
