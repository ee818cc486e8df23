//! Runs the registration of one tracked frame 20 times, for instruction
//! counting with `valgrind --tool=callgrind --toggle-collect='*register*'`.

use upetrack::{Frame, Params, Tracker};
use upetrack_synth::{RenderSettings, Scenario, ScenarioKind};

fn main() {
    let mut s = Scenario::new(ScenarioKind::StaticS, 3, 1, RenderSettings::default());
    let params = Params::default();
    let mut tracker = Tracker::new(params, s.camera(), s.hsv()).expect("tracker");
    let mut last = None;
    while let Some(f) = s.next_frame() {
        let frame = Frame::new(640, 480, &f.rgb, &f.depth, 0.001).expect("frame");
        let obs = tracker.observe(&frame, &[]).expect("observe");
        tracker.update(&frame, &obs);
        last = Some(obs);
    }
    let obs = last.expect("frames");
    let prev = tracker.nodes().to_vec();
    let vis = vec![true; prev.len()];
    let mut iterations = 0;
    for _ in 0..20 {
        let mut nodes = prev.clone();
        iterations += upetrack::upe::registration::register(
            &obs.cloud,
            &mut nodes,
            &vis,
            &params.upetrack.em(),
        )
        .iterations;
    }
    println!(
        "{} points, {} iterations per call",
        obs.cloud.len(),
        iterations / 20
    );
}
