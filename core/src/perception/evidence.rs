//! What this frame's images say about a point in space: whether a rope
//! could be there unseen. A hidden node is plausible only where something
//! hides it (a surface nearer the camera in the depth image, a declared
//! occlusion rectangle), outside the image, where the depth camera has no
//! measurement, or on rope-coloured pixels; a node whose pixels show a
//! surface at or behind it with no rope colour is in free space.

use super::camera::CameraIntrinsics;
use super::frame::Frame;
use super::segmentation::{Mask, Rect};
use crate::math::Vec3;

/// A surface this much nearer the camera than a point hides it, metres:
/// well above the depth noise at a metre (about 3 mm) and below the gap
/// between a rope and a hand or box held just above it.
pub const OCCLUDER_MARGIN: f64 = 0.01;

/// Half-width of the window of pixels looked at around a point's
/// projection, as a multiple of the rope's radius in pixels (the window
/// covers the rope's width, so a node near an occluder's edge is not
/// judged by a single pixel beside it).
pub const WINDOW_RADII: f64 = 1.5;

/// Smallest half-width of that window, pixels.
pub const MIN_WINDOW_PX: i64 = 2;

/// Largest half-width of that window, pixels (caps the cost per point).
pub const MAX_WINDOW_PX: i64 = 12;

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
}

impl Evidence<'_> {
    /// What the images say about `p` (camera frame, metres).
    pub fn sight(&self, p: &Vec3) -> Sight {
        let Some(q) = self.camera.project(p) else {
            return Sight::OutOfView;
        };
        let (u, v) = (libm::round(q.x) as i64, libm::round(q.y) as i64);
        let (w, h) = (self.frame.width as i64, self.frame.height as i64);
        if u < 0 || v < 0 || u >= w || v >= h {
            return Sight::OutOfView;
        }
        if self.occlusions.iter().any(|r| r.contains(u, v)) {
            return Sight::Covered;
        }
        let focal = 0.5 * (self.camera.fx + self.camera.fy);
        let half = (libm::ceil(WINDOW_RADII * self.radius * focal / p.z) as i64)
            .clamp(MIN_WINDOW_PX, MAX_WINDOW_PX);
        let mut any_depth = false;
        for y in (v - half).max(0)..=(v + half).min(h - 1) {
            for x in (u - half).max(0)..=(u + half).min(w - 1) {
                if self.mask.get(x, y) {
                    return Sight::Rope;
                }
                let raw = self.frame.depth[(y * w + x) as usize];
                if raw == 0 {
                    continue;
                }
                any_depth = true;
                if (raw as f64) * self.frame.depth_scale < p.z - OCCLUDER_MARGIN {
                    return Sight::Occluded;
                }
            }
        }
        if any_depth {
            Sight::FreeSpace
        } else {
            Sight::Unknown
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;

    #[test]
    fn the_window_spans_one_and_a_half_rope_radii_in_pixels() {
        let camera = CameraIntrinsics {
            width: 80,
            height: 40,
            fx: 40.0,
            fy: 40.0,
            cx: 40.0,
            cy: 20.0,
        };
        let rgb = vec![0u8; 80 * 40 * 3];
        let depth = vec![600u16; 80 * 40];
        let frame = Frame::new(80, 40, &rgb, &depth, 0.001).expect("frame");
        let mut mask = Mask::new(80, 40);
        mask.data[20 * 80 + 46] = true;
        let p = Vec3::new(0.0, 0.0, 0.59);
        let sight = |radius: f64| {
            Evidence {
                frame: &frame,
                mask: &mask,
                occlusions: &[],
                camera: &camera,
                radius,
            }
            .sight(&p)
        };
        // 1.5 r f / z pixels, rounded up: r = 5.9 cm -> 6 px (sees the rope
        // pixel 6 px away); r = 4.9 cm -> 5 px (does not); 1 mm -> at least 2 px.
        assert_eq!(sight(0.059), Sight::Rope);
        assert_eq!(sight(0.049), Sight::FreeSpace);
        assert_eq!(sight(0.001), Sight::FreeSpace);
        // The cap: 12 px whatever the radius.
        mask.data[20 * 80 + 46] = false;
        mask.data[20 * 80 + 53] = true;
        let far = Evidence {
            frame: &frame,
            mask: &mask,
            occlusions: &[],
            camera: &camera,
            radius: 1.0,
        };
        assert_eq!(far.sight(&p), Sight::FreeSpace);
        mask.data[20 * 80 + 53] = false;
        mask.data[20 * 80 + 52] = true;
        let edge = Evidence {
            frame: &frame,
            mask: &mask,
            occlusions: &[],
            camera: &camera,
            radius: 1.0,
        };
        assert_eq!(edge.sight(&p), Sight::Rope);
    }

    #[test]
    fn a_point_is_judged_by_what_its_pixels_show() {
        let camera = CameraIntrinsics {
            width: 40,
            height: 40,
            fx: 40.0,
            fy: 40.0,
            cx: 20.0,
            cy: 20.0,
        };
        // A table at 0.6 m; a box at 0.5 m over columns 30..40; no depth in
        // rows 0..5; rope pixels at column 5.
        let rgb = vec![0u8; 40 * 40 * 3];
        let mut depth = vec![600u16; 40 * 40];
        for y in 0..40 {
            for x in 30..40 {
                depth[y * 40 + x] = 500;
            }
        }
        for x in 0..40 {
            for y in 0..5 {
                depth[y * 40 + x] = 0;
            }
        }
        let frame = Frame::new(40, 40, &rgb, &depth, 0.001).expect("frame");
        let mut mask = Mask::new(40, 40);
        for y in 0..40 {
            mask.data[y * 40 + 5] = true;
        }
        let rect = [Rect {
            x: 15,
            y: 30,
            w: 5,
            h: 5,
        }];
        let e = Evidence {
            frame: &frame,
            mask: &mask,
            occlusions: &rect,
            camera: &camera,
            radius: 0.0075,
        };
        // A pixel at (u, v) for a point 0.59 m away, just above the table.
        let at =
            |u: f64, v: f64| Vec3::new((u - 20.0) * 0.59 / 40.0, (v - 20.0) * 0.59 / 40.0, 0.59);
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
        // A surface 5 mm nearer is noise, 15 mm nearer an occluder.
        let mut near = depth.clone();
        for x in 15..25 {
            near[20 * 40 + x] = 585;
            near[25 * 40 + x] = 575;
        }
        let frame2 = Frame::new(40, 40, &rgb, &near, 0.001).expect("frame");
        let e2 = Evidence {
            frame: &frame2,
            ..e
        };
        assert_eq!(
            e2.sight(&Vec3::new(0.0, (20.0 - 20.0) * 0.59 / 40.0, 0.59)),
            Sight::FreeSpace
        );
        assert_eq!(e2.sight(&at(20.0, 25.0)), Sight::Occluded);
        // Below the table (behind it): the table is nearer, so it hides the point.
        let below = Vec3::new(0.0, 0.0, 0.62);
        assert_eq!(e.sight(&below), Sight::Occluded);
    }

    #[test]
    fn the_window_is_centred_and_stops_at_the_image_edge() {
        let camera = CameraIntrinsics {
            width: 80,
            height: 40,
            fx: 40.0,
            fy: 40.0,
            cx: 40.0,
            cy: 20.0,
        };
        let rgb = vec![0u8; 80 * 40 * 3];
        let mut depth = vec![600u16; 80 * 40];
        let p = Vec3::new(0.0, 0.0, 0.59);
        let judge = |mask: &Mask, depth: &[u16], p: &Vec3, radius: f64| {
            let frame = Frame::new(80, 40, &rgb, depth, 0.001).expect("frame");
            Evidence {
                frame: &frame,
                mask,
                occlusions: &[],
                camera: &camera,
                radius,
            }
            .sight(p)
        };
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
            let mut mask = Mask::new(80, 40);
            mask.data[y * 80 + x] = true;
            let expected = if inside {
                Sight::Rope
            } else {
                Sight::FreeSpace
            };
            assert_eq!(
                judge(&mask, &depth, &p, 0.02),
                expected,
                "rope pixel ({x}, {y})"
            );
        }
        // r = 8 cm: 1.5 r f / z = 8.1 -> 9 px, so a rope pixel 9 px away is seen.
        let mut mask = Mask::new(80, 40);
        mask.data[20 * 80 + 49] = true;
        assert_eq!(judge(&mask, &depth, &p, 0.08), Sight::Rope);
        // At the last column and row the window stops at the image: the
        // next row's first pixel (a near surface) is not read as beside it.
        let empty = Mask::new(80, 40);
        depth[21 * 80] = 300;
        let right = Vec3::new(39.0 * 0.59 / 40.0, 0.0, 0.59);
        assert_eq!(judge(&empty, &depth, &right, 0.02), Sight::FreeSpace);
        let corner = Vec3::new(39.0 * 0.59 / 40.0, 19.0 * 0.59 / 40.0, 0.59);
        assert_eq!(judge(&empty, &depth, &corner, 0.02), Sight::FreeSpace);
        // A surface exactly OCCLUDER_MARGIN nearer does not hide the point;
        // one depth unit more does.
        let flat = vec![300u16; 80 * 40];
        let z = 300.0 * 0.001 + OCCLUDER_MARGIN;
        assert_eq!(
            judge(&empty, &flat, &Vec3::new(0.0, 0.0, z), 0.02),
            Sight::FreeSpace
        );
        let nearer = vec![299u16; 80 * 40];
        assert_eq!(
            judge(&empty, &nearer, &Vec3::new(0.0, 0.0, z), 0.02),
            Sight::Occluded
        );
    }
}
