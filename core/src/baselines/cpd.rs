//! Coherent point drift, deformable (Myronenko and Song, TPAMI 2010): the
//! baseline registration, and the M-step pieces TrackDLO's CPD-LLE shares.
//!
//! The source points `Y` (rows, any dimension `D`) move by `T = Y + G W`,
//! `G` a Gaussian kernel of width `beta` on the source points, to maximise
//! the likelihood of the target points `X` under a Gaussian mixture centred
//! on `T` plus a uniform outlier component of weight `w`, with `lambda`
//! weighting the smoothness of the displacement field. The iteration and the
//! stopping rule follow pycpd's `DeformableRegistration` so that the golden
//! tests can compare against it.

use nalgebra::DMatrix;

use crate::math::{self, Vec3};
use crate::step::{Algorithm, StepInput, StepOutput, TrackingStep};
use crate::validation::{below_one, check, positive, ParamsError};

/// Most `M x N` point pairs one registration accepts (the responsibility
/// matrix has that many entries, 8 bytes each: 32 MB).
pub const MAX_CPD_PAIRS: usize = 4_000_000;

/// Most iterations accepted in one registration.
pub const MAX_CPD_ITERATIONS: u32 = 10_000;

/// A column of responsibilities summing to zero is divided by this instead
/// (pycpd's guard, `numpy.finfo(float).eps`).
const ZERO_COLUMN_GUARD: f64 = f64::EPSILON;

/// Errors of one registration.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CpdError {
    /// A point set has no points.
    #[error("the {which} point set is empty")]
    Empty {
        /// `"source"` or `"target"`.
        which: &'static str,
    },
    /// The point sets have different dimensions.
    #[error("source points have {source_dim} coordinates but target points have {target_dim}")]
    DimensionMismatch {
        /// Columns of the source set.
        source_dim: usize,
        /// Columns of the target set.
        target_dim: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("the {which} point set has a coordinate that is not finite")]
    NotFinite {
        /// `"source"` or `"target"`.
        which: &'static str,
    },
    /// Too many point pairs.
    #[error("{pairs} point pairs exceed the cap of {max}")]
    TooLarge {
        /// `M x N`.
        pairs: usize,
        /// [`MAX_CPD_PAIRS`].
        max: usize,
    },
    /// A setting outside its range.
    #[error(transparent)]
    Setting(#[from] ParamsError),
}

/// Settings of deformable CPD. Lengths in the units of the points.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct CpdSettings {
    /// Width of the Gaussian coherence kernel (`beta`).
    pub beta: f64,
    /// Weight of the smoothness regulariser (`lambda`; pycpd's `alpha`).
    pub lambda: f64,
    /// Weight of the uniform outlier component (`w`), in `[0, 1)`.
    pub outlier_weight: f64,
    /// Most EM iterations.
    pub max_iterations: u32,
    /// Stop when `sigma^2` changes by no more than this between iterations.
    pub tolerance: f64,
}

impl Default for CpdSettings {
    /// The values used to track a rope in metres (see
    /// `docs/algorithm-notes.md`, "CPD baseline"): `beta` = 0.1 m,
    /// `lambda` = 50000 (TrackDLO's), `w` = 0.1, 50 iterations, tolerance 1e-8 m^2.
    fn default() -> Self {
        Self {
            beta: 0.1,
            lambda: 50_000.0,
            outlier_weight: 0.1,
            max_iterations: 50,
            tolerance: 1e-8,
        }
    }
}

impl CpdSettings {
    /// pycpd's defaults: `beta = 2`, `lambda` (its `alpha`) = 2, `w = 0`,
    /// 100 iterations, tolerance 0.001.
    pub const PYCPD: Self = Self {
        beta: 2.0,
        lambda: 2.0,
        outlier_weight: 0.0,
        max_iterations: 100,
        tolerance: 0.001,
    };
}

impl CpdSettings {
    /// Checks every field (named `cpd.<field>` in errors).
    pub fn validate(&self) -> Result<(), ParamsError> {
        positive("cpd.beta", self.beta)?;
        positive("cpd.lambda", self.lambda)?;
        let w = self.outlier_weight;
        below_one("cpd.outlier_weight", w)?;
        check(
            "cpd.max_iterations",
            self.max_iterations as f64,
            (1..=MAX_CPD_ITERATIONS).contains(&self.max_iterations),
            "an integer in 1..=10000",
        )?;
        check(
            "cpd.tolerance",
            self.tolerance,
            self.tolerance >= 0.0,
            "at least 0",
        )
    }
}

/// The result of one registration.
#[derive(Debug, Clone, PartialEq)]
pub struct CpdOutcome {
    /// The moved source points `T`, one per row.
    pub points: DMatrix<f64>,
    /// Final `sigma^2`.
    pub variance: f64,
    /// Iterations run.
    pub iterations: u32,
    /// `false` when the iteration cap was reached or the M-step system was
    /// singular (the points are then those of the last good iteration).
    pub converged: bool,
}

/// 3D points as the rows of an `N x 3` matrix.
pub fn points_to_matrix(points: &[Vec3]) -> DMatrix<f64> {
    DMatrix::from_fn(points.len(), 3, |i, c| points[i][c])
}

/// The rows of an `N x 3` matrix as 3D points.
pub fn matrix_to_points(rows: &DMatrix<f64>) -> alloc::vec::Vec<Vec3> {
    (0..rows.nrows())
        .map(|i| Vec3::new(rows[(i, 0)], rows[(i, 1)], rows[(i, 2)]))
        .collect()
}

/// The Gaussian kernel `G_ij = exp(-|y_i - y_j|^2 / (2 beta^2))` on the rows of `points`.
pub fn gaussian_kernel(points: &DMatrix<f64>, beta: f64) -> DMatrix<f64> {
    let m = points.nrows();
    let scale = 1.0 / (2.0 * beta * beta);
    DMatrix::from_fn(m, m, |i, j| {
        math::exp(-(points.row(i) - points.row(j)).norm_squared() * scale)
    })
}

/// `sigma^2` from the mean squared distance over all pairs (pycpd's start).
pub fn pairwise_variance(target: &DMatrix<f64>, source: &DMatrix<f64>) -> f64 {
    let (n, d) = target.shape();
    let m = source.nrows();
    let mut sum = 0.0;
    for i in 0..m {
        for j in 0..n {
            sum += (source.row(i) - target.row(j)).norm_squared();
        }
    }
    sum / (d * m * n) as f64
}

/// The uniform component's share of each column's normaliser: `c = (2 pi
/// sigma^2)^(D/2) w / (1 - w) M / N` (Eq. 7 of the CPD paper).
pub fn outlier_constant(variance: f64, dim: usize, w: f64, m: usize, n: usize) -> f64 {
    libm::pow(2.0 * core::f64::consts::PI * variance, dim as f64 / 2.0) * w / (1.0 - w) * m as f64
        / n as f64
}

/// `points` thinned by a stride so that `sources x points` stays within
/// [`MAX_CPD_PAIRS`] (the trackers' way to respect the cap on huge clouds).
pub fn thin_to_pair_cap<T: Copy>(points: &[T], sources: usize) -> alloc::vec::Vec<T> {
    let max_points = (MAX_CPD_PAIRS / sources.max(1)).max(1);
    let stride = points.len().div_ceil(max_points).max(1);
    points.iter().step_by(stride).copied().collect()
}

/// Divides each column of the unnormalised responsibilities by its sum plus `c`.
pub fn normalise_columns(p: &mut DMatrix<f64>, c: f64) {
    for mut col in p.column_iter_mut() {
        let mut den = col.sum();
        if den == 0.0 {
            den = ZERO_COLUMN_GUARD;
        }
        col /= den + c;
    }
}

/// Sums of the responsibilities the M-step needs.
pub struct Responsibilities {
    /// `P 1`, per source point.
    pub p1: DMatrix<f64>,
    /// `P^T 1`, per target point.
    pub pt1: DMatrix<f64>,
    /// `P X`.
    pub px: DMatrix<f64>,
    /// `sum(P)`.
    pub total: f64,
}

impl Responsibilities {
    /// The sums of `p` (`M x N`) against `target` (`N x D`).
    pub fn of(p: &DMatrix<f64>, target: &DMatrix<f64>) -> Self {
        let m = p.nrows();
        let n = p.ncols();
        let p1 = DMatrix::from_fn(m, 1, |i, _| p.row(i).sum());
        let pt1 = DMatrix::from_fn(n, 1, |j, _| p.column(j).sum());
        let total = p1.sum();
        Self {
            p1,
            pt1,
            px: p * target,
            total,
        }
    }

    /// `diag(P1) A`.
    pub fn scale_rows(&self, a: &DMatrix<f64>) -> DMatrix<f64> {
        let mut out = a.clone();
        for (i, mut row) in out.row_iter_mut().enumerate() {
            row *= self.p1[i];
        }
        out
    }

    /// The variance update (Eq. 23 of the CPD paper) for the moved points
    /// `t`: `(tr(X^T d(P^T 1) X) - 2 tr((PX)^T T) + tr(T^T d(P1) T)) / (N_P D)`.
    pub fn variance(&self, target: &DMatrix<f64>, t: &DMatrix<f64>) -> f64 {
        let d = target.ncols();
        let xpx: f64 = (0..target.nrows())
            .map(|j| self.pt1[j] * target.row(j).norm_squared())
            .sum();
        let ypy: f64 = (0..t.nrows())
            .map(|i| self.p1[i] * t.row(i).norm_squared())
            .sum();
        let trpxy = self.px.component_mul(t).sum();
        (xpx - 2.0 * trpxy + ypy) / (self.total * d as f64)
    }
}

/// Solves `A W = B` by LU (the coherent M-step, and TrackDLO's LLE
/// weights), `None` when `A` is singular or the solution is not finite.
pub fn solve_linear(a: DMatrix<f64>, b: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let w = a.lu().solve(b)?;
    w.iter().all(|v| v.is_finite()).then_some(w)
}

fn check_points(points: &DMatrix<f64>, which: &'static str) -> Result<(), CpdError> {
    if points.nrows() == 0 || points.ncols() == 0 {
        return Err(CpdError::Empty { which });
    }
    if !points.iter().all(|v| v.is_finite()) {
        return Err(CpdError::NotFinite { which });
    }
    Ok(())
}

/// Registers `source` (`M x D`) onto `target` (`N x D`). `initial_variance`
/// `None` starts from [`pairwise_variance`], as pycpd does.
pub fn register_deformable(
    target: &DMatrix<f64>,
    source: &DMatrix<f64>,
    initial_variance: Option<f64>,
    settings: &CpdSettings,
) -> Result<CpdOutcome, CpdError> {
    settings.validate()?;
    check_points(target, "target")?;
    check_points(source, "source")?;
    if target.ncols() != source.ncols() {
        return Err(CpdError::DimensionMismatch {
            source_dim: source.ncols(),
            target_dim: target.ncols(),
        });
    }
    let (m, n, d) = (source.nrows(), target.nrows(), target.ncols());
    let pairs = m.saturating_mul(n);
    if pairs > MAX_CPD_PAIRS {
        return Err(CpdError::TooLarge {
            pairs,
            max: MAX_CPD_PAIRS,
        });
    }
    let mut variance = match initial_variance {
        Some(v) if v > 0.0 && v.is_finite() => v,
        _ => pairwise_variance(target, source),
    };
    if !(variance > 0.0) {
        // Every point on every other: nothing to register.
        return Ok(CpdOutcome {
            points: source.clone(),
            variance: 0.0,
            iterations: 0,
            converged: true,
        });
    }
    let g = gaussian_kernel(source, settings.beta);
    let mut moved = source.clone();
    let mut change = f64::INFINITY;
    let mut iterations = 0;
    let mut p = DMatrix::zeros(m, n);
    while iterations < settings.max_iterations && change > settings.tolerance {
        let scale = 1.0 / (2.0 * variance);
        for i in 0..m {
            for j in 0..n {
                p[(i, j)] = math::exp(-(target.row(j) - moved.row(i)).norm_squared() * scale);
            }
        }
        let c = outlier_constant(variance, d, settings.outlier_weight, m, n);
        normalise_columns(&mut p, c);
        let r = Responsibilities::of(&p, target);
        let a = r.scale_rows(&g) + DMatrix::identity(m, m) * (settings.lambda * variance);
        let b = &r.px - r.scale_rows(source);
        let Some(w) = solve_linear(a, &b) else {
            return Ok(CpdOutcome {
                points: moved,
                variance,
                iterations,
                converged: false,
            });
        };
        moved = source + &g * w;
        let previous = variance;
        variance = r.variance(target, &moved);
        if !(variance > 0.0) {
            // pycpd's rule for a collapsed (or NaN) variance.
            variance = settings.tolerance / 10.0;
        }
        change = (variance - previous).abs();
        iterations += 1;
    }
    Ok(CpdOutcome {
        points: moved,
        variance,
        iterations,
        converged: change <= settings.tolerance,
    })
}

/// The CPD baseline's step: plain deformable CPD from the previous nodes,
/// `sigma^2` started from the data each frame; no occlusion handling beyond
/// its coherence.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CpdStep;

impl TrackingStep for CpdStep {
    type Settings = CpdSettings;
    type Report = ();
    const ALGORITHM: Algorithm = Algorithm::Cpd;

    fn start(&mut self, _nodes: &[Vec3]) {}

    fn step(&mut self, input: &StepInput<'_>, settings: &CpdSettings) -> StepOutput<()> {
        let y = points_to_matrix(input.previous);
        let x = points_to_matrix(&thin_to_pair_cap(input.cloud, input.previous.len()));
        // An empty cloud leaves the nodes where they were.
        let nodes = match register_deformable(&x, &y, None, settings) {
            Ok(out) => matrix_to_points(&out.points),
            Err(_) => input.previous.to_vec(),
        };
        StepOutput {
            nodes,
            visible: input.visible.to_vec(),
            report: (),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn cloud(rng: &mut SplitMix64, n: usize, d: usize) -> DMatrix<f64> {
        DMatrix::from_fn(n, d, |_, _| rng.range(-1.0, 1.0))
    }

    #[test]
    fn a_translated_copy_is_recovered() {
        let mut rng = SplitMix64::new(7);
        let y = cloud(&mut rng, 30, 3);
        let shift = DMatrix::from_fn(30, 3, |_, c| [0.1, -0.05, 0.02][c]);
        let x = &y + &shift;
        let s = CpdSettings {
            tolerance: 1e-10,
            max_iterations: 500,
            ..CpdSettings::PYCPD
        };
        let out = register_deformable(&x, &y, None, &s).expect("registers");
        let err = (&out.points - &x).abs().max();
        assert!(err < 1e-3, "max error {err}");
    }

    #[test]
    fn thinning_keeps_the_pairs_under_the_cap() {
        let points: alloc::vec::Vec<u32> = (0..10_000).collect();
        let thin = thin_to_pair_cap(&points, 1000);
        assert!(
            thin.len() * 1000 <= MAX_CPD_PAIRS && thin.len() >= 2000,
            "{}",
            thin.len()
        );
        assert_eq!(thin[0], 0);
        assert_eq!(thin_to_pair_cap(&points, 24).len(), 10_000);
        assert!(thin_to_pair_cap(&[] as &[u32], 0).is_empty());
    }

    #[test]
    fn bad_inputs_are_errors_not_panics() {
        let x = DMatrix::from_element(3, 2, 0.5);
        let empty = DMatrix::<f64>::zeros(0, 2);
        let s = CpdSettings::PYCPD;
        assert_eq!(
            register_deformable(&empty, &x, None, &s),
            Err(CpdError::Empty { which: "target" })
        );
        let y3 = DMatrix::from_element(3, 3, 0.5);
        assert!(matches!(
            register_deformable(&x, &y3, None, &s),
            Err(CpdError::DimensionMismatch { .. })
        ));
        let mut nan = x.clone();
        nan[(1, 1)] = f64::NAN;
        assert_eq!(
            register_deformable(&x, &nan, None, &s),
            Err(CpdError::NotFinite { which: "source" })
        );
        let bad = CpdSettings {
            outlier_weight: 1.0,
            ..s
        };
        assert!(matches!(
            register_deformable(&x, &x, None, &bad),
            Err(CpdError::Setting(ParamsError::OutOfRange {
                name: "cpd.outlier_weight",
                ..
            }))
        ));
        // Identical single points: nothing to do, no division by zero.
        let one = DMatrix::from_element(1, 2, 0.25);
        let out = register_deformable(&one, &one, None, &s).expect("trivial");
        assert_eq!(out.points, one);
    }
}
