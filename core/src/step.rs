//! The per-frame tracking step, the one stage that differs between
//! algorithms. Segmentation, the point cloud, initialisation, loss and
//! re-initialisation are shared by [`crate::tracker::Tracker`]; each
//! algorithm only turns the previous nodes and this frame's cloud into new
//! nodes: UPETrack (visibility, GMM-EM, UPE, resampling), CPD (deformable
//! coherent point drift from the previous nodes) or TrackDLO.

use alloc::vec::Vec;

use crate::camera::CameraIntrinsics;
use crate::cpd::{matrix_to_points, points_to_matrix, register_deformable, thin_to_pair_cap};
use crate::math::{self, Vec3};
use crate::occlusion::{estimate_hidden, UpeReport};
use crate::params::Params;
use crate::registration::{register, EmReport};
use crate::resampling::resample_uniform;
use crate::trackdlo::{TrackDloReport, TrackDloState};

/// The tracking algorithms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "lowercase"))]
pub enum Algorithm {
    /// UPETrack, the paper's tracker.
    #[default]
    Upetrack,
    /// Deformable coherent point drift from the previous nodes (baseline).
    Cpd,
    /// TrackDLO (Xiang et al. 2023), reimplemented (baseline).
    Trackdlo,
}

impl Algorithm {
    /// Every algorithm, UPETrack first.
    pub const ALL: [Algorithm; 3] = [Algorithm::Upetrack, Algorithm::Cpd, Algorithm::Trackdlo];

    /// The name used on the command line and in result files.
    pub fn name(self) -> &'static str {
        match self {
            Algorithm::Upetrack => "upetrack",
            Algorithm::Cpd => "cpd",
            Algorithm::Trackdlo => "trackdlo",
        }
    }

    /// The algorithm of a name given by [`Algorithm::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|a| a.name() == name)
    }
}

/// What a step needs: the nodes of the previous frame and this frame's cloud.
#[derive(Debug, Clone, Copy)]
pub struct StepInput<'a> {
    /// The `M` nodes after the previous frame.
    pub previous: &'a [Vec3],
    /// This frame's downsampled cloud on the rope's centre line.
    pub cloud: &'a [Vec3],
    /// UPETrack's visibility of the previous nodes (the tracker's shared
    /// test for loss; UPETrack's own step uses it too).
    pub visible: &'a [bool],
    /// The camera.
    pub camera: &'a CameraIntrinsics,
    /// The parameters in force.
    pub params: &'a Params,
}

/// What a step produced.
#[derive(Debug, Clone, PartialEq)]
pub struct StepOutput {
    /// The new nodes.
    pub nodes: Vec<Vec3>,
    /// The visibility the algorithm used (for CPD, which has none: the
    /// shared test's, for display).
    pub visible: Vec<bool>,
    /// UPETrack's registration report.
    pub em: Option<EmReport>,
    /// UPETrack's occlusion report.
    pub upe: Option<UpeReport>,
    /// TrackDLO's report.
    pub trackdlo: Option<TrackDloReport>,
}

impl StepOutput {
    /// New nodes and visibility, with no algorithm-specific report.
    pub fn nodes(nodes: Vec<Vec3>, visible: Vec<bool>) -> Self {
        Self {
            nodes,
            visible,
            em: None,
            upe: None,
            trackdlo: None,
        }
    }
}

/// One algorithm's per-frame step and its state between frames.
pub trait TrackingStep {
    /// Which algorithm this is.
    fn algorithm(&self) -> Algorithm;
    /// Called with freshly (re)initialised nodes: forget per-track state.
    fn start(&mut self, nodes: &[Vec3]);
    /// New nodes from the previous ones and this frame's cloud.
    fn step(&mut self, input: &StepInput<'_>) -> StepOutput;
}

/// UPETrack's step: GMM-EM of the visible nodes, UPE of the hidden ones,
/// uniform resampling.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct UpeTrackStep;

impl TrackingStep for UpeTrackStep {
    fn algorithm(&self) -> Algorithm {
        Algorithm::Upetrack
    }

    fn start(&mut self, _nodes: &[Vec3]) {}

    fn step(&mut self, input: &StepInput<'_>) -> StepOutput {
        let p = input.params;
        let mut nodes = input.previous.to_vec();
        let em = register(input.cloud, &mut nodes, input.visible, &p.em());
        let upe = estimate_hidden(&mut nodes, input.visible, input.previous, &p.upe());
        StepOutput {
            em: Some(em),
            upe: Some(upe),
            ..StepOutput::nodes(
                resample_uniform(&nodes, p.node_count),
                input.visible.to_vec(),
            )
        }
    }
}

/// Plain deformable CPD from the previous nodes, `sigma^2` started from the
/// data each frame; no occlusion handling beyond its coherence.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CpdStep;

impl TrackingStep for CpdStep {
    fn algorithm(&self) -> Algorithm {
        Algorithm::Cpd
    }

    fn start(&mut self, _nodes: &[Vec3]) {}

    fn step(&mut self, input: &StepInput<'_>) -> StepOutput {
        let y = points_to_matrix(input.previous);
        let x = points_to_matrix(&thin_to_pair_cap(input.cloud, input.previous.len()));
        // An empty cloud leaves the nodes where they were.
        let nodes = match register_deformable(&x, &y, None, &input.params.cpd) {
            Ok(out) => matrix_to_points(&out.points),
            Err(_) => input.previous.to_vec(),
        };
        StepOutput::nodes(nodes, input.visible.to_vec())
    }
}

/// TrackDLO's step; its state is the rest coordinates and `sigma^2`.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TrackDloStep {
    state: Option<TrackDloState>,
}

impl TrackingStep for TrackDloStep {
    fn algorithm(&self) -> Algorithm {
        Algorithm::Trackdlo
    }

    fn start(&mut self, nodes: &[Vec3]) {
        self.state = Some(TrackDloState::new(nodes));
    }

    fn step(&mut self, input: &StepInput<'_>) -> StepOutput {
        let state = self
            .state
            .get_or_insert_with(|| TrackDloState::new(input.previous));
        let mut nodes = input.previous.to_vec();
        let (visible, report) = state.step(
            &mut nodes,
            input.cloud,
            input.camera,
            &input.params.trackdlo,
        );
        StepOutput {
            trackdlo: Some(report),
            ..StepOutput::nodes(nodes, visible)
        }
    }
}

/// The step of the algorithm in force, dispatched without boxing so that
/// the tracker stays `Clone` and its snapshots serialisable.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Stepper {
    /// UPETrack.
    Upetrack,
    /// CPD.
    Cpd,
    /// TrackDLO with its state.
    Trackdlo(TrackDloStep),
}

impl Stepper {
    /// A fresh step of `algorithm`.
    pub fn new(algorithm: Algorithm) -> Self {
        match algorithm {
            Algorithm::Upetrack => Stepper::Upetrack,
            Algorithm::Cpd => Stepper::Cpd,
            Algorithm::Trackdlo => Stepper::Trackdlo(TrackDloStep { state: None }),
        }
    }
}

impl TrackingStep for Stepper {
    fn algorithm(&self) -> Algorithm {
        match self {
            Stepper::Upetrack => Algorithm::Upetrack,
            Stepper::Cpd => Algorithm::Cpd,
            Stepper::Trackdlo(_) => Algorithm::Trackdlo,
        }
    }

    fn start(&mut self, nodes: &[Vec3]) {
        if let Stepper::Trackdlo(s) = self {
            s.start(nodes);
        }
    }

    fn step(&mut self, input: &StepInput<'_>) -> StepOutput {
        let mut out = match self {
            Stepper::Upetrack => UpeTrackStep.step(input),
            Stepper::Cpd => CpdStep.step(input),
            Stepper::Trackdlo(s) => s.step(input),
        };
        if out.nodes.len() != input.previous.len() || !out.nodes.iter().all(math::is_finite) {
            // Cannot happen with finite inputs; keep the last good nodes if it does.
            out.nodes = input.previous.to_vec();
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for a in Algorithm::ALL {
            assert_eq!(Algorithm::from_name(a.name()), Some(a));
            assert_eq!(Stepper::new(a).algorithm(), a);
        }
        assert_eq!(Algorithm::from_name("gltp"), None);
    }
}
