//! Times reading, decoding and aligning a recording's frames (a development aid).
use std::time::Instant;
fn main() {
    let path = std::env::args().nth(1).expect("recording");
    let t = Instant::now();
    let f = upetrack_recordings::FileBytes::open(std::path::Path::new(&path)).expect("open");
    let mut rec = upetrack_recordings::Recording::open(f, &Default::default()).expect("rec");
    println!(
        "open {:.1} ms, {} frames",
        t.elapsed().as_secs_f64() * 1e3,
        rec.len()
    );
    let t = Instant::now();
    let n = rec.len().min(100);
    for i in 0..n {
        rec.frame(i).expect("frame");
    }
    println!(
        "frame {:.2} ms each",
        t.elapsed().as_secs_f64() * 1e3 / n as f64
    );
    let t = Instant::now();
    for i in 0..n {
        rec.frame(i).expect("frame");
    }
    println!(
        "again, chunks cached {:.2} ms each",
        t.elapsed().as_secs_f64() * 1e3 / n as f64
    );
    rec.depth_to_color = None;
    let t = Instant::now();
    for i in 0..n {
        rec.frame(i).expect("frame");
    }
    println!(
        "without alignment {:.2} ms each",
        t.elapsed().as_secs_f64() * 1e3 / n as f64
    );
}
