//! Median decoding time of the colour and depth files of a sequence:
//! `cargo run --release -p upetrack-cli --example decode_cost -- samples/static-s`.

use std::time::Instant;

use upetrack_io::decode::{decode_color, decode_depth};

fn main() {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "samples/static-s".into());
    let mut color = Vec::new();
    let mut depth = Vec::new();
    for i in 0..20 {
        let c = std::fs::read(format!("{dir}/color/{i:06}.jpg")).expect("colour file");
        let d = std::fs::read(format!("{dir}/depth/{i:06}.png")).expect("depth file");
        let t = Instant::now();
        decode_color(&c, "c").expect("colour");
        color.push(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        decode_depth(&d, "d").expect("depth");
        depth.push(t.elapsed().as_secs_f64() * 1e3);
    }
    color.sort_by(f64::total_cmp);
    depth.sort_by(f64::total_cmp);
    println!(
        "median decode: colour {:.2} ms, depth {:.2} ms",
        color[10], depth[10]
    );
}
