//! Our TrackDLO step against the upstream C++ tracking step (RMDLO/trackdlo,
//! its own `trackdlo.cpp`, the parameters of its evaluation launch file) on
//! fixed inputs: the goldens of `tests/data/trackdlo-upstream/make_goldens.py`.
//! Given the same visible and extended node lists, the same cloud, previous
//! nodes, rest coordinates and sigma^2, both must place the guide nodes, the
//! correspondence priors and the final nodes alike (tolerances below).

use serde_json::Value;
use upetrack::baselines::trackdlo::{TrackDloParams, TrackDloState};
use upetrack::math::Vec3;

fn goldens() -> Value {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/trackdlo-upstream/goldens.json"
    );
    serde_json::from_str(&std::fs::read_to_string(path).expect("goldens")).expect("json")
}

fn points(v: &Value) -> Vec<Vec3> {
    v.as_array()
        .expect("rows")
        .iter()
        .map(|r| {
            let c: Vec<f64> = r
                .as_array()
                .expect("row")
                .iter()
                .map(|x| x.as_f64().expect("num"))
                .collect();
            Vec3::new(c[0], c[1], c[2])
        })
        .collect()
}

fn indices(v: &Value) -> Vec<usize> {
    v.as_array()
        .expect("list")
        .iter()
        .map(|x| x.as_u64().expect("index") as usize)
        .collect()
}

/// The evaluation launch file's parameters, as the goldens were made with.
fn params(g: &Value) -> TrackDloParams {
    let p = &g["params"];
    let f = |k: &str| p[k].as_f64().expect(k);
    TrackDloParams {
        visibility_threshold: f("visibility_threshold"),
        beta: f("beta"),
        lambda: f("lambda_"),
        alpha: f("alpha"),
        k_vis: f("k_vis"),
        mu: f("mu"),
        max_iterations: f("max_iter") as u32,
        tolerance: f("tol"),
        beta_pre_proc: f("beta_pre_proc"),
        lambda_pre_proc: f("lambda_pre_proc"),
        lle_weight: f("lle_weight"),
        ..TrackDloParams::default()
    }
}

struct Ours {
    nodes: Vec<Vec3>,
    guide: Vec<Vec3>,
    priors: Vec<(usize, Vec3)>,
    sigma2: f64,
}

fn run_ours(c: &Value, p: &TrackDloParams) -> Ours {
    let prev = points(&c["prev"]);
    let m = prev.len();
    let cloud = points(&c["cloud"]);
    let ext = indices(&c["extended"]);
    let extended: Vec<bool> = (0..m).map(|i| ext.contains(&i)).collect();
    let rest: Vec<f64> = c["geodesic"]
        .as_array()
        .expect("geo")
        .iter()
        .map(|x| x.as_f64().expect("num"))
        .collect();
    let mut state = TrackDloState {
        rest,
        variance: c["sigma2"].as_f64().expect("sigma2"),
    };
    let mut nodes = prev.clone();
    let report = state.step_with_visibility(&mut nodes, &cloud, &extended, p);
    Ours {
        nodes,
        guide: report.guide,
        priors: report.priors.iter().map(|q| (q.node, q.position)).collect(),
        sigma2: state.variance,
    }
}

fn max_dist(a: &[Vec3], b: &[Vec3]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max)
}

#[test]
fn our_step_matches_upstream_trackdlo_on_every_golden_case() {
    let g = goldens();
    let p = params(&g);
    let mut report = Vec::new();
    for c in g["cases"].as_array().expect("cases") {
        let name = c["name"].as_str().expect("name");
        let up = &c["upstream"];
        let ours = run_ours(c, &p);
        assert!(
            ours.nodes.iter().all(|q| q.iter().all(|v| v.is_finite())),
            "{name}: not finite"
        );
        if up["aborted"].as_bool().expect("aborted") {
            // Upstream aborts (its issue #81); ours must give finite nodes,
            // which the line above checked.
            report.push(format!("{name}: upstream aborted, ours finite"));
            continue;
        }
        let guide = max_dist(&ours.guide, &points(&up["guide"]));
        let nodes = max_dist(&ours.nodes, &points(&up["nodes"]));
        let up_priors: Vec<(usize, Vec3)> = up["priors"]
            .as_array()
            .expect("priors")
            .iter()
            .map(|r| {
                let v: Vec<f64> = r
                    .as_array()
                    .expect("prior")
                    .iter()
                    .map(|x| x.as_f64().expect("num"))
                    .collect();
                (v[0] as usize, Vec3::new(v[1], v[2], v[3]))
            })
            .collect();
        let prior_nodes: Vec<usize> = ours.priors.iter().map(|q| q.0).collect();
        let mut up_nodes: Vec<usize> = up_priors.iter().map(|q| q.0).collect();
        up_nodes.sort_unstable();
        up_nodes.dedup();
        let prior_err = ours
            .priors
            .iter()
            .filter_map(|(i, q)| {
                // Upstream may list a node twice (both walks): compare with the mean.
                let theirs: Vec<Vec3> = up_priors
                    .iter()
                    .filter(|u| u.0 == *i)
                    .map(|u| u.1)
                    .collect();
                (!theirs.is_empty())
                    .then(|| (q - theirs.iter().sum::<Vec3>() / theirs.len() as f64).norm())
            })
            .fold(0.0, f64::max);
        let up_sigma2 = up["sigma2"].as_f64().expect("sigma2");
        if name == "both-ends-hidden" {
            // The one deviation that shows here (docs/algorithm-notes.md):
            // upstream walks from the least-moved node towards the tail only
            // (its head-side loop is commented out); ours walks both ways, so
            // it has priors for the head-side guide nodes too, and the nodes
            // end up to a millimetre apart.
            assert!(
                up_nodes.iter().all(|i| prior_nodes.contains(i)),
                "{name}: {up_nodes:?} vs {prior_nodes:?}"
            );
            assert!(prior_nodes.len() > up_nodes.len(), "{name}");
            assert!(
                guide < 1e-6 && prior_err < 1e-6 && nodes < 1e-3,
                "{name}: {guide} {prior_err} {nodes}"
            );
        } else {
            // Measured at most 3.2e-7 m: the pre-registration's LLE Gram
            // matrix is regularised by 1e-3 of its trace here and inverted
            // as it is upstream (rank-deficient with six neighbours in 3D),
            // and sums run in another order. A micrometre is a thousandth of
            // the smallest error the tables report.
            assert_eq!(prior_nodes, up_nodes, "{name}: prior nodes");
            assert!(guide < 1e-6, "{name}: guide nodes {guide} m apart");
            assert!(prior_err < 1e-6, "{name}: priors {prior_err} m apart");
            assert!(nodes < 1e-6, "{name}: nodes {nodes} m apart");
            assert!(
                (ours.sigma2 - up_sigma2).abs() < 1e-3 * up_sigma2,
                "{name}: sigma2"
            );
        }
        report.push(format!(
            "{name}: guide {:.2e} m, priors {:?} vs {:?} ({prior_err:.2e} m), nodes {:.2e} m, sigma2 {:.3e} vs {:.3e}",
            guide, prior_nodes.len(), up_nodes.len(), nodes, ours.sigma2, up_sigma2
        ));
    }
    eprintln!("{}", report.join("\n"));
}
