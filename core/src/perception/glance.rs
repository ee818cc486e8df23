//! A glance at a frame's background: whether the camera has stayed still
//! since an earlier frame, read from a sparse grid of the background at a
//! small part of the cost of estimating the camera's motion
//! ([`super::ego_motion`]), which is then needed only when it has not.
//!
//! A motion of the camera moves the image of the whole background: to
//! first order each pixel's brightness changes by its gradient times an
//! image motion that is affine across the image, and the inverse depth of
//! a plane (the table) by an affine function of the pixel. The changes are
//! regressed on those two models and each fit is tested against what it
//! leaves (an F test: the variance it explains per parameter against the
//! residual's). The test needs no noise level: a still camera's noise,
//! whatever its size, explains nothing in either model, while a motion the
//! estimate would resolve explains hundreds of times its share.

use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{SMatrix, SVector};

use crate::math::{median_abs, MAD_TO_SIGMA};
use crate::perception::camera::CameraIntrinsics;
use crate::perception::ego_motion::{
    agreed_depth, FINEST_WIDTH, MIN_POINTS, SIGNIFICANCE, SIGNIFICANCE_3,
};
use crate::perception::frame::Frame;
use crate::perception::segmentation::{Mask, Rect};

/// Background samples a glance reads at most (an even grid): a motion of
/// a tenth of a pixel on a textured table explains several times the
/// test's threshold with this many.
pub const GLANCE_SAMPLES: usize = 2048;
/// A sample the fit leaves further than this many robust deviations from
/// it is something moving on its own (a hand, a gripper) and is left out:
/// a Gaussian residual goes so far about once in 16,000 samples.
const OUTLIER_DEVIATIONS: f64 = 4.0;
/// Ridge on the normal equations, relative to their mean curvature (as the
/// motion estimate's): what the samples leave undetermined explains
/// nothing.
const RIDGE: f64 = 1e-6;

/// One grid point: the mean brightness of its 2x2 pixels, the brightness
/// gradient there (from the pixels beside the block and the difference of
/// its rows: neither correlates with the mean's noise), and its inverse
/// depth. NaN where it is not background or not known.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Sample {
    grey: f32,
    gx: f32,
    gy: f32,
    inverse_depth: f32,
}

impl Sample {
    const NOT_BACKGROUND: Self = Self {
        grey: f32::NAN,
        gx: 0.0,
        gy: 0.0,
        inverse_depth: f32::NAN,
    };
}

/// A sparse grid of one frame's background (see the module's text).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BackgroundGlance {
    width: u32,
    height: u32,
    /// Grid points, row by row.
    samples: Vec<Sample>,
    /// Working row: the rope rows round a grid row, or-ed.
    near: Vec<bool>,
}

/// The grid of a `width` x `height` image: its first point's coordinate
/// and its step (the top left of each sample's 2x2 block, with a pixel
/// beside the block inside the image).
fn grid(width: usize, height: usize) -> (usize, usize) {
    let area = (width * height) as f64;
    let step = (libm::ceil(libm::sqrt(area / GLANCE_SAMPLES as f64)) as usize).max(1);
    ((step / 2).max(1), step)
}

/// The grid points along a side of `length` pixels.
fn along(length: usize, (first, step): (usize, usize)) -> impl Iterator<Item = usize> + Clone {
    (first..length.saturating_sub(2)).step_by(step)
}

impl BackgroundGlance {
    /// The glance of `frame`: the `rope` mask (and a margin round it: its
    /// edge and shadow move with it) and the declared `occluders` are not
    /// background; depths outside `min..=max` metres are unknown.
    pub fn new(
        frame: &Frame<'_>,
        rope: &Mask,
        occluders: &[Rect],
        depth_range: (f64, f64),
    ) -> Self {
        let mut glance = Self::default();
        glance.rebuild(frame, rope, occluders, depth_range);
        glance
    }

    /// [`BackgroundGlance::new`] into this glance's storage.
    pub fn rebuild(
        &mut self,
        frame: &Frame<'_>,
        rope: &Mask,
        occluders: &[Rect],
        (min_depth, max_depth): (f64, f64),
    ) {
        let (w, h) = (frame.width as usize, frame.height as usize);
        (self.width, self.height) = (frame.width, frame.height);
        self.samples.clear();
        let grid = grid(w, h);
        // The margin: one block of the motion estimate's finest level (its
        // own margin round the rope).
        let margin = (frame.width.div_ceil(FINEST_WIDTH) as usize).max(1);
        let rope_fits = rope.width == frame.width && rope.height == frame.height;
        // (R + 2G + B), four times the motion estimate's brightness, in
        // integers: a sample reads twelve pixels.
        let luma = |i: usize| match frame.color.get(3 * i..3 * i + 3) {
            Some(&[r, g, b]) => r as u32 + 2 * g as u32 + b as u32,
            _ => 0,
        };
        // Metres, 0 (unknown) outside the range.
        let metres = |i: usize| {
            let z = frame.depth[i] as f64 * frame.depth_scale;
            if z >= min_depth && z <= max_depth {
                z as f32
            } else {
                0.0
            }
        };
        for v in along(h, grid) {
            // The rope's rows round this grid row, or-ed into one.
            let mut any_rope = false;
            if rope_fits {
                self.near.clear();
                self.near.resize(w, false);
                for y in v.saturating_sub(margin)..(v + 2 + margin).min(h) {
                    let row = &rope.data[y * w..(y + 1) * w];
                    // Branch-free, so that it is vectorised.
                    if row.iter().fold(false, |any, &m| any | m) {
                        any_rope = true;
                        self.near.iter_mut().zip(row).for_each(|(n, &m)| *n |= m);
                    }
                }
            }
            for u in along(w, grid) {
                let near_rope = any_rope
                    && self.near[u.saturating_sub(margin)..(u + 2 + margin).min(w)]
                        .iter()
                        .any(|&m| m);
                let (x, y) = (u as i64, v as i64);
                let covered = occluders
                    .iter()
                    .any(|r| r.contains(x, y) || r.contains(x + 1, y + 1));
                if near_rope || covered {
                    self.samples.push(Sample::NOT_BACKGROUND);
                    continue;
                }
                // The block's pixels a b / c d, and those beside it.
                let (a, c) = (v * w + u, (v + 1) * w + u);
                let (b, d) = (a + 1, c + 1);
                let (la, lb, lc, ld) = (luma(a), luma(b), luma(c), luma(d));
                let grey = (la + lb + lc + ld) as f32 / 16.0;
                let right = (luma(b + 1) + luma(d + 1)) as f32;
                let left = (luma(a - 1) + luma(c - 1)) as f32;
                let (top, bottom) = ((la + lb) as f32, (lc + ld) as f32);
                // One surface, as the motion estimate's blocks.
                let depth = agreed_depth([a, b, c, d].map(metres));
                let inverse_depth = if depth > 0.0 { 1.0 / depth } else { f32::NAN };
                self.samples.push(Sample {
                    grey,
                    // Along x: the columns beside the block; along y its
                    // own rows (one pixel apart: their difference is
                    // uncorrelated with their sum), two pixels of four
                    // times the brightness each. Two rows are read.
                    gx: (right - left) / 24.0,
                    gy: (bottom - top) / 8.0,
                    inverse_depth,
                });
            }
        }
    }

    /// Whether the camera has stayed still from `earlier` (a glance of the
    /// same camera) to this one: neither the brightness changes' fit by an
    /// affine image motion nor the inverse depth changes' fit by an affine
    /// function of the pixel is significant (at the level the motion
    /// estimate takes a motion at). `false` when the glances cannot tell
    /// (other sizes, fewer than [`MIN_POINTS`] samples for both tests).
    pub fn still_since(&self, earlier: &Self, camera: &CameraIntrinsics) -> bool {
        if (self.width, self.height) != (earlier.width, earlier.height)
            || self.samples.len() != earlier.samples.len()
        {
            return false;
        }
        let n = self.samples.len();
        let mut brightness = Fit::<6>::with_capacity(n);
        let mut depth = Fit::<3>::with_capacity(n);
        let (w, h) = (self.width as usize, self.height as usize);
        let grid = grid(w, h);
        let points = along(h, grid).flat_map(|v| along(w, grid).map(move |u| (u, v)));
        let columns = along(w, grid).count();
        let pairs = self.samples.iter().zip(&earlier.samples);
        for (at, ((now, then), (u, v))) in pairs.zip(points).enumerate() {
            let x = (u as f64 + 0.5 - camera.cx) / camera.fx;
            let y = (v as f64 + 0.5 - camera.cy) / camera.fy;
            let change = now.grey as f64 - then.grey as f64;
            if change.is_finite() {
                let (gx, gy) = (then.gx as f64, then.gy as f64);
                brightness.add([gx, gx * x, gx * y, gy, gy * x, gy * y], change, at);
            }
            let change = now.inverse_depth as f64 - then.inverse_depth as f64;
            if change.is_finite() {
                depth.add([1.0, x, y], change, at);
            }
        }
        let verdicts = [
            brightness.significant(SIGNIFICANCE, columns),
            depth.significant(SIGNIFICANCE_3, columns),
        ];
        // Still when a test could tell and none found a motion.
        verdicts.iter().any(Option::is_some) && verdicts.iter().all(|v| *v != Some(true))
    }
}

/// A linear least-squares fit of changes on `P` regressors.
#[derive(Debug, Clone, Default)]
struct Fit<const P: usize> {
    samples: Vec<([f64; P], f64)>,
    /// Each sample's grid point (row-major index).
    at: Vec<usize>,
}

/// A least-squares fit: its coefficients, the squares it explains and
/// those it leaves.
struct Solution<const P: usize> {
    beta: [f64; P],
    explained: f64,
    left: f64,
}

impl<const P: usize> Solution<P> {
    /// The fit's F statistic times `P` on `count` samples (a chi-square of
    /// `P` degrees of freedom under no change, for many samples).
    fn statistic(&self, count: usize) -> f64 {
        if self.explained == 0.0 {
            return 0.0;
        }
        let residual = self.left / count.saturating_sub(P).max(1) as f64;
        if residual > 0.0 {
            self.explained / residual
        } else {
            f64::INFINITY
        }
    }
}

/// The least-squares fit of the `kept` samples (with the ridge), or
/// `None` when no regressor varies. Plain arrays: the normal equations of
/// a few thousand samples are the glance's largest cost.
fn solve<const P: usize>(samples: &[([f64; P], f64)], kept: &[bool]) -> Option<Solution<P>> {
    let mut normal = [[0.0f64; P]; P];
    let (mut moment, mut squares) = ([0.0f64; P], 0.0);
    for ((x, change), _) in samples.iter().zip(kept).filter(|(_, &k)| k) {
        for i in 0..P {
            for j in 0..=i {
                normal[i][j] += x[i] * x[j];
            }
            moment[i] += x[i] * change;
        }
        squares += change * change;
    }
    let mut matrix = SMatrix::<f64, P, P>::from_fn(|i, j| normal[i.max(j)][i.min(j)]);
    let scale = matrix.trace() / P as f64;
    if !(scale > 0.0) {
        return None;
    }
    matrix += SMatrix::<f64, P, P>::identity() * (RIDGE * scale);
    let moment = SVector::<f64, P>::from(moment);
    let beta = matrix.cholesky()?.solve(&moment);
    let explained = beta.dot(&moment).clamp(0.0, squares);
    Some(Solution {
        beta: beta.into(),
        explained,
        left: squares - explained,
    })
}

impl<const P: usize> Fit<P> {
    /// An empty fit with room for `n` samples (a glance's grid).
    fn with_capacity(n: usize) -> Self {
        Self {
            samples: Vec::with_capacity(n),
            at: Vec::with_capacity(n),
        }
    }

    fn add(&mut self, regressors: [f64; P], change: f64, at: usize) {
        self.samples.push((regressors, change));
        self.at.push(at);
    }

    /// Whether the fit explains the changes significantly: its F statistic
    /// (times `P`) above `chi_square` (the chi-square of `P` degrees of
    /// freedom at the level; the F distribution's limit for many samples),
    /// on the samples the fit leaves within [`OUTLIER_DEVIATIONS`] of it
    /// and not next to one it leaves out on the `columns` wide
    /// grid: something moving on its own in a still scene (a hand, a
    /// gripper) is a region of the image, not a motion of the whole of it,
    /// and the samples of that region whose change happens to be small
    /// would still pull the fit. `Some(true)` as well when that leaves out
    /// most samples (more changed than a first-order motion says), and
    /// `None` when it cannot tell (too few samples, no regressor varies).
    fn significant(&self, chi_square: f64, columns: usize) -> Option<bool> {
        let count = self.samples.len();
        if count < MIN_POINTS.max(P + 1) {
            return None;
        }
        let mut kept = vec![true; count];
        let whole = solve(&self.samples, &kept)?;
        let residual = |(x, change): &([f64; P], f64)| {
            change - x.iter().zip(&whole.beta).map(|(x, b)| x * b).sum::<f64>()
        };
        let mut residuals: Vec<f64> = self.samples.iter().map(residual).collect();
        let limit = OUTLIER_DEVIATIONS * MAD_TO_SIGMA * median_abs(&mut residuals);
        for (k, s) in kept.iter_mut().zip(&self.samples) {
            *k = residual(s).abs() <= limit;
        }
        if kept.iter().all(|&k| k) {
            // Nothing moves on its own.
            return Some(whole.statistic(count) > chi_square);
        }
        // The region round each sample left out.
        let rows = self.at.iter().max().map_or(0, |&i| i / columns.max(1) + 1);
        let mut out = vec![false; columns * rows];
        for (&i, &k) in self.at.iter().zip(&kept) {
            out[i] |= !k;
        }
        let near_out = |i: usize| {
            let (u, v) = (i % columns, i / columns);
            (v.saturating_sub(1)..(v + 2).min(rows))
                .any(|y| (u.saturating_sub(1)..(u + 2).min(columns)).any(|x| out[y * columns + x]))
        };
        for (k, &i) in kept.iter_mut().zip(&self.at) {
            *k = !near_out(i);
        }
        let left = kept.iter().filter(|&&k| k).count();
        if 2 * left < count {
            return Some(true);
        }
        if left < MIN_POINTS.max(P + 1) {
            return None;
        }
        let rest = solve(&self.samples, &kept)?;
        Some(rest.statistic(left) > chi_square)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::perception::ego_motion::fixture::*;
    use crate::perception::ego_motion::{camera_motion, BackgroundView};

    fn frame(images: &(Vec<u8>, Vec<u16>)) -> Frame<'_> {
        Frame::new(CAMERA.width, CAMERA.height, &images.0, &images.1, 0.001).expect("frame")
    }

    fn glance(images: &(Vec<u8>, Vec<u16>), rope: &Mask) -> BackgroundGlance {
        BackgroundGlance::new(&frame(images), rope, &[], (0.1, 3.0))
    }

    fn table_from(
        centre: Vec3,
        turn: Vec3,
        textured: bool,
        noise: f64,
        seed: u64,
    ) -> (Vec<u8>, Vec<u16>) {
        view(centre, turn, textured, noise, seed, None)
    }

    #[test]
    fn a_still_camera_reads_still_whatever_the_image_noise() {
        for (textured, noise) in [(true, 0.5), (true, 2.0), (true, 12.0), (false, 2.0)] {
            let a = glance(
                &table_from(HOME, Vec3::zeros(), textured, noise, 1),
                &no_rope(),
            );
            let b = glance(
                &table_from(HOME, Vec3::zeros(), textured, noise, 2),
                &no_rope(),
            );
            assert!(
                b.still_since(&a, &CAMERA),
                "textured {textured}, noise {noise}"
            );
        }
    }

    #[test]
    fn a_still_camera_is_seldom_taken_for_a_moving_one() {
        // At the 0.999 level two tests read a still camera moved about once
        // in 500 pairs; each time the glance errs this way the estimate
        // runs (and finds no motion).
        let moved = (0..24)
            .filter(|&seed| {
                let a = glance(
                    &table_from(HOME, Vec3::zeros(), true, 3.0, 2 * seed),
                    &no_rope(),
                );
                let b = glance(
                    &table_from(HOME, Vec3::zeros(), true, 3.0, 2 * seed + 1),
                    &no_rope(),
                );
                !b.still_since(&a, &CAMERA)
            })
            .count();
        assert!(moved <= 1, "{moved} of 24 still pairs read moved");
    }

    #[test]
    fn every_motion_the_estimate_takes_is_seen() {
        // Moves from a tenth of a pixel to several: the glance must never
        // skip what the estimate would take.
        let px = HOME.z / CAMERA.fx;
        let moves = [
            (Vec3::new(0.1 * px, 0.0, 0.0), Vec3::zeros()),
            (Vec3::new(0.2 * px, 0.0, 0.0), Vec3::zeros()),
            (Vec3::new(0.0, 0.3 * px, 0.0), Vec3::zeros()),
            (Vec3::new(0.0, 0.0, -0.002), Vec3::zeros()),
            (Vec3::zeros(), Vec3::new(0.0, 0.0, 0.0008)),
            (
                Vec3::new(4.0 * px, -2.0 * px, 0.003),
                Vec3::new(0.002, -0.003, 0.004),
            ),
        ];
        let mut taken = 0;
        for (k, (shift, turn)) in moves.into_iter().enumerate() {
            // Noise up to where the estimate no longer takes the smallest.
            for noise in [2.0, 6.0, 10.0] {
                let (a, b) = (
                    table_from(HOME, Vec3::zeros(), true, noise, 1),
                    table_from(HOME + shift, turn, true, noise, 2),
                );
                let estimate = camera_motion(
                    &BackgroundView::new(&frame(&a), &CAMERA, &no_rope(), &[], (0.1, 3.0)),
                    &BackgroundView::new(&frame(&b), &CAMERA, &no_rope(), &[], (0.1, 3.0)),
                );
                taken += usize::from(estimate.is_some());
                let still = glance(&b, &no_rope()).still_since(&glance(&a, &no_rope()), &CAMERA);
                let what = alloc::format!(
                    "move {k} at noise {noise} (the estimate took it: {})",
                    estimate.is_some()
                );
                assert!(!(still && estimate.is_some()), "{what}");
                assert!(!still || noise > 2.0, "{what}");
            }
        }
        assert!(taken >= 8, "the estimate took {taken} of the moves");
    }

    #[test]
    fn a_box_moving_over_the_table_is_not_the_camera_moving() {
        // A textured box lifted off the table slides 3 px across a fifth of
        // the image; nothing masks it.
        let slid = |shift| sliding_box(60..160, shift);
        let a = glance(
            &view(HOME, Vec3::zeros(), true, 2.0, 1, slid(0.0)),
            &no_rope(),
        );
        let b = glance(
            &view(HOME, Vec3::zeros(), true, 2.0, 2, slid(3.0)),
            &no_rope(),
        );
        assert!(b.still_since(&a, &CAMERA), "the box read as the camera");
        // The camera moving as well is still seen.
        let px = HOME.z / CAMERA.fx;
        let moved = view(
            HOME + Vec3::new(0.3 * px, 0.0, 0.0),
            Vec3::zeros(),
            true,
            2.0,
            2,
            slid(3.0),
        );
        assert!(!glance(&moved, &no_rope()).still_since(&a, &CAMERA));
    }

    #[test]
    fn a_camera_moving_towards_a_plain_table_is_seen_in_its_depth() {
        let a = glance(&table_from(HOME, Vec3::zeros(), false, 1.0, 1), &no_rope());
        let b = glance(
            &table_from(Vec3::new(0.0, 0.0, 0.795), Vec3::zeros(), false, 1.0, 2),
            &no_rope(),
        );
        assert!(!b.still_since(&a, &CAMERA));
    }

    #[test]
    fn glances_that_cannot_tell_are_not_still() {
        let images = table_from(HOME, Vec3::zeros(), true, 2.0, 1);
        let mut all = no_rope();
        all.data.fill(true);
        assert!(!glance(&images, &all).still_since(&glance(&images, &all), &CAMERA));
        let other = BackgroundGlance::default();
        assert!(!glance(&images, &no_rope()).still_since(&other, &CAMERA));
        assert!(!other.still_since(&other, &CAMERA));
    }

    #[test]
    fn frames_of_any_size_give_a_glance_without_a_panic() {
        for (w, h) in [(1, 1), (3, 2), (2, 3), (5, 5), (6, 7), (641, 17), (17, 641)] {
            let (rgb, depth) = (vec![90u8; 3 * w * h], vec![800u16; w * h]);
            let frame = Frame::new(w as u32, h as u32, &rgb, &depth, 0.001).expect("frame");
            let mut rope = Mask::new(w as u32, h as u32);
            rope.data[0] = true;
            let box_over = [Rect {
                x: -3,
                y: -3,
                w: 4,
                h: 4,
            }];
            let a = BackgroundGlance::new(&frame, &rope, &box_over, (0.1, 3.0));
            let b = BackgroundGlance::new(&frame, &Mask::new(1, 1), &[], (0.1, 3.0));
            let camera = CameraIntrinsics {
                width: w as u32,
                height: h as u32,
                ..CAMERA
            };
            // Identical plain frames: still where the glance can tell, never a panic.
            let _ = a.still_since(&b, &camera);
            assert!(!a.still_since(&BackgroundGlance::default(), &camera));
        }
    }

    #[test]
    fn the_same_images_read_still() {
        let images = table_from(HOME, Vec3::zeros(), true, 2.0, 1);
        let a = glance(&images, &no_rope());
        assert!(a.still_since(&a, &CAMERA));
    }
}
