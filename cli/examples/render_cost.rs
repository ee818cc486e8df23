//! Median cost of making one synthetic frame: simulation and rendering, then
//! the JPEG and PNG encoding that `upetrack synth` (and the page's scene
//! generator) add: `cargo run --release -p upetrack-cli --example render_cost`.

use std::time::Instant;

use upetrack_io::write::{encode_depth_png, encode_jpeg, JPEG_QUALITY};
use upetrack_synth::{RenderSettings, Scenario, ScenarioKind};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let mut s = Scenario::new(ScenarioKind::DynamicPull, 30, 2, RenderSettings::default());
    let camera = s.camera();
    let (mut render, mut jpeg, mut png) = (Vec::new(), Vec::new(), Vec::new());
    loop {
        let t = Instant::now();
        let Some(f) = s.next_frame() else { break };
        render.push(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        encode_jpeg(camera.width, camera.height, &f.rgb, JPEG_QUALITY).expect("jpeg");
        jpeg.push(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        encode_depth_png(camera.width, camera.height, &f.depth).expect("png");
        png.push(t.elapsed().as_secs_f64() * 1e3);
    }
    println!(
        "median per frame: simulate and render {:.1} ms, JPEG {:.1} ms, depth PNG {:.1} ms",
        median(render),
        median(jpeg),
        median(png)
    );
}
