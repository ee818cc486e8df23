//! How much of the rope's width its colour mask covers, read across the
//! centre line in the depth image, and the push from the surface the mask
//! sees to the rope's axis. A white or grey rope's shaded edges fall out of
//! its colour range: its mask is a strip along the middle, nearer the
//! camera on average than the whole width's surface, and narrower than the
//! rope, so a push of [`SURFACE_TO_AXIS_RATIO`] of its half width leaves
//! the cloud in front of the axis.

use alloc::vec::Vec;

use super::candidates::median;
use super::lift::NO_ZONE;
use crate::math::Vec2;
use crate::perception::camera::{depth_noise, CameraIntrinsics};
use crate::perception::frame::Frame;
#[cfg(doc)]
use crate::perception::point_cloud::SURFACE_TO_AXIS_RATIO;
use crate::perception::point_cloud::{depth_at, CloudSettings};
use crate::perception::segmentation::Mask;

/// Most centre-line points whose cross-section is read (evenly spread).
pub const MAX_SECTION_SAMPLES: usize = 256;
/// Fewest cross-sections read for a cover.
pub const MIN_SECTION_SAMPLES: usize = 8;
/// Narrowest mask (half width, pixels) whose cross-section is read: a rope
/// a few pixels wide has no depth profile to speak of.
pub const MIN_SECTION_HALF_WIDTH_PX: f64 = 2.0;
/// The background beside the rope is read from this many of the mask's
/// half widths off the centre line...
pub const BACKGROUND_FROM_HALF_WIDTHS: f64 = 2.5;
/// ...to this many: beyond the rope's edge when the mask covers as little
/// as 0.6 of the width, within a short reach of it.
pub const BACKGROUND_TO_HALF_WIDTHS: f64 = 4.0;
/// A side is read only when the background lies this many depth
/// deviations (at the rope's depth) behind the rope's top: a rope's pixel
/// is then told from the background's by a threshold half way between them.
pub const SECTION_CONTRAST_SIGMAS: f64 = 2.0;

/// Mean distance along the viewing ray from a cylinder's surface to its
/// axis over the strip of half width `s` radii about its middle, in radii:
/// `h(s) = (s sqrt(1 - s^2) + asin s) / (2 s)`, the mean of `sqrt(1 - u^2)`
/// over `|u| < s`. `pi / 4` over the whole width, 1 for a thin strip.
pub fn strip_depth_ratio(s: f64) -> f64 {
    let s = s.clamp(0.0, 1.0);
    if s < 1e-6 {
        return 1.0;
    }
    (s * libm::sqrt(1.0 - s * s) + libm::asin(s)) / (2.0 * s)
}

/// The push from the surface a mask covering the share `cover` of the
/// rope's width sees to the axis of a rope of `radius` metres:
/// `radius h(cover)` ([`strip_depth_ratio`]).
pub fn strip_push(radius: f64, cover: f64) -> f64 {
    radius.max(0.0) * strip_depth_ratio(cover)
}

/// The share of the rope's width its mask covers, read across the centre
/// line `path` (with the junction `zones` skipped) of a mask
/// `mask_half_width_px` wide on each side: at each point the rope's top is
/// the median depth over the mask's middle, the background the median
/// between [`BACKGROUND_FROM_HALF_WIDTHS`] and [`BACKGROUND_TO_HALF_WIDTHS`]
/// off the centre line, and the pixels nearer than half way between them
/// are the rope (a cylinder's surface lies within a radius of its top; a
/// table beside it two radii behind; a lifted rope's background farther
/// still); the mask's pixels are counted along the same line. The median
/// of the ratios, at most 1; `None` with fewer than [`MIN_SECTION_SAMPLES`]
/// read or a mask under [`MIN_SECTION_HALF_WIDTH_PX`].
pub fn mask_cover(
    frame: &Frame<'_>,
    mask: &Mask,
    camera: &CameraIntrinsics,
    settings: &CloudSettings,
    path: &[Vec2],
    zones: &[u32],
    mask_half_width_px: f64,
) -> Option<f64> {
    let a = mask_half_width_px;
    if !(a >= MIN_SECTION_HALF_WIDTH_PX) || !a.is_finite() || path.len() < 3 {
        return None;
    }
    let reader = SectionReader {
        frame,
        mask,
        settings,
        focal: 0.5 * (camera.fx + camera.fy),
        half_width: a,
    };
    let reach = (libm::ceil(a) as usize).max(2);
    let stride = path.len().div_ceil(MAX_SECTION_SAMPLES).max(1);
    let mut covers = Vec::new();
    for i in (reach..path.len().saturating_sub(reach)).step_by(stride) {
        if zones.get(i).is_some_and(|&z| z != NO_ZONE) {
            continue;
        }
        let t = path[i + reach] - path[i - reach];
        let n = t.norm();
        if !(n > 0.0) {
            continue;
        }
        let normal = Vec2::new(-t.y / n, t.x / n);
        let Some(top) = reader.top(path[i], normal) else {
            continue;
        };
        let sides = [normal, -normal].map(|d| reader.side(path[i], d, top));
        if let [Some(l), Some(r)] = sides {
            covers.push((l.mask + r.mask) / (l.rope + r.rope));
        }
    }
    if covers.len() < MIN_SECTION_SAMPLES {
        return None;
    }
    Some(median(&mut covers).min(1.0))
}

/// One side of a cross-section, pixels from the centre line (the centre
/// pixel counts half on each side).
struct Side {
    /// Where the depth shows the rope (a pixel without depth counts half).
    rope: f64,
    /// Where the mask does.
    mask: f64,
}

/// Reads one frame's depth and mask across a rope whose mask is
/// `half_width` pixels wide on each side.
struct SectionReader<'a> {
    frame: &'a Frame<'a>,
    mask: &'a Mask,
    settings: &'a CloudSettings,
    focal: f64,
    half_width: f64,
}

impl SectionReader<'_> {
    /// The pixel `s` pixels from `at` along `dir`.
    fn pixel(&self, at: Vec2, dir: Vec2, s: i64) -> (i64, i64) {
        let p = at + dir * s as f64;
        (libm::round(p.x) as i64, libm::round(p.y) as i64)
    }

    /// Depth at `s` pixels from `at` along `dir`, metres.
    fn depth(&self, at: Vec2, dir: Vec2, s: i64) -> Option<f64> {
        let (u, v) = self.pixel(at, dir, s);
        let (w, h) = (self.frame.width as i64, self.frame.height as i64);
        if !(u >= 0 && v >= 0 && u < w && v < h) {
            return None;
        }
        depth_at(self.frame, (v * w + u) as usize, self.settings)
    }

    /// The depth of the rope's top at `at`: the median over the mask's
    /// middle, across the rope (`dir`).
    fn top(&self, at: Vec2, dir: Vec2) -> Option<f64> {
        let middle = libm::floor(0.5 * self.half_width) as i64;
        let mut top: Vec<f64> = (-middle..=middle)
            .filter_map(|s| self.depth(at, dir, s))
            .collect();
        (!top.is_empty()).then(|| median(&mut top))
    }

    /// The side `dir` of the cross-section at `at`, whose top lies at depth
    /// `top`, or `None` where the background does not stand out from the
    /// rope.
    fn side(&self, at: Vec2, dir: Vec2, top: f64) -> Option<Side> {
        let a = self.half_width;
        let from = libm::ceil(BACKGROUND_FROM_HALF_WIDTHS * a) as i64;
        let to = libm::floor(BACKGROUND_TO_HALF_WIDTHS * a) as i64;
        let mut back: Vec<f64> = (from..=to).filter_map(|s| self.depth(at, dir, s)).collect();
        if 2 * back.len() < (to - from + 1) as usize {
            return None;
        }
        let back = median(&mut back);
        if back - top < SECTION_CONTRAST_SIGMAS * depth_noise(top, self.focal) {
            return None;
        }
        let half_way = 0.5 * (top + back);
        let mut side = Side {
            rope: 0.5,
            mask: 0.5,
        };
        for s in 1..from {
            side.rope += match self.depth(at, dir, s) {
                Some(z) if z < half_way => 1.0,
                Some(_) => 0.0,
                None => 0.5,
            };
            let (u, v) = self.pixel(at, dir, s);
            side.mask += if self.mask.get(u, v) { 1.0 } else { 0.0 };
        }
        Some(side)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;

    #[test]
    fn the_whole_width_gives_pi_over_four_and_a_thin_strip_the_full_radius() {
        assert!((strip_depth_ratio(1.0) - core::f64::consts::FRAC_PI_4).abs() < 1e-12);
        assert!((strip_depth_ratio(1e-4) - 1.0).abs() < 1e-6);
        // The mean of sqrt(1 - u^2) over |u| < 0.6, summed numerically.
        let n = 100_000;
        let mean = (0..n)
            .map(|k| {
                let u = 0.6 * (k as f64 + 0.5) / n as f64;
                libm::sqrt(1.0 - u * u)
            })
            .sum::<f64>()
            / n as f64;
        assert!((strip_depth_ratio(0.6) - mean).abs() < 1e-9);
    }

    #[test]
    fn a_mask_over_a_strip_of_the_rope_is_pushed_farther_than_over_its_whole_width() {
        let r = 0.005;
        assert!((strip_push(r, 1.0) - r * core::f64::consts::FRAC_PI_4).abs() < 1e-15);
        // A mask over 0.7 of the width: the rope's radius is r / 0.7, the
        // strip's mean surface h(0.7) = 0.911 of it in front of the axis.
        let pushed = strip_push(r / 0.7, 0.7);
        assert!((pushed / r - 1.301).abs() < 0.001, "{}", pushed / r);
    }

    /// A cylinder of radius `r` lying on a table along the image's x axis
    /// at `z` metres, seen straight down by a 600 px camera; depth in mm,
    /// and a mask over the share `cover` of its width.
    fn cylinder_on_a_table(r: f64, z: f64, cover: f64) -> (CameraIntrinsics, Vec<u16>, Mask) {
        let (w, h) = (200u32, 100u32);
        let camera = CameraIntrinsics {
            width: w,
            height: h,
            fx: 600.0,
            fy: 600.0,
            cx: 100.0,
            cy: 50.0,
        };
        let table = z + r;
        let across = |v: u32| (v as f64 - 50.0) * table / 600.0;
        let depth = (0..h)
            .flat_map(|v| {
                (0..w).map(move |_| {
                    let y = across(v);
                    let depth = if y.abs() < r {
                        table - libm::sqrt(r * r - y * y)
                    } else {
                        table + r
                    };
                    libm::round(depth * 1000.0) as u16
                })
            })
            .collect();
        let mut mask = Mask::new(w, h);
        for v in 0..h {
            if across(v).abs() < cover * r {
                for u in 0..w {
                    mask.data[(v * w + u) as usize] = true;
                }
            }
        }
        (camera, depth, mask)
    }

    #[test]
    fn the_depth_shows_how_much_of_the_rope_a_narrow_mask_covers() {
        let (r, z) = (0.008, 0.5);
        let (camera, depth, mask) = cylinder_on_a_table(r, z, 0.6);
        let (w, h) = (camera.width, camera.height);
        let color = vec![0u8; (w * h * 3) as usize];
        let frame = Frame::new(w, h, &color, &depth, 0.001).expect("frame");
        let settings = crate::params::Params::default().cloud();
        let path: Vec<Vec2> = (20..180).map(|u| Vec2::new(u as f64, 50.0)).collect();
        let zones = vec![NO_ZONE; path.len()];
        // The rope is 2 r 600 / (z + r) = 18.9 px wide; its mask 60 % of it.
        let half_px = 0.6 * r * 600.0 / (z + r);
        let cover =
            mask_cover(&frame, &mask, &camera, &settings, &path, &zones, half_px).expect("a cover");
        assert!((cover - 0.6).abs() < 0.06, "cover {cover}");
        // Flat ground: nothing stands out, nothing is measured.
        let flat = vec![500u16; (w * h) as usize];
        let frame = Frame::new(w, h, &color, &flat, 0.001).expect("frame");
        assert_eq!(
            mask_cover(&frame, &mask, &camera, &settings, &path, &zones, half_px),
            None
        );
    }
}
