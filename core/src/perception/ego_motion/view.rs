//! What the motion estimate keeps of a frame: its background as a
//! pyramid of brightness, depth and gradients, built in reused storage.

use alloc::vec::Vec;

use crate::math::{median_abs, Vec3, MAD_TO_SIGMA};
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
/// Most pixels the brightness noise is measured on (an even grid): the
/// median of that many is within about 1 % of the whole image's.
pub const NOISE_SAMPLES: usize = 16_384;
/// A block's depths agree (one surface) when their spread is within this
/// share of their mean.
const DEPTH_AGREEMENT: f32 = 0.02;

/// One level of a frame's pyramid.
#[derive(Debug, Clone, Default, PartialEq)]
pub(super) struct Level {
    pub(super) width: usize,
    pub(super) height: usize,
    /// Brightness, grey levels.
    pub(super) grey: Vec<f32>,
    /// Depth, metres; 0 where unknown or across an edge.
    pub(super) depth: Vec<f32>,
    /// Background: not the rope, not a declared occluder.
    pub(super) background: Vec<bool>,
    /// Brightness gradient along x and y (central differences; 0 on the
    /// border).
    pub(super) gx: Vec<f32>,
    pub(super) gy: Vec<f32>,
    pub(super) fx: f64,
    pub(super) fy: f64,
    pub(super) cx: f64,
    pub(super) cy: f64,
}

impl Level {
    pub(super) fn at(&self, u: usize, v: usize) -> usize {
        v * self.width + u
    }

    /// Pixel `(u, v)` in 3D, metres, where its depth is known.
    pub(super) fn point(&self, u: usize, v: usize) -> Option<Vec3> {
        let z = self.depth[self.at(u, v)] as f64;
        (z > 0.0).then(|| {
            Vec3::new(
                (u as f64 - self.cx) * z / self.fx,
                (v as f64 - self.cy) * z / self.fy,
                z,
            )
        })
    }

    /// Makes this a `width` x `height` level, each pixel `factor` pixels of
    /// the image whose intrinsics are `(fx, fy, cx, cy)`, reusing its
    /// storage (a view is rebuilt every frame: fresh buffers of this size
    /// cost more in page faults than the work done in them).
    fn reshape(
        &mut self,
        (width, height): (usize, usize),
        (fx, fy, cx, cy): (f64, f64, f64, f64),
        factor: f64,
    ) {
        let n = width * height;
        (self.width, self.height) = (width, height);
        for image in [&mut self.grey, &mut self.depth, &mut self.gx, &mut self.gy] {
            image.clear();
            image.resize(n, 0.0);
        }
        self.background.clear();
        self.background.resize(n, true);
        self.fx = fx / factor;
        self.fy = fy / factor;
        self.cx = (cx + 0.5) / factor - 0.5;
        self.cy = (cy + 0.5) / factor - 0.5;
    }

    /// The depth's central-difference gradient at the pixel nearest the
    /// inner point `(x, y)`, where its four neighbours' depths are known.
    pub(super) fn depth_gradient(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let (u, v) = (libm::round(x) as usize, libm::round(y) as usize);
        let at = |u, v| self.depth[self.at(u, v)];
        let (l, r, a, b) = (at(u - 1, v), at(u + 1, v), at(u, v - 1), at(u, v + 1));
        (l > 0.0 && r > 0.0 && a > 0.0 && b > 0.0)
            .then_some((0.5 * (r - l) as f64, 0.5 * (b - a) as f64))
    }

    /// Fills the gradient images from the brightness.
    fn fill_gradients(&mut self) {
        let w = self.width;
        for v in 1..self.height.saturating_sub(1) {
            for u in 1..w - 1 {
                let i = v * w + u;
                self.gx[i] = 0.5 * (self.grey[i + 1] - self.grey[i - 1]);
                self.gy[i] = 0.5 * (self.grey[i + w] - self.grey[i - w]);
            }
        }
    }

    /// Makes `out` this level halved by 2x2 averages.
    fn halve_into(&self, out: &mut Level) {
        let (w, h) = (self.width / 2, self.height / 2);
        let intrinsics = (self.fx, self.fy, self.cx, self.cy);
        out.reshape((w, h), intrinsics, 2.0);
        for v in 0..h {
            let top = 2 * v * self.width;
            let bottom = top + self.width;
            for u in 0..w {
                let ids = [
                    top + 2 * u,
                    top + 2 * u + 1,
                    bottom + 2 * u,
                    bottom + 2 * u + 1,
                ];
                let o = v * w + u;
                out.grey[o] = 0.25 * ids.map(|i| self.grey[i]).iter().sum::<f32>();
                out.depth[o] = agreed_depth(ids.map(|i| self.depth[i]));
                out.background[o] = ids.iter().all(|&i| self.background[i]);
            }
        }
        out.fill_gradients();
    }
}

/// Luma close enough, in integers: `R + 2G + B` (four times it).
#[inline]
fn luma(c: &[u8]) -> u32 {
    c[0] as u32 + 2 * c[1] as u32 + c[2] as u32
}

/// Adds to each of `sums` the luma of its block of `s` pixels of `row`
/// (RGB bytes). Always inlined, so that a constant `s` unrolls.
#[inline(always)]
fn add_block_lumas(row: &[u8], sums: &mut [u32], s: usize) {
    for (sum, block) in sums.iter_mut().zip(row.chunks_exact(3 * s)) {
        *sum += block.chunks_exact(3).map(luma).sum::<u32>();
    }
}

/// The mean of four `depths` when all are known and agree (one surface),
/// else 0.
pub(crate) fn agreed_depth(depths: [f32; 4]) -> f32 {
    // Plain comparisons (no NaN can reach them): the library's min and max
    // handle NaN at a cost this loop over every block notices.
    let [a, b, c, d] = depths;
    let (ab, cd) = (
        if a < b { (a, b) } else { (b, a) },
        if c < d { (c, d) } else { (d, c) },
    );
    let lo = if ab.0 < cd.0 { ab.0 } else { cd.0 };
    let hi = if ab.1 > cd.1 { ab.1 } else { cd.1 };
    let mean = 0.25 * (a + b + c + d);
    if lo > 0.0 && hi - lo <= DEPTH_AGREEMENT * mean {
        mean
    } else {
        0.0
    }
}

/// What the motion estimate keeps of one frame: its pyramid, finest first.
#[derive(Debug, Clone, Default)]
pub struct BackgroundView {
    pub(super) levels: Vec<Level>,
    /// Brightness noise of the finest level, grey levels.
    pub(super) noise: f64,
    /// The full image's focal length, pixels (for the depth noise).
    pub(super) focal: f64,
    /// Working rows of the finest level: block sums and the rope's blocks
    /// (kept to be reused).
    sums: Vec<u32>,
    rope: Vec<bool>,
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
        let mut view = Self::default();
        view.rebuild(frame, camera, rope, occluders, depth_range);
        view
    }

    /// [`BackgroundView::new`] into this view's storage: a tracker keeps
    /// two views (the last frame's and a spare) and rebuilds the spare.
    pub fn rebuild(
        &mut self,
        frame: &Frame<'_>,
        camera: &CameraIntrinsics,
        rope: &Mask,
        occluders: &[Rect],
        depth_range: (f64, f64),
    ) {
        let (fw, fh) = (frame.width as usize, frame.height as usize);
        let s = (frame.width.div_ceil(FINEST_WIDTH)).max(1) as usize;
        let (w, h) = (fw / s, fh / s);
        let intrinsics = (camera.fx, camera.fy, camera.cx, camera.cy);
        if self.levels.is_empty() {
            self.levels.push(Level::default());
        }
        let finest = &mut self.levels[0];
        finest.reshape((w, h), intrinsics, s as f64);
        self.fill_brightness(frame, s);
        self.fill_depth(frame, s, rope, depth_range);
        self.leave_out(frame, s, occluders);
        let finest = &mut self.levels[0];
        finest.fill_gradients();
        let mut count = 1;
        while count < self.levels.len() + 1 {
            let last = &self.levels[count - 1];
            if last.width as u32 <= COARSEST_WIDTH || last.height < 16 {
                break;
            }
            if count == self.levels.len() {
                self.levels.push(Level::default());
            }
            let (done, rest) = self.levels.split_at_mut(count);
            done[count - 1].halve_into(&mut rest[0]);
            count += 1;
        }
        self.levels.truncate(count);
        self.noise = noise(&self.levels[0]);
        self.focal = camera.fx.max(camera.fy);
    }

    /// The finest level's brightness: the mean of each `s` x `s` block.
    fn fill_brightness(&mut self, frame: &Frame<'_>, s: usize) {
        let fw = frame.width as usize;
        let finest = &mut self.levels[0];
        let (w, h) = (finest.width, finest.height);
        // Brightness is the whole block's mean: reading fewer pixels would
        // alias the table's fine texture, which then changes under a move
        // of less than a block. Row by row, so the image is read in order.
        self.sums.clear();
        self.sums.resize(w, 0);
        let inv = 1.0 / (4 * s * s) as f32;
        for v in 0..h {
            self.sums.iter_mut().for_each(|x| *x = 0);
            for y in v * s..(v + 1) * s {
                let row = &frame.color[3 * y * fw..3 * (y * fw + w * s)];
                // Blocks of a known width unroll (the common sizes: the
                // finest level is at most 320 wide).
                let sums = &mut self.sums;
                match s {
                    1 => add_block_lumas(row, sums, 1),
                    2 => add_block_lumas(row, sums, 2),
                    3 => add_block_lumas(row, sums, 3),
                    4 => add_block_lumas(row, sums, 4),
                    _ => add_block_lumas(row, sums, s),
                }
            }
            for (grey, sum) in finest.grey[v * w..(v + 1) * w].iter_mut().zip(&self.sums) {
                *grey = *sum as f32 * inv;
            }
        }
    }

    /// The finest level's depth, and the rope's blocks.
    fn fill_depth(&mut self, frame: &Frame<'_>, s: usize, rope: &Mask, depth_range: (f64, f64)) {
        let fw = frame.width as usize;
        let finest = &mut self.levels[0];
        let (w, h) = (finest.width, finest.height);
        // Depth and the mask at each block's centre 2x2 pixels (one pixel
        // four times when the block is one pixel): depth is smooth where it
        // is used, and the mask is widened by a block below.
        let (off, step) = if s >= 2 { (s / 2 - 1, 1) } else { (0, 0) };
        // The depth range in the frame's units (0, unknown, is outside it):
        // `first..=first + span`, empty when no unit is inside.
        let scale = frame.depth_scale;
        // (A millionth of a unit's slack: 1.234 / 0.001 is 1233.99...).
        let first = libm::ceil(depth_range.0 / scale - 1e-6).max(1.0);
        let last = libm::floor(depth_range.1 / scale + 1e-6).min(u16::MAX as f64);
        let (first, span, scale) = if first <= last {
            (first as u16, (last - first) as u16, scale as f32)
        } else {
            (1, 0, 0.0)
        };
        let metres = |z: u16| {
            if z.wrapping_sub(first) <= span {
                z as f32 * scale
            } else {
                0.0
            }
        };
        let rope_fits = rope.width == frame.width && rope.height == frame.height;
        self.rope.clear();
        self.rope.resize(w * h, false);
        for v in 0..h {
            let top = (v * s + off) * fw;
            let bottom = top + step * fw;
            let (d0, d1) = (
                &frame.depth[top..top + fw],
                &frame.depth[bottom..bottom + fw],
            );
            let blocks = d0[off..].chunks_exact(s).zip(d1[off..].chunks_exact(s));
            for (out, (a, b)) in finest.depth[v * w..(v + 1) * w].iter_mut().zip(blocks) {
                *out = agreed_depth([a[0], a[step], b[0], b[step]].map(metres));
            }
            if rope_fits {
                let (m0, m1) = (&rope.data[top..top + fw], &rope.data[bottom..bottom + fw]);
                // Most rows have no rope: a branch-free test of the whole row.
                if !m0.iter().chain(m1).fold(false, |any, &m| any | m) {
                    continue;
                }
                for u in 0..w {
                    let (x, y) = (u * s + off, u * s + off + step);
                    self.rope[v * w + u] = m0[x] || m0[y] || m1[x] || m1[y];
                }
            }
        }
    }

    /// The finest level's background: all but the rope's blocks widened
    /// by one and the declared `occluders`.
    fn leave_out(&mut self, frame: &Frame<'_>, s: usize, occluders: &[Rect]) {
        let finest = &mut self.levels[0];
        let (w, h) = (finest.width, finest.height);
        // The rope's edge and shadow move with it: one pixel round the mask.
        for (v, row) in self.rope.chunks_exact(w).enumerate() {
            if !row.iter().fold(false, |any, &r| any | r) {
                continue;
            }
            for u in (0..w).filter(|&u| row[u]) {
                let (left, right) = (u.saturating_sub(1), (u + 2).min(w));
                for y in v.saturating_sub(1)..(v + 2).min(h) {
                    finest.background[y * w + left..y * w + right].fill(false);
                }
            }
        }
        for r in occluders {
            if let Some((x0, x1, y0, y1)) = r.clip(frame.width, frame.height) {
                for v in y0 / s..y1.div_ceil(s).min(h) {
                    let row = &mut finest.background[v * w..(v + 1) * w];
                    for b in &mut row[x0 / s..x1.div_ceil(s).min(w)] {
                        *b = false;
                    }
                }
            }
        }
    }
}

/// The brightness noise of `level`'s background, grey levels: the robust
/// spread of the Laplacian `4 I - (its four neighbours)`, whose variance is
/// 20 times the noise's where the image is flat. Read on an even grid of
/// at most [`NOISE_SAMPLES`] pixels.
fn noise(level: &Level) -> f64 {
    let (w, h) = (level.width, level.height);
    let interior = w.saturating_sub(2) * h.saturating_sub(2);
    let stride = (libm::ceil(libm::sqrt(interior as f64 / NOISE_SAMPLES as f64)) as usize).max(1);
    let g = &level.grey;
    let mut laplacian = Vec::with_capacity(interior / (stride * stride) + w + h);
    for v in (1..h.saturating_sub(1)).step_by(stride) {
        for u in (1..w.saturating_sub(1)).step_by(stride) {
            let i = v * w + u;
            if level.background[i] {
                let l = 4.0 * g[i] - g[i - 1] - g[i + 1] - g[i - w] - g[i + w];
                laplacian.push(l as f64);
            }
        }
    }
    MAD_TO_SIGMA * median_abs(&mut laplacian) / libm::sqrt(20.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;
    use alloc::vec;

    #[test]
    fn the_finest_brightness_is_each_block_s_mean_luma_at_every_block_width() {
        // Block widths 1-4 take the unrolled sums, 5 the general one.
        for s in 1..=5usize {
            let (w, h) = (FINEST_WIDTH as usize * s, 4 * s);
            let mut rng = SplitMix64::new(s as u64);
            let color: Vec<u8> = (0..3 * w * h)
                .map(|_| (rng.uniform() * 255.0) as u8)
                .collect();
            let depth = vec![0u16; w * h];
            let frame = Frame::new(w as u32, h as u32, &color, &depth, 0.001).expect("frame");
            let camera = CameraIntrinsics {
                width: w as u32,
                height: h as u32,
                fx: 300.0,
                fy: 300.0,
                cx: 0.5 * w as f64,
                cy: 0.5 * h as f64,
            };
            let rope = Mask::new(w as u32, h as u32);
            let view = BackgroundView::new(&frame, &camera, &rope, &[], (0.1, 3.0));
            let finest = &view.levels[0];
            assert_eq!((finest.width, finest.height), (FINEST_WIDTH as usize, 4));
            for v in 0..finest.height {
                for u in 0..finest.width {
                    let mut sum = 0u32;
                    for y in v * s..(v + 1) * s {
                        for x in u * s..(u + 1) * s {
                            let c = &color[3 * (y * w + x)..3 * (y * w + x) + 3];
                            sum += c[0] as u32 + 2 * c[1] as u32 + c[2] as u32;
                        }
                    }
                    // As the view scales: by the reciprocal.
                    let want = sum as f32 * (1.0 / (4 * s * s) as f32);
                    assert_eq!(finest.grey[v * finest.width + u], want, "s {s} at {u} {v}");
                }
            }
        }
    }
}
