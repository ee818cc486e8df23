//! A shape's skeleton as a graph: junction zones (where strands meet or
//! cross) joined by branches, and walks through it the way a rope goes,
//! straight on through each crossing with the least bending.

use alloc::vec;
use alloc::vec::Vec;

use super::skeleton::Grid;
use crate::math::Vec2;

/// A junction zone's radius, in units of the largest disc centred on its
/// junction cells: the skeleton bends towards a junction within about a
/// rope's width of it, so the branches are measured from outside the zone.
const ZONE_RADIUS_DISCS: f64 = 1.5;
/// Junction zones joined by a branch shorter than this many rope widths
/// are one crossing: two strands crossing at a shallow angle overlap over
/// `w / sin(angle)`, three widths at 20 degrees.
const MERGE_BRANCH_WIDTHS: f64 = 3.0;
/// A branch from a junction zone to a free end shorter than this many zone
/// radii is a spur of the thinning (a blunt tip's fork), not a strand.
const SPUR_ZONE_RADII: f64 = 2.0;
/// Most junction cells one shape may have: more is not a rope (a textured
/// blob), and is refused before any quadratic work.
pub const MAX_JUNCTION_CELLS: usize = 512;
/// Cells over which a branch's direction at an end is measured, in rope
/// widths (at least [`MIN_TANGENT_CELLS`]).
const TANGENT_WIDTHS: f64 = 2.0;
/// Fewest cells a direction is measured over (pixel steps are 45 degrees apart).
const MIN_TANGENT_CELLS: usize = 4;
/// Largest turn, degrees, a rope is followed through a junction with: a
/// crossing goes straight on; at a T the stem's rope ends there. (A zone
/// left with two branches has nothing to choose: no limit there.)
pub const MAX_CROSSING_TURN_DEGREES: f64 = 60.0;

/// What a branch end attaches to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum End {
    /// A tip of the skeleton.
    Free,
    /// A junction zone.
    Zone(usize),
}

/// A run of skeleton cells between two ends.
#[derive(Debug, Clone)]
pub(super) struct Branch {
    /// Grid cells in order.
    pub cells: Vec<usize>,
    /// What its first and last cells attach to.
    pub ends: [End; 2],
}

/// Where strands meet: the skeleton cells near junction cells.
#[derive(Debug, Clone, Default)]
struct Zone {
    /// Junction cells (grid).
    junctions: Vec<usize>,
    /// Cells of short branches between junctions, taken into the zone.
    absorbed: Vec<usize>,
}

/// The positions and outward directions of a branch's two ends.
#[derive(Debug, Clone, Copy)]
struct Tips {
    /// Image position of the first and last cells.
    at: [Vec2; 2],
    /// Direction of travel arriving at each end (pointing out of the branch).
    out: [Vec2; 2],
}

/// A shape's skeleton as junction zones and branches.
pub(super) struct SkeletonGraph {
    /// The branches, spurs removed.
    pub branches: Vec<Branch>,
    tips: Vec<Tips>,
    /// Number of zones (zone ids are `0..zones`).
    pub zones: usize,
}

/// Why a shape's skeleton is no graph of a rope.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct TooBranched {
    /// Junction cells found.
    pub junctions: usize,
}

/// Disjoint sets over `0..n`.
struct Sets(Vec<usize>);

impl Sets {
    fn new(n: usize) -> Self {
        Self((0..n).collect())
    }
    fn find(&mut self, mut a: usize) -> usize {
        while self.0[a] != a {
            self.0[a] = self.0[self.0[a]];
            a = self.0[a];
        }
        a
    }
    fn join(&mut self, a: usize, b: usize) {
        let (a, b) = (self.find(a), self.find(b));
        if a != b {
            self.0[a.max(b)] = a.min(b);
        }
    }
}

impl SkeletonGraph {
    /// The graph of the thinned `grid`.
    pub fn of(grid: &Grid) -> Result<Self, TooBranched> {
        let skel = |i: usize| grid.cells[i];
        let cells: Vec<usize> = (0..grid.cells.len())
            .filter(|&i| skel(i) && grid.inside(i))
            .collect();
        let junctions: Vec<usize> = cells
            .iter()
            .copied()
            .filter(|&i| grid.degree(i) >= 3)
            .collect();
        if junctions.len() > MAX_JUNCTION_CELLS {
            return Err(TooBranched {
                junctions: junctions.len(),
            });
        }
        let radius = |j: usize| (ZONE_RADIUS_DISCS * f64::from(grid.dist[j])).max(1.5);
        let pos = |i: usize| Vec2::new((i % grid.w) as f64, (i / grid.w) as f64);
        // Junction cells whose discs overlap are one zone.
        let mut sets = Sets::new(junctions.len());
        for a in 0..junctions.len() {
            for b in a + 1..junctions.len() {
                let (ja, jb) = (junctions[a], junctions[b]);
                if (pos(ja) - pos(jb)).norm() <= radius(ja).max(radius(jb)) {
                    sets.join(a, b);
                }
            }
        }
        let mut zones = Self::zones_of(&junctions, &mut sets);
        loop {
            let zone_of = Self::mark_zones(grid, &zones, radius);
            let branches = trace_branches(grid, &cells, &zone_of);
            // Zones joined by a short branch are one crossing; a short
            // branch from a zone back to it is a hole the thinning left.
            let mut merge = Sets::new(zones.len());
            let mut absorbed: Vec<(usize, &Branch)> = Vec::new();
            // Zones whose cells touch have no branch between them to keep
            // them apart (on a rope whose mask's edge is ragged, junctions
            // follow each other along it): they are one zone.
            let touching = touching_zones(grid, &cells, &zone_of);
            for &(a, c) in &touching {
                merge.join(a, c);
            }
            for b in &branches {
                if let [End::Zone(a), End::Zone(c)] = b.ends {
                    let width = b
                        .cells
                        .iter()
                        .map(|&i| grid.width_at(i))
                        .fold(1.0, f64::max);
                    if (b.cells.len() as f64) < MERGE_BRANCH_WIDTHS * width {
                        merge.join(a, c);
                        absorbed.push((a, b));
                    }
                }
            }
            if !absorbed.is_empty() || !touching.is_empty() {
                let mut groups: Vec<Zone> = vec![Zone::default(); zones.len()];
                for (z, zone) in zones.iter().enumerate() {
                    let g = &mut groups[merge.find(z)];
                    g.junctions.extend(zone.junctions.iter().copied());
                    g.absorbed.extend(zone.absorbed.iter().copied());
                }
                for (a, b) in absorbed {
                    let root = merge.find(a);
                    groups[root].absorbed.extend(b.cells.iter().copied());
                }
                zones = groups
                    .into_iter()
                    .filter(|g| !g.junctions.is_empty())
                    .collect();
                continue;
            }
            let branches = prune_spurs(branches, &zones, radius);
            let tips = branches.iter().map(|b| tips_of(grid, b)).collect();
            return Ok(Self {
                branches,
                tips,
                zones: zones.len(),
            });
        }
    }

    fn zones_of(junctions: &[usize], sets: &mut Sets) -> Vec<Zone> {
        let mut groups: Vec<Vec<usize>> = vec![Vec::new(); junctions.len()];
        for (k, &j) in junctions.iter().enumerate() {
            groups[sets.find(k)].push(j);
        }
        groups
            .into_iter()
            .filter(|g| !g.is_empty())
            .map(|junctions| Zone {
                junctions,
                absorbed: Vec::new(),
            })
            .collect()
    }

    /// The zone of each skeleton cell within a junction's radius (`usize::MAX` elsewhere).
    fn mark_zones(grid: &Grid, zones: &[Zone], radius: impl Fn(usize) -> f64) -> Vec<usize> {
        let mut zone_of = vec![usize::MAX; grid.cells.len()];
        for (z, zone) in zones.iter().enumerate() {
            for &c in &zone.absorbed {
                zone_of[c] = z;
            }
            for &j in &zone.junctions {
                let r = radius(j);
                let reach = libm::ceil(r) as i64;
                let (x, y) = ((j % grid.w) as i64, (j / grid.w) as i64);
                for dy in -reach..=reach {
                    for dx in -reach..=reach {
                        let (nx, ny) = (x + dx, y + dy);
                        if nx < 0 || ny < 0 || nx >= grid.w as i64 || ny >= grid.h as i64 {
                            continue;
                        }
                        let k = ny as usize * grid.w + nx as usize;
                        if grid.cells[k] && ((dx * dx + dy * dy) as f64) <= r * r {
                            zone_of[k] = z;
                        }
                    }
                }
            }
        }
        zone_of
    }
}

/// Pairs of different zones with neighbouring skeleton cells, each once.
fn touching_zones(grid: &Grid, cells: &[usize], zone_of: &[usize]) -> Vec<(usize, usize)> {
    let mut pairs = Vec::new();
    for &i in cells {
        let a = zone_of[i];
        if a == usize::MAX {
            continue;
        }
        for j in grid.ring(i) {
            let b = zone_of[j];
            if grid.cells[j] && b != usize::MAX && b != a {
                pairs.push((a.min(b), a.max(b)));
            }
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

/// The skeleton outside the zones cut into branches, each traced in order
/// (4-neighbours first, so a staircase's corner cells are kept in line).
fn trace_branches(grid: &Grid, cells: &[usize], zone_of: &[usize]) -> Vec<Branch> {
    let free = |i: usize| grid.cells[i] && zone_of[i] == usize::MAX && grid.inside(i);
    let mut visited = vec![false; grid.cells.len()];
    // Ends first: cells with fewest free neighbours start the traces.
    let mut starts: Vec<(usize, usize)> = cells
        .iter()
        .copied()
        .filter(|&i| free(i))
        .map(|i| (grid.ring(i).iter().filter(|&&j| free(j)).count(), i))
        .collect();
    starts.sort_unstable();
    let step = |i: usize, visited: &[bool]| -> Option<usize> {
        let ring = grid.ring(i);
        // N, E, S, W first, then the diagonals.
        [0, 2, 4, 6, 1, 3, 5, 7]
            .iter()
            .map(|&k| ring[k])
            .find(|&j| free(j) && !visited[j])
    };
    let mut branches = Vec::new();
    for (_, start) in starts {
        if visited[start] {
            continue;
        }
        visited[start] = true;
        let mut forward = vec![start];
        while let Some(j) = step(forward[forward.len() - 1], &visited) {
            visited[j] = true;
            forward.push(j);
        }
        let mut backward = Vec::new();
        let mut at = start;
        while let Some(j) = step(at, &visited) {
            visited[j] = true;
            backward.push(j);
            at = j;
        }
        backward.reverse();
        backward.extend(forward);
        let cells = backward;
        let end_of = |i: usize| {
            grid.ring(i)
                .iter()
                .find(|&&j| grid.cells[j] && zone_of[j] != usize::MAX)
                .map_or(End::Free, |&j| End::Zone(zone_of[j]))
        };
        let ends = [end_of(cells[0]), end_of(cells[cells.len() - 1])];
        branches.push(Branch { cells, ends });
    }
    branches
}

/// Drops spurs (short branches from a zone to a free end), then frees the
/// ends of branches left alone at a zone (a blunt tip's fork).
fn prune_spurs(
    branches: Vec<Branch>,
    zones: &[Zone],
    radius: impl Fn(usize) -> f64,
) -> Vec<Branch> {
    let zone_radius: Vec<f64> = zones
        .iter()
        .map(|z| z.junctions.iter().map(|&j| radius(j)).fold(0.0, f64::max))
        .collect();
    let degree = |bs: &[Branch]| {
        let mut d = vec![0usize; zones.len()];
        for b in bs {
            for e in b.ends {
                if let End::Zone(z) = e {
                    d[z] += 1;
                }
            }
        }
        d
    };
    let before = degree(&branches);
    let mut kept: Vec<Branch> = branches
        .into_iter()
        .filter(|b| {
            let spur_at = match b.ends {
                [End::Zone(z), End::Free] | [End::Free, End::Zone(z)] => Some(z),
                _ => None,
            };
            // A spur goes only if its zone keeps two other branches, so a
            // rope's own end beside a small fork is never taken for one.
            !spur_at.is_some_and(|z| {
                (b.cells.len() as f64) < SPUR_ZONE_RADII * zone_radius[z] && before[z] >= 3
            })
        })
        .collect();
    let after = degree(&kept);
    for b in kept.iter_mut() {
        for e in b.ends.iter_mut() {
            if let End::Zone(z) = *e {
                if after[z] == 1 {
                    *e = End::Free;
                }
            }
        }
    }
    kept
}

/// Where a branch's ends are and which way it leaves through each, over
/// about two rope widths.
fn tips_of(grid: &Grid, b: &Branch) -> Tips {
    let cells = &b.cells;
    let n = cells.len();
    let at = [grid.to_image(cells[0]), grid.to_image(cells[n - 1])];
    let reach = |tip: usize| {
        let r = libm::round(TANGENT_WIDTHS * grid.width_at(tip)) as usize;
        r.max(MIN_TANGENT_CELLS).min(n - 1)
    };
    let out = if n < 2 {
        [Vec2::zeros(); 2]
    } else {
        [
            at[0] - grid.to_image(cells[reach(cells[0])]),
            at[1] - grid.to_image(cells[n - 1 - reach(cells[n - 1])]),
        ]
    };
    Tips { at, out }
}

/// A path through a shape: image positions about a pixel apart, the local
/// width at each (NaN across a junction zone), and the zone each lies in.
#[derive(Debug, Clone, Default)]
pub(super) struct Walk {
    /// Image positions, in order.
    pub points: Vec<Vec2>,
    /// Local width, pixels (NaN across a zone).
    pub widths: Vec<f64>,
    /// The junction zone crossed at each point (`u32::MAX` outside zones),
    /// numbered image-wide.
    pub zones: Vec<u32>,
    /// Whether each end is a tip of the skeleton (else it stops at a junction).
    pub free: [bool; 2],
}

/// Angle between two vectors, radians (0 for a zero vector).
pub(super) fn angle(a: Vec2, b: Vec2) -> f64 {
    let (na, nb) = (a.norm(), b.norm());
    if !(na > 0.0) || !(nb > 0.0) {
        return 0.0;
    }
    libm::acos((a.dot(&b) / (na * nb)).clamp(-1.0, 1.0))
}

/// One branch traversed in a direction.
#[derive(Debug, Clone, Copy)]
struct Leg {
    branch: usize,
    forward: bool,
}

impl SkeletonGraph {
    fn ordered(&self, leg: Leg) -> impl Iterator<Item = usize> + '_ {
        let cells = &self.branches[leg.branch].cells;
        let n = cells.len();
        (0..n).map(move |k| {
            if leg.forward {
                cells[k]
            } else {
                cells[n - 1 - k]
            }
        })
    }

    /// The leg's last end, where the walk arrives.
    fn arrival(&self, leg: Leg) -> End {
        self.branches[leg.branch].ends[usize::from(leg.forward)]
    }

    /// Position and direction of travel where a leg arrives.
    fn arriving(&self, leg: Leg) -> (Vec2, Vec2) {
        let e = usize::from(leg.forward);
        let t = &self.tips[leg.branch];
        (t.at[e], t.out[e])
    }

    /// Position and direction of travel where a leg starts.
    fn leaving(&self, leg: Leg) -> (Vec2, Vec2) {
        let e = usize::from(!leg.forward);
        let t = &self.tips[leg.branch];
        (t.at[e], -t.out[e])
    }

    /// Branch ends at zone `z`.
    fn degree(&self, z: usize) -> usize {
        let ends = self.branches.iter().flat_map(|b| b.ends);
        ends.filter(|&e| e == End::Zone(z)).count()
    }

    /// The walk from `start` on, never reusing a branch of `used`: at each
    /// zone the unused branch the rope bends least into, if the bend is at
    /// most [`MAX_CROSSING_TURN_DEGREES`] (any bend at a zone of two
    /// branches).
    fn walk_from(&self, start: Leg, used: &[bool]) -> (Vec<Leg>, f64) {
        let mut used = used.to_vec();
        used[start.branch] = true;
        let mut legs = vec![start];
        let mut length = self.branches[start.branch].cells.len() as f64;
        let limit = MAX_CROSSING_TURN_DEGREES.to_radians();
        loop {
            let last = legs[legs.len() - 1];
            let End::Zone(z) = self.arrival(last) else {
                break;
            };
            let (p_in, d_in) = self.arriving(last);
            let mut best: Option<(f64, Leg, f64)> = None;
            // A zone left with two branches (a spur pruned from a tight
            // bend: a ragged edge, glare) offers no strand to choose: the
            // rope goes on round it however sharply it turns.
            let limit = if self.degree(z) == 2 {
                core::f64::consts::PI
            } else {
                limit
            };
            for (b, branch) in self.branches.iter().enumerate() {
                if used[b] {
                    continue;
                }
                for (end, forward) in [(0, true), (1, false)] {
                    if branch.ends[end] != End::Zone(z) {
                        continue;
                    }
                    let leg = Leg { branch: b, forward };
                    let (p_out, d_out) = self.leaving(leg);
                    let chord = p_out - p_in;
                    let turn = if chord.norm() < 2.0 {
                        angle(d_in, d_out)
                    } else {
                        angle(d_in, chord).max(angle(chord, d_out))
                    };
                    if turn <= limit && best.is_none_or(|(t, _, _)| turn < t) {
                        best = Some((turn, leg, chord.norm()));
                    }
                }
            }
            let Some((_, leg, bridge)) = best else {
                break;
            };
            used[leg.branch] = true;
            length += bridge + self.branches[leg.branch].cells.len() as f64;
            legs.push(leg);
        }
        (legs, length)
    }

    /// Walks covering the skeleton, longest first: each starts at a free
    /// end (or, once none is left, at any unused branch) and goes on as
    /// [`Self::walk_from`] does; `zone_base` numbers this shape's zones
    /// image-wide.
    pub fn walks(&self, grid: &Grid, zone_base: u32) -> Vec<Walk> {
        let mut used = vec![false; self.branches.len()];
        let mut out = Vec::new();
        loop {
            let mut starts: Vec<Leg> = Vec::new();
            for (b, branch) in self.branches.iter().enumerate() {
                if used[b] {
                    continue;
                }
                if branch.ends[0] == End::Free {
                    starts.push(Leg {
                        branch: b,
                        forward: true,
                    });
                }
                if branch.ends[1] == End::Free {
                    starts.push(Leg {
                        branch: b,
                        forward: false,
                    });
                }
            }
            if starts.is_empty() {
                // Only loops and pieces between zones are left.
                if let Some(b) = (0..self.branches.len()).find(|&b| !used[b]) {
                    starts.push(Leg {
                        branch: b,
                        forward: true,
                    });
                }
            }
            let best = starts.into_iter().map(|s| self.walk_from(s, &used)).fold(
                None::<(Vec<Leg>, f64)>,
                |best, w| match best {
                    Some(b) if b.1 >= w.1 => Some(b),
                    _ => Some(w),
                },
            );
            let Some((legs, _)) = best else {
                break;
            };
            for l in &legs {
                used[l.branch] = true;
            }
            out.push(self.assemble(grid, &legs, zone_base));
        }
        out
    }

    /// The walk's points: each leg's cells, and between legs a bridge
    /// through the zone (a cubic that leaves and arrives along the legs).
    fn assemble(&self, grid: &Grid, legs: &[Leg], zone_base: u32) -> Walk {
        let mut w = Walk::default();
        for (k, &leg) in legs.iter().enumerate() {
            if k > 0 {
                let prev = legs[k - 1];
                let zone = match self.arrival(prev) {
                    End::Zone(z) => zone_base + z as u32,
                    End::Free => u32::MAX,
                };
                let (a, da) = self.arriving(prev);
                let (b, db) = self.leaving(leg);
                let (da, db) = (unit(da), unit(db));
                let chord = (b - a).norm();
                let steps = libm::ceil(chord) as usize;
                for s in 1..steps {
                    let t = s as f64 / steps as f64;
                    w.points.push(hermite(a, da * chord, b, db * chord, t));
                    w.widths.push(f64::NAN);
                    w.zones.push(zone);
                }
            }
            for c in self.ordered(leg) {
                w.points.push(grid.to_image(c));
                w.widths.push(grid.width_at(c));
                w.zones.push(u32::MAX);
            }
        }
        let first = legs[0];
        let last = legs[legs.len() - 1];
        w.free = [
            self.branches[first.branch].ends[usize::from(!first.forward)] == End::Free,
            self.arrival(last) == End::Free,
        ];
        w
    }
}

fn unit(v: Vec2) -> Vec2 {
    let n = v.norm();
    if n > 0.0 {
        v / n
    } else {
        v
    }
}

/// The cubic Hermite curve from `a` (tangent `ta`) to `b` (tangent `tb`) at `t`.
pub(super) fn hermite(a: Vec2, ta: Vec2, b: Vec2, tb: Vec2, t: f64) -> Vec2 {
    let (t2, t3) = (t * t, t * t * t);
    a * (2.0 * t3 - 3.0 * t2 + 1.0)
        + ta * (t3 - 2.0 * t2 + t)
        + b * (-2.0 * t3 + 3.0 * t2)
        + tb * (t3 - t2)
}
