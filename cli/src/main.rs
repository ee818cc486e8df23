//! The `upetrack` command: track sequences, evaluate against ground truth,
//! write synthetic scenarios, and benchmark the per-frame cost.

mod args;
mod bench;
mod bench_files;
mod compare;
mod figure;
mod overlay;
mod pipeline;
mod progress;
mod random_bench;
mod recording;
mod several_bench;
mod synth;

use std::path::Path;
use std::process::ExitCode;

use clap::{CommandFactory, Parser};
use upetrack::{Algorithm, Params};
use upetrack_io::eval::{summarise_ropes, Summary};
use upetrack_io::{Sequence, SequenceError};

pub use args::RecordingArgs;
use args::{AlgorithmArg, Cli, Command, EvalArgs, ScoreArgs, TableOutputs, TrackArgs};

/// Why a command failed; it sets the exit code (`upetrack --help` lists them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Failure {
    /// Bad input: exit code 1.
    Input,
    /// A malformed command line: exit code 2 (clap's own code for its errors).
    Usage,
    /// A bug in upetrack: exit code 3.
    Internal,
}

impl Failure {
    fn exit_code(self) -> u8 {
        match self {
            Failure::Input => 1,
            Failure::Usage => 2,
            Failure::Internal => 3,
        }
    }
}

/// A command-line error with its message.
#[derive(Debug)]
pub struct CliError {
    /// What kind of failure it is.
    pub failure: Failure,
    /// What went wrong, for the user.
    pub message: String,
}

impl CliError {
    /// Bad input (a file, a sequence, a value in it).
    pub fn input(message: impl Into<String>) -> Self {
        Self {
            failure: Failure::Input,
            message: message.into(),
        }
    }

    /// Options that parse but do not go together.
    pub fn usage(message: impl Into<String>) -> Self {
        Self {
            failure: Failure::Usage,
            message: message.into(),
        }
    }

    /// Something that should not happen (a worker thread panicked).
    pub fn internal(message: impl Into<String>) -> Self {
        Self {
            failure: Failure::Internal,
            message: message.into(),
        }
    }
}

impl From<SequenceError> for CliError {
    fn from(e: SequenceError) -> Self {
        Self::input(e.to_string())
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
    let text =
        std::fs::read_to_string(path).map_err(|e| CliError::input(format!("{path}: {e}")))?;
    Ok(upetrack_io::params_file::parse_params(&text, path)?)
}

/// The algorithms of `--algorithm a,b,..` (the parameter file's when absent).
fn algorithms(chosen: &[AlgorithmArg], params: &Params) -> Vec<Algorithm> {
    if chosen.is_empty() {
        vec![params.algorithm]
    } else {
        chosen.iter().map(|a| a.0).collect()
    }
}

impl args::AlgorithmsArgs {
    /// The parameters in force and the algorithms to run with them.
    fn resolve(&self) -> Result<(Params, Vec<Algorithm>), CliError> {
        let params = load_params(self.params.params.as_deref())?;
        Ok((params, algorithms(&self.algorithm, &params)))
    }
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

/// The reader options of `rec`.
fn recording_options(topics: &args::TopicArgs) -> upetrack_recordings::RecordingOptions {
    upetrack_recordings::RecordingOptions {
        color_topic: topics.color_topic.clone(),
        depth_topic: topics.depth_topic.clone(),
        align: topics.align.map(Into::into),
    }
}

fn open_sequence(path: &str, rec: &RecordingArgs) -> Result<AnySequence, CliError> {
    let p = Path::new(path);
    // Only with --dlo: telling a recording by its bytes reads the file's head.
    if rec.dlo.is_some() && !(p.is_file() && upetrack_io::recorded::is_recording_file(p)) {
        return Err(CliError::usage(format!(
            "{path}: --dlo is for recordings (.bag, .db3, .mcap); a sequence folder has its own dlo.json"
        )));
    }
    Ok(upetrack_io::recorded::open_any(
        p,
        rec.dlo.as_deref(),
        &recording_options(&rec.topics),
    )?)
}

fn cmd_track(args: &TrackArgs) -> Result<(), CliError> {
    let params = load_params(args.params.params.as_deref())?;
    let params = match args.algorithm {
        Some(a) => with_algorithm(params, a.0),
        None => params,
    };
    let seq = open_sequence(&args.sequence, &args.recording)?;
    let bar = progress::bar(seq.len() as u64, "frames", params.algorithm.name());
    let result = pipeline::track(&seq, params, &bar)?;
    bar.finish_and_clear();
    upetrack_io::write::write_json(&args.out, &result)?;
    let lost = result.frames.iter().filter(|f| f.lost).count();
    eprintln!(
        "{}: {} frames tracked with {} ({} lost) -> {}",
        args.sequence,
        result.frames.len(),
        result.algorithm,
        lost,
        args.out.display()
    );
    report_checks(&result);
    report_initialisations(&result)
}

/// Says on how many frames a recovery test fired and what came of it
/// (`checks` in the result JSON has every frame's measures).
fn report_checks(result: &upetrack_io::result::TrackResult) {
    let mut verdicts: Vec<(&str, usize)> = Vec::new();
    for c in result.frames.iter().filter_map(|f| f.checks.as_ref()) {
        if c.tests.fired.is_empty() {
            continue;
        }
        match verdicts.iter_mut().find(|(v, _)| *v == c.verdict) {
            Some((_, n)) => *n += 1,
            None => verdicts.push((&c.verdict, 1)),
        }
    }
    let fired: usize = verdicts.iter().map(|(_, n)| n).sum();
    if fired > 0 {
        let said: Vec<String> = verdicts
            .iter()
            .map(|(v, n)| format!("{} {n}", v.replace('_', " ")))
            .collect();
        eprintln!(
            "a recovery test fired on {fired} frames: {} (`checks` in the result JSON says what each measured)",
            said.join(", ")
        );
    }
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
        return Err(CliError::input(format!(
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

fn cmd_eval(args: &EvalArgs) -> Result<(), CliError> {
    let (params, algorithms) = args.runs.resolve()?;
    let several = args.sequences.len() > 1 || algorithms.len() > 1;
    let runs = args.sequences.len() * algorithms.len();
    let mut rows = Vec::new();
    for (s, path) in args.sequences.iter().enumerate() {
        let seq = open_sequence(path, &args.recording)?;
        let name = sequence_name(path);
        for (k, &algorithm) in algorithms.iter().enumerate() {
            let label = format!(
                "{}/{runs} {name} {}",
                s * algorithms.len() + k + 1,
                algorithm.name()
            );
            let bar = progress::bar(seq.len() as u64, "frames", label);
            let (summaries, result) =
                evaluate_ropes(&seq, &name, with_algorithm(params, algorithm), &bar)?;
            bar.finish_and_clear();
            if let Some(csv) = &args.per_frame {
                let path = if several {
                    format!("{csv}.{name}.{}.csv", algorithm.name())
                } else {
                    csv.clone()
                };
                write_per_frame(Path::new(&path), &name, &result, &seq)?;
            }
            if summaries.iter().all(|s| s.evaluated_frames == 0) {
                eprintln!("{path}: no ground truth; errors are not available");
            }
            rows.extend(summaries);
        }
    }
    print_table(&rows, &args.outputs)
}

/// `upetrack score <sequence> <result.json>...`: the eval table of result
/// files written by any tracker in the contract's layout, against the
/// sequence's ground truth.
fn cmd_score(args: &ScoreArgs) -> Result<(), CliError> {
    let seq = open_sequence(&args.sequence, &args.recording)?;
    let name = sequence_name(&args.sequence);
    let mut rows = Vec::new();
    for r in &args.results {
        let result = upetrack_io::result::read_result(r)?;
        let in_order = result.frames.iter().enumerate().all(|(i, f)| f.frame == i);
        if result.frames.len() != seq.len() || !in_order {
            return Err(CliError::input(format!(
                "{}: frames must be 0..{} in order, one entry each, as the sequence has (found {})",
                r.display(),
                seq.len(),
                result.frames.len()
            )));
        }
        if result.rope_count() != seq.ropes.len() {
            return Err(CliError::input(format!(
                "{}: {} rope(s), but the sequence's dlo.json lists {}",
                r.display(),
                result.rope_count(),
                seq.ropes.len()
            )));
        }
        rows.extend(summarise_ropes(&name, &result, &seq));
    }
    print_table(&rows, &args.outputs)
}

/// A sequence's name in tables: its folder's or file's name.
fn sequence_name(path: &str) -> String {
    Path::new(path)
        .file_name()
        .map_or(path.to_string(), |n| n.to_string_lossy().into_owned())
}

/// Prints the table of `rows` (and the identity swaps of several ropes'
/// rows), and writes it where `--json` and `--markdown` say.
fn print_table(rows: &[Summary], outputs: &TableOutputs) -> Result<(), CliError> {
    let table = markdown_table(rows);
    println!("{table}");
    for r in rows.iter().filter(|r| r.sequence.ends_with("/all")) {
        println!(
            "{} {}: {} identity swap(s), {} frame(s) with a rope nearer another rope's ground truth than its own",
            r.sequence, r.algorithm, r.identity_swaps, r.swapped_frames
        );
    }
    if let Some(p) = &outputs.json {
        upetrack_io::write::write_json(p, &rows)?;
    }
    if let Some(p) = &outputs.markdown {
        upetrack_io::write::write_file(p, table.as_bytes())?;
    }
    Ok(())
}

/// Tracks `seq` with `params` (counting frames on `bar`) and summarises
/// the errors against its ground truth (of all its ropes together).
fn evaluate(
    seq: &AnySequence,
    name: &str,
    params: Params,
    bar: &indicatif::ProgressBar,
) -> Result<(Summary, upetrack_io::result::TrackResult), CliError> {
    let (mut rows, result) = evaluate_ropes(seq, name, params, bar)?;
    let summary = rows
        .pop()
        .ok_or_else(|| CliError::input(format!("{name}: no rope to evaluate")))?;
    Ok((summary, result))
}

/// [`evaluate`] with a row per rope before the row of all of them (one
/// row for one rope).
fn evaluate_ropes(
    seq: &AnySequence,
    name: &str,
    params: Params,
    bar: &indicatif::ProgressBar,
) -> Result<(Vec<Summary>, upetrack_io::result::TrackResult), CliError> {
    let result = pipeline::track(seq, params, bar)?;
    Ok((summarise_ropes(name, &result, seq), result))
}

/// `true` for a sequence of several ropes.
fn result_is_several(seq: &AnySequence) -> bool {
    seq.ropes.len() > 1
}

/// Writes one CSV row per frame: error, timings, visible nodes, lost.
fn write_per_frame(
    path: &Path,
    name: &str,
    result: &upetrack_io::result::TrackResult,
    seq: &AnySequence,
) -> Result<(), CliError> {
    let mut text =
        String::from("sequence,frame,error_mm,error_px,track_ms,total_ms,visible_nodes,lost\n");
    // Several ropes: each rope's rows, named `<sequence>/<rope>`.
    for (k, rope) in seq.ropes.iter().enumerate() {
        let Some(result) = result.rope(k) else {
            break;
        };
        let label = if result_is_several(seq) {
            format!("{name}/{}", rope.name)
        } else {
            name.to_string()
        };
        let errors = upetrack_io::eval::frame_errors(&result, &rope.groundtruth, &seq.camera);
        for f in &result.frames {
            let e = errors.iter().find(|e| e.frame == f.frame);
            text += &format!(
                "{label},{},{},{},{:.4},{:.4},{},{}\n",
                f.frame,
                e.map_or(String::new(), |e| format!("{:.3}", e.mm)),
                e.map_or(String::new(), |e| format!("{:.3}", e.px)),
                f.track_ms,
                f.total_ms,
                f.visible.iter().filter(|&&v| v).count(),
                f.lost
            );
        }
    }
    upetrack_io::write::write_file(path, text.as_bytes())?;
    Ok(())
}

fn run(cli: Cli) -> Result<(), CliError> {
    progress::set_quiet(cli.quiet);
    match cli.command {
        Command::Track(a) => cmd_track(&a),
        Command::Eval(a) => cmd_eval(&a),
        Command::Score(a) => cmd_score(&a),
        Command::Compare(a) => compare::cmd_compare(&a),
        Command::Synth(a) => synth::cmd_synth(&a),
        Command::Bench(a) => bench::cmd_bench(&a),
        Command::Overlay(a) => overlay::cmd_overlay(&a),
        Command::Info(a) => recording::cmd_info(&a),
        Command::Export(a) => recording::cmd_export(&a),
        Command::Scenarios => {
            print!("{}", args::scenario_list());
            Ok(())
        }
        Command::Algorithms => {
            print!("{}", args::algorithm_list());
            Ok(())
        }
        Command::Completions { shell } => {
            clap_complete::generate(
                shell,
                &mut Cli::command(),
                "upetrack",
                &mut std::io::stdout(),
            );
            Ok(())
        }
    }
}

fn main() -> ExitCode {
    // clap prints its own errors (with a suggestion) and exits with 2 on a
    // usage error, 0 on --help and --version.
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", e.message);
            if e.failure == Failure::Usage {
                eprintln!("\nFor more information, try '--help'.");
            }
            ExitCode::from(e.failure.exit_code())
        }
    }
}
