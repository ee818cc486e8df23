//! The command line as data: every command's options, their help and
//! examples (clap derives the parser, the help, the errors and completions).

use std::path::PathBuf;

use clap::builder::PossibleValue;
use clap::{Args, Parser, Subcommand, ValueEnum};
use upetrack::Algorithm;
use upetrack_recordings::align::AlignArithmetic;
use upetrack_synth::random::SeedRange;
use upetrack_synth::{ScenarioKind, SeveralKind, Variant};

/// What the exit codes mean (the README repeats it).
const EXIT_CODES: &str = "\
Exit codes:
  0  done
  1  bad input: a file that cannot be read, a sequence that breaks the
     contract (docs/sequence-format.md), no rope found in any frame
  2  usage: an unknown command or option, a missing or malformed value
  3  internal: a bug in upetrack (please report it with the command line)";

/// upetrack: track a rope, cable or thread in RGB-D sequences (UPETrack).
///
/// A sequence is a folder in the layout of docs/sequence-format.md, a .zip
/// of one, or a camera recording (ROS1 .bag, rosbag2 .db3 or .mcap from the
/// RealSense Viewer, rs-record or realsense-ros). `upetrack <command> --help`
/// explains each command, with an example.
#[derive(Debug, Parser)]
#[command(
    name = "upetrack",
    version,
    propagate_version = true,
    arg_required_else_help = true,
    after_help = EXIT_CODES
)]
pub struct Cli {
    /// Show no progress bars (they are drawn only on a terminal anyway).
    #[arg(short, long, global = true)]
    pub quiet: bool,
    /// The command.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Track one sequence and write the result JSON.
    #[command(after_help = "\
Examples:
  upetrack track samples/static-s --out result.json
  upetrack track recording.bag --dlo dlo.json --algorithm trackdlo --out result.json")]
    Track(TrackArgs),
    /// Track sequences with ground truth and print the error table.
    #[command(after_help = "\
Examples:
  upetrack eval samples/static-s samples/dynamic-pull --algorithm upetrack,cpd
  upetrack eval samples/static-s --per-frame errors.csv --markdown table.md")]
    Eval(EvalArgs),
    /// Score result files written by any tracker against a sequence's ground truth.
    #[command(after_help = "\
Example:
  upetrack score samples/static-s result.json other-tracker.json --markdown scores.md")]
    Score(ScoreArgs),
    /// Run every algorithm on the project's scenarios (or on drawn scenes) and
    /// print the comparison.
    #[command(after_help = "\
Examples:
  upetrack compare --frames 30 --only static-s,box-over-end
  upetrack compare --random report --count 20 --markdown report.md")]
    Compare(CompareArgs),
    /// Write a simulated scenario (or drawn scenes) as sequence folders.
    #[command(after_help = SYNTH_EXAMPLES, after_long_help = synth_long_help())]
    Synth(SynthArgs),
    /// Time every stage of a frame (read+decode, segmentation, cloud, step).
    #[command(after_help = "\
Examples:
  upetrack bench
  upetrack bench samples/static-s --frames 60 --algorithm upetrack,trackdlo")]
    Bench(BenchArgs),
    /// Draw a result's nodes over one frame of a sequence, as a PNG.
    #[command(after_help = "\
Example:
  upetrack overlay samples/static-s result.json 40 frame-40.png")]
    Overlay(OverlayArgs),
    /// Describe what a camera recording holds (streams, intrinsics, pairing).
    #[command(after_help = "\
Example:
  upetrack info recording.bag --json")]
    Info(InfoArgs),
    /// Write a camera recording as a sequence folder.
    #[command(after_help = "\
Example:
  upetrack export recording.bag /tmp/sequence --frames 0..300 --dlo dlo.json")]
    Export(ExportArgs),
    /// List the simulator's scenarios and variants.
    Scenarios,
    /// List the tracking algorithms.
    Algorithms,
    /// Print a shell completion script.
    #[command(after_help = "\
Example:
  upetrack completions bash > ~/.local/share/bash-completion/completions/upetrack")]
    Completions {
        /// The shell.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
}

/// A tracking algorithm on the command line (the core's list).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AlgorithmArg(pub Algorithm);

/// [`Algorithm::ALL`] as command-line values.
const ALGORITHM_ARGS: [AlgorithmArg; Algorithm::ALL.len()] = {
    let mut out = [AlgorithmArg(Algorithm::Upetrack); Algorithm::ALL.len()];
    let mut i = 0;
    while i < out.len() {
        out[i] = AlgorithmArg(Algorithm::ALL[i]);
        i += 1;
    }
    out
};

impl ValueEnum for AlgorithmArg {
    fn value_variants<'a>() -> &'a [Self] {
        &ALGORITHM_ARGS
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.0.name()).help(self.0.description()))
    }
}

/// How librealsense aligned depth to colour when the recording was made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum AlignArg {
    /// The SSE aligner of x86 builds up to librealsense 2.55 (ROS1 .bag era).
    X86Sse,
    /// The portable aligner (librealsense 2.59 wheels, ARM builds).
    Portable,
}

impl From<AlignArg> for AlignArithmetic {
    fn from(a: AlignArg) -> Self {
        match a {
            AlignArg::X86Sse => AlignArithmetic::X86Sse,
            AlignArg::Portable => AlignArithmetic::Portable,
        }
    }
}

/// Which streams of a recording to read, and how to align them.
#[derive(Debug, Clone, Default, Args)]
pub struct TopicArgs {
    /// The colour topic, when it is not found by name.
    #[arg(long, value_name = "TOPIC")]
    pub color_topic: Option<String>,
    /// The depth topic, when it is not found by name.
    #[arg(long, value_name = "TOPIC")]
    pub depth_topic: Option<String>,
    /// librealsense's aligner to reproduce [default: the recording's era].
    #[arg(long, value_enum)]
    pub align: Option<AlignArg>,
}

/// How to read a camera recording: its configuration and streams.
#[derive(Debug, Clone, Default, Args)]
pub struct RecordingArgs {
    /// A recording's configuration (colour range, occluders, rope); a
    /// sequence folder has its own dlo.json.
    #[arg(long, value_name = "dlo.json")]
    pub dlo: Option<PathBuf>,
    /// Streams and alignment.
    #[command(flatten)]
    pub topics: TopicArgs,
}

/// The parameters to track with.
#[derive(Debug, Clone, Default, Args)]
pub struct ParamsArg {
    /// A parameter file (any subset of the fields; the rest take their
    /// defaults) or a preset name: default, paper.
    #[arg(long, value_name = "params.json|PRESET")]
    pub params: Option<String>,
}

/// The parameters, and the algorithms to run with them.
#[derive(Debug, Clone, Default, Args)]
pub struct AlgorithmsArgs {
    /// Algorithms, comma-separated [default: the parameter file's, else upetrack].
    #[arg(short, long, value_enum, value_delimiter = ',', value_name = "A,B,..")]
    pub algorithm: Vec<AlgorithmArg>,
    #[allow(missing_docs)]
    #[command(flatten)]
    pub params: ParamsArg,
}

/// Where a table is written besides standard output.
#[derive(Debug, Clone, Default, Args)]
pub struct TableOutputs {
    /// Also write the rows as JSON.
    #[arg(long, value_name = "out.json")]
    pub json: Option<PathBuf>,
    /// Also write the table as Markdown.
    #[arg(long, value_name = "out.md")]
    pub markdown: Option<PathBuf>,
}

/// `upetrack track`.
#[derive(Debug, Args)]
pub struct TrackArgs {
    /// A sequence folder, a .zip of one, or a recording (.bag, .db3, .mcap).
    pub sequence: String,
    /// Where to write the result JSON.
    #[arg(short, long, value_name = "result.json")]
    pub out: PathBuf,
    /// The tracking algorithm [default: the parameter file's, else upetrack].
    #[arg(short, long, value_enum)]
    pub algorithm: Option<AlgorithmArg>,
    #[allow(missing_docs)]
    #[command(flatten)]
    pub params: ParamsArg,
    #[allow(missing_docs)]
    #[command(flatten)]
    pub recording: RecordingArgs,
}

/// `upetrack eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// Sequences (folders, .zip files or recordings).
    #[arg(required = true)]
    pub sequences: Vec<String>,
    #[allow(missing_docs)]
    #[command(flatten)]
    pub runs: AlgorithmsArgs,
    /// Also write one CSV row per frame (error, timings, visible nodes);
    /// with several runs, one file each, suffixed .SEQUENCE.ALGORITHM.csv.
    #[arg(long, value_name = "out.csv")]
    pub per_frame: Option<String>,
    #[allow(missing_docs)]
    #[command(flatten)]
    pub outputs: TableOutputs,
    #[allow(missing_docs)]
    #[command(flatten)]
    pub recording: RecordingArgs,
}

/// `upetrack score`.
#[derive(Debug, Args)]
pub struct ScoreArgs {
    /// The sequence with ground truth.
    pub sequence: String,
    /// Result files in the contract's layout (frames 0..N in order).
    #[arg(required = true, value_name = "RESULT")]
    pub results: Vec<PathBuf>,
    #[allow(missing_docs)]
    #[command(flatten)]
    pub outputs: TableOutputs,
    #[allow(missing_docs)]
    #[command(flatten)]
    pub recording: RecordingArgs,
}

/// Fewest and most frames `compare --frames` takes.
pub const COMPARE_FRAMES: std::ops::RangeInclusive<i64> = 10..=1000;

/// `upetrack compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// Where the generated scenarios are cached.
    #[arg(long, value_name = "DIR", default_value = "target/compare-data")]
    pub data: PathBuf,
    /// Frames of every scenario [default: 150 for static-s and dynamic-pull,
    /// 90 for the others; 48 for drawn scenes at 30 fps].
    #[arg(long, value_parser = clap::value_parser!(u32).range(COMPARE_FRAMES))]
    pub frames: Option<u32>,
    /// Algorithms, comma-separated [default: all].
    #[arg(short, long, value_enum, value_delimiter = ',', value_name = "A,B,..")]
    pub algorithm: Vec<AlgorithmArg>,
    /// Only the scenarios of these names (quick studies).
    #[arg(long, value_delimiter = ',', value_name = "NAME,..")]
    pub only: Vec<String>,
    /// Write the frame-error figures of static-s and dynamic-pull (SVG) here.
    #[arg(long, value_name = "DIR")]
    pub figures: Option<PathBuf>,
    /// Run on the drawn scenes of a seed range instead: tune to choose rules
    /// on, report to judge them.
    #[arg(long, value_name = "RANGE", value_parser = seed_ranges())]
    pub random: Option<String>,
    /// With --random: the range's first N seeds.
    #[arg(long, requires = "random")]
    pub count: Option<u64>,
    /// With --random: film the drawn scenes at this many frames per second
    /// (the same scenes, their events at the same times in seconds; the
    /// frames grow with the rate unless --frames is given) [default: 30].
    #[arg(long, requires = "random", value_parser = parse_fps, value_name = "FPS")]
    pub fps: Option<f64>,
    /// Run on the scenes of several ropes instead: each rope beside the
    /// others against the same rope alone, and the identity swaps; with
    /// --random, on drawn scenes of several ropes of that seed range.
    #[arg(long)]
    pub several: bool,
    /// Replace the text between the comparison markers of this page.
    #[arg(long, value_name = "page.md")]
    pub update: Option<PathBuf>,
    #[allow(missing_docs)]
    #[command(flatten)]
    pub params: ParamsArg,
    #[allow(missing_docs)]
    #[command(flatten)]
    pub outputs: TableOutputs,
}

/// The seed ranges' names and what they hold.
fn seed_ranges() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(SeedRange::ALL.map(|r| {
        PossibleValue::new(r.name).help(format!("seeds {}..{}", r.first, r.first + r.count - 1))
    }))
}

/// `upetrack synth`.
#[derive(Debug, Args)]
pub struct SynthArgs {
    /// A scenario (`upetrack scenarios` describes them), or `random` for
    /// scenes drawn from the seed.
    #[arg(value_parser = parse_scenario, value_name = "SCENARIO")]
    pub scenario: SynthScenario,
    /// The folder to write (with --count, the folder of the drawn scenes' folders).
    pub dir: PathBuf,
    /// Frames [default: 150, or 48 for random at 30 fps].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=upetrack_synth::MAX_FRAMES as i64))]
    pub frames: Option<u32>,
    /// The seed of the noise (and of the drawn scene).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// With random: write seeds SEED..SEED+N-1 into folders random-SEED-FRAMESf.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=MAX_RANDOM_COUNT))]
    pub count: Option<u64>,
    /// Render at 1280x720 instead of 640x480.
    #[arg(long)]
    pub hd: bool,
    /// The look of the rope and scene [default: the scenario's].
    #[arg(long, value_parser = parse_variant, value_name = "VARIANT")]
    pub variant: Option<Variant>,
    /// With random: film the drawn scene at this many frames per second
    /// (the same scene, its events at the same times in seconds; the frames
    /// grow with the rate unless --frames is given) [default: 30].
    #[arg(long, value_parser = parse_fps, value_name = "FPS")]
    pub fps: Option<f64>,
    /// Write the rope's length and diameter into dlo.json.
    #[arg(long)]
    pub rope_prior: bool,
    /// Multiply the depth noise of the camera model by X [default: 1].
    #[arg(long, value_name = "X", value_parser = parse_depth_noise, allow_negative_numbers = true)]
    pub depth_noise: Option<f64>,
    /// JPEG quality of the colour frames.
    #[arg(long, value_name = "Q", default_value_t = upetrack_io::write::JPEG_QUALITY,
          value_parser = clap::value_parser!(u8).range(1..=100))]
    pub jpeg_quality: u8,
    /// Also write the colour frames as a .y4m video (a fake camera's input).
    #[arg(long, value_name = "video.y4m")]
    pub y4m: Option<PathBuf>,
    /// With a scene of several ropes: leave rope K (from 0) out, simulated
    /// and drawn without it (the single-rope figure to compare with).
    #[arg(long, value_name = "K", conflicts_with = "only")]
    pub without: Option<usize>,
    /// With a scene of several ropes: rope K (from 0) alone, simulated and
    /// drawn without the others.
    #[arg(long, value_name = "K")]
    pub only: Option<usize>,
}

/// `synth`'s examples.
const SYNTH_EXAMPLES: &str = "\
Examples:
  upetrack synth static-s /tmp/static-s --frames 60 --hd
  upetrack synth random /tmp/drawn --seed 1000 --count 10";

/// `synth --help`: the examples, then every scenario and variant.
fn synth_long_help() -> String {
    format!("{SYNTH_EXAMPLES}\n\n{}", scenario_list())
}

/// Most scenes one `synth random --count` writes.
pub const MAX_RANDOM_COUNT: u64 = 10_000;

/// Largest `--depth-noise` multiplier.
pub const MAX_DEPTH_NOISE: f64 = 10.0;

/// The name of the drawn scenes of several ropes.
pub const SEVERAL_RANDOM: &str = "several-random";

/// What `synth` writes.
#[derive(Debug, Clone, Copy)]
pub enum SynthScenario {
    /// A described scenario.
    Described(ScenarioKind),
    /// Scenes drawn from the seed.
    Random,
    /// A scene of several ropes.
    Several(SeveralKind),
    /// A scene of several ropes drawn from the seed.
    SeveralRandom,
}

/// A frame rate within [`upetrack_synth::FPS_RANGE`].
fn parse_fps(text: &str) -> Result<f64, String> {
    let (lo, hi) = upetrack_synth::FPS_RANGE;
    match text.parse::<f64>() {
        Ok(fps) if (lo..=hi).contains(&fps) => Ok(fps),
        _ => Err(format!(
            "a frame rate from {lo} to {hi} frames per second (the D435i's range)"
        )),
    }
}

fn parse_scenario(name: &str) -> Result<SynthScenario, String> {
    if name == "random" {
        return Ok(SynthScenario::Random);
    }
    if let Some(kind) = SeveralKind::parse(name) {
        return Ok(SynthScenario::Several(kind));
    }
    if name == SEVERAL_RANDOM {
        return Ok(SynthScenario::SeveralRandom);
    }
    ScenarioKind::parse(name)
        .map(SynthScenario::Described)
        .ok_or_else(|| format!("unknown scenario; {}", scenario_names()))
}

fn parse_variant(name: &str) -> Result<Variant, String> {
    Variant::parse(name).ok_or_else(|| {
        let names: Vec<&str> = Variant::ALL.iter().map(|v| v.name).collect();
        format!("unknown variant; one of {}", names.join(", "))
    })
}

fn parse_depth_noise(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(x) if (0.0..=MAX_DEPTH_NOISE).contains(&x) => Ok(x),
        _ => Err(format!("a number in 0..={MAX_DEPTH_NOISE}")),
    }
}

/// The name of a scenario on the command line (sweeps by their pattern).
pub fn scenario_name(kind: &ScenarioKind) -> String {
    match kind {
        ScenarioKind::OcclusionSweep { .. } => {
            format!("sweep-<K> (K in 10..={})", ScenarioKind::MAX_SWEEP_PERCENT)
        }
        _ => kind.name(),
    }
}

/// "one of a, b, ..": the scenarios the simulator knows.
fn scenario_names() -> String {
    let mut names: Vec<String> = ScenarioKind::EXAMPLES.iter().map(scenario_name).collect();
    names.extend(SeveralKind::ALL.iter().map(|k| k.name().to_string()));
    names.push(SEVERAL_RANDOM.to_string());
    format!("one of random, {}", names.join(", "))
}

/// Every scenario and variant with its description (from the simulator).
pub fn scenario_list() -> String {
    let mut s = String::from("Scenarios:\n");
    for k in ScenarioKind::EXAMPLES {
        s += &list_entry(&scenario_name(&k), k.description());
    }
    s += &list_entry(
        "random",
        "a whole scene drawn from the seed (docs/synthetic.md)",
    );
    s += "\nScenes of several ropes (dlo.json lists them; --without K leaves rope K out, --only K keeps it alone):\n";
    for k in SeveralKind::ALL {
        s += &list_entry(k.name(), k.description());
    }
    s += &list_entry(
        SEVERAL_RANDOM,
        "two or three ropes drawn from the seed: of one colour or three, crossing or not, one or two dragged or pulled at an end, a box passing or not (docs/synthetic.md)",
    );
    s += "\nVariants (--variant):\n";
    for v in Variant::ALL {
        s += &list_entry(v.name, v.description);
    }
    s
}

/// Columns of a list entry's name, and of the whole line.
const NAME_COLUMNS: usize = 30;
const LINE_COLUMNS: usize = 100;

/// `name` and its `description`, wrapped under itself within [`LINE_COLUMNS`].
fn list_entry(name: &str, description: &str) -> String {
    let mut out = format!("  {name:width$}", width = NAME_COLUMNS - 2);
    let mut column = out.len().max(NAME_COLUMNS);
    for word in description.split_whitespace() {
        if column + 1 + word.len() > LINE_COLUMNS {
            out += &format!("\n{:NAME_COLUMNS$}", "");
            column = NAME_COLUMNS;
        }
        out.push(' ');
        out += word;
        column += 1 + word.len();
    }
    out + "\n"
}

/// Every algorithm with its description (from the core).
pub fn algorithm_list() -> String {
    let mut s = String::new();
    for a in Algorithm::ALL {
        s += &list_entry(a.name(), a.description());
    }
    s
}

/// `upetrack bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Sequences to time [default: synthetic static-s and dynamic-pull at
    /// 640x480, static-s at 1280x720 in the hd-green-oak variant].
    pub sequences: Vec<String>,
    /// Frames of each sequence.
    #[arg(long, default_value_t = 90)]
    pub frames: usize,
    /// Runs over the frames (the medians are over all of them).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    pub repeat: u32,
    #[allow(missing_docs)]
    #[command(flatten)]
    pub runs: AlgorithmsArgs,
    #[allow(missing_docs)]
    #[command(flatten)]
    pub recording: RecordingArgs,
}

/// `upetrack overlay`.
#[derive(Debug, Args)]
pub struct OverlayArgs {
    /// The sequence.
    pub sequence: String,
    /// A result file of that sequence.
    pub result: PathBuf,
    /// The frame's index.
    pub frame: usize,
    /// The PNG to write.
    pub out: PathBuf,
    /// Draw over the depth image instead of the colour image.
    #[arg(long)]
    pub depth: bool,
    #[allow(missing_docs)]
    #[command(flatten)]
    pub recording: RecordingArgs,
}

/// `upetrack info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The recording (.bag, .db3, .mcap).
    pub recording: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
    #[allow(missing_docs)]
    #[command(flatten)]
    pub topics: TopicArgs,
}

/// `upetrack export`.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// The recording (.bag, .db3, .mcap).
    pub recording: String,
    /// The sequence folder to write.
    pub dir: PathBuf,
    /// The frames to write: A..B (B excluded), A.. or ..B [default: all].
    #[arg(long, value_name = "A..B", value_parser = frame_range)]
    pub frames: Option<std::ops::Range<usize>>,
    #[allow(missing_docs)]
    #[command(flatten)]
    pub recording_args: RecordingArgs,
}

/// `A..B` (B excluded), `A..` or `..B`.
pub fn frame_range(text: &str) -> Result<std::ops::Range<usize>, String> {
    let bad = || format!("`{text}` is not a range like 10..200");
    let (a, b) = text.split_once("..").ok_or_else(bad)?;
    let a = if a.is_empty() {
        0
    } else {
        a.parse().map_err(|_| bad())?
    };
    let b = if b.is_empty() {
        usize::MAX
    } else {
        b.parse().map_err(|_| bad())?
    };
    if a >= b {
        return Err(bad());
    }
    Ok(a..b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn the_command_line_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn algorithm_values_are_the_cores_list() {
        let names: Vec<&str> = AlgorithmArg::value_variants()
            .iter()
            .map(|a| a.0.name())
            .collect();
        let core: Vec<&str> = Algorithm::ALL.iter().map(|a| a.name()).collect();
        assert_eq!(names, core);
    }

    #[test]
    fn frame_ranges_exclude_their_end() {
        assert_eq!(frame_range("3..7").ok(), Some(3..7));
        assert_eq!(frame_range("..7").ok(), Some(0..7));
        assert_eq!(frame_range("5..").ok(), Some(5..usize::MAX));
        assert!(frame_range("7..3").is_err());
        assert!(frame_range("7").is_err());
        assert!(frame_range("a..b").is_err());
    }

    #[test]
    fn every_scenario_example_parses_by_its_name() {
        for k in ScenarioKind::EXAMPLES {
            assert!(
                matches!(parse_scenario(&k.name()), Ok(SynthScenario::Described(p)) if p == k),
                "{}",
                k.name()
            );
        }
        assert!(parse_scenario("nope").is_err_and(|e| e.contains("static-s")));
    }
}
