//! The scenes' layouts: the shapes a rope is laid along before it settles,
//! the flat things lying on the table beside it, and a crossing's upper
//! strand laid over the lower.

use alloc::vec::Vec;

use upetrack::math::Vec3;

use crate::render::OccluderBox;
use crate::rope::Rope;

/// An S laid on the table: one period of a sine across the view.
pub(crate) fn s_shape() -> Vec<Vec3> {
    (0..400)
        .map(|i| {
            let t = i as f64 / 399.0;
            Vec3::new(
                -0.17 + 0.34 * t,
                0.11 * libm::sin(core::f64::consts::TAU * t),
                0.0,
            )
        })
        .collect()
}

/// A gentle arc, for the tip and pull scenarios.
pub(crate) fn arc_shape() -> Vec<Vec3> {
    (0..400)
        .map(|i| {
            let t = i as f64 / 399.0;
            Vec3::new(
                -0.25 + 0.5 * t,
                -0.12 + 0.25 * libm::sin(core::f64::consts::PI * t),
                0.0,
            )
        })
        .collect()
}

/// A U (hairpin) 0.80 m long: two arms 0.32 m long along x, 0.10 m apart,
/// joined at -x by a half circle; the second arm's end at +x.
pub(crate) fn hairpin_shape() -> Vec<Vec3> {
    const ARM: f64 = 0.32;
    const RADIUS: f64 = 0.05;
    let bend = core::f64::consts::PI * RADIUS;
    let total = 2.0 * ARM + bend;
    let x0 = 0.5 * (ARM - RADIUS);
    (0..400)
        .map(|i| {
            let s = total * i as f64 / 399.0;
            if s < ARM {
                Vec3::new(x0 - s, RADIUS, 0.0)
            } else if s < ARM + bend {
                let a = (s - ARM) / RADIUS;
                let cx = x0 - ARM;
                Vec3::new(cx - RADIUS * libm::sin(a), RADIUS * libm::cos(a), 0.0)
            } else {
                Vec3::new(x0 - ARM + (s - ARM - bend), -RADIUS, 0.0)
            }
        })
        .collect()
}

/// A cable laid in several bends: two periods of a sine, about 1 m long.
pub(crate) fn bends_shape() -> Vec<Vec3> {
    (0..400)
        .map(|i| {
            let t = i as f64 / 399.0;
            Vec3::new(
                -0.16 + 0.36 * t,
                0.115 * libm::sin(core::f64::consts::TAU * 2.0 * t),
                0.0,
            )
        })
        .collect()
}

/// A loop crossing itself: the nodal cubic `y^2 = x^2 (x + 1)` (crossing at
/// the origin at right angles), tails to +x.
pub(crate) fn loop_shape() -> Vec<Vec3> {
    (0..400)
        .map(|i| {
            let t = -1.35 + 2.7 * i as f64 / 399.0;
            Vec3::new(0.1 - 0.15 * (t * t - 1.0), 0.15 * t * (t * t - 1.0), 0.0)
        })
        .collect()
}

/// A flat object lying on the table, corners `(x0, y0)` and `(x1, y1)`, `h` high.
pub(crate) fn lying(x0: f64, y0: f64, x1: f64, y1: f64, h: f64, color: [f64; 3]) -> OccluderBox {
    OccluderBox {
        min: Vec3::new(x0, y0, 0.0),
        max: Vec3::new(x1, y1, h),
        color: Some(color),
    }
}

/// Lays the loop's second crossing strand over the first: the particles
/// of the later strand within a few thicknesses of the crossing are raised
/// by a thickness (with a smooth bump), so that settling leaves them
/// resting on the strand underneath instead of pushing it aside.
pub(crate) fn lift_upper_strand(rope: &mut Rope) {
    let n = rope.x.len();
    let t = rope.settings.thickness;
    // The crossing: the closest pair of particles far apart along the rope.
    let mut best = (f64::MAX, 0, 0);
    for i in 0..n {
        for j in i + n / 4..n {
            let d = upetrack::math::norm(&(rope.x[j] - rope.x[i]));
            if d < best.0 {
                best = (d, i, j);
            }
        }
    }
    let (_, _, upper) = best;
    let spacing = rope.settings.length / (n - 1) as f64;
    let reach = 4.0 * t;
    for (k, p) in rope.x.iter_mut().enumerate() {
        let s = (k as f64 - upper as f64) * spacing / reach;
        if s.abs() < 1.0 {
            p.z += t * (0.5 + 0.5 * libm::cos(core::f64::consts::PI * s));
        }
    }
}

/// A gripper holding a point: its palm over the point, its wrist up from
/// it and its forearm away to +y (corners relative to the point; `r` the
/// rope's radius, `color` `None` for the occluders' colour).
pub(crate) fn gripper(r: f64, color: Option<[f64; 3]>) -> [OccluderBox; 3] {
    let part = |min: Vec3, max: Vec3| OccluderBox { min, max, color };
    [
        part(
            Vec3::new(-0.035, -0.035, r + 0.005),
            Vec3::new(0.035, 0.035, r + 0.025),
        ),
        part(
            Vec3::new(-0.02, -0.02, r + 0.025),
            Vec3::new(0.02, 0.02, 0.20),
        ),
        part(Vec3::new(-0.02, -0.02, 0.18), Vec3::new(0.02, 0.28, 0.22)),
    ]
}
