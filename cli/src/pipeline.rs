//! Tracking a sequence on two threads: one reads and decodes the frames
//! ahead, the other tracks them, so a run takes as long as the slower half.

use std::sync::mpsc::sync_channel;
use std::time::Instant;

use indicatif::ProgressBar;
use upetrack::{Params, Rect};
use upetrack_io::result::TrackResult;
use upetrack_io::run::SequenceRun;
use upetrack_io::sequence::DecodedFrame;

use crate::{AnySequence, CliError};

/// Frames decoded ahead of the tracker: enough to smooth a slow frame out,
/// few enough that 1280x720 frames hold about 30 MB.
pub const DECODE_AHEAD: usize = 8;

/// A clock in milliseconds since `start`.
pub fn now_ms_since(start: Instant) -> impl FnMut() -> f64 {
    move || start.elapsed().as_secs_f64() * 1000.0
}

/// One decoded frame on its way to the tracker.
struct Decoded {
    frame: DecodedFrame,
    occlusions: Vec<Rect>,
    name: String,
}

/// Tracks every frame of `seq` with `params`, decoding ahead on a second
/// thread; `bar` counts the frames tracked. The same records as
/// [`upetrack_io::run::track_sequence`], which does both on one thread.
pub fn track(
    seq: &AnySequence,
    params: Params,
    bar: &ProgressBar,
) -> Result<TrackResult, CliError> {
    let mut run = SequenceRun::new(seq, params)?;
    let (send, receive) = sync_channel::<Decoded>(DECODE_AHEAD);
    std::thread::scope(|scope| {
        let tracking = scope.spawn(move || {
            let mut now_ms = now_ms_since(Instant::now());
            for d in receive {
                run.push(&d.frame, &d.occlusions, &d.name, &mut now_ms)?;
                bar.inc(1);
            }
            Ok::<_, CliError>(run)
        });
        // Reading stops at the first frame that cannot be decoded, or when
        // the tracker has stopped (its error is the one reported).
        let mut read_error = None;
        for i in 0..seq.len() {
            match seq.frame(i) {
                Ok(frame) => {
                    let d = Decoded {
                        frame,
                        occlusions: seq.occlusions_at(i),
                        name: seq.frame_name(i),
                    };
                    if send.send(d).is_err() {
                        break;
                    }
                }
                Err(e) => {
                    read_error = Some(e);
                    break;
                }
            }
        }
        drop(send);
        let run = tracking
            .join()
            .map_err(|_| CliError::internal("the tracking thread panicked"))??;
        match read_error {
            Some(e) => Err(e.into()),
            None => Ok(run.finish()),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The records without their timings (the only fields a clock sets).
    fn untimed(mut r: TrackResult) -> String {
        for f in &mut r.frames {
            f.track_ms = 0.0;
            f.total_ms = 0.0;
        }
        serde_json::to_string(&r).unwrap_or_default()
    }

    #[test]
    fn decoding_ahead_gives_the_records_of_one_thread_to_the_last_bit() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../samples/dynamic-pull");
        let seq = crate::open_sequence(path, &crate::RecordingArgs::default())
            .unwrap_or_else(|e| panic!("{}", e.message));
        for algorithm in upetrack::Algorithm::ALL {
            let params = Params {
                algorithm,
                ..Params::default()
            };
            let ahead = track(&seq, params, &ProgressBar::hidden())
                .unwrap_or_else(|e| panic!("{}", e.message));
            let inline = upetrack_io::run::track_sequence(&seq, params, &mut || 0.0)
                .unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(ahead.frames.len(), seq.len());
            assert_eq!(untimed(ahead), untimed(inline), "{}", algorithm.name());
        }
    }
}
