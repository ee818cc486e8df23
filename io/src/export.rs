//! Writing any sequence (a recording above all) as a sequence folder in the
//! contract's layout: lossless PNG colour and depth, the intrinsics, and a
//! `dlo.json` carrying the depth scale, the frame rate and the configuration.

use std::path::Path;

use crate::error::SequenceError;
use crate::sequence::{DecodedFrame, IntrinsicsFile, OcclusionConfig, Sequence};
use crate::source::Source;
use crate::write::{encode_depth_png, encode_rgb_png, write_file, write_json};

/// Writes frames `range` of `seq` into `dir`; returns the number written.
/// Occlusion frame ranges are shifted to the exported numbering; the ground
/// truth is not carried over.
pub fn export_sequence<S: Source>(
    seq: &Sequence<S>,
    dir: &Path,
    range: std::ops::Range<usize>,
    on_frame: &mut dyn FnMut(usize, usize),
) -> Result<usize, SequenceError> {
    let range = range.start.min(seq.len())..range.end.min(seq.len());
    if range.is_empty() {
        return Err(SequenceError::invalid(
            &dir.display().to_string(),
            format!("no frames to export: the sequence has {} frames", seq.len()),
        ));
    }
    write_json(
        &dir.join("camera_intrinsic.json"),
        &IntrinsicsFile::from_camera(&seq.camera),
    )?;
    let mut config = seq.config.clone();
    config.depth_scale = Some(seq.depth_scale);
    config.fps = Some(seq.fps);
    config.groundtruth = None;
    let (first, last) = (range.start as u64, range.end as u64 - 1);
    config.occlusions = config
        .occlusions
        .iter()
        .filter(|o| o.frames[1] >= first && o.frames[0] <= last)
        .map(|o| OcclusionConfig {
            frames: [
                o.frames[0].max(first) - first,
                o.frames[1].min(last) - first,
            ],
            rect: o.rect,
        })
        .collect();
    write_json(&dir.join("dlo.json"), &config)?;
    let total = range.len();
    // Frames are read (and aligned) here while a second thread encodes and
    // writes the previous ones: on two cores the slower of the two sets the pace.
    std::thread::scope(|scope| {
        let (to_writer, frames) = std::sync::mpsc::sync_channel::<(usize, DecodedFrame)>(2);
        let writer = scope.spawn(move || -> Result<(), SequenceError> {
            for (n, f) in frames {
                write_file(
                    &dir.join(format!("color/{n:06}.png")),
                    &encode_rgb_png(f.width, f.height, &f.color)?,
                )?;
                write_file(
                    &dir.join(format!("depth/{n:06}.png")),
                    &encode_depth_png(f.width, f.height, &f.depth)?,
                )?;
            }
            Ok(())
        });
        let mut read = Ok(());
        for (n, i) in range.enumerate() {
            match seq.frame(i) {
                // A writer that stopped has an error to report, below.
                Ok(f) => {
                    if to_writer.send((n, f)).is_err() {
                        break;
                    }
                }
                Err(e) => {
                    read = Err(e);
                    break;
                }
            }
            on_frame(n + 1, total);
        }
        drop(to_writer);
        let written = writer.join().unwrap_or_else(|_| {
            Err(SequenceError::invalid(
                &dir.display().to_string(),
                "the writer thread failed",
            ))
        });
        read.and(written)
    })?;
    Ok(total)
}
