//! After each step: the state checked against the images
//! ([`Contradiction`]) and, when it contradicts them, replaced by the rope
//! found again, unless that rope is the one tracked and what contradicted
//! lay beside it.

use alloc::vec::Vec;
use core::ops::ControlFlow;

use super::recovery::{
    beside_rope_found, seen_left_out, Contradiction, FoundAgain, Judgement, Verdict,
    UNEXPLAINED_REACH,
};
use super::stepper::StepReports;
use super::{FrameOutput, FrameStatus, Observation, Tracker};
use crate::math::Vec3;
use crate::perception::frame::Frame;
use crate::perception::initialisation::Initialisation;
use crate::step::StepOutput;
use crate::upe::emerging;

impl Tracker {
    /// Checks the step's `out` (from the `previous` nodes) against the images: a state that
    /// contradicts them is replaced by the rope found again (as often as
    /// the back-off allows, by a rope as thick as the one tracked), unless
    /// only the unexplained cloud fired and the rope found is the one
    /// tracked: then the state is kept. `Continue` with the points to
    /// remember beside the rope and the judgement, or `Break` with the
    /// recovered frame.
    pub(super) fn judge_step(
        &mut self,
        frame: &Frame<'_>,
        obs: &Observation,
        (previous, out): (&[Vec3], &StepOutput<StepReports>),
        not_rope: &[Vec3],
    ) -> ControlFlow<FrameOutput, (Vec<Vec3>, Judgement)> {
        let measured = self.contradiction(&out.nodes, &obs.cloud, &out.report, not_rope);
        let judged = |verdict, found| Judgement {
            measured,
            verdict,
            cloud_points: obs.cloud.len(),
            found,
        };
        let kept = |verdict, found| ControlFlow::Continue((Vec::new(), judged(verdict, found)));
        if !measured.contradicts() {
            self.recovery.agreed();
            return kept(Verdict::Agreed, None);
        }
        if !self.recovery.may_recover() {
            return kept(Verdict::Waited, None);
        }
        let attempt = self.find_rope(frame, obs).ok();
        self.recovery.recovered();
        let Some(init) = attempt else {
            return kept(Verdict::NothingFound, None);
        };
        let reach = self.unexplained_reach();
        let found = FoundAgain {
            length: init.length,
            diameter: init.diameter(),
            seen_left_out: seen_left_out(previous, &out.visible, &init.nodes, reach),
        };
        if !self.as_thick_as_tracked(&init) {
            return kept(Verdict::OtherThickness, Some(found));
        }
        // A state that sees most of its rope is mostly right: a rope found
        // that leaves out rope it sees is not the whole rope, and replacing
        // the state would lose what is seen. Seen: the previous nodes with
        // this frame's rope points beside them (the step may have dragged
        // them off). Not where ropes alike share the frame: a node may be
        // seen on another.
        let sees_most = crate::visibility::sees_most(&out.visible);
        let alike = obs.others.as_ref().is_some_and(|o| o.alike);
        if sees_most && !alike && found.seen_left_out > 0 {
            return kept(Verdict::LeavesSeenRopeOut, Some(found));
        }
        let step = (&out.nodes[..], &out.visible[..]);
        match self.beside_the_rope_found(step, &init, &obs.cloud, &measured) {
            Some(beside) => {
                ControlFlow::Continue((beside, judged(Verdict::BesideTheRope, Some(found))))
            }
            None => {
                let mut again = self.adopt(init, frame, obs);
                again.status = FrameStatus::Recovered(measured);
                again.judgement = Some(judged(Verdict::Recovered, Some(found)));
                ControlFlow::Break(again)
            }
        }
    }

    /// What the images say against the nodes after a step, leaving out
    /// the things remembered beside the rope ([`Contradiction::measure`]).
    fn contradiction(
        &self,
        nodes: &[Vec3],
        cloud: &[Vec3],
        report: &StepReports,
        not_rope: &[Vec3],
    ) -> Contradiction {
        let reach = self.unexplained_reach();
        Contradiction::measure(nodes, cloud, report, self.rest_length, reach, not_rope)
    }

    /// How far from the axis through the nodes a point of the cloud is
    /// rope they do not explain: [`UNEXPLAINED_REACH`] visibility radii.
    fn unexplained_reach(&self) -> f64 {
        UNEXPLAINED_REACH * self.params.visibility_radius
    }

    /// When only the unexplained cloud contradicted the state, the state
    /// has hidden nodes (the shape a re-initialisation would lose) and the
    /// step's nodes (and their visibility) are the rope `init` found
    /// again, the points of `cloud` beside that rope
    /// ([`beside_rope_found`]); `None` when the rope found is to replace
    /// the state.
    fn beside_the_rope_found(
        &self,
        (nodes, visible): (&[Vec3], &[bool]),
        init: &Initialisation,
        cloud: &[Vec3],
        against: &Contradiction,
    ) -> Option<Vec<Vec3>> {
        let hides = visible.iter().any(|&v| !v);
        if !against.only_unexplained() || !hides {
            return None;
        }
        let spacing = self.rest_spacing(nodes.len())?;
        let reach = self.unexplained_reach();
        let beside = beside_rope_found(nodes, visible, &init.nodes, cloud, (self.radius(), reach))?;
        // Only what no hidden run could reach is remembered: a point
        // within reach may be its rope, a fragment the initialisation set
        // aside, which a hidden end coming out must still be able to take.
        Some(emerging::beyond_hidden_reach(
            nodes, visible, &beside, spacing,
        ))
    }
}
