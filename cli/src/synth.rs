//! `upetrack synth`: writes a scenario as a sequence folder in the contract's layout.

use std::path::Path;
use std::time::Instant;

use upetrack_io::synthetic::SyntheticWriter;
use upetrack_io::write::{write_file, y4m_frame, y4m_header};
use upetrack_synth::random::{RandomScene, DEFAULT_RANDOM_FRAMES};
use upetrack_synth::variant::D435I_1280X720;
use upetrack_synth::{Scenario, SeveralKind, SeveralRopes, SIMULATOR_VERSION};

use indicatif::ProgressBar;

use crate::args::{SynthArgs, SynthScenario};
use crate::bench_files::{ensure_written, forget_written};
use crate::{progress, CliError};

/// Writes `scenario` into `dir`; returns the number of frames written.
pub fn write_scenario(scenario: Scenario, dir: &Path) -> Result<usize, CliError> {
    write_scenario_and_video(
        SyntheticWriter::new(scenario),
        dir,
        None,
        &ProgressBar::hidden(),
    )
}

/// [`write_scenario`], and with `video` its colour frames as a `.y4m` (a
/// fake camera's input) from the same rendering; `bar` counts the frames.
fn write_scenario_and_video(
    writer: SyntheticWriter,
    dir: &Path,
    video: Option<&Path>,
    bar: &ProgressBar,
) -> Result<usize, CliError> {
    let camera = writer.scenario().camera();
    let fps = writer.scenario().fps().round() as u32;
    let mut y4m = video.map(|_| y4m_header(camera.width, camera.height, fps));
    let n = upetrack_io::synthetic::write_scenario(
        writer,
        &mut |(path, bytes)| write_file(&dir.join(path), &bytes),
        &mut |f| {
            bar.inc(1);
            if let Some(out) = y4m.as_mut() {
                out.extend(y4m_frame(camera.width, camera.height, &f.rgb)?);
            }
            Ok(())
        },
    )?;
    if let (Some(path), Some(out)) = (video, y4m) {
        write_file(path, &out)?;
    }
    Ok(n)
}

/// `upetrack synth <scenario> <dir> [--frames N] [--seed S] [--hd] [--variant V]
/// [--depth-noise X] [--jpeg-quality Q] [--y4m <video.y4m>]`.
pub fn cmd_synth(args: &SynthArgs) -> Result<(), CliError> {
    let kind = match args.scenario {
        SynthScenario::Random => return synth_random(args),
        SynthScenario::Several(kind) => return synth_several(Some(kind), args),
        SynthScenario::SeveralRandom => return synth_several(None, args),
        SynthScenario::Described(kind) => kind,
    };
    if args.without.is_some() || args.only.is_some() {
        return Err(CliError::usage(
            "--without and --only are for scenes of several ropes (`upetrack scenarios` lists them)",
        ));
    }
    if args.count.is_some() {
        return Err(CliError::usage(
            "--count is for `synth random`: a described scenario is one folder",
        ));
    }
    if args.fps.is_some() {
        return Err(CliError::usage(
            "--fps is for `synth random`: a described scenario is filmed at 30 frames per second",
        ));
    }
    let frames = args.frames.map_or(DEFAULT_FRAMES, |n| n as usize);
    let variant = args.variant.unwrap_or_else(|| kind.default_variant());
    let mut render = variant.render();
    if args.hd {
        render.camera = D435I_1280X720;
    }
    render.depth_noise_multiplier *= args.depth_noise.unwrap_or(1.0);
    let start = Instant::now();
    let scenario = Scenario::with_rope(kind, frames, args.seed, render, variant.rope());
    let writer = SyntheticWriter::new(scenario)
        .with_jpeg_quality(args.jpeg_quality)
        .with_rope_prior(args.rope_prior);
    let bar = progress::bar(frames as u64, "frames", kind.name());
    let n = write_scenario_and_video(writer, &args.dir, args.y4m.as_deref(), &bar)?;
    bar.finish_and_clear();
    if let Some(video) = &args.y4m {
        eprintln!("{}: the {n} colour frames as a .y4m video", video.display());
    }
    eprintln!(
        "{}: {n} frames of {} written in {:.1} s",
        args.dir.display(),
        kind.name(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// `upetrack synth <several-ropes scene> <dir> [--frames N] [--seed S]
/// [--without K | --only K] [--rope-prior]`, or `synth several-random
/// <dir> --seed S` (`kind` `None`): the ropes listed in `dlo.json`, each
/// with its own ground-truth file.
fn synth_several(kind: Option<SeveralKind>, args: &SynthArgs) -> Result<(), CliError> {
    let refused = [
        ("count", args.count.is_some()),
        ("fps", args.fps.is_some()),
        ("hd", args.hd),
        ("variant", args.variant.is_some()),
        ("y4m", args.y4m.is_some()),
        ("without", kind.is_none() && args.without.is_some()),
        ("only", kind.is_none() && args.only.is_some()),
    ];
    if let Some((name, _)) = refused.iter().find(|(_, given)| *given) {
        return Err(CliError::usage(format!(
            "--{name} does not apply to this scene of several ropes: its camera and ropes are the scene's"
        )));
    }
    let frames = args.frames.map_or(DEFAULT_FRAMES, |n| n as usize);
    let mut scene = match kind {
        Some(kind) => described_several(kind, frames, args)?,
        None => SeveralRopes::random(args.seed, frames),
    };
    scene.render.depth_noise_multiplier *= args.depth_noise.unwrap_or(1.0);
    let label = scene.name.clone();
    let start = Instant::now();
    let bar = progress::bar(frames as u64, "frames", label.clone());
    let dir = args.dir.as_path();
    let (prior, quality) = (args.rope_prior, args.jpeg_quality);
    let mut put = |(path, bytes): (String, Vec<u8>)| {
        if path.starts_with("color/") {
            bar.inc(1);
        }
        write_file(&dir.join(path), &bytes)
    };
    let n = upetrack_io::synthetic_several::write_several(scene, prior, quality, &mut put)?;
    bar.finish_and_clear();
    eprintln!(
        "{}: {n} frames of {label} written in {:.1} s",
        dir.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// A described scene of several ropes, whole or with `--without` or
/// `--only` one rope.
fn described_several(
    kind: SeveralKind,
    frames: usize,
    args: &SynthArgs,
) -> Result<SeveralRopes, CliError> {
    let no_such = |option: &str, k: usize| {
        CliError::usage(format!(
            "--{option} {k}: {} has ropes 0 to {}",
            kind.name(),
            kind.rope_count() - 1
        ))
    };
    Ok(match (args.without, args.only) {
        (Some(k), _) => SeveralRopes::without(kind, frames, args.seed, k)
            .ok_or_else(|| no_such("without", k))?,
        (None, Some(k)) => {
            SeveralRopes::only(kind, frames, args.seed, k).ok_or_else(|| no_such("only", k))?
        }
        (None, None) => SeveralRopes::new(kind, frames, args.seed),
    })
}

/// Frames of a described scenario when `--frames` is absent.
const DEFAULT_FRAMES: usize = 150;

/// How drawn scenes are filmed: frames and frames per second.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Filming {
    /// Frames of each scene.
    pub frames: usize,
    /// Frames per second.
    pub fps: f64,
}

impl Filming {
    /// `--frames` and `--fps` as given: the default rate, and as many
    /// frames as [`DEFAULT_RANDOM_FRAMES`] last at the default rate (so a
    /// scene lasts as long at any rate).
    pub fn of(frames: Option<u32>, fps: Option<f64>) -> Self {
        let fps = fps.unwrap_or(upetrack_synth::SIMULATED_FPS);
        let frames = frames.map_or_else(
            || {
                let seconds = DEFAULT_RANDOM_FRAMES as f64 / upetrack_synth::SIMULATED_FPS;
                ((seconds * fps).round() as usize).max(1)
            },
            |n| n as usize,
        );
        Self { frames, fps }
    }
}

/// The folder of drawn scene `seed` inside `dir`.
pub fn random_dir(dir: &Path, seed: u64, film: Filming) -> std::path::PathBuf {
    let Filming { frames, fps } = film;
    if fps == upetrack_synth::SIMULATED_FPS {
        dir.join(format!("random-{seed}-{frames}f"))
    } else {
        dir.join(format!("random-{seed}-{frames}f-{fps}fps"))
    }
}

/// `upetrack synth random <dir> [--seed S] [--count N] [--frames N] [--rope-prior]`:
/// one drawn scene into `dir`, or with `--count` scenes `S..S+N` into
/// folders `random-<seed>-<frames>f` inside it, one per core at a time.
/// Without `--rope-prior` a batch's folders are the ones `compare --random
/// --data <dir>` reads: a scene already written by this simulator is kept.
fn synth_random(args: &SynthArgs) -> Result<(), CliError> {
    let film = Filming::of(args.frames, args.fps);
    let frames = film.frames;
    let refused = [
        ("hd", args.hd),
        ("variant", args.variant.is_some()),
        ("depth-noise", args.depth_noise.is_some()),
        ("y4m", args.y4m.is_some()),
    ];
    if let Some((name, _)) = refused.iter().find(|(_, given)| *given) {
        return Err(CliError::usage(format!(
            "--{name} does not apply to `synth random`: the camera, rope and noise are drawn from the seed"
        )));
    }
    let (seed, dir, prior) = (args.seed, args.dir.as_path(), args.rope_prior);
    let start = Instant::now();
    let Some(count) = args.count else {
        let bar = progress::bar(frames as u64, "frames", format!("random-{seed}"));
        write_random(seed, film, prior, dir, &bar)?;
        bar.finish_and_clear();
        eprintln!(
            "{}: {frames} frames of random-{seed} written in {:.1} s",
            dir.display(),
            start.elapsed().as_secs_f64()
        );
        return Ok(());
    };
    let seeds: Vec<u64> = (seed..seed.saturating_add(count)).collect();
    let bar = progress::bar(count, "scenes", "synth random");
    for_each_parallel(&seeds, |&s| {
        let to = random_dir(dir, s, film);
        let write = |d: &Path| write_random(s, film, prior, d, &ProgressBar::hidden()).map(drop);
        if prior {
            // Its `dlo.json` is not the comparison's: no longer its cache.
            forget_written(&to)?;
            write(&to)?;
        } else {
            // Fingerprinted as `compare --random` writes them, so that it
            // reuses these scenes and a batch run again resumes.
            ensure_written(&to, &fingerprint(s, film)?, write)?;
        }
        bar.inc(1);
        Ok(())
    })?;
    bar.finish_and_clear();
    eprintln!(
        "{}: {count} drawn scenes of {frames} frames (seeds {seed}..{}) written in {:.1} s",
        dir.display(),
        seed + count - 1,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// What the simulator makes of drawn scene `seed`: its version and the
/// draw, so that a cached sequence of another draw is never reused.
pub fn fingerprint(seed: u64, film: Filming) -> Result<String, CliError> {
    let draw = RandomScene::draw_at(seed, film.frames, film.fps);
    let draw =
        serde_json::to_string(&draw).map_err(|e| CliError::input(format!("random-{seed}: {e}")))?;
    Ok(format!("simulator {SIMULATOR_VERSION}, draw {draw}\n"))
}

/// Writes drawn scene `seed` into `dir` (its `scene.json` beside the contract's files).
pub fn write_random(
    seed: u64,
    film: Filming,
    prior: bool,
    dir: &Path,
    bar: &ProgressBar,
) -> Result<usize, CliError> {
    let scenario = Scenario::random_at(seed, film.frames, film.fps);
    let writer = SyntheticWriter::new(scenario).with_rope_prior(prior);
    write_scenario_and_video(writer, dir, None, bar)
}

/// What worker threads collected under a mutex (an error when one of them
/// panicked while holding it).
pub fn gathered<T>(collected: std::sync::Mutex<Vec<T>>) -> Result<Vec<T>, CliError> {
    collected
        .into_inner()
        .map_err(|_| CliError::internal("a worker thread panicked"))
}

/// Runs `work` on every item, one item per thread at a time on as many
/// threads as the machine has cores; stops at the first error and returns it.
pub fn for_each_parallel<T: Sync>(
    items: &[T],
    work: impl Fn(&T) -> Result<(), CliError> + Sync,
) -> Result<(), CliError> {
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(items.len())
        .max(1);
    let next = std::sync::atomic::AtomicUsize::new(0);
    let first_error = std::sync::Mutex::new(None);
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(item) = items.get(i) else { break };
                if let Err(e) = work(item) {
                    if let Ok(mut slot) = first_error.lock() {
                        slot.get_or_insert(e);
                    }
                    break;
                }
            });
        }
    });
    match first_error.into_inner() {
        Ok(Some(e)) => Err(e),
        _ => Ok(()),
    }
}
