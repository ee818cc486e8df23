//! A shape's grid by runs of equal cells along its rows: its small holes
//! filled and its distance transform, in time that grows with the runs,
//! not with the grid's area (a thin rope across a 1280x720 image has a
//! grid of 600 k cells and a few thousand runs).

use alloc::vec;
use alloc::vec::Vec;

/// A run of cells of one row: columns `first..=last`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Run {
    row: usize,
    first: usize,
    last: usize,
}

/// The runs of cells equal to `value` in each row of a `w`-wide grid, row
/// by row, left to right.
fn runs(cells: &[bool], w: usize, value: bool) -> Vec<Run> {
    let mut out = Vec::new();
    for (row, line) in cells.chunks_exact(w).enumerate() {
        let mut x = 0;
        while x < w {
            // Skip to the next cell of `value`, then to the end of its run.
            match line[x..].iter().position(|&c| c == value) {
                None => break,
                Some(k) => x += k,
            }
            let len = line[x..].iter().position(|&c| c != value).unwrap_or(w - x);
            out.push(Run {
                row,
                first: x,
                last: x + len - 1,
            });
            x += len;
        }
    }
    out
}

/// The indices of the set cells of a `w`-wide grid, in order (found by
/// runs, so empty stretches are skipped at once).
pub(super) fn set_cells(cells: &[bool], w: usize) -> Vec<usize> {
    if w == 0 {
        return Vec::new();
    }
    runs(cells, w, true)
        .into_iter()
        .flat_map(|r| r.row * w + r.first..=r.row * w + r.last)
        .collect()
}

/// Union-find root of `a`, halving the path on the way.
fn root(parent: &mut [usize], mut a: usize) -> usize {
    while parent[a] != a {
        parent[a] = parent[parent[a]];
        a = parent[a];
    }
    a
}

/// Fills the holes of a shape (unset regions not reaching the grid's
/// border, side neighbours connecting) no larger than the square of its
/// mean width (twice its area over its perimeter): a pixel of glare or a
/// speck of colour noise inside a rope, which the skeleton would otherwise
/// go round. A loop the rope lies in encloses far more.
pub(super) fn fill_small_holes(cells: &mut [bool], w: usize, h: usize) {
    if w == 0 || cells.len() != w * h {
        return;
    }
    let set = runs(cells, w, true);
    let area: usize = set.iter().map(|r| r.last - r.first + 1).sum();
    // Perimeter: set cells with an unset (or missing-at-the-border, never
    // counted) side neighbour. A run's ends have one unless at the border.
    let unset = |x: usize, y: usize| !cells[y * w + x];
    let mut perimeter = 0;
    for r in &set {
        for x in r.first..=r.last {
            let y = r.row;
            let edge = (x == r.first && x > 0)
                || (x == r.last && x + 1 < w)
                || (y > 0 && unset(x, y - 1))
                || (y + 1 < h && unset(x, y + 1));
            perimeter += usize::from(edge);
        }
    }
    if perimeter == 0 {
        return;
    }
    let width = 2.0 * area as f64 / perimeter as f64;
    let limit = (width * width) as usize;
    // The unset runs joined where runs of neighbouring rows share a column.
    let gaps = runs(cells, w, false);
    let mut parent: Vec<usize> = (0..gaps.len()).collect();
    let mut row_start = 0;
    let mut previous = 0..0;
    for k in 0..=gaps.len() {
        if k < gaps.len() && gaps[k].row == gaps[row_start].row {
            continue;
        }
        let here = row_start..k;
        let adjacent = previous.end > previous.start
            && here.end > here.start
            && gaps[previous.start].row + 1 == gaps[row_start].row;
        if adjacent {
            let (mut i, mut j) = (previous.start, here.start);
            while i < previous.end && j < here.end {
                let (a, b) = (gaps[i], gaps[j]);
                if a.first <= b.last && b.first <= a.last {
                    let (ra, rb) = (root(&mut parent, i), root(&mut parent, j));
                    parent[ra.max(rb)] = ra.min(rb);
                }
                // Move past whichever run ends first.
                if a.last < b.last {
                    i += 1;
                } else {
                    j += 1;
                }
            }
        }
        previous = here;
        row_start = k;
    }
    let mut size = vec![0usize; gaps.len()];
    let mut outside = vec![false; gaps.len()];
    for k in 0..gaps.len() {
        let r = root(&mut parent, k);
        let g = gaps[k];
        size[r] += g.last - g.first + 1;
        outside[r] |= g.first == 0 || g.last + 1 == w || g.row == 0 || g.row + 1 == h;
    }
    for k in 0..gaps.len() {
        let r = root(&mut parent, k);
        if !outside[r] && size[r] <= limit {
            let g = gaps[k];
            cells[g.row * w + g.first..=g.row * w + g.last].fill(true);
        }
    }
}

/// Exact Euclidean distance from each set cell to the nearest unset cell,
/// in cells (unset cells get 0): the distance down each column, then
/// Felzenszwalb and Huttenlocher's lower envelope of parabolas along each
/// run of set cells of a row with the unset cells at its two ends (no
/// cell beyond them can be nearer). A cell with no unset cell in its row
/// or column counts one `w + h` away in that direction.
pub(super) fn distance_transform(cells: &[bool], w: usize, h: usize) -> Vec<f32> {
    let mut dist = vec![0.0f32; cells.len()];
    if w == 0 || cells.len() != w * h {
        return dist;
    }
    // Cells to the nearest unset cell above, then below, in each column;
    // `far` (a grid side is at most a few image sides, so `far + h` fits
    // 16 bits) where there is none. Selected with masks, so rows vectorise.
    let far = i32::try_from(w + h)
        .unwrap_or(i32::MAX)
        .min(i32::from(i16::MAX) / 3) as i16;
    let mut vertical = vec![0i16; cells.len()];
    let mut above = vec![far; w];
    for (line, v) in cells.chunks_exact(w).zip(vertical.chunks_exact_mut(w)) {
        for ((a, &c), v) in above.iter_mut().zip(line).zip(v.iter_mut()) {
            *a = (*a + 1) & -i16::from(c);
            *v = *a;
        }
    }
    let mut below = vec![far; w];
    for (line, v) in cells
        .chunks_exact(w)
        .zip(vertical.chunks_exact_mut(w))
        .rev()
    {
        for ((b, &c), v) in below.iter_mut().zip(line).zip(v.iter_mut()) {
            *b = (*b + 1) & -i16::from(c);
            *v = (*v).min(*b);
        }
    }
    let inf = f64::from(far) * f64::from(far);
    let (mut f, mut out, mut hull, mut bounds) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for r in runs(cells, w, true) {
        // The run with its unset neighbours in the row, where there are any.
        let lo = r.first.saturating_sub(1);
        let hi = (r.last + 1).min(w - 1);
        let n = hi - lo + 1;
        f.clear();
        f.extend((lo..=hi).map(|x| {
            let d = f64::from(vertical[r.row * w + x].min(far));
            if cells[r.row * w + x] {
                (d * d).min(inf)
            } else {
                0.0
            }
        }));
        out.resize(n, 0.0);
        hull.resize(n, 0);
        bounds.resize(n + 1, 0.0);
        envelope(&f, &mut out, &mut hull, &mut bounds);
        for x in r.first..=r.last {
            dist[r.row * w + x] = libm::sqrt(out[x - lo]) as f32;
        }
    }
    dist
}

/// One dimension of [`distance_transform`]: `out[q] = min_p (q - p)^2 + f[p]`.
fn envelope(f: &[f64], out: &mut [f64], hull: &mut [usize], bounds: &mut [f64]) {
    let n = f.len();
    if n == 0 {
        return;
    }
    let mut k = 0;
    hull[0] = 0;
    bounds[0] = f64::NEG_INFINITY;
    bounds[1] = f64::INFINITY;
    let cross = |p: usize, q: usize| {
        ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * (q as f64 - p as f64))
    };
    for q in 1..n {
        // bounds[0] is minus infinity, so the loop stops at k = 0.
        let mut s = cross(hull[k], q);
        while s <= bounds[k] {
            k -= 1;
            s = cross(hull[k], q);
        }
        k += 1;
        hull[k] = q;
        bounds[k] = s;
        bounds[k + 1] = f64::INFINITY;
    }
    k = 0;
    for (q, o) in out.iter_mut().enumerate() {
        while bounds[k + 1] < q as f64 {
            k += 1;
        }
        let p = hull[k];
        let d = q as f64 - p as f64;
        *o = d * d + f[p];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each set cell's distance to the nearest unset cell, by trying all.
    fn brute(cells: &[bool], w: usize, h: usize) -> Vec<f32> {
        (0..w * h)
            .map(|i| {
                if !cells[i] {
                    return 0.0;
                }
                let (x, y) = ((i % w) as f64, (i / w) as f64);
                (0..w * h)
                    .filter(|&j| !cells[j])
                    .map(|j| {
                        let (a, b) = ((j % w) as f64 - x, (j / w) as f64 - y);
                        libm::sqrt(a * a + b * b)
                    })
                    .fold(f64::MAX, f64::min) as f32
            })
            .collect()
    }

    /// The holes by flooding the unset cells from the border, one cell at
    /// a time (the definition), then filled as `fill_small_holes` says.
    fn flood_reference(cells: &mut [bool], w: usize, h: usize) {
        let side = |i: usize| -> [Option<usize>; 4] {
            let (x, y) = (i % w, i / w);
            [
                (y > 0).then(|| i - w),
                (x + 1 < w).then(|| i + 1),
                (y + 1 < h).then(|| i + w),
                (x > 0).then(|| i - 1),
            ]
        };
        let area = cells.iter().filter(|&&c| c).count();
        let perimeter = (0..cells.len())
            .filter(|&i| cells[i] && side(i).iter().any(|n| n.is_some_and(|j| !cells[j])))
            .count();
        if perimeter == 0 {
            return;
        }
        let width = 2.0 * area as f64 / perimeter as f64;
        let limit = (width * width) as usize;
        let mut seen = vec![0u8; cells.len()];
        let mut stack: Vec<usize> = (0..cells.len())
            .filter(|&i| {
                let (x, y) = (i % w, i / w);
                !cells[i] && (x == 0 || y == 0 || x + 1 == w || y + 1 == h)
            })
            .collect();
        for &i in &stack {
            seen[i] = 1;
        }
        while let Some(i) = stack.pop() {
            for j in side(i).into_iter().flatten() {
                if !cells[j] && seen[j] == 0 {
                    seen[j] = 1;
                    stack.push(j);
                }
            }
        }
        for start in 0..cells.len() {
            if cells[start] || seen[start] != 0 {
                continue;
            }
            let mut hole = vec![start];
            seen[start] = 2;
            let mut k = 0;
            while k < hole.len() {
                for j in side(hole[k]).into_iter().flatten() {
                    if !cells[j] && seen[j] == 0 {
                        seen[j] = 2;
                        hole.push(j);
                    }
                }
                k += 1;
            }
            if hole.len() <= limit {
                for &i in &hole {
                    cells[i] = true;
                }
            }
        }
    }

    /// A grid of 1..=`max_side` cells a side whose cells are set with a
    /// probability drawn from `density`; and its width and height.
    fn random_grid(
        rng: &mut crate::rng::SplitMix64,
        max_side: u64,
        density: core::ops::Range<f64>,
    ) -> (Vec<bool>, usize, usize) {
        let (w, h) = (
            1 + rng.below(max_side) as usize,
            1 + rng.below(max_side) as usize,
        );
        let p = density.start + (density.end - density.start) * rng.uniform();
        ((0..w * h).map(|_| rng.uniform() < p).collect(), w, h)
    }

    #[test]
    fn distance_transform_is_exact_against_brute_force() {
        let mut rng = crate::rng::SplitMix64::new(3);
        for _ in 0..200 {
            let (mut cells, w, h) = random_grid(&mut rng, 16, 0.5..0.95);
            cells[0] = false;
            assert_eq!(
                distance_transform(&cells, w, h),
                brute(&cells, w, h),
                "{w}x{h}"
            );
        }
    }

    #[test]
    fn holes_are_those_the_flood_from_the_border_leaves() {
        let mut rng = crate::rng::SplitMix64::new(5);
        for _ in 0..300 {
            let (cells, w, h) = random_grid(&mut rng, 24, 0.4..0.95);
            let (mut ours, mut theirs) = (cells.clone(), cells);
            fill_small_holes(&mut ours, w, h);
            flood_reference(&mut theirs, w, h);
            assert_eq!(ours, theirs, "{w}x{h}");
        }
    }

    #[test]
    fn a_ring_keeps_its_large_hole_and_loses_its_speck() {
        // A 16 x 16 square ring 4 cells thick with a one-cell speck in its
        // wall: the speck is filled, the 8 x 8 middle is not (64 cells,
        // above the mean width squared, about 17).
        let (w, h) = (18, 18);
        let mut cells = vec![false; w * h];
        for y in 1..17 {
            for x in 1..17 {
                let wall = !(5..13).contains(&x) || !(5..13).contains(&y);
                cells[y * w + x] = wall;
            }
        }
        cells[2 * w + 2] = false;
        fill_small_holes(&mut cells, w, h);
        assert!(cells[2 * w + 2]);
        assert!(!cells[6 * w + 6]);
    }
}
