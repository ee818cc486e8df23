//! [`Tracker::explain`]: a frame's update with the stages that led to it,
//! for the page's step-by-step view.

use alloc::vec::Vec;

use super::{FrameOutput, Observation, Tracker};
use crate::math::Vec3;
use crate::perception::frame::Frame;
use crate::step::Algorithm;
use crate::upe::explain::StepExplanation;
use crate::upe::UpeTrackStep;

/// What [`Tracker::explain`] found.
#[derive(Debug, Clone)]
pub struct FrameExplanation {
    /// The frame's update, as [`Tracker::update`] gives it.
    pub output: FrameOutput,
    /// The nodes before the frame (empty when the frame initialised).
    pub previous: Vec<Vec3>,
    /// Cloud points within `r_vis` of each previous node (`q`).
    pub neighbour_counts: Vec<usize>,
    /// The shared visibility of the previous nodes.
    pub visible: Vec<bool>,
    /// Every stage of the UPETrack step, when one ran (the frame was
    /// tracked, or recovered after the step contradicted the images; its
    /// recovery tests are `output.judgement`).
    pub step: Option<StepExplanation>,
}

impl Tracker {
    /// Explains the update of `frame` (observed as `obs`) from the present
    /// state, without changing it: the same result [`Tracker::update`]
    /// would give, with the stages that led to it.
    pub fn explain(&self, frame: &Frame<'_>, obs: &Observation) -> FrameExplanation {
        let output = self.clone().update(frame, obs);
        let previous = match &self.state {
            Some(s) if !s.lost => s.nodes.clone(),
            _ => Vec::new(),
        };
        let classes = self.visibility(
            &previous,
            &obs.cloud,
            &self.evidence(&self.camera, frame, obs),
        );
        // A step ran when the recovery tests read one: on a tracked frame,
        // and on one recovered after its step contradicted the images.
        let stepped = output.judgement.is_some();
        let step = (stepped && self.params.algorithm == Algorithm::Upetrack).then(|| {
            let camera = self.camera;
            let not_rope = self.state.as_ref().map_or(&[][..], |s| &s.not_rope);
            let input = self.step_input(&camera, frame, obs, &previous, &classes, not_rope);
            UpeTrackStep::explain(&input, &self.params.upetrack).1
        });
        FrameExplanation {
            output,
            previous,
            neighbour_counts: classes.counts,
            visible: classes.visible,
            step,
        }
    }
}
