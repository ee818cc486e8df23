//! Length conservation of hidden ends (this project's addition after
//! Eq. 11): a rope does not stretch, so a hidden run at an end of the rope
//! may not be longer than the arc length that the rest of the rope leaves
//! of the rope's known length. A run too long has its nodes placed evenly
//! along its own estimated curve from the anchor (the last visible node)
//! up to that length; a run shorter is left as it is (a hidden tip may lie
//! curled up: nothing says where the missing length went).

use alloc::vec::Vec;

use super::resampling::resample;
use super::slide::{hidden_runs, HiddenRun};
use crate::curve::RopeCurve;
use crate::math::{self, Vec3};
use crate::polyline::{polyline_length, resample_uniform};

/// What the stage did in one frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LengthReport {
    /// Hidden end runs re-spaced.
    pub runs: usize,
    /// Largest relative change of a run's length (0.1: 10 %).
    pub largest_change: f64,
}

/// `count` points after `curve[0]` evenly spaced by `step` along `curve`,
/// continued straight past its end.
pub(super) fn along(curve: &RopeCurve<'_>, count: usize, step: f64) -> Vec<Vec3> {
    (1..=count).map(|i| curve.at(step * i as f64)).collect()
}

/// Re-spaces every hidden run that reaches an end of the rope (`known[m]`
/// false) and is longer than its share, so that the whole rope is no
/// longer than `rest_length`. Both ends hidden: each gets a share of what
/// the middle leaves in proportion to its node count.
pub fn conserve_end_lengths(nodes: &mut [Vec3], known: &[bool], rest_length: f64) -> LengthReport {
    let mut report = LengthReport::default();
    let m = nodes.len();
    if known.len() != m || !(rest_length > 0.0) || !known.iter().any(|&k| k) {
        return report;
    }
    let runs = hidden_runs(known);
    let head = runs.first().filter(|r| r.start == 0).copied();
    let tail = runs.last().filter(|r| r.end == m).copied();
    // The part of the rope between the end runs (their anchors included).
    let (from, to) = (
        head.map_or(0, |r| r.end),
        tail.map_or(m - 1, |r| r.start - 1),
    );
    if from > to {
        return report;
    }
    let budget = rest_length - polyline_length(&nodes[from..=to]);
    let ends: Vec<(usize, bool)> = [
        // A head run starts at node 0: its node count is its end.
        head.map(|r| (r.end, true)),
        tail.map(|r| (r.end - r.start, false)),
    ]
    .into_iter()
    .flatten()
    .collect();
    let total: usize = ends.iter().map(|(n, _)| n).sum();
    if total == 0 {
        return report;
    }
    for (count, at_head) in ends {
        let share = (budget * count as f64 / total as f64).max(0.0);
        let curve = end_run_from_anchor(nodes, count, at_head);
        let old = polyline_length(&curve);
        if old <= share {
            continue;
        }
        let placed = along(&RopeCurve::polyline(&curve), count, share / count as f64);
        if !placed.iter().all(math::is_finite) {
            continue;
        }
        // old > share >= 0 here, so the ratio is finite.
        report.largest_change = report.largest_change.max((share - old).abs() / old);
        report.runs += 1;
        set_end_run(nodes, count, at_head, placed);
    }
    report
}

/// The hidden run of `count` nodes at the rope's first end (`at_head`) or
/// last, as a curve from its anchor (the visible node next to it)
/// outwards. `count` must be below the node count.
pub(super) fn end_run_from_anchor(nodes: &[Vec3], count: usize, at_head: bool) -> Vec<Vec3> {
    if at_head {
        nodes[..=count].iter().rev().copied().collect()
    } else {
        nodes[nodes.len() - 1 - count..].to_vec()
    }
}

/// Writes `placed` (the run's nodes from its anchor outwards, as
/// [`end_run_from_anchor`] orders them, without the anchor) back over the
/// run of `count` nodes at the first end (`at_head`) or the last.
pub(super) fn set_end_run(nodes: &mut [Vec3], count: usize, at_head: bool, placed: Vec<Vec3>) {
    let m = nodes.len();
    if at_head {
        for (k, p) in placed.into_iter().enumerate() {
            nodes[count - 1 - k] = p;
        }
    } else {
        nodes[m - count..].copy_from_slice(&placed);
    }
}

/// Rope radii taken off the centre line's length at the first
/// initialisation to give the rest length `L0`: that line runs to the
/// blob's edge at both tips, which for a rounded tip is a radius past the
/// end of the rope's axis and for a flat cut one is the axis's end. Chosen
/// on the tuning subset with the hidden ends at the rest spacing and
/// extended under occluders: 0 / 1 / 1.25 / 1.5 / 1.75 / 2 radii gave
/// 3.99 / 3.81 / 3.77 / 3.79 / 3.94 / 4.05 mm (`docs/algorithm-notes.md`).
pub const TIP_TRIM_RADII: f64 = 1.25;

/// The rest length `L0` of a rope whose centre line measured
/// `centre_line_length` at initialisation: [`TIP_TRIM_RADII`] radii
/// shorter, but never below half the line (a radius that does not fit the
/// rope is not trusted).
pub fn rest_length(centre_line_length: f64, radius: f64) -> f64 {
    let trimmed = centre_line_length - TIP_TRIM_RADII * radius.max(0.0);
    if trimmed.is_finite() {
        trimmed.max(0.5 * centre_line_length)
    } else {
        centre_line_length
    }
}

/// The rest spacing `L0 / (M - 1)` of `rest_length` over `nodes` nodes
/// (one spacing for fewer than two).
pub fn rest_spacing(rest_length: f64, nodes: usize) -> f64 {
    rest_length / (nodes.max(2) - 1) as f64
}

/// A rope shorter than its rest length by less than this many node spacings
/// is left as it is (the resampled polyline's own error).
pub const MIN_SHORTFALL_SPACINGS: f64 = 0.5;

/// How much shorter the polyline through `nodes` is than `rest_length`:
/// rope the state holds nowhere (negative when it is longer).
pub fn shortfall(nodes: &[Vec3], rest_length: f64) -> f64 {
    rest_length - polyline_length(nodes)
}

/// Step of the walk along an end's tangent, in node spacings.
pub const EXTENSION_STEP_SPACINGS: f64 = 0.25;

/// What [`extend_short_ends`] added, metres, at the first and the last end.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ExtensionReport {
    /// Added beyond node 0.
    pub head: f64,
    /// Added beyond node `M - 1`.
    pub tail: f64,
}

/// Which ends of the rope [`extend_short_ends`] may extend.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OpenEnds {
    /// The end at node 0.
    pub head: bool,
    /// The end at node `M - 1`.
    pub tail: bool,
}

impl OpenEnds {
    /// Both ends.
    pub const BOTH: Self = Self {
        head: true,
        tail: true,
    };
}

/// The unit direction from `inner` on past `end`, if they are apart.
fn outwards(end: &Vec3, inner: &Vec3) -> Option<Vec3> {
    let d = end - inner;
    let n = math::norm(&d);
    (n > math::LENGTH_EPSILON).then(|| d / n)
}

/// How far, up to `limit`, the rope may go on straight from `end` along
/// `dir` (in steps of `step`) through points where `allows` says a rope
/// may lie.
fn reach(end: &Vec3, dir: &Vec3, limit: f64, step: f64, allows: &dyn Fn(&Vec3) -> bool) -> f64 {
    if !(step > 0.0) {
        return 0.0;
    }
    let mut reached = 0.0;
    let mut k = 1;
    loop {
        let along = (step * k as f64).min(limit);
        if !allows(&(end + dir * along)) {
            return reached;
        }
        reached = along;
        if along >= limit {
            return reached;
        }
        k += 1;
    }
}

/// A rope found shorter than its rest length lost the difference at its
/// ends: EM draws an end node in towards the middle of the points it sees,
/// about half a spacing short of the tip every frame. The missing length
/// is given back along each end's tangent, as far as `allows` (the images
/// show rope there, or the rope leaves the image), half to each end and
/// to the other what one cannot take. Only the ends `open` says may be
/// extended are (a hidden end keeps its length by
/// [`resample_with_end_runs_at_rest`] instead). Returns the polyline with
/// the extensions (to be resampled) and what was added.
pub fn extend_short_ends(
    nodes: &[Vec3],
    rest_length: f64,
    open: OpenEnds,
    allows: &dyn Fn(&Vec3) -> bool,
) -> (Vec<Vec3>, ExtensionReport) {
    let m = nodes.len();
    let mut report = ExtensionReport::default();
    if m < 2 || !(rest_length > 0.0) || !nodes.iter().all(math::is_finite) {
        return (nodes.to_vec(), report);
    }
    let spacing = rest_length / (m - 1) as f64;
    let shortfall = shortfall(nodes, rest_length);
    if !(shortfall > MIN_SHORTFALL_SPACINGS * spacing) {
        return (nodes.to_vec(), report);
    }
    let step = EXTENSION_STEP_SPACINGS * spacing;
    let (first, last) = (nodes[0], nodes[m - 1]);
    let (head_dir, tail_dir) = (outwards(&first, &nodes[1]), outwards(&last, &nodes[m - 2]));
    let reach_along = |end: &Vec3, dir: Option<Vec3>, open: bool| match (dir, open) {
        (Some(d), true) => reach(end, &d, shortfall, step, allows),
        _ => 0.0,
    };
    let (head, tail) = (
        reach_along(&first, head_dir, open.head),
        reach_along(&last, tail_dir, open.tail),
    );
    // Each end up to half, then what one cannot take to the other.
    let (mut h, mut t) = (head.min(shortfall / 2.0), tail.min(shortfall / 2.0));
    let left = shortfall - h - t;
    h += left.min(head - h);
    t += (shortfall - h - t).min(tail - t);
    let mut out = Vec::with_capacity(m + 2);
    if let (Some(d), true) = (head_dir, h > 0.0) {
        out.push(first + d * h);
    }
    out.extend_from_slice(nodes);
    if let (Some(d), true) = (tail_dir, t > 0.0) {
        out.push(last + d * t);
    }
    report.head = h;
    report.tail = t;
    (out, report)
}

/// Longest reach of a seen end towards its tip, in rest spacings: EM draws
/// an end node in from the tip by less than half a spacing (its Gaussian
/// has points on one side only).
pub const TIP_REACH_SPACINGS: f64 = 0.5;

/// Step of the walk towards a seen end's tip, in rope radii.
pub const TIP_STEP_RADII: f64 = 0.5;

/// Where the tip of the rope lies beyond its end node `end` (0 or the
/// last; `None` for any other, or when the images show no rope beyond
/// it): the end carried on along its tangent to where the images stop
/// showing rope (`shows`) or another node is nearer than the end's
/// (another part of the rope: a loop, a crossing), at most
/// [`TIP_REACH_SPACINGS`] of the `spacing`, less the rope's `radius` (the
/// centre line ends a radius inside its mask's end: a whipped, melted or
/// worn end is rounded).
pub fn seen_tip(
    nodes: &[Vec3],
    end: usize,
    spacing: f64,
    radius: f64,
    shows: &dyn Fn(&Vec3) -> bool,
) -> Option<Vec3> {
    let m = nodes.len();
    let inner = match end {
        0 if m >= 2 => 1,
        e if m >= 2 && e == m - 1 => m - 2,
        _ => return None,
    };
    let step = TIP_STEP_RADII * radius;
    if !(spacing > 0.0) || !(step > 0.0) || !nodes.iter().all(math::is_finite) {
        return None;
    }
    let tip = nodes[end];
    let dir = outwards(&tip, &nodes[inner])?;
    let own = |p: &Vec3| {
        let r2 = (p - tip).norm_squared();
        shows(p)
            && nodes
                .iter()
                .enumerate()
                .all(|(k, q)| k == end || (p - q).norm_squared() > r2)
    };
    let limit = TIP_REACH_SPACINGS * spacing + radius;
    let along = reach(&tip, &dir, limit, step, &own) - radius;
    (along > 0.0).then(|| tip + dir * along)
}

/// The nodes of a re-initialisation on a rope found shorter than its
/// `rest_length` (part of it hidden, or out of the image): the missing
/// length laid along the ends' tangents as far as `allows` lets a rope go
/// (where the images show rope or something hides it) by
/// [`extend_short_ends`], and the same number of nodes spread evenly over
/// the whole. Laid over the part found alone, every spacing was short by
/// the missing share and the hidden rest had no node.
pub fn laid_whole_length(
    nodes: &[Vec3],
    rest_length: f64,
    allows: &dyn Fn(&Vec3) -> bool,
) -> Vec<Vec3> {
    let (longer, report) = extend_short_ends(nodes, rest_length, OpenEnds::BOTH, allows);
    if report.head + report.tail > 0.0 {
        resample_uniform(&longer, nodes.len())
    } else {
        nodes.to_vec()
    }
}

/// Resampling (Eq. 12-15) that keeps each hidden run at an end of the rope
/// at the rest spacing `l0 = L0 / (M - 1)`: the `head` hidden nodes at the
/// start of `nodes` and the `tail` at its end are placed `l0` apart along
/// their own curve from their anchor (continued straight past their tip
/// when the curve is short, as far as `allows` lets a hidden rope go; a
/// run that does not fit is spread evenly over what there is, closer than
/// `l0`), and only the part between the two anchors is
/// spread evenly by `resample`. Spread over the whole rope instead, the
/// length a rope loses where nothing shows it (a held end inside a
/// gripper's jaws) would shorten every hidden run by the same share
/// (`docs/algorithm-notes.md`, "Hidden ends keep the rest spacing").
/// `None` when there is no hidden end, or fewer than two nodes would be
/// left between the anchors, or the result is not finite.
pub fn resample_with_end_runs_at_rest(
    nodes: &[Vec3],
    head: usize,
    tail: usize,
    count: usize,
    rest_spacing: f64,
    smooth: bool,
    allows: &dyn Fn(&Vec3) -> bool,
) -> Option<Vec<Vec3>> {
    let n = nodes.len();
    let ends = head.checked_add(tail)?;
    if ends == 0 || ends + 2 > count || ends + 2 > n || !(rest_spacing > 0.0) {
        return None;
    }
    let middle = resample(&nodes[head..n - tail], count - ends, smooth);
    let (&first, &last) = (middle.first()?, middle.last()?);
    let mut out = Vec::with_capacity(count);
    // Each run's curve from its anchor outwards.
    let placed = |anchor: Vec3, outwards: &mut dyn Iterator<Item = &Vec3>, count: usize| {
        let curve: Vec<Vec3> = core::iter::once(anchor).chain(outwards.copied()).collect();
        along_within(&RopeCurve::new(&curve, smooth), count, rest_spacing, allows)
    };
    out.extend(
        placed(first, &mut nodes[..head].iter().rev(), head)
            .into_iter()
            .rev(),
    );
    out.extend_from_slice(&middle);
    out.extend(placed(last, &mut nodes[n - tail..].iter(), tail));
    (out.len() == count && out.iter().all(math::is_finite)).then_some(out)
}

/// [`along`], but continued past the curve's end only as far as `allows`
/// (walked in steps of [`EXTENSION_STEP_SPACINGS`] of `step`); when the
/// curve and that reach are shorter than `count` steps, the points are
/// spread evenly over what there is.
fn along_within(
    curve: &RopeCurve<'_>,
    count: usize,
    step: f64,
    allows: &dyn Fn(&Vec3) -> bool,
) -> Vec<Vec3> {
    let length = curve.length();
    let wanted = step * count as f64;
    let pieces = curve.pieces();
    if pieces.len() < 2 || length >= wanted || count == 0 {
        return along(curve, count, step);
    }
    let n = pieces.len();
    let Some(dir) = outwards(&pieces[n - 1], &pieces[n - 2]) else {
        return along(curve, count, step);
    };
    let walk = EXTENSION_STEP_SPACINGS * step;
    let more = reach(&pieces[n - 1], &dir, wanted - length, walk, allows);
    along(curve, count, ((length + more) / count as f64).min(step))
}

/// Bisection steps of [`conserve_middle_lengths`]: the factor to 2^-30.
const BISECTION_STEPS: usize = 30;

/// The points of `curve` with their offsets from the chord `curve[0]` ->
/// `curve[last]` scaled by `scale` (each point's chord point at its arc
/// length fraction): 0 is the chord, 1 the curve.
fn scaled_from_chord<'a>(
    curve: &'a [Vec3],
    fractions: &'a [f64],
    scale: f64,
) -> impl Iterator<Item = Vec3> + 'a {
    let (a, b) = (curve[0], curve[curve.len() - 1]);
    curve.iter().zip(fractions).map(move |(p, &t)| {
        let on_chord = a + (b - a) * t;
        on_chord + (p - on_chord) * scale
    })
}

/// Length of the polyline through `points`, without collecting them.
fn length_of(mut points: impl Iterator<Item = Vec3>) -> f64 {
    let Some(mut prev) = points.next() else {
        return 0.0;
    };
    points.fold(0.0, |sum, p| {
        let step = math::norm(&(p - prev));
        prev = p;
        sum + step
    })
}

/// The whole rope does not stretch through the hidden runs between two
/// visible stretches (this project's addition, issue 28): when the rope
/// is longer than `rest_length`, those runs give up the excess, shared in
/// proportion to their lengths. A rope pulled out from under an occluder
/// takes that length from the hidden bend, which tightens.
///
/// Where one of a run's two visible stretches moved away from it since
/// `previous` (its tip's move along the rope, outwards: `pulled_side`) and
/// the other less, the rope is pulled from that side: the run straightens
/// from there and keeps its curve from the other anchor on
/// (`taut_from_pulled_end`), as a rope dragged by one end across a table
/// does. Otherwise (`previous` not of the nodes' length, nothing moved
/// outwards) a run's new curve keeps its anchors and scales its offsets
/// from their chord by one factor: the polyline's length grows
/// monotonically with it (a sum of norms of affine functions is convex,
/// and least at the chord, the shortest path), so a bisection finds it.
/// A run asked for less than its chord is laid on the chord. An excess
/// under [`MIN_SHORTFALL_SPACINGS`] node spacings may be the rest length's
/// or the visible rope's own error: a run gives up that much only where a
/// pull is seen, and at most the rope that slid out of it since
/// `previous` (`Pull::slid_out`), so a rope pulled through keeps its
/// length frame by frame instead of in steps of half a spacing. A rope
/// shorter than its rest length is left: a polyline of `M` nodes cuts
/// every bend, so falling short is no evidence that the hidden bend holds
/// more (opening bends to make up the difference moved them off the rope
/// on the tuning range).
pub fn conserve_middle_lengths(
    nodes: &mut [Vec3],
    known: &[bool],
    previous: &[Vec3],
    rest_length: f64,
) -> LengthReport {
    let mut report = LengthReport::default();
    let m = nodes.len();
    if known.len() != m || m < 3 || !(rest_length > 0.0) || !nodes.iter().all(math::is_finite) {
        return report;
    }
    let middle: Vec<HiddenRun> = hidden_runs(known)
        .into_iter()
        .filter(|r| r.start > 0 && r.end < m)
        .collect();
    let lengths: Vec<f64> = middle
        .iter()
        .map(|r| polyline_length(&nodes[r.start - 1..=r.end]))
        .collect();
    let hidden: f64 = lengths.iter().sum();
    if middle.is_empty() || !(hidden > math::LENGTH_EPSILON) {
        return report;
    }
    // What the hidden runs hold beyond what the visible rope leaves them
    // (the rope's length over its rest length, summed in this order).
    let excess = hidden - (rest_length - (polyline_length(nodes) - hidden));
    if !(excess > 0.0) {
        return report;
    }
    let whole = excess >= MIN_SHORTFALL_SPACINGS * rest_length / (m - 1) as f64;
    // Read before any run moves: each run's pull is from its own stretches.
    let pulls: Vec<Option<Pull>> = middle
        .iter()
        .map(|run| pulled_side(nodes, known, previous, *run))
        .collect();
    for ((run, old), pull) in middle.iter().zip(&lengths).zip(&pulls) {
        let share = excess * old / hidden;
        let give = match (whole, pull) {
            (true, _) => share,
            (false, Some(pull)) => share.min(pull.slid_out),
            (false, None) => continue,
        };
        if !(give > 0.0) {
            continue;
        }
        let target = (old - give).max(0.0);
        let curve = nodes[run.start - 1..=run.end].to_vec();
        let placed = match pull {
            Some(pull) => taut_spread(&curve, target, pull.side),
            None => scaled_towards_chord(&curve, *old, target),
        };
        if !placed.iter().all(math::is_finite) {
            continue;
        }
        let new = polyline_length(&placed);
        report.largest_change = report.largest_change.max((new - old).abs() / old);
        report.runs += 1;
        nodes[run.start..run.end].copy_from_slice(&placed[1..placed.len() - 1]);
    }
    report
}

/// `curve` (a run with its two anchors, `old` long) with its offsets from
/// the anchors' chord scaled to make it `target` long.
fn scaled_towards_chord(curve: &[Vec3], old: f64, target: f64) -> Vec<Vec3> {
    let mut travelled = 0.0;
    let mut fractions = Vec::with_capacity(curve.len());
    fractions.push(0.0);
    for w in curve.windows(2) {
        travelled += math::norm(&(w[1] - w[0]));
        fractions.push(travelled / old);
    }
    // The bisection measures each trial without allocating it.
    let length_at = |scale: f64| length_of(scaled_from_chord(curve, &fractions, scale));
    let (mut lo, mut hi) = (0.0, 1.0);
    let scale = if target <= length_at(lo) {
        lo
    } else {
        for _ in 0..BISECTION_STEPS {
            let mid = 0.5 * (lo + hi);
            if length_at(mid) < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    };
    scaled_from_chord(curve, &fractions, scale).collect()
}

/// Which anchor of a run the rope is pulled from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    Start,
    End,
}

/// A pull on a hidden run from one of its visible stretches.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Pull {
    /// The anchor the rope is pulled from.
    side: Side,
    /// The rope that left the run since the previous frame, metres: the
    /// pulled stretch's tip's move out less the other tip's move, out (the
    /// bend carried along) or in (rope that went into the run there).
    slid_out: f64,
}

/// The side of `run` whose visible stretch was pulled away from it since
/// `previous` more than the other, when one was, and the rope that slid
/// out of the run: the move of the stretch's far node (the rope's tip,
/// where the stretch reaches it) along the rope, outwards. Along a
/// straight stretch the nodes slide as EM parameterises the points, so
/// their mean move shows nothing of a pull along the rope; a tip shows it.
fn pulled_side(nodes: &[Vec3], known: &[bool], previous: &[Vec3], run: HiddenRun) -> Option<Pull> {
    let m = nodes.len();
    if previous.len() != m {
        return None;
    }
    // The last known node of each stretch, away from the run (its anchor
    // when the stretch is that one node).
    let (a, b) = (run.start - 1, run.end);
    let start_tip = (0..=a).rev().take_while(|&k| known[k]).last().unwrap_or(a);
    let end_tip = (b..m).take_while(|&k| known[k]).last().unwrap_or(b);
    let pull = |tip: usize, inner: usize| {
        outwards(&nodes[tip], &nodes[inner]).map(|out| (nodes[tip] - previous[tip]).dot(&out))
    };
    match (pull(start_tip, start_tip + 1), pull(end_tip, end_tip - 1)) {
        (Some(s), Some(e)) if e > 0.0 && e > s => Some(Pull {
            side: Side::End,
            slid_out: e - s.abs(),
        }),
        (Some(s), Some(e)) if s > 0.0 && s > e => Some(Pull {
            side: Side::Start,
            slid_out: s - e.abs(),
        }),
        _ => None,
    }
}

/// `curve` (a run with its anchors) made `target` long by the pull from
/// `side` ([`taut_from_pulled_end`]), its points spread evenly over it.
fn taut_spread(curve: &[Vec3], target: f64, side: Side) -> Vec<Vec3> {
    match side {
        Side::End => resample_uniform(&taut_from_pulled_end(curve, target), curve.len()),
        Side::Start => {
            let reversed: Vec<Vec3> = curve.iter().rev().copied().collect();
            let mut placed =
                resample_uniform(&taut_from_pulled_end(&reversed, target), curve.len());
            placed.reverse();
            placed
        }
    }
}

/// The curve `run`, from a resting anchor `run[0]` to the point the rope
/// is pulled by, `run[last]`, made `target` long: a rope dragged by one
/// end across a table straightens from that end, and its bends farther
/// away stay until the pull reaches them. It keeps its curve from `run[0]`
/// up to the point from which a straight line to the pulled point makes
/// `target` (`s + |C(s) - P|` grows with `s`, as `|C'| = 1`: a bisection
/// finds it). Below the chord: the chord; above the curve's length: the
/// curve.
pub(super) fn taut_from_pulled_end(run: &[Vec3], target: f64) -> Vec<Vec3> {
    let n = run.len();
    let curve = RopeCurve::polyline(run);
    let old = curve.length();
    if n < 2 || !(target < old) {
        return run.to_vec();
    }
    let pulled = run[n - 1];
    let (mut lo, mut hi) = (0.0, old);
    for _ in 0..BISECTION_STEPS {
        let mid = 0.5 * (lo + hi);
        if mid + math::norm(&(curve.at(mid) - pulled)) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    // The points up to `lo` kept (the first always), then C(lo) and P.
    let kept = (0..n - 1)
        .take_while(|&i| curve.arc_of(i) <= lo)
        .count()
        .max(1);
    let at = curve.at(lo);
    let mut out: Vec<Vec3> = run[..kept].to_vec();
    if math::norm(&(at - run[kept - 1])) > math::LENGTH_EPSILON {
        out.push(at);
    }
    out.push(pulled);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::fixture::{off_circle, on_circle};

    fn line(n: usize, step: f64) -> Vec<Vec3> {
        (0..n)
            .map(|i| Vec3::new(i as f64 * step, 0.0, 0.6))
            .collect()
    }

    #[test]
    fn a_stretched_hidden_tail_is_brought_back_to_the_rope_length() {
        // Ten nodes, 1 cm spacing, rope 9 cm; the hidden tail (7-9) was
        // extrapolated 3 cm a step, running off.
        let mut nodes = line(10, 0.01);
        for (k, i) in (7..10).enumerate() {
            nodes[i] = Vec3::new(0.06 + 0.03 * (k + 1) as f64, 0.0, 0.6);
        }
        let known: Vec<bool> = (0..10).map(|i| i < 7).collect();
        let r = conserve_end_lengths(&mut nodes, &known, 0.09);
        assert_eq!(r.runs, 1);
        assert!((polyline_length(&nodes) - 0.09).abs() < 1e-12);
        for (i, p) in nodes.iter().enumerate() {
            assert!((p.x - i as f64 * 0.01).abs() < 1e-12, "node {i}: {p:?}");
        }
    }

    #[test]
    fn a_stretched_hidden_head_keeps_its_bend_and_a_short_one_is_left_alone() {
        // Hidden head 0-2 bent at a right angle, stretched to 2 cm spacing.
        let mut nodes = line(10, 0.01);
        nodes[2] = Vec3::new(0.01, 0.0, 0.6);
        nodes[1] = Vec3::new(0.01, 0.02, 0.6);
        nodes[0] = Vec3::new(0.01, 0.04, 0.6);
        let known: Vec<bool> = (0..10).map(|i| i > 2).collect();
        let r = conserve_end_lengths(&mut nodes, &known, 0.09);
        assert_eq!(r.runs, 1);
        assert!((polyline_length(&nodes) - 0.09).abs() < 1e-12);
        // Even spacing of 1 cm along the bent curve from the anchor (x = 3 cm).
        assert!((nodes[2] - Vec3::new(0.02, 0.0, 0.6)).norm() < 1e-12);
        assert!((nodes[1] - Vec3::new(0.01, 0.0, 0.6)).norm() < 1e-12);
        assert!((nodes[0] - Vec3::new(0.01, 0.01, 0.6)).norm() < 1e-12);
        // Compressed instead: left alone.
        let mut short = line(10, 0.01);
        short[0] = Vec3::new(0.015, 0.0, 0.6);
        let before = short.clone();
        let known: Vec<bool> = (0..10).map(|i| i > 0).collect();
        assert_eq!(conserve_end_lengths(&mut short, &known, 0.09).runs, 0);
        assert_eq!(short, before);
    }

    #[test]
    fn points_along_a_bent_curve_land_at_exact_arc_lengths() {
        // Segments of 1, 2 (repeated point in between) and 1, then straight on.
        let curve = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(2.0, 2.0, 0.0),
        ];
        let out = along(&RopeCurve::polyline(&curve), 6, 0.75);
        let expect = [
            Vec3::new(0.75, 0.0, 0.0),
            Vec3::new(1.0, 0.5, 0.0),
            Vec3::new(1.0, 1.25, 0.0),
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(1.75, 2.0, 0.0),
            Vec3::new(2.5, 2.0, 0.0),
        ];
        for (a, b) in out.iter().zip(&expect) {
            assert!((a - b).norm() < 1e-12, "{a:?} vs {b:?}");
        }
        let one = RopeCurve::polyline(&curve[..1]);
        assert_eq!(along(&one, 2, 1.0), alloc::vec![curve[0]; 2]);
    }

    #[test]
    fn the_report_gives_the_relative_change_and_both_ends_share_the_budget() {
        // Twelve nodes 1 cm apart, rope 11 cm; both ends hidden (0-1 and 10-11)
        // and each pushed out to 3 cm steps: 4 of the 8 cm of hidden length
        // 4 cm are allowed (11 - 7), shared 2 : 2.
        let mut nodes = line(12, 0.01);
        nodes[1] = Vec3::new(-0.02, 0.0, 0.6);
        nodes[0] = Vec3::new(-0.05, 0.0, 0.6);
        nodes[10] = Vec3::new(0.12, 0.0, 0.6);
        nodes[11] = Vec3::new(0.15, 0.0, 0.6);
        let known: Vec<bool> = (0..12).map(|i| (2..10).contains(&i)).collect();
        let r = conserve_end_lengths(&mut nodes, &known, 0.11);
        assert_eq!(r.runs, 2);
        // Each end: 7 cm long with its anchor segment, 2 cm allowed: 5/7.
        assert!(
            (r.largest_change - 5.0 / 7.0).abs() < 1e-12,
            "{}",
            r.largest_change
        );
        for (i, p) in nodes.iter().enumerate() {
            assert!((p.x - i as f64 * 0.01).abs() < 1e-12, "node {i}: {p:?}");
        }
        // Nothing to do on bad inputs.
        let before = nodes.clone();
        assert_eq!(conserve_end_lengths(&mut nodes, &known[..11], 0.11).runs, 0);
        assert_eq!(conserve_end_lengths(&mut nodes, &known, 0.0).runs, 0);
        assert_eq!(conserve_end_lengths(&mut nodes, &known, f64::NAN).runs, 0);
        assert_eq!(nodes, before);
    }

    #[test]
    fn a_single_visible_node_anchors_both_ends() {
        // Five nodes, only the middle one seen, both ends stretched to 2 cm
        // steps; the rope is 4 cm long: 2 cm for each end.
        let mut nodes: Vec<Vec3> = (0..5)
            .map(|i| Vec3::new((i as f64 - 2.0) * 0.02, 0.0, 0.6))
            .collect();
        let known = [false, false, true, false, false];
        let r = conserve_end_lengths(&mut nodes, &known, 0.04);
        assert_eq!(r.runs, 2);
        for (i, p) in nodes.iter().enumerate() {
            assert!(
                (p.x - (i as f64 - 2.0) * 0.01).abs() < 1e-12,
                "node {i}: {p:?}"
            );
        }
    }

    #[test]
    fn middle_runs_and_fully_visible_ropes_are_left_alone() {
        let mut nodes = line(10, 0.01);
        nodes[5].y = 0.02;
        let before = nodes.clone();
        let known: Vec<bool> = (0..10).map(|i| i != 5).collect();
        assert_eq!(conserve_end_lengths(&mut nodes, &known, 0.09).runs, 0);
        assert_eq!(conserve_end_lengths(&mut nodes, &[true; 10], 0.09).runs, 0);
        assert_eq!(conserve_end_lengths(&mut nodes, &[false; 10], 0.09).runs, 0);
        assert_eq!(nodes, before);
    }

    #[test]
    fn a_short_rope_is_given_its_length_back_where_the_images_allow() {
        // Ten nodes 1 cm apart (9 cm), a rope known to be 12 cm long.
        let nodes = line(10, 0.01);
        // Anything allowed: 1.5 cm at each end.
        let (out, r) = extend_short_ends(&nodes, 0.12, OpenEnds::BOTH, &|_| true);
        assert!((r.head - 0.015).abs() < 1e-12 && (r.tail - 0.015).abs() < 1e-12);
        assert!((polyline_length(&out) - 0.12).abs() < 1e-12);
        assert_eq!(out.len(), 12);
        assert!((out[0] - Vec3::new(-0.015, 0.0, 0.6)).norm() < 1e-12);
        // Free space beyond the head (x < 0): the tail takes it all.
        let (out, r) = extend_short_ends(&nodes, 0.12, OpenEnds::BOTH, &|p| p.x >= 0.0);
        assert_eq!(r.head, 0.0);
        assert!((r.tail - 0.03).abs() < 1e-12, "{r:?}");
        assert!((out[out.len() - 1] - Vec3::new(0.12, 0.0, 0.6)).norm() < 1e-12);
        // Free space 1 cm past the tail too: each end as far as it may go.
        let (_, r) = extend_short_ends(&nodes, 0.12, OpenEnds::BOTH, &|p| p.x >= 0.0 && p.x <= 0.1);
        assert!(r.head == 0.0 && (r.tail - 0.01).abs() < 1e-12, "{r:?}");
    }

    #[test]
    fn a_closed_end_is_not_extended_and_the_open_one_takes_the_shortfall() {
        let nodes = line(10, 0.01);
        let head_closed = OpenEnds {
            head: false,
            tail: true,
        };
        let (out, r) = extend_short_ends(&nodes, 0.12, head_closed, &|_| true);
        assert!(r.head == 0.0 && (r.tail - 0.03).abs() < 1e-12, "{r:?}");
        assert_eq!(out[0], nodes[0]);
        let shut = OpenEnds {
            head: false,
            tail: false,
        };
        let (out, r) = extend_short_ends(&nodes, 0.12, shut, &|_| true);
        assert_eq!((out, r), (nodes.clone(), ExtensionReport::default()));
    }

    #[test]
    fn hidden_end_runs_keep_the_rest_spacing_and_the_middle_is_spread() {
        // Ten nodes: a hidden head 0-1 compressed to 5 mm steps and bent at
        // node 1, a visible middle 2-7 whose nodes EM bunched, a hidden
        // tail 8-9 stretched to 2 cm steps; the rest spacing is 1 cm.
        let mut nodes = line(10, 0.01);
        nodes[1] = Vec3::new(0.015, 0.0, 0.6);
        nodes[0] = Vec3::new(0.015, 0.005, 0.6);
        nodes[3] = Vec3::new(0.021, 0.0, 0.6);
        nodes[8] = Vec3::new(0.09, 0.0, 0.6);
        nodes[9] = Vec3::new(0.11, 0.0, 0.6);
        let out =
            resample_with_end_runs_at_rest(&nodes, 2, 2, 10, 0.01, false, &|_| true).expect("runs");
        assert_eq!(out.len(), 10);
        // The middle (anchors 2 and 7 kept) spread evenly: 1 cm steps.
        for (i, p) in out.iter().enumerate().take(8).skip(2) {
            assert!((p.x - i as f64 * 0.01).abs() < 1e-12, "node {i}: {p:?}");
        }
        // The head: 5 mm back to the bend at node 1 and 5 mm up its curve
        // to its old tip, then 1 cm on straight past it.
        assert!(
            (out[1] - Vec3::new(0.015, 0.005, 0.6)).norm() < 1e-12,
            "{:?}",
            out[1]
        );
        assert!(
            (out[0] - Vec3::new(0.015, 0.015, 0.6)).norm() < 1e-12,
            "{:?}",
            out[0]
        );
        // The tail: drawn back in along its line to 1 cm steps.
        assert!((out[8].x - 0.08).abs() < 1e-12 && (out[9].x - 0.09).abs() < 1e-12);
    }

    #[test]
    fn end_runs_without_a_middle_to_spread_are_left_to_the_resampler() {
        let nodes = line(6, 0.01);
        let f = |head, tail| {
            resample_with_end_runs_at_rest(&nodes, head, tail, 6, 0.01, false, &|_| true)
        };
        assert_eq!(f(0, 0), None); // nothing hidden at an end
        assert_eq!(f(3, 2), None); // one node left between the runs
        assert_eq!(f(6, 0), None);
        assert_eq!(f(usize::MAX, 1), None);
        assert!(f(2, 2).is_some());
        // Fewer nodes than the runs and a middle need: nothing to spread.
        assert_eq!(
            resample_with_end_runs_at_rest(&nodes[..3], 1, 1, 6, 0.01, false, &|_| true),
            None
        );
        // A rest spacing that is not a positive length.
        for bad in [f64::NAN, 0.0, -0.01, f64::INFINITY] {
            assert_eq!(
                resample_with_end_runs_at_rest(&nodes, 1, 0, 6, bad, false, &|_| true),
                None,
                "{bad}"
            );
        }
    }

    /// Regression for "a hidden wave unrolls while the rope rests" (drawn
    /// scene 1072): a hidden end is re-spaced at the rest spacing from its
    /// anchor every frame, while EM's noise moves the anchor a little along
    /// the rope. Measured and placed on the run's polyline, each node moved
    /// along a chord, inside the bend, and the bend opened frame by frame;
    /// on the smooth curve through the nodes the run stays where it lay.
    #[test]
    fn a_hidden_end_re_spaced_every_frame_keeps_its_bend() {
        // Nodes 1 cm apart along a circle of 2 cm radius; the last eight
        // hidden, the rest spacing the arc's 1 cm.
        let radius = 0.02;
        let on_circle = |s: f64| on_circle(radius, s);
        let start: Vec<Vec3> = (0..12).map(|i| on_circle(0.01 * i as f64)).collect();
        let after = |smooth: bool| {
            let mut nodes = start.clone();
            for frame in 0..30 {
                // The anchor 1 mm along the rope, then back.
                let jitter = if frame % 2 == 0 { 0.001 } else { 0.0 };
                nodes[3] = on_circle(0.03 + jitter);
                nodes = resample_with_end_runs_at_rest(&nodes, 0, 8, 12, 0.01, smooth, &|_| true)
                    .expect("runs");
            }
            off_circle(&nodes, radius)
        };
        // Polyline 9.6 mm off the bend; curve 0.6 mm (the Catmull-Rom curve
        // is not exactly a circle at 0.5 rad a node).
        let (flat, curved) = (after(false), after(true));
        assert!(flat > 5e-3, "polyline: {:.2} mm off the bend", flat * 1e3);
        assert!(
            curved < 1.5e-3,
            "curve: {:.2} mm off the bend",
            curved * 1e3
        );
    }

    #[test]
    fn the_rest_length_leaves_out_a_rounded_tip_but_never_half_the_rope() {
        assert!((rest_length(0.8, 0.008) - (0.8 - TIP_TRIM_RADII * 0.008)).abs() < 1e-15);
        assert_eq!(rest_length(0.8, 0.0), 0.8);
        assert_eq!(rest_length(0.8, -1.0), 0.8);
        assert_eq!(rest_length(0.02, 1.0), 0.01);
        // A radius that is not a number is not trusted.
        assert_eq!(rest_length(0.8, f64::INFINITY), 0.8);
        assert_eq!(rest_length(0.8, f64::NAN), 0.8);
    }

    #[test]
    fn a_rope_at_its_length_or_a_bad_input_is_left_alone() {
        let nodes = line(10, 0.01);
        // Short by less than half a spacing.
        let (out, r) = extend_short_ends(&nodes, 0.094, OpenEnds::BOTH, &|_| true);
        assert_eq!((out, r), (nodes.clone(), ExtensionReport::default()));
        let (out, _) = extend_short_ends(&nodes, f64::NAN, OpenEnds::BOTH, &|_| true);
        assert_eq!(out, nodes);
        let mut bad = nodes.clone();
        bad[3].x = f64::NAN;
        let (out, r) = extend_short_ends(&bad, 0.2, OpenEnds::BOTH, &|_| true);
        assert_eq!(out.len(), 10);
        assert_eq!(r, ExtensionReport::default());
        // Two nodes at one place: no direction to go on in.
        let same = [Vec3::new(0.0, 0.0, 0.6); 2];
        let (out, r) = extend_short_ends(&same, 0.1, OpenEnds::BOTH, &|_| true);
        assert_eq!((out.len(), r), (2, ExtensionReport::default()));
    }

    /// A U of `n` nodes (odd), arms along x `arm` long and `gap` apart,
    /// with its bend (the middle `bend` nodes) drawn `depth` out to -x.
    fn hairpin(n: usize, arm: usize, gap: f64, depth: f64) -> Vec<Vec3> {
        let step = 0.01;
        (0..n)
            .map(|i| {
                if i < arm {
                    Vec3::new((arm - i) as f64 * step, gap / 2.0, 0.6)
                } else if i >= n - arm {
                    Vec3::new((i - (n - arm - 1)) as f64 * step, -gap / 2.0, 0.6)
                } else {
                    let t = (i - arm + 1) as f64 / (n - 2 * arm + 1) as f64;
                    let a = core::f64::consts::PI * t;
                    Vec3::new(-depth * libm::sin(a), gap / 2.0 * libm::cos(a), 0.6)
                }
            })
            .collect()
    }

    /// `hairpin(21, 7, 0.06, 0.04)` with its bend (nodes 6-14) hidden: a
    /// middle run between two visible arms.
    fn hidden_bend() -> (Vec<Vec3>, Vec<bool>) {
        let known = (0..21).map(|i| !(6..15).contains(&i)).collect();
        (hairpin(21, 7, 0.06, 0.04), known)
    }

    #[test]
    fn a_taut_run_keeps_its_curve_from_the_resting_anchor_and_goes_straight_to_the_pull() {
        // An L of length 2 from (0, 0) up to (0, 1), then to (1, 1), pulled
        // by (1, 1) to 1.8: s + sqrt(1 + (1 - s)^2) = 1.8 at s = 0.775.
        let p = |x: f64, y: f64| Vec3::new(x, y, 0.6);
        let run = [
            p(0.0, 0.0),
            p(0.0, 0.5),
            p(0.0, 1.0),
            p(0.5, 1.0),
            p(1.0, 1.0),
        ];
        let taut = taut_from_pulled_end(&run, 1.8);
        assert_eq!(taut.len(), 4);
        assert_eq!(taut[..2], run[..2]);
        assert!((taut[2] - p(0.0, 0.775)).norm() < 1e-8, "{:?}", taut[2]);
        assert_eq!(taut[3], run[4]);
        assert!((polyline_length(&taut) - 1.8).abs() < 1e-8);
        // Below the chord: the chord; not shorter: the curve.
        assert_eq!(taut_from_pulled_end(&run, 1.0), alloc::vec![run[0], run[4]]);
        assert_eq!(taut_from_pulled_end(&run, 2.5), run.to_vec());
    }

    /// Regression for "a hidden bend pulled by one end flattens as a whole"
    /// (drawn scenes 1054 and 1059, a rope dragged while part of it is
    /// hidden): a rope pulled by one end straightens from that end, and
    /// the bend at the other stays where it was.
    #[test]
    fn a_rope_pulled_by_one_end_straightens_from_that_end_and_keeps_its_far_bend() {
        let (before, known) = hidden_bend();
        let rest = polyline_length(&before) - 0.03;
        let on_old_curve = |q: &Vec3| {
            crate::polyline::distance_to_polyline(q, &before[5..=15]).is_some_and(|d| d < 1e-9)
        };
        // The stretch after the run (15-20) moved 1 cm outwards, along the rope.
        let out_end = (before[15] - before[14]).normalize();
        let mut previous = before.clone();
        for q in &mut previous[15..] {
            *q -= out_end * 0.01;
        }
        let mut pulled = before.clone();
        assert_eq!(
            conserve_middle_lengths(&mut pulled, &known, &previous, rest).runs,
            1
        );
        // Spread back over the run's nodes, the curve loses what its chords cut.
        let length = polyline_length(&pulled);
        assert!(
            length <= rest && length > 0.99 * rest,
            "{length} for {rest}"
        );
        assert!(pulled[6..=8].iter().all(on_old_curve), "the far bend moved");
        assert!(
            !on_old_curve(&pulled[13]),
            "the pulled side did not straighten"
        );
        // Pulled by the other end: the mirror image.
        let out_start = (before[5] - before[6]).normalize();
        let mut previous = before.clone();
        for q in &mut previous[..=5] {
            *q -= out_start * 0.01;
        }
        let mut other = before.clone();
        conserve_middle_lengths(&mut other, &known, &previous, rest);
        assert!(other[12..=14].iter().all(on_old_curve) && !on_old_curve(&other[7]));
        // Nothing moved outwards (both stretches inwards, one less): scaled
        // from the chord as a whole.
        let mut inwards = before.clone();
        for q in &mut inwards[15..] {
            *q += out_end * 0.01;
        }
        for q in &mut inwards[..=5] {
            *q += out_start * 0.02;
        }
        let (mut a, mut b) = (before.clone(), before.clone());
        conserve_middle_lengths(&mut a, &known, &inwards, rest);
        conserve_middle_lengths(&mut b, &known, &[], rest);
        assert_eq!(a, b);
        assert!(!on_old_curve(&a[7]));
    }

    /// Regression for "the pulled arm told by its nodes' mean move"
    /// (pulled-through: a U bend whose arm is pulled along itself; EM's
    /// nodes on a straight arm slide as they spread over its points, and the
    /// other arm's read as the pulled one, 4.8 mm instead of 3.1).
    #[test]
    fn the_pulled_side_is_told_by_the_tip_of_its_stretch() {
        let (before, known) = hidden_bend();
        let (out_start, out_end) = (
            (before[5] - before[6]).normalize(),
            (before[15] - before[14]).normalize(),
        );
        // The start arm's inner nodes slid out 5 mm but its tip went in 5 mm;
        // the end arm's tip went out 1 cm, its other nodes did not move.
        let mut previous = before.clone();
        for q in &mut previous[1..=5] {
            *q -= out_start * 0.005;
        }
        previous[0] += out_start * 0.005;
        previous[20] -= out_end * 0.01;
        let run = HiddenRun { start: 6, end: 15 };
        let side = |pull: Option<Pull>| pull.map(|p| p.side);
        let pull = pulled_side(&before, &known, &previous, run);
        assert_eq!(side(pull), Some(Side::End));
        // The other tip went in 5 mm: that much rope went into the run
        // there, so 5 mm of the pulled tip's 1 cm left it.
        assert!((pull.map_or(0.0, |p| p.slid_out) - 0.005).abs() < 1e-12);
        // A stretch between two runs has no tip: its node farthest from the run.
        let mut known = known;
        known[18] = false;
        previous[17] -= out_end * 0.02;
        assert_eq!(
            side(pulled_side(&before, &known, &previous, run)),
            Some(Side::End)
        );
        // Both tips out (the bend carried along): only the difference slid out.
        previous[0] = before[0] - out_start * 0.015;
        let both = pulled_side(&before, &known, &previous, run);
        assert_eq!(side(both), Some(Side::End));
        assert!((both.map_or(0.0, |p| p.slid_out) - 0.005).abs() < 1e-12);
        previous[0] = before[0] + out_start * 0.005;
        previous[17] = before[17];
        assert_eq!(pulled_side(&before, &known, &previous, run), None);
    }

    #[test]
    fn a_rope_pulled_out_from_under_an_occluder_tightens_its_hidden_bend() {
        let (mut nodes, known) = hidden_bend();
        let before = nodes.clone();
        let total = polyline_length(&nodes);
        // The visible rope leaves 3 cm less for the bend than it holds.
        let rest = total - 0.03;
        let r = conserve_middle_lengths(&mut nodes, &known, &[], rest);
        assert_eq!(r.runs, 1);
        assert!((polyline_length(&nodes) - rest).abs() < 1e-6);
        for i in (0..21).filter(|&i| known[i]) {
            assert_eq!(nodes[i], before[i], "visible node {i} moved");
        }
        // Tighter: the apex nearer the anchors' chord (x = 0.01), not flipped.
        assert!(nodes[10].x > before[10].x && nodes[10].x < 0.01);
        // Fed under the occluder instead (3 cm more): left as it is.
        let mut fed = before.clone();
        assert_eq!(
            conserve_middle_lengths(&mut fed, &known, &[], total + 0.03).runs,
            0
        );
        assert_eq!(fed, before);
    }

    /// Regression for "the pulled-through rope grows in steps of half a
    /// spacing": an excess under `MIN_SHORTFALL_SPACINGS` was left until it
    /// passed the threshold, so the rope pulled through grew 2-3 % and
    /// snapped back (`pulled-through`: 3.3 % at worst). With a pull seen,
    /// the run gives up what slid out on this frame, at most the excess.
    #[test]
    fn a_small_excess_is_given_up_as_far_as_the_rope_was_seen_to_slide_out() {
        let (before, known) = hidden_bend();
        let total = polyline_length(&before);
        let spacing = total / 20.0;
        let rest = total - 0.3 * spacing;
        let out_end = (before[20] - before[19]).normalize();
        let pulled_by = |slid: f64| {
            let mut previous = before.clone();
            previous[20] -= out_end * slid;
            let mut nodes = before.clone();
            conserve_middle_lengths(&mut nodes, &known, &previous, rest);
            polyline_length(&nodes)
        };
        // Pulled 2 mm: the run gives up those 2 mm of the excess (0.3 of a
        // spacing, 3.7 mm), and a little more where its nodes, spread
        // evenly, cut the new corner of this tight hairpin.
        let (little, far) = (pulled_by(0.002), pulled_by(0.05));
        assert!(little < total - 0.002 + 1e-9, "{little} of {total}");
        // Pulled farther than the excess: down to the rest length.
        assert!(
            far < rest + 1e-9 && far < little - 0.001,
            "{far} / {little}"
        );
        // No pull seen: the small excess stays (noise).
        let mut resting = before.clone();
        conserve_middle_lengths(&mut resting, &known, &before, rest);
        assert_eq!(resting, before);
    }

    #[test]
    fn a_hidden_bend_asked_for_less_than_its_chord_is_laid_straight() {
        let (before, known) = hidden_bend();
        let mut nodes = before.clone();
        let r = conserve_middle_lengths(&mut nodes, &known, &[], 0.1);
        assert_eq!(r.runs, 1);
        for p in &nodes[6..15] {
            assert!((p.x - before[5].x).abs() < 1e-12, "{p:?}");
        }
    }

    #[test]
    fn a_middle_run_within_half_a_spacing_of_its_share_or_bad_input_is_left() {
        let (before, known) = hidden_bend();
        let total = polyline_length(&before);
        let spacing = total / 20.0;
        for rest in [total - 0.4 * spacing, f64::NAN, -1.0] {
            let mut nodes = before.clone();
            assert_eq!(
                conserve_middle_lengths(&mut nodes, &known, &[], rest).runs,
                0
            );
            assert_eq!(nodes, before);
        }
        let mut nodes = before.clone();
        nodes[3].x = f64::NAN;
        assert_eq!(
            conserve_middle_lengths(&mut nodes, &known, &[], total - 0.03).runs,
            0
        );
        assert_eq!(
            conserve_middle_lengths(&mut nodes, &known[..5], &[], total).runs,
            0
        );
    }

    #[test]
    fn a_hidden_end_short_of_its_curve_stops_where_the_images_forbid_a_rope() {
        // Eight nodes on a line, the last three hidden but bunched up 5 mm
        // apart: at the rest spacing (1 cm) the tail goes on straight past
        // x = 0.06 ...
        let mut nodes = line(8, 0.01);
        for (k, i) in (5..8).enumerate() {
            nodes[i] = Vec3::new(0.045 + 0.005 * k as f64, 0.0, 0.6);
        }
        let free =
            resample_with_end_runs_at_rest(&nodes, 0, 3, 8, 0.01, false, &|_| true).expect("runs");
        assert!((free[7].x - 0.07).abs() < 1e-9, "{:?}", free[7]);
        // ... but not into free space beyond x = 0.062: the three nodes
        // share what there is.
        let walled = |p: &Vec3| p.x <= 0.062;
        let kept =
            resample_with_end_runs_at_rest(&nodes, 0, 3, 8, 0.01, false, &walled).expect("runs");
        assert!(
            kept[7].x <= 0.062 + 1e-9 && kept[7].x > 0.055,
            "{:?}",
            kept[7]
        );
        assert!(kept[6].x < kept[7].x && kept[5].x < kept[6].x);
    }

    /// Regression for "an end node in view stops short of the rope's tip"
    /// (EM leaves it inside the tip: on the drawn tuning range the end
    /// nodes seen stopped 6.9 mm short on the median sequence, 19 mm at
    /// the p90).
    #[test]
    fn a_seen_end_reaches_the_tip_its_mask_shows_less_a_radius() {
        // Ten nodes 1 cm apart along x; the mask covers x in
        // [-4 mm, 96 mm] (a rope from -2 to 94 mm with rounded ends).
        let nodes: Vec<Vec3> = (0..10)
            .map(|k| Vec3::new(0.01 * k as f64, 0.0, 0.6))
            .collect();
        let (spacing, radius) = (0.01, 0.002);
        let mask = |p: &Vec3| p.x >= -0.004 - 1e-9 && p.x <= 0.096 + 1e-9;
        let tail = seen_tip(&nodes, 9, spacing, radius, &mask).expect("tail");
        assert!((tail.x - 0.094).abs() < 1e-9, "{tail:?}");
        let head = seen_tip(&nodes, 0, spacing, radius, &mask).expect("head");
        assert!((head.x + 0.002).abs() < 1e-9, "{head:?}");
        // Rope all the way: half a spacing at most.
        let far = seen_tip(&nodes, 9, spacing, radius, &|_| true).expect("far");
        assert!((far.x - 0.095).abs() < 1e-9, "{far:?}");
        // No rope beyond, a middle node, a step of nothing: no tip.
        assert_eq!(seen_tip(&nodes, 9, spacing, radius, &|p| p.x <= 0.09), None);
        assert_eq!(seen_tip(&nodes, 4, spacing, radius, &|_| true), None);
        assert_eq!(seen_tip(&nodes, 9, spacing, 0.0, &|_| true), None);
    }

    #[test]
    fn a_seen_end_does_not_walk_onto_another_part_of_the_rope() {
        // The rope's middle (node 5) comes back 3 mm past the tail end.
        let mut nodes: Vec<Vec3> = (0..10)
            .map(|k| Vec3::new(0.01 * k as f64, 0.0, 0.6))
            .collect();
        nodes[5] = Vec3::new(0.093, 0.0, 0.6);
        assert_eq!(seen_tip(&nodes, 9, 0.01, 0.002, &|_| true), None);
    }
}
