//! A hidden end pulled out from under its occluder (this project's
//! addition, issue 28): rope in view that no node explains, that comes out
//! of hidden space within the reach of a hidden end run, is where that end
//! went. The run is laid from its anchor under the occluder to the piece
//! and along it, keeping its rest length.

use alloc::vec::Vec;

use super::length::{
    along, end_run_from_anchor, set_end_run, shortfall, taut_from_pulled_end,
    MIN_SHORTFALL_SPACINGS,
};
use super::slide::HiddenEnds;
use crate::curve::RopeCurve;
use crate::math::{self, NearNodes, Vec3};
use crate::perception::evidence::OCCLUDER_MARGIN;
use crate::perception::table::Plane;
use crate::polyline::polyline_length;
use crate::visibility::sees_most;

/// Points of rope one piece is made of are at most this many rest spacings
/// apart: a wider gap is no longer one stretch of rope the nodes could
/// sample.
pub const PIECE_LINK_SPACINGS: f64 = 0.5;

/// The share of the rope's length its rest length may be short by: frame
/// 0's tracked length against the truth on the randomised tuning range,
/// 10th percentile 0.957.
pub const REST_LENGTH_SLACK: f64 = 0.043;

/// What the rope a run or an end can take may be off by: a node spacing
/// (where its visible anchor lies) or the rest length's own error
/// ([`REST_LENGTH_SLACK`] of `count` nodes' rope), the larger.
fn length_slack(rest_spacing: f64, count: usize) -> f64 {
    rest_spacing.max(REST_LENGTH_SLACK * rest_spacing * count.saturating_sub(1) as f64)
}

/// A piece shorter than this many rest spacings is not taken: a run's node
/// could not be told to lie on it rather than beside it.
pub const MIN_PIECE_SPACINGS: f64 = 1.0;

/// The hidden space a piece comes out of lies within this many rest
/// spacings of its near tip, and none within it of its far tip.
pub const EXIT_GAP_SPACINGS: f64 = 0.5;

/// Most unexplained points looked at (the pieces are found in `O(n^2)`);
/// more are thinned evenly.
pub const MAX_PIECE_POINTS: usize = 512;

/// A piece most of whose points (more than this share) lie within
/// [`PIECE_LINK_SPACINGS`] of rope-coloured points that were not the rope
/// when it was last wholly seen is that thing, not the rope.
pub const NOT_ROPE_SHARE: f64 = 0.5;

/// How far from every node a point of the cloud must be to be rope the
/// nodes do not explain: a node spacing (the most a point on the tracked
/// rope lies from its nearest node, twice over) and the rope's radius (the
/// cloud's points lie on its surface, not its axis).
pub fn explained_reach(rest_spacing: f64, radius: f64) -> f64 {
    rest_spacing + radius.max(0.0)
}

/// The points of `cloud` farther than `reach` from every node, thinned
/// evenly to at most [`MAX_PIECE_POINTS`].
pub fn unexplained_points(nodes: &[Vec3], cloud: &[Vec3], reach: f64) -> Vec<Vec3> {
    let mut near = NearNodes::new(nodes, reach);
    let far: Vec<Vec3> = cloud
        .iter()
        .filter(|p| math::is_finite(p))
        .filter(|p| !near.any(p, |_| true))
        .copied()
        .collect();
    thinned(far)
}

/// Most points kept of things seen beside the rope
/// ([`remember_not_rope`]).
pub const MAX_NOT_ROPE_POINTS: usize = 256;

/// `true` when `p` lies within a [`PIECE_LINK_SPACINGS`] link of a point
/// of `not_rope` (things seen beside the rope, [`remember_not_rope`]): it
/// is that thing, not rope.
pub fn near_not_rope(p: &Vec3, not_rope: &[Vec3], rest_spacing: f64) -> bool {
    let link = PIECE_LINK_SPACINGS * rest_spacing;
    not_rope
        .iter()
        .any(|q| (p - q).norm_squared() <= link * link)
}

/// `true` when more than [`NOT_ROPE_SHARE`] of `points` (one piece) lie
/// near things seen beside the rope ([`near_not_rope`]): the piece is that
/// thing.
fn mostly_not_rope(points: &[Vec3], not_rope: &[Vec3], rest_spacing: f64) -> bool {
    let known = points
        .iter()
        .filter(|p| near_not_rope(p, not_rope, rest_spacing))
        .count();
    (known as f64) > NOT_ROPE_SHARE * points.len() as f64
}

/// Adds to `memory` the `points` (unexplained rope-coloured points on a
/// frame where the rope was wholly seen) not already within half a
/// [`PIECE_LINK_SPACINGS`] link of a remembered one, up to
/// [`MAX_NOT_ROPE_POINTS`]. Things beside the rope stay where they are, and
/// one may be covered on the frame that would have replaced the memory.
pub fn remember_not_rope(memory: &mut Vec<Vec3>, points: &[Vec3], rest_spacing: f64) {
    let close = 0.5 * PIECE_LINK_SPACINGS * rest_spacing;
    if !(close > 0.0) {
        return;
    }
    for p in points.iter().filter(|p| math::is_finite(p)) {
        if memory.len() >= MAX_NOT_ROPE_POINTS {
            return;
        }
        if memory
            .iter()
            .all(|q| (p - q).norm_squared() > close * close)
        {
            memory.push(*p);
        }
    }
}

/// The `points` no end or hidden run of the rope could reach with its
/// rest length (`rest_spacing` per node): farther from the anchor of a
/// run at an end than its nodes' rope, and from the two anchors of a run
/// in the middle than the rope between them, each with the length the
/// nodes' polyline lacks of the rest length added (rope the state holds
/// nowhere, which an end can take: [`follow_rope_past_ends`]); a seen end
/// reaches that much past its node. Unexplained rope-coloured points of
/// these are something beside the rope, not rope of it.
pub fn beyond_hidden_reach(
    nodes: &[Vec3],
    known: &[bool],
    points: &[Vec3],
    rest_spacing: f64,
) -> Vec<Vec3> {
    let m = nodes.len();
    if known.len() != m || !known.iter().any(|&k| k) {
        return Vec::new();
    }
    let spare = shortfall(nodes, rest_spacing * m.saturating_sub(1) as f64).max(0.0);
    let runs = super::slide::hidden_runs(known);
    let to = |p: &Vec3, i: usize| math::norm(&(p - nodes[i]));
    let reaches = |p: &Vec3| {
        let seen_end = |i: usize| known[i] && to(p, i) <= spare;
        seen_end(0)
            || seen_end(m - 1)
            || runs.iter().any(|r| {
                // A run of `k` nodes: `k` spacings of rope past an end's
                // anchor, `k + 1` between a middle run's two.
                let k = (r.end - r.start) as f64;
                match (r.start.checked_sub(1), (r.end < m).then_some(r.end)) {
                    (Some(a), Some(b)) => to(p, a) + to(p, b) <= rest_spacing * (k + 1.0) + spare,
                    (Some(a), None) | (None, Some(a)) => to(p, a) <= rest_spacing * k + spare,
                    (None, None) => true,
                }
            })
    };
    points.iter().filter(|p| !reaches(p)).copied().collect()
}

/// What a tracker remembers of things beside the rope after a frame: its
/// `memory`, and the points of `cloud` no node explains that no hidden run
/// could reach ([`beyond_hidden_reach`], [`remember_not_rope`]), once the
/// rope's rest spacing is known.
pub fn remembered_beside(
    memory: &[Vec3],
    nodes: &[Vec3],
    visible: &[bool],
    cloud: &[Vec3],
    rest_spacing: Option<f64>,
    radius: f64,
) -> Vec<Vec3> {
    let mut memory = memory.to_vec();
    if let Some(spacing) = rest_spacing {
        let far = unexplained_points(nodes, cloud, explained_reach(spacing, radius));
        let beside = beyond_hidden_reach(nodes, visible, &far, spacing);
        remember_not_rope(&mut memory, &beside, spacing);
    }
    memory
}

/// `items` thinned evenly to at most [`MAX_PIECE_POINTS`].
fn thinned<T>(items: Vec<T>) -> Vec<T> {
    if items.len() <= MAX_PIECE_POINTS {
        return items;
    }
    let stride = items.len().div_ceil(MAX_PIECE_POINTS);
    items.into_iter().step_by(stride).collect()
}

/// `true` when a rope of radius `radius` whose axis runs through `line`
/// lies on `table`: the median height of its points above the plane is a
/// radius, within [`OCCLUDER_MARGIN`] (the depth a surface must be nearer
/// by to hide a rope). The median, as one point's depth is noisier than
/// that far away (a centimetre at 1.5 m).
pub fn lies_on(table: &Plane, line: &[Vec3], radius: f64) -> bool {
    let mut heights: Vec<f64> = line
        .iter()
        .map(|p| table.height(p))
        .filter(|h| h.is_finite())
        .collect();
    if heights.is_empty() {
        return false;
    }
    heights.sort_by(f64::total_cmp);
    libm::fabs(heights[heights.len() / 2] - radius) <= OCCLUDER_MARGIN
}

/// What the frame shows around the rope, for [`follow_emerged_ends`].
#[derive(Clone, Copy)]
pub struct InView<'a> {
    /// The rope-coloured points in view (the cloud).
    pub cloud: &'a [Vec3],
    /// Rope-coloured points seen beside the rope when it was wholly in
    /// view (`StepInput::not_rope`).
    pub not_rope: &'a [Vec3],
    /// Whether something hides the rope within a distance of a point
    /// (`Evidence::hidden_around`).
    pub hidden_near: &'a dyn Fn(&Vec3, f64) -> bool,
    /// Whether a piece of rope (its line) may be rope where it is: on the
    /// table ([`lies_on`]) or in the air, with a surface well behind it
    /// on both sides (`Evidence::stands_free`), not along an object's edge.
    pub on_surface: &'a dyn Fn(&[Vec3]) -> bool,
}

/// What the stage did in one frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EmergedReport {
    /// Hidden end runs laid onto a piece that came out.
    pub runs: usize,
    /// Length of the longest piece taken, metres.
    pub piece_length: f64,
    /// What a rope found short took past its ends
    /// ([`follow_rope_past_ends`]).
    pub past_ends: PastEndsReport,
}

/// A piece of rope in view that no node explains, as a polyline from one
/// tip to the other (the centroids of its points in slices across the line
/// between its tips).
#[derive(Debug, Clone, PartialEq)]
struct Piece {
    line: Vec<Vec3>,
    length: f64,
}

impl Piece {
    /// The piece from `points` (one connected set), sliced every `slice`
    /// metres along the line between its two farthest points.
    fn of(points: &[Vec3], slice: f64) -> Option<Self> {
        let farthest = |from: &Vec3| {
            points.iter().copied().max_by(|a, b| {
                (a - from)
                    .norm_squared()
                    .total_cmp(&(b - from).norm_squared())
            })
        };
        let a = farthest(points.first()?)?;
        let b = farthest(&a)?;
        let span = math::norm(&(b - a));
        if !(span > math::LENGTH_EPSILON) || !(slice > 0.0) {
            return None;
        }
        let axis = (b - a) / span;
        let bins = (libm::ceil(span / slice) as usize).max(1);
        let mut sums = alloc::vec![(Vec3::zeros(), 0usize); bins];
        for p in points {
            let k = ((p - a).dot(&axis) / slice) as usize;
            let (sum, n) = &mut sums[k.min(bins - 1)];
            *sum += p;
            *n += 1;
        }
        let mut line: Vec<Vec3> = core::iter::once(a)
            .chain(
                sums.iter()
                    .filter(|(_, n)| *n > 0)
                    .map(|(s, n)| s / *n as f64),
            )
            .chain(core::iter::once(b))
            .collect();
        line.dedup_by(|x, y| math::norm(&(*x - *y)) <= math::LENGTH_EPSILON);
        let length = polyline_length(&line);
        Some(Self { line, length })
    }

    /// The piece's line from the tip nearer `from` to the other.
    fn line_out_from(&self, from: &Vec3) -> Vec<Vec3> {
        let (first, last) = (self.line[0], self.line[self.line.len() - 1]);
        let mut line = self.line.clone();
        if (last - from).norm_squared() < (first - from).norm_squared() {
            line.reverse();
        }
        line
    }
}

/// Connected sets of `points` (their indices), linked where two are
/// within `link`.
fn connected_sets(points: &[Vec3], link: f64) -> Vec<Vec<usize>> {
    let mut set_of: Vec<Option<usize>> = alloc::vec![None; points.len()];
    let mut sets = Vec::new();
    for seed in 0..points.len() {
        if set_of[seed].is_some() {
            continue;
        }
        let id = sets.len();
        set_of[seed] = Some(id);
        let mut members = alloc::vec![seed];
        let mut next = 0;
        while next < members.len() {
            let p = points[members[next]];
            next += 1;
            for (j, q) in points.iter().enumerate() {
                if set_of[j].is_none() && (q - p).norm_squared() <= link * link {
                    set_of[j] = Some(id);
                    members.push(j);
                }
            }
        }
        sets.push(members);
    }
    sets
}

/// Lays each hidden run at an end of the rope (`known[k]` false up to an
/// end) onto rope that came out from under its occluder: a piece of the
/// `cloud` that no visible node explains (within `reach`) and part of
/// which no node does, not touching rope a visible node explains, not
/// (for the most part) where `not_rope` saw a rope-coloured thing beside
/// the rope when it was wholly in view, at least [`MIN_PIECE_SPACINGS`]
/// long, coming out of hidden space onto the surface (`hidden_near(p, r)`:
/// something hides the rope within `r` of `p`, near its near tip, not near
/// its far one; `on_surface(line)`: the piece lies on the table or stands
/// free in the air), and which the run's rest length (`rest_spacing`
/// per node, give or take a spacing or [`REST_LENGTH_SLACK`] of the rope,
/// the larger) can reach along with the piece. The run's new curve keeps its
/// old shape from the anchor and is pulled straight to the piece's near
/// tip (`length::taut_from_pulled_end`) with what the piece leaves of its rest
/// length, then runs along the piece; its nodes are placed `rest_spacing`
/// apart on it. The longest piece that fits is taken, one per run.
pub fn follow_emerged_ends(
    nodes: &mut [Vec3],
    known: &[bool],
    view: &InView<'_>,
    reach: f64,
    rest_spacing: f64,
) -> EmergedReport {
    let InView {
        cloud,
        not_rope,
        hidden_near,
        on_surface,
    } = *view;
    let mut report = EmergedReport::default();
    let m = nodes.len();
    if known.len() != m
        || m < 3
        || !(reach > 0.0)
        || !(rest_spacing > 0.0)
        || !known.iter().any(|&k| k)
        || !nodes.iter().all(math::is_finite)
    {
        return report;
    }
    let head = known.iter().take_while(|&&k| !k).count();
    let tail = known.iter().rev().take_while(|&&k| !k).count();
    if head == 0 && tail == 0 {
        return report;
    }
    let link = PIECE_LINK_SPACINGS * rest_spacing;
    // Each point: explained by a visible node (seen), or not; and of the
    // latter, whether any node explains it. Points only hidden nodes
    // explain (a hidden run left at the old exit) stay in their piece.
    let mut candidates = Vec::new();
    let mut near = NearNodes::new(nodes, reach);
    for p in cloud.iter().filter(|p| math::is_finite(p)) {
        if !near.any(p, |k| known[k]) {
            candidates.push((*p, !near.any(p, |_| true)));
        }
    }
    if !candidates.iter().any(|&(_, new)| new) {
        return report;
    }
    // Only now (rarely) the points the visible nodes explain.
    let seen: Vec<Vec3> = cloud
        .iter()
        .filter(|p| math::is_finite(p) && near.any(p, |k| known[k]))
        .copied()
        .collect();
    let candidates = thinned(candidates);
    let points: Vec<Vec3> = candidates.iter().map(|&(p, _)| p).collect();
    let mut pieces: Vec<Piece> = connected_sets(&points, link)
        .into_iter()
        // Something no node explains yet.
        .filter(|set| set.iter().any(|&i| candidates[i].1))
        .map(|set| set.into_iter().map(|i| points[i]).collect::<Vec<Vec3>>())
        // Rope within reach of what the visible nodes explain may be
        // theirs, moved farther than EM followed: not a hidden end's.
        .filter(|set| {
            !set.iter()
                .any(|p| seen.iter().any(|q| (p - q).norm_squared() <= reach * reach))
        })
        // Nor is a thing seen beside the rope when it was wholly in view.
        .filter(|set| !mostly_not_rope(set, not_rope, rest_spacing))
        .filter_map(|set| Piece::of(&set, link))
        .filter(|piece| piece.length >= MIN_PIECE_SPACINGS * rest_spacing)
        .collect();
    // Longest first: each run takes the longest piece that fits it.
    pieces.sort_by(|a, b| b.length.total_cmp(&a.length));
    let mut taken = alloc::vec![false; pieces.len()];
    let runs = [(head, true), (tail, false)];
    let slack = length_slack(rest_spacing, m);
    for (count, at_head) in runs.into_iter().filter(|&(c, _)| c > 0 && c < m) {
        let mut curve = end_run_from_anchor(nodes, count, at_head);
        let anchor = curve[0];
        let rest = rest_spacing * count as f64;
        let choice = pieces
            .iter()
            .enumerate()
            .filter(|&(i, _)| !taken[i])
            .find_map(|(i, piece)| {
                fits(
                    piece,
                    &anchor,
                    rest + slack,
                    rest_spacing,
                    hidden_near,
                    on_surface,
                )
                .map(|line| (i, piece.length, line))
            });
        let Some((i, length, line)) = choice else {
            continue;
        };
        curve.push(line[0]);
        let mut curve = taut_from_pulled_end(&curve, rest - length);
        curve.extend_from_slice(&line[1..]);
        let placed = along(&RopeCurve::polyline(&curve), count, rest_spacing);
        if placed.len() != count || !placed.iter().all(math::is_finite) {
            continue;
        }
        taken[i] = true;
        report.runs += 1;
        report.piece_length = report.piece_length.max(length);
        set_end_run(nodes, count, at_head, placed);
    }
    report
}

/// Whether a run anchored at `anchor` with `rest` metres of rope (its slack
/// included) can have come out as `piece`: the rope from the anchor to the
/// piece's near tip and along the piece is no longer than the run, and
/// the piece comes out of hidden space onto the surface: there is hidden
/// space within [`EXIT_GAP_SPACINGS`] of its near tip and none around its
/// far tip (a bend of the run that bulges out and back under has hidden
/// space at both), and it lies on the surface or stands free (a box's
/// dark lower edge stands above the table, against the box's face). Its
/// line from the near tip when it can.
fn fits(
    piece: &Piece,
    anchor: &Vec3,
    rest: f64,
    rest_spacing: f64,
    hidden_near: &dyn Fn(&Vec3, f64) -> bool,
    on_surface: &dyn Fn(&[Vec3]) -> bool,
) -> Option<Vec<Vec3>> {
    let line = piece.line_out_from(anchor);
    let (near, far) = (line[0], line[line.len() - 1]);
    let gap = math::norm(&(anchor - near));
    if gap + piece.length > rest {
        return None;
    }
    let exit = EXIT_GAP_SPACINGS * rest_spacing;
    (hidden_near(&near, exit) && !hidden_near(&far, exit) && on_surface(&line)).then_some(line)
}

/// What [`follow_rope_past_ends`] took, metres of rope added at each end.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PastEndsReport {
    /// Added before node 0 (the piece and the gap to it).
    pub head: f64,
    /// Added after node `M - 1`.
    pub tail: f64,
}

/// A rope found shorter than its rest length follows rope in view past its
/// ends (issue 28): after a fast pull EM leaves the pulled end behind, its
/// nodes bunched along what they saw, and the rope that went on lies in
/// view with no node near it (past a rope-coloured box it went under, or
/// where a hand that hid it has gone). A piece of the `cloud` that no
/// node explains (farther than `reach` from every node; not, for the most
/// part, a thing `not_rope` saw beside the rope), at least
/// [`MIN_PIECE_SPACINGS`] long, every point of which lies nearest an end
/// node or a node of the hidden run at that end, on the surface
/// (`on_surface`), and which the length the rope lacks can reach (the gap
/// from the end node and the piece together no longer than the shortfall
/// against `rest_length`, give or take a spacing or [`REST_LENGTH_SLACK`]
/// of the rope, the larger) is where that end went: the polyline goes on
/// from the end node to the piece's near tip and along it. The longest
/// such piece at each end; the head first, the tail with what is left.
/// Only a state that sees most of its rope ([`crate::visibility::sees_most`])
/// follows: one that sees less is a guess, and a rope that jumped away
/// from it is found again by the recovery (rope no node explains is its
/// evidence), not taken piece by piece. `nodes` is the polyline of the
/// rope's nodes (with what [`super::length::extend_short_ends`] added at
/// a seen end), `known` their visibility (one per node), `rest_spacing`
/// the rest length over the node count less one.
/// Returns the polyline with the pieces (to be spread evenly over the
/// rope's nodes: the bunched ones slide along it) and what was added.
pub fn follow_rope_past_ends(
    nodes: &[Vec3],
    known: &[bool],
    view: &InView<'_>,
    reach: f64,
    rest_spacing: f64,
) -> (Vec<Vec3>, PastEndsReport) {
    let mut report = PastEndsReport::default();
    let m = nodes.len();
    let count = known.len();
    let rest_length = rest_spacing * count.saturating_sub(1) as f64;
    if m < 3
        || !sees_most(known)
        || !(reach > 0.0)
        || !(rest_length > 0.0)
        || !nodes.iter().all(math::is_finite)
    {
        return (nodes.to_vec(), report);
    }
    let hidden = HiddenEnds::of(known);
    let mut lacking = shortfall(nodes, rest_length);
    if !(lacking > MIN_SHORTFALL_SPACINGS * rest_spacing) {
        return (nodes.to_vec(), report);
    }
    let link = PIECE_LINK_SPACINGS * rest_spacing;
    let far = unexplained_points(nodes, view.cloud, reach);
    if far.is_empty() {
        return (nodes.to_vec(), report);
    }
    // The nodes an end's piece may lie nearest: the end node and the
    // hidden run at that end.
    let (head, tail) = (hidden.head.max(1), hidden.tail.max(1));
    let nearest = |p: &Vec3| {
        (0..m)
            .map(|k| (k, (p - nodes[k]).norm_squared()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(0, |(k, _)| k)
    };
    let mut pieces: [Vec<Piece>; 2] = [Vec::new(), Vec::new()];
    for set in connected_sets(&far, link) {
        let points: Vec<Vec3> = set.into_iter().map(|i| far[i]).collect();
        if mostly_not_rope(&points, view.not_rope, rest_spacing) {
            continue;
        }
        let ends: Vec<usize> = points.iter().map(nearest).collect();
        let side = if ends.iter().all(|&k| k < head) {
            0
        } else if ends.iter().all(|&k| k + tail >= m) {
            1
        } else {
            continue;
        };
        if let Some(piece) = Piece::of(&points, link)
            .filter(|piece| piece.length >= MIN_PIECE_SPACINGS * rest_spacing)
        {
            pieces[side].push(piece);
        }
    }
    let slack = length_slack(rest_spacing, count);
    let mut taken: [Option<Vec<Vec3>>; 2] = [None, None];
    for (side, end) in [(0, nodes[0]), (1, nodes[m - 1])] {
        pieces[side].sort_by(|a, b| b.length.total_cmp(&a.length));
        let choice = pieces[side].iter().find_map(|piece| {
            let line = piece.line_out_from(&end);
            let added = math::norm(&(line[0] - end)) + piece.length;
            (added <= lacking + slack && (view.on_surface)(&line)).then_some((line, added))
        });
        if let Some((line, added)) = choice {
            lacking -= added;
            match side {
                0 => report.head = added,
                _ => report.tail = added,
            }
            taken[side] = Some(line);
        }
    }
    let [before, after] = taken;
    let mut out = Vec::with_capacity(m);
    out.extend(before.into_iter().flat_map(|line| line.into_iter().rev()));
    out.extend_from_slice(nodes);
    out.extend(after.into_iter().flatten());
    (out, report)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Nodes 1 cm apart along x at depth 0.6, the first `hidden` hidden.
    fn rope(m: usize, hidden: usize) -> (Vec<Vec3>, Vec<bool>) {
        let nodes = (0..m)
            .map(|i| Vec3::new(0.01 * i as f64, 0.0, 0.6))
            .collect();
        (nodes, (0..m).map(|i| i >= hidden).collect())
    }

    /// `hides` looked at round a circle of radius `r` about `p` (eight
    /// directions, at half and the whole radius), as
    /// `Evidence::hidden_around` does.
    fn around(hides: impl Fn(&Vec3) -> bool) -> impl Fn(&Vec3, f64) -> bool {
        move |p: &Vec3, r: f64| {
            (0..8).any(|k| {
                let a = core::f64::consts::TAU * k as f64 / 8.0;
                let dir = Vec3::new(libm::cos(a), libm::sin(a), 0.0);
                [0.5, 1.0].iter().any(|s| hides(&(p + dir * (r * s))))
            })
        }
    }

    /// [`follow_emerged_ends`] with a reach of 1.5 cm and a rest spacing
    /// of 1 cm.
    fn lay(
        nodes: &mut [Vec3],
        known: &[bool],
        cloud: &[Vec3],
        not_rope: &[Vec3],
        hidden_near: &dyn Fn(&Vec3, f64) -> bool,
        on_surface: &dyn Fn(&[Vec3]) -> bool,
    ) -> EmergedReport {
        let view = InView {
            cloud,
            not_rope,
            hidden_near,
            on_surface,
        };
        follow_emerged_ends(nodes, known, &view, 0.015, 0.01)
    }

    /// Every piece lies on the table.
    fn on_table(_: &[Vec3]) -> bool {
        true
    }

    /// Points every millimetre from `a` to `b`.
    fn points(a: Vec3, b: Vec3) -> Vec<Vec3> {
        let n = (math::norm(&(b - a)) / 0.001) as usize;
        (0..=n)
            .map(|k| a + (b - a) * (k as f64 / n as f64))
            .collect()
    }

    #[test]
    fn a_hidden_end_pulled_out_from_under_its_occluder_is_laid_onto_the_rope_that_came_out() {
        // Twenty nodes 1 cm apart, the first eight hidden under an occluder
        // (x < 0.075, y < 0.048). The end was pulled out sideways: 2.5 cm of
        // rope now lie in view from (0.07, 0.05) to (0.07, 0.075).
        let (mut nodes, known) = rope(20, 8);
        let mut cloud = points(Vec3::new(0.08, 0.0, 0.6), Vec3::new(0.19, 0.0, 0.6));
        cloud.extend(points(
            Vec3::new(0.07, 0.05, 0.6),
            Vec3::new(0.07, 0.075, 0.6),
        ));
        let hides = around(|p: &Vec3| p.x < 0.075 && p.y < 0.048);
        let r = lay(&mut nodes, &known, &cloud, &[], &hides, &on_table);
        assert_eq!(r.runs, 1);
        assert!((r.piece_length - 0.025).abs() < 1e-9, "{}", r.piece_length);
        // Eight spacings of rope from the anchor (node 8 at x = 0.08): 5.5 cm
        // under the occluder to the piece, then its 2.5 cm; the tip on the
        // piece's far end.
        assert!(
            (nodes[0] - Vec3::new(0.07, 0.075, 0.6)).norm() < 1e-6,
            "{:?}",
            nodes[0]
        );
        assert!(
            (nodes[2] - Vec3::new(0.07, 0.055, 0.6)).norm() < 1e-6,
            "{:?}",
            nodes[2]
        );
        // (1 cm of arc apart; the chord across the corner is shorter.)
        for w in nodes[..=8].windows(2) {
            let d = math::norm(&(w[1] - w[0]));
            assert!(d <= 0.01 + 1e-9 && d > 0.005, "{d}");
        }
        // The visible nodes are untouched.
        assert!(nodes[8..]
            .iter()
            .enumerate()
            .all(|(k, p)| (p.x - 0.01 * (k + 8) as f64).abs() < 1e-12));
    }

    #[test]
    fn a_finely_spaced_ropes_end_may_need_its_rest_lengths_error_more_than_a_spacing() {
        // As above, with 4.5 cm of rope come out: 5.1 cm from the anchor to
        // the piece and the piece need 1.6 cm more than the run's eight
        // spacings. On 48 nodes that is within the rest length's error
        // (4.3 % of 0.47 m, 2.0 cm); on 20 nodes (0.19 m) a spacing is more
        // than that, and 1 cm is too little.
        for (m, taken) in [(48, 1), (20, 0)] {
            let (mut nodes, known) = rope(m, 8);
            let far = 0.01 * (m - 1) as f64;
            let mut cloud = points(Vec3::new(0.08, 0.0, 0.6), Vec3::new(far, 0.0, 0.6));
            cloud.extend(points(
                Vec3::new(0.07, 0.05, 0.6),
                Vec3::new(0.07, 0.095, 0.6),
            ));
            let hides = around(|p: &Vec3| p.x < 0.075 && p.y < 0.048);
            let r = lay(&mut nodes, &known, &cloud, &[], &hides, &on_table);
            assert_eq!(r.runs, taken, "{m} nodes");
        }
    }

    #[test]
    fn rope_in_view_that_is_not_beside_hidden_space_or_out_of_reach_is_left() {
        let (nodes, known) = rope(20, 8);
        let cloud = points(Vec3::new(0.03, 0.05, 0.6), Vec3::new(0.03, 0.08, 0.6));
        // Nothing hides the rope near the piece: a distractor on the table.
        let mut a = nodes.clone();
        let none = |_: &Vec3, _: f64| false;
        assert_eq!(lay(&mut a, &known, &cloud, &[], &none, &on_table).runs, 0);
        assert_eq!(a, nodes);
        // Beyond what eight spacings of rope can reach.
        let far = points(Vec3::new(0.03, 0.09, 0.6), Vec3::new(0.03, 0.13, 0.6));
        let hides = around(|p: &Vec3| p.x < 0.075 && p.y < 0.095);
        assert_eq!(lay(&mut a, &known, &far, &[], &hides, &on_table).runs, 0);
        // Out of the occluder at its near tip only, within reach, but
        // shorter than a spacing.
        let short = points(Vec3::new(0.07, 0.05, 0.6), Vec3::new(0.07, 0.056, 0.6));
        let exit = around(|p: &Vec3| p.x < 0.075 && p.y < 0.048);
        assert_eq!(lay(&mut a, &known, &short, &[], &exit, &on_table).runs, 0);
        assert_eq!(a, nodes);
    }

    #[test]
    fn rope_that_touches_what_a_visible_node_explains_is_not_a_hidden_ends() {
        // The visible rope moved up faster than its nodes: its new points
        // lie beyond reach but join points the visible nodes still explain.
        let (mut nodes, known) = rope(20, 8);
        let mut cloud = points(Vec3::new(0.12, 0.01, 0.6), Vec3::new(0.12, 0.06, 0.6));
        cloud.extend(points(Vec3::new(0.08, 0.0, 0.6), Vec3::new(0.19, 0.0, 0.6)));
        let before = nodes.clone();
        let hides = around(|p: &Vec3| p.x < 0.125);
        assert_eq!(
            lay(&mut nodes, &known, &cloud, &[], &hides, &on_table).runs,
            0
        );
        assert_eq!(nodes, before);
    }

    #[test]
    fn a_bend_that_bulges_out_and_back_under_or_a_thing_seen_before_is_not_an_end_that_came_out() {
        // The piece of the first test, but the occluder also covers y > 0.078:
        // hidden space around both its tips, as a bend of the run bulging out
        // of a rectangle's edge and back under, or a dark edge along a box.
        let (nodes, known) = rope(20, 8);
        let mut cloud = points(Vec3::new(0.08, 0.0, 0.6), Vec3::new(0.19, 0.0, 0.6));
        let piece = points(Vec3::new(0.07, 0.05, 0.6), Vec3::new(0.07, 0.075, 0.6));
        cloud.extend_from_slice(&piece);
        let bulge = around(|p: &Vec3| p.x < 0.075 && (p.y < 0.048 || p.y > 0.078));
        let mut a = nodes.clone();
        assert_eq!(lay(&mut a, &known, &cloud, &[], &bulge, &on_table).runs, 0);
        // Out of an occluder only at its near tip, but seen beside the rope
        // when it was wholly in view: a thing, not rope.
        let exit = around(|p: &Vec3| p.x < 0.075 && p.y < 0.048);
        let mut seen_before = Vec::new();
        remember_not_rope(&mut seen_before, &piece, 0.01);
        assert!(seen_before.len() < piece.len(), "kept one point per 2.5 mm");
        let r = lay(&mut a, &known, &cloud, &seen_before, &exit, &on_table);
        assert_eq!(r.runs, 0);
        assert_eq!(a, nodes);
        // Its far tip not on the surface around it (a box's dark lower edge,
        // standing above the table): not rope that came out.
        let floating = |_: &[Vec3]| false;
        let r = lay(&mut a, &known, &cloud, &[], &exit, &floating);
        assert_eq!(r.runs, 0);
        // Half of it seen before is not enough to leave it.
        let half: Vec<Vec3> = seen_before
            .iter()
            .copied()
            .filter(|p| p.y < 0.058)
            .collect();
        let r = lay(&mut a, &known, &cloud, &half, &exit, &on_table);
        assert_eq!(r.runs, 1);
    }

    /// [`follow_rope_past_ends`] with a reach of 1.5 cm, a rest spacing of
    /// 1 cm and 20 nodes (a rest length of 19 cm), every piece on the
    /// table and nothing hidden around.
    fn past(
        nodes: &[Vec3],
        hidden: HiddenEnds,
        cloud: &[Vec3],
        not_rope: &[Vec3],
    ) -> (Vec<Vec3>, PastEndsReport) {
        let view = InView {
            cloud,
            not_rope,
            hidden_near: &|_: &Vec3, _: f64| false,
            on_surface: &on_table,
        };
        let known: Vec<bool> = (0..20)
            .map(|i| i >= hidden.head && i + hidden.tail < 20)
            .collect();
        follow_rope_past_ends(nodes, &known, &view, 0.015, 0.01)
    }

    /// Twenty nodes bunched 8 mm apart along x from 0 (15.2 cm of a 19 cm
    /// rope: 3.8 cm held nowhere).
    fn bunched() -> Vec<Vec3> {
        (0..20)
            .map(|i| Vec3::new(0.008 * i as f64, 0.0, 0.6))
            .collect()
    }

    const SEEN: HiddenEnds = HiddenEnds { head: 0, tail: 0 };

    /// The bunched rope's cloud (x from 0 to 15.2 cm) and a rope-coloured
    /// line from `a` to `b` beside it.
    fn bunched_beside(a: Vec3, b: Vec3) -> Vec<Vec3> {
        let mut cloud = points(Vec3::new(0.0, 0.0, 0.6), Vec3::new(0.152, 0.0, 0.6));
        cloud.extend(points(a, b));
        cloud
    }

    /// The bunched rope with `hidden` ends follows nothing in `cloud`: its
    /// polyline comes back as it was.
    fn not_followed(hidden: HiddenEnds, cloud: &[Vec3], not_rope: &[Vec3]) {
        let (line, report) = past(&bunched(), hidden, cloud, not_rope);
        assert_eq!((line.len(), report), (20, PastEndsReport::default()));
    }

    #[test]
    fn a_short_rope_follows_rope_in_view_past_its_end() {
        // The rope goes on in view to x = 19 cm: past node 19 (15.2) and
        // its reach (16.7) lie 2.3 cm of rope no node explains.
        let cloud = points(Vec3::new(0.0, 0.0, 0.6), Vec3::new(0.19, 0.0, 0.6));
        let (line, report) = past(&bunched(), SEEN, &cloud, &[]);
        assert_eq!(report.head, 0.0);
        assert!((report.tail - 0.038).abs() < 1e-3, "{report:?}");
        let tip = line[line.len() - 1];
        assert!((tip - Vec3::new(0.19, 0.0, 0.6)).norm() < 1e-3, "{tip:?}");
        assert!((polyline_length(&line) - 0.19).abs() < 1e-3);
        // The same rope past its first end instead.
        let cloud = points(Vec3::new(-0.038, 0.0, 0.6), Vec3::new(0.152, 0.0, 0.6));
        let (line, report) = past(&bunched(), SEEN, &cloud, &[]);
        assert!(report.head > 0.037 && report.tail == 0.0, "{report:?}");
        assert!(
            (line[0] - Vec3::new(-0.038, 0.0, 0.6)).norm() < 1e-3,
            "{:?}",
            line[0]
        );
    }

    #[test]
    fn a_rope_at_its_rest_length_or_rope_it_cannot_reach_is_not_followed() {
        // At rest, 1 cm apart: nothing is held nowhere, the rope past the
        // end is something else.
        let at_rest: Vec<Vec3> = (0..20)
            .map(|i| Vec3::new(0.01 * i as f64, 0.0, 0.6))
            .collect();
        let cloud = points(Vec3::new(0.0, 0.0, 0.6), Vec3::new(0.23, 0.0, 0.6));
        let (line, report) = past(&at_rest, SEEN, &cloud, &[]);
        assert_eq!((line.len(), report), (20, PastEndsReport::default()));
        // Bunched, but the rope past the end is 9.8 cm: more than the 3.8
        // held nowhere and a spacing.
        let cloud = points(Vec3::new(0.0, 0.0, 0.6), Vec3::new(0.25, 0.0, 0.6));
        not_followed(SEEN, &cloud, &[]);
    }

    #[test]
    fn rope_beside_the_middle_or_a_thing_seen_before_is_not_followed() {
        // 3 cm of rope-coloured line 2 cm beside nodes 6-10: nearest the
        // middle, not an end.
        let beside = bunched_beside(Vec3::new(0.05, 0.02, 0.6), Vec3::new(0.08, 0.02, 0.6));
        not_followed(SEEN, &beside, &[]);
        // 2 cm of it 2 cm beside nodes 17-19: partly nearest the end, partly
        // the middle (within the length held nowhere).
        let beside = bunched_beside(Vec3::new(0.135, 0.02, 0.6), Vec3::new(0.155, 0.02, 0.6));
        not_followed(SEEN, &beside, &[]);
        // Past the end, but where a rope-coloured thing was seen beside
        // the rope.
        let cloud = points(Vec3::new(0.0, 0.0, 0.6), Vec3::new(0.19, 0.0, 0.6));
        let seen_before = points(Vec3::new(0.165, 0.0, 0.6), Vec3::new(0.19, 0.0, 0.6));
        not_followed(SEEN, &cloud, &seen_before);
        // Nearest a node of the hidden run at that end: followed.
        let tail_hidden = HiddenEnds { head: 0, tail: 3 };
        let (_, report) = past(&bunched(), tail_hidden, &cloud, &[]);
        assert!(report.tail > 0.037, "{report:?}");
        // A state that sees 9 of its 20 nodes is a guess: it does not
        // follow (a rope that jumped is the recovery's).
        not_followed(HiddenEnds { head: 0, tail: 11 }, &cloud, &[]);
    }

    #[test]
    fn only_points_no_hidden_run_can_reach_are_beside_the_rope() {
        // Nodes 1 cm apart, at rest 1.25 cm apart: the rope is slack, its
        // polyline 19 cm against 23.75 (4.75 cm held nowhere, which any
        // end or run may take). 0-2 hidden (3.75 + 4.75 = 8.5 cm of rope
        // past node 3), 10-11 hidden (8.5 cm between nodes 9 and 12, 3 cm
        // apart); the last end seen (4.75 cm past node 19).
        let (nodes, mut known) = rope(20, 3);
        known[10] = false;
        known[11] = false;
        let at = |x: f64, y: f64| Vec3::new(x, y, 0.6);
        let points = [
            at(0.03, 0.0849),
            at(0.03, 0.0851),
            at(0.105, 0.039),
            at(0.105, 0.041),
            at(0.19, 0.047),
            at(0.19, 0.048),
        ];
        let beside = beyond_hidden_reach(&nodes, &known, &points, 0.0125);
        // 8.49 cm from node 3: the end's rope reaches; 8.51: not. Via
        // nodes 9 and 12: 2 x 4.18 cm = 8.36 cm reaches, 2 x 4.37 does
        // not. Past the seen end: 4.7 cm reaches, 4.8 does not.
        assert_eq!(beside, alloc::vec![points[1], points[3], points[5]]);
        assert!(beyond_hidden_reach(&nodes, &known[..5], &points, 0.01).is_empty());
        // Nothing hidden and nothing held nowhere (at rest 1 cm apart):
        // everything unexplained is beside the rope.
        assert_eq!(
            beyond_hidden_reach(&nodes, &[true; 20], &points, 0.01),
            points.to_vec()
        );
    }

    #[test]
    fn the_memory_of_things_beside_the_rope_keeps_one_point_per_place_up_to_its_cap() {
        let mut memory = Vec::new();
        let line = points(Vec3::new(0.0, 0.0, 0.6), Vec3::new(0.1, 0.0, 0.6));
        remember_not_rope(&mut memory, &line, 0.01);
        // Points at least 2.5 mm apart: 1 mm steps, every third kept.
        assert_eq!(memory.len(), 34);
        let again = memory.clone();
        remember_not_rope(&mut memory, &line, 0.01);
        assert_eq!(memory, again);
        let far = points(Vec3::new(0.0, 0.0, 0.6), Vec3::new(10.0, 0.0, 0.6));
        remember_not_rope(&mut memory, &far, 0.01);
        assert_eq!(memory.len(), MAX_NOT_ROPE_POINTS);
        let mut none = Vec::new();
        remember_not_rope(&mut none, &line, f64::NAN);
        assert!(none.is_empty());
    }

    #[test]
    fn random_and_non_finite_inputs_never_panic_and_leave_finite_nodes() {
        use crate::rng::SplitMix64;
        let mut rng = SplitMix64::new(43);
        let odd = [f64::NAN, f64::INFINITY, -f64::INFINITY, 0.0, 1e300];
        for round in 0..300 {
            let m = 3 + rng.below(20) as usize;
            let point = |rng: &mut SplitMix64| {
                let mut p = Vec3::new(
                    rng.range(-0.2, 0.2),
                    rng.range(-0.2, 0.2),
                    rng.range(0.3, 0.9),
                );
                if rng.below(20) == 0 {
                    p[rng.below(3) as usize] = odd[rng.below(5) as usize];
                }
                p
            };
            let mut nodes: Vec<Vec3> = (0..m).map(|_| point(&mut rng)).collect();
            let known: Vec<bool> = (0..m).map(|_| rng.below(2) == 0).collect();
            let cloud: Vec<Vec3> = (0..rng.below(400)).map(|_| point(&mut rng)).collect();
            let not_rope: Vec<Vec3> = (0..rng.below(40)).map(|_| point(&mut rng)).collect();
            let (reach, spacing) = (rng.range(0.0, 0.05), rng.range(0.0, 0.05));
            let hides = around(|p: &Vec3| p.x < 0.0);
            let finite_before = nodes.iter().all(math::is_finite);
            let before = nodes.clone();
            let view = InView {
                cloud: &cloud,
                not_rope: &not_rope,
                hidden_near: &hides,
                on_surface: &on_table,
            };
            let r = follow_emerged_ends(&mut nodes, &known, &view, reach, spacing);
            if finite_before {
                assert!(nodes.iter().all(math::is_finite), "round {round}");
            } else {
                assert_eq!(r.runs, 0, "round {round}");
                assert_eq!(nodes.len(), before.len());
            }
            let beside = beyond_hidden_reach(&before, &known, &cloud, spacing);
            assert!(beside.len() <= cloud.len());
            let mut memory = not_rope.clone();
            remember_not_rope(&mut memory, &cloud, spacing);
            assert!(memory.len() <= MAX_NOT_ROPE_POINTS.max(not_rope.len()));
        }
    }

    #[test]
    fn a_piece_lies_on_the_table_when_its_median_height_is_a_radius() {
        // A table 0.6 m away facing the camera; a rope of 5 mm radius.
        let table = Plane {
            normal: Vec3::new(0.0, 0.0, -1.0),
            offset: -0.6,
        };
        let at = |z: f64| points(Vec3::new(0.0, 0.0, z), Vec3::new(0.05, 0.0, z));
        assert!(lies_on(&table, &at(0.595), 0.005));
        // A box's edge 2 cm above the table; one noisy point does not count.
        assert!(!lies_on(&table, &at(0.58), 0.005));
        let mut noisy = at(0.595);
        noisy[3].z = 0.55;
        assert!(lies_on(&table, &noisy, 0.005));
        assert!(!lies_on(&table, &[], 0.005));
        assert!(!lies_on(&table, &[Vec3::new(f64::NAN, 0.0, 0.6)], 0.005));
    }

    #[test]
    fn nothing_to_do_on_bad_inputs() {
        let (mut nodes, known) = rope(6, 2);
        let cloud = points(Vec3::new(0.0, 0.05, 0.6), Vec3::new(0.0, 0.08, 0.6));
        let all = |_: &Vec3, _: f64| true;
        let before = nodes.clone();
        for (reach, spacing) in [
            (0.0, 0.01),
            (0.015, 0.0),
            (f64::NAN, 0.01),
            (0.015, f64::NAN),
        ] {
            assert_eq!(
                follow_emerged_ends(
                    &mut nodes,
                    &known,
                    &InView {
                        cloud: &cloud,
                        not_rope: &[],
                        hidden_near: &all,
                        on_surface: &on_table
                    },
                    reach,
                    spacing
                )
                .runs,
                0
            );
        }
        assert_eq!(
            lay(&mut nodes, &known[..5], &cloud, &[], &all, &on_table).runs,
            0
        );
        assert_eq!(
            lay(&mut nodes, &[false; 6], &cloud, &[], &all, &on_table).runs,
            0
        );
        assert_eq!(
            lay(&mut nodes, &[true; 6], &cloud, &[], &all, &on_table).runs,
            0
        );
        assert_eq!(nodes, before);
        let mut nan = nodes.clone();
        nan[3].x = f64::NAN;
        assert_eq!(lay(&mut nan, &known, &cloud, &[], &all, &on_table).runs, 0);
    }
}
