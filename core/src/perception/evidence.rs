//! What this frame's images say about a point in space: whether a rope
//! could be there unseen. A hidden node is plausible only where something
//! hides it (a surface nearer the camera in the depth image, a declared
//! occlusion rectangle), outside the image, where the depth camera has no
//! measurement, or on rope-coloured pixels; a node whose pixels show a
//! surface at or behind it with no rope colour is in free space.

use alloc::vec::Vec;

use super::camera::{depth_noise, CameraIntrinsics};
use super::frame::Frame;
use super::point_cloud::median_around;
use super::segmentation::{Mask, Rect};
use crate::math::{Vec2, Vec3};

/// A surface this much nearer the camera than a point hides it, metres:
/// well above the depth noise at a metre (about 3 mm) and below the gap
/// between a rope and a hand or box held just above it.
pub const OCCLUDER_MARGIN: f64 = 0.01;

/// How unlikely it must be that depth noise alone made the pixels of an
/// open table behind a point look nearer than it, as a one-sided normal
/// quantile (3.09: one chance in a thousand), before [`Evidence::sight`]
/// takes them for an occluder.
pub const OCCLUDER_FALSE_ALARM_SIGMAS: f64 = 3.09;

/// Half-width of the window of pixels looked at around a point's
/// projection, as a multiple of the rope's radius in pixels (the window
/// covers the rope's width, so a node near an occluder's edge is not
/// judged by a single pixel beside it).
pub const WINDOW_RADII: f64 = 1.5;

/// How far from a piece's axis, in its radii, [`Evidence::stands_free`]
/// looks at each side: a radius past the rope's own edge. Chosen on the
/// tuning range: 1.5 and 2 take drawn 1031's lifted end as it comes out
/// (7.56 -> 6.09 mm), 3 and 5 do not; nothing else moves.
pub const FREE_SIDE_RADII: f64 = 2.0;

/// Smallest half-width of that window, pixels.
pub const MIN_WINDOW_PX: i64 = 2;

/// Largest half-width of that window, pixels (caps the cost per point).
pub const MAX_WINDOW_PX: i64 = 12;

/// Opposite pairs of directions [`Evidence::hidden_around`] looks in
/// (four pairs: every 45 degrees round the circle).
pub const AROUND_DIRECTIONS: usize = 4;

/// What the images say about a point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sight {
    /// Behind the camera or projecting outside the image.
    OutOfView,
    /// Rope-coloured pixels around its projection.
    Rope,
    /// Inside a declared occlusion rectangle.
    Covered,
    /// A surface clearly nearer the camera than the point.
    Occluded,
    /// No depth measurement around its projection.
    Unknown,
    /// Its pixels show a surface at or behind it and no rope: nothing hides
    /// it, so a hidden rope cannot be there.
    FreeSpace,
}

impl Sight {
    /// `true` when a hidden node may be there.
    pub fn allows_hidden(self) -> bool {
        self != Sight::FreeSpace
    }
}

/// The evidence of one frame: its depth, the rope mask and the declared
/// occlusion rectangles.
#[derive(Debug, Clone, Copy)]
pub struct Evidence<'a> {
    /// The frame (depth in its units).
    pub frame: &'a Frame<'a>,
    /// The rope mask (after the rectangles were blacked out).
    pub mask: &'a Mask,
    /// The declared occlusion rectangles of this frame.
    pub occlusions: &'a [Rect],
    /// The camera.
    pub camera: &'a CameraIntrinsics,
    /// The rope's radius, metres (sizes the window).
    pub radius: f64,
    /// Pixels of the other ropes tracked in the same frame
    /// (`MultiTracker`): another rope there hides this one as an occluder
    /// does, however little nearer the camera it lies.
    pub others: Option<&'a Mask>,
}

impl Evidence<'_> {
    /// `true` when the rope may go on at `p` as the images show it: the
    /// pixel `p` projects to is rope-coloured, or `p` is out of view (behind
    /// the camera, outside the image). Unlike [`Evidence::sight`] it looks
    /// at that one pixel, so a rope's end does not go on past its tip just
    /// because the window around the point still holds the tip's pixels;
    /// nor under an occluder, where nothing says which way a hidden tip
    /// goes.
    pub fn shows_rope_at(&self, p: &Vec3) -> bool {
        self.pixel_of(p).is_none_or(|(u, v)| self.mask.get(u, v))
    }

    /// `true` when something at the one pixel `p` projects to hides it: a
    /// declared occlusion rectangle, or a depth measurement nearer the
    /// camera than `p` by more than [`OCCLUDER_MARGIN`]. Like
    /// [`Evidence::shows_rope_at`] it looks at that one pixel, so a rope's
    /// end walked under an occluder stops at the occluder's edge.
    pub fn hides_rope_at(&self, p: &Vec3) -> bool {
        let Some((u, v)) = self.pixel_of(p) else {
            return false;
        };
        if self.covered_at(u, v) {
            return true;
        }
        self.depth_at_pixel(u, v)
            .is_some_and(|z| z < p.z - OCCLUDER_MARGIN)
    }

    /// `true` when something hides the rope within `reach` metres of `p`
    /// across the viewing direction: a declared rectangle or another rope
    /// at one of the pixels half-way and all the way round a circle of that
    /// radius (in [`AROUND_DIRECTIONS`] directions), or a surface there
    /// nearer than the table behind `p` by [`OCCLUDER_MARGIN`]. The table
    /// there is not taken at `p`'s depth (a table tilted 30 degrees to the
    /// camera is 1.2 cm nearer 2 cm up the image): each pixel is paired
    /// with the one opposite, whose depths sum, on any plane, to twice the
    /// plane's depth at the centre, there a radius behind `p`; a pair whose
    /// sum falls short of that by the margin has something in front, when
    /// one of the two also lies in front of `p` by the margin: a thick
    /// rope's own edge, outside its mask, is a diameter nearer than the
    /// table but not nearer than the rope (`docs/algorithm-notes.md`, "A
    /// rope's own edge beside an end that came out"). Rope pixels and
    /// pixels without depth say nothing.
    pub fn hidden_around(&self, p: &Vec3, reach: f64) -> bool {
        let Some(q) = self.camera.project(p) else {
            return false;
        };
        if !(reach > 0.0) || !(p.z > 0.0) {
            return false;
        }
        let focal = 0.5 * (self.camera.fx + self.camera.fy);
        let px = reach * focal / p.z;
        let (w, h) = (self.frame.width as i64, self.frame.height as i64);
        let pixel = |du: f64, dv: f64| {
            let (u, v) = (libm::round(q.x + du) as i64, libm::round(q.y + dv) as i64);
            (u >= 0 && v >= 0 && u < w && v < h).then_some((u, v))
        };
        let covered = |(u, v): (i64, i64)| self.covered_at(u, v);
        // A depth that can stand for the table: measured and not rope.
        let depth = |(u, v): (i64, i64)| {
            let raw = self.frame.depth[(v * w + u) as usize];
            (raw != 0 && !self.mask.get(u, v)).then_some(raw as f64 * self.frame.depth_scale)
        };
        let table_sum = 2.0 * (p.z + self.radius);
        (0..AROUND_DIRECTIONS).any(|k| {
            let a = core::f64::consts::PI * k as f64 / AROUND_DIRECTIONS as f64;
            let (c, s) = (libm::cos(a), libm::sin(a));
            [0.5, 1.0].iter().any(|share| {
                let (du, dv) = (c * px * share, s * px * share);
                let (Some(one), Some(other)) = (pixel(du, dv), pixel(-du, -dv)) else {
                    return false;
                };
                if covered(one) || covered(other) {
                    return true;
                }
                match (depth(one), depth(other)) {
                    (Some(a), Some(b)) => {
                        a + b < table_sum - OCCLUDER_MARGIN && a.min(b) < p.z - OCCLUDER_MARGIN
                    }
                    _ => false,
                }
            })
        })
    }

    /// `true` when a piece of rope whose axis runs through `line` stands
    /// free of any surface: on both sides of it, [`FREE_SIDE_RADII`] of
    /// its radius from the axis across its image direction, a surface
    /// farther than the piece by [`OCCLUDER_MARGIN`], at more than half of
    /// its segments where both sides are measured (not rope, not covered).
    /// A rope lifted off the table does; an object's edge, which has the
    /// object's face on one side, does not.
    pub fn stands_free(&self, line: &[Vec3]) -> bool {
        let focal = 0.5 * (self.camera.fx + self.camera.fy);
        let (w, h) = (self.frame.width as i64, self.frame.height as i64);
        let behind = |q: Vec2, z: f64| {
            let (u, v) = (libm::round(q.x) as i64, libm::round(q.y) as i64);
            if u < 0 || v < 0 || u >= w || v >= h || self.mask.get(u, v) {
                return None;
            }
            if self.covered_at(u, v) {
                return Some(false);
            }
            self.depth_at_pixel(u, v).map(|d| d > z + OCCLUDER_MARGIN)
        };
        let (mut measured, mut free) = (0usize, 0usize);
        for pair in line.windows(2) {
            let mid = 0.5 * (pair[0] + pair[1]);
            let (Some(a), Some(b), Some(q)) = (
                self.camera.project(&pair[0]),
                self.camera.project(&pair[1]),
                self.camera.project(&mid),
            ) else {
                continue;
            };
            let along = b - a;
            let len = along.norm();
            if !(len > 0.0) || !(mid.z > 0.0) {
                continue;
            }
            let across = Vec2::new(-along.y, along.x) / len;
            let offset = across * (FREE_SIDE_RADII * self.radius * focal / mid.z);
            if let (Some(one), Some(other)) = (behind(q + offset, mid.z), behind(q - offset, mid.z))
            {
                measured += 1;
                free += usize::from(one && other);
            }
        }
        measured > 0 && 2 * free > measured
    }

    /// The median depth of this rope's pixels (in the mask, not another
    /// rope's) within `half` pixels of the image point `at`, metres; `None`
    /// where none has a measurement or `at` is outside the image.
    pub fn rope_depth_near(&self, at: Vec2, half: i64) -> Option<f64> {
        let (w, h) = (self.frame.width as f64, self.frame.height as f64);
        if !(at.x >= 0.0 && at.y >= 0.0 && at.x < w && at.y < h) {
            return None;
        }
        let pixel = (libm::round(at.x) as i64, libm::round(at.y) as i64);
        median_around(pixel, half, &mut Vec::new(), |x, y| {
            (self.mask.get(x, y) && !self.other_rope_at(x, y))
                .then(|| self.depth_at_pixel(x, y))
                .flatten()
        })
    }

    /// The depth measured at the pixel `p` projects to, metres; `None` out
    /// of view or without a measurement.
    pub fn depth_at_point(&self, p: &Vec3) -> Option<f64> {
        let (u, v) = self.pixel_of(p)?;
        self.depth_at_pixel(u, v)
    }

    /// The depth measured at pixel `(u, v)` (inside the image), metres.
    fn depth_at_pixel(&self, u: i64, v: i64) -> Option<f64> {
        let raw = self.frame.depth[(v * self.frame.width as i64 + u) as usize];
        (raw != 0).then_some(raw as f64 * self.frame.depth_scale)
    }

    /// `true` when a declared occlusion rectangle or another tracked rope
    /// covers pixel `(u, v)`.
    fn covered_at(&self, u: i64, v: i64) -> bool {
        self.occlusions.iter().any(|r| r.contains(u, v)) || self.other_rope_at(u, v)
    }

    /// `true` when another tracked rope covers pixel `(u, v)`.
    fn other_rope_at(&self, u: i64, v: i64) -> bool {
        self.others.is_some_and(|m| m.get(u, v))
    }

    /// The pixel `p` projects to, rounded; `None` when `p` is behind the
    /// camera or that pixel is outside the image.
    fn pixel_of(&self, p: &Vec3) -> Option<(i64, i64)> {
        let q = self.camera.project(p)?;
        let (u, v) = (libm::round(q.x) as i64, libm::round(q.y) as i64);
        let (w, h) = (self.frame.width as i64, self.frame.height as i64);
        (u >= 0 && v >= 0 && u < w && v < h).then_some((u, v))
    }

    /// What the images say about `p` (camera frame, metres).
    pub fn sight(&self, p: &Vec3) -> Sight {
        let Some((u, v)) = self.pixel_of(p) else {
            return Sight::OutOfView;
        };
        let (w, h) = (self.frame.width as i64, self.frame.height as i64);
        if self.covered_at(u, v) {
            return Sight::Covered;
        }
        let focal = 0.5 * (self.camera.fx + self.camera.fy);
        let half = (libm::ceil(WINDOW_RADII * self.radius * focal / p.z) as i64)
            .clamp(MIN_WINDOW_PX, MAX_WINDOW_PX);
        let (mut measured, mut nearer) = (0usize, 0usize);
        for y in (v - half).max(0)..=(v + half).min(h - 1) {
            for x in (u - half).max(0)..=(u + half).min(w - 1) {
                if self.mask.get(x, y) {
                    return Sight::Rope;
                }
                let raw = self.frame.depth[(y * w + x) as usize];
                if raw == 0 {
                    continue;
                }
                measured += 1;
                if (raw as f64) * self.frame.depth_scale < p.z - OCCLUDER_MARGIN {
                    nearer += 1;
                }
            }
        }
        if measured == 0 {
            Sight::Unknown
        } else if nearer > 0 && nearer >= self.occluder_pixels(p.z, measured) {
            Sight::Occluded
        } else {
            Sight::FreeSpace
        }
    }

    /// The fewest of `measured` pixels around a point `z` metres away that
    /// must be nearer than it by [`OCCLUDER_MARGIN`] to say something hides
    /// it: one more than depth noise alone would give, with the chance
    /// [`OCCLUDER_FALSE_ALARM_SIGMAS`] allows, if the pixels showed the
    /// open table a rope's radius behind the point (each one that near with
    /// chance `q`, one deviation of the count above its mean). Near the
    /// camera `q` is negligible and one pixel is enough (0.9 m, a 5 mm
    /// rope: `q` below 1e-6); at 1.9 m one deviation of depth is 9 mm, as
    /// much as the margin, and a window of 81 pixels needs 9.
    pub fn occluder_pixels(&self, z: f64, measured: usize) -> usize {
        let focal = 0.5 * (self.camera.fx + self.camera.fy);
        let sigma = depth_noise(z, focal);
        let q =
            0.5 * libm::erfc((OCCLUDER_MARGIN + self.radius) / (sigma * core::f64::consts::SQRT_2));
        let n = measured as f64;
        let spread = libm::sqrt(n * q * (1.0 - q));
        1 + libm::floor(n * q + OCCLUDER_FALSE_ALARM_SIGMAS * spread) as usize
    }
}

/// A scene for tests: a flat table seen straight on, no rope pixels.
#[cfg(test)]
pub(crate) mod fixture {
    use super::Evidence;
    use crate::math::Vec3;
    use crate::perception::camera::CameraIntrinsics;
    use crate::perception::frame::Frame;
    use crate::perception::segmentation::{Mask, Rect};
    use alloc::vec::Vec;

    /// A `width` x `height` camera of focal `focal` px, principal point at
    /// the centre, over a table at `depth` mm (1 mm depth units).
    pub struct Table {
        pub camera: CameraIntrinsics,
        pub rgb: Vec<u8>,
        pub depth: Vec<u16>,
        pub mask: Mask,
    }

    impl Table {
        pub fn new(width: u32, height: u32, focal: f64, depth: u16) -> Self {
            let n = (width * height) as usize;
            Self {
                camera: CameraIntrinsics {
                    width,
                    height,
                    fx: focal,
                    fy: focal,
                    cx: width as f64 / 2.0,
                    cy: height as f64 / 2.0,
                },
                rgb: alloc::vec![0; n * 3],
                depth: alloc::vec![depth; n],
                mask: Mask::new(width, height),
            }
        }

        pub fn frame(&self) -> Frame<'_> {
            let c = &self.camera;
            Frame::new(c.width, c.height, &self.rgb, &self.depth, 0.001).expect("frame")
        }

        pub fn evidence<'a>(
            &'a self,
            frame: &'a Frame<'a>,
            occlusions: &'a [Rect],
            radius: f64,
        ) -> Evidence<'a> {
            Evidence {
                frame,
                mask: &self.mask,
                occlusions,
                camera: &self.camera,
                radius,
                others: None,
            }
        }

        /// The point `z` metres away that projects to pixel (u, v).
        pub fn at(&self, u: f64, v: f64, z: f64) -> Vec3 {
            let c = &self.camera;
            Vec3::new((u - c.cx) * z / c.fx, (v - c.cy) * z / c.fy, z)
        }

        /// Six nodes along row 24 at 0.59 m (just above a table at 0.6 m):
        /// 0-2 from column 44 in to column 36, 3-5 (a hidden tip) on to
        /// column 22.
        pub fn tip_along_row_24(&self) -> Vec<Vec3> {
            [44.0, 40.0, 36.0, 30.0, 26.0, 22.0]
                .iter()
                .map(|&u| self.at(u, 24.0, 0.59))
                .collect()
        }

        /// Rope points along row 24 from column 36 to 44, at 0.59 m: what
        /// the first three nodes of [`Table::tip_along_row_24`] see.
        pub fn rope_along_row_24(&self) -> Vec<Vec3> {
            (0..=40)
                .map(|k| self.at(36.0 + k as f64 * 0.2, 24.0, 0.59))
                .collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::fixture::Table;
    use super::*;
    use crate::perception::segmentation::Mask;

    /// A piece along row 20 of a table at 0.6 m (80x40 camera, focal 60
    /// px, radius 5 mm: it looks 2 radii, a pixel, to each side):
    /// lifted 5 cm it stands free; on the table it does not; lifted along
    /// the top edge of a box standing as high, whose face is on one side
    /// of it, it does not either; and a declared rectangle beside it, or a
    /// side with no depth, says nothing for it.
    #[test]
    fn only_a_piece_with_a_surface_well_behind_it_on_both_sides_stands_free() {
        let mut t = Table::new(80, 40, 60.0, 600);
        for u in 20..60 {
            t.mask.data[20 * 80 + u] = true;
        }
        let line = |z: f64| -> Vec<Vec3> {
            (20..60)
                .step_by(5)
                .map(|u| t.at(u as f64, 20.0, z))
                .collect()
        };
        let (lifted, resting) = (line(0.545), line(0.595));
        {
            let frame = t.frame();
            let e = t.evidence(&frame, &[], 0.005);
            assert!(e.stands_free(&lifted));
            assert!(!e.stands_free(&resting));
            // A rectangle over the rows above: that side is covered.
            let above = [Rect {
                x: 0,
                y: 0,
                w: 80,
                h: 20,
            }];
            let e = t.evidence(&frame, &above, 0.005);
            assert!(!e.stands_free(&lifted));
        }
        // The same piece over other rows below it, at `depth` mm.
        let below = |depth: u16| {
            let mut other = Table::new(80, 40, 60.0, 600);
            other.mask.data.clone_from(&t.mask.data);
            other.depth[21 * 80..].fill(depth);
            other
        };
        // A box 5.5 cm high over the rows below, its top edge along the
        // piece: one side is the box's face.
        let boxed = below(545);
        let frame = boxed.frame();
        assert!(!boxed.evidence(&frame, &[], 0.005).stands_free(&lifted));
        // No depth below: only the side above is measured, and one side
        // alone is no evidence.
        let unmeasured = below(0);
        let frame = unmeasured.frame();
        assert!(!unmeasured.evidence(&frame, &[], 0.005).stands_free(&lifted));
        assert!(!t.evidence(&t.frame(), &[], 0.005).stands_free(&[]));
    }

    /// One row of a table at 0.6 m seen by an 80x40 camera, for points at
    /// 0.59 m: a rope pixel at column 46, a surface at 0.5 m at column 10,
    /// one 5 mm in front of the points at 30 (depth noise), no depth at 12;
    /// and a rectangle over columns 60-64.
    fn one_row() -> (Table, [Rect; 1]) {
        let mut t = Table::new(80, 40, 40.0, 600);
        t.mask.data[20 * 80 + 46] = true;
        t.depth[20 * 80 + 10] = 500;
        t.depth[20 * 80 + 30] = 585;
        t.depth[20 * 80 + 12] = 0;
        let rect = Rect {
            x: 60,
            y: 15,
            w: 5,
            h: 10,
        };
        (t, [rect])
    }

    /// Open table 1.9 m away, a 13.6 mm rope's axis a radius in front of
    /// it (drawn tuning seed 1025): one deviation of depth there is 9.4 mm,
    /// so a few of the window's 81 pixels are always a centimetre nearer
    /// by noise alone, and taking any one of them for an occluder let a
    /// hidden end run out of its rectangle onto the open table (2.1 ->
    /// 17.3 mm). Noise alone is free space; a box over a third of the
    /// window is an occluder, as is one pixel near the camera.
    #[test]
    fn depth_noise_on_open_table_far_away_is_not_an_occluder() {
        let (focal, radius, table_mm) = (615.0, 0.0068, 1900u16);
        let mut t = Table::new(80, 80, focal, table_mm);
        let sigma_mm = 1000.0 * depth_noise(1.9, focal);
        assert!((sigma_mm - 9.4).abs() < 0.1, "{sigma_mm}");
        let mut rng = crate::rng::SplitMix64::new(1025);
        for d in t.depth.iter_mut() {
            *d = libm::round(f64::from(table_mm) + sigma_mm * rng.normal()) as u16;
        }
        let p = t.at(40.0, 40.0, 1.9 - radius);
        let nearer = |t: &Table| {
            let (u0, u1) = (36, 44);
            (u0..=u1)
                .flat_map(|y| (u0..=u1).map(move |x| (x, y)))
                .filter(|&(x, y)| f64::from(t.depth[y * 80 + x]) * 0.001 < p.z - OCCLUDER_MARGIN)
                .count()
        };
        // The old rule's one pixel is there; the count is not above noise.
        assert!(nearer(&t) >= 1, "the noise draw shows no near pixel");
        let sight = |t: &Table| {
            let f = t.frame();
            t.evidence(&f, &[], radius).sight(&p)
        };
        assert_eq!(sight(&t), Sight::FreeSpace);
        // A box 5 cm above the table over the window's three left columns.
        let mut boxed = Table::new(80, 80, focal, table_mm);
        boxed.depth.clone_from(&t.depth);
        for y in 36..=44 {
            for x in 36..=38 {
                boxed.depth[y * 80 + x] = table_mm - 50;
            }
        }
        assert_eq!(sight(&boxed), Sight::Occluded);
        // Near the camera a single pixel still counts.
        let f = t.frame();
        let e = t.evidence(&f, &[], 0.005);
        assert_eq!(e.occluder_pixels(0.9, 81), 1);
        assert!(e.occluder_pixels(1.9, 81) > 5);
    }

    #[test]
    fn a_rope_goes_on_only_over_rope_pixels_or_out_of_view() {
        let (t, rect) = one_row();
        let f = t.frame();
        let e = t.evidence(&f, &rect, 0.05);
        let shows = |u: f64| e.shows_rope_at(&t.at(u, 20.0, 0.59));
        assert!(shows(46.0)); // rope colour
        assert!(shows(200.0) && shows(-3.0)); // outside the image
                                              // Behind the camera.
        assert!(e.shows_rope_at(&Vec3::new(0.0, 0.0, -1.0)));
        // Free table beside the rope pixel, and what could hide a rope but
        // does not show one: a surface in front, no depth, a rectangle.
        for u in [45.0, 10.0, 30.0, 12.0, 62.0] {
            assert!(!shows(u), "{u}");
        }
    }

    #[test]
    fn only_an_occluder_at_its_own_pixel_hides_a_rope() {
        let (t, rect) = one_row();
        let f = t.frame();
        let e = t.evidence(&f, &rect, 0.05);
        let hides = |u: f64| e.hides_rope_at(&t.at(u, 20.0, 0.59));
        assert!(hides(10.0) && hides(62.0));
        // Just past the last column, in the row above a surface at the next
        // row's first column: outside the image, so nothing hides it.
        let mut edge = Table::new(80, 40, 40.0, 600);
        edge.depth[20 * 80] = 500;
        let ef = edge.frame();
        let ee = edge.evidence(&ef, &[], 0.05);
        assert!(ee.hides_rope_at(&edge.at(0.0, 20.0, 0.59)));
        assert!(!ee.hides_rope_at(&edge.at(80.0, 19.0, 0.59)));
        assert!(ee.shows_rope_at(&edge.at(80.0, 19.0, 0.59)));
        // Beside the occluder (its window would see it), the noise, no
        // depth, rope colour, free table, outside the image, behind the camera.
        for u in [11.0, 30.0, 12.0, 46.0, 45.0, 200.0, -3.0] {
            assert!(!hides(u), "{u}");
        }
        assert!(!e.hides_rope_at(&Vec3::new(0.0, 0.0, -1.0)));
    }

    #[test]
    fn the_window_spans_one_and_a_half_rope_radii_in_pixels() {
        let mut t = Table::new(80, 40, 40.0, 600);
        let p = Vec3::new(0.0, 0.0, 0.59);
        let sight = |t: &Table, radius: f64| t.evidence(&t.frame(), &[], radius).sight(&p);
        t.mask.data[20 * 80 + 46] = true;
        // 1.5 r f / z pixels, rounded up: r = 5.9 cm -> 6 px (sees the rope
        // pixel 6 px away); r = 4.9 cm -> 5 px (does not); 1 mm -> at least 2 px.
        assert_eq!(sight(&t, 0.059), Sight::Rope);
        assert_eq!(sight(&t, 0.049), Sight::FreeSpace);
        assert_eq!(sight(&t, 0.001), Sight::FreeSpace);
        // The cap: 12 px whatever the radius.
        t.mask.data[20 * 80 + 46] = false;
        t.mask.data[20 * 80 + 53] = true;
        assert_eq!(sight(&t, 1.0), Sight::FreeSpace);
        t.mask.data[20 * 80 + 53] = false;
        t.mask.data[20 * 80 + 52] = true;
        assert_eq!(sight(&t, 1.0), Sight::Rope);
    }

    #[test]
    fn a_point_is_judged_by_what_its_pixels_show() {
        // A table at 0.6 m; a box at 0.5 m over columns 30..40; no depth in
        // rows 0..5; rope pixels at column 5.
        let mut t = Table::new(40, 40, 40.0, 600);
        for y in 0..40 {
            for x in 30..40 {
                t.depth[y * 40 + x] = 500;
            }
        }
        for x in 0..40 {
            for y in 0..5 {
                t.depth[y * 40 + x] = 0;
            }
        }
        for y in 0..40 {
            t.mask.data[y * 40 + 5] = true;
        }
        let rect = [Rect {
            x: 15,
            y: 30,
            w: 5,
            h: 5,
        }];
        let frame = t.frame();
        let e = t.evidence(&frame, &rect, 0.0075);
        // A pixel at (u, v) for a point 0.59 m away, just above the table.
        let at = |u: f64, v: f64| t.at(u, v, 0.59);
        assert_eq!(e.sight(&at(20.0, 20.0)), Sight::FreeSpace);
        assert!(!e.sight(&at(20.0, 20.0)).allows_hidden());
        assert_eq!(e.sight(&at(35.0, 20.0)), Sight::Occluded);
        assert_eq!(e.sight(&at(6.0, 20.0)), Sight::Rope);
        assert_eq!(e.sight(&at(17.0, 32.0)), Sight::Covered);
        assert_eq!(e.sight(&at(20.0, 1.0)), Sight::Unknown);
        assert_eq!(e.sight(&at(60.0, 20.0)), Sight::OutOfView);
        assert_eq!(e.sight(&Vec3::new(0.0, 0.0, -1.0)), Sight::OutOfView);
        // The image's first and last columns are in view, one beyond is not.
        assert_ne!(e.sight(&at(0.0, 20.0)), Sight::OutOfView);
        assert_ne!(e.sight(&at(39.4, 20.0)), Sight::OutOfView);
        assert_ne!(e.sight(&at(20.0, 0.0)), Sight::OutOfView);
        assert_eq!(e.sight(&at(-0.6, 20.0)), Sight::OutOfView);
        assert_eq!(e.sight(&at(20.0, 39.6)), Sight::OutOfView);
        // Below the table (behind it): the table is nearer, so it hides the point.
        assert_eq!(e.sight(&Vec3::new(0.0, 0.0, 0.62)), Sight::Occluded);
        // A surface 5 mm nearer is noise, 15 mm nearer over three rows of
        // the window an occluder. (This toy camera's 40 px focal length
        // makes one deviation of depth 14 mm at 0.6 m: one row of the 5 x 5
        // window, 5 pixels, is what noise alone could give.)
        let mut near = Table::new(40, 40, 40.0, 600);
        near.depth.clone_from(&t.depth);
        near.mask = t.mask.clone();
        for x in 15..25 {
            near.depth[20 * 40 + x] = 585;
            for y in 24..=26 {
                near.depth[y * 40 + x] = 575;
            }
        }
        let frame2 = near.frame();
        let e2 = near.evidence(&frame2, &rect, 0.0075);
        assert_eq!(e2.sight(&at(20.0, 20.0)), Sight::FreeSpace);
        assert_eq!(e2.sight(&at(20.0, 25.0)), Sight::Occluded);
    }

    #[test]
    fn the_window_is_centred_and_stops_at_the_image_edge() {
        let mut t = Table::new(80, 40, 40.0, 600);
        let sight = |t: &Table, p: &Vec3| t.evidence(&t.frame(), &[], 0.02).sight(p);
        let p = Vec3::new(0.0, 0.0, 0.59);
        // r = 2 cm: 1.5 * 0.02 * 40 / 0.59 = 2.03 -> 3 px on every side.
        for (x, y, inside) in [
            (37, 20, true),
            (36, 20, false),
            (40, 17, true),
            (40, 16, false),
            (40, 23, true),
            (40, 24, false),
            (43, 20, true),
            (44, 20, false),
        ] {
            t.mask = Mask::new(80, 40);
            t.mask.data[y * 80 + x] = true;
            let expected = if inside {
                Sight::Rope
            } else {
                Sight::FreeSpace
            };
            assert_eq!(sight(&t, &p), expected, "rope pixel ({x}, {y})");
        }
        // r = 8 cm: 1.5 r f / z = 8.1 -> 9 px, so a rope pixel 9 px away is seen.
        t.mask = Mask::new(80, 40);
        t.mask.data[20 * 80 + 49] = true;
        assert_eq!(t.evidence(&t.frame(), &[], 0.08).sight(&p), Sight::Rope);
        // At the last column and row the window stops at the image: the
        // next row's first pixel (a near surface) is not read as beside it.
        t.mask = Mask::new(80, 40);
        t.depth[21 * 80] = 300;
        assert_eq!(sight(&t, &t.at(79.0, 20.0, 0.59)), Sight::FreeSpace);
        assert_eq!(sight(&t, &t.at(79.0, 39.0, 0.59)), Sight::FreeSpace);
        // A surface exactly OCCLUDER_MARGIN nearer does not hide the point;
        // one depth unit more does.
        let z = 300.0 * 0.001 + OCCLUDER_MARGIN;
        let flat = Table::new(80, 40, 40.0, 300);
        assert_eq!(sight(&flat, &Vec3::new(0.0, 0.0, z)), Sight::FreeSpace);
        let nearer = Table::new(80, 40, 40.0, 299);
        assert_eq!(sight(&nearer, &Vec3::new(0.0, 0.0, z)), Sight::Occluded);
    }

    #[test]
    fn the_rope_s_depth_near_a_point_is_the_median_of_its_own_measured_pixels() {
        // Rope pixels in columns 10..13 at 590, 600 and 610 mm, one of them
        // without depth; the table (not rope) at 700 mm.
        let mut t = Table::new(40, 30, 100.0, 700);
        for v in 0..30 {
            for (u, z) in [(10, 590), (11, 600), (12, 610)] {
                t.mask.data[v * 40 + u] = true;
                t.depth[v * 40 + u] = z;
            }
            t.depth[v * 40 + 12] = if v == 15 { 0 } else { 610 };
        }
        let frame = t.frame();
        let e = t.evidence(&frame, &[], 0.005);
        let at = |u: f64, v: f64| e.rope_depth_near(Vec2::new(u, v), 1);
        // A 3x3 window over columns 10..12: the median of nine rope pixels.
        assert_eq!(at(11.0, 5.0), Some(0.6));
        // Only the table around: nothing; the window's own rope pixels only.
        assert_eq!(at(20.0, 5.0), None);
        assert_eq!(at(13.0, 5.0), Some(0.61));
        // Without depth at (12, 15): the eight others (590 x 3, 600 x 3, 610 x 2).
        assert_eq!(at(11.0, 15.0), Some(0.6));
        // Another rope's pixels are not this rope's.
        let mut others = Mask::new(40, 30);
        for v in 0..30 {
            others.data[v * 40 + 10] = true;
            others.data[v * 40 + 11] = true;
        }
        let shared = Evidence {
            others: Some(&others),
            ..e
        };
        assert_eq!(shared.rope_depth_near(Vec2::new(11.0, 5.0), 1), Some(0.61));
        // Outside the image or not a number: nothing, and no panic.
        for bad in [(-1.0, 5.0), (40.0, 5.0), (f64::NAN, 5.0), (1e300, 1e300)] {
            assert_eq!(at(bad.0, bad.1), None);
        }
    }

    #[test]
    fn something_hides_the_rope_around_a_point_only_in_front_of_the_table_however_tilted() {
        // A 80x80 camera of focal 100 px over a table tilted about 40
        // degrees about the image's x axis: 0.6 m deep at the centre row,
        // 5 mm deeper per row down (6 mm across). A rope point on it, 5 mm radius, at the centre.
        let mut t = Table::new(80, 80, 100.0, 600);
        for v in 0..80 {
            for u in 0..80 {
                t.depth[v * 80 + u] = (600 + 5 * (v as i64 - 40)) as u16;
            }
        }
        let p = t.at(40.0, 40.0, 0.595);
        let hidden = |t: &Table, rects: &[Rect]| {
            t.evidence(&t.frame(), rects, 0.005).hidden_around(&p, 0.06)
        };
        // 6 cm at 0.595 m: 10 px, where the table is 5 cm nearer above and
        // deeper below: no occluder, though a point at p's depth 10 px up
        // lies 4.5 cm behind the table there.
        assert!(!hidden(&t, &[]));
        assert!(t
            .evidence(&t.frame(), &[], 0.005)
            .hides_rope_at(&t.at(40.0, 30.0, 0.595)));
        // A box 2 cm above the table over columns 48..52: something hides.
        let mut boxed = Table {
            depth: t.depth.clone(),
            ..Table::new(80, 80, 100.0, 600)
        };
        for v in 0..80 {
            for u in 48..52 {
                boxed.depth[v * 80 + u] -= 20;
            }
        }
        assert!(hidden(&boxed, &[]));
        // The same box painted as rope says nothing.
        for v in 0..80 {
            for u in 48..52 {
                boxed.mask.data[v * 80 + u] = true;
            }
        }
        assert!(!hidden(&boxed, &[]));
        // A declared rectangle 5 px away does.
        assert!(hidden(
            &t,
            &[Rect {
                x: 44,
                y: 0,
                w: 16,
                h: 80
            }]
        ));
        assert!(!hidden(
            &t,
            &[Rect {
                x: 60,
                y: 0,
                w: 10,
                h: 80
            }]
        ));
        // Nothing to say behind the camera or with no radius.
        let f = t.frame();
        let e = t.evidence(&f, &[], 0.005);
        assert!(!e.hidden_around(&Vec3::new(0.0, 0.0, -0.5), 0.06));
        assert!(!e.hidden_around(&p, 0.0));
        assert!(!e.hidden_around(&p, f64::NAN));
    }
    #[test]
    fn a_thick_rope_s_own_edge_outside_its_mask_does_not_hide_its_tip() {
        // A table at 0.6 m; a rope 16 mm thick along column 40 from row 40
        // down, its top 0.584 m away over columns 37-43 but its mask only
        // columns 39-41 (a shaded edge out of the colour range). Its tip's
        // point at (40, 40) lies on the end's cap, at the axis' depth.
        let mut t = Table::new(80, 80, 100.0, 600);
        for v in 40..80 {
            for u in 37..=43 {
                t.depth[v * 80 + u] = 584;
            }
            for u in 39..=41 {
                t.mask.data[v * 80 + u] = true;
            }
        }
        let tip = t.at(40.0, 40.0, 0.592);
        let f = t.frame();
        let e = t.evidence(&f, &[], 0.008);
        // 2 cm round it: its own edges, and open table beyond the tip.
        assert!(!e.hidden_around(&tip, 0.02));
        // A box 2 cm above the table beside it does hide.
        let mut boxed = Table {
            depth: t.depth.clone(),
            mask: t.mask.clone(),
            ..Table::new(80, 80, 100.0, 600)
        };
        for v in 30..50 {
            for u in 42..60 {
                boxed.depth[v * 80 + u] = 580;
            }
        }
        let f = boxed.frame();
        assert!(boxed.evidence(&f, &[], 0.008).hidden_around(&tip, 0.02));
    }
}
