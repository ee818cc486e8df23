//! `upetrack compare --random <range>`: every algorithm on the drawn scenes
//! of one seed range (`tune` to choose rules on, `report` to judge them),
//! summarised per algorithm: median, p90 and max of each sequence's
//! after-occlusion error, the share of frames above 20 mm, and the worst
//! seeds with what was drawn for them.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use serde::Serialize;
use upetrack::{Algorithm, Params};
use upetrack_io::eval::Summary;
use upetrack_synth::random::{MotionKind, OccluderKind, RandomScene, SeedRange, ShapeDraw};

use crate::bench_files::{ensure_written, publish};
use crate::synth::{fingerprint, for_each_parallel, gathered, random_dir, write_random, Filming};
use indicatif::ProgressBar;

use crate::args::CompareArgs;
use crate::{evaluate, fmt, open_sequence, progress, with_algorithm, CliError};

/// Lines of a page between which `--update` writes the random table.
const BEGIN_MARKER: &str = "<!-- random:begin -->";
const END_MARKER: &str = "<!-- random:end -->";
/// Seeds listed as the worst.
const WORST: usize = 10;

/// One drawn sequence tracked by one algorithm.
#[derive(Serialize)]
struct Row {
    seed: u64,
    /// The sequence's error after its first occluded frame (its whole mean
    /// when nothing hides the rope), mm and px.
    after_mm: f64,
    after_px: f64,
    summary: Summary,
}

/// Everything `--json` writes.
#[derive(Serialize)]
struct RandomComparison {
    range: &'static str,
    seeds: Vec<u64>,
    frames: usize,
    rows: Vec<Row>,
    draws: Vec<RandomScene>,
}

/// The quantile `q` of `xs` (sorted copy, nearest rank; NaN left out).
fn quantile(xs: &[f64], q: f64) -> f64 {
    let mut v: Vec<f64> = xs.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let rank = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len());
    v[rank - 1]
}

/// One line on what was drawn for a scene.
pub fn describe(d: &RandomScene) -> String {
    let camera = match &d.camera.motion {
        None => "still",
        Some(upetrack_synth::random::CameraPath::Arm { .. }) => "on an arm",
        Some(upetrack_synth::random::CameraPath::Handheld { .. }) => "handheld",
    };
    let motion = match d.motion.kind {
        MotionKind::Rest => "at rest".to_string(),
        k => format!("{k:?} {:.0} cm", d.motion.distance_m * 100.0),
    };
    let occluder = match d.occluder.kind {
        OccluderKind::None => "no occluder".to_string(),
        k => format!(
            "{k:?} over {:.0} % from frame {}{}",
            d.occluder.share * 100.0,
            d.occluder.first_frame,
            if d.moved_end_hidden() {
                ", the moved end under it while it moves"
            } else {
                ""
            }
        ),
    };
    let shape = match d.shape {
        ShapeDraw::Arc { depth } => format!("an arc {depth:.2} deep"),
        ShapeDraw::Wave { periods, amplitude } => {
            format!("a wave of {periods:.1} periods, {amplitude:.2} high")
        }
        ShapeDraw::Loop => "a loop crossing itself".into(),
    };
    format!(
        "{}x{} at {:.2} m tilted {:.0} deg, {camera}; {:.2} m x {:.1} mm {:?} rope on {:?} table, {} clutter; {shape}; {motion}; {occluder}",
        d.camera.width,
        d.camera.height,
        d.camera.distance_m,
        d.camera.tilt_deg,
        d.rope.length_m,
        d.rope.diameter_m * 1000.0,
        d.rope.colour,
        d.table.kind,
        d.placed.clutter.len(),
    )
}

/// The table per algorithm and the worst seeds, in Markdown.
fn tables(
    range: SeedRange,
    rows: &[Row],
    draws: &[RandomScene],
    algorithms: &[Algorithm],
) -> String {
    let seeds = draws.len();
    let mut s = format!(
        "Produced by `upetrack compare --random {}`: {seeds} drawn scenes (seeds {}..{}) of {} frames. \
         Per sequence, the error after its first occluded frame (its whole mean when nothing hides the rope); \
         below, the median, p90 and max of that over the sequences; in brackets, the sequences with a frame above 20 mm whose moved end was under the occluder while it moved.\n\n\
         | algorithm | median mm | p90 mm | max mm | median px | p90 px | max px | frames > 20 mm | sequences with a frame > 20 mm | lost frames |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        range.name,
        draws.first().map_or(0, |d| d.seed),
        draws.last().map_or(0, |d| d.seed),
        draws.first().map_or(0, |d| d.frames),
    );
    // The seeds whose moved end was hidden while it moved, once for every algorithm.
    let unseen: Vec<u64> = draws
        .iter()
        .filter(|d| d.moved_end_hidden())
        .map(|d| d.seed)
        .collect();
    for a in algorithms {
        let mine: Vec<&Row> = rows
            .iter()
            .filter(|r| r.summary.algorithm == a.name())
            .collect();
        let mm: Vec<f64> = mine.iter().map(|r| r.after_mm).collect();
        let px: Vec<f64> = mine.iter().map(|r| r.after_px).collect();
        let frames: usize = mine.iter().map(|r| r.summary.frames).sum();
        let above: usize = mine.iter().map(|r| r.summary.frames_above_20mm).sum();
        let lost: usize = mine.iter().map(|r| r.summary.lost_frames).sum();
        let failing: Vec<u64> = mine
            .iter()
            .filter(|r| r.summary.frames_above_20mm > 0)
            .map(|r| r.seed)
            .collect();
        let failing_unseen = failing.iter().filter(|s| unseen.contains(s)).count();
        let failing = failing.len();
        let share = |k: usize| 100.0 * k as f64 / frames.max(1) as f64;
        s += &format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} % | {failing} of {} ({failing_unseen}) | {} % |\n",
            a.name(),
            fmt(quantile(&mm, 0.5), 2),
            fmt(quantile(&mm, 0.9), 2),
            fmt(quantile(&mm, 1.0), 1),
            fmt(quantile(&px, 0.5), 2),
            fmt(quantile(&px, 0.9), 2),
            fmt(quantile(&px, 1.0), 1),
            fmt(share(above), 1),
            mine.len(),
            fmt(share(lost), 1),
        );
    }
    s += "\nThe whole rope's length (each sequence's largest relative error of the node polyline's length against the true centre line's, over its frames, and how many sequences have a frame above 5 %; then the same against the true centre line sampled at the tracker's node count by arc length, whose polyline cuts the bends as the nodes' must), the visible nodes' mean offset from the true centre line along the viewing ray (positive: behind it), the ends seen (each sequence's mean distance from an end node in view to the true rope's tip, and how much centre line lies between the tip and the node: how far short of it the tracked rope stops) and the hidden ends (the same distance for an end node not seen), over the sequences:\n\n\
         | algorithm | length error max: median | p90 | max | above 5 % | at the node count: median | p90 | above 5 % | ray offset mm: median | p10 | p90 | median of its size | end mm: median | p90 | short of the tip mm: median | hidden end mm: median | p90 |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for a in algorithms {
        let mine: Vec<&Row> = rows
            .iter()
            .filter(|r| r.summary.algorithm == a.name())
            .collect();
        let length: Vec<f64> = mine
            .iter()
            .map(|r| 100.0 * r.summary.length_error_max)
            .collect();
        let sampled: Vec<f64> = mine
            .iter()
            .map(|r| 100.0 * r.summary.length_error_sampled_max)
            .collect();
        let above = |v: &[f64]| v.iter().filter(|&&e| e > 5.0).count();
        let offset: Vec<f64> = mine
            .iter()
            .map(|r| r.summary.visible_ray_offset_mm)
            .collect();
        let size: Vec<f64> = offset.iter().map(|o| o.abs()).collect();
        let end: Vec<f64> = mine.iter().map(|r| r.summary.end_mm).collect();
        let short: Vec<f64> = mine.iter().map(|r| r.summary.end_arc_mm).collect();
        let hidden: Vec<f64> = mine.iter().map(|r| r.summary.hidden_end_mm).collect();
        s += &format!(
            "| {} | {} % | {} % | {} % | {} | {} % | {} % | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            a.name(),
            fmt(quantile(&length, 0.5), 1),
            fmt(quantile(&length, 0.9), 1),
            fmt(quantile(&length, 1.0), 1),
            above(&length),
            fmt(quantile(&sampled, 0.5), 1),
            fmt(quantile(&sampled, 0.9), 1),
            above(&sampled),
            fmt(quantile(&offset, 0.5), 2),
            fmt(quantile(&offset, 0.1), 2),
            fmt(quantile(&offset, 0.9), 2),
            fmt(quantile(&size, 0.5), 2),
            fmt(quantile(&end, 0.5), 1),
            fmt(quantile(&end, 0.9), 1),
            fmt(quantile(&short, 0.5), 1),
            fmt(quantile(&hidden, 0.5), 1),
            fmt(quantile(&hidden, 0.9), 1),
        );
    }
    let mut ours: Vec<&Row> = rows
        .iter()
        .filter(|r| r.summary.algorithm == Algorithm::Upetrack.name())
        .collect();
    ours.sort_by(|a, b| b.after_mm.total_cmp(&a.after_mm));
    s += &format!(
        "\nThe {WORST} seeds where UPETrack's error is largest (mm; each baseline's beside it):\n\n\
         | seed | upetrack |"
    );
    let baselines: Vec<&Algorithm> = algorithms
        .iter()
        .filter(|a| **a != Algorithm::Upetrack)
        .collect();
    for b in &baselines {
        s += &format!(" {} |", b.name());
    }
    s += " what was drawn |\n|---:|---:|";
    s += &"---:|".repeat(baselines.len());
    s += "---|\n";
    for r in ours.iter().take(WORST) {
        s += &format!("| {} | {} |", r.seed, fmt(r.after_mm, 2));
        for b in &baselines {
            let theirs = rows
                .iter()
                .find(|x| x.seed == r.seed && x.summary.algorithm == b.name())
                .map_or(f64::NAN, |x| x.after_mm);
            s += &format!(" {} |", fmt(theirs, 2));
        }
        let what = draws
            .iter()
            .find(|d| d.seed == r.seed)
            .map(describe)
            .unwrap_or_default();
        s += &format!(" {what} |\n");
    }
    s
}

/// `upetrack compare --random <tune|report> [--count N] [--frames N] [--data <dir>]
/// [--algorithm A,B] [--params <params.json>] [--json ..] [--markdown ..] [--update <page.md>]`.
pub fn run(
    args: &CompareArgs,
    range_name: &str,
    params: Params,
    algorithms: &[Algorithm],
) -> Result<(), CliError> {
    let count = args.count.unwrap_or(u64::MAX);
    let data = args.data.as_path();
    let (outputs, update) = (&args.outputs, args.update.as_deref());
    let range = SeedRange::parse(range_name).ok_or_else(|| {
        CliError::usage(format!(
            "--random takes a seed range: {}",
            SeedRange::ALL
                .map(|r| format!("{} (seeds {}..{})", r.name, r.first, r.first + r.count - 1))
                .join(" or ")
        ))
    })?;
    let film = Filming::of(args.frames, args.fps);
    let frames = film.frames;
    let seeds: Vec<u64> = range.seeds(count).collect();
    let dirs: Vec<(u64, PathBuf)> = seeds
        .iter()
        .map(|&s| (s, random_dir(data, s, film)))
        .collect();
    let bar = progress::bar(dirs.len() as u64, "scenes", "writing drawn scenes");
    for_each_parallel(&dirs, |(seed, dir)| {
        ensure_written(dir, &fingerprint(*seed, film)?, |partial| {
            write_random(*seed, film, false, partial, &ProgressBar::hidden()).map(drop)
        })?;
        bar.inc(1);
        Ok(())
    })?;
    bar.finish_and_clear();
    let bar = progress::bar(dirs.len() as u64, "scenes", "tracking drawn scenes");
    let rows = Mutex::new(Vec::new());
    let draws = Mutex::new(Vec::new());
    for_each_parallel(&dirs, |(seed, dir)| {
        let seq = open_sequence(&dir.to_string_lossy(), &crate::RecordingArgs::default())?;
        let scene: RandomScene = read_scene(dir)?;
        for &a in algorithms {
            let (summary, _) = evaluate(
                &seq,
                &format!("random-{seed}"),
                with_algorithm(params, a),
                &ProgressBar::hidden(),
            )?;
            let (after_mm, after_px) = if summary.occluded_mean_mm.is_finite() {
                (summary.occluded_mean_mm, summary.occluded_mean_px)
            } else {
                (summary.mm.mean, summary.px.mean)
            };
            progress::say(
                &bar,
                &format!(
                    "random-{seed:<5} {:9} after occlusion {:>6} mm {:>5} px",
                    a.name(),
                    fmt(after_mm, 2),
                    fmt(after_px, 2)
                ),
            );
            if let Ok(mut rows) = rows.lock() {
                rows.push(Row {
                    seed: *seed,
                    after_mm,
                    after_px,
                    summary,
                });
            }
        }
        if let Ok(mut draws) = draws.lock() {
            draws.push(scene);
        }
        bar.inc(1);
        Ok(())
    })?;
    bar.finish_and_clear();
    let mut rows = gathered(rows)?;
    let mut draws = gathered(draws)?;
    rows.sort_by_key(|r| r.seed);
    draws.sort_by_key(|d| d.seed);
    let text = tables(range, &rows, &draws, algorithms);
    let all = RandomComparison {
        range: range.name,
        seeds,
        frames,
        rows,
        draws,
    };
    publish(&text, &all, outputs, update, (BEGIN_MARKER, END_MARKER))?;
    Ok(())
}

/// The draw recorded beside a drawn sequence.
fn read_scene(dir: &Path) -> Result<RandomScene, CliError> {
    let path = dir.join(upetrack_io::synthetic::SCENE_FILE);
    let text = std::fs::read_to_string(&path)
        .map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
    serde_json::from_str(&text).map_err(|e| CliError::input(format!("{}: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_draw_s_line_tells_a_moved_end_under_the_occluder() {
        for seed in [2093, 2027, 2066] {
            let d = RandomScene::draw(seed, 48);
            assert_eq!(
                describe(&d).contains("the moved end under it while it moves"),
                d.moved_end_hidden(),
                "seed {seed}"
            );
        }
    }
}
