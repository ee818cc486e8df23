//! The point cloud of one frame: masked pixels with valid depth, deprojected,
//! downsampled on a voxel grid, and moved from the rope's surface to its axis.

use alloc::vec;
use alloc::vec::Vec;

use super::camera::CameraIntrinsics;
use super::frame::Frame;
use super::segmentation::Mask;
use crate::math::{self, Vec3};

/// Most points handed to registration. Larger clouds are thinned by a fixed
/// stride so that one frame's cost stays bounded whatever the input.
pub const MAX_CLOUD_POINTS: usize = 20_000;

/// Voxel indices beyond this magnitude (about 8 km at 8 mm leaves) are dropped.
const MAX_VOXEL_INDEX: i64 = 1 << 20;

/// Ratio of the mean depth offset between a cylinder's visible surface and its
/// axis to its radius: the mean of sqrt(1 - s^2) over s in [-1, 1] is pi/4.
pub const SURFACE_TO_AXIS_RATIO: f64 = core::f64::consts::FRAC_PI_4;

/// Which depths count as measurements, and how to turn pixels into points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CloudSettings {
    /// Nearest valid depth, metres.
    pub min_depth: f64,
    /// Farthest valid depth, metres.
    pub max_depth: f64,
    /// Voxel leaf size, metres (0 keeps every point).
    pub voxel_size: f64,
    /// Distance each point is pushed away from the camera along its ray, metres.
    pub axis_offset: f64,
}

/// Depth in metres of pixel `i`, or `None` if it has no valid measurement.
#[inline]
pub fn depth_at(frame: &Frame<'_>, i: usize, settings: &CloudSettings) -> Option<f64> {
    let raw = *frame.depth.get(i)?;
    if raw == 0 {
        return None;
    }
    let z = raw as f64 * frame.depth_scale;
    (z >= settings.min_depth && z <= settings.max_depth).then_some(z)
}

/// Deprojects every masked pixel with a valid depth.
pub fn deproject_mask(
    frame: &Frame<'_>,
    mask: &Mask,
    camera: &CameraIntrinsics,
    settings: &CloudSettings,
) -> Vec<Vec3> {
    let width = frame.width as usize;
    let mut points = Vec::new();
    for (v, row) in mask.data.chunks_exact(width).enumerate() {
        for (k, run) in row.chunks(MASK_RUN).enumerate() {
            // Most runs are empty: a test without early exit vectorises.
            if !run.iter().fold(false, |any, &m| any | m) {
                continue;
            }
            let u0 = k * MASK_RUN;
            for (u, _) in run.iter().enumerate().filter(|(_, &m)| m) {
                let u = u0 + u;
                if let Some(z) = depth_at(frame, v * width + u, settings) {
                    points.push(camera.deproject(u as f64, v as f64, z));
                }
            }
        }
    }
    points
}

/// Mask pixels tested together before deprojection looks at each.
const MASK_RUN: usize = 32;

/// `floor(x)` as an integer for finite `x` (saturating beyond the i64
/// range), the same value as `libm::floor(x) as i64` without the call.
#[inline]
fn floor_to_i64(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) > x {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// One voxel's accumulator in [`voxel_downsample`]'s table.
#[derive(Clone, Copy)]
struct VoxelSlot {
    key: u64,
    sum: Vec3,
    count: u32,
}

/// Slot key of an empty slot (no voxel key reaches it: keys use 63 bits).
const EMPTY_VOXEL: u64 = u64::MAX;

/// Smallest voxel table; it doubles whenever it is half full.
const MIN_VOXEL_SLOTS: usize = 64;

/// Voxel-grid downsampling: one point, the centroid, per occupied cube of
/// side `leaf`. The output is ordered by voxel index, so it does not depend
/// on the input order. Non-finite points are dropped.
pub fn voxel_downsample(points: &[Vec3], leaf: f64) -> Vec<Vec3> {
    if !(leaf > 0.0 && leaf.is_finite()) {
        return points.iter().copied().filter(math::is_finite).collect();
    }
    // Open addressing, at most half full: a rope's cloud has far fewer
    // voxels than points, so the table starts small and doubles.
    let mut slots = vec![
        VoxelSlot {
            key: EMPTY_VOXEL,
            sum: Vec3::zeros(),
            count: 0,
        };
        MIN_VOXEL_SLOTS
    ];
    let mut used = 0;
    let inv = 1.0 / leaf;
    for p in points {
        if !math::is_finite(p) {
            continue;
        }
        let idx = [p.x, p.y, p.z].map(|c| floor_to_i64(c * inv));
        if idx.iter().any(|k| k.abs() >= MAX_VOXEL_INDEX) {
            continue;
        }
        let key = idx
            .iter()
            .fold(0u64, |acc, &k| (acc << 21) | (k + MAX_VOXEL_INDEX) as u64);
        if 2 * (used + 1) > slots.len() {
            slots = grown(&slots);
        }
        let at = voxel_slot(&slots, key);
        let slot = &mut slots[at];
        if slot.key == EMPTY_VOXEL {
            slot.key = key;
            used += 1;
        }
        slot.sum += p;
        slot.count += 1;
    }
    let mut occupied: Vec<(u64, usize)> = slots
        .iter()
        .enumerate()
        .filter(|(_, s)| s.key != EMPTY_VOXEL)
        .map(|(i, s)| (s.key, i))
        .collect();
    occupied.sort_unstable();
    occupied
        .into_iter()
        .map(|(_, i)| slots[i].sum / slots[i].count as f64)
        .collect()
}

/// The slot holding `key`, or the empty one where it goes (the table has a
/// power-of-two length and at least one empty slot).
fn voxel_slot(slots: &[VoxelSlot], key: u64) -> usize {
    let mask = slots.len() - 1;
    let shift = 64 - slots.len().trailing_zeros();
    let mut slot = (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> shift) as usize;
    while slots[slot].key != EMPTY_VOXEL && slots[slot].key != key {
        slot = (slot + 1) & mask;
    }
    slot
}

/// The table at twice the size, with every voxel moved over unchanged.
fn grown(slots: &[VoxelSlot]) -> Vec<VoxelSlot> {
    let empty = VoxelSlot {
        key: EMPTY_VOXEL,
        sum: Vec3::zeros(),
        count: 0,
    };
    let mut out = vec![empty; 2 * slots.len()];
    for s in slots.iter().filter(|s| s.key != EMPTY_VOXEL) {
        let slot = voxel_slot(&out, s.key);
        out[slot] = *s;
    }
    out
}

/// Moves each point `offset` metres farther along its viewing ray. A camera
/// sees a rope's front surface; its centre line lies on average
/// [`SURFACE_TO_AXIS_RATIO`] times the radius behind it.
pub fn push_along_rays(points: &mut [Vec3], offset: f64) {
    if offset == 0.0 {
        return;
    }
    for p in points.iter_mut() {
        let n = math::norm(p);
        if n > math::LENGTH_EPSILON {
            *p += *p * (offset / n);
        }
    }
}

/// Thins `points` to at most `max` by keeping every k-th point.
pub fn cap_points(points: Vec<Vec3>, max: usize) -> Vec<Vec3> {
    if points.len() <= max || max == 0 {
        return points;
    }
    let stride = points.len().div_ceil(max);
    points.into_iter().step_by(stride).collect()
}

/// The whole stage: deprojection, downsampling, surface-to-axis offset, cap.
pub fn build_cloud(
    frame: &Frame<'_>,
    mask: &Mask,
    camera: &CameraIntrinsics,
    settings: &CloudSettings,
) -> Vec<Vec3> {
    let raw = deproject_mask(frame, mask, camera, settings);
    let mut cloud = voxel_downsample(&raw, settings.voxel_size);
    push_along_rays(&mut cloud, settings.axis_offset);
    cap_points(cloud, MAX_CLOUD_POINTS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn voxel_downsample_averages_points_in_one_cube() {
        let pts = vec![
            Vec3::new(0.001, 0.001, 0.001),
            Vec3::new(0.003, 0.003, 0.003),
            Vec3::new(0.011, 0.0, 0.0),
            Vec3::new(f64::NAN, 0.0, 0.0),
        ];
        let out = voxel_downsample(&pts, 0.01);
        assert_eq!(out.len(), 2);
        assert!((out[0] - Vec3::new(0.002, 0.002, 0.002)).norm() < 1e-12);
        assert!((out[1] - Vec3::new(0.011, 0.0, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn voxel_downsample_does_not_depend_on_input_order() {
        let mut pts: Vec<Vec3> = (0..50)
            .map(|i| Vec3::new(i as f64 * 0.0013, (i % 7) as f64 * 0.002, 0.6))
            .collect();
        let a = voxel_downsample(&pts, 0.005);
        pts.reverse();
        let b = voxel_downsample(&pts, 0.005);
        assert_eq!(a.len(), b.len());
        for (p, q) in a.iter().zip(&b) {
            assert!((p - q).norm() < 1e-15);
        }
    }

    /// The growing hash table against a sorted map: the same voxels, the
    /// same centroids bit for bit (each voxel sums its points in input
    /// order either way), over clouds that make the table double many times.
    #[test]
    fn voxel_table_that_grows_gives_the_sorted_map_s_centroids() {
        let mut rng = crate::rng::SplitMix64::new(5);
        for (count, spread) in [(10usize, 0.02), (3000, 0.3), (20_000, 1.0)] {
            let pts: Vec<Vec3> = (0..count)
                .map(|_| {
                    Vec3::new(
                        rng.range(-spread, spread),
                        rng.range(-spread, spread),
                        rng.range(0.3, 0.3 + spread),
                    )
                })
                .collect();
            let leaf = 0.008;
            let mut reference: alloc::collections::BTreeMap<[i64; 3], (Vec3, u32)> =
                alloc::collections::BTreeMap::new();
            for p in &pts {
                let key = [p.x, p.y, p.z].map(|c| math::floor(c * (1.0 / leaf)) as i64);
                let e = reference.entry(key).or_insert((Vec3::zeros(), 0));
                e.0 += p;
                e.1 += 1;
            }
            let want: Vec<Vec3> = reference.values().map(|(s, n)| s / *n as f64).collect();
            let got = voxel_downsample(&pts, leaf);
            assert_eq!(got.len(), want.len(), "{count} points");
            for (g, w) in got.iter().zip(&want) {
                assert_eq!(g, w);
            }
        }
    }

    #[test]
    fn floor_to_i64_is_floor() {
        for x in [
            -2.5,
            -2.0,
            -1e-300,
            -0.0,
            0.0,
            0.3,
            1.0,
            7.999_999_999,
            1e15 + 0.5,
            -1e15 - 0.5,
        ] {
            assert_eq!(floor_to_i64(x), math::floor(x) as i64, "{x}");
        }
        assert_eq!(floor_to_i64(1e300), i64::MAX);
        assert_eq!(floor_to_i64(-1e300), i64::MIN);
    }

    #[test]
    fn push_along_rays_moves_points_away_from_the_camera() {
        let mut pts = vec![Vec3::new(0.0, 0.0, 0.6), Vec3::new(0.3, 0.4, 0.0)];
        push_along_rays(&mut pts, 0.01);
        assert!((pts[0].z - 0.61).abs() < 1e-12);
        assert!((pts[1] - Vec3::new(0.306, 0.408, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn depth_outside_the_valid_range_is_ignored() {
        let color = [0u8; 9];
        let depth = [0u16, 600, 9000];
        let f = Frame::new(3, 1, &color, &depth, 0.001).expect("frame");
        let s = CloudSettings {
            min_depth: 0.1,
            max_depth: 3.0,
            voxel_size: 0.0,
            axis_offset: 0.0,
        };
        let mask = Mask {
            width: 3,
            height: 1,
            data: vec![true; 3],
        };
        let cam = CameraIntrinsics {
            width: 3,
            height: 1,
            fx: 1.0,
            fy: 1.0,
            cx: 1.0,
            cy: 0.0,
        };
        let pts = build_cloud(&f, &mask, &cam, &s);
        assert_eq!(pts.len(), 1);
        assert!((pts[0] - Vec3::new(0.0, 0.0, 0.6)).norm() < 1e-12);
    }

    #[test]
    fn cap_points_bounds_the_cloud() {
        let pts = vec![Vec3::zeros(); 45_001];
        assert!(cap_points(pts, MAX_CLOUD_POINTS).len() <= MAX_CLOUD_POINTS);
    }
}
