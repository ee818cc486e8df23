//! Where CDCPD2's step spends its time, stage by stage, on a synthetic
//! sequence: `cargo run --release -p upetrack-cli --example cdcpd2_cost`.

use std::time::Instant;

use upetrack::baselines::cdcpd2::{
    constrained_step, fit_table, visibility_prior, Cdcpd2Settings, Cdcpd2State,
};
use upetrack::perception::evidence::Evidence;
use upetrack::{Algorithm, Frame, Params, Tracker};
use upetrack_synth::{RenderSettings, Scenario, ScenarioKind};

fn main() {
    let mut s = Scenario::new(ScenarioKind::StaticS, 40, 1, RenderSettings::default());
    let params = Params {
        algorithm: Algorithm::Cdcpd2,
        ..Params::default()
    };
    let mut tracker = Tracker::new(params, s.camera(), s.hsv()).expect("tracker");
    let cam = s.camera();
    let settings = Cdcpd2Settings::default();
    let (mut t_prior, mut t_cpd, mut t_table, mut t_qp, mut iters, mut n) =
        (0.0, 0.0, 0.0, 0.0, 0, 0);
    while let Some(f) = s.next_frame() {
        let frame = Frame::new(640, 480, &f.rgb, &f.depth, 0.001).expect("frame");
        let obs = tracker.observe(&frame, &[]).expect("observe");
        let nodes = tracker.nodes().to_vec();
        if !nodes.is_empty() {
            let e = Evidence {
                frame: &frame,
                mask: &obs.mask,
                occlusions: &[],
                camera: &cam,
                radius: 0.0075,
            };
            let t0 = Instant::now();
            let _ = visibility_prior(&nodes, &e, settings.k_vis);
            let t1 = Instant::now();
            let mut state = Cdcpd2State::new(&nodes, &settings);
            let (cpd, it) = state
                .cpd(&nodes, &obs.cloud, Some(&e), &settings)
                .expect("cpd");
            let t2 = Instant::now();
            let table = fit_table(&e);
            let t3 = Instant::now();
            let bounds: Vec<f64> = nodes.windows(2).map(|w| (w[1] - w[0]).norm()).collect();
            let _ = constrained_step(&cpd, &bounds, table);
            let t4 = Instant::now();
            t_prior += (t1 - t0).as_secs_f64();
            t_cpd += (t2 - t1).as_secs_f64();
            t_table += (t3 - t2).as_secs_f64();
            t_qp += (t4 - t3).as_secs_f64();
            iters += it;
            n += 1;
        }
        let _ = tracker.update(&frame, &obs);
    }
    let ms = |t: f64| 1000.0 * t / n as f64;
    println!(
        "{n} frames: prior {:.2} ms, cpd {:.2} ms ({:.1} iterations, includes the prior), table {:.2} ms, qp {:.2} ms",
        ms(t_prior),
        ms(t_cpd),
        iters as f64 / n as f64,
        ms(t_table),
        ms(t_qp)
    );
}
