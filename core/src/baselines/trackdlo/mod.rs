//! TrackDLO (Xiang et al., RA-L 2023), reimplemented as a baseline from its
//! paper and its public source: node visibility with a self-occlusion test,
//! visible nodes extended across short gaps, a pre-registration of the
//! visible ("guide") nodes by CPD-LLE, correspondence priors from walking
//! along the guide nodes at the rest spacing (five occlusion cases), and a
//! final CPD on the distance along the rope with the priors and a visibility
//! weighting of the responsibilities. Deviations from the source are listed
//! in `docs/algorithm-notes.md` ("TrackDLO baseline").
//!
//! Its stages, one module each: [`visibility`], [`registration`] (CPD-LLE,
//! used twice per frame), [`priors`]; [`settings`] holds its parameters.

use alloc::vec::Vec;

pub mod priors;
pub mod registration;
pub mod settings;
pub mod visibility;

pub use priors::{OcclusionCase, Prior};
pub use registration::{CpdLleReport, CpdLleSettings};
pub use settings::TrackDloParams;

use crate::math::Vec3;
use crate::perception::camera::CameraIntrinsics;
use crate::polyline::arc_coordinates;
use crate::step::{Algorithm, StepInput, StepOutput, TrackingStep};
use priors::correspondence_priors;
use registration::cpd_lle;
use visibility::{extend_visible, node_visibility};

/// What a TrackDLO step decided, for display and tests.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackDloReport {
    /// The occlusion case (`None` when no node was visible).
    pub case: Option<OcclusionCase>,
    /// The correspondence priors, by node index.
    pub priors: Vec<Prior>,
    /// The guide nodes after the pre-registration (the extended visible
    /// nodes, in order).
    pub guide: Vec<Vec3>,
    /// The final registration.
    pub registration: CpdLleReport,
}

/// TrackDLO's state between frames: the rest coordinates along the rope and `sigma^2`.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TrackDloState {
    /// Distance of each node from the first along the rope at initialisation, metres.
    pub rest: Vec<f64>,
    /// `sigma^2` carried between frames (0: start from the data).
    pub variance: f64,
}

impl TrackDloState {
    /// State for freshly initialised nodes.
    pub fn new(nodes: &[Vec3]) -> Self {
        Self {
            rest: arc_coordinates(nodes),
            variance: 0.0,
        }
    }

    /// One frame: moves `nodes` onto `cloud`; returns the visibility of the
    /// nodes before the move and what was done.
    pub fn step(
        &mut self,
        nodes: &mut [Vec3],
        cloud: &[Vec3],
        camera: &CameraIntrinsics,
        params: &TrackDloParams,
    ) -> (Vec<bool>, TrackDloReport) {
        if self.rest.len() != nodes.len() {
            *self = Self::new(nodes);
        }
        let visible = node_visibility(nodes, cloud, camera, params);
        let extended = extend_visible(&visible, &self.rest, params.d_vis);
        let report = self.step_with_visibility(nodes, cloud, &extended, params);
        (visible, report)
    }

    /// The step after visibility: pre-registration of the nodes marked in
    /// `extended` (the visible ones with short gaps filled), priors, final
    /// registration. Moves `nodes` in place.
    pub fn step_with_visibility(
        &mut self,
        nodes: &mut [Vec3],
        cloud: &[Vec3],
        extended: &[bool],
        params: &TrackDloParams,
    ) -> TrackDloReport {
        if self.rest.len() != nodes.len() || extended.len() != nodes.len() {
            *self = Self::new(nodes);
        }
        let mut guide: Vec<Vec3> = (0..nodes.len())
            .filter(|&i| extended[i])
            .map(|i| nodes[i])
            .collect();
        let idle = TrackDloReport {
            case: None,
            priors: Vec::new(),
            guide: Vec::new(),
            registration: CpdLleReport {
                iterations: 0,
                converged: false,
            },
        };
        if guide.is_empty() {
            return idle;
        }
        let mut pre_variance = self.variance;
        let pre = CpdLleSettings {
            beta: params.beta_pre_proc,
            lambda: params.lambda_pre_proc,
            lle_weight: params.lle_weight,
            alpha: 0.0,
            mu: params.mu,
            max_iterations: params.max_iterations,
            tolerance: params.tolerance,
            k_vis: 0.0,
            visibility_threshold: params.visibility_threshold,
        };
        cpd_lle(cloud, &mut guide, &mut pre_variance, &pre, &[], None);
        let (case, priors) = correspondence_priors(extended, &guide, nodes, &self.rest);
        let main = CpdLleSettings {
            beta: params.beta,
            lambda: params.lambda,
            lle_weight: 0.0,
            alpha: params.alpha,
            k_vis: params.k_vis,
            ..pre
        };
        let registration = cpd_lle(
            cloud,
            nodes,
            &mut self.variance,
            &main,
            &priors,
            Some(extended),
        );
        TrackDloReport {
            case,
            priors,
            guide,
            registration,
        }
    }
}

/// TrackDLO's step; its state is the rest coordinates and `sigma^2`.
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TrackDloStep {
    state: Option<TrackDloState>,
}

impl TrackingStep for TrackDloStep {
    type Settings = TrackDloParams;
    type Report = TrackDloReport;
    const ALGORITHM: Algorithm = Algorithm::Trackdlo;

    fn start(&mut self, nodes: &[Vec3]) {
        self.state = Some(TrackDloState::new(nodes));
    }

    fn fits(&self, nodes: &[Vec3]) -> bool {
        self.state.as_ref().is_none_or(|s| {
            s.rest.len() == nodes.len()
                && s.rest.iter().all(|r| r.is_finite())
                && s.variance.is_finite()
                && s.variance >= 0.0
        })
    }

    fn step(
        &mut self,
        input: &StepInput<'_>,
        settings: &TrackDloParams,
    ) -> StepOutput<TrackDloReport> {
        let state = self
            .state
            .get_or_insert_with(|| TrackDloState::new(input.previous));
        let mut nodes = input.previous.to_vec();
        let (visible, report) = state.step(&mut nodes, input.cloud, input.camera, settings);
        StepOutput {
            nodes,
            visible,
            report,
        }
    }
}

#[cfg(test)]
mod testing {
    //! Hand-made ropes for the stage tests.
    use alloc::vec::Vec;

    use crate::math::Vec3;

    /// `m` nodes on a straight line along x, `spacing` apart, 0.6 m away.
    pub fn line(m: usize, spacing: f64) -> Vec<Vec3> {
        (0..m)
            .map(|i| Vec3::new(i as f64 * spacing, 0.0, 0.6))
            .collect()
    }

    /// A visibility pattern of `m` nodes with `hidden` hidden.
    pub fn mask(m: usize, hidden: &[usize]) -> Vec<bool> {
        (0..m).map(|i| !hidden.contains(&i)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::testing::line;
    use super::*;

    #[test]
    fn a_step_with_no_points_leaves_the_nodes_alone() {
        let mut nodes = line(8, 0.02);
        let before = nodes.clone();
        let mut state = TrackDloState::new(&nodes);
        let (visible, report) = state.step(
            &mut nodes,
            &[],
            &CameraIntrinsics::D435I_640X480,
            &TrackDloParams::default(),
        );
        assert_eq!(nodes, before);
        assert!(visible.iter().all(|&v| !v));
        assert_eq!(report.case, None);
    }
}
