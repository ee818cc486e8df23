//! `upetrack bench`: per-frame cost of each stage (segmentation, point
//! cloud, tracking step, the whole frame), as medians over frames, on
//! synthetic D435i-like frames (static-s and dynamic-pull at 640x480,
//! static-s at 1280x720 on a table as saturated as the rope) or on given
//! sequences (whose
//! reading and decoding is timed apart: the contract's `total_ms` excludes it;
//! a sequence of several ropes is tracked whole, its "cloud" the sharing of
//! pixels with every rope's cloud and its step every rope's).

use std::time::Instant;

use upetrack::perception::initialisation::RopePrior;
use upetrack::{Frame, MultiTracker, Tracker};
use upetrack_io::eval::quantile;
use upetrack_io::run::{run_frame, run_frame_several};
use upetrack_synth::{Scenario, ScenarioKind, Variant};

use crate::args::BenchArgs;
use crate::{open_sequence, with_algorithm, CliError};

/// Frames decoded or rendered, then timed.
struct Prepared {
    name: String,
    camera: upetrack::CameraIntrinsics,
    hsv: upetrack::HsvRange,
    depth_scale: f64,
    /// Frames per second (the trackers' frame rate).
    fps: f64,
    frames: Vec<(Vec<u8>, Vec<u16>, Vec<upetrack::Rect>)>,
    /// Decoding time of each frame's files, ms (none for rendered frames).
    decode_ms: Vec<f64>,
    /// With several ropes, each one's colour range and prior (tracked
    /// together by a `MultiTracker`); empty for one.
    ropes: Vec<(upetrack::HsvRange, RopePrior)>,
}

/// Per-frame times of every stage, ms, over all frames and runs.
#[derive(Default)]
struct StageTimes {
    segment: Vec<f64>,
    cloud: Vec<f64>,
    track: Vec<f64>,
    total: Vec<f64>,
}

fn timed(p: &Prepared, params: upetrack::Params, repeats: usize) -> Result<StageTimes, CliError> {
    if !p.ropes.is_empty() {
        return timed_several(p, params, repeats);
    }
    let mut t = StageTimes::default();
    for _ in 0..repeats {
        let mut tracker = Tracker::new(params, p.camera, p.hsv)
            .and_then(|mut t| t.set_frame_rate(p.fps).map(|()| t))
            .map_err(|e| CliError::input(e.to_string()))?;
        let start = Instant::now();
        let mut now = move || start.elapsed().as_secs_f64() * 1000.0;
        for (rgb, depth, occ) in &p.frames {
            let frame = Frame::new(p.camera.width, p.camera.height, rgb, depth, p.depth_scale)
                .map_err(|e| CliError::input(e.to_string()))?;
            let rec = run_frame(&mut tracker, &frame, occ, &mut now)
                .map_err(|e| CliError::input(e.to_string()))?;
            t.segment.push(rec.segment_ms);
            t.cloud.push(rec.cloud_ms);
            t.track.push(rec.track_ms);
            t.total.push(rec.total_ms);
        }
    }
    Ok(t)
}

/// [`timed`] for several ropes: segmentation (one mask per colour), the
/// sharing of pixels with every rope's cloud, and every rope's step.
fn timed_several(
    p: &Prepared,
    params: upetrack::Params,
    repeats: usize,
) -> Result<StageTimes, CliError> {
    let input = |e: upetrack::tracker::TrackerError| CliError::input(e.to_string());
    let mut t = StageTimes::default();
    for _ in 0..repeats {
        let trackers = p
            .ropes
            .iter()
            .map(|(hsv, prior)| {
                let mut one = Tracker::new(params, p.camera, *hsv)?;
                one.set_rope_prior(*prior)?;
                one.set_frame_rate(p.fps)?;
                Ok(one)
            })
            .collect::<Result<Vec<_>, _>>()
            .map_err(input)?;
        let mut ropes = MultiTracker::new(trackers).map_err(input)?;
        let start = Instant::now();
        let mut now = move || start.elapsed().as_secs_f64() * 1000.0;
        for (rgb, depth, occ) in &p.frames {
            let frame = Frame::new(p.camera.width, p.camera.height, rgb, depth, p.depth_scale)
                .map_err(|e| CliError::input(e.to_string()))?;
            let rec = run_frame_several(&mut ropes, &frame, occ, &mut now).map_err(input)?;
            t.segment.push(rec.segment_ms);
            t.cloud.push(rec.cloud_ms);
            t.track.push(rec.track_ms);
            t.total.push(rec.total_ms);
        }
    }
    Ok(t)
}

/// `upetrack bench [<sequence>...] [--frames N] [--repeat R] [--algorithm A,B,..]`.
pub fn cmd_bench(args: &BenchArgs) -> Result<(), CliError> {
    let frames = args.frames;
    let repeats = args.repeat as usize;
    let mut sets = Vec::new();
    if args.sequences.is_empty() {
        // The paper's two scenes, and a 1280x720 one whose table passes the
        // rope's value and saturation range (only its hue tells them apart).
        for (kind, variant) in [
            (ScenarioKind::StaticS, Variant::BASE),
            (ScenarioKind::DynamicPull, Variant::BASE),
            (ScenarioKind::StaticS, Variant::HD_GREEN_OAK),
        ] {
            let mut s = Scenario::with_rope(kind, frames, 1, variant.render(), variant.rope());
            let mut fr = Vec::new();
            while let Some(f) = s.next_frame() {
                let occ = s.occlusions_at(f.index);
                fr.push((f.rgb, f.depth, occ));
            }
            sets.push(Prepared {
                name: format!("synthetic {} ({})", kind.name(), variant.name),
                camera: s.camera(),
                hsv: s.hsv(),
                depth_scale: 0.001,
                fps: s.fps(),
                frames: fr,
                decode_ms: Vec::new(),
                ropes: Vec::new(),
            });
        }
    } else {
        for path in &args.sequences {
            let seq = open_sequence(path, &args.recording)?;
            let mut fr = Vec::new();
            let mut decode_ms = Vec::new();
            for i in 0..seq.len().min(frames) {
                let t = Instant::now();
                let d = seq.frame(i)?;
                decode_ms.push(t.elapsed().as_secs_f64() * 1000.0);
                fr.push((d.color, d.depth, seq.occlusions_at(i)));
            }
            let several = seq.ropes.len() > 1;
            sets.push(Prepared {
                name: if several {
                    format!("{path} ({} ropes)", seq.ropes.len())
                } else {
                    path.clone()
                },
                camera: seq.camera,
                hsv: seq.hsv,
                depth_scale: seq.depth_scale,
                fps: seq.fps,
                frames: fr,
                decode_ms,
                ropes: if several {
                    seq.ropes.iter().map(|r| (r.hsv, r.prior)).collect()
                } else {
                    Vec::new()
                },
            });
        }
    }
    let (params, algorithms) = args.runs.resolve()?;
    println!("| data | algorithm | size | frames x runs | median read+decode | median segmentation | median cloud | median tracking step | median whole frame | p90 whole frame |");
    println!("|---|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for p in &sets {
        let decode = if p.decode_ms.is_empty() {
            "-".to_string()
        } else {
            format!("{:.3}", quantile(&p.decode_ms, 0.5))
        };
        for &a in &algorithms {
            let t = timed(p, with_algorithm(params, a), repeats)?;
            println!(
                "| {} | {} | {}x{} | {} x {} | {decode} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} |",
                p.name,
                a.name(),
                p.camera.width,
                p.camera.height,
                p.frames.len(),
                repeats,
                quantile(&t.segment, 0.5),
                quantile(&t.cloud, 0.5),
                quantile(&t.track, 0.5),
                quantile(&t.total, 0.5),
                quantile(&t.total, 0.9)
            );
        }
    }
    println!(
        "\nSegmentation ran its {} variant (chosen for this processor; every variant gives the same mask).",
        upetrack::perception::segmentation::segmentation_variant()
    );
    Ok(())
}
