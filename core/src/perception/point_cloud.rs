//! The point cloud of one frame: masked pixels with valid depth, deprojected,
//! downsampled (in columns along the viewing rays, or on a voxel grid), and
//! moved from the rope's surface to its axis.

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
    /// How the cloud is downsampled.
    pub downsampling: Downsampling,
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

/// The median of what `value(x, y)` gives over the pixels within `half`
/// of `(u, v)` (a square window), `None` where it gives nothing; the
/// values are gathered in `scratch`, cleared first.
pub fn median_around(
    (u, v): (i64, i64),
    half: i64,
    scratch: &mut Vec<f64>,
    value: impl Fn(i64, i64) -> Option<f64>,
) -> Option<f64> {
    scratch.clear();
    for y in v - half..=v + half {
        scratch.extend((u - half..=u + half).filter_map(|x| value(x, y)));
    }
    scratch.sort_unstable_by(f64::total_cmp);
    scratch.get(scratch.len() / 2).copied()
}

/// Deprojects every masked pixel with a valid depth.
pub fn deproject_mask(
    frame: &Frame<'_>,
    mask: &Mask,
    camera: &CameraIntrinsics,
    settings: &CloudSettings,
) -> Vec<Vec3> {
    let mut points = Vec::new();
    for_each_masked_depth(frame, mask, settings, |u, v, z| {
        points.push(camera.deproject(u as f64, v as f64, z));
    });
    points
}

/// Calls `visit(u, v, z)` for every masked pixel with a valid depth, row by
/// row.
fn for_each_masked_depth(
    frame: &Frame<'_>,
    mask: &Mask,
    settings: &CloudSettings,
    mut visit: impl FnMut(usize, usize, f64),
) {
    let width = frame.width as usize;
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
                    visit(u, v, z);
                }
            }
        }
    }
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

/// Slot key of an empty slot (no cell key reaches it: keys use 63 bits).
const EMPTY_CELL: u64 = u64::MAX;

/// Smallest cell table; it doubles whenever it is half full.
const MIN_CELL_SLOTS: usize = 64;

/// Cells (voxels, ray columns) met in a cloud, each given a dense index in
/// the order first met: an open-addressing table, at most half full, that
/// starts small and doubles (a rope's cloud has far fewer cells than points).
struct CellIndex {
    /// `(key, dense index)`, or `(EMPTY_CELL, _)`.
    slots: Vec<(u64, u32)>,
    /// Every key met, by dense index.
    keys: Vec<u64>,
}

impl CellIndex {
    fn new() -> Self {
        Self {
            slots: vec![(EMPTY_CELL, 0); MIN_CELL_SLOTS],
            keys: Vec::new(),
        }
    }

    /// The dense index of `key`, given the next one if it is new.
    fn index_of(&mut self, key: u64) -> usize {
        if 2 * (self.keys.len() + 1) > self.slots.len() {
            let mut grown = vec![(EMPTY_CELL, 0); 2 * self.slots.len()];
            for &(k, i) in self.slots.iter().filter(|s| s.0 != EMPTY_CELL) {
                let at = cell_slot(&grown, k);
                grown[at] = (k, i);
            }
            self.slots = grown;
        }
        let at = cell_slot(&self.slots, key);
        if self.slots[at].0 == EMPTY_CELL {
            self.slots[at] = (key, self.keys.len() as u32);
            self.keys.push(key);
        }
        self.slots[at].1 as usize
    }

    /// Dense indices ordered by key, so that what is built from them does
    /// not depend on the order the points came in.
    fn by_key(&self) -> Vec<usize> {
        let mut order: Vec<usize> = (0..self.keys.len()).collect();
        order.sort_unstable_by_key(|&i| self.keys[i]);
        order
    }
}

/// The slot holding `key`, or the empty one where it goes (the table has a
/// power-of-two length and at least one empty slot).
fn cell_slot(slots: &[(u64, u32)], key: u64) -> usize {
    let mask = slots.len() - 1;
    let shift = 64 - slots.len().trailing_zeros();
    let mut slot = (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> shift) as usize;
    while slots[slot].0 != EMPTY_CELL && slots[slot].0 != key {
        slot = (slot + 1) & mask;
    }
    slot
}

/// The key of the cell with integer coordinates `idx`, or `None` beyond
/// [`MAX_VOXEL_INDEX`].
fn cell_key(idx: [i64; 3]) -> Option<u64> {
    if idx.iter().any(|k| k.abs() >= MAX_VOXEL_INDEX) {
        return None;
    }
    Some(
        idx.iter()
            .fold(0u64, |acc, &k| (acc << 21) | (k + MAX_VOXEL_INDEX) as u64),
    )
}

/// Voxel-grid downsampling: one point, the centroid, per occupied cube of
/// side `leaf`. The output is ordered by voxel index, so it does not depend
/// on the input order. Non-finite points are dropped.
pub fn voxel_downsample(points: &[Vec3], leaf: f64) -> Vec<Vec3> {
    if !(leaf > 0.0 && leaf.is_finite()) {
        return points.iter().copied().filter(math::is_finite).collect();
    }
    let mut cells = CellIndex::new();
    let mut sums: Vec<(Vec3, u32)> = Vec::new();
    let inv = 1.0 / leaf;
    for p in points.iter().filter(|p| math::is_finite(p)) {
        let Some(key) = cell_key([p.x, p.y, p.z].map(|c| floor_to_i64(c * inv))) else {
            continue;
        };
        let i = cells.index_of(key);
        if i == sums.len() {
            sums.push((Vec3::zeros(), 0));
        }
        sums[i].0 += p;
        sums[i].1 += 1;
    }
    cells
        .by_key()
        .into_iter()
        .map(|i| sums[i].0 / sums[i].1 as f64)
        .collect()
}

/// Width of a ray column as a fraction of the voxel leaf, at the cloud's
/// mean depth. Chosen on the tuning subset (`docs/algorithm-notes.md`).
pub const COLUMN_WIDTH_RATIO: f64 = 0.5;

/// A ray column's points, sorted by depth, are split where the depth jumps
/// by more than this multiple of the leaf: another layer (the rope crossing
/// itself, what lies behind a thick rope). Smaller jumps happen inside one
/// rope's surface, between its steep and noisy silhouette pixels, and
/// splitting there brings the voxel grid's bias back (chosen on the tuning
/// subset, `docs/algorithm-notes.md`).
pub const COLUMN_GAP_RATIO: f64 = 2.0;

/// Deepest span of one ray column's cluster, as a multiple of the leaf: a
/// rope seen end-on still gives one point per few leaves (chosen on the
/// tuning subset, `docs/algorithm-notes.md`).
pub const COLUMN_SPAN_RATIO: f64 = 3.0;

/// The cloud's downsampling.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Downsampling {
    /// Each algorithm's own: ray columns for UPETrack, the voxel grid for
    /// the baselines, as their published pipelines downsample (resolved by
    /// `Params::cloud`; in [`CloudSettings`] it means ray columns).
    #[default]
    Auto,
    /// Cubes of the voxel leaf (PCL's voxel grid, as TrackDLO and CDCPD
    /// use it). Cubes cut by the silhouette hold only the rope's far side
    /// and count as much as full ones: the cloud lies deeper than the
    /// rope's surface does on average (about 1-2 mm at 8 mm leaves).
    VoxelGrid,
    /// Columns along the viewing rays, [`COLUMN_WIDTH_RATIO`] of a leaf
    /// wide, each split along its depth at gaps ([`ray_column_downsample`]):
    /// every point is the mean depth of the pixels it stands for.
    RayColumns,
}

/// Ray-column downsampling: the points are binned by viewing direction in
/// square columns `COLUMN_WIDTH_RATIO * leaf` wide at the cloud's mean
/// depth; a column's points, in depth order, are split where the depth jumps
/// by more than `COLUMN_GAP_RATIO * leaf` (another layer) or the cluster would span more
/// than `COLUMN_SPAN_RATIO * leaf`; each cluster gives its centroid. Ordered
/// by column and depth, so independent of the input order. Non-finite points
/// and points not in front of the camera are dropped.
pub fn ray_column_downsample(points: &[Vec3], leaf: f64) -> Vec<Vec3> {
    let usable = |p: &Vec3| math::is_finite(p) && p.z > 0.0;
    if !(leaf > 0.0 && leaf.is_finite()) {
        return points.iter().copied().filter(usable).collect();
    }
    let (mut depth_sum, mut n) = (0.0, 0usize);
    for p in points.iter().filter(|p| usable(p)) {
        depth_sum += p.z;
        n += 1;
    }
    if n == 0 {
        return Vec::new();
    }
    let inv = depth_sum / (n as f64 * COLUMN_WIDTH_RATIO * leaf);
    let at: Vec<Option<(i64, i64)>> = points
        .iter()
        .map(|p| {
            usable(p)
                .then(|| {
                    let scale = inv / p.z;
                    (floor_to_i64(p.x * scale), floor_to_i64(p.y * scale))
                })
                .filter(|(x, y)| x.abs() < MAX_VOXEL_INDEX && y.abs() < MAX_VOXEL_INDEX)
        })
        .collect();
    summed_columns(points, &at, n, leaf)
}

/// Ray columns straight from the mask, as [`ray_column_downsample`] makes
/// them from its deprojected points: a pixel's viewing ray, hence its
/// column, depends on the pixel alone, so each image column and row gives
/// its column index once instead of every point dividing by its depth.
pub fn ray_columns_from_mask(
    frame: &Frame<'_>,
    mask: &Mask,
    camera: &CameraIntrinsics,
    settings: &CloudSettings,
) -> Vec<Vec3> {
    let leaf = settings.voxel_size;
    if !(leaf > 0.0 && leaf.is_finite()) {
        return deproject_mask(frame, mask, camera, settings);
    }
    let (mut points, mut pixels, mut depth_sum) = (Vec::new(), Vec::new(), 0.0);
    for_each_masked_depth(frame, mask, settings, |u, v, z| {
        points.push(camera.deproject(u as f64, v as f64, z));
        pixels.push((u as u32, v as u32));
        depth_sum += z;
    });
    if points.is_empty() {
        return Vec::new();
    }
    let n = points.len();
    let inv = depth_sum / (n as f64 * COLUMN_WIDTH_RATIO * leaf);
    let index = |offset: f64, focal: f64| {
        let k = floor_to_i64(offset / focal * inv);
        (k.abs() < MAX_VOXEL_INDEX).then_some(k)
    };
    let xs: Vec<Option<i64>> = (0..frame.width)
        .map(|u| index(u as f64 - camera.cx, camera.fx))
        .collect();
    let ys: Vec<Option<i64>> = (0..frame.height)
        .map(|v| index(v as f64 - camera.cy, camera.fy))
        .collect();
    let at: Vec<Option<(i64, i64)>> = pixels
        .iter()
        .map(|&(u, v)| Some((xs[u as usize]?, ys[v as usize]?)))
        .collect();
    summed_columns(&points, &at, n, leaf)
}

/// The ray columns' points: `points[i]` lies in column `at[i]` (`None`:
/// dropped); `n` points are usable, their mean depth set the columns.
fn summed_columns(points: &[Vec3], at: &[Option<(i64, i64)>], n: usize, leaf: f64) -> Vec<Vec3> {
    let (mut lo, mut hi) = ((i64::MAX, i64::MAX), (i64::MIN, i64::MIN));
    for &(x, y) in at.iter().flatten() {
        lo = (lo.0.min(x), lo.1.min(y));
        hi = (hi.0.max(x), hi.1.max(y));
    }
    if lo.0 > hi.0 {
        return Vec::new();
    }
    let (nx, ny) = ((hi.0 - lo.0 + 1) as u64, (hi.1 - lo.1 + 1) as u64);
    // Each column gets an id in the order first met, from a dense grid over
    // the bounding box when it is small against the cloud (a camera's
    // image), else from a table; its points are summed as they come.
    const NO_COLUMN: u32 = u32::MAX;
    let dense =
        nx.saturating_mul(ny) <= (DENSE_COLUMNS_PER_POINT * n as u64).max(MIN_DENSE_COLUMNS);
    let mut grid: Vec<u32> = if dense {
        vec![NO_COLUMN; (nx * ny) as usize]
    } else {
        Vec::new()
    };
    let mut cells = CellIndex::new();
    let mut columns: Vec<ColumnSum> = Vec::new();
    let column_of: Vec<u32> = points
        .iter()
        .zip(at)
        .map(|(p, column)| {
            let Some((x, y)) = *column else {
                return NO_COLUMN;
            };
            let id = if dense {
                let slot = &mut grid[((x - lo.0) as u64 * ny + (y - lo.1) as u64) as usize];
                if *slot == NO_COLUMN {
                    *slot = columns.len() as u32;
                }
                *slot as usize
            } else {
                // In range: checked above.
                cell_key([x, y, 0]).map_or(0, |key| cells.index_of(key))
            };
            if id == columns.len() {
                columns.push(ColumnSum::default());
            }
            columns[id].add(p);
            id as u32
        })
        .collect();
    let order: Vec<usize> = if dense {
        grid.iter()
            .filter(|&&id| id != NO_COLUMN)
            .map(|&id| id as usize)
            .collect()
    } else {
        cells.by_key()
    };
    // Within one gap and one span the walk would split nowhere: such a
    // column is its centroid. The few deeper ones (another layer behind,
    // a rope seen end-on) get their points back, in input order.
    let (gap, span) = (COLUMN_GAP_RATIO * leaf, COLUMN_SPAN_RATIO * leaf);
    let mut deep: Vec<Option<Vec<Vec3>>> = columns
        .iter()
        .map(|c| (c.zmax - c.zmin > gap.min(span)).then(Vec::new))
        .collect();
    if deep.iter().any(Option::is_some) {
        for (p, &id) in points.iter().zip(&column_of) {
            if let Some(Some(list)) = deep.get_mut(id as usize) {
                list.push(*p);
            }
        }
    }
    let mut out = Vec::with_capacity(order.len());
    for id in order {
        match &mut deep[id] {
            None => out.push(columns[id].sum / columns[id].count as f64),
            Some(column) => {
                column.sort_unstable_by(|a, b| a.z.total_cmp(&b.z));
                let mut first = 0;
                for k in 1..=column.len() {
                    let split = k == column.len()
                        || column[k].z - column[k - 1].z > gap
                        || column[k].z - column[first].z > span;
                    if split {
                        let cluster = &column[first..k];
                        let sum = cluster.iter().fold(Vec3::zeros(), |s, p| s + p);
                        out.push(sum / cluster.len() as f64);
                        first = k;
                    }
                }
            }
        }
    }
    out
}

/// One ray column's points as they are summed: their sum, count and depth
/// range.
struct ColumnSum {
    sum: Vec3,
    count: u32,
    zmin: f64,
    zmax: f64,
}

impl Default for ColumnSum {
    fn default() -> Self {
        Self {
            sum: Vec3::zeros(),
            count: 0,
            zmin: f64::INFINITY,
            zmax: f64::NEG_INFINITY,
        }
    }
}

impl ColumnSum {
    fn add(&mut self, p: &Vec3) {
        self.sum += p;
        self.count += 1;
        self.zmin = self.zmin.min(p.z);
        self.zmax = self.zmax.max(p.z);
    }
}

/// The column grid is dense (one id per column of the cloud's bounding
/// box) while it has at most this many columns per point (16 bytes a
/// point, less than the points themselves)...
const DENSE_COLUMNS_PER_POINT: u64 = 4;

/// ...or at most this many columns (a small cloud).
const MIN_DENSE_COLUMNS: u64 = 1 << 16;

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
    let mut cloud = match settings.downsampling {
        Downsampling::VoxelGrid => voxel_downsample(
            &deproject_mask(frame, mask, camera, settings),
            settings.voxel_size,
        ),
        Downsampling::RayColumns | Downsampling::Auto => {
            ray_columns_from_mask(frame, mask, camera, settings)
        }
    };
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

    /// `downsample` gives the same points for `pts` and for them reversed.
    fn assert_independent_of_order(
        mut pts: Vec<Vec3>,
        downsample: fn(&[Vec3], f64) -> Vec<Vec3>,
        leaf: f64,
    ) {
        let a = downsample(&pts, leaf);
        pts.reverse();
        let b = downsample(&pts, leaf);
        assert_eq!(a.len(), b.len());
        for (p, q) in a.iter().zip(&b) {
            assert!((p - q).norm() < 1e-15);
        }
    }

    #[test]
    fn voxel_downsample_does_not_depend_on_input_order() {
        let pts: Vec<Vec3> = (0..50)
            .map(|i| Vec3::new(i as f64 * 0.0013, (i % 7) as f64 * 0.002, 0.6))
            .collect();
        assert_independent_of_order(pts, voxel_downsample, 0.005);
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

    /// The visible surface of a 15 mm rope lying along x, its axis through
    /// `(0, y_axis, z_axis)`, seen by a 615 px camera: one point per pixel.
    fn rope_surface_pixels(y_axis: f64, z_axis: f64) -> Vec<Vec3> {
        let (f, r) = (615.0, 0.0075);
        let mut pts = Vec::new();
        for u in -100..100 {
            for v in -20..20 {
                // The pixel's ray (u/f, v/f, 1) against the cylinder
                // (y - y_axis)^2 + (z - z_axis)^2 = r^2, nearest hit.
                let (a, b) = (u as f64 / f, (v as f64 + 0.5) / f);
                let qa = b * b + 1.0;
                let qb = -2.0 * (b * y_axis + z_axis);
                let qc = y_axis * y_axis + z_axis * z_axis - r * r;
                let disc = qb * qb - 4.0 * qa * qc;
                if disc >= 0.0 {
                    let t = (-qb - libm::sqrt(disc)) / (2.0 * qa);
                    pts.push(Vec3::new(a * t, b * t, t));
                }
            }
        }
        pts
    }

    fn mean_depth(points: &[Vec3]) -> f64 {
        points.iter().map(|p| p.z).sum::<f64>() / points.len() as f64
    }

    #[test]
    fn ray_columns_keep_the_pixels_mean_depth_where_voxels_lose_it() {
        // Over ropes at eight places against the grid, as a moving rope is.
        let (mut col_bias, mut vox_bias) = (0.0, 0.0);
        for k in 0..8 {
            let pixels = rope_surface_pixels(0.001 * k as f64, 0.6 + 0.001 * k as f64);
            let want = mean_depth(&pixels);
            col_bias += (mean_depth(&ray_column_downsample(&pixels, 0.008)) - want) / 8.0;
            vox_bias += (mean_depth(&voxel_downsample(&pixels, 0.008)) - want) / 8.0;
        }
        // Measured: columns +0.53 mm (partial columns at the silhouette still
        // count as full points, on a smaller scale), voxels +1.01 mm.
        assert!(col_bias.abs() < 0.0007, "columns {col_bias} m");
        // Why the columns exist: cubes cut by the silhouette hold far points only.
        assert!(
            vox_bias > 0.0009 && vox_bias > 1.5 * col_bias,
            "voxels {vox_bias} m"
        );
    }

    #[test]
    fn ray_columns_split_where_depth_jumps_and_drop_bad_points() {
        // One column: the rope's surface 0.600-0.604 m, the rope again
        // where it crosses behind itself (0.622-0.623 m: a jump of 18 mm),
        // a flying point far behind, and points no ray can have.
        let mut pts: Vec<Vec3> = (0..9)
            .map(|i| Vec3::new(0.0001, 0.0001, 0.600 + 0.0005 * i as f64))
            .collect();
        pts.extend([0.622, 0.623].map(|z| Vec3::new(0.0001, 0.0001, z)));
        pts.push(Vec3::new(0.0001, 0.0001, 0.9));
        pts.extend([
            Vec3::new(f64::NAN, 0.0, 0.6),
            Vec3::new(0.0, 0.0, -0.6),
            Vec3::new(0.0, 0.0, 0.0),
        ]);
        let out = ray_column_downsample(&pts, 0.008);
        let depths: Vec<f64> = out.iter().map(|p| p.z).collect();
        assert_eq!(depths.len(), 3, "{depths:?}");
        assert!((depths[0] - 0.602).abs() < 1e-9);
        assert!((depths[1] - 0.6225).abs() < 1e-9);
        assert!((depths[2] - 0.9).abs() < 1e-9);
        // Jumps within one surface, 10 mm at most, are not split.
        let edge: Vec<Vec3> = [0.600, 0.601, 0.611, 0.612]
            .map(|z| Vec3::new(0.0001, 0.0001, z))
            .to_vec();
        assert_eq!(ray_column_downsample(&edge, 0.008).len(), 1);
        // A column that runs deep in small steps (a rope seen end-on) is cut
        // every COLUMN_SPAN_RATIO leaves.
        let end_on: Vec<Vec3> = (0..100)
            .map(|i| Vec3::new(0.0, 0.0, 0.6 + 0.001 * i as f64))
            .collect();
        let cut = ray_column_downsample(&end_on, 0.008);
        assert_eq!(cut.len(), 5, "{cut:?}");
        assert!(ray_column_downsample(&[], 0.008).is_empty());
    }

    #[test]
    fn a_column_deeper_than_a_gap_is_split_whatever_the_input_order() {
        // Two layers 20 mm apart in one column (more than the 16 mm gap of
        // 8 mm leaves, less than the 24 mm span), given out of depth order.
        let at = |z: f64| Vec3::new(0.0001, 0.0001, z);
        let pts = [0.620, 0.600, 0.621, 0.601].map(at).to_vec();
        let out = ray_column_downsample(&pts, 0.008);
        let depths: Vec<f64> = out.iter().map(|p| p.z).collect();
        assert_eq!(depths.len(), 2, "{depths:?}");
        assert!((depths[0] - 0.6005).abs() < 1e-12, "{depths:?}");
        assert!((depths[1] - 0.6205).abs() < 1e-12, "{depths:?}");
    }

    #[test]
    fn ray_columns_from_the_dense_grid_and_from_the_table_agree() {
        // A rope's pixels (a small box: the dense grid), and the same with
        // two far points that make the box too large for it (the table).
        let pixels = rope_surface_pixels(0.002, 0.6);
        let dense = ray_column_downsample(&pixels, 0.008);
        let mut spread = pixels.clone();
        spread.extend([Vec3::new(-500.0, -500.0, 0.6), Vec3::new(500.0, 500.0, 0.6)]);
        let table = ray_column_downsample(&spread, 0.008);
        assert_eq!(table.len(), dense.len() + 2);
        // The far points are the first and the last column in key order.
        assert_eq!(&table[1..table.len() - 1], &dense[..]);
    }

    #[test]
    fn ray_columns_do_not_depend_on_input_order() {
        assert_independent_of_order(
            rope_surface_pixels(0.003, 0.6),
            ray_column_downsample,
            0.008,
        );
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
            downsampling: Downsampling::default(),
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

    /// The columns made from the mask's pixels are those made from its
    /// deprojected points: a rope across a depth image at a slant, with
    /// a crossing layer behind it in some columns.
    #[test]
    fn ray_columns_from_the_mask_are_those_of_the_deprojected_points() {
        let (w, h) = (160u32, 120u32);
        let cam = CameraIntrinsics {
            width: w,
            height: h,
            fx: 150.0,
            fy: 183.0,
            cx: 79.3,
            cy: 60.6,
        };
        let color = vec![0u8; 3 * (w * h) as usize];
        let mut depth = vec![0u16; (w * h) as usize];
        let mut mask = Mask::new(w, h);
        for v in 0..h as usize {
            for u in 0..w as usize {
                let along = u as f64 * 0.4 + 20.0 - v as f64;
                if along.abs() < 4.0 {
                    let i = v * w as usize + u;
                    mask.data[i] = true;
                    // The rope nearer at its middle, a layer 60 mm behind
                    // on a few rows.
                    let behind = if (50..56).contains(&v) && u % 3 == 0 {
                        60
                    } else {
                        0
                    };
                    depth[i] = (600.0 + 2.0 * along * along + 0.1 * u as f64) as u16 + behind;
                }
            }
        }
        let f = Frame::new(w, h, &color, &depth, 0.001).expect("frame");
        let s = CloudSettings {
            min_depth: 0.1,
            max_depth: 3.0,
            voxel_size: 0.016,
            axis_offset: 0.0,
            downsampling: Downsampling::RayColumns,
        };
        let from_points = ray_column_downsample(&deproject_mask(&f, &mask, &cam, &s), s.voxel_size);
        let from_mask = ray_columns_from_mask(&f, &mask, &cam, &s);
        assert!(from_points.len() > 30, "{} columns", from_points.len());
        assert_eq!(from_mask, from_points);
    }

    #[test]
    fn cap_points_bounds_the_cloud() {
        // Points along x: what is kept must stay spread over the whole rope.
        let line =
            |n: usize| -> Vec<Vec3> { (0..n).map(|i| Vec3::new(i as f64, 0.0, 1.0)).collect() };
        let n = 3 * MAX_CLOUD_POINTS + 1;
        let kept = cap_points(line(n), MAX_CLOUD_POINTS);
        assert!(kept.len() <= MAX_CLOUD_POINTS && kept.len() >= MAX_CLOUD_POINTS / 2);
        assert_eq!(kept[0].x, 0.0);
        assert!(kept[kept.len() - 1].x >= (n - 5) as f64);
        // At the cap nothing is dropped.
        assert_eq!(
            cap_points(line(MAX_CLOUD_POINTS), MAX_CLOUD_POINTS).len(),
            MAX_CLOUD_POINTS
        );
    }
}
