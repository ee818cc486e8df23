//! CPD against pycpd: `tests/data/pycpd/goldens.json` holds point sets and
//! pycpd 2.0.0's `DeformableRegistration` outputs, made once by the script
//! beside it.
//!
//! Tolerance: both compute the same float64 iteration; they differ only in
//! rounding (libm's `exp` against numpy's, an LU solve against LAPACK's),
//! about 1e-16 relative per operation. Over tens of iterations through
//! kernel systems with condition numbers up to about 1e6 that can grow to
//! 1e-10 of the point sets' extent, so positions must agree within 1e-8 of
//! the extent and `sigma^2` within 1e-6 relative, with the same iteration
//! count (measured: at most 8e-14 of the extent). A wrong formula (a missing factor 2 in the variance, `M/N`
//! dropped from the outlier constant) moves the result by 1e-3 or more.

use nalgebra::DMatrix;
use serde_json::Value;
use upetrack::baselines::cpd::{register_deformable, CpdSettings};

fn matrix(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = v
        .as_array()
        .expect("rows")
        .iter()
        .map(|r| {
            r.as_array()
                .expect("row")
                .iter()
                .map(|x| x.as_f64().expect("number"))
                .collect()
        })
        .collect();
    DMatrix::from_fn(rows.len(), rows[0].len(), |i, j| rows[i][j])
}

/// The settings of a golden case, with its outlier weight or `w`.
fn settings(c: &Value, w: Option<f64>) -> CpdSettings {
    CpdSettings {
        beta: c["beta"].as_f64().expect("beta"),
        lambda: c["lambda_"].as_f64().expect("lambda"),
        outlier_weight: w.unwrap_or_else(|| c["w"].as_f64().expect("w")),
        max_iterations: c["max_iterations"].as_u64().expect("iterations") as u32,
        tolerance: c["tolerance"].as_f64().expect("tolerance"),
    }
}

fn goldens() -> Vec<Value> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/pycpd/goldens.json"
    );
    let text = std::fs::read_to_string(path).expect("goldens.json");
    let v: Value = serde_json::from_str(&text).expect("json");
    v["cases"].as_array().expect("cases").clone()
}

#[test]
fn deformable_cpd_matches_pycpd_on_every_golden_case() {
    let cases = goldens();
    assert_eq!(cases.len(), 4);
    for c in cases {
        let name = c["name"].as_str().expect("name");
        let x = matrix(&c["X"]);
        let y = matrix(&c["Y"]);
        let expected = matrix(&c["TY"]);
        let out = register_deformable(&x, &y, None, &settings(&c, None)).expect(name);
        let extent = x
            .column_iter()
            .map(|col| col.max() - col.min())
            .fold(0.0, f64::max);
        let err = (&out.points - &expected).abs().max();
        let sigma2 = c["sigma2"].as_f64().expect("sigma2");
        eprintln!(
            "{name}: max position difference {err:.3e} ({:.3e} of the extent), sigma2 {:.3e} vs {sigma2:.3e}",
            err / extent,
            out.variance
        );
        assert_eq!(
            u64::from(out.iterations),
            c["iterations"].as_u64().expect("iterations"),
            "{name}: iterations"
        );
        assert!(err <= 1e-8 * extent, "{name}: positions differ by {err}");
        assert!(
            (out.variance - sigma2).abs() <= 1e-6 * sigma2,
            "{name}: sigma2 {} vs {sigma2}",
            out.variance
        );
    }
}

#[test]
fn a_golden_case_fails_with_the_outlier_weight_ignored() {
    // The check has teeth: dropping `w` (the 2D outlier case uses 0.2)
    // moves the result far outside the tolerance above.
    let c = goldens()
        .into_iter()
        .find(|c| c["name"] == "2d-outliers")
        .expect("case");
    let x = matrix(&c["X"]);
    let y = matrix(&c["Y"]);
    let expected = matrix(&c["TY"]);
    let out = register_deformable(&x, &y, None, &settings(&c, Some(0.0))).expect("runs");
    assert!((&out.points - &expected).abs().max() > 1e-3);
}
