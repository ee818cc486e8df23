//! Going back to an earlier frame (the page's timeline): the state a
//! tracker carries from frame to frame, taken and restored.

use super::{Tracker, TrackerError, TrackerSnapshot};
use crate::math;
use crate::params::{MAX_NODES, MIN_NODES};
use crate::polyline::resample_uniform;
use crate::tracker::stepper::Stepper;

impl Tracker {
    /// The state after the last frame.
    pub fn snapshot(&self) -> TrackerSnapshot {
        TrackerSnapshot {
            state: self.state.clone(),
            known_length: self.known_length,
            known_radius: self.known_radius,
            known_cover: self.known_cover,
            known_diameter: self.known_diameter,
            rest_length: self.rest_length,
            rope_node_count: self.rope_node_count,
            refused_jump_cloud: self.refused_jump_cloud,
            recovery: self.recovery,
            stepper: self.stepper.clone(),
        }
    }

    /// Goes back to a state taken by [`Tracker::snapshot`]. Its nodes are
    /// resampled to the count in force: the rope's count the snapshot
    /// carries while `Params::node_spacing_diameters` sets counts (at least
    /// `Params::node_count`), else `Params::node_count`. One taken with
    /// another node count or algorithm, or whose step state does not fit its
    /// nodes, starts the step afresh. A snapshot with non-finite nodes or
    /// lengths is refused and the tracker left as it was.
    pub fn restore(&mut self, snapshot: TrackerSnapshot) -> Result<(), TrackerError> {
        let bad = |reason| Err(TrackerError::Snapshot { reason });
        if let Some(s) = &snapshot.state {
            if !s.nodes.iter().all(math::is_finite) {
                return bad("a node is not finite");
            }
        }
        let lengths = [
            snapshot.known_length,
            snapshot.known_radius,
            snapshot.known_diameter,
            snapshot.rest_length,
        ];
        if lengths.iter().flatten().any(|l| !l.is_finite() || *l < 0.0) {
            return bad("a length is negative or not finite");
        }
        // The push divides by it.
        if snapshot.known_cover.is_some_and(|c| !(c > 0.0 && c <= 1.0)) {
            return bad("the share of the rope's width its mask covers is not in (0, 1]");
        }
        if snapshot
            .rope_node_count
            .is_some_and(|m| !(MIN_NODES..=MAX_NODES).contains(&m))
        {
            return bad("the rope's node count is outside the accepted range");
        }
        let mut restart = snapshot.stepper.algorithm() != self.params.algorithm;
        // The parameters may have changed since (the page's panel).
        let rope = snapshot
            .rope_node_count
            .filter(|_| self.params.node_spacing_diameters > 0.0)
            .map(|m| m.max(self.params.node_count));
        let m = rope.unwrap_or(self.params.node_count);
        self.state = snapshot.state.map(|mut s| {
            if s.nodes.len() != m && !s.nodes.is_empty() {
                s.nodes = resample_uniform(&s.nodes, m);
                restart = true;
            }
            s
        });
        self.known_length = snapshot.known_length;
        self.known_radius = snapshot.known_radius;
        self.known_cover = snapshot.known_cover;
        self.known_diameter = snapshot.known_diameter;
        self.rest_length = snapshot.rest_length;
        self.rope_node_count = rope;
        self.refused_jump_cloud = snapshot.refused_jump_cloud;
        self.recovery = snapshot.recovery;
        self.stepper = snapshot.stepper;
        if restart || !self.stepper.fits(self.nodes()) {
            self.stepper = Stepper::new(self.params.algorithm);
            let nodes = self.nodes().to_vec();
            self.stepper.start(&nodes);
        }
        Ok(())
    }
}
