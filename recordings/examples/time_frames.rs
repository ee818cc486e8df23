//! Times reading, decoding and aligning a recording's frames (a development aid).
use std::time::Instant;

use upetrack_recordings::{FileBytes, Recording};

/// Decodes the first `n` frames and prints the mean time per frame.
fn time_frames(rec: &mut Recording<FileBytes>, n: usize, label: &str) {
    let t = Instant::now();
    for i in 0..n {
        rec.frame(i).expect("frame");
    }
    println!(
        "{label} {:.2} ms each",
        t.elapsed().as_secs_f64() * 1e3 / n as f64
    );
}

fn main() {
    let path = std::env::args().nth(1).expect("recording");
    let t = Instant::now();
    let f = FileBytes::open(std::path::Path::new(&path)).expect("open");
    let mut rec = Recording::open(f, &Default::default()).expect("rec");
    println!(
        "open {:.1} ms, {} frames",
        t.elapsed().as_secs_f64() * 1e3,
        rec.len()
    );
    let n = rec.len().min(100);
    time_frames(&mut rec, n, "frame");
    time_frames(&mut rec, n, "again, chunks cached");
    rec.depth_to_color = None;
    time_frames(&mut rec, n, "without alignment");
}
