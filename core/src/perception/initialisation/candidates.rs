//! Rope-shaped evidence: each shape's walks cut where the width or the
//! depth jumps, each piece tested as a rope would be (thin, of even width,
//! long, smooth), and the pieces that pass joined end to end into the
//! candidates for the whole rope.

use alloc::vec;
use alloc::vec::Vec;

use super::graph::{angle, hermite, SkeletonGraph};
use super::lift::{depths_along, line_through, resolve_crossings, NO_ZONE};
use super::report::{NotRope, SetAside};
use super::skeleton::{Grid, Shape};
use crate::math::{Vec2, Vec3};
use crate::perception::camera::{depth_noise, CameraIntrinsics};
use crate::perception::frame::Frame;
use crate::perception::point_cloud::CloudSettings;
use crate::perception::segmentation::Mask;
use crate::polyline::polyline_length;

/// A point whose width exceeds this multiple of its walk's lower-quartile
/// width (plus [`WIDTH_SLACK_PX`]) belongs to something thicker the rope
/// touches (a phone, a hand): the walk is cut there.
pub const THICK_RATIO: f64 = 2.0;
/// Pixels of width a thin line's mask may gain or lose at its edges.
pub const WIDTH_SLACK_PX: f64 = 1.5;
/// A rope's width is even: this share of its points lie within
/// [`EVEN_TOLERANCE`] of its median width (plus [`WIDTH_SLACK_PX`]).
pub const MIN_EVEN_SHARE: f64 = 0.75;
/// Relative tolerance of the even-width test (perspective across a tilted
/// view changes a rope's width by up to a third).
pub const EVEN_TOLERANCE: f64 = 0.5;
/// Shortest piece of rope worth joining, in its own widths (a stretch of
/// rope between two patches of glare).
pub const MIN_FRAGMENT_ELONGATION: f64 = 3.0;
/// Shortest rope, in its own widths: a rope is at least ten times longer
/// than it is thick (a finger is four or five).
pub const MIN_ROPE_ELONGATION: f64 = 10.0;
/// Sharpest turn between chords one width long, degrees: a rope folded
/// flat turns through 115 degrees over its width, no more.
pub const MAX_TURN_PER_WIDTH_DEGREES: f64 = 120.0;
/// Thinnest and thickest rope without a prior, metres.
pub const ROPE_DIAMETER_RANGE: (f64, f64) = (0.001, 0.1);
/// A prior diameter `d` accepts widths from `d / k` to `k d`: the mask of a
/// thin rope loses or gains a pixel at each edge.
pub const DIAMETER_PRIOR_FACTOR: f64 = 2.0;
/// Largest angle, degrees, between a fragment's end direction and the gap
/// to the next one for the two to be joined.
pub const MAX_JOIN_ANGLE_DEGREES: f64 = 45.0;
/// Widest gap joined regardless of the fragments' lengths, in rope diameters
/// (an occluder a few widths across: a pen over a thin cable).
pub const JOIN_GAP_DIAMETERS: f64 = 6.0;
/// Widest gap joined, as a fraction of the shorter of the two fragments
/// (a box over the middle of a rope).
pub const JOIN_GAP_FRACTION: f64 = 0.5;
/// Largest ratio of two fragments' diameters for them to be one rope.
pub const JOIN_DIAMETER_RATIO: f64 = 1.6;

/// Whether two measured diameters can be one rope's (within
/// [`JOIN_DIAMETER_RATIO`]; `false` for an unmeasured one: not positive
/// or not a number, which `f64::max` would pass over).
pub fn one_rope_thick(a: f64, b: f64) -> bool {
    a > 0.0 && b > 0.0 && a.max(b) / a.min(b) <= JOIN_DIAMETER_RATIO
}
/// Fewest points a piece must have to be measured at all.
const MIN_PIECE_POINTS: usize = 4;
/// Longest extension of a skeleton end towards its shape's tip, pixels.
const MAX_END_EXTENSION: usize = 60;
/// Pixels back from a skeleton end used for the direction of its extension.
const END_DIRECTION_PIXELS: usize = 8;
/// A change of depth between neighbouring points of a path larger than
/// this many depth-noise deviations (plus [`DEPTH_JUMP_SLOPE`] times their
/// distance across the view) is two things touching in the image.
const DEPTH_JUMP_SIGMAS: f64 = 6.0;
/// Steepest a rope rises between two points of a path, as depth per
/// distance across the view (72 degrees).
const DEPTH_JUMP_SLOPE: f64 = 3.0;

/// What a piece is measured against: the frame's depth, or nothing (image only).
#[derive(Clone, Copy)]
pub(super) struct Metric<'a> {
    pub frame: &'a Frame<'a>,
    pub camera: &'a CameraIntrinsics,
    pub cloud: &'a CloudSettings,
}

/// A stretch of one shape's skeleton measured as a rope.
#[derive(Debug, Clone)]
pub(super) struct Piece {
    pub points: Vec<Vec2>,
    pub widths: Vec<f64>,
    pub zones: Vec<u32>,
    /// Depth at each point (empty without depth).
    pub depths: Vec<Option<f64>>,
    /// Label of its shape.
    pub label: u32,
    /// Mask pixels it stands for (its shape's, when it is the shape's only piece).
    pub pixels: f64,
    /// Median width, pixels.
    pub width_px: f64,
    /// Length along the image, pixels.
    pub length_px: f64,
    /// The unpushed line through it (metres, or pixels with z = 0).
    pub line: Vec<Vec3>,
    /// Length, metres (pixels without depth).
    pub length: f64,
    /// Diameter, metres (pixels without depth).
    pub diameter: f64,
}

/// The pieces of every shape that pass the rope test, and the shapes none
/// of whose pieces did.
pub(super) fn rope_pieces(
    shapes: &[Shape],
    labels: &[u32],
    mask: &Mask,
    metric: Option<Metric<'_>>,
    diameter_prior: Option<f64>,
) -> (Vec<Piece>, Vec<SetAside>) {
    let mut kept = Vec::new();
    let mut set_aside = Vec::new();
    let mut zone_base = 0u32;
    for shape in shapes {
        let centre = shape.centre(mask.width);
        let aside = |reason| SetAside {
            pixels: shape.pixels.len(),
            centre: [centre.x, centre.y],
            reason,
        };
        let mut grid = Grid::around(&shape.pixels, mask.width);
        grid.thin();
        grid.prune_spurs();
        let graph = match SkeletonGraph::of(&grid) {
            Ok(g) => g,
            Err(e) => {
                set_aside.push(aside(NotRope::Branched {
                    junctions: e.junctions,
                }));
                continue;
            }
        };
        let walks = graph.walks(&grid, zone_base);
        zone_base = zone_base.saturating_add(graph.zones as u32);
        let mut pieces = Vec::new();
        for mut walk in walks {
            for (end, free) in walk.free.into_iter().enumerate() {
                if free {
                    extend_end(&mut walk, end == 0, labels, mask.width, shape.label);
                }
            }
            for (a, b) in thin_runs(&walk.widths) {
                let mut run = Piece::empty(shape.label);
                run.points = walk.points[a..b].to_vec();
                run.widths = walk.widths[a..b].to_vec();
                run.zones = walk.zones[a..b].to_vec();
                if let Some(m) = metric {
                    run.depths = depths_along(&run.points, m.frame, mask, m.cloud);
                    pieces.extend(run.split_at_depth_jumps(m));
                } else {
                    pieces.push(run);
                }
            }
        }
        pieces.retain(|p| p.points.len() >= MIN_PIECE_POINTS);
        let sole = pieces.len() == 1;
        let mut failures = Vec::new();
        let before = kept.len();
        for mut p in pieces {
            match p.measure(metric, diameter_prior) {
                Ok(()) => {
                    p.pixels = if sole {
                        shape.pixels.len() as f64
                    } else {
                        p.width_px * p.length_px
                    };
                    kept.push(p);
                }
                Err(reason) => failures.push((p.length_px, reason)),
            }
        }
        if kept.len() == before {
            // Nothing of this shape is rope: its longest piece says why.
            let reason = failures
                .into_iter()
                .max_by(|a, b| a.0.total_cmp(&b.0))
                .map_or(NotRope::Compact, |f| f.1);
            set_aside.push(aside(reason));
        }
    }
    (kept, set_aside)
}

/// The runs `[a, b)` of a walk between points too thick to be its rope.
fn thin_runs(widths: &[f64]) -> Vec<(usize, usize)> {
    let mut known: Vec<f64> = widths.iter().copied().filter(|w| w.is_finite()).collect();
    if known.is_empty() {
        return vec![(0, widths.len())];
    }
    known.sort_unstable_by(f64::total_cmp);
    let limit = THICK_RATIO * known[known.len() / 4] + WIDTH_SLACK_PX;
    let mut runs = Vec::new();
    let mut start = None;
    for (k, w) in widths.iter().enumerate() {
        let thick = *w > limit;
        match (thick, start) {
            (false, None) => start = Some(k),
            (true, Some(a)) => {
                runs.push((a, k));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(a) = start {
        runs.push((a, widths.len()));
    }
    runs
}

/// Continues a walk's end in its direction while its shape goes on (the
/// skeleton stops about half a width short of a tip).
fn extend_end(walk: &mut super::graph::Walk, head: bool, labels: &[u32], width: u32, label: u32) {
    let n = walk.points.len();
    if n < 2 {
        return;
    }
    let back = END_DIRECTION_PIXELS.min(n - 1);
    let (end, from) = if head {
        (walk.points[0], walk.points[back])
    } else {
        (walk.points[n - 1], walk.points[n - 1 - back])
    };
    let dir = end - from;
    let len = dir.norm();
    if !(len > 1e-9) {
        return;
    }
    let dir = dir / len;
    let height = labels.len() / width.max(1) as usize;
    let mut added = Vec::new();
    for k in 1..=MAX_END_EXTENSION {
        let p = end + dir * k as f64;
        let (u, v) = (libm::round(p.x) as i64, libm::round(p.y) as i64);
        let inside = u >= 0 && v >= 0 && (u as usize) < width as usize && (v as usize) < height;
        if !inside || labels[v as usize * width as usize + u as usize] != label {
            break;
        }
        added.push(p);
    }
    let k = added.len();
    if head {
        added.reverse();
        walk.points.splice(0..0, added);
        walk.widths.splice(0..0, vec![f64::NAN; k]);
        walk.zones.splice(0..0, vec![NO_ZONE; k]);
    } else {
        walk.points.extend(added);
        walk.widths.extend(vec![f64::NAN; k]);
        walk.zones.extend(vec![NO_ZONE; k]);
    }
}

/// The median of `values` (NaN when empty), reordering them.
pub(super) fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_unstable_by(f64::total_cmp);
    values[values.len() / 2]
}

impl Piece {
    fn empty(label: u32) -> Self {
        Self {
            points: Vec::new(),
            widths: Vec::new(),
            zones: Vec::new(),
            depths: Vec::new(),
            label,
            pixels: 0.0,
            width_px: f64::NAN,
            length_px: 0.0,
            line: Vec::new(),
            length: 0.0,
            diameter: f64::NAN,
        }
    }

    /// The piece cut between neighbouring measured points (outside junction
    /// zones) whose depths differ more than a rope can rise between them.
    fn split_at_depth_jumps(self, m: Metric<'_>) -> Vec<Piece> {
        let f = 0.5 * (m.camera.fx + m.camera.fy);
        let mut cuts = Vec::new();
        let mut last: Option<(usize, f64)> = None;
        for (k, d) in self.depths.iter().enumerate() {
            let (Some(z), true) = (*d, self.zones[k] == NO_ZONE) else {
                continue;
            };
            if let Some((i, zi)) = last {
                let across = (self.points[k] - self.points[i]).norm() * z / f;
                let allowed = DEPTH_JUMP_SLOPE * across + DEPTH_JUMP_SIGMAS * depth_noise(z, f);
                if (z - zi).abs() > allowed {
                    cuts.push(k);
                }
            }
            last = Some((k, z));
        }
        if cuts.is_empty() {
            return vec![self];
        }
        let mut out = Vec::new();
        let mut a = 0;
        for b in cuts.into_iter().chain([self.points.len()]) {
            let mut p = Piece::empty(self.label);
            p.points = self.points[a..b].to_vec();
            p.widths = self.widths[a..b].to_vec();
            p.zones = self.zones[a..b].to_vec();
            p.depths = self.depths[a..b].to_vec();
            out.push(p);
            a = b;
        }
        out
    }

    /// Measures the piece and tests it as a fragment of rope.
    fn measure(
        &mut self,
        metric: Option<Metric<'_>>,
        diameter_prior: Option<f64>,
    ) -> Result<(), NotRope> {
        let mut widths: Vec<f64> = self
            .widths
            .iter()
            .copied()
            .filter(|w| w.is_finite())
            .collect();
        let w = median(&mut widths);
        if !(w > 0.0) {
            return Err(NotRope::Compact);
        }
        self.width_px = w;
        self.length_px = self.points.windows(2).map(|p| (p[1] - p[0]).norm()).sum();
        match metric {
            Some(m) => {
                let mut depths = self.depths.clone();
                resolve_crossings(&mut depths, &self.zones);
                let mut z: Vec<f64> = depths.iter().flatten().copied().collect();
                let z = median(&mut z);
                self.line =
                    line_through(&self.points, &depths, m.camera, 0.0).ok_or(NotRope::NoDepth)?;
                self.diameter = w * z / (0.5 * (m.camera.fx + m.camera.fy));
                let (lo, hi) = match diameter_prior {
                    Some(d) => (d / DIAMETER_PRIOR_FACTOR, d * DIAMETER_PRIOR_FACTOR),
                    None => ROPE_DIAMETER_RANGE,
                };
                if !(self.diameter >= lo && self.diameter <= hi) {
                    return Err(NotRope::Diameter {
                        diameter_mm: self.diameter * 1000.0,
                        low_mm: lo * 1000.0,
                        high_mm: hi * 1000.0,
                    });
                }
            }
            None => {
                self.line = self
                    .points
                    .iter()
                    .map(|p| Vec3::new(p.x, p.y, 0.0))
                    .collect();
                self.diameter = w;
            }
        }
        self.length = polyline_length(&self.line);
        let even = widths
            .iter()
            .filter(|&&x| (x - w).abs() <= EVEN_TOLERANCE * w + WIDTH_SLACK_PX)
            .count() as f64
            / widths.len() as f64;
        if even < MIN_EVEN_SHARE {
            return Err(NotRope::Uneven { even_share: even });
        }
        let elongation = self.length / self.diameter;
        if !(elongation >= MIN_FRAGMENT_ELONGATION) {
            return Err(NotRope::Short { elongation });
        }
        let turn = sharpest_turn(&self.points, w.max(2.0));
        if turn > MAX_TURN_PER_WIDTH_DEGREES {
            return Err(NotRope::Kinked { turn_degrees: turn });
        }
        Ok(())
    }

    /// Image position of an end and the direction out of the piece there,
    /// over about two widths.
    fn end(&self, head: bool) -> (Vec2, Vec2) {
        let n = self.points.len();
        let reach = (libm::round(2.0 * self.width_px) as usize)
            .max(4)
            .min(n / 2)
            .max(1)
            .min(n - 1);
        if head {
            (self.points[0], self.points[0] - self.points[reach])
        } else {
            (
                self.points[n - 1],
                self.points[n - 1] - self.points[n - 1 - reach],
            )
        }
    }

    fn end_3d(&self, head: bool) -> Vec3 {
        if head {
            self.line[0]
        } else {
            self.line[self.line.len() - 1]
        }
    }
}

/// The sharpest turn, degrees, between consecutive chords `step` pixels long.
fn sharpest_turn(points: &[Vec2], step: f64) -> f64 {
    let mut marks = Vec::new();
    let mut last: Option<Vec2> = None;
    for &p in points {
        if last.is_none_or(|q| (p - q).norm() >= step) {
            marks.push(p);
            last = Some(p);
        }
    }
    marks
        .windows(3)
        .map(|m| angle(m[1] - m[0], m[2] - m[1]).to_degrees())
        .fold(0.0, f64::max)
}

/// Pieces joined end to end: one rope as far as the images tell.
#[derive(Debug, Clone)]
pub(super) struct Chain {
    /// Image path, about a pixel between points.
    pub points: Vec<Vec2>,
    /// The junction zone of each point (`NO_ZONE` elsewhere).
    pub zones: Vec<u32>,
    /// Depth at each point (`None` in gaps; empty without depth).
    pub depths: Vec<Option<f64>>,
    /// Length, metres (pixels without depth), gaps included.
    pub length: f64,
    /// Diameter, metres (pixels without depth), length-weighted.
    pub diameter: f64,
    /// Mask pixels it stands for.
    pub pixels: f64,
    /// Pieces in it.
    pub fragments: usize,
    /// Junction zones it passes more than once (crossings with itself).
    pub crossings: usize,
    /// The unpushed line through its pieces (gaps not bridged), for distances.
    pub line: Vec<Vec3>,
}

impl Chain {
    /// Image length, pixels.
    pub fn length_px(&self) -> f64 {
        self.points.windows(2).map(|w| (w[1] - w[0]).norm()).sum()
    }
}

/// `true` when `target` lies ahead of an end at `from` going `dir`, within
/// [`MAX_JOIN_ANGLE_DEGREES`] of its direction: the end of a piece cut by an
/// occluder's edge may sit anywhere across the rope's width, so the cone
/// starts `slack` pixels wide.
fn points_at(from: Vec2, dir: Vec2, target: Vec2, slack: f64) -> bool {
    let n = dir.norm();
    if !(n > 0.0) {
        return false;
    }
    let g = target - from;
    let along = g.dot(&dir) / n;
    let across = (g - dir * (along / n)).norm();
    let cone = libm::tan(MAX_JOIN_ANGLE_DEGREES.to_radians());
    along >= -slack && across <= cone * along.max(0.0) + slack
}

/// `true` when the ends at `a` going `da` and at `b` going `db` turn into
/// each other at one corner: their two rays meet ahead of both (`slack`
/// pixels behind counts as ahead), neither farther from its end than the
/// ends are apart plus `slack`. A rope that crosses itself kinks where it
/// settles against its own strand, and the walk through the crossing stops
/// at the kink: its two ends point past each other at the kink, not at
/// each other (drawn report scenes 2030 and 2061, a loop cut there).
fn meet_at_corner(a: Vec2, da: Vec2, b: Vec2, db: Vec2, slack: f64) -> bool {
    let (na, nb) = (da.norm(), db.norm());
    if !(na > 0.0 && nb > 0.0) {
        return false;
    }
    let (ua, ub) = (da / na, db / nb);
    // a + s ua = b + t ub, solved by Cramer's rule.
    let cross = ua.x * ub.y - ua.y * ub.x;
    if !(cross.abs() > CORNER_MIN_SINE) {
        return false;
    }
    let g = b - a;
    let s = (g.x * ub.y - g.y * ub.x) / cross;
    let t = (g.x * ua.y - g.y * ua.x) / cross;
    let reach = g.norm() + slack;
    (-slack..=reach).contains(&s) && (-slack..=reach).contains(&t)
}

/// Rays closer to parallel than this sine of their angle meet nowhere
/// near: two ends that follow one line are the straight test's.
const CORNER_MIN_SINE: f64 = 0.1;

/// A possible join of two piece ends.
struct Link {
    /// A corner join ([`meet_at_corner`]), taken only after every straight one.
    corner: bool,
    gap: f64,
    a: (usize, bool),
    b: (usize, bool),
}

/// Which joins [`join`] may make beyond the straight ones.
#[derive(Debug, Clone, Copy)]
pub(super) struct Joins {
    /// Ends that meet at a corner ([`meet_at_corner`]): not where another
    /// rope of the colour may be in view.
    pub corners: bool,
}

impl Default for Joins {
    /// Corners joined: one rope in view.
    fn default() -> Self {
        Self { corners: true }
    }
}

/// Joins pieces end to end where their ends are close and point at each
/// other (or, as `joins` allows, meet at a corner), and the two are as
/// thick, then lays each chain out as one path.
pub(super) fn join(pieces: &[Piece], metric: bool, joins: Joins) -> Vec<Chain> {
    let n = pieces.len();
    let mut links = Vec::new();
    for a in 0..n {
        for b in a + 1..n {
            let (pa, pb) = (&pieces[a], &pieces[b]);
            if !one_rope_thick(pa.diameter, pb.diameter) {
                continue;
            }
            let reach = (JOIN_GAP_DIAMETERS * pa.diameter.min(pb.diameter))
                .max(JOIN_GAP_FRACTION * pa.length.min(pb.length));
            for ha in [true, false] {
                for hb in [true, false] {
                    let gap = (pa.end_3d(ha) - pb.end_3d(hb)).norm();
                    if !(gap <= reach) {
                        continue;
                    }
                    let ((xa, oa), (xb, ob)) = (pa.end(ha), pb.end(hb));
                    let slack = pa.width_px.max(pb.width_px);
                    let straight = points_at(xa, oa, xb, slack) && points_at(xb, ob, xa, slack);
                    let corner =
                        !straight && joins.corners && meet_at_corner(xa, oa, xb, ob, slack);
                    if !(straight || corner) {
                        continue;
                    }
                    links.push(Link {
                        corner,
                        gap,
                        a: (a, ha),
                        b: (b, hb),
                    });
                }
            }
        }
    }
    links.sort_by(|x, y| x.corner.cmp(&y.corner).then(x.gap.total_cmp(&y.gap)));
    // Each end takes at most one link; no link closes a ring.
    let mut next: Vec<[Option<(usize, bool)>; 2]> = vec![[None, None]; n];
    let mut group: Vec<usize> = (0..n).collect();
    fn root(g: &mut [usize], mut a: usize) -> usize {
        while g[a] != a {
            g[a] = g[g[a]];
            a = g[a];
        }
        a
    }
    let slot = |head: bool| usize::from(!head);
    for l in links {
        let (ra, rb) = (root(&mut group, l.a.0), root(&mut group, l.b.0));
        if ra == rb || next[l.a.0][slot(l.a.1)].is_some() || next[l.b.0][slot(l.b.1)].is_some() {
            continue;
        }
        next[l.a.0][slot(l.a.1)] = Some(l.b);
        next[l.b.0][slot(l.b.1)] = Some(l.a);
        group[ra.max(rb)] = ra.min(rb);
    }
    let mut placed = vec![false; n];
    let mut chains = Vec::new();
    for start in 0..n {
        if placed[start] {
            continue;
        }
        // Go to one end of this chain, then lay it out from there.
        let (mut at, mut enter_head) = (start, true);
        let mut guard = 0;
        while let Some((p, h)) = next[at][slot(enter_head)] {
            // Leaving `at` by its head: `p` is entered by `h`, left by the other end.
            (at, enter_head) = (p, !h);
            guard += 1;
            if guard > n {
                break;
            }
        }
        // `at` is an end piece; it is traversed starting from its free end.
        let mut parts = Vec::new();
        let mut cur = Some((at, enter_head));
        while let Some((p, free_head)) = cur {
            if placed[p] {
                break;
            }
            placed[p] = true;
            // Traversed from `free_head`'s end to the other.
            parts.push((p, !free_head));
            cur = next[p][slot(!free_head)];
        }
        chains.push(lay_out(pieces, &parts, metric));
    }
    chains
}

/// A chain's path: its pieces in order (reversed where `reversed`), with a
/// bridge across each gap that leaves and arrives along the pieces.
fn lay_out(pieces: &[Piece], parts: &[(usize, bool)], metric: bool) -> Chain {
    let mut c = Chain {
        points: Vec::new(),
        zones: Vec::new(),
        depths: Vec::new(),
        length: 0.0,
        diameter: 0.0,
        pixels: 0.0,
        fragments: parts.len(),
        crossings: 0,
        line: Vec::new(),
    };
    let (mut weighted, mut measured) = (0.0, 0.0);
    for (k, &(i, reversed)) in parts.iter().enumerate() {
        let p = &pieces[i];
        let order: Vec<usize> = if reversed {
            (0..p.points.len()).rev().collect()
        } else {
            (0..p.points.len()).collect()
        };
        if k > 0 {
            let (prev, prev_rev) = parts[k - 1];
            let q = &pieces[prev];
            // Leaving `q` at the end it finishes on, entering `p` at the one it starts from.
            let (a, da) = q.end(prev_rev);
            let (b, db) = p.end(!reversed);
            let chord = (b - a).norm();
            let unit = |v: Vec2| if v.norm() > 0.0 { v / v.norm() } else { v };
            let steps = libm::ceil(chord) as usize;
            for s in 1..steps {
                let t = s as f64 / steps as f64;
                c.points
                    .push(hermite(a, unit(da) * chord, b, -unit(db) * chord, t));
                c.zones.push(NO_ZONE);
                if metric {
                    c.depths.push(None);
                }
            }
            c.length += (p.end_3d(!reversed) - q.end_3d(prev_rev)).norm();
        }
        for &j in &order {
            c.points.push(p.points[j]);
            c.zones.push(p.zones[j]);
            if metric {
                c.depths.push(p.depths.get(j).copied().flatten());
            }
        }
        c.line.extend(order.iter().map(|&j| p.line[j]));
        c.length += p.length;
        c.pixels += p.pixels;
        weighted += p.diameter * p.length;
        measured += p.length;
    }
    c.diameter = weighted / measured.max(f64::MIN_POSITIVE);
    let mut zones: Vec<u32> = Vec::new();
    let mut k = 0;
    while k < c.zones.len() {
        let z = c.zones[k];
        if z != NO_ZONE {
            zones.push(z);
        }
        while k < c.zones.len() && c.zones[k] == z {
            k += 1;
        }
    }
    zones.sort_unstable();
    c.crossings = zones.windows(2).filter(|w| w[0] == w[1]).count();
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The two ends drawn report scene 2030's loop was cut at, frame 0
    /// (pixels; the rope 11.8 px wide): the loop's strand going up, the
    /// rope's end beside it going right, so the two turn into each other.
    const LOOP_END: (Vec2, Vec2) = (Vec2::new(680.0, 372.0), Vec2::new(0.0, -24.0));
    const ARM_END: (Vec2, Vec2) = (Vec2::new(662.0, 349.0), Vec2::new(23.0, -4.0));
    const WIDTH: f64 = 11.8;

    #[test]
    fn ends_that_turn_into_each_other_meet_at_a_corner_the_straight_test_misses() {
        let ((a, da), (b, db)) = (LOOP_END, ARM_END);
        assert!(!(points_at(a, da, b, WIDTH) && points_at(b, db, a, WIDTH)));
        assert!(meet_at_corner(a, da, b, db, WIDTH));
        assert!(meet_at_corner(b, db, a, da, WIDTH), "not symmetric");
    }

    /// A piece of image points only (no depth), `WIDTH` wide.
    fn piece(points: Vec<Vec2>) -> Piece {
        let mut p = Piece::empty(1);
        p.widths = alloc::vec![WIDTH; points.len()];
        p.zones = alloc::vec![NO_ZONE; points.len()];
        p.line = points.iter().map(|q| Vec3::new(q.x, q.y, 0.0)).collect();
        p.length_px = points.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
        p.length = p.length_px;
        p.pixels = WIDTH * p.length_px;
        p.width_px = WIDTH;
        p.diameter = WIDTH;
        p.points = points;
        p
    }

    /// 2030's loop strand, 48 px up to its end, and the rope's arm, 60 px
    /// from its end going left.
    fn kinked_pair() -> [Piece; 2] {
        let up = (0..=48)
            .map(|k| Vec2::new(680.0, 420.0 - k as f64))
            .collect();
        let left = (0..=60)
            .map(|k| Vec2::new(662.0 - k as f64, 349.0 + k as f64 * 4.0 / 23.0))
            .collect();
        [piece(up), piece(left)]
    }

    #[test]
    fn a_corner_join_is_made_for_one_rope_and_not_where_ropes_alike_may_meet() {
        let one = join(&kinked_pair(), false, Joins::default());
        assert_eq!(one.len(), 1, "one rope: the kink is joined");
        let alike = join(&kinked_pair(), false, Joins { corners: false });
        assert_eq!(alike.len(), 2, "ropes alike: the two ends stay apart");
    }

    #[test]
    fn ends_pointing_away_parallel_or_meeting_far_off_are_no_corner() {
        let ((a, da), (b, db)) = (LOOP_END, ARM_END);
        assert!(!meet_at_corner(a, -da, b, db, WIDTH), "one points away");
        assert!(
            !meet_at_corner(a, da, b, -db, WIDTH),
            "the other points away"
        );
        assert!(!meet_at_corner(a, da, b, da, WIDTH), "parallel");
        // Rays that meet, but farther from both ends than the gap and a
        // width (45 and 50 px for a 29 px gap): a detour, no kink.
        let far = Vec2::new(1.0, -1.0);
        assert!(!meet_at_corner(a, far, b, db, WIDTH));
        assert!(
            !meet_at_corner(a, da, b, Vec2::zeros(), WIDTH),
            "no direction"
        );
    }
}
