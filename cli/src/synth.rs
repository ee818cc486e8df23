//! `upetrack synth`: writes a scenario as a sequence folder in the contract's layout.

use std::path::Path;
use std::time::Instant;

use upetrack_io::synthetic::SyntheticWriter;
use upetrack_io::write::{write_file, y4m_frame, y4m_header, JPEG_QUALITY};
use upetrack_synth::random::DEFAULT_RANDOM_FRAMES;
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
pub fn write_scenario(scenario: Scenario, dir: &Path) -> Result<usize, CliError> {
    write_scenario_and_video(SyntheticWriter::new(scenario), dir, None)
}

/// [`write_scenario`], and with `video` its colour frames as a `.y4m` (a
/// fake camera's input) from the same rendering.
fn write_scenario_and_video(
    writer: SyntheticWriter,
    dir: &Path,
    video: Option<&Path>,
) -> Result<usize, CliError> {
    let camera = writer.scenario().camera();
    let fps = upetrack_io::synthetic::SYNTHETIC_FPS as u32;
    let mut y4m = video.map(|_| y4m_header(camera.width, camera.height, fps));
    let n = upetrack_io::synthetic::write_scenario(
        writer,
        &mut |(path, bytes)| write_file(&dir.join(path), &bytes),
        &mut |f| {
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

/// Largest `--depth-noise` multiplier.
pub const MAX_DEPTH_NOISE: f64 = 10.0;

/// `upetrack synth <scenario> <dir> [--frames N] [--seed S] [--hd] [--variant V]
/// [--depth-noise X] [--jpeg-quality Q] [--y4m <video.y4m>]`.
pub fn cmd_synth(raw: &[String]) -> Result<(), CliError> {
    let args = Args::parse(
        raw,
        &["hd", "rope-prior"],
        &[
            "count",
            "frames",
            "seed",
            "variant",
            "depth-noise",
            "jpeg-quality",
            "y4m",
        ],
    )?;
    let [name, dir] = args.positional.as_slice() else {
        return Err(CliError(format!(
            "synth takes a scenario and a folder\n\n{USAGE}"
        )));
    };
    if name == "random" {
        return synth_random(&args, Path::new(dir));
    }
    let kind = ScenarioKind::parse(name).ok_or_else(|| {
        CliError(format!(
            "unknown scenario `{name}`; `upetrack scenarios` lists them"
        ))
    })?;
    let frames: usize = args.number("frames", 150)?;
    if frames == 0 || frames > upetrack_synth::MAX_FRAMES {
        return Err(CliError(format!(
            "--frames must be in 1..={}",
            upetrack_synth::MAX_FRAMES
        )));
    }
    let seed: u64 = args.number("seed", 1)?;
    let variant = match args.value("variant") {
        None => kind.default_variant(),
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
    let depth_noise: f64 = args.number("depth-noise", 1.0)?;
    if !(0.0..=MAX_DEPTH_NOISE).contains(&depth_noise) {
        return Err(CliError(format!(
            "--depth-noise must be in 0..={MAX_DEPTH_NOISE}"
        )));
    }
    render.depth_noise_multiplier *= depth_noise;
    let quality: u8 = args.number("jpeg-quality", JPEG_QUALITY)?;
    if !(1..=100).contains(&quality) {
        return Err(CliError("--jpeg-quality must be in 1..=100".into()));
    }
    let start = Instant::now();
    let scenario = Scenario::with_rope(kind, frames, seed, render, variant.rope());
    let writer = SyntheticWriter::new(scenario)
        .with_jpeg_quality(quality)
        .with_rope_prior(args.flag("rope-prior"));
    let video = args.value("y4m");
    let n = write_scenario_and_video(writer, Path::new(dir), video.map(Path::new))?;
    if let Some(video) = video {
        eprintln!("{video}: the {n} colour frames as a .y4m video");
    }
    eprintln!(
        "{}: {n} frames of {} written in {:.1} s",
        dir,
        kind.name(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Most scenes one `synth random --count` writes.
pub const MAX_RANDOM_COUNT: u64 = 10_000;

/// The folder of drawn scene `seed` inside `dir`.
pub fn random_dir(dir: &Path, seed: u64, frames: usize) -> std::path::PathBuf {
    dir.join(format!("random-{seed}-{frames}f"))
}

/// `upetrack synth random <dir> [--seed S] [--count N] [--frames N] [--rope-prior]`:
/// one drawn scene into `dir`, or with `--count` scenes `S..S+N` into
/// folders `random-<seed>-<frames>f` inside it, two at a time.
fn synth_random(args: &Args, dir: &Path) -> Result<(), CliError> {
    let frames: usize = args.number("frames", DEFAULT_RANDOM_FRAMES)?;
    if frames == 0 || frames > upetrack_synth::MAX_FRAMES {
        return Err(CliError(format!(
            "--frames must be in 1..={}",
            upetrack_synth::MAX_FRAMES
        )));
    }
    for refused in ["hd", "variant", "depth-noise", "y4m"] {
        if args.flag(refused) || args.value(refused).is_some() {
            return Err(CliError(format!(
                "--{refused} does not apply to `synth random`: the camera, rope and noise are drawn from the seed"
            )));
        }
    }
    let seed: u64 = args.number("seed", 1)?;
    let start = Instant::now();
    let prior = args.flag("rope-prior");
    let Some(count) = args
        .value("count")
        .map(|_| args.number::<u64>("count", 1))
        .transpose()?
    else {
        write_random(seed, frames, prior, dir)?;
        eprintln!(
            "{}: {frames} frames of random-{seed} written in {:.1} s",
            dir.display(),
            start.elapsed().as_secs_f64()
        );
        return Ok(());
    };
    if !(1..=MAX_RANDOM_COUNT).contains(&count) {
        return Err(CliError(format!(
            "--count must be in 1..={MAX_RANDOM_COUNT}"
        )));
    }
    let seeds: Vec<u64> = (seed..seed.saturating_add(count)).collect();
    for_each_parallel(&seeds, |&s| {
        write_random(s, frames, prior, &random_dir(dir, s, frames)).map(drop)
    })?;
    eprintln!(
        "{}: {count} drawn scenes of {frames} frames (seeds {seed}..{}) written in {:.1} s",
        dir.display(),
        seed + count - 1,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Writes drawn scene `seed` into `dir` (its `scene.json` beside the contract's files).
pub fn write_random(seed: u64, frames: usize, prior: bool, dir: &Path) -> Result<usize, CliError> {
    let writer = SyntheticWriter::new(Scenario::random(seed, frames)).with_rope_prior(prior);
    write_scenario_and_video(writer, dir, None)
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
