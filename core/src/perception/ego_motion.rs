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
//! still.

use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{Matrix3, SMatrix, SVector};

use crate::math::Vec3;
use crate::motion::{rotation_of, RigidMotion};
use crate::perception::camera::CameraIntrinsics;
use crate::perception::frame::Frame;
use crate::perception::segmentation::{Mask, Rect};

/// Width, pixels, the finest level is box-averaged down to (at most): the
/// motion of a background a metre away is then found to a few tenths of a
/// millimetre (at 160 px, on 1280x720 images, errors were 20-30 % of a
/// handheld camera's move). Coarser levels halve it.
pub const FINEST_WIDTH: u32 = 320;
/// Width, pixels, at which halving stops: the coarsest level still has a
/// few hundred textured pixels and catches a move of several pixels.
pub const COARSEST_WIDTH: u32 = 40;
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
/// A pixel is decisive when its own loss changes by more than the
/// chi-square of one degree of freedom at 0.95 (in units of the
/// residuals' variance, twice the loss).
const DECISIVE: f64 = 3.84;
/// The median absolute residual times this is the standard deviation of
/// Gaussian residuals.
const MAD_TO_SIGMA: f64 = 1.4826;
/// Smallest brightness noise assumed, grey levels (8-bit images quantise).
const MIN_BRIGHTNESS_SIGMA: f64 = 0.5;
/// Smallest depth noise assumed, metres (millimetre depth units).
const MIN_DEPTH_SIGMA: f64 = 0.0005;
/// A block's depths agree (one surface) when their spread is within this
/// share of their mean.
const DEPTH_AGREEMENT: f32 = 0.02;
/// The chi-square of six degrees of freedom at 0.999: how much better (in
/// units of the residuals' variance) the motion must explain the images
/// than no motion to be taken.
const SIGNIFICANCE: f64 = 22.46;
/// Ridge on the normal equations, relative to their mean curvature: what
/// the background leaves undetermined (a flat, plain table's slide) is
/// taken as no motion.
const RIDGE: f64 = 1e-6;

/// One level of a frame's pyramid.
#[derive(Debug, Clone)]
struct Level {
    width: usize,
    height: usize,
    /// Brightness, grey levels.
    grey: Vec<f32>,
    /// Depth, metres; 0 where unknown or across an edge.
    depth: Vec<f32>,
    /// Background: not the rope, not a declared occluder.
    background: Vec<bool>,
    /// Brightness gradient along x and y (central differences; 0 on the
    /// border).
    gx: Vec<f32>,
    gy: Vec<f32>,
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
}

impl Level {
    fn at(&self, u: usize, v: usize) -> usize {
        v * self.width + u
    }

    /// Pixel `(u, v)` in 3D, metres, where its depth is known.
    fn point(&self, u: usize, v: usize) -> Option<Vec3> {
        let z = self.depth[self.at(u, v)] as f64;
        (z > 0.0).then(|| {
            Vec3::new(
                (u as f64 - self.cx) * z / self.fx,
                (v as f64 - self.cy) * z / self.fy,
                z,
            )
        })
    }

    /// A `width` x `height` level of images `grey`, `depth` and
    /// `background`, each pixel `factor` pixels of the image whose
    /// intrinsics are `(fx, fy, cx, cy)`; its gradients filled.
    fn new(
        (width, height): (usize, usize),
        grey: Vec<f32>,
        depth: Vec<f32>,
        background: Vec<bool>,
        (fx, fy, cx, cy): (f64, f64, f64, f64),
        factor: f64,
    ) -> Self {
        Self {
            width,
            height,
            grey,
            depth,
            background,
            gx: Vec::new(),
            gy: Vec::new(),
            fx: fx / factor,
            fy: fy / factor,
            cx: (cx + 0.5) / factor - 0.5,
            cy: (cy + 0.5) / factor - 0.5,
        }
        .with_gradients()
    }

    /// The depth's central-difference gradient at the pixel nearest the
    /// inner point `(x, y)`, where its four neighbours' depths are known.
    fn depth_gradient(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let (u, v) = (libm::round(x) as usize, libm::round(y) as usize);
        let at = |u, v| self.depth[self.at(u, v)];
        let (l, r, a, b) = (at(u - 1, v), at(u + 1, v), at(u, v - 1), at(u, v + 1));
        (l > 0.0 && r > 0.0 && a > 0.0 && b > 0.0)
            .then_some((0.5 * (r - l) as f64, 0.5 * (b - a) as f64))
    }

    /// Fills the gradient images from the brightness.
    fn with_gradients(mut self) -> Self {
        let w = self.width;
        self.gx = vec![0.0; self.grey.len()];
        self.gy = vec![0.0; self.grey.len()];
        for v in 1..self.height.saturating_sub(1) {
            for u in 1..w - 1 {
                let i = v * w + u;
                self.gx[i] = 0.5 * (self.grey[i + 1] - self.grey[i - 1]);
                self.gy[i] = 0.5 * (self.grey[i + w] - self.grey[i - w]);
            }
        }
        self
    }

    /// The level below, halved by 2x2 averages.
    fn halved(&self) -> Self {
        let (w, h) = (self.width / 2, self.height / 2);
        let mut grey = vec![0.0; w * h];
        let mut depth = vec![0.0; w * h];
        let mut background = vec![false; w * h];
        for v in 0..h {
            for u in 0..w {
                let ids = [
                    self.at(2 * u, 2 * v),
                    self.at(2 * u + 1, 2 * v),
                    self.at(2 * u, 2 * v + 1),
                    self.at(2 * u + 1, 2 * v + 1),
                ];
                let o = v * w + u;
                grey[o] = 0.25 * ids.iter().map(|&i| self.grey[i]).sum::<f32>();
                depth[o] = agreed_depth(ids.iter().map(|&i| self.depth[i]));
                background[o] = ids.iter().all(|&i| self.background[i]);
            }
        }
        let intrinsics = (self.fx, self.fy, self.cx, self.cy);
        Self::new((w, h), grey, depth, background, intrinsics, 2.0)
    }
}

/// The mean of `depths` when all are known and agree (one surface), else 0.
fn agreed_depth(depths: impl Iterator<Item = f32>) -> f32 {
    let (mut lo, mut hi, mut sum, mut n) = (f32::INFINITY, 0.0f32, 0.0f32, 0u32);
    for z in depths {
        if !(z > 0.0) {
            return 0.0;
        }
        lo = lo.min(z);
        hi = hi.max(z);
        sum += z;
        n += 1;
    }
    if n == 0 {
        return 0.0;
    }
    let mean = sum / n as f32;
    if hi - lo <= DEPTH_AGREEMENT * mean {
        mean
    } else {
        0.0
    }
}

/// What the motion estimate keeps of one frame: its pyramid, finest first.
#[derive(Debug, Clone)]
pub struct BackgroundView {
    levels: Vec<Level>,
    /// Brightness noise of the finest level, grey levels.
    noise: f64,
    /// The full image's focal length, pixels (for the depth noise).
    focal: f64,
}

impl BackgroundView {
    /// The pyramid of `frame` seen by `camera` (the frame's own size),
    /// with the `rope` mask (and a pixel round it) and the declared
    /// `occluders` left out of the background; depths outside
    /// `min_depth..=max_depth` metres are unknown.
    pub fn new(
        frame: &Frame<'_>,
        camera: &CameraIntrinsics,
        rope: &Mask,
        occluders: &[Rect],
        depth_range: (f64, f64),
    ) -> Self {
        let (fw, fh) = (frame.width as usize, frame.height as usize);
        let s = (frame.width.div_ceil(FINEST_WIDTH)).max(1) as usize;
        let (w, h) = (fw / s, fh / s);
        let mut excluded = vec![false; w * h];
        let rope_fits = rope.width == frame.width && rope.height == frame.height;
        let (zmin, zmax) = (depth_range.0 as f32, depth_range.1 as f32);
        let scale = frame.depth_scale as f32;
        let mut grey = vec![0.0f32; w * h];
        let mut depth = vec![0.0f32; w * h];
        // Brightness is the whole block's mean: reading fewer pixels would
        // alias the table's fine texture, which then changes under a move
        // of less than a block. Row by row, so the image is read in order.
        let mut sums = vec![0u32; w];
        for v in 0..h {
            sums.iter_mut().for_each(|x| *x = 0);
            for y in v * s..(v + 1) * s {
                let row = &frame.color[3 * y * fw..3 * (y * fw + w * s)];
                for (sum, block) in sums.iter_mut().zip(row.chunks_exact(3 * s)) {
                    for c in block.chunks_exact(3) {
                        // Luma close enough, in integers: (R + 2G + B) / 4.
                        *sum += c[0] as u32 + 2 * c[1] as u32 + c[2] as u32;
                    }
                }
            }
            let inv = 1.0 / (4 * s * s) as f32;
            for (u, sum) in sums.iter().enumerate() {
                grey[v * w + u] = *sum as f32 * inv;
            }
        }
        // Depth and the mask at each block's centre 2x2 pixels (one pixel
        // four times when the block is one pixel): depth is smooth where it
        // is used, and the mask is widened by a block below.
        let (off, step) = if s >= 2 { (s / 2 - 1, 1) } else { (0, 0) };
        let reading = |z: u16| {
            let z = z as f32 * scale;
            if z >= zmin && z <= zmax {
                z
            } else {
                0.0
            }
        };
        for v in 0..h {
            let top = (v * s + off) * fw;
            let bottom = top + step * fw;
            for u in 0..w {
                let x = u * s + off;
                let ids = [top + x, top + x + step, bottom + x, bottom + x + step];
                let o = v * w + u;
                excluded[o] = rope_fits && ids.iter().any(|&i| rope.data[i]);
                depth[o] = agreed_depth(ids.iter().map(|&i| reading(frame.depth[i])));
            }
        }
        // The rope's edge and shadow move with it: one pixel round the mask.
        let mut background = vec![true; w * h];
        for v in 0..h {
            for u in 0..w {
                if excluded[v * w + u] {
                    for y in v.saturating_sub(1)..(v + 2).min(h) {
                        for x in u.saturating_sub(1)..(u + 2).min(w) {
                            background[y * w + x] = false;
                        }
                    }
                }
            }
        }
        for r in occluders {
            if let Some((x0, x1, y0, y1)) = r.clip(frame.width, frame.height) {
                for v in y0 / s..y1.div_ceil(s).min(h) {
                    for b in &mut background[v * w + x0 / s..v * w + x1.div_ceil(s).min(w)] {
                        *b = false;
                    }
                }
            }
        }
        let intrinsics = (camera.fx, camera.fy, camera.cx, camera.cy);
        let finest = Level::new((w, h), grey, depth, background, intrinsics, s as f64);
        let mut levels = vec![finest];
        while let Some(last) = levels.last() {
            if last.width as u32 <= COARSEST_WIDTH || last.height < 16 {
                break;
            }
            let next = last.halved();
            levels.push(next);
        }
        let noise = noise(&levels[0]);
        Self {
            levels,
            noise,
            focal: camera.fx.max(camera.fy),
        }
    }
}

/// A followed background pixel of the earlier frame.
struct Template {
    /// Where it is, metres, the earlier camera's frame.
    point: Vec3,
    /// Its brightness, where it is textured enough to follow by it.
    grey: Option<f64>,
}

/// The background pixels of `level` with a depth, one in each cell of a
/// grid: the one with the strongest gradient above [`GRADIENT_FLOOR`],
/// followed by brightness and depth, else the cell's first, followed by
/// depth alone. Every part of the background speaks: a plain table by its
/// plane, so that a textured hand moving over it is outvoted.
/// `noise` is the level's brightness noise.
/// With a `plane` (and the focal length for its tolerance), only pixels on
/// it count, and a textured one only when the four neighbours its gradient
/// is taken from are on it too: the edge of a box standing on the table is
/// the box's texture, not the table's.
fn templates(level: &Level, noise: f64, plane: Option<(&Plane, f64)>) -> Vec<Template> {
    let on = |u: usize, v: usize| {
        plane.is_none_or(|(plane, focal)| level.point(u, v).is_some_and(|p| plane.holds(&p, focal)))
    };
    let floor =
        GRADIENT_FLOOR.max((GRADIENT_NOISE_SCALES * noise / core::f64::consts::SQRT_2) as f32);
    let area = level.width * level.height;
    let cell = (libm::ceil(libm::sqrt(area as f64 / MAX_POINTS as f64)) as usize).max(1);
    let mut out = Vec::new();
    for cv in (1..level.height - 1).step_by(cell) {
        for cu in (1..level.width - 1).step_by(cell) {
            let mut best: Option<(f32, usize, usize)> = None;
            let mut plain = None;
            for v in cv..(cv + cell).min(level.height - 1) {
                for u in cu..(cu + cell).min(level.width - 1) {
                    let i = level.at(u, v);
                    if !level.background[i] || !(level.depth[i] > 0.0) {
                        continue;
                    }
                    let (gx, gy) = (level.gx[i], level.gy[i]);
                    let g = libm::sqrtf(gx * gx + gy * gy);
                    let better = g >= floor && best.is_none_or(|b| g > b.0);
                    if (plain.is_none() || better) && on(u, v) {
                        plain = plain.or(Some((u, v)));
                        let stencil = [(u - 1, v), (u + 1, v), (u, v - 1), (u, v + 1)];
                        if better && stencil.iter().all(|&(x, y)| on(x, y)) {
                            best = Some((g, u, v));
                        }
                    }
                }
            }
            let chosen = best.map(|(_, u, v)| (u, v, true));
            if let Some((u, v, textured)) = chosen.or(plain.map(|(u, v)| (u, v, false))) {
                if let Some(point) = level.point(u, v) {
                    out.push(Template {
                        point,
                        grey: textured.then_some(level.grey[level.at(u, v)] as f64),
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

    fn distance(&self, p: &Vec3) -> f64 {
        (self.normal.dot(p) - self.offset).abs()
    }

    /// How far from a plane `p` may lie and still be on it.
    fn tolerance(p: &Vec3, focal: f64) -> f64 {
        PLANE_SIGMAS * crate::perception::camera::depth_noise(p.z, focal).max(MIN_DEPTH_SIGMA)
    }

    fn holds(&self, p: &Vec3, focal: f64) -> bool {
        self.distance(p) <= Self::tolerance(p, focal)
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
    let scored: Vec<(Vec3, f64)> = points
        .iter()
        .step_by(stride)
        .map(|p| (*p, Plane::tolerance(p, focal)))
        .collect();
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
            .filter(|(p, tol)| plane.distance(p) <= *tol)
            .count();
        if best.is_none_or(|(k, _)| count > k) {
            best = Some((count, plane));
        }
    }
    best.map(|(_, plane)| plane)
}

/// The brightness noise of `level`'s background, grey levels: the robust
/// spread of the Laplacian `4 I - (its four neighbours)`, whose variance is
/// 20 times the noise's where the image is flat.
fn noise(level: &Level) -> f64 {
    let mut laplacian = Vec::new();
    for v in 1..level.height - 1 {
        for u in 1..level.width - 1 {
            let i = level.at(u, v);
            if level.background[i] {
                let g = &level.grey;
                let l = 4.0 * g[i] - g[i - 1] - g[i + 1] - g[i - level.width] - g[i + level.width];
                laplacian.push(l as f64);
            }
        }
    }
    MAD_TO_SIGMA * median_abs(&mut laplacian) / libm::sqrt(20.0)
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
    let lerp = |f: &dyn Fn(usize, usize) -> f32| {
        let top = f(u, v) * (1.0 - a) + f(u + 1, v) * a;
        let bottom = f(u, v + 1) * (1.0 - a) + f(u + 1, v + 1) * a;
        (top * (1.0 - b) + bottom * b) as f64
    };
    let grey = lerp(&|u, v| level.grey[level.at(u, v)]);
    let gx = lerp(&|u, v| level.gx[level.at(u, v)]);
    let gy = lerp(&|u, v| level.gy[level.at(u, v)]);
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

/// The median of `|v|` (0 for none); reorders `v`.
fn median_abs(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    for x in v.iter_mut() {
        *x = x.abs();
    }
    let mid = v.len() / 2;
    v.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
    v[mid]
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

fn residuals(templates: &[Template], later: &Level, motion: &RigidMotion) -> Rows {
    let mut rows = Vec::with_capacity(templates.len());
    for t in templates {
        rows.push(residual(t, later, motion));
    }
    rows
}

/// [`residuals`] of one template.
fn residual(t: &Template, later: &Level, motion: &RigidMotion) -> Option<Row> {
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
            (z - p.z, increment(along))
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

/// One Gauss-Newton update of `motion`, or `None` when the normal
/// equations cannot be solved.
fn update(rows: &Rows, (sb, sd): (f64, f64)) -> Option<SVector<f64, 6>> {
    let mut a = SMatrix::<f64, 6, 6>::zeros();
    let mut g = SVector::<f64, 6>::zeros();
    let mut add = |r: f64, j: &SVector<f64, 6>, s: f64| {
        let (r, j) = (r / s, j / s);
        let w = cauchy_weight(r);
        a += j * j.transpose() * w;
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
    let scale = a.trace() / 6.0;
    if !(scale > 0.0) {
        return None;
    }
    a += SMatrix::<f64, 6, 6>::identity() * (RIDGE * scale);
    let x = -a.cholesky()?.solve(&g);
    x.iter().all(|v| v.is_finite()).then_some(x)
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
    let on_plane = {
        let points: Vec<Vec3> = templates(&earlier.levels[0], earlier.noise, None)
            .iter()
            .map(|t| t.point)
            .collect();
        support_plane(&points, earlier.focal)?
    };
    for (k, (e, l)) in earlier.levels.iter().zip(&later.levels).enumerate().rev() {
        if e.width != l.width || e.height != l.height {
            return None;
        }
        // Halving averages four pixels: half the noise per level.
        let noise = earlier.noise / (1u32 << k) as f64;
        let templates = templates(e, noise, Some((&on_plane, earlier.focal)));
        let depth =
            templates.iter().map(|t| t.point.z).sum::<f64>() / templates.len().max(1) as f64;
        for _ in 0..MAX_ITERATIONS {
            let rows = residuals(&templates, l, &motion);
            if rows.iter().flatten().count() < MIN_POINTS {
                break;
            }
            let Some(x) = update(&rows, spreads(&rows)) else {
                break;
            };
            let (v, w) = (Vec3::new(x[0], x[1], x[2]), Vec3::new(x[3], x[4], x[5]));
            let turn: Matrix3<f64> = rotation_of(&w);
            motion = RigidMotion {
                rotation: turn * motion.rotation,
                translation: turn * motion.translation + v,
            };
            if l.fx * (v.norm() / depth + w.norm()) < CONVERGED_PX {
                break;
            }
        }
        finest = Some(templates);
    }
    let templates = finest?;
    let moved = residuals(&templates, &later.levels[0], &motion);
    let still = residuals(&templates, &later.levels[0], &RigidMotion::identity());
    // Judged on the pixels both follow, at the motion's deviations.
    let s = spreads(&moved);
    let (mut points, mut gain, mut shift) = (0, 0.0, 0.0);
    let (mut better, mut decisive) = (0usize, 0usize);
    let finest = &later.levels[0];

    for ((m, n), t) in moved.iter().zip(&still).zip(&templates) {
        if let (Some(m), Some(n)) = (m, n) {
            points += 1;
            let drop = 2.0 * (loss(n, s) - loss(m, s));
            gain += drop;
            if drop.abs() > DECISIVE {
                decisive += 1;
                better += usize::from(drop > 0.0);
            }
            let (p, q) = (t.point, motion.apply(&t.point));
            let du = finest.fx * (q.x / q.z - p.x / p.z);
            let dv = finest.fy * (q.y / q.z - p.y / p.z);
            shift += libm::sqrt(du * du + dv * dv);
        }
    }
    let shift_px = shift / points.max(1) as f64;
    let support = better as f64 / decisive.max(1) as f64;
    let resolved = shift_px >= MIN_RESOLVED_SHIFT;
    let shared = decisive >= MIN_DECISIVE && support >= WHOLE_BACKGROUND_SHARE;
    let taken =
        points >= MIN_POINTS && resolved && shared && gain > SIGNIFICANCE && motion.is_finite();
    taken.then_some(CameraMotion {
        motion,
        points,
        gain,
        shift_px,
        support,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    const CAMERA: CameraIntrinsics = CameraIntrinsics {
        width: 320,
        height: 240,
        fx: 300.0,
        fy: 300.0,
        cx: 160.0,
        cy: 120.0,
    };

    /// A table's brightness at world `(x, y)` (metres): value noise (a
    /// hashed lattice, interpolated) at 4 cm and 1 cm, or plain grey.
    fn table(x: f64, y: f64, textured: bool) -> f64 {
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
    fn view(
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
    struct Thing {
        columns: (f64, f64),
        rows: core::ops::Range<usize>,
        shift: f64,
        lift: f64,
    }

    fn background(images: &(Vec<u8>, Vec<u16>), rope: &Mask) -> BackgroundView {
        let frame =
            Frame::new(CAMERA.width, CAMERA.height, &images.0, &images.1, 0.001).expect("frame");
        BackgroundView::new(&frame, &CAMERA, rope, &[], (0.1, 3.0))
    }

    fn no_rope() -> Mask {
        Mask::new(CAMERA.width, CAMERA.height)
    }

    const HOME: Vec3 = Vec3::new(0.0, 0.0, 0.8);

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
        let slid = |shift| {
            Some(Thing {
                columns: (60.0, 160.0),
                rows: 60..180,
                shift,
                lift: 0.06,
            })
        };
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
}
