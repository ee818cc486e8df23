//! The mask's shapes one by one: connected components, each cropped to a
//! grid with its distance transform (half the local width of the shape)
//! and its skeleton (Zhang-Suen thinning).

use alloc::vec;
use alloc::vec::Vec;

use super::runs::{distance_transform, fill_small_holes, set_cells};
use crate::math::Vec2;
use crate::perception::segmentation::Mask;

/// Most shapes of one mask examined, the largest first: a colour range that
/// selects thousands of specks (a textured table) costs a bounded amount.
pub const MAX_SHAPES: usize = 64;

/// Longest spur removed, in units of the largest disc at its junction
/// (a spur runs from the axis to the edge: about one disc).
pub const SPUR_DISCS: f64 = 1.5;
/// Most passes of spur removal.
const MAX_PRUNE_PASSES: usize = 8;
/// Most passes removing the simple cells Zhang-Suen leaves.
const MAX_SIMPLIFY_PASSES: usize = 16;

/// One 8-connected component of the mask.
#[derive(Debug, Clone)]
pub(super) struct Shape {
    /// Image indices of its pixels.
    pub pixels: Vec<usize>,
    /// Its label in the label image (1-based).
    pub label: u32,
}

impl Shape {
    /// Mean position of its pixels, image coordinates.
    pub fn centre(&self, image_width: u32) -> Vec2 {
        let w = image_width as usize;
        let n = self.pixels.len().max(1) as f64;
        let (su, sv) = self.pixels.iter().fold((0.0, 0.0), |(a, b), &i| {
            (a + (i % w) as f64, b + (i / w) as f64)
        });
        Vec2::new(su / n, sv / n)
    }
}

/// The mask's components of at least `min_pixels` pixels, largest first (at
/// most [`MAX_SHAPES`]), and an image of their labels (0 elsewhere).
pub(super) fn shapes(mask: &Mask, min_pixels: usize) -> (Vec<Shape>, Vec<u32>) {
    let (w, h) = (mask.width as i64, mask.height as i64);
    let mut label = vec![0u32; mask.data.len()];
    let mut found: Vec<Vec<usize>> = Vec::new();
    let mut stack = Vec::new();
    // Labels are provisional here (u32::MAX marks a visited pixel).
    let mut next = 0;
    // Jumps from set pixel to set pixel (the mask is mostly empty).
    while let Some(k) = mask.data[next..].iter().position(|&m| m) {
        let start = next + k;
        next = start + 1;
        if label[start] != 0 {
            continue;
        }
        let mut blob = Vec::new();
        label[start] = u32::MAX;
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
                    if mask.data[j] && label[j] == 0 {
                        label[j] = u32::MAX;
                        stack.push(j);
                    }
                }
            }
        }
        if blob.len() >= min_pixels.max(1) {
            found.push(blob);
        }
    }
    // Largest first; equal sizes by first pixel, so the order is the mask's.
    found.sort_by(|a, b| b.len().cmp(&a.len()).then(a[0].cmp(&b[0])));
    found.truncate(MAX_SHAPES);
    label.fill(0);
    let shapes = found
        .into_iter()
        .enumerate()
        .map(|(k, mut pixels)| {
            pixels.sort_unstable();
            for &i in &pixels {
                label[i] = k as u32 + 1;
            }
            Shape {
                pixels,
                label: k as u32 + 1,
            }
        })
        .collect();
    (shapes, label)
}

/// A binary grid cropped around a shape, with a one-cell empty border.
pub(super) struct Grid {
    /// Width in cells.
    pub w: usize,
    /// Height in cells.
    pub h: usize,
    /// Image coordinates of cell (0, 0).
    pub u0: i64,
    /// Image coordinates of cell (0, 0).
    pub v0: i64,
    /// Set cells: the shape, then its skeleton after [`Grid::thin`].
    pub cells: Vec<bool>,
    /// Distance from each cell of the shape to the nearest cell outside it,
    /// in cells (0 outside): the radius of the largest disc centred there.
    pub dist: Vec<f32>,
}

impl Grid {
    /// The grid of `pixels` (image indices) of an image `image_width` wide,
    /// with its distance transform.
    pub fn around(pixels: &[usize], image_width: u32) -> Self {
        let w_img = image_width as usize;
        let (mut umin, mut vmin, mut umax, mut vmax) = (usize::MAX, usize::MAX, 0, 0);
        for &i in pixels {
            let (u, v) = (i % w_img, i / w_img);
            umin = umin.min(u);
            umax = umax.max(u);
            vmin = vmin.min(v);
            vmax = vmax.max(v);
        }
        if pixels.is_empty() {
            (umin, vmin) = (0, 0);
        }
        let (w, h) = (umax - umin + 3, vmax - vmin + 3);
        let mut cells = vec![false; w * h];
        for &i in pixels {
            let (u, v) = (i % w_img, i / w_img);
            cells[(v - vmin + 1) * w + (u - umin + 1)] = true;
        }
        // (the holes filled here are not in `pixels`: the shape's own
        // pixel count stays the mask's)
        fill_small_holes(&mut cells, w, h);
        let dist = distance_transform(&cells, w, h);
        Self {
            w,
            h,
            u0: umin as i64 - 1,
            v0: vmin as i64 - 1,
            cells,
            dist,
        }
    }

    /// The eight neighbours P2..P9 of cell `i` (N, NE, E, SE, S, SW, W, NW).
    /// `i` must not lie on the border (the shape never does).
    pub fn ring(&self, i: usize) -> [usize; 8] {
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

    /// `true` for a cell off the one-cell border, whose ring exists.
    pub fn inside(&self, i: usize) -> bool {
        let (x, y) = (i % self.w, i / self.w);
        x >= 1 && y >= 1 && x + 1 < self.w && y + 1 < self.h
    }

    /// Zhang-Suen thinning to a one-cell-wide skeleton.
    pub fn thin(&mut self) {
        let mut live = set_cells(&self.cells, self.w);
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
                    if transitions(&p) != 1 {
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
        // Zhang-Suen leaves the corner cells of staircases and, now and
        // then, a 2 x 2 block. Removing every simple cell that is not an
        // end (one whose neighbours stay connected, and whose background
        // stays one region, without it) until none is left makes the
        // skeleton one cell wide everywhere: then a cell with three or
        // more neighbours is a junction, as in the graph of a curve.
        for _ in 0..MAX_SIMPLIFY_PASSES {
            let mut changed = false;
            for &i in &live {
                if !self.cells[i] {
                    continue;
                }
                let p = self.ring(i).map(|j| self.cells[j]);
                let b = p.iter().filter(|&&x| x).count();
                if b >= 2 && ring_components(&p) == 1 && background_runs(&p) == 1 {
                    self.cells[i] = false;
                    changed = true;
                }
            }
            live.retain(|&i| self.cells[i]);
            if !changed {
                break;
            }
        }
    }

    /// Removes spurs: a run of cells from a skeleton end to a junction no
    /// longer than [`SPUR_DISCS`] times the largest disc at the junction is
    /// the thinning's answer to a bump on the shape's edge (or a square
    /// tip's corner), not a strand. A rope's own end is longer, unless it
    /// stops within a width of a junction.
    /// Spurs that branch (a ragged bump) go over several passes, at most
    /// [`MAX_PRUNE_PASSES`].
    pub fn prune_spurs(&mut self) {
        let mut skeleton = set_cells(&self.cells, self.w);
        for _ in 0..MAX_PRUNE_PASSES {
            if !self.prune_spurs_once(&skeleton) {
                break;
            }
            skeleton.retain(|&i| self.cells[i]);
        }
    }

    /// One pass of [`Grid::prune_spurs`] over the `skeleton`'s cells.
    fn prune_spurs_once(&mut self, skeleton: &[usize]) -> bool {
        let ends: Vec<usize> = skeleton
            .iter()
            .copied()
            .filter(|&i| self.cells[i] && self.inside(i) && self.degree(i) == 1)
            .collect();
        let mut remove = Vec::new();
        for e in ends {
            let mut path = vec![e];
            let mut prev = usize::MAX;
            let mut at = e;
            loop {
                let next: Vec<usize> = self
                    .ring(at)
                    .into_iter()
                    .filter(|&j| self.cells[j] && j != prev && !path.contains(&j))
                    .collect();
                if next.len() != 1 {
                    break;
                }
                let j = next[0];
                if self.degree(j) >= 3 {
                    // `j` is the junction the run comes from.
                    if path.len() as f64 <= SPUR_DISCS * f64::from(self.dist[j]) {
                        remove.extend(path.iter().copied());
                    }
                    break;
                }
                if path.len() as f64 > SPUR_DISCS * f64::from(self.dist[j]) + 2.0 {
                    break;
                }
                prev = at;
                at = j;
                path.push(j);
            }
        }
        let changed = !remove.is_empty();
        for i in remove {
            self.cells[i] = false;
        }
        changed
    }

    /// Set skeleton cells among the eight neighbours of cell `i`.
    pub fn degree(&self, i: usize) -> usize {
        self.ring(i).iter().filter(|&&j| self.cells[j]).count()
    }

    /// Image coordinates of cell `i`.
    pub fn to_image(&self, i: usize) -> Vec2 {
        Vec2::new(
            (self.u0 + (i % self.w) as i64) as f64,
            (self.v0 + (i / self.w) as i64) as f64,
        )
    }

    /// The shape's local width at cell `i`, pixels: the diameter of the
    /// largest disc centred there, `2 d - 1` for a distance `d` measured
    /// between cell centres (a line `2k + 1` cells wide has `d = k + 1` on
    /// its axis).
    pub fn width_at(&self, i: usize) -> f64 {
        (2.0 * f64::from(self.dist[i]) - 1.0).max(1.0)
    }
}

/// Number of runs of unset cells round a ring that include a side cell
/// (N, E, S or W): the background regions touching the cell.
fn background_runs(p: &[bool; 8]) -> usize {
    let Some(start) = (0..8).find(|&k| p[k]) else {
        return 1;
    };
    let mut runs = 0;
    let mut in_run = false;
    let mut has_side = false;
    for n in 1..=8 {
        let k = (start + n) % 8;
        if !p[k] {
            in_run = true;
            has_side |= k % 2 == 0;
        } else if in_run {
            runs += usize::from(has_side);
            in_run = false;
            has_side = false;
        }
    }
    runs
}

/// Number of 0 -> 1 changes going once round a ring of eight neighbours
/// (Zhang-Suen's `A`).
fn transitions(p: &[bool; 8]) -> usize {
    (0..8).filter(|&k| !p[k] && p[(k + 1) % 8]).count()
}

/// Number of groups the set cells of a ring form when touching cells
/// (side or corner) are one group: neighbours in the ring touch, and so do
/// the side neighbours N, E, S, W next to each other (N and E meet at a corner).
fn ring_components(p: &[bool; 8]) -> usize {
    let mut group = [0usize, 1, 2, 3, 4, 5, 6, 7];
    fn root(g: &mut [usize; 8], mut a: usize) -> usize {
        while g[a] != a {
            a = g[a];
        }
        a
    }
    for k in 0..8 {
        let touching = [(k + 1) % 8, (k + 2) % 8];
        for (n, &j) in touching.iter().enumerate() {
            // Two apart only from a side cell (even index) to the next side cell.
            if n == 1 && k % 2 == 1 {
                continue;
            }
            if p[k] && p[j] {
                let (a, b) = (root(&mut group, k), root(&mut group, j));
                group[a.max(b)] = a.min(b);
            }
        }
    }
    (0..8).filter(|&k| p[k] && root(&mut group, k) == k).count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_five_cells_wide_measures_five_on_its_axis() {
        let mut mask = Mask::new(40, 20);
        for v in 5..10 {
            for u in 5..35 {
                mask.data[v * 40 + u] = true;
            }
        }
        let (shapes, labels) = shapes(&mask, 1);
        assert_eq!(shapes.len(), 1);
        assert_eq!(labels[7 * 40 + 20], 1);
        let grid = Grid::around(&shapes[0].pixels, 40);
        // Image (20, 7) is on the axis.
        let i = (7 - grid.v0) as usize * grid.w + (20 - grid.u0) as usize;
        assert_eq!(grid.width_at(i), 5.0);
    }

    #[test]
    fn shapes_come_largest_first_and_small_ones_are_dropped() {
        let mut mask = Mask::new(30, 10);
        for u in 0..3 {
            mask.data[u] = true; // 3 pixels
        }
        for u in 10..20 {
            mask.data[5 * 30 + u] = true; // 10 pixels
        }
        mask.data[9 * 30 + 29] = true; // 1 pixel
        let (s, labels) = shapes(&mask, 2);
        assert_eq!(
            s.iter().map(|s| s.pixels.len()).collect::<Vec<_>>(),
            [10, 3]
        );
        assert_eq!((labels[5 * 30 + 12], labels[1], labels[299]), (1, 2, 0));
    }
}
