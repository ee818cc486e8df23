//! `upetrack compare --several`: the simulator's scenes of several ropes,
//! each rope tracked beside the others against the same rope tracked alone
//! (in the same scene made without the others, and in the same images with
//! the others ignored), with the identity swaps and the step's cost.

use std::path::{Path, PathBuf};

use indicatif::ProgressBar;
use upetrack::{Algorithm, Params};
use upetrack_io::eval::{quantile, summarise_ropes, Summary};
use upetrack_io::result::TrackResult;
use upetrack_synth::{SeveralKind, SeveralRopes, SIMULATOR_VERSION};

use crate::args::CompareArgs;
use crate::bench_files::{ensure_written, publish};
use crate::{fmt, open_sequence, pipeline, progress, with_algorithm, AnySequence, CliError};

/// Lines of a page between which `--update` writes the table.
const BEGIN_MARKER: &str = "<!-- several:begin -->";
const END_MARKER: &str = "<!-- several:end -->";

/// Frames of every scene when `--frames` is absent.
const DEFAULT_SEVERAL_FRAMES: usize = 90;

/// The seed of every scene.
const SEED: u64 = 1;

/// One rope of one scene tracked by one algorithm.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SeveralRow {
    /// Scene name.
    pub scene: String,
    /// Rope name.
    pub rope: String,
    /// Algorithm name.
    pub algorithm: String,
    /// Mean frame error beside the other ropes, mm.
    pub mean_mm: f64,
    /// Largest frame error beside the other ropes, mm.
    pub max_mm: f64,
    /// Frames this rope was lost on (its last nodes repeated, and counted
    /// in the errors).
    pub lost_frames: usize,
    /// Mean frame error of the same scene made with this rope alone, mm.
    pub alone_scene_mm: f64,
    /// Mean frame error in the same images, the other ropes not tracked, mm.
    pub alone_images_mm: f64,
    /// Identity swaps of the scene (every rope of it).
    pub identity_swaps: usize,
    /// Median tracking step of all the scene's ropes together, ms.
    pub step_ms: f64,
    /// Median whole frame (segmentation, sharing, clouds, steps), ms.
    pub frame_ms: f64,
}

/// A scene's folder in `data`: `variant` is "" for the whole scene,
/// `-only<k>` for rope `k` alone.
fn scene_dir(data: &Path, kind: SeveralKind, variant: &str, frames: usize) -> PathBuf {
    data.join(format!("several-{}{variant}-{frames}f", kind.name()))
}

/// Writes the scene (or rope `only` alone) into `dir` unless it is there.
fn ensure_scene(
    dir: &Path,
    kind: SeveralKind,
    only: Option<usize>,
    frames: usize,
) -> Result<(), CliError> {
    // `hints`: dlo.json names a pixel on each rope (written since then).
    let print = format!(
        "simulator {SIMULATOR_VERSION}, {} only {only:?}, {frames} frames, seed {SEED}, hints\n",
        kind.name()
    );
    ensure_written(dir, &print, |partial| {
        let scene = match only {
            Some(k) => SeveralRopes::only(kind, frames, SEED, k)
                .ok_or_else(|| CliError::input(format!("{}: no rope {k}", kind.name())))?,
            None => SeveralRopes::new(kind, frames, SEED),
        };
        upetrack_io::synthetic_several::write_several(
            scene,
            false,
            upetrack_io::write::JPEG_QUALITY,
            &mut |(path, bytes)| upetrack_io::write::write_file(&partial.join(path), &bytes),
        )?;
        Ok(())
    })
}

/// `seq` with only rope `k`: its colour, prior and ground truth.
fn with_one_rope(mut seq: AnySequence, k: usize) -> Option<AnySequence> {
    let rope = seq.ropes.get(k)?.clone();
    seq.hsv = rope.hsv;
    seq.groundtruth = rope.groundtruth.clone();
    seq.groundtruth_occluded = rope.groundtruth_occluded.clone();
    seq.ropes = vec![rope];
    Some(seq)
}

/// The mean error of `seq` tracked with `params` (its one rope, or all).
fn track(
    seq: &AnySequence,
    name: &str,
    params: Params,
) -> Result<(Vec<Summary>, TrackResult), CliError> {
    let result = pipeline::track(seq, params, &ProgressBar::hidden())?;
    Ok((summarise_ropes(name, &result, seq), result))
}

fn open(dir: &Path) -> Result<AnySequence, CliError> {
    open_sequence(&dir.to_string_lossy(), &crate::RecordingArgs::default())
}

/// `upetrack compare --several [--frames N] [--data <dir>] [--algorithm A,B]
/// [--params <params.json>] [--json ..] [--markdown ..] [--update <page.md>]`.
pub fn run(args: &CompareArgs, params: Params, algorithms: &[Algorithm]) -> Result<(), CliError> {
    if let Some(range) = &args.random {
        return run_drawn(args, range, params, algorithms);
    }
    let frames = args.frames.map_or(DEFAULT_SEVERAL_FRAMES, |n| n as usize);
    let data = args.data.as_path();
    let kinds = SeveralKind::ALL;
    let bar = progress::bar(kinds.len() as u64, "scenes", "scenes of several ropes");
    let mut rows = Vec::new();
    for kind in kinds {
        let dir = scene_dir(data, kind, "", frames);
        ensure_scene(&dir, kind, None, frames)?;
        let seq = open(&dir)?;
        // Each rope alone: in the scene made without the others, and in
        // the same images with only that rope in dlo.json.
        let mut alone = Vec::new();
        for k in 0..seq.ropes.len() {
            let alone_dir = scene_dir(data, kind, &format!("-only{k}"), frames);
            ensure_scene(&alone_dir, kind, Some(k), frames)?;
            let same = with_one_rope(open(&dir)?, k)
                .ok_or_else(|| CliError::input(format!("{}: no rope {k}", kind.name())))?;
            alone.push((open(&alone_dir)?, same));
        }
        for &a in algorithms {
            let p = with_algorithm(params, a);
            let (summaries, result) = track(&seq, kind.name(), p)?;
            let swaps = summaries.last().map_or(0, |s| s.identity_swaps);
            let steps: Vec<f64> = result.frames.iter().map(|f| f.track_ms).collect();
            let whole: Vec<f64> = result.frames.iter().map(|f| f.total_ms).collect();
            for (k, (rope, (scene, images))) in seq.ropes.iter().zip(&alone).enumerate() {
                let (scene, _) = track(scene, kind.name(), p)?;
                let (images, _) = track(images, kind.name(), p)?;
                let mine = summaries.get(k).ok_or_else(|| {
                    CliError::input(format!("{}: no row for rope {k}", kind.name()))
                })?;
                let mean_of = |s: &[Summary]| s.first().map_or(f64::NAN, |s| s.mm.mean);
                rows.push(SeveralRow {
                    scene: kind.name().to_string(),
                    rope: rope.name.clone(),
                    algorithm: a.name().to_string(),
                    mean_mm: mine.mm.mean,
                    max_mm: mine.max_mm,
                    lost_frames: mine.lost_frames,
                    alone_scene_mm: mean_of(&scene),
                    alone_images_mm: mean_of(&images),
                    identity_swaps: swaps,
                    step_ms: quantile(&steps, 0.5),
                    frame_ms: quantile(&whole, 0.5),
                });
            }
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let text = markdown(&rows, frames);
    let update = args.update.as_deref();
    publish(
        &text,
        &rows,
        &args.outputs,
        update,
        (BEGIN_MARKER, END_MARKER),
    )
}

/// The table of `rows`.
fn markdown(rows: &[SeveralRow], frames: usize) -> String {
    let mut s = format!(
        "Scenes of {frames} frames (seed {SEED}; `upetrack synth <scene>`). Mean and max frame error of each rope \
         tracked beside the others, and the frames it was lost on (out of view: its last nodes repeated, \
         counted in the errors); its mean error alone in the same scene made without the others (`--only K`) \
         and in the same images with the others not tracked, and the ratios; the scene's identity swaps; the \
         median step of all its ropes and the median whole frame.\n\n\
         | scene | rope | algorithm | mean mm | max mm | lost | alone (scene) mm | ratio | alone (images) mm | ratio | swaps | step ms | frame ms |\n\
         |---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n"
    );
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.scene,
            r.rope,
            r.algorithm,
            fmt(r.mean_mm, 2),
            fmt(r.max_mm, 1),
            r.lost_frames,
            fmt(r.alone_scene_mm, 2),
            fmt(r.mean_mm / r.alone_scene_mm, 2),
            fmt(r.alone_images_mm, 2),
            fmt(r.mean_mm / r.alone_images_mm, 2),
            r.identity_swaps,
            fmt(r.step_ms, 3),
            fmt(r.frame_ms, 3),
        );
    }
    s
}

/// One drawn scene of several ropes tracked by one algorithm.
#[derive(Debug, Clone, serde::Serialize)]
pub struct DrawnRow {
    /// The seed.
    pub seed: u64,
    /// Algorithm name.
    pub algorithm: String,
    /// Ropes in the scene.
    pub ropes: usize,
    /// `true` when every rope has one colour.
    pub one_colour: bool,
    /// Each rope's mean frame error, mm, in the scene's order.
    pub mean_mm: Vec<f64>,
    /// The largest frame error of any rope, mm.
    pub max_mm: f64,
    /// Frames (of all ropes) above 20 mm.
    pub frames_above_20mm: usize,
    /// Frames (of all ropes) with ground truth.
    pub evaluated_frames: usize,
    /// Identity swaps.
    pub identity_swaps: usize,
    /// Median step of all ropes together, ms.
    pub step_ms: f64,
}

/// The folder of drawn scene `seed` of several ropes in `data`.
fn drawn_dir(data: &Path, seed: u64, frames: usize) -> PathBuf {
    data.join(format!("several-random-{seed}-{frames}f"))
}

/// `upetrack compare --several --random tune|report [--count N]`: the
/// drawn scenes of several ropes of a seed range; per algorithm the median,
/// p90 and max of the ropes' mean errors, the share of frames above 20 mm
/// and the identity swaps, and the worst scenes.
fn run_drawn(
    args: &CompareArgs,
    range_name: &str,
    params: Params,
    algorithms: &[Algorithm],
) -> Result<(), CliError> {
    let range = upetrack_synth::SeedRange::parse(range_name)
        .ok_or_else(|| CliError::usage(format!("--random {range_name}: tune or report")))?;
    let frames = args
        .frames
        .map_or(upetrack_synth::random::DEFAULT_RANDOM_FRAMES, |n| {
            n as usize
        });
    let seeds: Vec<u64> = range.seeds(args.count.unwrap_or(u64::MAX)).collect();
    let data = args.data.as_path();
    let bar = progress::bar(
        seeds.len() as u64,
        "scenes",
        "drawn scenes of several ropes",
    );
    let rows = std::sync::Mutex::new(Vec::new());
    crate::synth::for_each_parallel(&seeds, |&seed| {
        let dir = drawn_dir(data, seed, frames);
        let print = format!(
            "simulator {SIMULATOR_VERSION}, several-random {seed}, {frames} frames, hints\n"
        );
        ensure_written(&dir, &print, |partial| {
            upetrack_io::synthetic_several::write_several(
                SeveralRopes::random(seed, frames),
                false,
                upetrack_io::write::JPEG_QUALITY,
                &mut |(path, bytes)| upetrack_io::write::write_file(&partial.join(path), &bytes),
            )?;
            Ok(())
        })?;
        let seq = open(&dir)?;
        let one_colour = seq.ropes.iter().all(|r| r.hsv == seq.ropes[0].hsv);
        for &a in algorithms {
            let (summaries, result) = track(
                &seq,
                &format!("several-random-{seed}"),
                with_algorithm(params, a),
            )?;
            let all = summaries.last().ok_or_else(|| CliError::input("no rows"))?;
            let steps: Vec<f64> = result.frames.iter().map(|f| f.track_ms).collect();
            let row = DrawnRow {
                seed,
                algorithm: a.name().to_string(),
                ropes: seq.ropes.len(),
                one_colour,
                mean_mm: summaries[..summaries.len().saturating_sub(1)]
                    .iter()
                    .map(|s| s.mm.mean)
                    .collect(),
                max_mm: all.max_mm,
                frames_above_20mm: all.frames_above_20mm,
                evaluated_frames: all.evaluated_frames,
                identity_swaps: all.identity_swaps,
                step_ms: quantile(&steps, 0.5),
            };
            if let Ok(mut rows) = rows.lock() {
                rows.push(row);
            }
        }
        bar.inc(1);
        Ok(())
    })?;
    bar.finish_and_clear();
    let mut rows = crate::synth::gathered(rows)?;
    rows.sort_by(|a, b| (a.seed, &a.algorithm).cmp(&(b.seed, &b.algorithm)));
    let text = drawn_markdown(&rows, range_name, &seeds, frames, algorithms);
    let markers = (DRAWN_BEGIN_MARKER, DRAWN_END_MARKER);
    publish(&text, &rows, &args.outputs, args.update.as_deref(), markers)
}

/// Lines of a page between which `--update` writes the drawn table.
const DRAWN_BEGIN_MARKER: &str = "<!-- several-random:begin -->";
const DRAWN_END_MARKER: &str = "<!-- several-random:end -->";

/// Scenes listed as the worst per algorithm.
const WORST_LISTED: usize = 5;

/// The table of the drawn scenes' rows.
fn drawn_markdown(
    rows: &[DrawnRow],
    range: &str,
    seeds: &[u64],
    frames: usize,
    algorithms: &[Algorithm],
) -> String {
    let (first, last) = (
        seeds.first().copied().unwrap_or(0),
        seeds.last().copied().unwrap_or(0),
    );
    let mut s = format!(
        "Produced by `upetrack compare --several --random {range}`: {} drawn scenes of several ropes (seeds \
         {first}..{last}) of {frames} frames. Per algorithm, over every rope of every scene: the median, p90 and \
         max of the ropes' mean frame error; the share of frames (of all ropes) above 20 mm; the identity swaps and \
         the scenes with one; the median step of all a scene's ropes; the worst scenes (their largest rope mean).\n\n\
         | algorithm | ropes | median mm | p90 mm | max mm | frames > 20 mm | swaps (scenes) | step ms | worst scenes |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---|\n",
        seeds.len()
    );
    for a in algorithms {
        let mine: Vec<&DrawnRow> = rows.iter().filter(|r| r.algorithm == a.name()).collect();
        let means: Vec<f64> = mine
            .iter()
            .flat_map(|r| r.mean_mm.iter().copied())
            .collect();
        let above: usize = mine.iter().map(|r| r.frames_above_20mm).sum();
        let evaluated: usize = mine.iter().map(|r| r.evaluated_frames).sum();
        let swaps: usize = mine.iter().map(|r| r.identity_swaps).sum();
        let swapped = mine.iter().filter(|r| r.identity_swaps > 0).count();
        let steps: Vec<f64> = mine.iter().map(|r| r.step_ms).collect();
        let worst_of = |r: &DrawnRow| r.mean_mm.iter().copied().fold(f64::NAN, f64::max);
        let mut worst = mine.clone();
        worst.sort_by(|x, y| worst_of(y).total_cmp(&worst_of(x)));
        let listed: Vec<String> = worst
            .iter()
            .take(WORST_LISTED)
            .map(|r| {
                format!(
                    "{} ({} mm, {} ropes{})",
                    r.seed,
                    fmt(worst_of(r), 1),
                    r.ropes,
                    if r.one_colour { ", one colour" } else { "" }
                )
            })
            .collect();
        s += &format!(
            "| {} | {} | {} | {} | {} | {} | {} ({}) | {} | {} |\n",
            a.name(),
            means.len(),
            fmt(quantile(&means, 0.5), 2),
            fmt(quantile(&means, 0.9), 2),
            fmt(means.iter().copied().fold(f64::NAN, f64::max), 1),
            fmt(100.0 * above as f64 / evaluated.max(1) as f64, 1) + " %",
            swaps,
            swapped,
            fmt(quantile(&steps, 0.5), 3),
            listed.join("; "),
        );
    }
    s
}
