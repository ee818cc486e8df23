//! TrackDLO (Xiang et al., RA-L 2023), reimplemented as a baseline from its
//! paper and its public source: node visibility with a self-occlusion test,
//! visible nodes extended across short gaps, a pre-registration of the
//! visible ("guide") nodes by CPD-LLE, correspondence priors from walking
//! along the guide nodes at the rest spacing (five occlusion cases), and a
//! final CPD on the distance along the rope with the priors and a visibility
//! weighting of the responsibilities. Deviations from the source are listed
//! in `docs/algorithm-notes.md` ("TrackDLO baseline").

use alloc::vec;
use alloc::vec::Vec;

use nalgebra::DMatrix;

use crate::camera::CameraIntrinsics;
use crate::cpd::{
    matrix_to_points, normalise_columns, outlier_constant, pairwise_variance, points_to_matrix,
    solve_linear, thin_to_pair_cap, Responsibilities,
};
use crate::math::{self, Vec2, Vec3};
use crate::params::{check, ParamsError};

/// Points farther than this from every node are left out of a registration,
/// metres (the source's 0.1 m prefilter).
pub const POINT_REACH: f64 = 0.1;

/// Neighbours (`k`) of each node in the LLE weights: `k / 2` on each side
/// along the rope, as in the source.
pub const LLE_NEIGHBOURS: usize = 6;

/// Regularisation of the LLE Gram matrix, as a fraction of its trace
/// (Roweis and Saul's recipe; see the notes for why not the source's).
const LLE_REGULARISATION: f64 = 1e-3;

/// A crossing this far (in segment fractions) past a segment's end still
/// counts as on it, so that rounding cannot stop a walk at a guide node.
const ROOT_SLACK: f64 = 1e-9;

/// Floor of `sigma^2`, square metres: only guards the division.
const MIN_VARIANCE: f64 = 1e-10;

/// Image width (pixels) at which [`TrackDloParams::dlo_pixel_width`] is given:
/// the 1280 x 720 stream of TrackDLO's evaluation.
pub const REFERENCE_IMAGE_WIDTH: f64 = 1280.0;

/// TrackDLO's parameters, with the values of its published evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct TrackDloParams {
    /// Width of the kernel on the distance along the rope (`beta`), metres. 0.35.
    pub beta: f64,
    /// Smoothness weight (`lambda`). 50000.
    pub lambda: f64,
    /// Weight of the correspondence priors (`alpha`). 3.
    pub alpha: f64,
    /// Outlier weight (`mu`). 0.1.
    pub mu: f64,
    /// Most iterations of each CPD-LLE. 50.
    pub max_iterations: u32,
    /// Stop when the mean node displacement of an iteration is below this, metres. 0.0002.
    pub tolerance: f64,
    /// Strength of the visibility weighting (`k_vis`), 1/metres. 50.
    pub k_vis: f64,
    /// Gaps between visible nodes up to this distance along the rope are
    /// taken as visible (`d_vis`), metres. 0.06.
    pub d_vis: f64,
    /// A node is visible when a point lies within this (`tau_vis`), metres. 0.008.
    pub visibility_threshold: f64,
    /// Projected rope width of the self-occlusion test (`w`), pixels at
    /// 1280 px image width, scaled to the camera's width. 40.
    pub dlo_pixel_width: f64,
    /// Kernel width of the pre-registration, metres. 3.
    pub beta_pre_proc: f64,
    /// Smoothness weight of the pre-registration. 1.
    pub lambda_pre_proc: f64,
    /// Weight of the LLE term of the pre-registration (`gamma`). 10.
    pub lle_weight: f64,
}

impl Default for TrackDloParams {
    /// TrackDLO's published evaluation values (its launch file).
    fn default() -> Self {
        Self {
            beta: 0.35,
            lambda: 50_000.0,
            alpha: 3.0,
            mu: 0.1,
            max_iterations: 50,
            tolerance: 0.0002,
            k_vis: 50.0,
            d_vis: 0.06,
            visibility_threshold: 0.008,
            dlo_pixel_width: 40.0,
            beta_pre_proc: 3.0,
            lambda_pre_proc: 1.0,
            lle_weight: 10.0,
        }
    }
}

impl TrackDloParams {
    /// Checks every field (named `trackdlo.<field>` in errors).
    pub fn validate(&self) -> Result<(), ParamsError> {
        let t = self;
        let positive = |name, v: f64| check(name, v, v > 0.0 && v <= 1e9, "in (0, 1e9]");
        positive("trackdlo.beta", t.beta)?;
        positive("trackdlo.lambda", t.lambda)?;
        positive("trackdlo.beta_pre_proc", t.beta_pre_proc)?;
        positive("trackdlo.lambda_pre_proc", t.lambda_pre_proc)?;
        positive("trackdlo.tolerance", t.tolerance)?;
        positive("trackdlo.visibility_threshold", t.visibility_threshold)?;
        let non_negative = |name, v: f64| check(name, v, (0.0..=1e9).contains(&v), "in [0, 1e9]");
        non_negative("trackdlo.alpha", t.alpha)?;
        non_negative("trackdlo.k_vis", t.k_vis)?;
        non_negative("trackdlo.d_vis", t.d_vis)?;
        non_negative("trackdlo.lle_weight", t.lle_weight)?;
        non_negative("trackdlo.dlo_pixel_width", t.dlo_pixel_width)?;
        check("trackdlo.mu", t.mu, (0.0..1.0).contains(&t.mu), "in [0, 1)")?;
        let it = t.max_iterations;
        check(
            "trackdlo.max_iterations",
            it as f64,
            (1..=crate::params::MAX_EM_ITERATIONS).contains(&it),
            "an integer in 1..=1000",
        )
    }
}

/// Cumulative distance along the polyline through `nodes`, from the first.
pub fn arc_coordinates(nodes: &[Vec3]) -> Vec<f64> {
    let mut s = Vec::with_capacity(nodes.len());
    let mut sum = 0.0;
    for (i, y) in nodes.iter().enumerate() {
        if i > 0 {
            sum += math::norm(&(y - nodes[i - 1]));
        }
        s.push(sum);
    }
    s
}

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

/// Visibility of each node (`tau_vis` and the self-occlusion test): a node
/// is visible when a cloud point lies within `visibility_threshold` and no
/// part of the rope nearer the camera covers it in the image. Edges are
/// taken nearest first; a node is covered when its pixel lies within half
/// the projected rope width of an edge taken before its own nearer edge.
pub fn node_visibility(
    nodes: &[Vec3],
    cloud: &[Vec3],
    camera: &CameraIntrinsics,
    params: &TrackDloParams,
) -> Vec<bool> {
    let m = nodes.len();
    let t2 = params.visibility_threshold * params.visibility_threshold;
    let near: Vec<bool> = nodes
        .iter()
        .map(|y| cloud.iter().any(|x| (x - y).norm_squared() <= t2))
        .collect();
    let pixels: Vec<Option<Vec2>> = nodes.iter().map(|y| camera.project(y)).collect();
    let half_width = 0.5 * params.dlo_pixel_width * f64::from(camera.width) / REFERENCE_IMAGE_WIDTH;
    // Edges by distance of their midpoints from the camera, nearest first.
    let mut order: Vec<usize> = (0..m.saturating_sub(1)).collect();
    let depth = |e: usize| math::norm(&((nodes[e] + nodes[e + 1]) * 0.5));
    order.sort_by(|&a, &b| depth(a).total_cmp(&depth(b)).then(a.cmp(&b)));
    let mut checked = vec![false; m];
    let mut visible = vec![false; m];
    for (rank, &e) in order.iter().enumerate() {
        for node in [e, e + 1] {
            if checked[node] {
                continue;
            }
            checked[node] = true;
            let covered = pixels[node].is_some_and(|p| {
                order[..rank]
                    .iter()
                    .any(|&f| match (pixels[f], pixels[f + 1]) {
                        (Some(a), Some(b)) => point_segment_distance(&p, &a, &b) <= half_width,
                        _ => false,
                    })
            });
            visible[node] = near[node] && pixels[node].is_some() && !covered;
        }
    }
    if m == 1 {
        visible[0] = near[0];
    }
    visible
}

fn point_segment_distance(p: &Vec2, a: &Vec2, b: &Vec2) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).norm()
}

/// Visible nodes with short gaps filled: the nodes between two visible nodes
/// at most `d_vis` apart along the rope (rest coordinates `rest`) count as visible.
pub fn extend_visible(visible: &[bool], rest: &[f64], d_vis: f64) -> Vec<bool> {
    let mut out = visible.to_vec();
    let seen: Vec<usize> = (0..visible.len()).filter(|&i| visible[i]).collect();
    for pair in seen.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        if b > a + 1 && (rest[b] - rest[a]).abs() <= d_vis {
            out[a..b].iter_mut().for_each(|v| *v = true);
        }
    }
    out
}

/// Which part of the rope is hidden: TrackDLO's five cases. The first node
/// is the head, the last the tail.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OcclusionCase {
    /// Every node visible (after short gaps are filled).
    None,
    /// Both ends visible, a middle part hidden.
    MidSection,
    /// The head visible, the tail hidden.
    Tail,
    /// The tail visible, the head hidden.
    Head,
    /// Both ends hidden.
    BothEnds,
}

/// The case of a visibility pattern, `None` when no node is visible.
pub fn occlusion_case(visible: &[bool]) -> Option<OcclusionCase> {
    let (&head, &tail) = (visible.first()?, visible.last()?);
    if !visible.iter().any(|&v| v) {
        return None;
    }
    Some(match (head, tail) {
        _ if visible.iter().all(|&v| v) => OcclusionCase::None,
        (true, true) => OcclusionCase::MidSection,
        (true, false) => OcclusionCase::Tail,
        (false, true) => OcclusionCase::Head,
        (false, false) => OcclusionCase::BothEnds,
    })
}

/// A correspondence prior: node `node` should be at `position`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prior {
    /// Node index.
    pub node: usize,
    /// Where the walk along the guide nodes placed it, metres.
    pub position: Vec3,
}

/// Where the sphere of radius `r` around `c` leaves the segment `a -> b`
/// going forward, if it does.
fn sphere_exit(a: &Vec3, b: &Vec3, c: &Vec3, r: f64) -> Option<Vec3> {
    let d = b - a;
    let f = a - c;
    let qa = d.norm_squared();
    if !(qa > math::LENGTH_EPSILON) {
        return None;
    }
    let qb = 2.0 * f.dot(&d);
    let qc = f.norm_squared() - r * r;
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 {
        return None;
    }
    let root = math::sqrt(disc);
    let t = [(-qb + root) / (2.0 * qa), (-qb - root) / (2.0 * qa)]
        .into_iter()
        .filter(|t| (-ROOT_SLACK..=1.0 + ROOT_SLACK).contains(t))
        .fold(None, |best: Option<f64>, t| {
            Some(best.map_or(t, |b| b.max(t)))
        })?
        .clamp(0.0, 1.0);
    let q = a + d * t;
    // A crossing behind the current centre is not progress.
    (math::norm(&(b - q)) <= math::norm(&(b - c)) + math::LENGTH_EPSILON).then_some(q)
}

/// Walks from guide node `start` along the run of consecutive guide nodes
/// in one direction, placing nodes one rest spacing apart (pure pursuit on
/// the guide polyline): the priors of TrackDLO's `traverse_euclidean`.
/// `guide_nodes[k]` is the node index of guide position `guide[k]`.
pub fn walk_priors(
    guide: &[Vec3],
    guide_nodes: &[usize],
    rest: &[f64],
    start: usize,
    forward: bool,
) -> Vec<Prior> {
    let Some(&first) = guide_nodes.get(start) else {
        return Vec::new();
    };
    // The run of consecutive nodes from `start`, in walking order.
    let mut run = vec![guide[start]];
    let mut k = start;
    loop {
        let next = if forward {
            k.checked_add(1)
        } else {
            k.checked_sub(1)
        };
        let Some(next) = next.filter(|&n| n < guide.len()) else {
            break;
        };
        let step_ok = if forward {
            guide_nodes[next] == guide_nodes[k] + 1
        } else {
            guide_nodes[next] + 1 == guide_nodes[k]
        };
        if !step_ok {
            break;
        }
        run.push(guide[next]);
        k = next;
    }
    let m = rest.len();
    let mut priors = vec![Prior {
        node: first,
        position: guide[start],
    }];
    let mut centre = guide[start];
    let mut node = first;
    let mut segment = 0;
    while segment + 1 < run.len() {
        let next = if forward {
            if node + 1 >= m {
                break;
            }
            node + 1
        } else {
            let Some(n) = node.checked_sub(1) else {
                break;
            };
            n
        };
        let spacing = (rest[next] - rest[node]).abs();
        let found = (segment..run.len() - 1)
            .find_map(|i| sphere_exit(&run[i], &run[i + 1], &centre, spacing).map(|q| (i, q)));
        let Some((i, q)) = found else {
            break;
        };
        segment = i;
        centre = q;
        node = next;
        priors.push(Prior { node, position: q });
    }
    priors
}

/// Averages priors given twice for one node; returns them by node index.
fn merge_priors(m: usize, lists: &[Vec<Prior>]) -> Vec<Prior> {
    let mut sum = vec![Vec3::zeros(); m];
    let mut count = vec![0u32; m];
    for p in lists.iter().flatten() {
        if p.node < m {
            sum[p.node] += p.position;
            count[p.node] += 1;
        }
    }
    (0..m)
        .filter(|&i| count[i] > 0)
        .map(|i| Prior {
            node: i,
            position: sum[i] / f64::from(count[i]),
        })
        .collect()
}

/// The correspondence priors of one frame. `guide` are the pre-registered
/// positions of the nodes marked in `extended`; `previous` the nodes before
/// it (to find the node that moved least when both ends are hidden).
pub fn correspondence_priors(
    extended: &[bool],
    guide: &[Vec3],
    previous: &[Vec3],
    rest: &[f64],
) -> (Option<OcclusionCase>, Vec<Prior>) {
    let m = extended.len();
    let guide_nodes: Vec<usize> = (0..m).filter(|&i| extended[i]).collect();
    let case = occlusion_case(extended);
    let Some(last) = guide_nodes.len().checked_sub(1) else {
        return (case, Vec::new());
    };
    let walk = |start, forward| walk_priors(guide, &guide_nodes, rest, start, forward);
    let lists = match case {
        None => Vec::new(),
        Some(OcclusionCase::None | OcclusionCase::MidSection) => {
            vec![walk(0, true), walk(last, false)]
        }
        Some(OcclusionCase::Tail) => vec![walk(0, true)],
        Some(OcclusionCase::Head) => vec![walk(last, false)],
        Some(OcclusionCase::BothEnds) => {
            let moved = |k: usize| math::norm(&(previous[guide_nodes[k]] - guide[k]));
            let anchor = (0..guide_nodes.len())
                .min_by(|&a, &b| moved(a).total_cmp(&moved(b)))
                .unwrap_or(0);
            vec![walk(anchor, true), walk(anchor, false)]
        }
    };
    (case, merge_priors(m, &lists))
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

/// What a TrackDLO step decided, for display and tests.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackDloReport {
    /// The occlusion case (`None` when no node was visible).
    pub case: Option<OcclusionCase>,
    /// Number of correspondence priors.
    pub priors: usize,
    /// The final registration.
    pub registration: CpdLleReport,
}

/// TrackDLO's state between frames: the rest coordinates along the rope and `sigma^2`.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TrackDloState {
    /// Distance of each node from the first along the rope at initialisation, metres.
    pub rest: Vec<f64>,
    /// `sigma^2` carried between frames (0: start from the data).
    pub variance: f64,
}

impl TrackDloState {
    /// State for freshly initialised nodes.
    pub fn new(nodes: &[Vec3]) -> Self {
        Self {
            rest: arc_coordinates(nodes),
            variance: 0.0,
        }
    }

    /// One frame: moves `nodes` onto `cloud`; returns the visibility of the
    /// nodes before the move and what was done.
    pub fn step(
        &mut self,
        nodes: &mut [Vec3],
        cloud: &[Vec3],
        camera: &CameraIntrinsics,
        params: &TrackDloParams,
    ) -> (Vec<bool>, TrackDloReport) {
        if self.rest.len() != nodes.len() {
            *self = Self::new(nodes);
        }
        let visible = node_visibility(nodes, cloud, camera, params);
        let extended = extend_visible(&visible, &self.rest, params.d_vis);
        let mut guide: Vec<Vec3> = (0..nodes.len())
            .filter(|&i| extended[i])
            .map(|i| nodes[i])
            .collect();
        let idle = TrackDloReport {
            case: None,
            priors: 0,
            registration: CpdLleReport {
                iterations: 0,
                converged: false,
            },
        };
        if guide.is_empty() {
            return (visible, idle);
        }
        let mut pre_variance = self.variance;
        let pre = CpdLleSettings {
            beta: params.beta_pre_proc,
            lambda: params.lambda_pre_proc,
            lle_weight: params.lle_weight,
            alpha: 0.0,
            mu: params.mu,
            max_iterations: params.max_iterations,
            tolerance: params.tolerance,
            k_vis: 0.0,
            visibility_threshold: params.visibility_threshold,
        };
        cpd_lle(cloud, &mut guide, &mut pre_variance, &pre, &[], None);
        let (case, priors) = correspondence_priors(&extended, &guide, nodes, &self.rest);
        let main = CpdLleSettings {
            beta: params.beta,
            lambda: params.lambda,
            lle_weight: 0.0,
            alpha: params.alpha,
            k_vis: params.k_vis,
            ..pre
        };
        let registration = cpd_lle(
            cloud,
            nodes,
            &mut self.variance,
            &main,
            &priors,
            Some(&extended),
        );
        (
            visible,
            TrackDloReport {
                case,
                priors: priors.len(),
                registration,
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(m: usize, spacing: f64) -> Vec<Vec3> {
        (0..m)
            .map(|i| Vec3::new(i as f64 * spacing, 0.0, 0.6))
            .collect()
    }

    fn mask(m: usize, hidden: &[usize]) -> Vec<bool> {
        (0..m).map(|i| !hidden.contains(&i)).collect()
    }

    #[test]
    fn kernel_is_symmetric_decreasing_and_follows_the_rope_not_space() {
        let beta = 0.35;
        let g = rope_kernel(&[0.0, 0.1, 0.2, 0.9], beta);
        let g0 = core::f64::consts::SQRT_2 * beta / (4.0 * beta * beta);
        assert!((g[(0, 0)] - g0).abs() < 1e-12);
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
        let d = 0.42;
        let sqrt2 = core::f64::consts::SQRT_2;
        let expect = (2.0 * d + sqrt2 * beta) * libm::exp(-sqrt2 * d / beta) / (4.0 * beta * beta);
        assert!((g[(0, 5)] - expect).abs() < 1e-12);
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
    fn short_gaps_are_filled_and_long_ones_kept() {
        let rest: Vec<f64> = (0..10).map(|i| i as f64 * 0.015).collect();
        let v = mask(10, &[3, 4, 7]);
        let e = extend_visible(&v, &rest, 0.06);
        assert_eq!(e, vec![true; 10]);
        let v = mask(10, &[2, 3, 4, 5, 6]);
        assert_eq!(extend_visible(&v, &rest, 0.06), v);
    }

    #[test]
    fn the_five_occlusion_cases_are_told_apart() {
        assert_eq!(occlusion_case(&mask(6, &[])), Some(OcclusionCase::None));
        assert_eq!(
            occlusion_case(&mask(6, &[2, 3])),
            Some(OcclusionCase::MidSection)
        );
        assert_eq!(occlusion_case(&mask(6, &[4, 5])), Some(OcclusionCase::Tail));
        assert_eq!(occlusion_case(&mask(6, &[0, 1])), Some(OcclusionCase::Head));
        assert_eq!(
            occlusion_case(&mask(6, &[0, 5])),
            Some(OcclusionCase::BothEnds)
        );
        assert_eq!(occlusion_case(&[false; 6]), None);
        assert_eq!(occlusion_case(&[]), None);
    }

    /// Priors of a hand-made case: 10 nodes at 2 cm rest spacing; the
    /// visible part has been pre-registered to `guide` (given for the nodes
    /// marked visible).
    fn priors_for(hidden: &[usize], guide_of: impl Fn(usize) -> Vec3) -> Vec<Prior> {
        let m = 10;
        let rest: Vec<f64> = (0..m).map(|i| i as f64 * 0.02).collect();
        let ext = mask(m, hidden);
        let previous = line(m, 0.02);
        let guide: Vec<Vec3> = (0..m).filter(|&i| ext[i]).map(&guide_of).collect();
        correspondence_priors(&ext, &guide, &previous, &rest).1
    }

    #[test]
    fn no_occlusion_priors_respace_a_slid_rope_at_rest_spacing() {
        // The visible rope moved 5 mm along itself and got 1 cm longer at
        // the tail: the walks from both ends place nodes 2 cm apart and
        // the merge averages them.
        let priors = priors_for(&[], |i| {
            Vec3::new(0.005 + i as f64 * 0.02 * (1.0 + 0.01 / 0.18), 0.0, 0.6)
        });
        assert_eq!(priors.len(), 10);
        // Head walk: 0.005 + 0.02 i; tail walk: 0.195 - 0.02 (9 - i).
        let head = priors[0].position.x;
        let tail = priors[9].position.x;
        assert!((head - 0.01).abs() < 1e-9 && (tail - 0.19).abs() < 1e-9);
        for w in priors.windows(2) {
            let gap = (w[1].position - w[0].position).norm();
            assert!((gap - 0.02).abs() < 1e-9, "gap {gap}");
        }
    }

    #[test]
    fn mid_section_priors_come_from_both_ends_and_stop_at_the_gap() {
        let priors = priors_for(&[4, 5, 6], |i| Vec3::new(i as f64 * 0.02, 0.01, 0.6));
        let nodes: Vec<usize> = priors.iter().map(|p| p.node).collect();
        assert_eq!(nodes, vec![0, 1, 2, 3, 7, 8, 9]);
        for p in &priors {
            assert!((p.position - Vec3::new(p.node as f64 * 0.02, 0.01, 0.6)).norm() < 1e-9);
        }
    }

    #[test]
    fn tail_occluded_priors_walk_from_the_head_only() {
        let priors = priors_for(&[6, 7, 8, 9], |i| Vec3::new(0.0, i as f64 * 0.02, 0.6));
        let nodes: Vec<usize> = priors.iter().map(|p| p.node).collect();
        assert_eq!(nodes, vec![0, 1, 2, 3, 4, 5]);
        assert!((priors[5].position.y - 0.10).abs() < 1e-9);
    }

    #[test]
    fn head_occluded_priors_walk_from_the_tail_only() {
        // The visible part is compressed (nodes 1.5 cm apart): walking at
        // the 2 cm rest spacing from the tail yields fewer priors than
        // visible nodes, none of them at a compressed spacing.
        let priors = priors_for(&[0, 1, 2, 3], |i| Vec3::new(i as f64 * 0.015, 0.0, 0.6));
        let nodes: Vec<usize> = priors.iter().map(|p| p.node).collect();
        assert_eq!(nodes, vec![6, 7, 8, 9]);
        assert!((priors[0].position.x - 0.075).abs() < 1e-9);
        for w in priors.windows(2) {
            assert!(((w[1].position - w[0].position).norm() - 0.02).abs() < 1e-9);
        }
    }

    #[test]
    fn both_ends_occluded_priors_grow_from_the_node_that_moved_least() {
        // Nodes 2..=7 visible; the guide moved 1 cm in y except node 4, which stayed.
        let priors = priors_for(&[0, 1, 8, 9], |i| {
            let dy = if i == 4 { 0.0 } else { 0.01 };
            Vec3::new(i as f64 * 0.02, dy, 0.6)
        });
        let nodes: Vec<usize> = priors.iter().map(|p| p.node).collect();
        assert!(nodes.contains(&4) && nodes.contains(&2) && nodes.contains(&7));
        let anchor = priors.iter().find(|p| p.node == 4).map(|p| p.position);
        assert_eq!(anchor, Some(Vec3::new(0.08, 0.0, 0.6)));
        assert!(nodes.iter().all(|&n| (2..=7).contains(&n)));
    }

    #[test]
    fn a_node_behind_a_nearer_part_of_the_rope_is_not_visible() {
        let camera = CameraIntrinsics::D435I_640X480;
        // A rope crossing over itself: the middle passes 5 cm nearer the
        // camera over the line of the first part.
        let mut nodes: Vec<Vec3> = (0..5)
            .map(|i| Vec3::new(-0.04 + i as f64 * 0.02, 0.0, 0.6))
            .collect();
        nodes.extend((0..5).map(|i| Vec3::new(0.0, -0.04 + i as f64 * 0.02, 0.55)));
        let cloud = nodes.clone();
        let v = node_visibility(&nodes, &cloud, &camera, &TrackDloParams::default());
        // Node 2 (0, 0, 0.6) lies under node 7 (0, 0, 0.55).
        assert!(!v[2]);
        assert!(v[7] && v[0] && v[9]);
        // Without the nearer part, node 2 is visible.
        let v = node_visibility(&nodes[..5], &cloud, &camera, &TrackDloParams::default());
        assert!(v.iter().all(|&b| b));
    }

    #[test]
    fn cpd_lle_follows_a_translated_rope_and_keeps_hidden_nodes_with_priors() {
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
    fn a_step_with_no_points_leaves_the_nodes_alone() {
        let mut nodes = line(8, 0.02);
        let before = nodes.clone();
        let mut state = TrackDloState::new(&nodes);
        let (visible, report) = state.step(
            &mut nodes,
            &[],
            &CameraIntrinsics::D435I_640X480,
            &TrackDloParams::default(),
        );
        assert_eq!(nodes, before);
        assert!(visible.iter().all(|&v| !v));
        assert_eq!(report.case, None);
    }
}
