//! One frame of the tracker explained (the demo's explain mode): what the
//! frame's update did, and, for a UPETrack step, every stage of it. The
//! tracker itself is not changed.

use alloc::vec::Vec;

use super::{FrameOutput, Observation, Tracker};
use crate::math::Vec3;
use crate::perception::frame::Frame;
use crate::step::Algorithm;
use crate::upe::explain::StepExplanation;
use crate::upe::visibility::neighbour_count;
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
    /// Every stage of the UPETrack step, when the frame was tracked by one.
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
        let radius = self.params.visibility_radius;
        let neighbour_counts = previous
            .iter()
            .map(|y| neighbour_count(y, &obs.cloud, radius))
            .collect();
        let visible = self.visibility(&previous, &obs.cloud);
        let tracked = output.status == super::FrameStatus::Tracked;
        let step = (tracked && self.params.algorithm == Algorithm::Upetrack).then(|| {
            let camera = self.camera;
            let input = self.step_input(&camera, frame, obs, &previous, &visible);
            UpeTrackStep::explain(&input, &self.params.upetrack).1
        });
        FrameExplanation {
            output,
            previous,
            neighbour_counts,
            visible,
            step,
        }
    }
}
