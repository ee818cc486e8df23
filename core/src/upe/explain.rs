//! What one UPETrack step did, stage by stage, for a page that shows the
//! algorithm at work (the demo's explain mode): the EM iterations with the
//! state each started from, the two sweeps of the occlusion estimate, and
//! the nodes before and after each later stage. Made by
//! [`super::UpeTrackStep::explain`], which runs the step itself.

use alloc::vec::Vec;

use super::occlusion::HiddenSweeps;
use super::registration::EmIteration;
use crate::math::Vec3;

/// One EM iteration's start (Eq. 4-5).
#[derive(Debug, Clone, PartialEq)]
pub struct EmStage {
    /// `sigma^2` of the E-step, square metres.
    pub variance: f64,
    /// `mu` of the E-step (Eq. 4).
    pub outlier_term: f64,
    /// Every node before the iteration's M-step.
    pub nodes: Vec<Vec3>,
}

impl EmStage {
    /// The stage an iteration reported.
    pub fn of(it: &EmIteration<'_>) -> Self {
        Self {
            variance: it.variance,
            outlier_term: it.outlier_term,
            nodes: it.nodes.to_vec(),
        }
    }
}

/// Every stage of one step.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepExplanation {
    /// The EM iterations, in order.
    pub em: Vec<EmStage>,
    /// The nodes after EM (hidden ones where they were).
    pub registered: Vec<Vec3>,
    /// The occlusion estimate's sweeps (Eq. 6-11).
    pub sweeps: HiddenSweeps,
    /// Hidden nodes of a run at an end of the rope (`alpha_end`, the slide).
    pub end_runs: Vec<bool>,
    /// The nodes after the occlusion estimate.
    pub estimated: Vec<Vec3>,
    /// The nodes after length conservation, the free-space check, the ends'
    /// extension and the emerged ends.
    pub before_resampling: Vec<Vec3>,
    /// The nodes after resampling (Eq. 12-15): the step's output.
    pub resampled: Vec<Vec3>,
}
