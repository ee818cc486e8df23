//! The camera's own motion between two frames, from the background: a
//! camera on a robot arm or in a hand moves everything at rest in the
//! world, the hidden part of a rope too. Direct RGB-D odometry: the
//! rigid motion that best carries the last frame's background pixels on
//! the support plane (the table; by brightness where textured, by depth
//! everywhere) onto this frame's, coarse to fine, with the rope, the
//! declared occluders and what stands above the table left out and
//! whatever else moved on its own weighed out by a robust loss. Taken only
//! when it explains the images significantly better than no motion and
//! nearly all pixels that decide side with it, so a still camera reads
//! still; a slide along the table only when its brightness shows it (the
//! depth of a plain table shows its tilt and distance, not the slide).

mod view;

use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{Matrix3, SMatrix, SVector};

use crate::math::{median_abs, Vec3, MAD_TO_SIGMA};
use crate::motion::{rotation_of, RigidMotion};
pub(crate) use view::agreed_depth;
use view::Level;
pub use view::{BackgroundView, COARSEST_WIDTH, FINEST_WIDTH, NOISE_SAMPLES};

/// Most background pixels followed per level (one per grid cell).
pub const MAX_POINTS: usize = 800;
/// Fewest background pixels (with texture and depth) a motion is
/// estimated from at the finest level; six unknowns need many more.
pub const MIN_POINTS: usize = 60;
/// Smallest brightness gradient (grey levels per pixel of the level) of a
/// followed pixel: below it a cell is flat and says nothing.
pub const GRADIENT_FLOOR: f32 = 1.5;
/// A followed pixel's gradient is at least this many times the image
/// noise's gradient scale (a flat pixel's gradient is Rayleigh distributed
/// with scale `sigma / sqrt 2`; one in ten thousand passes, so that few of
/// a plain table's grid cells, each the best of some fifty pixels, offer
/// noise as texture).
pub const GRADIENT_NOISE_SCALES: f64 = 4.29;
/// A motion moving the followed pixels by less than this on average
/// (pixels of the finest level) is below what the images resolve: taken
/// as none. Interpolating a noisy image between pixels smooths its noise,
/// which a sub-pixel fit of a still camera would otherwise take for a
/// significant gain.
pub const MIN_RESOLVED_SHIFT: f64 = 0.1;
/// A background pixel lies on the support plane (the table) when it is
/// within this many deviations of depth noise of it.
pub const PLANE_SIGMAS: f64 = 3.0;
/// Random three-point trials of the support plane's search (seeded: the
/// same plane on every run and target).
const PLANE_TRIALS: usize = 64;
/// Points a trial plane is scored on, at most.
const PLANE_SCORED_POINTS: usize = 200;
/// Gauss-Newton iterations per level, at most.
const MAX_ITERATIONS: usize = 12;
/// An update moving the background by less than this (pixels of the
/// level) ends the level's iterations.
const CONVERGED_PX: f64 = 0.01;
/// On a coarser level, an update moving the background by less than this
/// (pixels of the level) ends its iterations: the level only has to bring
/// the motion within the next one's reach, which then refines it.
const COARSE_CONVERGED_PX: f64 = 0.1;
/// On a coarser level, an update predicted to explain the images better
/// by less than this (twice the robust loss, in units of the residuals'
/// variance: one unit of chi-square) ends its iterations too: the images
/// cannot tell it from none. (Tried at the finest level as well: as fast,
/// but the estimates moved by up to their noise and three report seeds
/// with them.)
const CONVERGED_GAIN: f64 = 1.0;
/// The Cauchy loss's scale in robust standard deviations of the residuals
/// (95 % efficiency on Gaussian noise). A redescending loss: a box or a
/// hand moving over the table weighs next to nothing once the still
/// background is matched, where Huber's would still pull.
const CAUCHY: f64 = 2.385;
/// Share of the decisive background pixels (those a motion explains
/// clearly better or clearly worse than no motion) it must explain better:
/// the camera moves all of the background, so nearly every pixel that
/// tells a move from stillness sides with it; a box, a hand or a shadow
/// moving on its own is a part that speaks for it while the still rest
/// speaks against. (The same share as the visible rope's shared motion.)
const WHOLE_BACKGROUND_SHARE: f64 = 0.9;
/// Fewest decisive pixels the share is judged on: ten votes all one way
/// happen by chance about once in a thousand (`2^-10`).
const MIN_DECISIVE: usize = 10;
/// A slide in the table's plane is taken when it explains more of the
/// textured pixels better than chance would: more than half of them by
/// this many deviations of a fair coin's count (a one-sided sign test at
/// 0.999). Pixels of noise, where a plain table offers no texture, side
/// with a made-up slide about half the time whatever its size.
const SLIDE_SIGN_SIGMAS: f64 = 3.09;
/// A pixel is decisive when its own loss changes by more than the
/// chi-square of one degree of freedom at 0.95 (in units of the
/// residuals' variance, twice the loss).
const DECISIVE: f64 = 3.84;
/// Smallest brightness noise assumed, grey levels (8-bit images quantise).
const MIN_BRIGHTNESS_SIGMA: f64 = 0.5;
/// Smallest depth noise assumed, metres (millimetre depth units).
const MIN_DEPTH_SIGMA: f64 = 0.0005;
/// The chi-square of six degrees of freedom at 0.999: how much better (in
/// units of the residuals' variance) the motion must explain the images
/// than no motion to be taken.
pub(crate) const SIGNIFICANCE: f64 = 22.46;
/// The chi-square of three degrees of freedom at 0.999, for a model of
/// three parameters tested at the level [`SIGNIFICANCE`] sets for six: how
/// much better the slide in the table's plane must explain the brightness
/// than the motion without it (and the glance's inverse depth's affine
/// model).
pub(crate) const SIGNIFICANCE_3: f64 = 16.27;
/// Ridge on the normal equations, relative to their mean curvature: what
/// the background leaves undetermined (a flat, plain table's slide) is
/// taken as no motion.
const RIDGE: f64 = 1e-6;

/// A followed background pixel of the earlier frame.
struct Template {
    /// Where it is, metres, the earlier camera's frame.
    point: Vec3,
    /// Its brightness, where it is textured enough to follow by it.
    grey: Option<f64>,
}

/// The side, pixels, of the grid cells that give `level` at most
/// [`MAX_POINTS`] followed pixels.
fn cell_side(level: &Level) -> usize {
    let area = level.width * level.height;
    (libm::ceil(libm::sqrt(area as f64 / MAX_POINTS as f64)) as usize).max(1)
}

/// The background pixels of `level` with a depth, one in each grid cell
/// (its first in reading order), in 3D: an even spread to find the
/// support plane from.
fn spread_points(level: &Level) -> Vec<Vec3> {
    let (w, h) = (level.width, level.height);
    let cell = cell_side(level);
    let mut out = Vec::new();
    for cv in (0..h).step_by(cell) {
        for cu in (0..w).step_by(cell) {
            let first = (cv..(cv + cell).min(h))
                .flat_map(|v| (cu..(cu + cell).min(w)).map(move |u| (u, v)))
                .find(|&(u, v)| level.background[v * w + u] && level.depth[v * w + u] > 0.0);
            out.extend(first.and_then(|(u, v)| level.point(u, v)));
        }
    }
    out
}

/// The background pixels of `level` on the support `plane` (`focal` sets
/// its tolerance), one in each cell of a grid: the one with the strongest
/// gradient above [`GRADIENT_FLOOR`] whose four neighbours (its gradient's
/// stencil) are on the plane too, followed by brightness and depth, else
/// the cell's first on the plane, followed by depth alone. Every part of
/// the table speaks, a plain one by its plane, so that a textured hand
/// moving over it is outvoted; the edge of a box standing on the table is
/// the box's texture, not the table's. `noise` is the level's brightness
/// noise.
fn templates(level: &Level, noise: f64, plane: &Plane, focal: f64) -> Vec<Template> {
    let (w, h) = (level.width, level.height);
    if w < 3 || h < 3 {
        return Vec::new();
    }
    // `n . p` of pixel (u, v) at depth z is `z (a u + b v + c)`.
    let n = plane.normal;
    let (a, b) = (n.x / level.fx, n.y / level.fy);
    let c = n.z - a * level.cx - b * level.cy;
    let on = |u: usize, v: usize| {
        let z = level.depth[v * w + u] as f64;
        z > 0.0
            && Plane::within(
                z * (a * u as f64 + b * v as f64 + c) - plane.offset,
                z,
                focal,
            )
    };
    let floor =
        GRADIENT_FLOOR.max((GRADIENT_NOISE_SCALES * noise / core::f64::consts::SQRT_2) as f32);
    let floor2 = floor * floor;
    let cell = cell_side(level);
    let valid = |i: usize| level.background[i] && level.depth[i] > 0.0;
    let g2 = |i: usize| level.gx[i] * level.gx[i] + level.gy[i] * level.gy[i];
    let stencil = |u: usize, v: usize| {
        on(u, v) && on(u - 1, v) && on(u + 1, v) && on(u, v - 1) && on(u, v + 1)
    };
    let mut out = Vec::new();
    // Each band of cells is read row by row: a row's squared gradients
    // (-1 where not valid) in one pass, then each cell's part of the row
    // by its maximum; a cell's strongest is the first pixel in reading
    // order with the largest value, its first the first valid one.
    let columns: Vec<usize> = (1..w - 1).step_by(cell).collect();
    let mut row = vec![0.0f32; w];
    let mut strongest = vec![(-1.0f32, (0, 0)); columns.len()];
    let mut firsts: Vec<Option<(usize, usize)>> = vec![None; columns.len()];
    for cv in (1..h - 1).step_by(cell) {
        let rows = cv..(cv + cell).min(h - 1);
        strongest.fill((-1.0, (0, 0)));
        firsts.fill(None);
        for v in rows.clone() {
            let line = v * w..(v + 1) * w;
            let (bg, depth) = (&level.background[line.clone()], &level.depth[line.clone()]);
            let (gx, gy) = (&level.gx[line.clone()], &level.gy[line]);
            // Branch-free, so that the pass is vectorised.
            let pixels = bg.iter().zip(depth).zip(gx.iter().zip(gy));
            for (g, ((&b, &z), (&x, &y))) in row.iter_mut().zip(pixels) {
                let valid = b & (z > 0.0);
                let g2 = x * x + y * y;
                *g = if valid { g2 } else { -1.0 };
            }
            for ((&cu, best), first) in columns.iter().zip(&mut strongest).zip(&mut firsts) {
                let part = &row[cu..(cu + cell).min(w - 1)];
                let most = part.iter().fold(-1.0f32, |m, &g| if g > m { g } else { m });
                if most > best.0 {
                    if let Some(k) = part.iter().position(|&g| g == most) {
                        *best = (most, (cu + k, v));
                    }
                }
                if first.is_none() && most >= 0.0 {
                    *first = part.iter().position(|&g| g >= 0.0).map(|k| (cu + k, v));
                }
            }
        }
        for ((&cu, &(strongest, at)), &first) in columns.iter().zip(&strongest).zip(&firsts) {
            let columns = cu..(cu + cell).min(w - 1);
            // When the cell's strongest valid pixel and its first are on
            // the plane (nearly always) they are the answer, found without
            // asking every pixel.
            let strongest = (strongest >= 0.0).then_some((strongest, at.0, at.1));
            let mut best = strongest.filter(|&(g, u, v)| g >= floor2 && stencil(u, v));
            let mut plain = first.filter(|&(u, v)| on(u, v));
            let textured = strongest.is_some_and(|(g, _, _)| g >= floor2);
            if best.is_none() && (textured || plain.is_none()) {
                // The pixel-by-pixel rule: the strongest whose stencil is
                // on the plane, and the first on it.
                (best, plain) = (None, None);
                for v in rows.clone() {
                    for u in columns.clone() {
                        let i = v * w + u;
                        if !valid(i) {
                            continue;
                        }
                        let g = g2(i);
                        let better = g >= floor2 && best.is_none_or(|b| g > b.0);
                        if (plain.is_none() || better) && on(u, v) {
                            plain = plain.or(Some((u, v)));
                            if better && stencil(u, v) {
                                best = Some((g, u, v));
                            }
                        }
                    }
                }
            }
            let chosen = best.map(|(_, u, v)| (u, v, true));
            if let Some((u, v, textured)) = chosen.or(plain.map(|(u, v)| (u, v, false))) {
                if let Some(point) = level.point(u, v) {
                    out.push(Template {
                        point,
                        grey: textured.then_some(level.grey[v * w + u] as f64),
                    });
                }
            }
        }
    }
    out
}

/// A plane `n . p = d` (`n` a unit normal).
#[derive(Debug, Clone, Copy)]
struct Plane {
    normal: Vec3,
    offset: f64,
}

impl Plane {
    fn through(a: &Vec3, b: &Vec3, c: &Vec3) -> Option<Self> {
        let n = (b - a).cross(&(c - a));
        let len = n.norm();
        (len > 1e-9).then(|| {
            let normal = n / len;
            Self {
                normal,
                offset: normal.dot(a),
            }
        })
    }

    /// Whether a point at depth `z` whose signed distance from a plane is
    /// `distance` lies on it: within [`PLANE_SIGMAS`] deviations of depth
    /// noise.
    fn within(distance: f64, z: f64, focal: f64) -> bool {
        let noise = crate::perception::camera::depth_noise(z, focal).max(MIN_DEPTH_SIGMA);
        distance.abs() <= PLANE_SIGMAS * noise
    }
}

/// The plane most of `points` lie on (within [`PLANE_SIGMAS`] deviations of
/// depth noise): the surface the rope rests on. Hands, boxes, a gripper
/// and the rope move above it; the camera moves it all.
fn support_plane(points: &[Vec3], focal: f64) -> Option<Plane> {
    if points.len() < 3 {
        return None;
    }
    // Trials are scored on an even subset; a plane holding most points
    // holds most of any even share of them.
    let stride = points.len().div_ceil(PLANE_SCORED_POINTS);
    let scored: Vec<Vec3> = points.iter().step_by(stride).copied().collect();
    let mut rng = crate::rng::SplitMix64::new(0x7AB1E);
    let mut best: Option<(usize, Plane)> = None;
    let n = points.len() as u64;
    for _ in 0..PLANE_TRIALS {
        let mut pick = || points[rng.below(n) as usize];
        let (a, b, c) = (pick(), pick(), pick());
        let Some(plane) = Plane::through(&a, &b, &c) else {
            continue;
        };
        let count = scored
            .iter()
            .filter(|p| Plane::within(plane.normal.dot(p) - plane.offset, p.z, focal))
            .count();
        if best.is_none_or(|(k, _)| count > k) {
            best = Some((count, plane));
        }
    }
    best.map(|(_, plane)| plane)
}

/// Bilinear brightness, its gradient and the nearest pixel's depth at
/// `(x, y)` of a later frame's level, where that is background.
fn sample(level: &Level, x: f64, y: f64) -> Option<(f64, f64, f64, f64)> {
    if !(x >= 1.0 && y >= 1.0 && x < (level.width - 2) as f64 && y < (level.height - 2) as f64) {
        return None;
    }
    let (u, v) = (x as usize, y as usize);
    let (a, b) = ((x - u as f64) as f32, (y - v as f64) as f32);
    let near = level.at(
        if a < 0.5 { u } else { u + 1 },
        if b < 0.5 { v } else { v + 1 },
    );
    if !level.background[near] {
        return None;
    }
    let (i, w) = (level.at(u, v), level.width);
    let lerp = |image: &[f32]| {
        let top = image[i] * (1.0 - a) + image[i + 1] * a;
        let bottom = image[i + w] * (1.0 - a) + image[i + w + 1] * a;
        (top * (1.0 - b) + bottom * b) as f64
    };
    let (grey, gx, gy) = (lerp(&level.grey), lerp(&level.gx), lerp(&level.gy));
    Some((grey, gx, gy, level.depth[near] as f64))
}

/// The Cauchy weight of a residual `r` in robust deviations.
fn cauchy_weight(r: f64) -> f64 {
    let x = r / CAUCHY;
    1.0 / (1.0 + x * x)
}

/// The Cauchy loss of a residual in robust deviations (`r^2 / 2` near 0).
fn cauchy_loss(r: f64) -> f64 {
    let x = r / CAUCHY;
    0.5 * CAUCHY * CAUCHY * libm::log1p(x * x)
}

/// The residuals of the templates under `motion` on a later level: the
/// brightness and the depth residual (where known), and their Jacobians
/// in the motion's increment `(translation, rotation)`.
/// One per template, `None` where it left the image or the background.
type Rows = Vec<Option<Row>>;
/// A template's brightness residual and its Jacobian (a textured one), and
/// its depth residual and Jacobian (where the later depth is known).
type Row = (Option<Residual>, Option<Residual>);
/// A residual and its Jacobian in the motion's increment.
type Residual = (f64, SVector<f64, 6>);

fn residuals(templates: &[Template], later: &Level, motion: &RigidMotion, normal: &Vec3) -> Rows {
    // The table's normal (in the earlier frame) carried into the later.
    let normal = motion.rotation * normal;
    let mut rows = Vec::with_capacity(templates.len());
    for t in templates {
        rows.push(residual(t, later, motion, &normal));
    }
    rows
}

/// [`residuals`] of one template; `normal` is the table's in the later
/// frame.
fn residual(t: &Template, later: &Level, motion: &RigidMotion, normal: &Vec3) -> Option<Row> {
    let p = motion.apply(&t.point);
    if !(p.z > 0.0) {
        return None;
    }
    let x = later.fx * p.x / p.z + later.cx;
    let y = later.fy * p.y / p.z + later.cy;
    let (grey, gx, gy, z) = sample(later, x, y)?;
    // d(pixel)/d(point), then d(point)/d(increment) = [I | -[p]x].
    let iz = 1.0 / p.z;
    let du = Vec3::new(later.fx * iz, 0.0, -later.fx * p.x * iz * iz);
    let dv = Vec3::new(0.0, later.fy * iz, -later.fy * p.y * iz * iz);
    let increment = |d: Vec3| {
        let rot = p.cross(&d);
        SVector::<f64, 6>::new(d.x, d.y, d.z, rot.x, rot.y, rot.z)
    };
    let photometric = t.grey.map(|g| (grey - g, increment(du * gx + dv * gy)));
    let depth = (z > 0.0)
        .then(|| later.depth_gradient(x, y))
        .flatten()
        .map(|(zx, zy)| {
            let along = du * zx + dv * zy - Vec3::new(0.0, 0.0, 1.0);
            // A slide along the table (of `normal`) keeps it where it was:
            // its depth cannot see one. Noisy depth gradients would make it
            // seem to, so that part of the Jacobian is left out.
            let j = increment(along);
            let (jt, jr) = (Vec3::new(j[0], j[1], j[2]), Vec3::new(j[3], j[4], j[5]));
            let (jt, jr) = (normal * normal.dot(&jt), jr - normal * normal.dot(&jr));
            (
                z - p.z,
                SVector::<f64, 6>::new(jt.x, jt.y, jt.z, jr.x, jr.y, jr.z),
            )
        });
    (photometric.is_some() || depth.is_some()).then_some((photometric, depth))
}

/// Robust deviations of the brightness and depth residuals.
fn spreads(rows: &Rows) -> (f64, f64) {
    let mut b: Vec<f64> = rows
        .iter()
        .flatten()
        .filter_map(|r| r.0.map(|b| b.0))
        .collect();
    let mut d: Vec<f64> = rows
        .iter()
        .flatten()
        .filter_map(|r| r.1.map(|d| d.0))
        .collect();
    (
        (MAD_TO_SIGMA * median_abs(&mut b)).max(MIN_BRIGHTNESS_SIGMA),
        (MAD_TO_SIGMA * median_abs(&mut d)).max(MIN_DEPTH_SIGMA),
    )
}

/// The robust loss of a row at deviations `(sb, sd)`.
fn loss((b, d): &Row, (sb, sd): (f64, f64)) -> f64 {
    b.map_or(0.0, |(rb, _)| cauchy_loss(rb / sb)) + d.map_or(0.0, |(rd, _)| cauchy_loss(rd / sd))
}

/// One Gauss-Newton update of `motion` and how much it is predicted to
/// lower the robust loss (twice, in units of the residuals' variance), or
/// `None` when the normal equations cannot be solved. With `flat`, the
/// update is held to the motions that leave the table's plane slide-free
/// (the columns of [`flat_basis`]).
fn update(
    rows: &Rows,
    (sb, sd): (f64, f64),
    flat: Option<&SMatrix<f64, 6, 3>>,
) -> Option<(SVector<f64, 6>, f64)> {
    let mut a = SMatrix::<f64, 6, 6>::zeros();
    let mut g = SVector::<f64, 6>::zeros();
    let mut add = |r: f64, j: &SVector<f64, 6>, s: f64| {
        let (r, j) = (r / s, j / s);
        let w = cauchy_weight(r);
        // The lower triangle only: the matrix is symmetric.
        a.syger(w, &j, &j, 1.0);
        g += j * (r * w);
    };
    for (b, d) in rows.iter().flatten() {
        if let Some((rb, jb)) = b {
            add(*rb, jb, sb);
        }
        if let Some((rd, jd)) = d {
            add(*rd, jd, sd);
        }
    }
    a.fill_upper_triangle_with_lower_triangle();
    let x = match flat {
        None => {
            let scale = a.trace() / 6.0;
            if !(scale > 0.0) {
                return None;
            }
            a += SMatrix::<f64, 6, 6>::identity() * (RIDGE * scale);
            -a.cholesky()?.solve(&g)
        }
        Some(basis) => {
            let mut ar = basis.transpose() * a * basis;
            let scale = ar.trace() / 3.0;
            if !(scale > 0.0) {
                return None;
            }
            ar += SMatrix::<f64, 3, 3>::identity() * (RIDGE * scale);
            -(basis * ar.cholesky()?.solve(&(basis.transpose() * g)))
        }
    };
    let predicted = -g.dot(&x);
    x.iter().all(|v| v.is_finite()).then_some((x, predicted))
}

/// `motion` moved by the increment `x` (translation, rotation vector), and
/// how far that moves the background, pixels of a level of focal `fx` at
/// `depth` metres.
fn moved_by(motion: &RigidMotion, x: &SVector<f64, 6>, fx: f64, depth: f64) -> (RigidMotion, f64) {
    let (v, w) = (Vec3::new(x[0], x[1], x[2]), Vec3::new(x[3], x[4], x[5]));
    let turn: Matrix3<f64> = rotation_of(&w);
    let moved = RigidMotion {
        rotation: turn * motion.rotation,
        translation: turn * motion.translation + v,
    };
    (moved, fx * (v.norm() / depth + w.norm()))
}

/// The increments that do not slide the plane of unit `normal` within
/// itself (as columns: translation along the normal, turns about two axes
/// in the plane): what the depth of a plain table can tell.
fn flat_basis(normal: &Vec3) -> SMatrix<f64, 6, 3> {
    let n = *normal;
    // Any axis across the normal, from the camera axis it is least along.
    let other = if n.x.abs() <= n.y.abs() && n.x.abs() <= n.z.abs() {
        Vec3::x()
    } else if n.y.abs() <= n.z.abs() {
        Vec3::y()
    } else {
        Vec3::z()
    };
    let a = n.cross(&other).normalize();
    let b = n.cross(&a);
    let mut basis = SMatrix::<f64, 6, 3>::zeros();
    basis.fixed_view_mut::<3, 1>(0, 0).copy_from(&n);
    basis.fixed_view_mut::<3, 1>(3, 1).copy_from(&a);
    basis.fixed_view_mut::<3, 1>(3, 2).copy_from(&b);
    basis
}

/// `motion` without its slide in the plane of unit `normal` (its
/// translation along the plane, its turn about the normal).
fn without_slide(motion: &RigidMotion, normal: &Vec3) -> RigidMotion {
    let turn = nalgebra::Rotation3::from_matrix_unchecked(motion.rotation).scaled_axis();
    RigidMotion {
        rotation: rotation_of(&(turn - normal * normal.dot(&turn))),
        translation: normal * normal.dot(&motion.translation),
    }
}

/// How a motion's rows compare with another motion's on the pixels both
/// follow, at deviations `s`.
#[derive(Debug, Default)]
struct Tally {
    /// Pixels both follow.
    points: usize,
    /// Twice the robust loss's drop from `other` to `rows`.
    gain: f64,
    /// Pixels whose own loss changes by more than [`DECISIVE`].
    decisive: usize,
    /// Of those, the ones `rows` explains better.
    better: usize,
    /// Pixels `rows` explains better, decisive or not.
    improved: usize,
}

impl Tally {
    /// `rows` against `other`: brightness and depth, or with
    /// `brightness_only` the brightness alone.
    fn of(rows: &Rows, other: &Rows, s: (f64, f64), brightness_only: bool) -> Self {
        let mut t = Self::default();
        for (m, n) in rows.iter().zip(other) {
            let (Some(m), Some(n)) = (m, n) else {
                continue;
            };
            let drop = if brightness_only {
                let (Some((mb, _)), Some((nb, _))) = (m.0, n.0) else {
                    continue;
                };
                2.0 * (cauchy_loss(nb / s.0) - cauchy_loss(mb / s.0))
            } else {
                2.0 * (loss(n, s) - loss(m, s))
            };
            t.points += 1;
            t.gain += drop;
            t.improved += usize::from(drop > 0.0);
            if drop.abs() > DECISIVE {
                t.decisive += 1;
                t.better += usize::from(drop > 0.0);
            }
        }
        t
    }

    /// Significant at `significance` and shared by nearly every decisive
    /// pixel ([`WHOLE_BACKGROUND_SHARE`], of at least [`MIN_DECISIVE`]).
    fn taken(&self, significance: f64) -> bool {
        self.gain > significance
            && self.decisive >= MIN_DECISIVE
            && self.better as f64 >= WHOLE_BACKGROUND_SHARE * self.decisive as f64
    }

    /// Significant at `significance` and explaining more pixels better
    /// than chance would ([`SLIDE_SIGN_SIGMAS`]).
    fn more_than_chance(&self, significance: f64) -> bool {
        let n = self.points as f64;
        let chance = 0.5 * n + SLIDE_SIGN_SIGMAS * 0.5 * libm::sqrt(n);
        self.gain > significance && self.improved as f64 > chance
    }
}

/// `motion`, or when the brightness does not show its slide in the
/// table's plane (of unit `normal`) the motion that best explains the
/// `templates` on `later` without one: the depth of a plain table tells
/// its tilt and distance but not where along it the camera went, and a
/// slide read from noisy depth gradients alone ran to 15 cm a frame
/// (drawn scene 4046, a handheld camera over a dark table).
fn slide_seen_or_none(
    motion: RigidMotion,
    templates: &[Template],
    later: &Level,
    normal: &Vec3,
) -> RigidMotion {
    let moved = residuals(templates, later, &motion, normal);
    let flat = without_slide(&motion, normal);
    let unslid = residuals(templates, later, &flat, normal);
    if Tally::of(&moved, &unslid, spreads(&moved), true).more_than_chance(SIGNIFICANCE_3) {
        return motion;
    }
    fit(
        templates,
        later,
        flat,
        normal,
        Some(&flat_basis(normal)),
        true,
    )
}

/// Gauss-Newton from `motion` on `templates` against `later` (of the
/// table's `normal`), held to the columns of `flat` when given. The
/// `finest` level refines until an update moves the background by less
/// than [`CONVERGED_PX`]; a coarser one stops once the next can take over.
fn fit(
    templates: &[Template],
    later: &Level,
    mut motion: RigidMotion,
    normal: &Vec3,
    flat: Option<&SMatrix<f64, 6, 3>>,
    finest: bool,
) -> RigidMotion {
    let depth = templates.iter().map(|t| t.point.z).sum::<f64>() / templates.len().max(1) as f64;
    for _ in 0..MAX_ITERATIONS {
        let rows = residuals(templates, later, &motion, normal);
        if rows.iter().flatten().count() < MIN_POINTS {
            break;
        }
        let Some((x, predicted)) = update(&rows, spreads(&rows), flat) else {
            break;
        };
        let shift;
        (motion, shift) = moved_by(&motion, &x, later.fx, depth);
        let converged = if finest {
            shift < CONVERGED_PX
        } else {
            shift < COARSE_CONVERGED_PX || predicted < CONVERGED_GAIN
        };
        if converged {
            break;
        }
    }
    motion
}

/// The camera's estimated motion between two frames.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraMotion {
    /// Where a point at rest goes, from the earlier camera frame to the later.
    pub motion: RigidMotion,
    /// Background pixels it was judged on at the finest level.
    pub points: usize,
    /// How much better than no motion it explains them (the robust loss's
    /// drop, twice, in units of the residuals' variance; a chi-square of six
    /// degrees of freedom under no motion).
    pub gain: f64,
    /// Mean move of those pixels, pixels of the finest level.
    pub shift_px: f64,
    /// Share of the decisive pixels it explains better than no motion.
    pub support: f64,
}

/// The motion of the camera from `earlier` to `later` (two views of the
/// same camera), or `None` when the background says too little (fewer
/// than [`MIN_POINTS`] textured background pixels with depth, a failed
/// solve) or no motion is significant.
pub fn camera_motion(earlier: &BackgroundView, later: &BackgroundView) -> Option<CameraMotion> {
    if earlier.levels.len() != later.levels.len() {
        return None;
    }
    let mut motion = RigidMotion::identity();
    let mut finest = None;
    let on_plane = { support_plane(&spread_points(&earlier.levels[0]), earlier.focal)? };
    for (k, (e, l)) in earlier.levels.iter().zip(&later.levels).enumerate().rev() {
        if e.width != l.width || e.height != l.height {
            return None;
        }
        // Halving averages four pixels: half the noise per level.
        let noise = earlier.noise / (1u32 << k) as f64;
        let templates = templates(e, noise, &on_plane, earlier.focal);
        motion = fit(&templates, l, motion, &on_plane.normal, None, k == 0);
        finest = Some(templates);
    }
    let templates = finest?;
    let finest = &later.levels[0];
    let motion = slide_seen_or_none(motion, &templates, finest, &on_plane.normal);
    let moved = residuals(&templates, finest, &motion, &on_plane.normal);
    let still = residuals(
        &templates,
        finest,
        &RigidMotion::identity(),
        &on_plane.normal,
    );
    // Judged on the pixels both follow, at the motion's deviations.
    let tally = Tally::of(&moved, &still, spreads(&moved), false);
    let mut shift = 0.0;
    for ((m, n), t) in moved.iter().zip(&still).zip(&templates) {
        if m.is_some() && n.is_some() {
            let (p, q) = (t.point, motion.apply(&t.point));
            let du = finest.fx * (q.x / q.z - p.x / p.z);
            let dv = finest.fy * (q.y / q.z - p.y / p.z);
            shift += libm::sqrt(du * du + dv * dv);
        }
    }
    let points = tally.points;
    let shift_px = shift / points.max(1) as f64;
    let support = tally.better as f64 / tally.decisive.max(1) as f64;
    let resolved = shift_px >= MIN_RESOLVED_SHIFT;
    let taken = points >= MIN_POINTS && resolved && tally.taken(SIGNIFICANCE) && motion.is_finite();
    taken.then_some(CameraMotion {
        motion,
        points,
        gain: tally.gain,
        shift_px,
        support,
    })
}

#[cfg(test)]
/// Test scenes of a table seen by a moving camera, for the motion
/// estimate's tests and the glance's.
pub(crate) mod fixture {
    use super::*;
    use crate::perception::camera::CameraIntrinsics;
    use crate::perception::segmentation::Mask;
    use crate::rng::SplitMix64;
    use alloc::vec;

    pub(crate) const CAMERA: CameraIntrinsics = CameraIntrinsics {
        width: 320,
        height: 240,
        fx: 300.0,
        fy: 300.0,
        cx: 160.0,
        cy: 120.0,
    };

    /// A table's brightness at world `(x, y)` (metres): value noise (a
    /// hashed lattice, interpolated) at 4 cm and 1 cm, or plain grey.
    pub(crate) fn table(x: f64, y: f64, textured: bool) -> f64 {
        if !textured {
            return 128.0;
        }
        let lattice = |x: f64, y: f64, cell: f64| {
            let (gx, gy) = (libm::floor(x / cell), libm::floor(y / cell));
            let (a, b) = (x / cell - gx, y / cell - gy);
            let at = |i: f64, j: f64| {
                let mut h =
                    SplitMix64::new((((i as i64) * 73_856_093) ^ ((j as i64) * 19_349_663)) as u64);
                h.uniform()
            };
            let (s, t) = (a * a * (3.0 - 2.0 * a), b * b * (3.0 - 2.0 * b));
            let top = at(gx, gy) * (1.0 - s) + at(gx + 1.0, gy) * s;
            let bottom = at(gx, gy + 1.0) * (1.0 - s) + at(gx + 1.0, gy + 1.0) * s;
            top * (1.0 - t) + bottom * t
        };
        60.0 + 100.0 * lattice(x, y, 0.04) + 60.0 * lattice(x, y, 0.01)
    }

    /// Colour and depth of the table plane `z = 0` seen from a camera at
    /// `centre` looking down, turned by `turn` (a rotation vector), with
    /// `noise` grey levels of noise, and a `thing` moving on its own.
    pub(crate) fn view(
        centre: Vec3,
        turn: Vec3,
        textured: bool,
        noise: f64,
        seed: u64,
        thing: Option<Thing>,
    ) -> (Vec<u8>, Vec<u16>) {
        // Camera axes in the world: x right, y down (world -y), z down.
        let base = Matrix3::new(1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0);
        let rows = rotation_of(&turn) * base;
        let mut rng = SplitMix64::new(seed);
        let (w, h) = (CAMERA.width as usize, CAMERA.height as usize);
        let (mut rgb, mut depth) = (vec![0u8; w * h * 3], vec![0u16; w * h]);
        for v in 0..h {
            for u in 0..w {
                let ray = Vec3::new(
                    (u as f64 - CAMERA.cx) / CAMERA.fx,
                    (v as f64 - CAMERA.cy) / CAMERA.fy,
                    1.0,
                );
                let world_ray = rows.transpose() * ray;
                let t = -centre.z / world_ray.z;
                let hit = centre + world_ray * t;
                let mut g = table(hit.x, hit.y, textured);
                let mut z = t;
                if let Some(thing) = &thing {
                    let x = u as f64 - thing.shift;
                    if x >= thing.columns.0 && x < thing.columns.1 && thing.rows.contains(&v) {
                        g = 128.0
                            + 100.0
                                * libm::sin(0.7 * (v as f64 + thing.shift))
                                * libm::cos(0.3 * x);
                        z -= thing.lift;
                    }
                }
                g += noise * rng.normal();
                let g = g.clamp(0.0, 255.0) as u8;
                rgb[3 * (v * w + u)..3 * (v * w + u) + 3].copy_from_slice(&[g, g, g]);
                depth[v * w + u] = libm::round(z * 1000.0) as u16;
            }
        }
        (rgb, depth)
    }

    /// Something textured moving on its own: pixel `columns` and `rows`,
    /// moved `shift` pixels along the rows, `lift` metres above the table.
    #[derive(Clone)]
    pub(crate) struct Thing {
        pub(crate) columns: (f64, f64),
        pub(crate) rows: core::ops::Range<usize>,
        pub(crate) shift: f64,
        pub(crate) lift: f64,
    }

    /// A textured box 6 cm above the table over pixel columns 60-160 and
    /// `rows`, slid `shift` pixels along the rows.
    pub(crate) fn sliding_box(rows: core::ops::Range<usize>, shift: f64) -> Option<Thing> {
        Some(Thing {
            columns: (60.0, 160.0),
            rows,
            shift,
            lift: 0.06,
        })
    }

    pub(crate) fn no_rope() -> Mask {
        Mask::new(CAMERA.width, CAMERA.height)
    }

    pub(crate) const HOME: Vec3 = Vec3::new(0.0, 0.0, 0.8);
}

#[cfg(test)]
mod tests {
    use super::fixture::*;
    use super::*;
    use crate::perception::camera::CameraIntrinsics;
    use crate::perception::frame::Frame;
    use crate::perception::segmentation::Mask;
    use crate::rng::SplitMix64;

    fn background(images: &(Vec<u8>, Vec<u16>), rope: &Mask) -> BackgroundView {
        let frame =
            Frame::new(CAMERA.width, CAMERA.height, &images.0, &images.1, 0.001).expect("frame");
        BackgroundView::new(&frame, &CAMERA, rope, &[], (0.1, 3.0))
    }

    #[test]
    fn a_camera_that_moved_is_followed_to_a_fraction_of_its_move() {
        // About the most an arm or a hand moves a camera in a 30th of a second.
        let (to, turn) = (
            Vec3::new(0.006, -0.004, 0.795),
            Vec3::new(0.004, -0.005, 0.008),
        );
        let a = background(&view(HOME, Vec3::zeros(), true, 2.0, 1, None), &no_rope());
        let b = background(&view(to, turn, true, 2.0, 2, None), &no_rope());
        let found = camera_motion(&a, &b).expect("a significant motion");
        let base = Matrix3::new(1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0);
        let truth =
            RigidMotion::between_camera_poses(&base, &HOME, &(rotation_of(&turn) * base), &to);
        // A point on the table straight below, where a rope would lie.
        let p = Vec3::new(0.0, 0.0, 0.8);
        let moved = (truth.apply(&p) - p).norm();
        let error = (found.motion.apply(&p) - truth.apply(&p)).norm();
        assert!(moved > 0.008, "{moved}");
        assert!(error < 0.03 * moved, "{error} of {moved}");
    }

    #[test]
    fn a_still_camera_reads_still_through_image_noise() {
        let a = background(&view(HOME, Vec3::zeros(), true, 2.0, 1, None), &no_rope());
        let b = background(&view(HOME, Vec3::zeros(), true, 2.0, 2, None), &no_rope());
        assert_eq!(camera_motion(&a, &b), None);
    }

    #[test]
    fn a_plain_table_does_not_invent_a_slide_in_its_plane() {
        let to = Vec3::new(0.01, 0.005, 0.8);
        let a = background(&view(HOME, Vec3::zeros(), false, 1.0, 1, None), &no_rope());
        let b = background(&view(to, Vec3::zeros(), false, 1.0, 2, None), &no_rope());
        if let Some(m) = camera_motion(&a, &b) {
            let p = Vec3::new(0.0, 0.0, 0.8);
            assert!((m.motion.apply(&p) - p).norm() < 0.001, "{m:?}");
        }
    }

    /// `images` with the depth noise of a D435i at 640x480 (twice the
    /// fixture's focal length) at each pixel's depth.
    fn noisy_depth(mut images: (Vec<u8>, Vec<u16>), seed: u64) -> (Vec<u8>, Vec<u16>) {
        let mut rng = SplitMix64::new(seed);
        for z in images.1.iter_mut() {
            let metres = *z as f64 * 0.001;
            let noise = crate::perception::camera::depth_noise(metres, 2.0 * CAMERA.fx);
            *z = libm::round((metres + noise * rng.normal()) * 1000.0) as u16;
        }
        images
    }

    #[test]
    fn a_plain_table_s_tilt_does_not_bring_a_made_up_slide_along() {
        // The camera turns about its own x axis over a plain table: the
        // depth shows the tilt, nothing shows a slide along the table.
        let turn = Vec3::new(0.02, 0.0, 0.0);
        let a = background(
            &noisy_depth(view(HOME, Vec3::zeros(), false, 1.0, 1, None), 3),
            &no_rope(),
        );
        let b = background(
            &noisy_depth(view(HOME, turn, false, 1.0, 2, None), 4),
            &no_rope(),
        );
        let base = Matrix3::new(1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0);
        let truth =
            RigidMotion::between_camera_poses(&base, &HOME, &(rotation_of(&turn) * base), &HOME);
        let p = Vec3::new(0.0, 0.0, 0.8);
        let moved = (truth.apply(&p) - p).norm();
        let found = camera_motion(&a, &b).map_or(p, |m| m.motion.apply(&p));
        let error = (found - truth.apply(&p)).norm();
        assert!(error < 0.1 * moved, "{error} of {moved}");
    }

    #[test]
    fn the_depth_rows_cannot_see_a_slide_along_the_table() {
        let turn = Vec3::new(0.3, 0.1, 0.0);
        let images = noisy_depth(view(HOME, turn, true, 2.0, 1, None), 5);
        let a = background(&images, &no_rope());
        let level = &a.levels[0];
        let plane = support_plane(&spread_points(level), a.focal).expect("the table");
        let templates = templates(level, a.noise, &plane, a.focal);
        assert!(templates.len() > 100, "{}", templates.len());
        let n = plane.normal;
        let across = n.cross(&Vec3::x()).normalize();
        let slides = [
            SVector::<f64, 6>::new(across.x, across.y, across.z, 0.0, 0.0, 0.0),
            SVector::<f64, 6>::new(0.0, 0.0, 0.0, n.x, n.y, n.z),
        ];
        let rows = residuals(&templates, level, &RigidMotion::identity(), &n);
        let mut depth_rows = 0;
        for (_, depth) in rows.iter().flatten() {
            if let Some((_, j)) = depth {
                depth_rows += 1;
                for s in &slides {
                    assert!(j.dot(s).abs() < 1e-9 * j.norm(), "{j}");
                }
                // What the tilt and the distance change, they see.
                assert!((flat_basis(&n).transpose() * j).norm() > 0.5 * j.norm());
            }
        }
        assert!(depth_rows > 100, "{depth_rows}");
    }

    #[test]
    fn a_motion_without_its_slide_keeps_its_tilt_and_its_distance() {
        let normal = Vec3::new(0.0, -0.34, -0.94).normalize();
        let basis = flat_basis(&normal);
        // The basis is orthonormal and holds no slide.
        let gram = basis.transpose() * basis;
        assert!((gram - Matrix3::identity()).norm() < 1e-12, "{gram}");
        for column in basis.column_iter() {
            let (t, w) = (column.fixed_rows::<3>(0), column.fixed_rows::<3>(3));
            assert!((t - normal * normal.dot(&t)).norm() < 1e-12);
            assert!(normal.dot(&w).abs() < 1e-12);
        }
        let across = normal.cross(&Vec3::x()).normalize();
        let tilt = across * 0.01;
        let slide = RigidMotion {
            rotation: rotation_of(&(normal * 0.02)),
            translation: across * 0.05 + normal * 0.003,
        };
        let both = RigidMotion {
            rotation: rotation_of(&tilt) * slide.rotation,
            translation: rotation_of(&tilt) * slide.translation,
        };
        let flat = without_slide(&both, &normal);
        let left = nalgebra::Rotation3::from_matrix_unchecked(flat.rotation).scaled_axis();
        assert!((left - tilt).norm() < 3e-4, "{left} against {tilt}");
        assert!(normal.cross(&flat.translation).norm() < 1e-12);
        assert!((normal.dot(&flat.translation) - normal.dot(&both.translation)).abs() < 1e-12);
    }

    #[test]
    fn the_rope_moving_alone_is_not_the_camera() {
        // A third of the image is a strongly textured thing that moves; the
        // mask says it is the rope.
        let mut rope = no_rope();
        for v in 0..CAMERA.height as usize {
            for u in 100..200 {
                rope.data[v * CAMERA.width as usize + u] = true;
            }
        }
        let stripe = |shift| {
            Some(Thing {
                columns: (100.0, 200.0),
                rows: 0..CAMERA.height as usize,
                shift,
                lift: 0.0,
            })
        };
        let a = background(&view(HOME, Vec3::zeros(), true, 2.0, 1, stripe(0.0)), &rope);
        let b = background(&view(HOME, Vec3::zeros(), true, 2.0, 2, stripe(3.0)), &rope);
        assert_eq!(camera_motion(&a, &b), None);
    }

    #[test]
    fn a_box_sliding_over_a_plain_table_is_not_the_camera() {
        // Nothing masks it: it is not the rope and no rectangle was declared.
        let slid = |shift| sliding_box(60..180, shift);
        let a = background(
            &view(HOME, Vec3::zeros(), false, 1.0, 1, slid(0.0)),
            &no_rope(),
        );
        let b = background(
            &view(HOME, Vec3::zeros(), false, 1.0, 2, slid(6.0)),
            &no_rope(),
        );
        assert_eq!(camera_motion(&a, &b), None);
    }

    #[test]
    fn frames_of_any_size_give_no_motion_rather_than_a_panic() {
        for (w, h) in [
            (1u32, 1u32),
            (3, 2),
            (2, 3),
            (1280, 3),
            (3, 1280),
            (641, 17),
        ] {
            let camera = CameraIntrinsics {
                width: w,
                height: h,
                fx: 300.0,
                fy: 300.0,
                cx: w as f64 / 2.0,
                cy: h as f64 / 2.0,
            };
            let n = (w * h) as usize;
            let (rgb, depth) = (vec![128u8; 3 * n], vec![800u16; n]);
            let frame = Frame::new(w, h, &rgb, &depth, 0.001).expect("frame");
            let rope = Mask::new(w, h);
            let a = BackgroundView::new(&frame, &camera, &rope, &[], (0.1, 3.0));
            let mut b = a.clone();
            b.rebuild(&frame, &camera, &rope, &[], (0.1, 3.0));
            assert_eq!(camera_motion(&a, &b), None, "{w}x{h}");
        }
    }

    #[test]
    fn too_little_background_gives_no_motion() {
        let mut rope = no_rope();
        rope.data.iter_mut().for_each(|m| *m = true);
        let a = background(&view(HOME, Vec3::zeros(), true, 2.0, 1, None), &rope);
        let b = background(
            &view(Vec3::new(0.01, 0.0, 0.8), Vec3::zeros(), true, 2.0, 2, None),
            &rope,
        );
        assert_eq!(camera_motion(&a, &b), None);
    }

    #[test]
    fn four_depths_agree_only_when_all_are_known_and_close() {
        assert_eq!(agreed_depth([1.0, 1.0, 1.0, 1.0]), 1.0);
        assert!((agreed_depth([1.0, 1.01, 0.995, 1.005]) - 1.0025).abs() < 1e-6);
        // An unknown depth in any place, or a step between two surfaces.
        for unknown in 0..4 {
            let mut z = [1.0; 4];
            z[unknown] = 0.0;
            assert_eq!(agreed_depth(z), 0.0, "{z:?}");
        }
        assert_eq!(agreed_depth([1.0, 1.0, 1.0, 1.05]), 0.0);
        assert_eq!(agreed_depth([1.05, 1.0, 1.0, 1.0]), 0.0);
    }

    #[test]
    fn depths_outside_the_range_are_unknown() {
        // A tilted camera: the table's depth runs from `near` to `far`.
        let (rgb, depth) = view(HOME, Vec3::new(0.3, 0.0, 0.0), true, 0.0, 1, None);
        let frame = Frame::new(CAMERA.width, CAMERA.height, &rgb, &depth, 0.001).expect("frame");
        let known = |range| {
            let v = BackgroundView::new(&frame, &CAMERA, &no_rope(), &[], range);
            v.levels[0].depth.iter().filter(|&&z| z > 0.0).count()
        };
        let near = *depth.iter().min().expect("pixels") as f64 / 1000.0;
        let far = *depth.iter().max().expect("pixels") as f64 / 1000.0;
        assert!(far - near > 0.1, "{near}..{far}");
        let all = known((near, far));
        assert_eq!(all, CAMERA.width as usize * CAMERA.height as usize);
        assert_eq!(known((0.1, near - 0.001)), 0);
        assert_eq!(known((far + 0.001, 3.0)), 0);
        assert_eq!(known((far, near)), 0);
        let half = known((near, 0.5 * (near + far)));
        assert!(half > all / 4 && half < 3 * all / 4, "{half} of {all}");
    }

    #[test]
    fn a_view_rebuilt_in_another_frames_storage_is_the_view_built_afresh() {
        let rope = {
            let mut m = no_rope();
            for v in 100..110 {
                for u in 40..200 {
                    m.data[v * CAMERA.width as usize + u] = true;
                }
            }
            m
        };
        let images = view(HOME, Vec3::zeros(), true, 2.0, 1, None);
        let fresh = background(&images, &rope);
        // A bigger frame (more levels) with a rope elsewhere, then this one.
        let big = CameraIntrinsics {
            width: 640,
            height: 480,
            ..CAMERA
        };
        let (rgb, depth) = (vec![90u8; 640 * 480 * 3], vec![700u16; 640 * 480]);
        let other = Frame::new(640, 480, &rgb, &depth, 0.001).expect("frame");
        let mut wide_rope = Mask::new(640, 480);
        wide_rope.data[640 * 200..640 * 260].fill(true);
        let mut reused = BackgroundView::new(&other, &big, &wide_rope, &[], (0.1, 3.0));
        let frame =
            Frame::new(CAMERA.width, CAMERA.height, &images.0, &images.1, 0.001).expect("frame");
        reused.rebuild(&frame, &CAMERA, &rope, &[], (0.1, 3.0));
        assert_eq!(reused.levels, fresh.levels);
        assert_eq!(reused.noise, fresh.noise);
        // The rope and a block round it are not background.
        let finest = &fresh.levels[0];
        assert!(!finest.background[99 * finest.width + 39]);
        assert!(finest.background[98 * finest.width + 39]);
        assert!(!finest.background[110 * finest.width + 200]);
        assert!(finest.background[111 * finest.width + 201]);
    }
}
