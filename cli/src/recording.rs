//! `upetrack info` and `upetrack export`: what a camera recording holds, and
//! the recording written as a sequence folder.

use std::path::Path;
use std::time::Instant;

use upetrack_io::recorded::OpenRecording;
use upetrack_io::recording_info::RecordingInfo;

use crate::{open_sequence, with_recording_options, Args, CliError, RecordingArgs, USAGE};

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
pub fn cmd_info(raw: &[String]) -> Result<(), CliError> {
    let args = Args::parse(raw, &["json"], &["color-topic", "depth-topic", "align"])?;
    let [path] = args.positional.as_slice() else {
        return Err(CliError(format!("info takes one recording\n\n{USAGE}")));
    };
    let rec = OpenRecording::open(Path::new(path), &RecordingArgs::from(&args)?.options)?;
    let info = rec.info();
    if args.flag("json") {
        let text = serde_json::to_string_pretty(&info)
            .map_err(|e| CliError(format!("cannot write JSON: {e}")))?;
        println!("{text}");
    } else {
        print_info(&info);
    }
    Ok(())
}

/// `A..B` (B excluded), `A..` or `..B`.
fn frame_range(text: &str) -> Result<std::ops::Range<usize>, CliError> {
    let bad = || CliError(format!("--frames: `{text}` is not a range like 10..200"));
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

/// `upetrack export <recording> <dir> [--frames A..B] [--dlo dlo.json]`.
pub fn cmd_export(raw: &[String]) -> Result<(), CliError> {
    let args = Args::parse(raw, &[], &with_recording_options(&["frames"]))?;
    let [path, dir] = args.positional.as_slice() else {
        return Err(CliError(format!(
            "export takes a recording and a folder\n\n{USAGE}"
        )));
    };
    let range = match args.value("frames") {
        Some(r) => frame_range(r)?,
        None => 0..usize::MAX,
    };
    let seq = open_sequence(path, &RecordingArgs::from(&args)?)?;
    let start = Instant::now();
    let mut last_shown = 0;
    let n =
        upetrack_io::export::export_sequence(&seq, Path::new(dir), range, &mut |done, total| {
            let tenth = done * 10 / total;
            if tenth != last_shown {
                last_shown = tenth;
                eprint!("\r{done}/{total} frames");
            }
        })?;
    eprintln!(
        "\r{path}: {n} frames written to {dir} in {:.2} s",
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_ranges_exclude_their_end() {
        assert_eq!(frame_range("3..7").ok(), Some(3..7));
        assert_eq!(frame_range("..7").ok(), Some(0..7));
        assert_eq!(frame_range("5..").ok(), Some(5..usize::MAX));
        assert!(frame_range("7..3").is_err());
        assert!(frame_range("7").is_err());
        assert!(frame_range("a..b").is_err());
    }
}
