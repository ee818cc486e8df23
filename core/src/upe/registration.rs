//! GMM-EM registration of the visible nodes to the cloud (Eq. 1-5, with the
//! corrections of the project's algorithm notes): each visible node is the
//! mean of an isotropic Gaussian of shared variance `sigma^2`, plus one
//! uniform outlier component of weight `w`. Hidden nodes take no part.

use alloc::vec;
use alloc::vec::Vec;

use crate::math::{self, Vec3};
use crate::polyline::polyline_length;

/// Most EM iterations accepted per frame.
pub const MAX_EM_ITERATIONS: u32 = 1000;

/// Dimension of the points (`D` in the paper).
const DIM: f64 = 3.0;

/// Beyond this many `2 sigma^2`, a Gaussian term is taken as zero:
/// `exp(-20)` is 2e-9 of the term of a node at the point itself, below what
/// changes a responsibility in its eighth digit.
const EXPONENT_CUTOFF: f64 = 20.0;

/// Candidate lists are kept while no node has moved more than this fraction
/// of the cutoff's reach since they were built. A speed setting only (the
/// terms are the same for any margin): wider lists cost more tests per
/// point, narrower ones more rebuilds. 0.5 was the fastest of 0.25, 0.5
/// and 1 on every one of six sequences (EM 4-23 % faster than 0.25).
const CANDIDATE_MARGIN_FRACTION: f64 = 0.5;

/// A node whose total responsibility is below this keeps its position.
const MIN_RESPONSIBILITY: f64 = 1e-9;

/// Settings of one registration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EmSettings {
    /// Weight `w` of the uniform outlier component, in `[0, 1)`.
    pub outlier_weight: f64,
    /// Stop when no node moves more than this in one iteration, metres.
    pub tolerance: f64,
    /// Most EM iterations.
    pub max_iterations: u32,
    /// Floor of `sigma^2`, square metres.
    pub min_variance: f64,
}

/// What one registration did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EmReport {
    /// Iterations run.
    pub iterations: u32,
    /// Final `sigma^2`, square metres.
    pub variance: f64,
    /// `true` when the tolerance was met before the iteration cap.
    pub converged: bool,
}

/// Starting `sigma^2`: the mean squared distance from each point to its
/// nearest participating node, per dimension, over the points within a
/// node spacing of one (a point farther is not the rope near any node: a
/// thin distractor beside the rope, whose few points would otherwise raise
/// the start to its cap and let the end nodes follow it), kept between the
/// floor and the square of the mean node spacing (a larger start would let unregularised
/// nodes collapse onto the cloud's centroid).
pub fn initial_variance(cloud: &[Vec3], nodes: &[Vec3], active: &[bool], min_variance: f64) -> f64 {
    // The nodes' coordinates in three arrays, so that the nearest-node
    // search over them vectorises.
    let (mut xs, mut ys, mut zs) = (Vec::new(), Vec::new(), Vec::new());
    for (y, _) in nodes.iter().zip(active).filter(|(_, &a)| a) {
        xs.push(y.x);
        ys.push(y.y);
        zs.push(y.z);
    }
    let cap = if nodes.len() > 1 {
        let spacing = polyline_length(nodes) / (nodes.len() - 1) as f64;
        (spacing * spacing).max(min_variance)
    } else {
        f64::INFINITY
    };
    let mut sum = 0.0;
    let mut n = 0usize;
    for x in cloud {
        let mut d2 = f64::INFINITY;
        for ((&nx, &ny), &nz) in xs.iter().zip(&ys).zip(&zs) {
            let (dx, dy, dz) = (x.x - nx, x.y - ny, x.z - nz);
            d2 = d2.min(dx * dx + dy * dy + dz * dz);
        }
        if d2 <= cap {
            sum += d2;
            n += 1;
        }
    }
    if n == 0 {
        return cap;
    }
    (sum / (n as f64 * DIM)).clamp(min_variance, cap)
}

/// The weight of the outlier component in the E-step's denominator (Eq. 4):
/// `mu = (2 pi sigma^2)^(D/2) w K / ((1 - w) N)` for `K` nodes and `N` points.
pub fn outlier_term(variance: f64, outlier_weight: f64, nodes: usize, points: usize) -> f64 {
    libm::pow(core::f64::consts::TAU * variance, DIM / 2.0) * outlier_weight * nodes as f64
        / ((1.0 - outlier_weight) * points as f64)
}

/// The responsibilities of the `nodes` for the point `x` (Eq. 4), as
/// `(node, P(m|x))` for the terms inside the cutoff the registration uses.
pub fn responsibilities(x: &Vec3, nodes: &[Vec3], variance: f64, mu: f64) -> Vec<(usize, f64)> {
    let inv_two_var = 0.5 / variance;
    let mut terms: Vec<(usize, f64)> = nodes
        .iter()
        .enumerate()
        .filter_map(|(m, y)| {
            let e = (x - y).norm_squared() * inv_two_var;
            (e < EXPONENT_CUTOFF).then(|| (m, math::exp_neg(e)))
        })
        .collect();
    let denom = mu + terms.iter().map(|t| t.1).sum::<f64>();
    if !(denom > 0.0) {
        return Vec::new();
    }
    terms.iter_mut().for_each(|t| t.1 /= denom);
    terms
}

/// The state at the start of one EM iteration, as [`register_observed`]
/// reports it.
#[derive(Debug, Clone, Copy)]
pub struct EmIteration<'a> {
    /// 1 for the first iteration.
    pub iteration: u32,
    /// `sigma^2` of this iteration's E-step, square metres.
    pub variance: f64,
    /// `mu` of this iteration's E-step.
    pub outlier_term: f64,
    /// Every node (hidden ones too) before this iteration's M-step.
    pub nodes: &'a [Vec3],
}

/// Registers the nodes marked `active` to `cloud` in place (Eq. 4-5).
///
/// E-step: `P(m|x) = exp(-|x - y_m|^2 / 2 sigma^2) / (sum_k exp(...) + mu)`,
/// `mu = (2 pi sigma^2)^(D/2) w K / ((1 - w) N)` for `K` active nodes and
/// `N` points. M-step: `y_m = sum_n P x_n / sum_n P` and
/// `sigma^2 = sum P |x - y|^2 / (D sum P)`.
pub fn register(
    cloud: &[Vec3],
    nodes: &mut [Vec3],
    active: &[bool],
    settings: &EmSettings,
) -> EmReport {
    register_observed(cloud, nodes, active, &[], settings, &mut |_| {})
}

/// [`register`] with the nodes marked `fixed` (and not `active`) taking part
/// in the E-step as components that explain the points near them and never
/// move (`K` counts them; `sigma^2` is the active nodes'), telling `observe`
/// the state at the start of every iteration.
pub fn register_observed(
    cloud: &[Vec3],
    nodes: &mut [Vec3],
    active: &[bool],
    fixed: &[bool],
    settings: &EmSettings,
    observe: &mut dyn FnMut(EmIteration<'_>),
) -> EmReport {
    let participating: Vec<bool> = (0..nodes.len())
        .map(|m| active.get(m).copied().unwrap_or(false) && math::is_finite(&nodes[m]))
        .collect();
    // The E-step's components: the moving nodes, and the fixed ones.
    let idx: Vec<usize> = (0..nodes.len())
        .filter(|&m| {
            participating[m]
                || (fixed.get(m).copied().unwrap_or(false) && math::is_finite(&nodes[m]))
        })
        .collect();
    let moves: Vec<bool> = idx.iter().map(|&m| participating[m]).collect();
    let mut variance = settings.min_variance;
    if !participating.contains(&true) || cloud.is_empty() {
        return EmReport {
            iterations: 0,
            variance,
            converged: true,
        };
    }
    variance = initial_variance(cloud, nodes, &participating, settings.min_variance);
    let k = idx.len();
    let w = settings.outlier_weight;

    let mut p1 = vec![0.0; k];
    let mut px = vec![Vec3::zeros(); k];
    let mut pxx = vec![0.0; k];
    let mut near: Vec<(usize, f64)> = Vec::with_capacity(k);
    let mut anchor: Vec<Vec3> = Vec::with_capacity(k);
    let mut at: Vec<Vec3> = Vec::with_capacity(k);
    let mut offsets: Vec<u32> = Vec::with_capacity(cloud.len() + 1);
    let mut candidates: Vec<u16> = Vec::new();
    let (mut rebuild, mut built_variance, mut margin) = (true, 0.0, 0.0);
    let mut iterations = 0;
    let mut converged = false;

    while iterations < settings.max_iterations {
        iterations += 1;
        p1.fill(0.0);
        px.fill(Vec3::zeros());
        pxx.fill(0.0);
        let inv_two_var = 0.5 / variance;
        let mu = outlier_term(variance, w, k, cloud.len());
        observe(EmIteration {
            iteration: iterations,
            variance,
            outlier_term: mu,
            nodes,
        });
        debug_assert!(k <= u16::MAX as usize);
        // Candidate nodes per point: those within the cutoff's reach plus a
        // margin when the lists were built. A node left out was farther than
        // reach + margin then, has moved less than the margin since, and the
        // reach has not grown, so its term would be cut off anyway.
        let reach = math::sqrt(2.0 * variance * EXPONENT_CUTOFF);
        // The components' positions in E-step order, read once.
        at.clear();
        at.extend(idx.iter().map(|&m| nodes[m]));
        let moved = anchor
            .iter()
            .zip(&at)
            .map(|(a, y)| (y - a).norm_squared())
            .fold(0.0, f64::max);
        if rebuild || variance > built_variance || moved > margin * margin {
            built_variance = variance;
            margin = CANDIDATE_MARGIN_FRACTION * reach;
            anchor.clone_from(&at);
            let r2 = (reach + margin) * (reach + margin);
            offsets.clear();
            candidates.clear();
            for x in cloud {
                offsets.push(candidates.len() as u32);
                for (j, y) in anchor.iter().enumerate() {
                    if (x - y).norm_squared() < r2 {
                        candidates.push(j as u16);
                    }
                }
            }
            offsets.push(candidates.len() as u32);
            rebuild = false;
        }

        for (i, x) in cloud.iter().enumerate() {
            let mut denom = mu;
            near.clear();
            for &j in &candidates[offsets[i] as usize..offsets[i + 1] as usize] {
                let j = j as usize;
                let ej = (x - at[j]).norm_squared() * inv_two_var;
                if ej < EXPONENT_CUTOFF {
                    let gj = math::exp_neg(ej);
                    denom += gj;
                    near.push((j, gj));
                }
            }
            if near.is_empty() || !(denom > 0.0) {
                continue;
            }
            let x2 = x.norm_squared();
            let inv_denom = 1.0 / denom;
            for &(j, gj) in &near {
                let p = gj * inv_denom;
                p1[j] += p;
                px[j] += x * p;
                pxx[j] += p * x2;
            }
        }

        let mut max_shift2: f64 = 0.0;
        let mut spread = 0.0;
        let mut total = 0.0;
        for (j, &m) in idx.iter().enumerate() {
            if moves[j] && p1[j] > MIN_RESPONSIBILITY {
                let y = px[j] / p1[j];
                max_shift2 = max_shift2.max((y - nodes[m]).norm_squared());
                nodes[m] = y;
                // sum_n P |x_n - y|^2 with y the weighted mean.
                spread += (pxx[j] - px[j].norm_squared() / p1[j]).max(0.0);
                total += p1[j];
            }
        }
        if total > MIN_RESPONSIBILITY {
            let v = spread / (DIM * total);
            variance = if v.is_finite() {
                v.max(settings.min_variance)
            } else {
                settings.min_variance
            };
        }
        if math::sqrt(max_shift2) < settings.tolerance {
            converged = true;
            break;
        }
    }
    EmReport {
        iterations,
        variance,
        converged,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn settings() -> EmSettings {
        EmSettings {
            outlier_weight: 0.1,
            tolerance: 1e-7,
            max_iterations: 200,
            min_variance: 1e-8,
        }
    }

    #[test]
    fn one_node_moves_to_the_mean_of_a_symmetric_cluster() {
        // Four points symmetric about (1, 1, 1); a node started nearby ends
        // at their mean, which the weighted mean gives exactly by symmetry.
        let c = Vec3::new(1.0, 1.0, 1.0);
        let cloud = [
            c + Vec3::new(0.01, 0.0, 0.0),
            c - Vec3::new(0.01, 0.0, 0.0),
            c + Vec3::new(0.0, 0.01, 0.0),
            c - Vec3::new(0.0, 0.01, 0.0),
        ];
        let mut nodes = [c + Vec3::new(0.002, -0.001, 0.0)];
        let r = register(&cloud, &mut nodes, &[true], &settings());
        assert!(r.converged);
        assert!((nodes[0] - c).norm() < 1e-6, "{:?}", nodes[0]);
        // sigma^2 = mean squared distance / D = 1e-4 / 3.
        assert!((r.variance - 1e-4 / 3.0).abs() < 1e-7, "{}", r.variance);
    }

    #[test]
    fn hidden_nodes_do_not_move_or_absorb_points() {
        let cloud: Vec<Vec3> = (0..20)
            .map(|i| Vec3::new(i as f64 * 0.001, 0.0, 0.6))
            .collect();
        let hidden = Vec3::new(0.0105, 0.0, 0.6);
        let mut nodes = [Vec3::new(0.005, 0.003, 0.6), hidden];
        register(&cloud, &mut nodes, &[true, false], &settings());
        assert_eq!(nodes[1], hidden);
        // The visible node takes the whole cloud: it ends at its mean x.
        assert!((nodes[0].x - 0.0095).abs() < 1e-4, "{:?}", nodes[0]);
        assert!(nodes[0].y.abs() < 1e-4);
    }

    /// Regression for "a tail hidden by the relative visibility test hands
    /// its points to the last visible node, which runs 21 cm into it"
    /// (librealsense recordings, last frame).
    #[test]
    fn hidden_nodes_absorb_their_points_and_do_not_pull_the_visible_ones() {
        // The visible node's own points around x = 0; a few points around
        // the hidden node at x = 30 mm.
        let mut cloud: Vec<Vec3> = (-5..=5)
            .map(|i| Vec3::new(i as f64 * 0.001, 0.0, 0.6))
            .collect();
        cloud.extend((-1..=1).map(|i| Vec3::new(0.03 + i as f64 * 0.001, 0.0, 0.6)));
        let hidden = Vec3::new(0.03, 0.0, 0.6);
        let start = [Vec3::new(0.002, 0.0, 0.6), hidden];
        let mut nodes = start;
        let (active, fixed) = ([true, false], [false, true]);
        register_observed(
            &cloud,
            &mut nodes,
            &active,
            &fixed,
            &settings(),
            &mut |_| {},
        );
        assert_eq!(nodes[1], hidden);
        assert!(nodes[0].x.abs() < 1e-4, "{:?}", nodes[0]);
        // The paper's EM: the visible node takes the hidden node's points too.
        let mut nodes = start;
        register(&cloud, &mut nodes, &[true, false], &settings());
        assert!(nodes[0].x > 0.004, "{:?}", nodes[0]);
    }

    #[test]
    fn two_nodes_split_two_clusters() {
        let mut cloud = Vec::new();
        let mut rng = SplitMix64::new(3);
        for _ in 0..50 {
            cloud.push(Vec3::new(rng.normal() * 0.002, rng.normal() * 0.002, 0.6));
            cloud.push(Vec3::new(
                0.05 + rng.normal() * 0.002,
                rng.normal() * 0.002,
                0.6,
            ));
        }
        let mut nodes = [Vec3::new(0.008, 0.0, 0.6), Vec3::new(0.04, 0.0, 0.6)];
        register(&cloud, &mut nodes, &[true, true], &settings());
        assert!(
            nodes[0].x.abs() < 1e-3 && (nodes[1].x - 0.05).abs() < 1e-3,
            "{nodes:?}"
        );
    }

    #[test]
    fn empty_inputs_leave_nodes_as_they_are() {
        let mut nodes = [Vec3::new(1.0, 2.0, 3.0)];
        let r = register(&[], &mut nodes, &[true], &settings());
        assert_eq!(r.iterations, 0);
        assert_eq!(nodes[0], Vec3::new(1.0, 2.0, 3.0));
        let r = register(&[Vec3::zeros()], &mut nodes, &[false], &settings());
        assert_eq!(r.iterations, 0);
    }

    /// Property: any finite cloud and finite nodes give finite nodes.
    #[test]
    fn random_finite_inputs_give_finite_outputs() {
        let mut rng = SplitMix64::new(99);
        for case in 0..200 {
            let n = rng.below(60) as usize;
            let scale = [1e-6, 1e-3, 1.0, 1e3][rng.below(4) as usize];
            let cloud: Vec<Vec3> = (0..n)
                .map(|_| Vec3::new(rng.normal(), rng.normal(), rng.normal()) * scale)
                .collect();
            let m = 1 + rng.below(30) as usize;
            let mut nodes: Vec<Vec3> = (0..m)
                .map(|_| Vec3::new(rng.normal(), rng.normal(), rng.normal()) * scale)
                .collect();
            let active: Vec<bool> = (0..m).map(|_| rng.uniform() < 0.7).collect();
            let s = EmSettings {
                outlier_weight: rng.range(0.0, 0.99),
                tolerance: 1e-6,
                max_iterations: 30,
                min_variance: 1e-8,
            };
            let r = register(&cloud, &mut nodes, &active, &s);
            assert!(nodes.iter().all(math::is_finite), "case {case}");
            assert!(r.variance.is_finite() && r.variance > 0.0, "case {case}");
        }
    }

    /// Eq. 4-5 written out directly (every node-point pair, `libm::exp`, no
    /// candidate lists; terms past `EXPONENT_CUTOFF` dropped, as documented)
    /// for the optimised loop to be checked against.
    fn reference_em(
        cloud: &[Vec3],
        nodes: &mut [Vec3],
        active: &[bool],
        s: &EmSettings,
    ) -> (u32, f64) {
        let idx: Vec<usize> = (0..nodes.len()).filter(|&m| active[m]).collect();
        // Start: mean squared nearest-node distance per dimension over the
        // points within a node spacing, between the floor and the squared
        // mean node spacing.
        let len: f64 = nodes.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
        let spacing = len / (nodes.len() - 1) as f64;
        let near: Vec<f64> = cloud
            .iter()
            .map(|x| {
                idx.iter()
                    .map(|&m| (x - nodes[m]).norm_squared())
                    .fold(f64::INFINITY, f64::min)
            })
            .filter(|d2| *d2 <= spacing * spacing)
            .collect();
        let start = near.iter().sum::<f64>() / (near.len() as f64 * 3.0);
        let mut var = if near.is_empty() {
            spacing * spacing
        } else {
            start.clamp(s.min_variance, spacing * spacing)
        };
        let (k, n, w) = (idx.len() as f64, cloud.len() as f64, s.outlier_weight);
        for it in 1..=s.max_iterations {
            let mu = libm::pow(2.0 * core::f64::consts::PI * var, 1.5) * w * k / ((1.0 - w) * n);
            // P[i][j] for point i and active node j.
            let p: Vec<Vec<f64>> = cloud
                .iter()
                .map(|x| {
                    let g: Vec<f64> = idx
                        .iter()
                        .map(|&m| {
                            let e = (x - nodes[m]).norm_squared() / (2.0 * var);
                            if e < 20.0 {
                                libm::exp(-e)
                            } else {
                                0.0
                            }
                        })
                        .collect();
                    let denom: f64 = g.iter().sum::<f64>() + mu;
                    g.iter().map(|gj| gj / denom).collect()
                })
                .collect();
            let (mut shift, mut spread, mut total) = (0.0f64, 0.0, 0.0);
            for (j, &m) in idx.iter().enumerate() {
                let p1: f64 = p.iter().map(|row| row[j]).sum();
                if p1 > 1e-9 {
                    let y = cloud
                        .iter()
                        .zip(&p)
                        .fold(Vec3::zeros(), |acc, (x, row)| acc + x * row[j])
                        / p1;
                    shift = shift.max((y - nodes[m]).norm());
                    nodes[m] = y;
                    spread += cloud
                        .iter()
                        .zip(&p)
                        .map(|(x, row)| row[j] * (x - y).norm_squared())
                        .sum::<f64>();
                    total += p1;
                }
            }
            var = (spread / (3.0 * total)).max(s.min_variance);
            if shift < s.tolerance {
                return (it, var);
            }
        }
        (s.max_iterations, var)
    }

    /// Points every mm along a line of nodes 1 cm apart, 1 mm off it, and a few 7 cm
    /// away (a sliver of something else in the colour range): the start is
    /// the near points' mean square per dimension, not pulled to the cap.
    #[test]
    fn far_points_do_not_raise_the_first_variance() {
        let nodes: Vec<Vec3> = (0..10)
            .map(|k| Vec3::new(0.01 * k as f64, 0.0, 0.6))
            .collect();
        let active = vec![true; nodes.len()];
        let mut cloud: Vec<Vec3> = (0..90)
            .map(|k| Vec3::new(0.001 * k as f64, 0.001, 0.6))
            .collect();
        // Squared distances 0, 1, 4, 9, 16, 25, 16, 9, 4, 1 mm^2 along the
        // line (8.5 on average), plus 1 across: 9.5 mm^2 over 3 dimensions.
        let near = initial_variance(&cloud, &nodes, &active, 1e-8);
        assert!((near - 9.5e-6 / 3.0).abs() < 1e-12, "{near}");
        cloud.extend((0..5).map(|k| Vec3::new(0.005 * k as f64, 0.07, 0.6)));
        let with_far = initial_variance(&cloud, &nodes, &active, 1e-8);
        assert_eq!(with_far, near);
        // Only far points: the cap, the node spacing squared.
        let far: Vec<Vec3> = cloud[90..].to_vec();
        let cap = initial_variance(&far, &nodes, &active, 1e-8);
        assert!((cap - 1e-4).abs() < 1e-12, "{cap}");
    }

    #[test]
    fn candidate_lists_follow_a_growing_variance() {
        // Six nodes 1 mm apart in the middle of points spread over 20 cm:
        // sigma^2 starts at the squared spacing (1 mm^2) and grows tenfold,
        // the reach with it; the result is Eq. 4-5's written out. (The nodes
        // move too, which also rebuilds the lists; the next test isolates
        // the rebuild on growth.)
        let cloud: Vec<Vec3> = (0..200)
            .map(|k| Vec3::new(-0.1 + k as f64 * 0.001, 0.002 * libm::sin(k as f64), 0.6))
            .collect();
        let start: Vec<Vec3> = (0..6)
            .map(|i| Vec3::new(i as f64 * 0.001, 0.0, 0.6))
            .collect();
        let active = [true; 6];
        let s = EmSettings {
            outlier_weight: 0.1,
            tolerance: 1e-9,
            max_iterations: 6,
            min_variance: 1e-6,
        };
        let (mut ours, mut reference) = (start.clone(), start.clone());
        let r = register(&cloud, &mut ours, &active, &s);
        let (it, var) = reference_em(&cloud, &mut reference, &active, &s);
        assert_eq!(r.iterations, it);
        assert!(
            var > 10.0 * s.min_variance,
            "the case must grow sigma^2: {var}"
        );
        assert!(
            (r.variance - var).abs() < 1e-7 * var,
            "{} vs {var}",
            r.variance
        );
        for (a, b) in ours.iter().zip(&reference) {
            assert!((a - b).norm() < 1e-10, "{a:?} vs {b:?}");
        }
    }

    #[test]
    fn candidate_lists_are_rebuilt_when_only_the_variance_grows() {
        // Two nodes 1 mm apart between four points, 6 mm above and below and
        // 20 mm left and right. sigma^2 starts at the squared spacing; the
        // nodes meet in the middle (less than the margin, so that alone
        // rebuilds nothing), then sigma^2 grows and the far points come
        // within reach: only the rebuild on growth brings them in.
        let cloud = [
            Vec3::new(0.0, 0.006, 0.6),
            Vec3::new(0.0, -0.006, 0.6),
            Vec3::new(0.02, 0.0, 0.6),
            Vec3::new(-0.02, 0.0, 0.6),
        ];
        let start = [Vec3::new(-0.0005, 0.0, 0.6), Vec3::new(0.0005, 0.0, 0.6)];
        let active = [true; 2];
        let s = EmSettings {
            outlier_weight: 0.1,
            tolerance: 1e-9,
            max_iterations: 30,
            min_variance: 1e-8,
        };
        let (mut ours, mut reference) = (start, start);
        let r = register(&cloud, &mut ours, &active, &s);
        let (it, var) = reference_em(&cloud, &mut reference, &active, &s);
        assert_eq!(r.iterations, it);
        // Without the far points sigma^2 would stay at 1.2e-5.
        assert!(var > 5e-5, "the case must bring in the far points: {var}");
        assert!(
            (r.variance - var).abs() < 1e-9 * var,
            "{} vs {var}",
            r.variance
        );
    }

    #[test]
    fn the_optimised_em_is_eq_4_and_5_written_out() {
        let mut rng = SplitMix64::new(11);
        for case in 0..20 {
            // A noisy curve of points and nodes near it, some hidden.
            let m = 6 + case % 7;
            let cloud: Vec<Vec3> = (0..60 + 7 * case)
                .map(|i| {
                    let t = i as f64 * 0.004;
                    Vec3::new(t, 0.02 * libm::sin(8.0 * t), 0.6)
                        + Vec3::new(rng.normal(), rng.normal(), rng.normal()) * 0.002
                })
                .collect();
            let mut nodes: Vec<Vec3> = (0..m)
                .map(|i| {
                    Vec3::new(
                        i as f64 * 0.3 / m as f64,
                        0.004 * rng.normal(),
                        0.6 + 0.003 * rng.normal(),
                    )
                })
                .collect();
            let active: Vec<bool> = (0..m).map(|i| i % 4 != 3).collect();
            let s = EmSettings {
                outlier_weight: 0.05 + 0.2 * rng.uniform(),
                tolerance: 1e-4,
                max_iterations: 1 + case as u32 % 5,
                min_variance: 1e-6,
            };
            let mut expect = nodes.clone();
            let (it, var) = reference_em(&cloud, &mut expect, &active, &s);
            let r = register(&cloud, &mut nodes, &active, &s);
            assert_eq!(r.iterations, it, "case {case}");
            // Rounding only: exp_neg is within 1e-13 of exp, and the spread is
            // summed as sum P x^2 - |sum P x|^2 / sum P.
            assert!(
                (r.variance - var).abs() < 1e-7 * var,
                "case {case}: {} vs {var}",
                r.variance
            );
            for (a, b) in nodes.iter().zip(&expect) {
                assert!((a - b).norm() < 1e-10, "case {case}: {a:?} vs {b:?}");
            }
        }
    }
}
