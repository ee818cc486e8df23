//! TrackDLO's registration: CPD with the kernel on the distance along the
//! rope, geodesic responsibilities, an LLE term (the pre-registration of the
//! guide nodes), correspondence priors and the visibility weighting.

use alloc::vec::Vec;

use nalgebra::DMatrix;

use super::priors::Prior;
use crate::baselines::cpd::{
    matrix_to_points, normalise_columns, outlier_constant, pairwise_variance, points_to_matrix,
    solve_linear, thin_to_pair_cap, Responsibilities,
};
use crate::math::{self, Vec3};
use crate::polyline::arc_coordinates;

/// Points farther than this from every node are left out of a registration,
/// metres (the source's 0.1 m prefilter).
pub const POINT_REACH: f64 = 0.1;

/// Neighbours (`k`) of each node in the LLE weights: `k / 2` on each side
/// along the rope, as in the source.
pub const LLE_NEIGHBOURS: usize = 6;

/// Regularisation of the LLE Gram matrix, as a fraction of its trace
/// (Roweis and Saul's recipe; see the notes for why not the source's).
const LLE_REGULARISATION: f64 = 1e-3;
/// Floor of `sigma^2`, square metres: only guards the division.
const MIN_VARIANCE: f64 = 1e-10;
/// TrackDLO's kernel on the distance along the rope `d = |s_i - s_j|`:
/// `G = (2d + sqrt(2) beta) exp(-sqrt(2) d / beta) / (2 beta)^2`, a
/// Matern-type kernel that, unlike a Gaussian on Euclidean distance, keeps
/// two parts of the rope apart when they touch in space.
pub fn rope_kernel(s: &[f64], beta: f64) -> DMatrix<f64> {
    let m = s.len();
    let sqrt2 = core::f64::consts::SQRT_2;
    DMatrix::from_fn(m, m, |i, j| {
        let d = (s[i] - s[j]).abs();
        (2.0 * d + sqrt2 * beta) * math::exp(-sqrt2 * d / beta) / (4.0 * beta * beta)
    })
}

/// Locally linear embedding weights `L` (`M x M`): row `i` reconstructs node
/// `i` from its `LLE_NEIGHBOURS / 2` neighbours on each side along the rope,
/// with weights summing to one that minimise `|y_i - sum_j L_ij y_j|^2`.
pub fn lle_weights(nodes: &[Vec3]) -> DMatrix<f64> {
    let m = nodes.len();
    let half = LLE_NEIGHBOURS / 2;
    let mut l = DMatrix::zeros(m, m);
    for i in 0..m {
        let neighbours: Vec<usize> = (i.saturating_sub(half)..=(i + half).min(m.saturating_sub(1)))
            .filter(|&j| j != i)
            .collect();
        let k = neighbours.len();
        if k == 0 {
            continue;
        }
        let diffs: Vec<Vec3> = neighbours.iter().map(|&j| nodes[i] - nodes[j]).collect();
        let mut gram = DMatrix::from_fn(k, k, |a, b| diffs[a].dot(&diffs[b]));
        let trace = gram.trace();
        let reg = if trace > 0.0 {
            LLE_REGULARISATION * trace
        } else {
            1.0
        };
        for a in 0..k {
            gram[(a, a)] += reg;
        }
        let ones = DMatrix::from_element(k, 1, 1.0);
        let w = solve_linear(gram, &ones).unwrap_or_else(|| ones.clone());
        let total = w.sum();
        if !(total.abs() > f64::EPSILON) {
            continue;
        }
        for (c, &j) in neighbours.iter().enumerate() {
            l[(i, j)] = w[c] / total;
        }
    }
    l
}
/// Settings of one CPD-LLE registration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CpdLleSettings {
    /// Kernel width, metres.
    pub beta: f64,
    /// Smoothness weight.
    pub lambda: f64,
    /// Weight of the LLE term (0 leaves it out).
    pub lle_weight: f64,
    /// Weight of the correspondence priors.
    pub alpha: f64,
    /// Outlier weight.
    pub mu: f64,
    /// Most iterations.
    pub max_iterations: u32,
    /// Mean node displacement that ends the iteration, metres.
    pub tolerance: f64,
    /// Visibility weighting strength (0 turns it off).
    pub k_vis: f64,
    /// Distance within which a node counts as on the cloud, metres.
    pub visibility_threshold: f64,
}

/// What one CPD-LLE did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CpdLleReport {
    /// Iterations run.
    pub iterations: u32,
    /// `true` when the tolerance was met.
    pub converged: bool,
}

/// Squared Euclidean distances from every node (row) to every point (column).
fn squared_distances(nodes: &DMatrix<f64>, x: &DMatrix<f64>) -> DMatrix<f64> {
    DMatrix::from_fn(nodes.nrows(), x.nrows(), |i, j| {
        (nodes.row(i) - x.row(j)).norm_squared()
    })
}

/// Squared distances along the rope from each point to every node, from the
/// squared Euclidean ones `sq`: exact to the point's nearest node and its
/// nearer neighbour, then along the rope from whichever of the two is on the
/// node's side (the source's geodesic responsibilities).
fn geodesic_sq_distances(sq: &DMatrix<f64>, s: &[f64]) -> DMatrix<f64> {
    let (m, n) = sq.shape();
    let mut out = DMatrix::zeros(m, n);
    for j in 0..n {
        let dist = |i: usize| math::sqrt(sq[(i, j)]);
        let nearest = (0..m)
            .min_by(|&a, &b| dist(a).total_cmp(&dist(b)))
            .unwrap_or(0);
        if m == 1 {
            out[(0, j)] = dist(0) * dist(0);
            continue;
        }
        let second = match (
            nearest.checked_sub(1),
            (nearest + 1 < m).then_some(nearest + 1),
        ) {
            (Some(a), Some(b)) => {
                if dist(a) < dist(b) {
                    a
                } else {
                    b
                }
            }
            (Some(a), None) => a,
            (None, Some(b)) => b,
            (None, None) => nearest,
        };
        let (lo, hi) = if nearest < second {
            (nearest, second)
        } else {
            (second, nearest)
        };
        let (d_lo, d_hi) = (dist(lo), dist(hi));
        for i in 0..m {
            let d = if i <= lo {
                (s[lo] - s[i]).abs() + d_lo
            } else if i >= hi {
                (s[i] - s[hi]).abs() + d_hi
            } else {
                dist(i)
            };
            out[(i, j)] = d * d;
        }
    }
    out
}

/// CPD with TrackDLO's additions, moving `nodes` onto `cloud`: the kernel on
/// the distance along the rope, geodesic responsibilities, an LLE term,
/// correspondence priors and, when `visible` marks some nodes hidden, the
/// visibility weighting. `variance` is read (0 starts from the data) and updated.
pub fn cpd_lle(
    cloud: &[Vec3],
    nodes: &mut [Vec3],
    variance: &mut f64,
    settings: &CpdLleSettings,
    priors: &[Prior],
    visible: Option<&[bool]>,
) -> CpdLleReport {
    let m = nodes.len();
    let reachable: Vec<Vec3> = cloud
        .iter()
        .filter(|x| {
            nodes
                .iter()
                .any(|y| (*x - y).norm_squared() < POINT_REACH * POINT_REACH)
        })
        .copied()
        .collect();
    let near = thin_to_pair_cap(&reachable, m);
    let mut report = CpdLleReport {
        iterations: 0,
        converged: false,
    };
    if m == 0 || near.is_empty() {
        return report;
    }
    let x = points_to_matrix(&near);
    let n = near.len();
    let y0 = points_to_matrix(nodes);
    let s = arc_coordinates(nodes);
    let g = rope_kernel(&s, settings.beta);
    let h = if settings.lle_weight > 0.0 {
        let l = lle_weights(nodes);
        let i_l = DMatrix::identity(m, m) - l;
        Some(i_l.transpose() * i_l)
    } else {
        None
    };
    let mut j = DMatrix::zeros(m, m);
    let mut y_prior = y0.clone();
    for p in priors.iter().filter(|p| p.node < m) {
        j[(p.node, p.node)] = 1.0;
        for c in 0..3 {
            y_prior[(p.node, c)] = p.position[c];
        }
    }
    let weigh_visibility = settings.k_vis != 0.0
        && visible.is_some_and(|v| v.len() == m && v.iter().any(|&b| b) && !v.iter().all(|&b| b));
    if !(*variance > 0.0) || !variance.is_finite() {
        *variance = pairwise_variance(&x, &y0).max(MIN_VARIANCE);
    }
    let mut y = y0.clone();
    let t2 = settings.visibility_threshold * settings.visibility_threshold;
    for it in 0..settings.max_iterations {
        let sq = squared_distances(&y, &x);
        let mut p = geodesic_sq_distances(&sq, &s);
        let scale = 0.5 / *variance;
        p.iter_mut().for_each(|d| *d = math::exp(-*d * scale));
        let mut c = outlier_constant(*variance, 3, settings.mu, m, n);
        if weigh_visibility {
            let weights: Vec<f64> = (0..m)
                .map(|i| {
                    let d2 = sq.row(i).iter().copied().fold(f64::INFINITY, f64::min);
                    let d = if d2 <= t2 { 0.0 } else { math::sqrt(d2) };
                    math::exp(-settings.k_vis * d)
                })
                .collect();
            let total: f64 = weights.iter().sum();
            for (i, mut row) in p.row_iter_mut().enumerate() {
                row *= weights[i] / total;
            }
            // The source drops the M in c along with the weighting.
            c /= m as f64;
        }
        normalise_columns(&mut p, c);
        let r = Responsibilities::of(&p, &x);
        if !(r.total > 0.0) {
            break;
        }
        let mut a = r.scale_rows(&g) + DMatrix::identity(m, m) * (settings.lambda * *variance);
        let mut b = &r.px - r.scale_rows(&y0);
        if let Some(h) = &h {
            a += h * &g * (*variance * settings.lle_weight);
            b -= h * &y0 * (*variance * settings.lle_weight);
        }
        if !priors.is_empty() {
            a += &j * &g * settings.alpha;
            b += (&y_prior - &y0) * settings.alpha;
        }
        let Some(w) = solve_linear(a, &b) else {
            break;
        };
        let t = &y0 + &g * w;
        let v = r.variance(&x, &t);
        *variance = if v.is_finite() {
            v.max(MIN_VARIANCE)
        } else {
            MIN_VARIANCE
        };
        let moved: f64 = (0..m).map(|i| (t.row(i) - y.row(i)).norm()).sum::<f64>() / m as f64;
        y = t;
        report.iterations = it + 1;
        if moved < settings.tolerance {
            report.converged = true;
            break;
        }
    }
    for (node, p) in nodes.iter_mut().zip(matrix_to_points(&y)) {
        if math::is_finite(&p) {
            *node = p;
        }
    }
    report
}

#[cfg(test)]
mod tests {
    use super::super::settings::TrackDloParams;
    use super::super::testing::line;
    use super::*;

    #[test]
    fn kernel_is_symmetric_decreasing_and_follows_the_rope_not_space() {
        let beta = 0.35;
        let g = rope_kernel(&[0.0, 0.1, 0.2, 0.9], beta);
        // Values of upstream's `G` (trackdlo.cpp, line 233) at beta = 0.35,
        // computed separately in Python: d = 0, 0.1, 0.9.
        assert!((g[(0, 0)] - 1.010_152_544_552_210_8).abs() < 1e-12);
        assert!((g[(0, 1)] - 0.946_872_434_699_354).abs() < 1e-12);
        assert!((g[(0, 3)] - 0.123_381_088_535_025_77).abs() < 1e-12);
        assert_eq!(g[(1, 3)], g[(3, 1)]);
        assert!(g[(0, 0)] > g[(0, 1)] && g[(0, 1)] > g[(0, 2)] && g[(0, 2)] > g[(0, 3)]);
        // A U-shaped rope: the two ends are 2 cm apart in space but 0.5 m
        // apart along the rope, and the kernel sees the latter.
        let u: Vec<Vec3> = [
            (0.0, 0.0),
            (0.0, 0.1),
            (0.0, 0.2),
            (0.02, 0.2),
            (0.02, 0.1),
            (0.02, 0.0),
        ]
        .iter()
        .map(|&(x, y)| Vec3::new(x, y, 0.6))
        .collect();
        let s = arc_coordinates(&u);
        assert!((s[5] - 0.42).abs() < 1e-12);
        let g = rope_kernel(&s, beta);
        // G at d = 0.42 (Python, as above).
        assert!((g[(0, 5)] - 0.499_177_262_156_633).abs() < 1e-12);
        // On the 2 cm Euclidean distance the kernel would be twice as large.
        let euclidean = rope_kernel(&[0.0, 0.02], beta)[(0, 1)];
        assert!(g[(0, 5)] < 0.55 * euclidean, "{} vs {euclidean}", g[(0, 5)]);
    }

    #[test]
    fn lle_weights_sum_to_one_and_rebuild_a_line_and_an_arc() {
        let nodes = line(10, 0.02);
        let l = lle_weights(&nodes);
        for i in 0..10 {
            assert!((l.row(i).sum() - 1.0).abs() < 1e-9, "row {i}");
            let rebuilt = (0..10).fold(Vec3::zeros(), |acc, j| acc + nodes[j] * l[(i, j)]);
            // Exact where the neighbourhood is symmetric; the regularisation
            // costs a little where it is one-sided (the ends).
            let tol = if (3..=6).contains(&i) { 1e-9 } else { 1e-3 };
            assert!(
                (rebuilt - nodes[i]).norm() < tol,
                "node {i}: {}",
                (rebuilt - nodes[i]).norm()
            );
            assert_eq!(l[(i, i)], 0.0);
        }
        // An interior node of a uniform line weighs its neighbours symmetrically.
        assert!((l[(5, 4)] - l[(5, 6)]).abs() < 1e-9);
        assert!((l[(5, 2)] - l[(5, 8)]).abs() < 1e-9);
        assert_eq!(l[(5, 1)], 0.0);
        // On an arc of radius 0.1 m the reconstruction is close, not exact.
        let arc: Vec<Vec3> = (0..12)
            .map(|i| {
                let t = i as f64 * 0.15;
                Vec3::new(0.1 * libm::cos(t), 0.1 * libm::sin(t), 0.6)
            })
            .collect();
        let l = lle_weights(&arc);
        let rebuilt = (0..12).fold(Vec3::zeros(), |acc, j| acc + arc[j] * l[(6, j)]);
        assert!((rebuilt - arc[6]).norm() < 2e-3);
    }
    #[test]
    fn cpd_lle_follows_a_translated_rope() {
        let nodes = line(12, 0.02);
        let cloud: Vec<Vec3> = (0..60)
            .map(|k| Vec3::new(k as f64 * 0.22 / 59.0, 0.005, 0.6))
            .collect();
        let mut moved = nodes.clone();
        let mut variance = 0.0;
        let p = TrackDloParams::default();
        let s = CpdLleSettings {
            beta: p.beta,
            lambda: p.lambda,
            lle_weight: 0.0,
            alpha: p.alpha,
            mu: p.mu,
            max_iterations: p.max_iterations,
            tolerance: 1e-6,
            k_vis: 0.0,
            visibility_threshold: p.visibility_threshold,
        };
        let report = cpd_lle(&cloud, &mut moved, &mut variance, &s, &[], None);
        assert!(report.iterations > 0);
        for y in &moved {
            assert!((y.y - 0.005).abs() < 1e-3, "{y}");
        }
        assert!(variance > 0.0 && variance.is_finite());
    }

    #[test]
    fn cpd_lle_moves_hidden_nodes_to_their_priors() {
        // Nodes 0-7 see a cloud moved 5 mm in y; nodes 8-11 are hidden (no
        // points near them) and have priors 3 cm off the line.
        let nodes = line(12, 0.02);
        let cloud: Vec<Vec3> = (0..40)
            .map(|k| Vec3::new(k as f64 * 0.14 / 39.0, 0.005, 0.6))
            .collect();
        let visible: Vec<bool> = (0..12).map(|i| i < 8).collect();
        let priors: Vec<Prior> = (8..12)
            .map(|i| Prior {
                node: i,
                position: Vec3::new(i as f64 * 0.02, 0.03, 0.6),
            })
            .collect();
        let p = TrackDloParams::DEMO;
        let s = CpdLleSettings {
            beta: p.beta,
            lambda: p.lambda,
            lle_weight: 0.0,
            alpha: p.alpha,
            mu: p.mu,
            max_iterations: p.max_iterations,
            tolerance: p.tolerance,
            k_vis: p.k_vis,
            visibility_threshold: p.visibility_threshold,
        };
        let run = |priors: &[Prior]| {
            let mut moved = nodes.clone();
            let mut variance = 0.0;
            cpd_lle(
                &cloud,
                &mut moved,
                &mut variance,
                &s,
                priors,
                Some(&visible),
            );
            moved
        };
        let with = run(&priors);
        let without = run(&[]);
        let off = |ys: &[Vec3]| -> f64 {
            priors
                .iter()
                .map(|q| (ys[q.node] - q.position).norm())
                .sum::<f64>()
                / priors.len() as f64
        };
        let (d_with, d_without) = (off(&with), off(&without));
        assert!(d_with < 0.5 * d_without, "{d_with} vs {d_without}");
        // The far visible nodes still follow their points (the smooth
        // kernel lets the priors pull the ones next to the hidden part).
        for y in &with[..3] {
            assert!((y.y - 0.005).abs() < 3e-3, "{y}");
        }
    }
}
