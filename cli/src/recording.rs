//! `upetrack info` and `upetrack export`: what a camera recording holds, and
//! the recording written as a sequence folder.

use std::time::Instant;

use upetrack_io::recorded::OpenRecording;
use upetrack_io::recording_info::RecordingInfo;

use crate::args::{ExportArgs, InfoArgs};
use crate::{open_sequence, progress, recording_options, CliError};

fn print_info(info: &RecordingInfo) {
    println!("{}", info.path);
    println!("  layout: {}", info.layout);
    for (name, s) in [("colour", &info.color), ("depth", &info.depth)] {
        let [fx, fy, ppx, ppy] = s.intrinsics;
        println!(
            "  {name}: {} {}x{} at {:.1} fps, {} frames; fx {fx:.2} fy {fy:.2} ppx {ppx:.2} ppy {ppy:.2} ({})",
            s.topic, s.width, s.height, s.fps, s.frames, s.distortion
        );
    }
    println!(
        "  depth units: {} m{}",
        info.depth_units,
        if info.aligned_on_reading {
            "; depth is in the depth imager's frame and is aligned to colour on reading"
        } else {
            "; depth is already aligned to colour"
        }
    );
    println!(
        "  paired frames: {} ({} colour and {} depth frames without a partner within half a period)",
        info.paired_frames, info.unpaired_color, info.unpaired_depth
    );
    println!("  image topics:");
    for (topic, ty, n) in &info.image_topics {
        println!("    {topic} [{ty}] {n} messages");
    }
    for w in &info.warnings {
        println!("  warning: {w}");
    }
}

/// `upetrack info <recording> [--json]`.
pub fn cmd_info(args: &InfoArgs) -> Result<(), CliError> {
    let rec = OpenRecording::open(&args.recording, &recording_options(&args.topics))?;
    let info = rec.info();
    if args.json {
        let text = serde_json::to_string_pretty(&info)
            .map_err(|e| CliError::internal(format!("cannot write JSON: {e}")))?;
        println!("{text}");
    } else {
        print_info(&info);
    }
    Ok(())
}

/// `upetrack export <recording> <dir> [--frames A..B] [--dlo dlo.json]`.
pub fn cmd_export(args: &ExportArgs) -> Result<(), CliError> {
    let range = args.frames.clone().unwrap_or(0..usize::MAX);
    let seq = open_sequence(&args.recording, &args.recording_args)?;
    let start = Instant::now();
    let bar = progress::bar(0, "frames", "export");
    let n = upetrack_io::export::export_sequence(&seq, &args.dir, range, &mut |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    eprintln!(
        "{}: {n} frames written to {} in {:.2} s",
        args.recording,
        args.dir.display(),
        start.elapsed().as_secs_f64()
    );
    if let Some(info) = seq.recording_info() {
        if info.unpaired_color + info.unpaired_depth > 0 {
            eprintln!(
                "note: {} colour and {} depth frames had no partner within half a period and were not exported",
                info.unpaired_color, info.unpaired_depth
            );
        }
        for w in &info.warnings {
            eprintln!("warning: {w}");
        }
    }
    Ok(())
}
