//! The `upetrack` command: track sequences, evaluate against ground truth,
//! write synthetic scenarios, and benchmark the per-frame cost.

mod bench;
mod bench_files;
mod compare;
mod figure;
mod overlay;
mod random_bench;
mod recording;
mod synth;

use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

use upetrack::{Algorithm, Params};
use upetrack_io::eval::{summarise, Summary};
use upetrack_io::run::track_sequence;
use upetrack_io::{Sequence, SequenceError};

const USAGE: &str = "\
upetrack: track a rope in RGB-D sequences (UPETrack)

USAGE:
  upetrack track <sequence> --out <result.json> [--algorithm A] [--params <params.json>]
  upetrack eval <sequence>... [--algorithm A,B,..] [--params <params.json>] [--json <out.json>] [--markdown <out.md>] [--per-frame <out.csv>]
  upetrack score <sequence> <result.json>... [--json <out.json>] [--markdown <out.md>]
  upetrack compare [--data <dir>] [--frames N] [--json <out.json>] [--markdown <out.md>] [--update <page.md>] [--figures <dir>]
  upetrack compare --random tune|report [--count N] [--frames N] [--data <dir>] [--json ..] [--markdown ..] [--update <page.md>]
  upetrack synth <scenario> <dir> [--frames N] [--seed S] [--hd] [--variant V] [--rope-prior]
                 [--depth-noise X] [--jpeg-quality Q] [--y4m <video.y4m>]
  upetrack synth random <dir> [--seed S] [--count N] [--frames N] [--rope-prior]
  upetrack bench [<sequence>...] [--frames N] [--repeat R] [--algorithm A,B,..]
  upetrack overlay <sequence> <result.json> <frame> <out.png> [--depth]
  upetrack info <recording> [--json] [--color-topic T] [--depth-topic T]
  upetrack export <recording> <dir> [--frames A..B] [--dlo <dlo.json>] [--color-topic T] [--depth-topic T]
  upetrack scenarios

A sequence is a folder in the layout of docs/sequence-format.md, a .zip of one, or a
camera recording (ROS1 .bag or rosbag2 .db3 from the RealSense Viewer, rs-record or realsense-ros);
a recording takes its configuration from --dlo <dlo.json> (colour range, occluders),
and --color-topic / --depth-topic when the streams are not found by name;
--align x86-sse|portable picks librealsense's aligner (default: the recording's era).
Algorithms: upetrack (default), cpd, trackdlo, cdcpd2; --algorithm overrides the parameter file's.
Scenarios (`upetrack scenarios` describes them): static-s, dynamic-pull, tip-drag, sweep-10..sweep-70,
lifted-swing, fast-pull, gripper-swing, box-over-end, box-over-middle, cable-desk, crossing-loop, in-pieces,
pulled-through;
synth --rope-prior writes the rope's length and diameter into dlo.json.
synth random draws a whole scene from the seed (docs/synthetic.md lists the distributions) and writes
what it drew in scene.json; --count N writes seeds S..S+N-1 into folders random-<seed>-<frames>f.
compare --random runs every algorithm on the drawn scenes of a seed range: tune (1000..1099) to choose
rules on, report (2000..2099) to judge them; --count N takes the range's first N seeds.";

/// A command-line error with its message.
struct CliError(String);

impl From<SequenceError> for CliError {
    fn from(e: SequenceError) -> Self {
        Self(e.to_string())
    }
}

/// Parsed arguments: positionals and `--key value` options.
struct Args {
    positional: Vec<String>,
    options: Vec<(String, Option<String>)>,
}

impl Args {
    fn parse(raw: &[String], flags: &[&str], valued: &[&str]) -> Result<Self, CliError> {
        let mut positional = Vec::new();
        let mut options = Vec::new();
        let mut it = raw.iter();
        while let Some(a) = it.next() {
            if let Some(key) = a.strip_prefix("--") {
                if flags.contains(&key) {
                    options.push((key.to_string(), None));
                } else if valued.contains(&key) {
                    let v = it
                        .next()
                        .ok_or_else(|| CliError(format!("--{key} needs a value")))?;
                    options.push((key.to_string(), Some(v.clone())));
                } else {
                    return Err(CliError(format!("unknown option --{key}\n\n{USAGE}")));
                }
            } else {
                positional.push(a.clone());
            }
        }
        Ok(Self {
            positional,
            options,
        })
    }

    fn value(&self, key: &str) -> Option<&str> {
        self.options
            .iter()
            .rev()
            .find(|(k, _)| k == key)
            .and_then(|(_, v)| v.as_deref())
    }

    fn flag(&self, key: &str) -> bool {
        self.options.iter().any(|(k, _)| k == key)
    }

    fn number<T: std::str::FromStr>(&self, key: &str, default: T) -> Result<T, CliError> {
        match self.value(key) {
            None => Ok(default),
            Some(v) => v
                .parse()
                .map_err(|_| CliError(format!("--{key}: `{v}` is not a valid number"))),
        }
    }
}

/// Reads a parameter file (any subset of the fields; the rest take their defaults).
fn load_params(path: Option<&str>) -> Result<Params, CliError> {
    let Some(path) = path else {
        return Ok(Params::default());
    };
    // A preset name (`paper`, `default`) unless a file of that name exists.
    if !Path::new(path).exists() {
        if let Some(p) = Params::preset(path) {
            return Ok(p);
        }
    }
    let text = std::fs::read_to_string(path).map_err(|e| CliError(format!("{path}: {e}")))?;
    Ok(upetrack_io::params_file::parse_params(&text, path)?)
}

/// The algorithms of `--algorithm a,b,..` (the parameter file's when absent).
fn algorithms(args: &Args, params: &Params) -> Result<Vec<Algorithm>, CliError> {
    let Some(list) = args.value("algorithm") else {
        return Ok(vec![params.algorithm]);
    };
    list.split(',')
        .map(|name| {
            Algorithm::from_name(name.trim()).ok_or_else(|| {
                CliError(format!(
                    "--algorithm: unknown algorithm `{name}` (upetrack, cpd or trackdlo)"
                ))
            })
        })
        .collect()
}

/// `params` with `algorithm` as the tracking step.
fn with_algorithm(params: Params, algorithm: Algorithm) -> Params {
    Params {
        algorithm,
        ..params
    }
}

/// A sequence from a folder, a .zip or a recording.
pub type AnySequence = Sequence<Box<dyn upetrack_io::Source>>;

/// Options of every command that reads sequences, for recordings.
const RECORDING_OPTIONS: [&str; 4] = ["dlo", "color-topic", "depth-topic", "align"];

/// `valued` with the recording options added.
fn with_recording_options<'a>(valued: &[&'a str]) -> Vec<&'a str> {
    valued.iter().copied().chain(RECORDING_OPTIONS).collect()
}

/// How to read a recording: its configuration file and topics.
#[derive(Default)]
struct RecordingArgs {
    dlo: Option<String>,
    options: upetrack_recordings::RecordingOptions,
}

impl RecordingArgs {
    fn from(args: &Args) -> Result<Self, CliError> {
        use upetrack_recordings::align::AlignArithmetic;
        let align = match args.value("align") {
            None => None,
            Some("x86-sse") => Some(AlignArithmetic::X86Sse),
            Some("portable") => Some(AlignArithmetic::Portable),
            Some(other) => {
                return Err(CliError(format!(
                    "--align: `{other}` is not x86-sse or portable"
                )))
            }
        };
        Ok(Self {
            dlo: args.value("dlo").map(str::to_string),
            options: upetrack_recordings::RecordingOptions {
                color_topic: args.value("color-topic").map(str::to_string),
                depth_topic: args.value("depth-topic").map(str::to_string),
                align,
            },
        })
    }
}

fn open_sequence(path: &str, rec: &RecordingArgs) -> Result<AnySequence, CliError> {
    let p = Path::new(path);
    if p.is_file() && upetrack_io::recorded::is_recording_file(p) {
        return Ok(upetrack_io::recorded::open_recording(
            p,
            rec.dlo.as_deref().map(Path::new),
            &rec.options,
        )?);
    }
    if rec.dlo.is_some() {
        return Err(CliError(format!(
            "{path}: --dlo is for recordings (.bag); a sequence folder has its own dlo.json"
        )));
    }
    Ok(Sequence::open(upetrack_io::open::open_path(p)?)?)
}

fn now_ms_since(start: Instant) -> impl FnMut() -> f64 {
    move || start.elapsed().as_secs_f64() * 1000.0
}

fn cmd_track(raw: &[String]) -> Result<(), CliError> {
    let args = Args::parse(
        raw,
        &[],
        &with_recording_options(&["out", "params", "algorithm"]),
    )?;
    let [seq_path] = args.positional.as_slice() else {
        return Err(CliError(format!("track takes one sequence\n\n{USAGE}")));
    };
    let out = args
        .value("out")
        .ok_or_else(|| CliError("track needs --out <result.json>".into()))?;
    let params = load_params(args.value("params"))?;
    let params = match algorithms(&args, &params)?.as_slice() {
        [one] => with_algorithm(params, *one),
        _ => return Err(CliError("track runs one algorithm".into())),
    };
    let seq = open_sequence(seq_path, &RecordingArgs::from(&args)?)?;
    let result = track_sequence(&seq, params, &mut now_ms_since(Instant::now()))?;
    upetrack_io::write::write_json(Path::new(out), &result)?;
    let lost = result.frames.iter().filter(|f| f.lost).count();
    eprintln!(
        "{}: {} frames tracked with {} ({} lost) -> {}",
        seq_path,
        result.frames.len(),
        result.algorithm,
        lost,
        out
    );
    report_initialisations(&result)
}

/// Most initialisations `track` describes one by one.
const MAX_REPORTED_INITIALISATIONS: usize = 3;

/// Says where the rope was found and why (the first few times), and fails
/// when it was found in no frame: a scene where nothing is rope-shaped is
/// refused rather than tracked.
fn report_initialisations(result: &upetrack_io::result::TrackResult) -> Result<(), CliError> {
    let found: Vec<_> = result
        .frames
        .iter()
        .filter_map(|f| f.init.as_ref().map(|r| (f.frame, r)))
        .collect();
    for (frame, report) in found.iter().take(MAX_REPORTED_INITIALISATIONS) {
        eprintln!("frame {frame}: rope found: {report}");
    }
    if found.len() > MAX_REPORTED_INITIALISATIONS {
        eprintln!(
            "... and found again on {} more frames (`init` in the result JSON says how)",
            found.len() - MAX_REPORTED_INITIALISATIONS
        );
    }
    if found.is_empty() {
        let why = result
            .frames
            .iter()
            .find_map(|f| f.reason.clone())
            .unwrap_or_else(|| "the sequence has no frames".into());
        return Err(CliError(format!(
            "no rope found in any frame (the result JSON lists every frame as lost): {why}\n\
             Check the colour range (dlo.json's segmentation), or describe the rope \
             (dlo.json's \"rope\": {{\"length_m\": .., \"diameter_m\": ..}})"
        )));
    }
    Ok(())
}

fn fmt(x: f64, digits: usize) -> String {
    if x.is_finite() {
        format!("{x:.digits$}")
    } else {
        "-".into()
    }
}

/// The evaluation table in Markdown.
fn markdown_table(rows: &[Summary]) -> String {
    let mut s = String::from(
        "| sequence | algorithm | frames | lost | mean mm | median mm | IQR mm | mean px | median px | IQR px | occluded mean mm | occluded mean px | max mm | max px | frames > 20 mm | hidden length error max | median track ms | median total ms |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {} | {} | {} | {}-{} | {} | {} | {}-{} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.sequence,
            r.algorithm,
            r.frames,
            r.lost_frames,
            fmt(r.mm.mean, 2),
            fmt(r.mm.median, 2),
            fmt(r.mm.q1, 2),
            fmt(r.mm.q3, 2),
            fmt(r.px.mean, 2),
            fmt(r.px.median, 2),
            fmt(r.px.q1, 2),
            fmt(r.px.q3, 2),
            fmt(r.occluded_mean_mm, 2),
            fmt(r.occluded_mean_px, 2),
            fmt(r.max_mm, 1),
            fmt(r.max_px, 1),
            r.frames_above_20mm,
            if r.hidden_length_error_max.is_finite() {
                format!("{:.0} %", 100.0 * r.hidden_length_error_max)
            } else {
                "-".into()
            },
            fmt(r.median_track_ms, 3),
            fmt(r.median_total_ms, 3),
        );
    }
    s
}

fn cmd_eval(raw: &[String]) -> Result<(), CliError> {
    let args = Args::parse(
        raw,
        &[],
        &with_recording_options(&["params", "json", "markdown", "per-frame", "algorithm"]),
    )?;
    if args.positional.is_empty() {
        return Err(CliError(format!(
            "eval takes at least one sequence\n\n{USAGE}"
        )));
    }
    let params = load_params(args.value("params"))?;
    let algorithms = algorithms(&args, &params)?;
    let several = args.positional.len() > 1 || algorithms.len() > 1;
    let mut rows = Vec::new();
    for path in &args.positional {
        let seq = open_sequence(path, &RecordingArgs::from(&args)?)?;
        let name = sequence_name(path);
        for &algorithm in &algorithms {
            let (summary, result) = evaluate(&seq, &name, with_algorithm(params, algorithm))?;
            if let Some(csv) = args.value("per-frame") {
                let path = if several {
                    format!("{csv}.{name}.{}.csv", algorithm.name())
                } else {
                    csv.to_string()
                };
                write_per_frame(Path::new(&path), &name, &result, &seq)?;
            }
            if summary.evaluated_frames == 0 {
                eprintln!("{path}: no ground truth; errors are not available");
            }
            rows.push(summary);
        }
    }
    print_table(&rows, &args)
}

/// `upetrack score <sequence> <result.json>...`: the eval table of result
/// files written by any tracker in the contract's layout, against the
/// sequence's ground truth.
fn cmd_score(raw: &[String]) -> Result<(), CliError> {
    let args = Args::parse(raw, &[], &with_recording_options(&["json", "markdown"]))?;
    let (path, results) = match args.positional.as_slice() {
        [path, results @ ..] if !results.is_empty() => (path, results),
        _ => {
            return Err(CliError(format!(
                "score takes a sequence and result files\n\n{USAGE}"
            )))
        }
    };
    let seq = open_sequence(path, &RecordingArgs::from(&args)?)?;
    let name = sequence_name(path);
    let mut rows = Vec::new();
    for r in results {
        let result = upetrack_io::result::read_result(Path::new(r))?;
        let in_order = result.frames.iter().enumerate().all(|(i, f)| f.frame == i);
        if result.frames.len() != seq.len() || !in_order {
            return Err(CliError(format!(
                "{r}: frames must be 0..{} in order, one entry each, as the sequence has (found {})",
                seq.len(),
                result.frames.len()
            )));
        }
        rows.push(summarise(
            &name,
            &result,
            &seq.groundtruth,
            &seq.camera,
            seq.first_occluded_frame(),
        ));
    }
    print_table(&rows, &args)
}

/// A sequence's name in tables: its folder's or file's name.
fn sequence_name(path: &str) -> String {
    Path::new(path)
        .file_name()
        .map_or(path.to_string(), |n| n.to_string_lossy().into_owned())
}

/// Prints the table of `rows`, and writes it where `--json` and `--markdown` say.
fn print_table(rows: &[Summary], args: &Args) -> Result<(), CliError> {
    let table = markdown_table(rows);
    println!("{table}");
    if let Some(p) = args.value("json") {
        upetrack_io::write::write_json(Path::new(p), &rows)?;
    }
    if let Some(p) = args.value("markdown") {
        upetrack_io::write::write_file(Path::new(p), table.as_bytes())?;
    }
    Ok(())
}

/// Tracks `seq` with `params` and summarises the errors against its ground truth.
fn evaluate(
    seq: &AnySequence,
    name: &str,
    params: Params,
) -> Result<(Summary, upetrack_io::result::TrackResult), CliError> {
    let result = track_sequence(seq, params, &mut now_ms_since(Instant::now()))?;
    let summary = summarise(
        name,
        &result,
        &seq.groundtruth,
        &seq.camera,
        seq.first_occluded_frame(),
    );
    Ok((summary, result))
}

/// Writes one CSV row per frame: error, timings, visible nodes, lost.
fn write_per_frame(
    path: &Path,
    name: &str,
    result: &upetrack_io::result::TrackResult,
    seq: &AnySequence,
) -> Result<(), CliError> {
    let errors = upetrack_io::eval::frame_errors(result, &seq.groundtruth, &seq.camera);
    let mut text =
        String::from("sequence,frame,error_mm,error_px,track_ms,total_ms,visible_nodes,lost\n");
    for f in &result.frames {
        let e = errors.iter().find(|e| e.frame == f.frame);
        text += &format!(
            "{name},{},{},{},{:.4},{:.4},{},{}\n",
            f.frame,
            e.map_or(String::new(), |e| format!("{:.3}", e.mm)),
            e.map_or(String::new(), |e| format!("{:.3}", e.px)),
            f.track_ms,
            f.total_ms,
            f.visible.iter().filter(|&&v| v).count(),
            f.lost
        );
    }
    upetrack_io::write::write_file(path, text.as_bytes())?;
    Ok(())
}

fn run(raw: &[String]) -> Result<(), CliError> {
    let Some((cmd, rest)) = raw.split_first() else {
        println!("{USAGE}");
        return Ok(());
    };
    match cmd.as_str() {
        "track" => cmd_track(rest),
        "eval" => cmd_eval(rest),
        "score" => cmd_score(rest),
        "compare" => compare::cmd_compare(rest),
        "synth" => synth::cmd_synth(rest),
        "bench" => bench::cmd_bench(rest),
        "overlay" => overlay::cmd_overlay(rest),
        "info" => recording::cmd_info(rest),
        "export" => recording::cmd_export(rest),
        "scenarios" => {
            synth::list_scenarios();
            Ok(())
        }
        "-h" | "--help" | "help" => {
            println!("{USAGE}");
            Ok(())
        }
        other => Err(CliError(format!("unknown command `{other}`\n\n{USAGE}"))),
    }
}

fn main() -> ExitCode {
    let raw: Vec<String> = std::env::args().skip(1).collect();
    match run(&raw) {
        Ok(()) => ExitCode::SUCCESS,
        Err(CliError(msg)) => {
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}
