//! When a tracked state contradicts the images (the three tests, what a
//! rope found again says of the points beside it), and how often it is
//! then replaced: recoveries in a row back off.

use alloc::vec::Vec;

use super::stepper::StepReports;
use crate::math::{self, Vec3};
use crate::perception::sharing::{Axis, RopeLine};
use crate::polyline::polyline_length;
use crate::upe::emerging::near_not_rope;
use crate::upe::length::rest_spacing;

/// A tracked rope longer than this multiple of its length at
/// initialisation contradicts the images (ropes do not stretch).
pub const STRETCH_LIMIT: f64 = 1.2;
/// Hidden nodes that must stay in free space for the state to contradict the images.
pub const MIN_NODES_IN_FREE_SPACE: usize = 3;
/// A cloud point farther than this many visibility radii from the axis
/// through the nodes is rope the nodes do not explain.
pub const UNEXPLAINED_REACH: f64 = 2.0;
/// Share of the cloud left unexplained that contradicts the state.
pub const UNEXPLAINED_LIMIT: f64 = 0.3;
/// What the images say against the nodes after a step, as the three
/// recovery tests measure it; [`Contradiction::contradicts`] is `true`
/// when any test fires: the rope stretched past [`STRETCH_LIMIT`] of its
/// rest length, most hidden nodes left in free space (at least
/// [`MIN_NODES_IN_FREE_SPACE`]), or more than [`UNEXPLAINED_LIMIT`] of the
/// cloud farther than the reach from the axis through the nodes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Contradiction {
    /// The tracked length over the rest length (`None` without one).
    pub stretch: Option<f64>,
    /// Hidden nodes the free-space stage found in free space.
    pub hidden_in_free_space: usize,
    /// Of those, the ones still in free space after its correction.
    pub left_in_free_space: usize,
    /// Share of the cloud the nodes do not explain, leaving out points of
    /// things remembered beside the rope.
    pub unexplained: f64,
}

/// Whether a point lies within `reach` of the axis through `nodes`.
/// Measured from the axis between the nodes, not from the nodes: a rope's
/// points lie up to half a node spacing from the nearest node, which on a
/// long rope is more than the reach.
fn near_axis(nodes: &[Vec3], reach: f64) -> impl FnMut(&Vec3) -> bool {
    let axis = Axis::of(&RopeLine { nodes, radius: 0.0 });
    let mut start = 0;
    move |x| axis.axis_within(x, reach, &mut start)
}

/// The finite points of `cloud` (a point that is not finite is no
/// evidence of rope) farther than `reach` from the axis through `nodes`.
fn far_from_axis(nodes: &[Vec3], cloud: &[Vec3], reach: f64) -> Vec<Vec3> {
    let mut near = near_axis(nodes, reach);
    cloud
        .iter()
        .filter(|x| math::is_finite(x) && !near(x))
        .copied()
        .collect()
}

/// The share of `cloud` farther than `reach` from the axis through
/// `nodes` ([`far_from_axis`]); a point within a link of `not_rope`
/// (things seen beside the rope, `rest_spacing` apart) is left out of
/// the count and of the cloud it is a share of.
fn unexplained_share(
    nodes: &[Vec3],
    cloud: &[Vec3],
    reach: f64,
    not_rope: &[Vec3],
    rest_spacing: Option<f64>,
) -> f64 {
    let mut far = far_from_axis(nodes, cloud, reach);
    let mut total = cloud.len();
    // Only the far points are looked up: the memory holds up to 256.
    if let (Some(spacing), false) = (rest_spacing, not_rope.is_empty()) {
        let before = far.len();
        far.retain(|p| !near_not_rope(p, not_rope, spacing));
        total -= before - far.len();
    }
    if total == 0 {
        0.0
    } else {
        far.len() as f64 / total as f64
    }
}

impl Contradiction {
    /// The three measures of `nodes` against `cloud`, the step's `report`
    /// and the rope's `rest_length`; a point farther than `reach` (metres)
    /// from the axis through the nodes is unexplained, unless it is one of
    /// the things remembered beside the rope (`not_rope`).
    pub fn measure(
        nodes: &[Vec3],
        cloud: &[Vec3],
        report: &StepReports,
        rest_length: Option<f64>,
        reach: f64,
        not_rope: &[Vec3],
    ) -> Self {
        let rest_length = rest_length.filter(|&l| l > 0.0);
        let stretch = rest_length.map(|l| polyline_length(nodes) / l);
        let free = report.free_space.unwrap_or_default();
        let spacing = rest_length.map(|l| rest_spacing(l, nodes.len()));
        let unexplained = unexplained_share(nodes, cloud, reach, not_rope, spacing);
        Self {
            stretch,
            hidden_in_free_space: free.found,
            left_in_free_space: free.left,
            unexplained,
        }
    }

    /// The rope stretched past [`STRETCH_LIMIT`] (ropes do not stretch).
    pub fn stretched(&self) -> bool {
        self.stretch.is_some_and(|s| s > STRETCH_LIMIT)
    }

    /// Most hidden nodes found in free space stayed there.
    pub fn in_free_space(&self) -> bool {
        let (left, found) = (self.left_in_free_space, self.hidden_in_free_space);
        left >= MIN_NODES_IN_FREE_SPACE && 2 * left > found
    }

    /// More than [`UNEXPLAINED_LIMIT`] of the cloud is rope the nodes do
    /// not explain.
    pub fn unexplained_cloud(&self) -> bool {
        self.unexplained > UNEXPLAINED_LIMIT
    }

    /// Only the unexplained cloud fired: the state may be right and the
    /// cloud hold something beside the rope.
    pub fn only_unexplained(&self) -> bool {
        self.unexplained_cloud() && !self.stretched() && !self.in_free_space()
    }

    /// `true` when the nodes cannot be the rope in these images.
    pub fn contradicts(&self) -> bool {
        self.stretched() || self.in_free_space() || self.unexplained_cloud()
    }

    /// The names of the tests that fire, in the order above: `stretched`,
    /// `free_space`, `unexplained`.
    pub fn fired(&self) -> impl Iterator<Item = &'static str> {
        [
            (self.stretched(), "stretched"),
            (self.in_free_space(), "free_space"),
            (self.unexplained_cloud(), "unexplained"),
        ]
        .into_iter()
        .filter_map(|(fired, name)| fired.then_some(name))
    }
}

/// What came of a step once the recovery tests had read it (named in the
/// result JSON by [`Verdict::name`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// No test fired: the state agrees with the images.
    Agreed,
    /// A test fired, but recoveries in a row back off
    /// ([`RecoveryBackoff`]): the state is kept for this frame.
    Waited,
    /// A test fired and the images were searched, but no rope was found
    /// in them: the state is kept.
    NothingFound,
    /// The rope found is not as thick as the one tracked (another
    /// rope-coloured thing): the state is kept.
    OtherThickness,
    /// Only the unexplained cloud fired and the rope found is the one
    /// tracked: what contradicted lies beside it and is remembered.
    BesideTheRope,
    /// The rope found leaves out rope the state sees (a node seen on the
    /// rope lies beyond the unexplained reach of it): it is something
    /// else, or only part of the rope, and the state is kept.
    LeavesSeenRopeOut,
    /// The state was replaced by the rope found again.
    Recovered,
}

impl Verdict {
    /// The verdict's name in the result JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Agreed => "agreed",
            Self::Waited => "waited",
            Self::NothingFound => "nothing_found",
            Self::OtherThickness => "other_thickness",
            Self::BesideTheRope => "beside_the_rope",
            Self::LeavesSeenRopeOut => "leaves_seen_rope_out",
            Self::Recovered => "recovered",
        }
    }
}

/// The recovery tests' reading of one step, and what came of it: what
/// makes a recovery, or a missing one, explainable after the fact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Judgement {
    /// What the three tests measured.
    pub measured: Contradiction,
    /// What the tracker did about it.
    pub verdict: Verdict,
    /// Cloud points the tests read.
    pub cloud_points: usize,
    /// The rope found when the images were searched (`None` when they
    /// were not, or held no rope).
    pub found: Option<FoundAgain>,
}

/// A rope found again after a step that contradicted the images, taken or
/// not: what a refused recovery was offered.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FoundAgain {
    /// Its length, metres.
    pub length: f64,
    /// Its diameter as the rope test measures it, metres (`None` when not
    /// measured).
    pub diameter: Option<f64>,
    /// The nodes the state sees (visible, with rope points beside them)
    /// that it leaves out.
    pub seen_left_out: usize,
}

/// How many of the `visible` `nodes` (nodes with rope points beside them
/// in this frame) lie farther than `reach` from the axis through `found`,
/// the nodes of a rope found again: seen rope that rope would leave out.
pub fn seen_left_out(nodes: &[Vec3], visible: &[bool], found: &[Vec3], reach: f64) -> usize {
    let seen: Vec<Vec3> = nodes
        .iter()
        .zip(visible)
        .filter_map(|(n, &v)| v.then_some(*n))
        .collect();
    far_from_axis(found, &seen, reach).len()
}

/// Points of `cloud` beside the rope, when the tracked `nodes` (those
/// `visible` on rope points) are the rope an initialisation `found` (its
/// nodes) on the same images: every visible node, and the middle of every
/// segment between two, lies inside that rope (within its `radius` of the
/// found axis: a coarse state's chord across a bend does not), and of the
/// points within
/// `reach` of that axis
/// at most [`UNEXPLAINED_LIMIT`] lie farther than `reach` from the nodes'
/// (the unexplained test on the rope's own points). The points neither
/// explains are then something rope-coloured beside the rope that the
/// initialisation set aside by its shape, not rope the state missed;
/// `None` when the state misses the rope found or sits on something else.
pub fn beside_rope_found(
    nodes: &[Vec3],
    visible: &[bool],
    found: &[Vec3],
    cloud: &[Vec3],
    (radius, reach): (f64, f64),
) -> Option<Vec<Vec3>> {
    let mut seen: Vec<Vec3> = nodes
        .iter()
        .zip(visible)
        .filter_map(|(n, &v)| v.then_some(*n))
        .collect();
    seen.extend(
        nodes
            .windows(2)
            .zip(visible.windows(2))
            .filter(|(_, v)| v[0] && v[1])
            .map(|(n, _)| 0.5 * (n[0] + n[1])),
    );
    if !far_from_axis(found, &seen, radius).is_empty() {
        return None;
    }
    let mut on_rope_found = near_axis(found, reach);
    let (on_found, off_found): (Vec<Vec3>, Vec<Vec3>) = cloud
        .iter()
        .filter(|x| math::is_finite(x))
        .partition(|x| on_rope_found(x));
    let missed = unexplained_share(nodes, &on_found, reach, &[], None);
    if on_found.is_empty() || missed > UNEXPLAINED_LIMIT {
        return None;
    }
    Some(far_from_axis(nodes, &off_found, reach))
}

/// Longest wait, in frames, between recoveries from steps that contradict
/// the images (`2^k - 1` frames after the `k`-th recovery in a row): a
/// recovery costs a whole initialisation (10-50 ms at 1280x720, against
/// half a millisecond for a step), so a state that keeps contradicting
/// the images costs at most about one initialisation in this many frames,
/// yet is still retried. 63 frames: two seconds at 30 frames/s.
pub const MAX_RECOVERY_WAIT: u32 = 63;

/// How often a state that contradicts the images is re-initialised: after
/// the `k`-th recovery in a row, the next waits `2^k - 1` frames (at most
/// [`MAX_RECOVERY_WAIT`]); a step that agrees with the images ends the row.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RecoveryBackoff {
    /// Recoveries since the last step that agreed with the images.
    in_a_row: u32,
    /// Frames still to wait before the next recovery.
    wait: u32,
}

impl RecoveryBackoff {
    /// `true` when a recovery may run on this frame; else one frame of the
    /// wait passes.
    pub(super) fn may_recover(&mut self) -> bool {
        if self.wait == 0 {
            return true;
        }
        self.wait -= 1;
        false
    }

    /// A recovery ran (taken or not): the next one waits longer.
    pub(super) fn recovered(&mut self) {
        self.in_a_row = self.in_a_row.saturating_add(1);
        self.wait = 1u32
            .checked_shl(self.in_a_row)
            .map_or(MAX_RECOVERY_WAIT, |w| (w - 1).min(MAX_RECOVERY_WAIT));
    }

    /// A step agreed with the images: recoveries run at once again.
    pub(super) fn agreed(&mut self) {
        *self = Self::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recoveries_in_a_row_back_off_exponentially_up_to_the_cap() {
        let mut b = RecoveryBackoff::default();
        let mut ran = Vec::new();
        for frame in 0..200 {
            if b.may_recover() {
                ran.push(frame);
                b.recovered();
            }
        }
        assert_eq!(ran[..7], [0, 2, 6, 14, 30, 62, 126]);
        let gaps: Vec<u32> = ran.windows(2).map(|w| w[1] - w[0]).collect();
        assert!(gaps.iter().all(|&g| g <= MAX_RECOVERY_WAIT + 1), "{gaps:?}");
        assert_eq!(gaps.last(), Some(&(MAX_RECOVERY_WAIT + 1)));
        b.agreed();
        assert!(b.may_recover());
        for _ in 0..100 {
            b.recovered();
        }
        assert_eq!(b.wait, MAX_RECOVERY_WAIT);
    }

    /// `nodes` moved `dy` metres across the rope (along y).
    fn moved_across(nodes: &[Vec3], dy: f64) -> Vec<Vec3> {
        nodes.iter().map(|n| n + Vec3::new(0.0, dy, 0.0)).collect()
    }

    /// A straight rope of `length` metres seen as points every millimetre
    /// along its axis and a radius (7.5 mm) to one side, and 24 nodes on
    /// its axis.
    fn rope_and_nodes(length: f64) -> (Vec<Vec3>, Vec<Vec3>) {
        let points = (0..=(length * 1000.0) as usize)
            .map(|i| Vec3::new(i as f64 * 1e-3, 0.0075, 1.0))
            .collect();
        let nodes = (0..24)
            .map(|k| Vec3::new(length * k as f64 / 23.0, 0.0, 1.0))
            .collect();
        (points, nodes)
    }

    /// Regression for "a long rope tracked exactly is re-initialised": the
    /// unexplained cloud was measured from the nodes, and a rope's points
    /// lie up to half a node spacing from the nearest one; with 24 nodes
    /// on a 3 m rope that is 6.5 cm, beyond the 4 cm reach for 38 % of
    /// the points, so every step was taken for one that contradicts the
    /// images.
    #[test]
    fn a_long_rope_tracked_exactly_does_not_contradict_the_images() {
        let reach = UNEXPLAINED_REACH * 0.02;
        let (points, nodes) = rope_and_nodes(3.0);
        let reports = StepReports::default();
        let exact = Contradiction::measure(&nodes, &points, &reports, Some(3.0), reach, &[]);
        assert!(!exact.contradicts(), "{exact:?}");
        // The same nodes 5 cm beside the rope explain none of it.
        let beside = moved_across(&nodes, 0.05);
        let off = Contradiction::measure(&beside, &points, &reports, Some(3.0), reach, &[]);
        assert!(off.contradicts(), "{off:?}");
        assert_eq!(off.fired().collect::<Vec<_>>(), ["unexplained"]);
    }

    /// A square of points 20 cm beside the middle of the straight rope of
    /// [`rope_and_nodes`], 5 mm apart, 12 cm a side: as many points as
    /// 0.6 of the rope's.
    fn block_beside(length: f64) -> Vec<Vec3> {
        let mut block = Vec::new();
        for i in 0..24 {
            for j in 0..24 {
                let (x, y) = (i as f64 * 0.005, j as f64 * 0.005);
                block.push(Vec3::new(0.5 * length - 0.06 + x, 0.2 + y, 0.97));
            }
        }
        block
    }

    #[test]
    fn things_remembered_beside_the_rope_are_not_unexplained_rope() {
        let reach = UNEXPLAINED_REACH * 0.02;
        let (mut cloud, nodes) = rope_and_nodes(1.0);
        let block = block_beside(1.0);
        cloud.extend(&block);
        let reports = StepReports::default();
        let unknown = Contradiction::measure(&nodes, &cloud, &reports, Some(1.0), reach, &[]);
        assert!(unknown.unexplained_cloud(), "{unknown:?}");
        assert!(unknown.only_unexplained());
        // Remembered at the memory's own spacing (a quarter of a rest
        // spacing, 1.1 cm here): every point of the block is near one.
        let mut memory = Vec::new();
        crate::upe::emerging::remember_not_rope(&mut memory, &block, 1.0 / 23.0);
        let known = Contradiction::measure(&nodes, &cloud, &reports, Some(1.0), reach, &memory);
        assert_eq!(known.unexplained, 0.0, "{known:?}");
        assert!(!known.contradicts());
    }

    #[test]
    fn the_rope_found_again_where_the_nodes_are_leaves_the_rest_beside_it() {
        let reach = UNEXPLAINED_REACH * 0.02;
        let (mut cloud, nodes) = rope_and_nodes(1.0);
        let block = block_beside(1.0);
        cloud.extend(&block);
        let visible = [true; 24];
        // The same rope, found with other nodes: the block is beside it.
        let found: Vec<Vec3> = (0..17)
            .map(|k| Vec3::new(k as f64 / 16.0, 0.0, 1.0))
            .collect();
        let beside = beside_rope_found(&nodes, &visible, &found, &cloud, (0.0075, reach));
        assert_eq!(beside.as_deref(), Some(&block[..]));
        // Nodes 5 cm off the rope found are not that rope.
        let off = moved_across(&nodes, 0.05);
        assert_eq!(
            beside_rope_found(&off, &visible, &found, &cloud, (0.0075, reach)),
            None
        );
        // Nodes 1 cm beside it explain its points (within the 4 cm reach)
        // but lie outside the rope (7.5 mm radius): a coarse state the
        // rope found is to replace.
        let beside_it = moved_across(&nodes, 0.01);
        assert_eq!(
            beside_rope_found(&beside_it, &visible, &found, &cloud, (0.0075, reach)),
            None
        );
        // Nodes on only the first half miss half the rope found.
        let half: Vec<Vec3> = nodes
            .iter()
            .map(|n| Vec3::new(0.5 * n.x, 0.0, 1.0))
            .collect();
        assert_eq!(
            beside_rope_found(&half, &visible, &found, &cloud, (0.0075, reach)),
            None
        );
        // A visible node on the block is on something else.
        let mut onto = nodes.clone();
        onto[12] = block[300];
        assert_eq!(
            beside_rope_found(&onto, &visible, &found, &cloud, (0.0075, reach)),
            None
        );
        // Unless hidden: a hidden node may lie anywhere the step put it.
        let mut hidden = visible;
        hidden[12] = false;
        assert!(beside_rope_found(&onto, &hidden, &found, &cloud, (0.0075, reach)).is_some());
    }

    /// Regression for "a recovery takes a box's edge joined to part of the
    /// rope and loses the rope the state sees" (drawn 1032, frame 30).
    #[test]
    fn a_rope_found_that_leaves_seen_rope_out_is_counted_by_its_seen_nodes() {
        let reach = UNEXPLAINED_REACH * 0.02;
        let (_, nodes) = rope_and_nodes(1.0);
        let visible = [true; 24];
        // The whole rope found again, 1 cm off (a coarse state): nothing left out.
        assert_eq!(
            seen_left_out(&nodes, &visible, &moved_across(&nodes, 0.01), reach),
            0
        );
        // Only its first half found, with something else beyond it: the
        // seen nodes past the reach of that half are left out...
        let half: Vec<Vec3> = nodes.iter().take(12).copied().collect();
        let mut other = half.clone();
        other.extend((1..6).map(|k| Vec3::new(0.48, 0.05 * k as f64, 1.0)));
        let left = seen_left_out(&nodes, &visible, &other, reach);
        assert_eq!(left, 12);
        // ...unless the step did not see them: hidden nodes may be anywhere.
        let mut seen_half = visible;
        seen_half[12..].fill(false);
        assert_eq!(seen_left_out(&nodes, &seen_half, &other, reach), 0);
    }
}
