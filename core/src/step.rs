//! The interface every tracking algorithm implements: the per-frame step,
//! the one stage that differs between algorithms. Segmentation, the point
//! cloud, initialisation, loss and re-initialisation are shared by
//! [`crate::tracker::Tracker`]; a step only turns the previous nodes and this
//! frame's cloud into new nodes.
//!
//! An algorithm owns its settings (the trait's `Settings`, one field of
//! [`crate::params::Params`]) and its report; this module knows none of them.

use alloc::vec::Vec;

use crate::math::Vec3;
use crate::perception::camera::CameraIntrinsics;
use crate::perception::evidence::Evidence;

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
    /// CDCPD2 (Wang et al. 2021), reimplemented with a convex QP (baseline;
    /// needs the core's `cdcpd2` feature).
    Cdcpd2,
}

impl Algorithm {
    /// Every algorithm, UPETrack first.
    pub const ALL: [Algorithm; 4] = [
        Algorithm::Upetrack,
        Algorithm::Cpd,
        Algorithm::Trackdlo,
        Algorithm::Cdcpd2,
    ];

    /// The name used on the command line and in result files.
    pub fn name(self) -> &'static str {
        match self {
            Algorithm::Upetrack => "upetrack",
            Algorithm::Cpd => "cpd",
            Algorithm::Trackdlo => "trackdlo",
            Algorithm::Cdcpd2 => "cdcpd2",
        }
    }

    /// What the algorithm is, in one line (the command's help lists it).
    pub fn description(self) -> &'static str {
        match self {
            Algorithm::Upetrack => "UPETrack, the paper's tracker (default)",
            Algorithm::Cpd => "coherent point drift from the previous nodes (baseline)",
            Algorithm::Trackdlo => "TrackDLO (Xiang et al. 2023), reimplemented (baseline)",
            Algorithm::Cdcpd2 => "CDCPD2 (Wang et al. 2021), reimplemented (baseline)",
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
    /// The tracker's shared visibility of the previous nodes (its loss
    /// test, UPETrack's visibility stage); an algorithm may use its own.
    pub visible: &'a [bool],
    /// The hidden nodes that still have `V_lim` points within `r_vis`: the
    /// relative visibility test hid them (an occlusion's edge, a thinning
    /// view). Empty when not known.
    pub partly_seen: &'a [bool],
    /// The camera.
    pub camera: &'a CameraIntrinsics,
    /// This frame's images (depth, mask, rectangles), for an algorithm that
    /// checks where hidden nodes may be; `None` when not available.
    pub evidence: Option<Evidence<'a>>,
    /// The rope's length at initialisation, metres, when known.
    pub rest_length: Option<f64>,
    /// Seconds from the previous frame to this one (`1 / fps`): what turns
    /// a speed into a move per frame.
    pub frame_interval: f64,
    /// Rope-coloured points in view that were not this rope on the last
    /// frame it was wholly seen (a distractor beside it), carried with the
    /// camera's motion; empty when not known.
    pub not_rope: &'a [Vec3],
}

/// What a step produced.
#[derive(Debug, Clone, PartialEq)]
pub struct StepOutput<R> {
    /// The new nodes.
    pub nodes: Vec<Vec3>,
    /// The visibility the algorithm used (for CPD, which has none: the
    /// shared test's, for display).
    pub visible: Vec<bool>,
    /// What the algorithm reports about the step.
    pub report: R,
}

impl<R> StepOutput<R> {
    /// The same nodes and visibility with the report turned into another.
    pub fn map_report<S>(self, f: impl FnOnce(R) -> S) -> StepOutput<S> {
        StepOutput {
            nodes: self.nodes,
            visible: self.visible,
            report: f(self.report),
        }
    }
}

/// One algorithm's per-frame step and its state between frames.
pub trait TrackingStep {
    /// The algorithm's own settings.
    type Settings;
    /// What one step reports (`()` when nothing).
    type Report;
    /// Which algorithm this is.
    const ALGORITHM: Algorithm;
    /// Called with freshly (re)initialised nodes: forget per-track state.
    fn start(&mut self, nodes: &[Vec3]);
    /// `true` when the per-track state (if any) belongs to `nodes`: as many
    /// entries and finite. A state that does not (a restored snapshot of
    /// another rope) is started afresh rather than stepped.
    fn fits(&self, _nodes: &[Vec3]) -> bool {
        true
    }
    /// New nodes from the previous ones and this frame's cloud.
    fn step(
        &mut self,
        input: &StepInput<'_>,
        settings: &Self::Settings,
    ) -> StepOutput<Self::Report>;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for a in Algorithm::ALL {
            assert_eq!(Algorithm::from_name(a.name()), Some(a));
        }
        assert_eq!(Algorithm::from_name("gltp"), None);
    }
}
