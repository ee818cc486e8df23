//! The step of the algorithm in force, dispatched without boxing so that the
//! tracker stays `Clone` and its snapshots serialisable. Adding an algorithm
//! adds one variant here.

#[cfg(feature = "cdcpd2")]
use crate::baselines::cdcpd2::{Cdcpd2Report, Cdcpd2Step};
use crate::baselines::cpd::CpdStep;
use crate::baselines::trackdlo::{TrackDloReport, TrackDloStep};
use alloc::vec::Vec;

use crate::math::{self, Vec3};
use crate::params::Params;
use crate::step::{Algorithm, StepInput, StepOutput, TrackingStep};
use crate::upe::free_space::FreeSpaceReport;
use crate::upe::occlusion::UpeReport;
use crate::upe::registration::EmReport;
use crate::upe::UpeTrackStep;

/// What any algorithm's step reported, one field per kind of report.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StepReports {
    /// UPETrack's registration report.
    pub em: Option<EmReport>,
    /// UPETrack's occlusion report.
    pub upe: Option<UpeReport>,
    /// TrackDLO's report.
    pub trackdlo: Option<TrackDloReport>,
    /// UPETrack's free-space check.
    pub free_space: Option<FreeSpaceReport>,
    /// CDCPD2's report.
    #[cfg(feature = "cdcpd2")]
    pub cdcpd2: Option<Cdcpd2Report>,
}

/// One of the algorithms' steps, with its state.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Stepper {
    /// UPETrack.
    Upetrack,
    /// CPD.
    Cpd,
    /// TrackDLO with its state.
    Trackdlo(TrackDloStep),
    /// CDCPD2 with its state.
    #[cfg(feature = "cdcpd2")]
    Cdcpd2(Cdcpd2Step),
}

impl Stepper {
    /// A fresh step of `algorithm`.
    pub fn new(algorithm: Algorithm) -> Self {
        match algorithm {
            Algorithm::Upetrack => Stepper::Upetrack,
            Algorithm::Cpd => Stepper::Cpd,
            Algorithm::Trackdlo => Stepper::Trackdlo(TrackDloStep::default()),
            #[cfg(feature = "cdcpd2")]
            Algorithm::Cdcpd2 => Stepper::Cdcpd2(Cdcpd2Step::default()),
            // Refused by `Params::validate` in a build without the feature.
            #[cfg(not(feature = "cdcpd2"))]
            Algorithm::Cdcpd2 => Stepper::Upetrack,
        }
    }

    /// Which algorithm this is.
    pub fn algorithm(&self) -> Algorithm {
        match self {
            Stepper::Upetrack => UpeTrackStep::ALGORITHM,
            Stepper::Cpd => CpdStep::ALGORITHM,
            Stepper::Trackdlo(_) => TrackDloStep::ALGORITHM,
            #[cfg(feature = "cdcpd2")]
            Stepper::Cdcpd2(_) => Cdcpd2Step::ALGORITHM,
        }
    }

    /// Called with freshly (re)initialised nodes.
    pub fn start(&mut self, nodes: &[Vec3]) {
        match self {
            Stepper::Upetrack => UpeTrackStep.start(nodes),
            Stepper::Cpd => CpdStep.start(nodes),
            Stepper::Trackdlo(s) => s.start(nodes),
            #[cfg(feature = "cdcpd2")]
            Stepper::Cdcpd2(s) => s.start(nodes),
        }
    }

    /// `true` when the step's state belongs to `nodes` ([`TrackingStep::fits`]).
    pub fn fits(&self, nodes: &[Vec3]) -> bool {
        match self {
            Stepper::Upetrack => UpeTrackStep.fits(nodes),
            Stepper::Cpd => CpdStep.fits(nodes),
            Stepper::Trackdlo(s) => s.fits(nodes),
            #[cfg(feature = "cdcpd2")]
            Stepper::Cdcpd2(s) => s.fits(nodes),
        }
    }

    /// The nodes to report of a step's `nodes` (its state): UPETrack's
    /// visible nodes on their bends' arcs when `report_on_arcs` is set
    /// (`upe::bends`), every other algorithm's as they are.
    pub fn reported(&self, mut nodes: Vec<Vec3>, visible: &[bool], params: &Params) -> Vec<Vec3> {
        if matches!(self, Stepper::Upetrack) && params.upetrack.report_on_arcs {
            crate::upe::bends::onto_arcs(&mut nodes, visible);
        }
        nodes
    }

    /// The step, with the algorithm's settings taken from `params`. A state
    /// that does not fit the previous nodes is started afresh first; nodes
    /// that come out of the wrong count or not finite are replaced by the
    /// previous ones.
    pub fn step(&mut self, input: &StepInput<'_>, params: &Params) -> StepOutput<StepReports> {
        if !self.fits(input.previous) {
            self.start(input.previous);
        }
        let mut out = match self {
            Stepper::Upetrack => {
                UpeTrackStep
                    .step(input, &params.upetrack)
                    .map_report(|r| StepReports {
                        em: Some(r.em),
                        upe: Some(r.upe),
                        free_space: Some(r.free_space),
                        ..StepReports::default()
                    })
            }
            Stepper::Cpd => CpdStep
                .step(input, &params.cpd)
                .map_report(|()| StepReports::default()),
            Stepper::Trackdlo(s) => s.step(input, &params.trackdlo).map_report(|r| StepReports {
                trackdlo: Some(r),
                ..StepReports::default()
            }),
            #[cfg(feature = "cdcpd2")]
            Stepper::Cdcpd2(s) => s.step(input, &params.cdcpd2).map_report(|r| StepReports {
                cdcpd2: Some(r),
                ..StepReports::default()
            }),
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

    /// A state of another rope (a restored snapshot): TrackDLO's rest
    /// coordinates for 3 nodes, stepped with 24. It indexed past its rest
    /// coordinates and panicked (the page's worker died on the next frame).
    #[test]
    fn a_step_state_of_another_node_count_is_started_afresh_not_a_panic() {
        use crate::baselines::trackdlo::TrackDloStep;
        use crate::CameraIntrinsics;
        use alloc::{vec, vec::Vec};
        let short: Vec<Vec3> = (0..3)
            .map(|i| Vec3::new(i as f64 * 0.01, 0.0, 0.6))
            .collect();
        let mut other = TrackDloStep::default();
        other.start(&short);
        let nodes: Vec<Vec3> = (0..24)
            .map(|i| Vec3::new(i as f64 * 0.01, 0.0, 0.6))
            .collect();
        assert!(!other.fits(&nodes) && other.fits(&short));
        let mut stepper = Stepper::Trackdlo(other);
        let visible = vec![true; nodes.len()];
        let input = StepInput {
            previous: &nodes,
            cloud: &nodes,
            visible: &visible,
            partly_seen: &[],
            camera: &CameraIntrinsics::D435I_640X480,
            evidence: None,
            rest_length: None,
            frame_interval: 1.0 / crate::perception::camera::DEFAULT_FPS,
            not_rope: &[],
        };
        let out = stepper.step(&input, &Params::default());
        assert_eq!(out.nodes.len(), nodes.len());
        assert!(stepper.fits(&nodes));
    }

    /// Regression for "the free-space test never fired": UPETrack's
    /// free-space report was left out of [`StepReports`], so the recovery
    /// test of hidden nodes left in free space (`Contradiction::measure`)
    /// always read none. A hidden tip over bare table with nothing beside
    /// it to turn into: found, not cleared, and reported.
    #[test]
    fn the_free_space_report_reaches_the_recovery_tests() {
        use crate::perception::evidence::fixture::Table;
        use crate::tracker::recovery::Contradiction;
        // A bare table at 0.6 m, nothing declared hiding anything: the
        // three visible nodes lie on rope points, the hidden tip over table.
        let table = Table::new(64, 48, 60.0, 600);
        let frame = table.frame();
        let evidence = table.evidence(&frame, &[], 0.0075);
        let previous = table.tip_along_row_24();
        let cloud = table.rope_along_row_24();
        let visible = [true, true, true, false, false, false];
        let input = StepInput {
            previous: &previous,
            cloud: &cloud,
            visible: &visible,
            partly_seen: &[],
            camera: &table.camera,
            evidence: Some(evidence),
            rest_length: None,
            frame_interval: 1.0 / crate::perception::camera::DEFAULT_FPS,
            not_rope: &[],
        };
        let out = Stepper::Upetrack.step(&input, &Params::default());
        let free = out
            .report
            .free_space
            .expect("UPETrack reports its free-space stage");
        assert_eq!((free.found, free.left), (3, 3), "{free:?}");
        let against = Contradiction::measure(&out.nodes, &cloud, &out.report, None, 0.01, &[]);
        assert!(against.in_free_space(), "{against:?}");
    }

    #[test]
    fn every_algorithm_has_a_step() {
        for a in Algorithm::ALL {
            assert_eq!(Stepper::new(a).algorithm(), a);
        }
    }
}
