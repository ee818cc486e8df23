//! Depth to colour alignment, as librealsense's `rs2::align` (to colour) does
//! it: each depth pixel's corners are carried into the colour image, the
//! depth value fills the colour pixels between them, the nearer depth wins
//! where two depth pixels land on one colour pixel, and colour pixels that no
//! depth pixel reaches stay 0 (holes). Arithmetic in `f32`, as librealsense's.

use crate::error::RecordingError;

/// A lens distortion model, named as librealsense names them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Distortion {
    /// No distortion.
    None,
    /// Brown-Conrady, applied when projecting (librealsense's colour streams).
    ModifiedBrownConrady,
    /// Brown-Conrady inverse, applied when deprojecting.
    InverseBrownConrady,
    /// Brown-Conrady forward model (OpenCV's `plumb_bob`); deprojection iterates.
    BrownConrady,
}

impl Distortion {
    /// The model a `CameraInfo` names: librealsense's names and ROS's `plumb_bob`.
    pub fn from_name(name: &str) -> Option<Self> {
        match name.to_ascii_lowercase().as_str() {
            "none" | "" => Some(Self::None),
            "modified brown conrady" => Some(Self::ModifiedBrownConrady),
            "inverse brown conrady" => Some(Self::InverseBrownConrady),
            "brown conrady" | "plumb_bob" => Some(Self::BrownConrady),
            _ => None,
        }
    }
}

/// Pinhole intrinsics with a distortion model, as `rs2_intrinsics`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics {
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Principal point x, pixels.
    pub ppx: f32,
    /// Principal point y, pixels.
    pub ppy: f32,
    /// Focal length x, pixels.
    pub fx: f32,
    /// Focal length y, pixels.
    pub fy: f32,
    /// Distortion model.
    pub model: Distortion,
    /// `k1, k2, p1, p2, k3`.
    pub coeffs: [f32; 5],
}

impl Intrinsics {
    /// Pixel of a point in this camera's frame (metres), as `rs2_project_point_to_pixel`.
    #[inline]
    pub fn project(&self, p: [f32; 3]) -> [f32; 2] {
        self.project_normalised(p[0] / p[2], p[1] / p[2])
    }

    /// Pixel of the normalised image point `(x, y)` (a point at depth 1).
    #[inline]
    pub fn project_normalised(&self, mut x: f32, mut y: f32) -> [f32; 2] {
        let [k1, k2, p1, p2, k3] = self.coeffs;
        match self.model {
            Distortion::ModifiedBrownConrady => {
                let r2 = x * x + y * y;
                let f = 1.0 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2;
                x *= f;
                y *= f;
                let dx = x + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
                let dy = y + 2.0 * p2 * x * y + p1 * (r2 + 2.0 * y * y);
                x = dx;
                y = dy;
            }
            Distortion::BrownConrady => [x, y] = self.brown_conrady(x, y),
            Distortion::None | Distortion::InverseBrownConrady => {}
        }
        [x * self.fx + self.ppx, y * self.fy + self.ppy]
    }

    /// The Brown-Conrady polynomial at `(x, y)`: radial factor and tangential
    /// terms. Projection applies it for `BrownConrady`, deprojection for
    /// `InverseBrownConrady` (librealsense's convention).
    #[inline]
    fn brown_conrady(&self, x: f32, y: f32) -> [f32; 2] {
        let [k1, k2, p1, p2, k3] = self.coeffs;
        let r2 = x * x + y * y;
        let f = 1.0 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2;
        [
            x * f + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
            y * f + 2.0 * p2 * x * y + p1 * (r2 + 2.0 * y * y),
        ]
    }

    /// Point at `depth` metres behind pixel `px`, as `rs2_deproject_pixel_to_point`.
    pub fn deproject(&self, px: [f32; 2], depth: f32) -> [f32; 3] {
        let mut x = (px[0] - self.ppx) / self.fx;
        let mut y = (px[1] - self.ppy) / self.fy;
        let [k1, k2, p1, p2, k3] = self.coeffs;
        match self.model {
            Distortion::InverseBrownConrady => [x, y] = self.brown_conrady(x, y),
            Distortion::BrownConrady => {
                // Fixed-point undistortion; ten steps, as librealsense takes.
                let (xd, yd) = (x, y);
                for _ in 0..UNDISTORT_ITERATIONS {
                    let r2 = x * x + y * y;
                    let icdist = 1.0 / (1.0 + ((k3 * r2 + k2) * r2 + k1) * r2);
                    let dx = 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
                    let dy = 2.0 * p2 * x * y + p1 * (r2 + 2.0 * y * y);
                    x = (xd - dx) * icdist;
                    y = (yd - dy) * icdist;
                }
            }
            Distortion::None | Distortion::ModifiedBrownConrady => {}
        }
        [depth * x, depth * y, depth]
    }

    /// An error unless the size and focal lengths can be used.
    pub fn check(&self, what: &str) -> Result<(), RecordingError> {
        let finite = [self.ppx, self.ppy, self.fx, self.fy]
            .iter()
            .chain(&self.coeffs)
            .all(|v| v.is_finite());
        if self.width == 0 || self.height == 0 || !finite || self.fx <= 0.0 || self.fy <= 0.0 {
            return Err(RecordingError::message(
                what,
                format!("unusable intrinsics {self:?}"),
            ));
        }
        Ok(())
    }
}

/// `v` rounded half to even, as SSE's `cvtps2dq` does, without a call to
/// `rintf`: adding and taking away 1.5 * 2^23 leaves the nearest integer
/// (ties to even, the default rounding) for |v| < 2^22; other values take
/// the library's rounding.
#[inline]
fn round_half_even(v: f32) -> i32 {
    const MAGIC: f32 = 12_582_912.0;
    if v.abs() < 4_194_304.0 {
        ((v + MAGIC) - MAGIC) as i32
    } else {
        v.round_ties_even() as i32
    }
}

/// Undistortion iterations for the Brown-Conrady deprojection.
pub const UNDISTORT_ITERATIONS: usize = 10;
/// Largest distance between the depth and the colour camera, metres (a
/// D435's is 15 mm; rigs of two separate cameras rarely exceed 30 cm).
pub const MAX_BASELINE_M: f32 = 1.0;
/// Largest entry of `RᵀR - I` accepted as a rotation (`f32` rounding of a
/// unit quaternion is under 1e-6).
pub const ROTATION_TOLERANCE: f32 = 1e-3;
/// Bytes of the aligner's ray tables (12 per depth pixel and corner): a
/// 1280x720 depth stream takes 22 MB; 8192x8192 would take 1.6 GB.
pub const MAX_ALIGN_TABLE_BYTES: usize = 64 << 20;
/// How many times its nominal size (the ratio of the focal lengths) a depth
/// pixel may cover in the colour image; a larger footprint can only come
/// from a calibration that slipped past [`check_calibration`], and is skipped.
pub const MAX_FOOTPRINT_SCALE: f32 = 4.0;
/// Points sampled along each border and middle line of an image when
/// checking that its distortion keeps the rays in order.
const MONOTONIC_SAMPLES: usize = 64;

/// `true` when `f` is strictly increasing over `MONOTONIC_SAMPLES` steps from `a` to `b`.
fn increasing(a: f32, b: f32, f: impl Fn(f32) -> f32) -> bool {
    let mut last = f32::NEG_INFINITY;
    (0..=MONOTONIC_SAMPLES).all(|i| {
        let v = f(a + (b - a) * i as f32 / MONOTONIC_SAMPLES as f32);
        let ok = v.is_finite() && v > last;
        last = v;
        ok
    })
}

/// An error unless the cameras' calibration is one a real pair can have:
/// each distortion keeps its image's rays in order (a pixel further right
/// sees further right, along the borders and the middle lines), the
/// rotation is a rotation and the baseline at most [`MAX_BASELINE_M`].
/// Without it a finite but folded distortion can send every depth pixel
/// across the whole colour image.
pub fn check_calibration(
    depth: &Intrinsics,
    color: &Intrinsics,
    depth_to_color: &Extrinsics,
) -> Result<(), RecordingError> {
    let folded = |what: &str| {
        RecordingError::message(
            what,
            "the distortion folds the image (rays out of order): an implausible calibration",
        )
    };
    // Depth: rays through pixels, in pixel order.
    let (w, h) = (depth.width as f32, depth.height as f32);
    for y in [-0.5, h / 2.0, h - 0.5] {
        if !increasing(-0.5, w - 0.5, |x| depth.deproject([x, y], 1.0)[0]) {
            return Err(folded("depth"));
        }
    }
    for x in [-0.5, w / 2.0, w - 0.5] {
        if !increasing(-0.5, h - 0.5, |y| depth.deproject([x, y], 1.0)[1]) {
            return Err(folded("depth"));
        }
    }
    // Colour: pixels of rays, in ray order, over the rays its image spans.
    let span = |i: &Intrinsics| {
        [
            (-0.5 - i.ppx) / i.fx,
            (i.width as f32 - 0.5 - i.ppx) / i.fx,
            (-0.5 - i.ppy) / i.fy,
            (i.height as f32 - 0.5 - i.ppy) / i.fy,
        ]
    };
    let [x0, x1, y0, y1] = span(color);
    for y in [y0, (y0 + y1) / 2.0, y1] {
        if !increasing(x0, x1, |x| color.project_normalised(x, y)[0]) {
            return Err(folded("colour"));
        }
    }
    for x in [x0, (x0 + x1) / 2.0, x1] {
        if !increasing(y0, y1, |y| color.project_normalised(x, y)[1]) {
            return Err(folded("colour"));
        }
    }
    let r = &depth_to_color.rotation;
    let mut worst = 0.0f32;
    for a in 0..3 {
        for b in 0..3 {
            let dot: f32 = (0..3).map(|k| r[a * 3 + k] * r[b * 3 + k]).sum();
            let want = if a == b { 1.0 } else { 0.0 };
            worst = worst.max((dot - want).abs());
        }
    }
    if worst.is_nan() || worst > ROTATION_TOLERANCE {
        return Err(RecordingError::message(
            "extrinsics",
            format!(
                "the depth-to-colour rotation is not a rotation (RᵀR departs from I by {worst})"
            ),
        ));
    }
    let t = depth_to_color.translation;
    let baseline = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
    if baseline.is_nan() || baseline > MAX_BASELINE_M {
        return Err(RecordingError::message(
            "extrinsics",
            format!(
                "the depth and colour cameras are {baseline} m apart (at most {MAX_BASELINE_M} m is plausible)"
            ),
        ));
    }
    Ok(())
}

/// A rigid transform between two cameras, as `rs2_extrinsics`: `p' = R p + t`,
/// `rotation` column-major.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Extrinsics {
    /// Rotation, column-major 3x3.
    pub rotation: [f32; 9],
    /// Translation, metres.
    pub translation: [f32; 3],
}

impl Extrinsics {
    /// The identity.
    pub const IDENTITY: Self = Self {
        rotation: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        translation: [0.0; 3],
    };

    /// From a unit quaternion `x, y, z, w` and a translation (a `geometry_msgs/Transform`).
    pub fn from_quaternion(q: [f64; 4], t: [f64; 3]) -> Self {
        let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
        let [x, y, z, w] = if n > 0.0 {
            [q[0] / n, q[1] / n, q[2] / n, q[3] / n]
        } else {
            [0.0, 0.0, 0.0, 1.0]
        };
        // Row-major R of the quaternion, stored column-major.
        let r = [
            [
                1.0 - 2.0 * (y * y + z * z),
                2.0 * (x * y - z * w),
                2.0 * (x * z + y * w),
            ],
            [
                2.0 * (x * y + z * w),
                1.0 - 2.0 * (x * x + z * z),
                2.0 * (y * z - x * w),
            ],
            [
                2.0 * (x * z - y * w),
                2.0 * (y * z + x * w),
                1.0 - 2.0 * (x * x + y * y),
            ],
        ];
        let mut rotation = [0.0f32; 9];
        for col in 0..3 {
            for row in 0..3 {
                rotation[col * 3 + row] = r[row][col] as f32;
            }
        }
        Self {
            rotation,
            translation: [t[0] as f32, t[1] as f32, t[2] as f32],
        }
    }

    /// `R p + t`, as `rs2_transform_point_to_point`.
    pub fn apply(&self, p: [f32; 3]) -> [f32; 3] {
        let r = &self.rotation;
        [
            r[0] * p[0] + r[3] * p[1] + r[6] * p[2] + self.translation[0],
            r[1] * p[0] + r[4] * p[1] + r[7] * p[2] + self.translation[1],
            r[2] * p[0] + r[5] * p[1] + r[8] * p[2] + self.translation[2],
        ]
    }

    /// The inverse transform.
    pub fn inverse(&self) -> Self {
        let r = &self.rotation;
        // Transposed rotation, column-major.
        let rt = [r[0], r[3], r[6], r[1], r[4], r[7], r[2], r[5], r[8]];
        let t = self.translation;
        let inv = Self {
            rotation: rt,
            translation: [0.0; 3],
        };
        let m = inv.apply(t);
        Self {
            rotation: rt,
            translation: [-m[0], -m[1], -m[2]],
        }
    }

    /// `self` then `next`: `next(self(p))`.
    pub fn then(&self, next: &Self) -> Self {
        let mut rotation = [0.0f32; 9];
        for col in 0..3 {
            let c = [
                self.rotation[col * 3],
                self.rotation[col * 3 + 1],
                self.rotation[col * 3 + 2],
            ];
            let rc = next.apply(c);
            for row in 0..3 {
                rotation[col * 3 + row] = rc[row] - next.translation[row];
            }
        }
        Self {
            rotation,
            translation: next.apply(self.translation),
        }
    }
}

/// Horizontal and vertical field of view, degrees, as `rs2_fov` measures it.
fn fov_deg(i: &Intrinsics) -> [f32; 2] {
    let w = i.width as f32;
    let h = i.height as f32;
    [
        ((i.ppx + 0.5).atan2(i.fx) + (w - (i.ppx + 0.5)).atan2(i.fx)).to_degrees(),
        ((i.ppy + 0.5).atan2(i.fy) + (h - (i.ppy + 0.5)).atan2(i.fy)).to_degrees(),
    ]
}

/// `true` when a depth pixel is wider than a colour pixel, so each depth pixel
/// fills the span between its two corners; otherwise only its top-left corner
/// is filled, as librealsense decides (with its two special resolution pairs).
fn fills_span(depth: &Intrinsics, color: &Intrinsics) -> bool {
    let (fd, fc) = (fov_deg(depth), fov_deg(color));
    let per_angle = |i: &Intrinsics, f: [f32; 2]| [i.width as f32 / f[0], i.height as f32 / f[1]];
    let (pd, pc) = (per_angle(depth, fd), per_angle(color, fc));
    let special = matches!(
        (depth.width, depth.height, color.width, color.height),
        (640, 240, 320, 180) | (640, 480, 640, 360)
    );
    pd[0] < pc[0] || pd[1] < pc[1] || special
}

/// Which of librealsense's two aligners to reproduce. They differ on about
/// one pixel in ten (rounding, which corners fill, the image border), so a
/// recording is aligned the way the librealsense of its format aligns it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AlignArithmetic {
    /// The SSE aligner that x86 builds of librealsense up to 2.55 run (the
    /// era of ROS1 `.bag` recordings): both corners only when a depth pixel
    /// is wider than a colour pixel, `p + 0.5` rounded half to even,
    /// colour pixels outside the image clipped one by one.
    X86Sse,
    /// The portable aligner (librealsense 2.59's wheels, ARM builds): both
    /// corners always, `p + 0.5` truncated, colour pixels outside the image
    /// clipped one by one.
    Portable,
}

/// Depth (units of `depth_scale` metres, `depth_intr.width x height`, 0 = none)
/// seen from the colour camera, at the colour camera's size, with the
/// arithmetic of one of librealsense's aligners.
pub fn align_depth_to_color(
    depth: &[u16],
    depth_intr: &Intrinsics,
    color_intr: &Intrinsics,
    depth_to_color: &Extrinsics,
    depth_scale: f32,
    arithmetic: AlignArithmetic,
) -> Result<Vec<u16>, RecordingError> {
    Aligner::new(*depth_intr, *color_intr, *depth_to_color, arithmetic)?.align(depth, depth_scale)
}

/// An alignment set up once for a pair of cameras: the rays through every
/// depth pixel's corners (they do not depend on the depth) are computed
/// here, so each frame only transforms and projects.
#[derive(Debug, Clone)]
pub struct Aligner {
    depth_intr: Intrinsics,
    color_intr: Intrinsics,
    depth_to_color: Extrinsics,
    arithmetic: AlignArithmetic,
    span: bool,
    /// The ray `(x, y, 1)` through each pixel's top-left corner, rotated
    /// into the colour camera (`R (x, y, 1)`), row-major.
    top_left: Vec<[f32; 3]>,
    /// The same through each bottom-right corner (empty when not spanned).
    bottom_right: Vec<[f32; 3]>,
    /// Widest footprint of one depth pixel in the colour image, colour pixels.
    max_footprint: i32,
}

impl Aligner {
    /// The aligner from `depth_intr`'s camera into `color_intr`'s; an error
    /// for an implausible calibration ([`check_calibration`]) or tables
    /// above [`MAX_ALIGN_TABLE_BYTES`].
    pub fn new(
        depth_intr: Intrinsics,
        color_intr: Intrinsics,
        depth_to_color: Extrinsics,
        arithmetic: AlignArithmetic,
    ) -> Result<Self, RecordingError> {
        check_calibration(&depth_intr, &color_intr, &depth_to_color)?;
        let sse = arithmetic == AlignArithmetic::X86Sse;
        let span = !sse || fills_span(&depth_intr, &color_intr);
        let tables = (depth_intr.width as usize)
            .saturating_mul(depth_intr.height as usize)
            .saturating_mul(12 * (1 + usize::from(span)));
        if tables > MAX_ALIGN_TABLE_BYTES {
            return Err(RecordingError::TooLarge {
                what: "alignment tables of the depth stream in bytes",
                size: tables as u64,
                max: MAX_ALIGN_TABLE_BYTES as u64,
            });
        }
        let nominal = (color_intr.fx / depth_intr.fx).max(color_intr.fy / depth_intr.fy);
        let max_footprint = (MAX_FOOTPRINT_SCALE * nominal + 2.0).min(1e6) as i32;
        // The SSE aligner undistorts inverse Brown-Conrady only: a
        // Brown-Conrady depth camera's ray is then taken as undistorted.
        let ray_camera = if sse && depth_intr.model == Distortion::BrownConrady {
            Intrinsics {
                model: Distortion::None,
                ..depth_intr
            }
        } else {
            depth_intr
        };
        // rs2_deproject_pixel_to_point at depth 1: the x and y it multiplies by the depth.
        let ray = |px: f32, py: f32| -> [f32; 2] {
            let p = ray_camera.deproject([px, py], 1.0);
            [p[0], p[1]]
        };
        let (w, h) = (depth_intr.width as usize, depth_intr.height as usize);
        let r = depth_to_color.rotation;
        let map = |offset: f32| -> Vec<[f32; 3]> {
            (0..w * h)
                .map(|k| {
                    let [x, y] = ray((k % w) as f32 + offset, (k / w) as f32 + offset);
                    [
                        r[0] * x + r[3] * y + r[6],
                        r[1] * x + r[4] * y + r[7],
                        r[2] * x + r[5] * y + r[8],
                    ]
                })
                .collect()
        };
        let top_left = map(-0.5);
        let bottom_right = if span { map(0.5) } else { Vec::new() };
        Ok(Self {
            depth_intr,
            color_intr,
            depth_to_color,
            arithmetic,
            span,
            top_left,
            bottom_right,
            max_footprint,
        })
    }

    /// `true` when this aligner is the one for these cameras and arithmetic.
    pub fn is_for(
        &self,
        depth_intr: &Intrinsics,
        color_intr: &Intrinsics,
        depth_to_color: &Extrinsics,
        arithmetic: AlignArithmetic,
    ) -> bool {
        self.depth_intr == *depth_intr
            && self.color_intr == *color_intr
            && self.depth_to_color == *depth_to_color
            && self.arithmetic == arithmetic
    }

    /// The colour pixel of the corner with ray `(x, y)` at depth `d` metres.
    #[inline]
    fn corner(&self, ray: [f32; 3], d: f32) -> (i32, i32) {
        let t = &self.depth_to_color.translation;
        let qz = d * ray[2] + t[2];
        let q = self
            .color_intr
            .project_normalised((d * ray[0] + t[0]) / qz, (d * ray[1] + t[1]) / qz);
        if self.arithmetic == AlignArithmetic::Portable {
            // Truncation, as a C cast of `p + 0.5`.
            return ((q[0] + 0.5) as i32, (q[1] + 0.5) as i32);
        }
        (round_half_even(q[0] + 0.5), round_half_even(q[1] + 0.5))
    }

    /// `depth` (the depth camera's size) aligned to the colour camera.
    pub fn align(&self, depth: &[u16], depth_scale: f32) -> Result<Vec<u16>, RecordingError> {
        let (dw, dh) = (
            self.depth_intr.width as usize,
            self.depth_intr.height as usize,
        );
        if depth.len() != dw * dh {
            return Err(RecordingError::message(
                "depth",
                format!("{} depth values for a {dw}x{dh} depth image", depth.len()),
            ));
        }
        let (cw, ch) = (self.color_intr.width as i32, self.color_intr.height as i32);
        let mut out = vec![0u16; (cw as usize) * (ch as usize)];
        for (k, &z) in depth.iter().enumerate() {
            if z == 0 {
                continue;
            }
            let d = f32::from(z) * depth_scale;
            let (x0, y0) = self.corner(self.top_left[k], d);
            let (x1, y1) = if self.span {
                self.corner(self.bottom_right[k], d)
            } else {
                (x0, y0)
            };
            // Work per depth pixel bounded whatever the calibration.
            if x1.saturating_sub(x0) > self.max_footprint
                || y1.saturating_sub(y0) > self.max_footprint
            {
                continue;
            }
            let (xs, xe) = (x0.max(0), x1.min(cw - 1));
            if xs > xe {
                continue;
            }
            for y in y0.max(0)..=y1.min(ch - 1) {
                let row = y as usize * cw as usize;
                for o in &mut out[row + xs as usize..=row + xe as usize] {
                    *o = if *o == 0 { z } else { (*o).min(z) };
                }
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn intr(w: u32, h: u32, f: f32, ppx: f32, ppy: f32) -> Intrinsics {
        Intrinsics {
            width: w,
            height: h,
            ppx,
            ppy,
            fx: f,
            fy: f,
            model: Distortion::None,
            coeffs: [0.0; 5],
        }
    }

    #[test]
    fn each_depth_pixel_covers_its_corners_and_the_nearest_depth_wins() {
        // librealsense maps the corners (x - 0.5, x + 0.5) and fills every
        // colour pixel between them; a colour grid a quarter pixel off keeps
        // the corners away from the rounding edge, so each covers a 2x2 block.
        let d = intr(3, 3, 10.0, 1.0, 1.0);
        let c = intr(3, 3, 10.0, 1.25, 1.25);
        let depth = [900, 800, 0, 700, 0, 0, 0, 0, 0];
        let out = align_depth_to_color(
            &depth,
            &d,
            &c,
            &Extrinsics::IDENTITY,
            0.001,
            AlignArithmetic::X86Sse,
        )
        .expect("aligns");
        assert_eq!(out, vec![900, 800, 800, 700, 700, 800, 700, 700, 0]);
    }

    #[test]
    fn a_baseline_shifts_depth_by_its_disparity() {
        // Colour camera 15 mm to the right: a point at 1 m moves f * b / z = 1.5 px left.
        let i = intr(20, 3, 100.0, 9.5, 1.0);
        let mut depth = vec![0u16; 60];
        depth[20 + 10] = 1000;
        let shift = Extrinsics {
            translation: [-0.015, 0.0, 0.0],
            ..Extrinsics::IDENTITY
        };
        let out = align_depth_to_color(&depth, &i, &i, &shift, 0.001, AlignArithmetic::X86Sse)
            .expect("aligns");
        // Same pixel size on both cameras: only the top-left corner is filled.
        assert!(!fills_span(&i, &i));
        let filled: Vec<usize> = (0..60).filter(|&k| out[k] != 0).collect();
        assert_eq!(filled, vec![28]);
    }

    #[test]
    fn pixels_that_land_outside_are_dropped_not_clamped() {
        let i = intr(4, 3, 10.0, 1.5, 1.0);
        let mut depth = vec![0u16; 12];
        depth[4] = 1000;
        depth[7] = 1000;
        let shift = Extrinsics {
            translation: [0.5, 0.0, 0.0],
            ..Extrinsics::IDENTITY
        };
        let out = align_depth_to_color(&depth, &i, &i, &shift, 0.001, AlignArithmetic::X86Sse)
            .expect("aligns");
        assert_eq!(out, vec![0; 12]);
    }

    #[test]
    fn portable_aligner_spans_both_corners_on_one_camera_and_truncates() {
        // On one camera the x86 aligner fills the top-left corner's pixel
        // only; the portable one fills x..=x+1 (corners at x + 0.25 and
        // x + 1.25, truncated), clipped at the image border, nearest wins.
        let d = intr(3, 2, 10.0, 1.0, 1.0);
        let c = intr(3, 2, 10.0, 1.25, 1.25);
        let depth = [100, 200, 300, 400, 500, 600];
        let portable = align_depth_to_color(
            &depth,
            &d,
            &c,
            &Extrinsics::IDENTITY,
            0.001,
            AlignArithmetic::Portable,
        )
        .expect("aligns");
        assert_eq!(portable, vec![100, 100, 200, 100, 100, 200]);
        let x86 = align_depth_to_color(
            &depth,
            &d,
            &d,
            &Extrinsics::IDENTITY,
            0.001,
            AlignArithmetic::X86Sse,
        )
        .expect("aligns");
        assert!(!fills_span(&d, &d));
        assert_eq!(x86.iter().filter(|&&v| v != 0).count(), 6, "{x86:?}");
    }

    #[test]
    fn rounding_is_half_to_even_like_sse() {
        for (v, r) in [
            (0.5f32, 0),
            (1.5, 2),
            (2.5, 2),
            (-0.5, 0),
            (-1.5, -2),
            (2.4999, 2),
            (7.0, 7),
        ] {
            assert_eq!(round_half_even(v), r, "{v}");
            assert_eq!(round_half_even(v), v.round_ties_even() as i32, "{v}");
        }
        assert_eq!(round_half_even(1e9), 1_000_000_000);
    }

    #[test]
    fn quaternion_inverse_and_composition_agree() {
        let a = Extrinsics::from_quaternion([0.1, -0.2, 0.05, 0.97], [0.01, 0.02, -0.03]);
        let p = [0.3, -0.1, 1.2];
        let back = a.inverse().apply(a.apply(p));
        for k in 0..3 {
            assert!((back[k] - p[k]).abs() < 1e-6);
        }
        let b = Extrinsics::from_quaternion([0.0, 0.3, 0.0, 0.95], [0.0, 0.0, 0.1]);
        let ab = a.then(&b).apply(p);
        let step = b.apply(a.apply(p));
        for k in 0..3 {
            assert!((ab[k] - step[k]).abs() < 1e-6);
        }
    }

    #[test]
    fn distortion_round_trips() {
        let mut i = intr(64, 48, 50.0, 32.0, 24.0);
        i.coeffs = [0.1, -0.05, 0.001, -0.002, 0.01];
        i.model = Distortion::BrownConrady;
        let p = i.deproject([50.0, 10.0], 1.0);
        let q = i.project(p);
        assert!(
            (q[0] - 50.0).abs() < 1e-3 && (q[1] - 10.0).abs() < 1e-3,
            "{q:?}"
        );
    }

    #[test]
    fn an_8192_square_depth_stream_is_refused_before_its_tables_are_built() {
        let big = intr(8192, 8192, 6000.0, 4096.0, 4096.0);
        let color = intr(640, 480, 600.0, 320.0, 240.0);
        let e = Aligner::new(big, color, Extrinsics::IDENTITY, AlignArithmetic::Portable)
            .expect_err("refused");
        assert!(matches!(e, RecordingError::TooLarge { .. }), "{e}");
        // A D435's largest depth stream is set up.
        let hd = intr(1280, 720, 640.0, 640.0, 360.0);
        assert!(Aligner::new(hd, color, Extrinsics::IDENTITY, AlignArithmetic::Portable).is_ok());
    }

    #[test]
    fn a_distortion_that_folds_the_image_is_refused() {
        let plain = intr(64, 48, 50.0, 32.0, 24.0);
        let mut folded = plain;
        // The radial factor 1 + k1 r^2 turns negative inside the image.
        folded.model = Distortion::ModifiedBrownConrady;
        folded.coeffs = [-3.0, 0.0, 0.0, 0.0, 0.0];
        assert!(check_calibration(&plain, &folded, &Extrinsics::IDENTITY).is_err());
        let mut depth = plain;
        depth.model = Distortion::InverseBrownConrady;
        depth.coeffs = [-3.0, 0.0, 0.0, 0.0, 0.0];
        assert!(check_calibration(&depth, &plain, &Extrinsics::IDENTITY).is_err());
        // A real lens's mild distortion passes.
        let mut mild = plain;
        mild.model = Distortion::BrownConrady;
        mild.coeffs = [0.1, -0.05, 0.001, -0.002, 0.01];
        assert!(check_calibration(&mild, &mild, &Extrinsics::IDENTITY).is_ok());
    }

    #[test]
    fn a_baseline_of_metres_or_a_skewed_rotation_is_refused() {
        let i = intr(64, 48, 50.0, 32.0, 24.0);
        let far = Extrinsics {
            translation: [2.0, 0.0, 0.0],
            ..Extrinsics::IDENTITY
        };
        assert!(check_calibration(&i, &i, &far).is_err());
        let mut skew = Extrinsics::IDENTITY;
        skew.rotation[1] = 0.5;
        assert!(check_calibration(&i, &i, &skew).is_err());
        let d435 = Extrinsics::from_quaternion([0.001, -0.002, 0.003, 1.0], [0.015, 0.0, 0.0]);
        assert!(check_calibration(&i, &i, &d435).is_ok());
    }

    #[test]
    fn a_depth_pixel_wider_than_its_footprint_cap_fills_nothing() {
        let i = intr(8, 6, 10.0, 4.0, 3.0);
        let depth = vec![1000u16; 48];
        let mut a =
            Aligner::new(i, i, Extrinsics::IDENTITY, AlignArithmetic::Portable).expect("plausible");
        assert!(a
            .align(&depth, 0.001)
            .expect("aligned")
            .iter()
            .any(|&z| z > 0));
        // Each pixel spans two corners one colour pixel apart: over a cap of 0.
        a.max_footprint = 0;
        assert!(a
            .align(&depth, 0.001)
            .expect("aligned")
            .iter()
            .all(|&z| z == 0));
    }
}
