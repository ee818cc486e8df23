//! Initialisation without a learned model: the rope's centre line from the
//! mask (largest blob, thinned to a skeleton, longest path through it,
//! extended to the blob's ends), lifted to 3D with the depth image, and M
//! nodes placed evenly along it by arc length.

use alloc::collections::VecDeque;
use alloc::vec;
use alloc::vec::Vec;

use super::camera::CameraIntrinsics;
use super::frame::Frame;
use super::point_cloud::{depth_at, push_along_rays, CloudSettings, SURFACE_TO_AXIS_RATIO};
use super::segmentation::Mask;
use crate::math::{Vec2, Vec3};
use crate::polyline::{polyline_length, resample_uniform};

/// Fewest pixels on a centre line worth initialising from.
pub const MIN_CENTRE_LINE_PIXELS: usize = 8;
/// Pixels back from a skeleton end used for the direction of its extension.
const END_DIRECTION_PIXELS: usize = 8;
/// Longest extension of a skeleton end towards the blob's boundary, pixels.
const MAX_END_EXTENSION: usize = 60;
/// Half side of the window searched for depth around a centre-line pixel.
const DEPTH_WINDOW_RADIUS: i64 = 3;
/// Half width (in path samples) of the moving average smoothing the 3D line.
const SMOOTHING_HALF_WINDOW: usize = 4;

/// Why no centre line could be found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InitError {
    /// No blob of the mask is large enough to be the rope.
    #[error("no rope in view: largest blob has {largest} pixels, at least {min} needed")]
    NoRope {
        /// Pixels in the largest blob.
        largest: usize,
        /// The `min_blob_pixels` parameter.
        min: u32,
    },
    /// The centre line found is too short.
    #[error("centre line too short: {pixels} pixels")]
    TooShort {
        /// Pixels on it.
        pixels: usize,
    },
    /// No valid depth anywhere along the centre line.
    #[error("no valid depth along the rope's centre line")]
    NoDepth,
}

/// The pixels of the largest 8-connected blob of `mask`.
pub fn largest_blob(mask: &Mask) -> Vec<usize> {
    let (w, h) = (mask.width as i64, mask.height as i64);
    let mut seen = vec![false; mask.data.len()];
    let mut best: Vec<usize> = Vec::new();
    let mut stack = Vec::new();
    for start in 0..mask.data.len() {
        if !mask.data[start] || seen[start] {
            continue;
        }
        let mut blob = Vec::new();
        seen[start] = true;
        stack.push(start);
        while let Some(i) = stack.pop() {
            blob.push(i);
            let (u, v) = ((i as i64) % w, (i as i64) / w);
            for dv in -1..=1 {
                for du in -1..=1 {
                    let (nu, nv) = (u + du, v + dv);
                    if nu < 0 || nv < 0 || nu >= w || nv >= h {
                        continue;
                    }
                    let j = (nv * w + nu) as usize;
                    if mask.data[j] && !seen[j] {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
        }
        if blob.len() > best.len() {
            best = blob;
        }
    }
    best.sort_unstable();
    best
}

/// A binary grid cropped around a blob, with a one-pixel empty border.
struct Grid {
    w: usize,
    /// Image coordinates of grid cell (0, 0).
    u0: i64,
    v0: i64,
    cells: Vec<bool>,
}

impl Grid {
    fn around(pixels: &[usize], image_width: u32) -> Self {
        let w_img = image_width as usize;
        let (mut umin, mut vmin, mut umax, mut vmax) = (usize::MAX, usize::MAX, 0, 0);
        for &i in pixels {
            let (u, v) = (i % w_img, i / w_img);
            umin = umin.min(u);
            umax = umax.max(u);
            vmin = vmin.min(v);
            vmax = vmax.max(v);
        }
        let (w, h) = (umax - umin + 3, vmax - vmin + 3);
        let mut cells = vec![false; w * h];
        for &i in pixels {
            let (u, v) = (i % w_img, i / w_img);
            cells[(v - vmin + 1) * w + (u - umin + 1)] = true;
        }
        Self {
            w,
            u0: umin as i64 - 1,
            v0: vmin as i64 - 1,
            cells,
        }
    }

    /// The eight neighbours P2..P9 of cell `i` (N, NE, E, SE, S, SW, W, NW).
    fn ring(&self, i: usize) -> [usize; 8] {
        let w = self.w;
        [
            i - w,
            i - w + 1,
            i + 1,
            i + w + 1,
            i + w,
            i + w - 1,
            i - 1,
            i - w - 1,
        ]
    }

    /// Zhang-Suen thinning to a one-pixel-wide skeleton.
    fn thin(&mut self) {
        let mut live: Vec<usize> = (0..self.cells.len()).filter(|&i| self.cells[i]).collect();
        let mut remove = Vec::new();
        loop {
            let mut changed = false;
            for pass in 0..2 {
                remove.clear();
                for &i in &live {
                    let p = self.ring(i).map(|j| self.cells[j]);
                    let b = p.iter().filter(|&&x| x).count();
                    if !(2..=6).contains(&b) {
                        continue;
                    }
                    let a = (0..8).filter(|&k| !p[k] && p[(k + 1) % 8]).count();
                    if a != 1 {
                        continue;
                    }
                    let (n, e, s, wst) = (p[0], p[2], p[4], p[6]);
                    // Zhang-Suen: first pass P2.P4.P6 = 0 and P4.P6.P8 = 0,
                    // second pass P2.P4.P8 = 0 and P2.P6.P8 = 0.
                    let ok = if pass == 0 {
                        !(e && s && (n || wst))
                    } else {
                        !(n && wst && (e || s))
                    };
                    if ok {
                        remove.push(i);
                    }
                }
                for &i in &remove {
                    self.cells[i] = false;
                }
                changed |= !remove.is_empty();
                live.retain(|&i| self.cells[i]);
            }
            if !changed {
                break;
            }
        }
    }

    /// Breadth-first distances (in steps) from `start` over set cells, with
    /// each cell's parent; returns the farthest cell.
    fn bfs(&self, start: usize, parent: &mut [usize]) -> usize {
        let mut dist = vec![usize::MAX; self.cells.len()];
        let mut queue = VecDeque::new();
        dist[start] = 0;
        parent[start] = start;
        queue.push_back(start);
        let mut far = start;
        while let Some(i) = queue.pop_front() {
            if dist[i] > dist[far] {
                far = i;
            }
            for j in self.ring(i) {
                if self.cells[j] && dist[j] == usize::MAX {
                    dist[j] = dist[i] + 1;
                    parent[j] = i;
                    queue.push_back(j);
                }
            }
        }
        far
    }

    fn to_image(&self, i: usize) -> Vec2 {
        Vec2::new(
            (self.u0 + (i % self.w) as i64) as f64,
            (self.v0 + (i / self.w) as i64) as f64,
        )
    }
}

/// Extends the path past its last point along its end direction while the
/// blob continues (the skeleton stops about half a width short of the tip).
fn extend_end(path: &mut Vec<Vec2>, blob: &Mask) {
    let n = path.len();
    if n < 2 {
        return;
    }
    let end = path[n - 1];
    let back = path[n - 1 - END_DIRECTION_PIXELS.min(n - 1)];
    let dir = end - back;
    let len = dir.norm();
    if len < 1e-9 {
        return;
    }
    let dir = dir / len;
    for k in 1..=MAX_END_EXTENSION {
        let p = end + dir * k as f64;
        if !blob.get(libm::round(p.x) as i64, libm::round(p.y) as i64) {
            break;
        }
        path.push(p);
    }
}

/// The rope's centre line in the image: an ordered list of pixel positions
/// from one end of the largest blob to the other. The end with the smaller
/// x (then smaller y) comes first.
pub fn find_centre_line(mask: &Mask, min_blob_pixels: u32) -> Result<Vec<Vec2>, InitError> {
    centre_line_of_largest_blob(mask, min_blob_pixels).map(|(path, _)| path)
}

/// [`find_centre_line`] with the number of pixels of the blob it runs through.
fn centre_line_of_largest_blob(
    mask: &Mask,
    min_blob_pixels: u32,
) -> Result<(Vec<Vec2>, usize), InitError> {
    let blob = largest_blob(mask);
    if blob.len() < min_blob_pixels.max(1) as usize {
        return Err(InitError::NoRope {
            largest: blob.len(),
            min: min_blob_pixels,
        });
    }
    let mut blob_mask = Mask::new(mask.width, mask.height);
    for &i in &blob {
        blob_mask.data[i] = true;
    }
    let mut grid = Grid::around(&blob, mask.width);
    grid.thin();
    let Some(start) = (0..grid.cells.len()).find(|&i| grid.cells[i]) else {
        return Err(InitError::TooShort { pixels: 0 });
    };
    let mut parent = vec![usize::MAX; grid.cells.len()];
    let a = grid.bfs(start, &mut parent);
    parent.fill(usize::MAX);
    let b = grid.bfs(a, &mut parent);
    let mut path = Vec::new();
    let mut i = b;
    loop {
        path.push(grid.to_image(i));
        if i == a {
            break;
        }
        i = parent[i];
    }
    extend_end(&mut path, &blob_mask);
    path.reverse();
    extend_end(&mut path, &blob_mask);
    if path.len() < MIN_CENTRE_LINE_PIXELS {
        return Err(InitError::TooShort { pixels: path.len() });
    }
    let (first, last) = (path[0], path[path.len() - 1]);
    if (last.x, last.y) < (first.x, first.y) {
        path.reverse();
    }
    Ok((path, blob.len()))
}

/// Lifts an image centre line to 3D: the median valid depth of rope pixels
/// around each point (gaps filled from the nearest points with depth),
/// deprojected, moved from the surface to the axis, and smoothed.
pub fn lift_to_3d(
    path: &[Vec2],
    frame: &Frame<'_>,
    mask: &Mask,
    camera: &CameraIntrinsics,
    settings: &CloudSettings,
) -> Result<Vec<Vec3>, InitError> {
    let width = frame.width as i64;
    let mut depths: Vec<Option<f64>> = Vec::with_capacity(path.len());
    let mut window = Vec::new();
    for p in path {
        let (u, v) = (libm::round(p.x) as i64, libm::round(p.y) as i64);
        window.clear();
        for dv in -DEPTH_WINDOW_RADIUS..=DEPTH_WINDOW_RADIUS {
            for du in -DEPTH_WINDOW_RADIUS..=DEPTH_WINDOW_RADIUS {
                if mask.get(u + du, v + dv) {
                    let i = ((v + dv) * width + (u + du)) as usize;
                    if let Some(z) = depth_at(frame, i, settings) {
                        window.push(z);
                    }
                }
            }
        }
        depths.push(if window.is_empty() {
            None
        } else {
            window.sort_unstable_by(f64::total_cmp);
            Some(window[window.len() / 2])
        });
    }
    fill_gaps(&mut depths).ok_or(InitError::NoDepth)?;
    let mut pts: Vec<Vec3> = path
        .iter()
        .zip(&depths)
        .map(|(p, z)| camera.deproject(p.x, p.y, z.unwrap_or(0.0)))
        .collect();
    push_along_rays(&mut pts, settings.axis_offset);
    Ok(smooth(&pts, SMOOTHING_HALF_WINDOW))
}

/// Fills `None` entries by linear interpolation between the nearest known
/// neighbours (constant beyond the ends). `None` when nothing is known.
fn fill_gaps(values: &mut [Option<f64>]) -> Option<()> {
    let known: Vec<usize> = (0..values.len()).filter(|&i| values[i].is_some()).collect();
    let (&first, &last) = (known.first()?, known.last()?);
    let (vf, vl) = (values[first]?, values[last]?);
    for v in values[..first].iter_mut() {
        *v = Some(vf);
    }
    for v in values[last + 1..].iter_mut() {
        *v = Some(vl);
    }
    for pair in known.windows(2) {
        let (i, j) = (pair[0], pair[1]);
        let (a, b) = (values[i]?, values[j]?);
        for (k, v) in values.iter_mut().enumerate().take(j).skip(i + 1) {
            let t = (k - i) as f64 / (j - i) as f64;
            *v = Some(a + (b - a) * t);
        }
    }
    Some(())
}

/// Centred moving average whose window shrinks near the ends, so both end
/// points stay where they are.
fn smooth(points: &[Vec3], half: usize) -> Vec<Vec3> {
    let n = points.len();
    (0..n)
        .map(|i| {
            let h = half.min(i).min(n - 1 - i);
            let sum: Vec3 = points[i - h..=i + h].iter().sum();
            sum / (2 * h + 1) as f64
        })
        .collect()
}

/// A fresh set of nodes for the rope in this frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Initialisation {
    /// `M` nodes evenly spaced along the centre line.
    pub nodes: Vec<Vec3>,
    /// Length of the centre line, metres.
    pub length: f64,
    /// The rope's radius estimated from its width in the image, metres
    /// (`None` when not asked for or not measurable).
    pub radius: Option<f64>,
}

/// Smallest radius an estimate may give, metres (a thread).
pub const MIN_ESTIMATED_RADIUS: f64 = 0.0005;
/// Largest radius an estimate may give, metres (a hose).
pub const MAX_ESTIMATED_RADIUS: f64 = 0.05;

/// The rope's radius from its blob: the mean width in pixels (blob pixels
/// over the centre line's length in pixels) at the median depth of the
/// centre line, `r = w z / (2 f)`. `None` outside the plausible range.
pub fn estimate_radius(
    blob_pixels: usize,
    path: &[Vec2],
    line: &[Vec3],
    camera: &CameraIntrinsics,
) -> Option<f64> {
    let length_px: f64 = path.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    if !(length_px > 0.0) || line.is_empty() {
        return None;
    }
    let mut z: Vec<f64> = line.iter().map(|p| p.z).filter(|z| z.is_finite()).collect();
    if z.is_empty() {
        return None;
    }
    z.sort_by(f64::total_cmp);
    let width_px = blob_pixels as f64 / length_px;
    let r = 0.5 * width_px * z[z.len() / 2] / (0.5 * (camera.fx + camera.fy));
    (MIN_ESTIMATED_RADIUS..=MAX_ESTIMATED_RADIUS)
        .contains(&r)
        .then_some(r)
}

/// What initialisation needs from the parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InitSettings {
    /// Nodes to place (`M`).
    pub node_count: usize,
    /// Smallest blob of mask pixels taken as the rope.
    pub min_blob_pixels: u32,
    /// Depth range and the surface-to-axis push of the 3D lift.
    pub cloud: CloudSettings,
    /// Estimate the radius from the image and push the line by it instead
    /// of by `cloud.axis_offset`.
    pub estimate_radius: bool,
}

/// The whole stage: centre line, 3D lift, even placement of `M` nodes.
pub fn initialise(
    frame: &Frame<'_>,
    mask: &Mask,
    camera: &CameraIntrinsics,
    settings: &InitSettings,
) -> Result<Initialisation, InitError> {
    let (path, blob_pixels) = centre_line_of_largest_blob(mask, settings.min_blob_pixels)?;
    let mut line = lift_to_3d(&path, frame, mask, camera, &settings.cloud)?;
    let mut radius = None;
    if settings.estimate_radius {
        radius = estimate_radius(blob_pixels, &path, &line, camera);
        if let Some(r) = radius {
            // Lift again, pushed to the axis of a rope of this radius.
            let cloud = CloudSettings {
                axis_offset: r * SURFACE_TO_AXIS_RATIO,
                ..settings.cloud
            };
            line = lift_to_3d(&path, frame, mask, camera, &cloud)?;
        }
    }
    let length = polyline_length(&line);
    if !(length > 0.0) || !length.is_finite() {
        return Err(InitError::TooShort { pixels: path.len() });
    }
    Ok(Initialisation {
        nodes: resample_uniform(&line, settings.node_count),
        length,
        radius,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Draws a thick polyline (disc brush) into a mask.
    fn draw(mask: &mut Mask, curve: &[Vec2], radius: f64) {
        for w in curve.windows(2) {
            let steps = ((w[1] - w[0]).norm() * 2.0) as usize + 1;
            for s in 0..=steps {
                let p = w[0] + (w[1] - w[0]) * (s as f64 / steps as f64);
                let r = radius as i64 + 1;
                for dv in -r..=r {
                    for du in -r..=r {
                        let (u, v) = (libm::round(p.x) as i64 + du, libm::round(p.y) as i64 + dv);
                        let q = Vec2::new(u as f64, v as f64);
                        let inside =
                            u >= 0 && v >= 0 && u < mask.width as i64 && v < mask.height as i64;
                        if inside && (q - p).norm() <= radius {
                            mask.data[(v * mask.width as i64 + u) as usize] = true;
                        }
                    }
                }
            }
        }
    }

    fn curve(f: impl Fn(f64) -> Vec2) -> Vec<Vec2> {
        (0..=400).map(|i| f(i as f64 / 400.0)).collect()
    }

    /// Checks that `line` runs from one end of `truth` to the other, in order.
    fn assert_follows(line: &[Vec2], truth: &[Vec2], tol: f64) {
        let (a, b) = (truth[0], truth[truth.len() - 1]);
        let (s, e) = (line[0], line[line.len() - 1]);
        let direct = (s - a).norm().max((e - b).norm());
        let swapped = (s - b).norm().max((e - a).norm());
        assert!(direct.min(swapped) < tol, "ends {s:?} {e:?} vs {a:?} {b:?}");
        let truth: Vec<Vec2> = if direct <= swapped {
            truth.to_vec()
        } else {
            truth.iter().rev().copied().collect()
        };
        // Each line point lies on the curve, and the index of its nearest
        // truth sample never goes back by more than a rope width.
        let mut last = 0usize;
        for p in line {
            let (k, d) = truth
                .iter()
                .enumerate()
                .map(|(k, q)| (k, (p - q).norm()))
                .fold((0, f64::MAX), |best, x| if x.1 < best.1 { x } else { best });
            assert!(d < tol, "point {p:?} is {d} px off the curve");
            assert!(k + 10 >= last, "order goes back at {p:?}");
            last = last.max(k);
        }
    }

    #[test]
    fn straight_u_and_s_shapes_with_noise_blobs() {
        let shapes: [Vec<Vec2>; 3] = [
            curve(|t| Vec2::new(60.0 + 500.0 * t, 240.0 + 30.0 * t)),
            curve(|t| {
                let a = core::f64::consts::PI * t;
                Vec2::new(
                    320.0 + 150.0 * libm::sin(a) - 100.0 * (1.0 - t),
                    240.0 - 150.0 * libm::cos(a),
                )
            }),
            curve(|t| {
                let a = core::f64::consts::TAU * t;
                Vec2::new(100.0 + 440.0 * t, 240.0 + 120.0 * libm::sin(a))
            }),
        ];
        for shape in &shapes {
            let mut mask = Mask::new(640, 480);
            draw(&mut mask, shape, 7.0);
            // Noise: small blobs that must be ignored.
            draw(
                &mut mask,
                &[Vec2::new(20.0, 20.0), Vec2::new(24.0, 22.0)],
                3.0,
            );
            draw(
                &mut mask,
                &[Vec2::new(600.0, 450.0), Vec2::new(601.0, 450.0)],
                4.0,
            );
            let line = find_centre_line(&mask, 150).expect("centre line");
            // The blob, drawn with a disc, reaches one radius past the curve's ends.
            assert_follows(&line, shape, 9.0);
        }
    }

    #[test]
    fn empty_and_tiny_masks_are_errors() {
        let mask = Mask::new(64, 48);
        assert!(matches!(
            find_centre_line(&mask, 10),
            Err(InitError::NoRope { largest: 0, .. })
        ));
        let mut mask = Mask::new(64, 48);
        mask.data[100] = true;
        assert!(matches!(
            find_centre_line(&mask, 1),
            Err(InitError::TooShort { .. })
        ));
    }

    #[test]
    fn gaps_in_depth_are_interpolated() {
        let mut v = [None, Some(1.0), None, None, Some(4.0), None];
        fill_gaps(&mut v).expect("some known");
        assert_eq!(
            v,
            [
                Some(1.0),
                Some(1.0),
                Some(2.0),
                Some(3.0),
                Some(4.0),
                Some(4.0)
            ]
        );
        assert!(fill_gaps(&mut [None, None]).is_none());
    }
}
