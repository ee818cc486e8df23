//! The motion the visible rope shares: the rigid motion (rotation and
//! translation) that most visible nodes followed from the previous frame,
//! found robustly so that an end dragged alone does not count. A camera
//! on an arm or in a hand moves the whole rope in the image this way; the
//! hidden nodes are moved with it before the rules for a resting rope
//! (Eq. 6-11 and this project's) judge what is left.

use alloc::vec::Vec;

use nalgebra::{Matrix3, SMatrix, SVector};

use crate::math::{Vec3, MAD_TO_SIGMA};
use crate::motion::rotation_of;
pub use crate::motion::RigidMotion;

/// Fewest visible nodes a shared motion is estimated from: three
/// non-collinear points fix a rotation.
pub const MIN_SHARED_NODES: usize = 3;
/// Ridge on the fit, relative to its mean curvature: enough to settle
/// what the rope's shape leaves undetermined, too little to bias the rest.
const RIDGE: f64 = 1e-6;
/// The chi-square of six degrees of freedom at 0.999: how much better
/// than no motion (in units of the residual variance) a motion must
/// explain the moves to be taken as one.
const SIGNIFICANCE: f64 = 22.46;
/// Share of the visible nodes (by their final weights) that must follow
/// the motion for it to be the whole visible rope's.
const WHOLE_ROPE_SHARE: f64 = 0.9;
/// Reweighting rounds of the robust fit.
const ROUNDS: usize = 8;
/// The Cauchy weight's scale, times the residuals' robust spread: 95 %
/// efficiency on Gaussian residuals.
const CAUCHY_SCALE: f64 = 2.385;

/// The rope's unit tangent at node `k` of `chain` (the central difference
/// of its neighbours), or `None` where the chain gives no direction.
fn tangent(chain: &[Vec3], k: usize) -> Option<Vec3> {
    let last = chain.len().saturating_sub(1);
    let t = chain[(k + 1).min(last)] - chain[k.saturating_sub(1)];
    let n = t.norm();
    (n > crate::math::LENGTH_EPSILON).then(|| t / n)
}

/// The small rigid motion (rotation vector `omega` about `centre`, then
/// translation) whose moves of `from` best match `moves` across the rope:
/// each residual projected by `across[i]` (onto the plane normal to the
/// rope's tangent), weighted by `w`. Linearised (`R p = p + omega x p`),
/// with a little ridge so that what the rope's shape leaves undetermined
/// (a slide along a straight rope) is taken as no motion.
fn fit_across(
    from: &[Vec3],
    moves: &[Vec3],
    across: &[Matrix3<f64>],
    w: &[f64],
    centre: &Vec3,
) -> Option<(Vec3, Vec3)> {
    let mut a = SMatrix::<f64, 6, 6>::zeros();
    let mut b = SVector::<f64, 6>::zeros();
    for (((p, d), proj), w) in from.iter().zip(moves).zip(across).zip(w) {
        let q = p - centre;
        // omega x q = -[q]x omega
        let skew = Matrix3::new(0.0, q.z, -q.y, -q.z, 0.0, q.x, q.y, -q.x, 0.0);
        let mut j = SMatrix::<f64, 3, 6>::zeros();
        j.fixed_view_mut::<3, 3>(0, 0).copy_from(&(proj * skew));
        j.fixed_view_mut::<3, 3>(0, 3).copy_from(proj);
        a += j.transpose() * j * *w;
        b += j.transpose() * (proj * d) * *w;
    }
    let scale = a.trace() / 6.0;
    if !(scale > 0.0) {
        return None;
    }
    a += SMatrix::<f64, 6, 6>::identity() * (RIDGE * scale);
    let x = a.cholesky()?.solve(&b);
    x.iter()
        .all(|v| v.is_finite())
        .then(|| (Vec3::new(x[0], x[1], x[2]), Vec3::new(x[3], x[4], x[5])))
}

/// The rigid motion most of the visible nodes share from `previous` to
/// `current`, judged across the rope only: a node's slide along the rope
/// under EM is its parameterisation, not the rope's motion, and a slide
/// along a straight visible stretch is no evidence of a move. The fit
/// (`fit_across`) is reweighted with Cauchy weights on the residuals,
/// their spread taken robustly (`MAD`) but never below `noise` (metres:
/// how far a node of a still rope moves from frame to frame), starting
/// from weights on the moves themselves, so that a few nodes moving on
/// their own (a dragged end) get little weight. `None` with fewer than
/// [`MIN_SHARED_NODES`] visible nodes or on non-finite input.
pub fn shared_motion(
    previous: &[Vec3],
    current: &[Vec3],
    visible: &[bool],
    noise: f64,
) -> Option<RigidMotion> {
    let n = previous.len();
    if current.len() != n || visible.len() != n || !(noise > 0.0) {
        return None;
    }
    if !previous
        .iter()
        .chain(current)
        .all(|p| p.iter().all(|x| x.is_finite()))
    {
        return None;
    }
    let mut from = Vec::new();
    let mut moves = Vec::new();
    let mut across = Vec::new();
    for k in (0..n).filter(|&k| visible[k]) {
        let Some(t) = tangent(previous, k) else {
            continue;
        };
        from.push(previous[k]);
        moves.push(current[k] - previous[k]);
        across.push(Matrix3::identity() - t * t.transpose());
    }
    if from.len() < MIN_SHARED_NODES {
        return None;
    }
    let centre = from.iter().sum::<Vec3>() / from.len() as f64;
    let mut motion = (Vec3::zeros(), Vec3::zeros());
    let mut w = alloc::vec![1.0; from.len()];
    for _ in 0..ROUNDS {
        let r: Vec<f64> = from
            .iter()
            .zip(&moves)
            .zip(&across)
            .map(|((p, d), proj)| (proj * (motion.0.cross(&(p - centre)) + motion.1 - d)).norm())
            .collect();
        let spread = (MAD_TO_SIGMA * median(&r)).max(noise);
        let c = CAUCHY_SCALE * spread;
        for (w, r) in w.iter_mut().zip(&r) {
            *w = 1.0 / (1.0 + (r / c) * (r / c));
        }
        motion = fit_across(&from, &moves, &across, &w, &centre)?;
    }
    // Keep the motion only where it explains the moves better than no
    // motion by more than noise would: a likelihood-ratio test of the
    // six parameters at the residuals' own spread.
    let mut gain = 0.0;
    let mut spread2 = 0.0;
    let mut total = 0.0;
    for (((p, d), proj), w) in from.iter().zip(&moves).zip(&across).zip(&w) {
        let still = (proj * d).norm_squared();
        let fitted = (proj * (motion.0.cross(&(p - centre)) + motion.1 - d)).norm_squared();
        gain += w * (still - fitted);
        spread2 += w * fitted;
        total += w;
    }
    // The fit's own residual spread per node, never below the noise.
    let sigma2 = (spread2 / total.max(1e-12)).max(noise * noise);
    // And the whole visible rope must move so, not most of it: where part
    // of it moves on its own (a dragged end, a rope sliding round a bend)
    // the hidden part's motion is not the rest's.
    let whole = total / from.len() as f64 >= WHOLE_ROPE_SHARE;
    if !(gain / sigma2 > SIGNIFICANCE && whole) {
        return Some(RigidMotion::identity());
    }
    let rotation = rotation_of(&motion.0);
    Some(RigidMotion {
        rotation,
        translation: centre + motion.1 - rotation * centre,
    })
}

/// The median of `xs` (non-empty, finite).
fn median(xs: &[f64]) -> f64 {
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    let k = v.len() / 2;
    if v.len() % 2 == 1 {
        v[k]
    } else {
        0.5 * (v[k - 1] + v[k])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bent rope of `n` nodes, 2 cm apart, with some depth.
    fn rope(n: usize) -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let t = i as f64 * 0.02;
                Vec3::new(t, 0.05 * libm::sin(8.0 * t), 0.6 + 0.01 * t)
            })
            .collect()
    }

    fn turn(angle: f64) -> Matrix3<f64> {
        let (s, c) = (libm::sin(angle), libm::cos(angle));
        Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
    }

    #[test]
    fn a_camera_move_is_found_from_the_visible_nodes_alone() {
        let before = rope(24);
        let truth = RigidMotion {
            rotation: turn(0.01),
            translation: Vec3::new(0.004, -0.003, 0.001),
        };
        let after: Vec<Vec3> = before.iter().map(|p| truth.apply(p)).collect();
        let mut visible = alloc::vec![true; 24];
        visible[8..16].iter_mut().for_each(|v| *v = false);
        let found = shared_motion(&before, &after, &visible, 0.001).expect("a motion");
        // The hidden nodes follow it exactly.
        for k in 8..16 {
            let off = (found.apply(&before[k]) - after[k]).norm();
            assert!(off < 1e-4, "{off}");
        }
    }

    #[test]
    fn an_end_dragged_alone_is_not_a_shared_motion() {
        let before = rope(24);
        let mut after = before.clone();
        // The last six nodes dragged 5 cm; the rest lie still (with 0.5 mm jitter).
        for (k, p) in after.iter_mut().enumerate() {
            if k >= 18 {
                p.y += 0.05 * (k - 17) as f64 / 6.0;
            } else {
                p.x += 0.0005 * if k % 2 == 0 { 1.0 } else { -1.0 };
            }
        }
        let visible = alloc::vec![true; 24];
        let found = shared_motion(&before, &after, &visible, 0.001).expect("a motion");
        // A still node stays within a millimetre of where it was.
        for p in &before[..12] {
            assert!((found.apply(p) - p).norm() < 0.001, "{found:?}");
        }
        // A plain least-squares fit would have moved them.
        let across: Vec<Matrix3<f64>> = (0..24)
            .map(|k| {
                let t = tangent(&before, k).expect("a tangent");
                Matrix3::identity() - t * t.transpose()
            })
            .collect();
        let moves: Vec<Vec3> = before.iter().zip(&after).map(|(p, q)| q - p).collect();
        let centre = before.iter().sum::<Vec3>() / 24.0;
        let (omega, t) = fit_across(&before, &moves, &across, &[1.0; 24], &centre).expect("fit");
        assert!((omega.cross(&(before[0] - centre)) + t).norm() > 0.002);
    }

    #[test]
    fn a_slide_along_a_straight_rope_is_no_motion() {
        // EM's nodes slide 3 mm along a straight visible stretch.
        let before: Vec<Vec3> = (0..12)
            .map(|i| Vec3::new(0.02 * i as f64, 0.0, 0.6))
            .collect();
        let after: Vec<Vec3> = before
            .iter()
            .map(|p| p + Vec3::new(0.003, 0.0, 0.0))
            .collect();
        let found = shared_motion(&before, &after, &[true; 12], 0.001).expect("a motion");
        for p in &before {
            assert!((found.apply(p) - p).norm() < 1e-4, "{found:?}");
        }
    }

    #[test]
    fn too_few_nodes_or_bad_input_give_no_motion() {
        let before = rope(5);
        let visible = [true, true, false, false, false];
        assert_eq!(shared_motion(&before, &before, &visible, 0.001), None);
        let mut nan = before.clone();
        nan[0].x = f64::NAN;
        assert_eq!(shared_motion(&before, &nan, &[true; 5], 0.001), None);
        assert_eq!(
            shared_motion(&before, &before[..4], &[true; 5], 0.001),
            None
        );
        let still = shared_motion(&before, &before, &[true; 5], 0.001).expect("a motion");
        assert!((still.rotation - Matrix3::identity()).norm() < 1e-9);
    }
}
