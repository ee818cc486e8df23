//! Times each stage of one frame separately on a synthetic sequence:
//! `cargo run --release -p upetrack-cli --example stages`.

use std::time::Instant;

use upetrack::perception::point_cloud::{build_cloud, deproject_mask, voxel_downsample};
use upetrack::perception::segmentation::segment;
use upetrack::{Frame, Params, Tracker};
use upetrack_synth::{RenderSettings, Scenario, ScenarioKind};

fn main() {
    let mut s = Scenario::new(ScenarioKind::StaticS, 60, 1, RenderSettings::default());
    let params = Params::default();
    let mut tracker = Tracker::new(params, s.camera(), s.hsv()).expect("tracker");
    let cam = s.camera();
    let hsv = s.hsv();
    let mut t = [0.0f64; 5];
    let mut n_raw = 0;
    let mut n_cloud = 0;
    let mut count = 0;
    let mut iters = 0;
    while let Some(f) = s.next_frame() {
        let frame = Frame::new(640, 480, &f.rgb, &f.depth, 0.001).expect("frame");
        let t0 = Instant::now();
        let mask = segment(&frame, &hsv, &[]);
        let t1 = Instant::now();
        let raw = deproject_mask(&frame, &mask, &cam, &params.cloud());
        let t2 = Instant::now();
        let vox = voxel_downsample(&raw, params.voxel_size);
        let t3 = Instant::now();
        let cloud = build_cloud(&frame, &mask, &cam, &params.cloud());
        let obs = upetrack::tracker::Observation {
            mask,
            cloud,
            occlusions: Vec::new(),
        };
        let t4 = Instant::now();
        let out = tracker.update(&frame, &obs);
        if let Some(em) = out.em {
            iters += em.iterations as usize;
        }
        let t5 = Instant::now();
        if f.index > 0 {
            t[0] += (t1 - t0).as_secs_f64();
            t[1] += (t2 - t1).as_secs_f64();
            t[2] += (t3 - t2).as_secs_f64();
            t[3] += (t5 - t4).as_secs_f64();
            n_raw += raw.len();
            n_cloud += vox.len();
            count += 1;
        }
    }
    let ms = |x: f64| x * 1000.0 / count as f64;
    println!(
        "segment {:.3} ms, deproject {:.3} ms ({} pts), voxel {:.3} ms ({} pts), update {:.3} ms ({:.1} EM iterations)",
        ms(t[0]),
        ms(t[1]),
        n_raw / count,
        ms(t[2]),
        n_cloud / count,
        ms(t[3]),
        iters as f64 / count as f64
    );
}
