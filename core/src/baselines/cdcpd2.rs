//! CDCPD2 (Wang et al., "Tracking partially-occluded deformable objects
//! while enforcing geometric constraints", ICRA 2021), reimplemented as a
//! baseline from its paper and a reading of its public source
//! (UM-ARM-Lab/cdcpd): each frame, CPD with a Gaussian kernel on the
//! initial template, an LLE term and a visibility prior on the nodes, then
//! a constrained step: the nodes nearest the CPD result with every edge no
//! longer than its rest length times a stretch factor and no node below the
//! table plane. The QP is solved with Clarabel (a pure-Rust interior-point
//! solver) in place of Gurobi; edge bounds are second-order cones, so the
//! problem is convex as CDCPD2 states it. Gripper constraints are not
//! implemented. Deviations from the source are listed in
//! `docs/algorithm-notes.md` ("CDCPD2 baseline").

use alloc::vec;
use alloc::vec::Vec;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SecondOrderConeT,
    SolverStatus, SupportedConeT,
};
use nalgebra::DMatrix;

use super::cpd::{matrix_to_points, points_to_matrix, solve_linear, thin_to_pair_cap};
use crate::math::{self, Vec3};
use crate::perception::evidence::Evidence;
pub use crate::perception::table::{fit_table, Plane};
use crate::step::{Algorithm, StepInput, StepOutput, TrackingStep};
use crate::validation::{below_one, check, non_negative, positive, ParamsError};

/// Most CPD iterations accepted.
pub const MAX_CDCPD2_ITERATIONS: u32 = 1000;

/// CDCPD2's parameters, with the values of its source (`CDCPD_Parameters`).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct Cdcpd2Settings {
    /// Smoothness weight of the CPD step (`alpha`). 0.5.
    pub alpha: f64,
    /// Weight of the LLE term (`lambda`, the source's gamma). 1.
    pub lambda: f64,
    /// Width of the Gaussian kernel on the initial template (`beta`), metres. 1.
    pub beta: f64,
    /// Weight that holds the nodes to their prediction (`zeta`; the
    /// prediction is the previous nodes, no gripper model). 10.
    pub zeta: f64,
    /// Outlier weight (`w`). 0.1.
    pub outlier_weight: f64,
    /// Strength of the visibility prior (`k_vis`). 1000.
    pub k_vis: f64,
    /// Neighbours of each node in the LLE weights. 8.
    pub lle_neighbours: usize,
    /// CPD stops when `sigma^2` changes by no more than this. 1e-4.
    pub tolerance: f64,
    /// Most CPD iterations. 100.
    pub max_iterations: u32,
    /// Start of `sigma^2` as a fraction of the all-pairs mean. 1/8.
    pub initial_sigma_scale: f64,
    /// An edge may be at most this times its rest length. 1 (the source's
    /// `start_lambda`).
    pub stretch_factor: f64,
    /// Keep the nodes above the table plane fitted to the depth image. true.
    pub table_constraint: bool,
}

impl Default for Cdcpd2Settings {
    /// The source's defaults (`CDCPD_Parameters()`).
    fn default() -> Self {
        Self {
            alpha: 0.5,
            lambda: 1.0,
            beta: 1.0,
            zeta: 10.0,
            outlier_weight: 0.1,
            k_vis: 1000.0,
            lle_neighbours: 8,
            tolerance: 1e-4,
            max_iterations: 100,
            initial_sigma_scale: 0.125,
            stretch_factor: 1.0,
            table_constraint: true,
        }
    }
}

impl Cdcpd2Settings {
    /// Checks every field (named `cdcpd2.<field>` in errors).
    pub fn validate(&self) -> Result<(), ParamsError> {
        positive("cdcpd2.beta", self.beta)?;
        positive("cdcpd2.tolerance", self.tolerance)?;
        positive("cdcpd2.initial_sigma_scale", self.initial_sigma_scale)?;
        non_negative("cdcpd2.alpha", self.alpha)?;
        non_negative("cdcpd2.lambda", self.lambda)?;
        non_negative("cdcpd2.zeta", self.zeta)?;
        non_negative("cdcpd2.k_vis", self.k_vis)?;
        let w = self.outlier_weight;
        below_one("cdcpd2.outlier_weight", w)?;
        let s = self.stretch_factor;
        check(
            "cdcpd2.stretch_factor",
            s,
            (1.0..=10.0).contains(&s),
            "in [1, 10]",
        )?;
        let k = self.lle_neighbours;
        check(
            "cdcpd2.lle_neighbours",
            k as f64,
            (1..=64).contains(&k),
            "an integer in 1..=64",
        )?;
        let it = self.max_iterations;
        check(
            "cdcpd2.max_iterations",
            it as f64,
            (1..=MAX_CDCPD2_ITERATIONS).contains(&it),
            "an integer in 1..=1000",
        )
    }
}

/// Locally linear embedding weights of the template: each node rebuilt from
/// its `k` nearest nodes in space (weights summing to one, Gram matrix
/// regularised by 1e-3 of its trace, as the source), and `H = (I - W)^T (I - W)`.
pub fn lle_matrix(template: &[Vec3], k: usize) -> DMatrix<f64> {
    let m = template.len();
    let k = k.min(m.saturating_sub(1));
    let mut w = DMatrix::zeros(m, m);
    for i in 0..m {
        let mut order: Vec<usize> = (0..m).filter(|&j| j != i).collect();
        order.sort_by(|&a, &b| {
            (template[a] - template[i])
                .norm_squared()
                .total_cmp(&(template[b] - template[i]).norm_squared())
                .then(a.cmp(&b))
        });
        let nb = &order[..k];
        if nb.is_empty() {
            continue;
        }
        let diffs: Vec<Vec3> = nb.iter().map(|&j| template[j] - template[i]).collect();
        let mut gram = DMatrix::from_fn(k, k, |a, b| diffs[a].dot(&diffs[b]));
        let tr = gram.trace();
        let reg = if tr > 0.0 { 1e-3 * tr } else { 1e-3 };
        for a in 0..k {
            gram[(a, a)] += reg;
        }
        let ones = DMatrix::from_element(k, 1, 1.0);
        let Some(x) = solve_linear(gram, &ones) else {
            continue;
        };
        let total = x.sum();
        if !(total.abs() > f64::EPSILON) {
            continue;
        }
        for (c, &j) in nb.iter().enumerate() {
            w[(i, j)] = x[c] / total;
        }
    }
    let i_w = DMatrix::identity(m, m) - w;
    i_w.transpose() * i_w
}

/// Cells of `DISTANCE_CELL x DISTANCE_CELL` pixels over which the distance
/// to the mask is computed (a cell is mask if any of its pixels is).
const DISTANCE_CELL: usize = 4;

/// Chamfer distance (in pixels, at cell resolution) from every cell to the
/// nearest mask cell, two passes with weights 1, sqrt 2 and sqrt 5 (a 5x5
/// mask, as the source's `cv::distanceTransform(..., DIST_L2, 5)`), on a
/// grid of `DISTANCE_CELL`-pixel cells; returns the grid and its width.
/// Infinite everywhere when the mask is empty.
fn distance_to_mask(evidence: &Evidence<'_>) -> (Vec<f64>, usize) {
    let mask = evidence.mask;
    let (fw, fh) = (mask.width as usize, mask.height as usize);
    let (w, h) = (fw.div_ceil(DISTANCE_CELL), fh.div_ceil(DISTANCE_CELL));
    let mut d = vec![f64::INFINITY; w * h];
    for (k, &m) in mask.data.iter().enumerate() {
        if m {
            let (u, v) = (k % fw / DISTANCE_CELL, k / fw / DISTANCE_CELL);
            d[v * w + u] = 0.0;
        }
    }
    let (a, b, c) = (1.0, core::f64::consts::SQRT_2, libm::sqrt(5.0));
    let offsets = [
        (-1i64, 0i64, a),
        (-1, -1, b),
        (0, -1, a),
        (1, -1, b),
        (-1, -2, c),
        (1, -2, c),
        (-2, -1, c),
        (2, -1, c),
    ];
    for rev in [false, true] {
        for step in 0..w * h {
            let k = if rev { w * h - 1 - step } else { step };
            let (u, v) = ((k % w) as i64, (k / w) as i64);
            let mut best = d[k];
            for &(du, dv, cost) in &offsets {
                let (x, y) = if rev {
                    (u - du, v - dv)
                } else {
                    (u + du, v + dv)
                };
                if x >= 0 && y >= 0 && (x as usize) < w && (y as usize) < h {
                    best = best.min(d[y as usize * w + x as usize] + cost);
                }
            }
            d[k] = best;
        }
    }
    for x in d.iter_mut() {
        *x *= DISTANCE_CELL as f64;
    }
    (d, w)
}

/// The visibility prior of each node (the source's Eq. 7): `exp(-k_vis s)`
/// with `s` its pixel's distance to the mask (normalised by the largest in
/// the image) times how far it lies behind the observed depth.
pub fn visibility_prior(nodes: &[Vec3], evidence: &Evidence<'_>, k_vis: f64) -> Vec<f64> {
    let f = evidence.frame;
    let (w, h) = (f.width as i64, f.height as i64);
    let (dist, dw) = distance_to_mask(evidence);
    let max = dist
        .iter()
        .copied()
        .filter(|d| d.is_finite())
        .fold(0.0, f64::max);
    nodes
        .iter()
        .map(|p| {
            let q = evidence.camera.project(p);
            let (u, v) = q.map_or((0, 0), |q| {
                (
                    (libm::floor(q.x) as i64).clamp(0, w - 1),
                    (libm::floor(q.y) as i64).clamp(1, h - 1),
                )
            });
            let k = (v * w + u) as usize;
            let cell = (v as usize / DISTANCE_CELL) * dw + u as usize / DISTANCE_CELL;
            let raw = f.depth[k];
            // No depth: the source's 2 cm.
            let behind = if raw == 0 {
                0.02
            } else {
                (p.z - raw as f64 * f.depth_scale).max(0.0)
            };
            let to_mask = if max > 0.0 && dist[cell].is_finite() {
                dist[cell] / max
            } else {
                1.0
            };
            math::exp(-k_vis * to_mask * behind)
        })
        .collect()
}

/// What one CDCPD2 step did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Cdcpd2Report {
    /// CPD iterations run.
    pub iterations: u32,
    /// `true` when the QP was solved (else the CPD result is kept).
    pub constrained: bool,
    /// Edges whose bound is active (within 0.1 % of it) after the QP.
    pub active_edges: usize,
    /// Nodes on the table plane after the QP (within 0.1 mm).
    pub on_table: usize,
}

/// The constrained step (the source's `Optimizer`): the nodes nearest
/// `target` with `|y_i - y_{i+1}| <= bound_i` for every edge and
/// `normal . y_i >= offset` for the table. `None` when the solver fails.
pub fn constrained_step(
    target: &[Vec3],
    bounds: &[f64],
    table: Option<Plane>,
) -> Option<Vec<Vec3>> {
    let m = target.len();
    let n = 3 * m;
    if m == 0 || bounds.len() + 1 != m {
        return None;
    }
    // Objective: sum |y - target|^2 = y^T I y - 2 target^T y + const (P = 2 I).
    let p = CscMatrix::new(n, n, (0..=n).collect(), (0..n).collect(), vec![2.0; n]);
    let q: Vec<f64> = target
        .iter()
        .flat_map(|t| [-2.0 * t.x, -2.0 * t.y, -2.0 * t.z])
        .collect();
    // Rows of A (s = b - A y): per edge a cone of four rows [bound; -(y_i - y_j)].
    let mut triplets: Vec<(usize, usize, f64)> = Vec::new();
    let mut b = Vec::new();
    let mut cones: Vec<SupportedConeT<f64>> = Vec::new();
    for (e, &bound) in bounds.iter().enumerate() {
        let row = b.len();
        b.push(bound);
        for d in 0..3 {
            triplets.push((row + 1 + d, 3 * e + d, 1.0));
            triplets.push((row + 1 + d, 3 * (e + 1) + d, -1.0));
            b.push(0.0);
        }
        cones.push(SecondOrderConeT(4));
    }
    if let Some(t) = table {
        let row = b.len();
        for i in 0..m {
            for d in 0..3 {
                triplets.push((row + i, 3 * i + d, -t.normal[d]));
            }
            b.push(-t.offset);
        }
        cones.push(NonnegativeConeT(m));
    }
    let rows = b.len();
    // Column-compressed A.
    triplets.sort_by_key(|t| (t.1, t.0));
    let mut colptr = vec![0usize; n + 1];
    for &(_, c, _) in &triplets {
        colptr[c + 1] += 1;
    }
    for c in 0..n {
        colptr[c + 1] += colptr[c];
    }
    let rowval: Vec<usize> = triplets.iter().map(|t| t.0).collect();
    let nzval: Vec<f64> = triplets.iter().map(|t| t.2).collect();
    let a = CscMatrix::new(rows, n, colptr, rowval, nzval);
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .build()
        .ok()?;
    let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings).ok()?;
    solver.solve();
    match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {}
        _ => return None,
    }
    let x = &solver.solution.x;
    let out: Vec<Vec3> = (0..m)
        .map(|i| Vec3::new(x[3 * i], x[3 * i + 1], x[3 * i + 2]))
        .collect();
    out.iter().all(math::is_finite).then_some(out)
}

/// CDCPD2's state: the initial template, its kernel and LLE matrices, and
/// the rest lengths of its edges.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Cdcpd2State {
    template: Vec<Vec3>,
    rest: Vec<f64>,
    lle_neighbours: usize,
    beta: f64,
    #[cfg_attr(feature = "serde", serde(skip))]
    cache: Option<(DMatrix<f64>, DMatrix<f64>)>,
}

impl Cdcpd2State {
    /// State for freshly initialised nodes.
    pub fn new(nodes: &[Vec3], s: &Cdcpd2Settings) -> Self {
        Self {
            template: nodes.to_vec(),
            rest: nodes
                .windows(2)
                .map(|w| math::norm(&(w[1] - w[0])))
                .collect(),
            lle_neighbours: s.lle_neighbours,
            beta: s.beta,
            cache: None,
        }
    }

    /// The kernel `G` and LLE matrix `H` of the template (computed once).
    fn matrices(&mut self) -> (DMatrix<f64>, DMatrix<f64>) {
        if self.cache.is_none() {
            let m = self.template.len();
            let t = &self.template;
            let b2 = 2.0 * self.beta * self.beta;
            let g = DMatrix::from_fn(m, m, |i, j| math::exp(-(t[i] - t[j]).norm_squared() / b2));
            let h = lle_matrix(t, self.lle_neighbours);
            self.cache = Some((g, h));
        }
        self.cache
            .clone()
            .unwrap_or_else(|| (DMatrix::zeros(0, 0), DMatrix::zeros(0, 0)))
    }

    /// The CPD part of a frame (the source's `cpd`): the nodes moved towards
    /// `cloud` with the kernel on the template, the LLE term, the hold to
    /// the prediction (the previous nodes) and the visibility prior, and the
    /// iterations run. `None` when there is nothing to register.
    pub fn cpd(
        &mut self,
        nodes: &[Vec3],
        cloud: &[Vec3],
        evidence: Option<&Evidence<'_>>,
        s: &Cdcpd2Settings,
    ) -> Option<(Vec<Vec3>, u32)> {
        let m = nodes.len();
        if self.template.len() != m
            || s.lle_neighbours != self.lle_neighbours
            || s.beta != self.beta
        {
            *self = Self::new(nodes, s);
        }
        let x_pts = thin_to_pair_cap(cloud, m);
        if m < 2 || x_pts.is_empty() {
            return None;
        }
        let (g, h) = self.matrices();
        let prior = match evidence {
            Some(e) if s.k_vis > 0.0 => visibility_prior(nodes, e, s.k_vis),
            _ => vec![1.0; m],
        };
        let x = points_to_matrix(&x_pts);
        let y = points_to_matrix(nodes);
        let n = x_pts.len();
        // sigma^2 from the all-pairs mean, scaled.
        let mut total = 0.0;
        for i in 0..n {
            for j in 0..m {
                total += (x.row(i) - y.row(j)).norm_squared();
            }
        }
        let mut sigma2 = (total / (n * m * 3) as f64 * s.initial_sigma_scale).max(1e-12);
        let mut ty = y.clone();
        let mut error = s.tolerance + 1.0;
        let mut it = 0;
        // The source loops while iterations <= max_iterations.
        while it <= s.max_iterations && error > s.tolerance {
            let previous = sigma2;
            let c = libm::pow(core::f64::consts::TAU * sigma2, 1.5) * s.outlier_weight
                / (1.0 - s.outlier_weight)
                * m as f64
                / n as f64;
            let mut p = DMatrix::from_fn(m, n, |i, j| {
                prior[i] * math::exp(-(x.row(j) - ty.row(i)).norm_squared() / (2.0 * sigma2))
            });
            for j in 0..n {
                let den: f64 = p.column(j).sum() + c;
                if den > 0.0 {
                    p.column_mut(j).iter_mut().for_each(|v| *v /= den);
                }
            }
            let p1: Vec<f64> = (0..m).map(|i| p.row(i).sum()).collect();
            let pt1: Vec<f64> = (0..n).map(|j| p.column(j).sum()).collect();
            let np: f64 = p1.iter().sum();
            if !(np > 0.0) {
                break;
            }
            let px = &p * &x;
            let d1 = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(p1.clone()));
            // A = diag(P1) G + alpha sigma^2 I + sigma^2 lambda H G + zeta G;
            // B = P X - (diag(P1) + sigma^2 lambda H) Y (the prediction is Y).
            let a = &d1 * &g
                + DMatrix::identity(m, m) * (s.alpha * sigma2)
                + &h * &g * (sigma2 * s.lambda)
                + &g * s.zeta;
            let b = &px - (&d1 + &h * (sigma2 * s.lambda)) * &y;
            let Some(w) = solve_linear(a, &b) else {
                break;
            };
            ty = &y + &g * w;
            let xpx: f64 = (0..n).map(|j| pt1[j] * x.row(j).norm_squared()).sum();
            let ypy: f64 = (0..m).map(|i| p1[i] * ty.row(i).norm_squared()).sum();
            let trpxy: f64 = ty.component_mul(&px).sum();
            sigma2 = (xpx - 2.0 * trpxy + ypy) / (np * 3.0);
            if !(sigma2 > 0.0) || !sigma2.is_finite() {
                sigma2 = s.tolerance / 10.0;
            }
            error = (sigma2 - previous).abs();
            it += 1;
        }
        let out = matrix_to_points(&ty);
        out.iter().all(math::is_finite).then_some((out, it))
    }

    /// One frame: [`Cdcpd2State::cpd`], then the constrained step. Moves
    /// `nodes` in place.
    pub fn step(
        &mut self,
        nodes: &mut [Vec3],
        cloud: &[Vec3],
        evidence: Option<&Evidence<'_>>,
        s: &Cdcpd2Settings,
    ) -> Cdcpd2Report {
        let mut report = Cdcpd2Report::default();
        let Some((cpd, iterations)) = self.cpd(nodes, cloud, evidence, s) else {
            return report;
        };
        report.iterations = iterations;
        let bounds: Vec<f64> = self.rest.iter().map(|l| l * s.stretch_factor).collect();
        let table = match (s.table_constraint, evidence) {
            (true, Some(e)) => fit_table(e),
            _ => None,
        };
        match constrained_step(&cpd, &bounds, table) {
            Some(out) => {
                report.constrained = true;
                report.active_edges = out
                    .windows(2)
                    .zip(&bounds)
                    .filter(|(w, &bd)| math::norm(&(w[1] - w[0])) >= bd * 0.999)
                    .count();
                report.on_table =
                    table.map_or(0, |t| out.iter().filter(|p| t.height(p) < 1e-4).count());
                nodes.copy_from_slice(&out);
            }
            None => nodes.copy_from_slice(&cpd),
        }
        report
    }
}

/// CDCPD2's step; its state is the template and its matrices.
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Cdcpd2Step {
    state: Option<Cdcpd2State>,
}

impl TrackingStep for Cdcpd2Step {
    type Settings = Cdcpd2Settings;
    type Report = Cdcpd2Report;
    const ALGORITHM: Algorithm = Algorithm::Cdcpd2;

    fn start(&mut self, _nodes: &[Vec3]) {
        // The template is taken at the first step, with the settings in force.
        self.state = None;
    }

    fn fits(&self, nodes: &[Vec3]) -> bool {
        self.state.as_ref().is_none_or(|s| {
            s.template.len() == nodes.len()
                && s.rest.len() + 1 == nodes.len()
                && s.template.iter().all(math::is_finite)
                && s.rest.iter().all(|r| r.is_finite())
                && s.beta.is_finite()
                && s.beta > 0.0
        })
    }

    fn step(
        &mut self,
        input: &StepInput<'_>,
        settings: &Cdcpd2Settings,
    ) -> StepOutput<Cdcpd2Report> {
        let state = self
            .state
            .get_or_insert_with(|| Cdcpd2State::new(input.previous, settings));
        let mut nodes = input.previous.to_vec();
        let report = state.step(&mut nodes, input.cloud, input.evidence.as_ref(), settings);
        StepOutput {
            nodes,
            visible: input.visible.to_vec(),
            report,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::camera::CameraIntrinsics;
    use crate::perception::frame::Frame;
    use crate::perception::segmentation::Mask;
    use crate::rng::SplitMix64;

    fn line(m: usize, step: f64) -> Vec<Vec3> {
        (0..m)
            .map(|i| Vec3::new(i as f64 * step, 0.0, 0.6))
            .collect()
    }

    #[test]
    fn the_qp_keeps_every_edge_within_its_bound_and_every_node_above_the_table() {
        let mut rng = SplitMix64::new(3);
        // A target stretched to 1.5 times its rest spacing, wobbling, half
        // of it pushed 1 cm below a table plane at z = 0.6 facing the camera.
        let rest = 0.02;
        let target: Vec<Vec3> = (0..12)
            .map(|i| {
                Vec3::new(
                    i as f64 * rest * 1.5,
                    0.004 * rng.normal(),
                    0.6 + if i % 2 == 0 { 0.01 } else { -0.005 },
                )
            })
            .collect();
        let bounds = vec![rest; 11];
        let table = Plane {
            normal: Vec3::new(0.0, 0.0, -1.0),
            offset: -0.6,
        };
        let out = constrained_step(&target, &bounds, Some(table)).expect("solved");
        for (w, b) in out.windows(2).zip(&bounds) {
            assert!(
                (w[1] - w[0]).norm() <= b + 1e-6,
                "edge {} > {b}",
                (w[1] - w[0]).norm()
            );
        }
        for p in &out {
            assert!(
                table.normal.dot(p) >= table.offset - 1e-6,
                "{p:?} below the table"
            );
        }
        // Tight: the stretched chain ends up at its full length.
        let len: f64 = out.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
        assert!(len > 0.99 * 11.0 * rest, "{len}");
    }

    #[test]
    fn with_no_constraint_active_the_qp_returns_the_cpd_result() {
        let target = line(10, 0.02);
        let loose = vec![0.05; 9];
        let out = constrained_step(&target, &loose, None).expect("solved");
        for (a, b) in out.iter().zip(&target) {
            assert!((a - b).norm() < 1e-6, "{a:?} vs {b:?}");
        }
        // And a whole step with loose bounds and no table moves the nodes
        // exactly as its CPD does: onto a cloud 5 mm off the line.
        let s = Cdcpd2Settings {
            stretch_factor: 10.0,
            table_constraint: false,
            ..Cdcpd2Settings::default()
        };
        let cloud: Vec<Vec3> = (0..90)
            .map(|k| Vec3::new(k as f64 * 0.18 / 89.0, 0.005, 0.6))
            .collect();
        let mut nodes = line(10, 0.02);
        let mut state = Cdcpd2State::new(&nodes, &s);
        let (cpd, _) = state.cpd(&nodes, &cloud, None, &s).expect("cpd");
        let r = state.step(&mut nodes, &cloud, None, &s);
        assert!(r.constrained && r.iterations > 0, "{r:?}");
        assert_eq!(r.active_edges, 0);
        for (a, b) in nodes.iter().zip(&cpd) {
            assert!((a - b).norm() < 1e-6, "{a:?} vs {b:?}");
        }
        // CPD moved them towards the points (zeta holds them back: not all the way).
        assert!(
            nodes.iter().all(|y| y.y > 0.001 && y.y <= 0.0051),
            "{nodes:?}"
        );
    }

    #[test]
    fn lle_rebuilds_a_straight_template() {
        let t = line(12, 0.02);
        let h = lle_matrix(&t, 8);
        let y = points_to_matrix(&t);
        // (I - W) Y is near zero where the neighbourhood is symmetric.
        let r = &h * &y;
        assert!(r.norm() < 1e-3, "{}", r.norm());
    }

    #[test]
    fn the_visibility_prior_trusts_nodes_on_the_rope_and_not_behind_a_surface_far_from_it() {
        let camera = CameraIntrinsics::D435I_640X480;
        let depth = vec![600u16; 640 * 480];
        let rgb = vec![0u8; 640 * 480 * 3];
        let frame = Frame::new(640, 480, &rgb, &depth, 0.001).expect("frame");
        let mut mask = Mask::new(640, 480);
        for u in 300..340 {
            mask.data[240 * 640 + u] = true;
        }
        let e = Evidence {
            frame: &frame,
            mask: &mask,
            occlusions: &[],
            camera: &camera,
            radius: 0.0075,
            others: None,
        };
        let at = |u: f64, v: f64, z: f64| camera.deproject(u, v, z);
        let p = visibility_prior(
            &[
                at(320.0, 240.0, 0.61),
                at(320.0, 400.0, 0.59),
                at(600.0, 50.0, 0.65),
            ],
            &e,
            1000.0,
        );
        // On the mask: 1 whatever the depth; in front of the table: 1; behind
        // it (5 cm) and far from the mask: nearly 0.
        assert!(
            (p[0] - 1.0).abs() < 1e-12 && (p[1] - 1.0).abs() < 1e-12,
            "{p:?}"
        );
        assert!(p[2] < 1e-6, "{p:?}");
    }

    #[test]
    fn bad_settings_are_refused_by_name() {
        let bad = Cdcpd2Settings {
            stretch_factor: 0.5,
            ..Cdcpd2Settings::default()
        };
        assert!(matches!(
            bad.validate(),
            Err(ParamsError::OutOfRange {
                name: "cdcpd2.stretch_factor",
                ..
            })
        ));
        assert!(Cdcpd2Settings::default().validate().is_ok());
    }
}
