//! The nodes a tracked frame reports: the step's state with UPETrack's
//! readouts (visible nodes on their bends, end nodes in view at the
//! rope's tips), which the next frame does not start from.

use alloc::vec::Vec;

use super::{Observation, Stepper, Tracker};
use crate::math::Vec3;
use crate::perception::frame::Frame;
use crate::upe::length::seen_tip;

impl Tracker {
    /// The nodes to report of a step's state `nodes` (`Stepper::reported`),
    /// with UPETrack's end nodes in view where the rope's tips are seen
    /// when `report_seen_tips` is set.
    pub(super) fn reported(
        &self,
        nodes: Vec<Vec3>,
        visible: &[bool],
        frame: &Frame<'_>,
        obs: &Observation,
    ) -> Vec<Vec3> {
        let mut out = self.stepper.reported(nodes.clone(), visible, &self.params);
        let upe = matches!(self.stepper, Stepper::Upetrack);
        let spacing = self.rest_spacing(nodes.len());
        if let (true, true, Some(spacing)) = (upe, self.params.upetrack.report_seen_tips, spacing) {
            let e = self.evidence(&self.camera, frame, obs);
            for end in [0, nodes.len().saturating_sub(1)] {
                if visible.get(end) == Some(&true) {
                    let shows = |p: &Vec3| e.shows_rope_at(p);
                    if let Some(tip) = seen_tip(&nodes, end, spacing, e.radius, &shows) {
                        out[end] = tip;
                    }
                }
            }
        }
        out
    }
}
