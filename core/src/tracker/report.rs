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
        let last = nodes.len().saturating_sub(1);
        let spacing = self.rest_spacing(nodes.len());
        let upe = matches!(self.stepper, Stepper::Upetrack);
        let tips = match (upe && self.params.upetrack.report_seen_tips, spacing) {
            (true, Some(spacing)) => {
                let e = self.evidence(&self.camera, frame, obs);
                let shows = |p: &Vec3| e.shows_rope_at(p);
                [0, last].map(|end| {
                    let seen = visible.get(end) == Some(&true);
                    seen.then(|| seen_tip(&nodes, end, spacing, e.radius, &shows))
                        .flatten()
                })
            }
            _ => [None, None],
        };
        let mut out = self.stepper.reported(nodes, visible, &self.params);
        for (end, tip) in [0, last].into_iter().zip(tips) {
            if let Some(tip) = tip {
                out[end] = tip;
            }
        }
        out
    }
}
