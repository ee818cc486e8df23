//! The tracker: state between frames and the per-frame pipeline
//! (segmentation, point cloud, then initialisation or visibility,
//! registration, occlusion estimate and resampling).

use alloc::vec;
use alloc::vec::Vec;

use crate::baselines::trackdlo::TrackDloReport;
use crate::math::{Vec2, Vec3};
use crate::motion::RigidMotion;
use crate::params::{Params, ParamsError};
use crate::perception::camera::{
    is_frame_rate, CameraError, CameraIntrinsics, DEFAULT_FPS, MAX_FPS,
};
use crate::perception::ego_motion::CameraMotion;
use crate::perception::evidence::Evidence;
use crate::perception::frame::{Frame, FrameError};
use crate::perception::initialisation::{
    initialise, node_count_for, strip_push, whole_diameter, InitError, InitGuide, InitReport,
    Initialisation, PriorError, RopePrior, DIAMETER_PRIOR_FACTOR,
};
use crate::perception::point_cloud::build_cloud;
use crate::perception::segmentation::{
    segment, without_wide_parts, HsvRange, Mask, Rect, SegmentationError,
};
use crate::perception::sharing::{OtherRopes, MAX_SHARED};
use crate::polyline::{polyline_length, resample_uniform};
use crate::step::{Algorithm, StepInput};
use crate::upe::occlusion::UpeReport;
use crate::upe::registration::EmReport;
use crate::visibility::{
    classify_nodes, under_other_strand, NodeVisibility, CROSSING_DEPTH_WINDOW_PX,
};

mod adopt;
mod camera;
pub mod explain;
mod judge;
mod recovery;
mod report;
mod snapshot;
mod stepper;

pub(crate) use camera::CameraFollowing;
pub use recovery::{
    beside_rope_found, Contradiction, FoundAgain, Judgement, RecoveryBackoff, Verdict,
    MAX_RECOVERY_WAIT, MIN_NODES_IN_FREE_SPACE, STRETCH_LIMIT, UNEXPLAINED_LIMIT,
    UNEXPLAINED_REACH,
};
pub use stepper::{StepReports, Stepper};

use crate::upe::emerging;

/// After a jump re-initialisation was refused, it is tried again only once
/// the cloud has grown by this fraction: the attempt costs a whole
/// initialisation, and a rope that became long enough to pass the length
/// rule shows more points than one that did not.
pub const JUMP_RETRY_GROWTH: f64 = 0.1;

/// A tracker already lost re-initialises on a rope found at least this
/// fraction of its known length (and as thick as the one tracked), rather
/// than `Params::reinit_length_fraction`: the rest may be hidden (a
/// rectangle over a fifth of it kept drawn scene 4046 lost for 18 frames
/// with 72 % of the rope in view), and its held nodes are no estimate.
pub const LOST_REINIT_LENGTH_FRACTION: f64 = 0.5;

/// Errors building or reconfiguring a tracker.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TrackerError {
    /// Invalid parameters.
    #[error(transparent)]
    Params(#[from] ParamsError),
    /// Invalid intrinsics.
    #[error(transparent)]
    Camera(#[from] CameraError),
    /// Invalid HSV range.
    #[error(transparent)]
    Segmentation(#[from] SegmentationError),
    /// A frame that does not fit the camera.
    #[error(transparent)]
    Frame(#[from] FrameError),
    /// An invalid rope prior.
    #[error(transparent)]
    Prior(#[from] PriorError),
    /// A camera motion that is not a rigid motion.
    #[error("not a camera motion: {reason}")]
    CameraMotion {
        /// What is wrong with it.
        reason: &'static str,
    },
    /// A tracker of several ropes of no ropes or more than
    /// [`MAX_SHARED`].
    #[error("a tracker follows 1 to {max} ropes, not {count}", max = MAX_SHARED)]
    RopeCount {
        /// The number of ropes asked for.
        count: usize,
    },
    /// A rope of a tracker of several seen by another camera than the first.
    #[error(
        "rope {rope} has other camera intrinsics than rope 0: all ropes are seen by one camera"
    )]
    CameraMismatch {
        /// Index of the rope.
        rope: usize,
    },
    /// A frame rate that is not a positive number of frames per second.
    #[error("a frame rate of {fps} frames per second: it must be in (0, {max}]", max = MAX_FPS)]
    FrameRate {
        /// The rate given.
        fps: f64,
    },
    /// A snapshot that no tracker could have taken.
    #[error("a snapshot the tracker cannot return to: {reason}")]
    Snapshot {
        /// What is wrong with it.
        reason: &'static str,
    },
}

/// Why a frame produced no tracked nodes.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LostReason {
    /// The tracker has never been initialised and could not be now.
    #[error("not initialised: {0}")]
    NotInitialised(InitError),
    /// No node had enough points nearby; re-initialisation failed too.
    #[error("no node is visible and the rope could not be found again: {0}")]
    NoVisibleNodes(InitError),
    /// Tracking was lost earlier and the rope is not back in full view.
    #[error("still lost: {0}")]
    StillLost(InitError),
    /// The rope found is shorter than the fraction of its known length needed to re-initialise.
    #[error("rope only partly in view ({found_mm:.0} mm of {known_mm:.0} mm)")]
    PartlyInView {
        /// Length found, millimetres.
        found_mm: f64,
        /// Length at the first initialisation, millimetres.
        known_mm: f64,
    },
}

/// What happened in one frame.
#[derive(Debug, Clone, PartialEq)]
pub enum FrameStatus {
    /// Nodes were placed from scratch (first frame, or after a loss).
    Initialised,
    /// Nodes were tracked from the previous frame.
    Tracked,
    /// The tracked state contradicted the images (a stretched rope, hidden
    /// nodes in free space, rope in view far from every node) and the rope
    /// was found again from what is visible; what the images said against it.
    Recovered(Contradiction),
    /// No tracking this frame; the nodes shown are the last known ones.
    Lost(LostReason),
}

/// The result of one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameOutput {
    /// The `M` nodes in order along the rope (empty if never initialised).
    pub nodes: Vec<Vec3>,
    /// The visibility decision of each node.
    pub visible: Vec<bool>,
    /// How the nodes were obtained.
    pub status: FrameStatus,
    /// What the registration did (tracked frames only).
    pub em: Option<EmReport>,
    /// How hidden nodes were placed (tracked frames only).
    pub upe: Option<UpeReport>,
    /// What TrackDLO did (TrackDLO's tracked frames only).
    pub trackdlo: Option<TrackDloReport>,
    /// What initialisation found and why it took what it took (frames
    /// initialised or recovered only).
    pub init: Option<InitReport>,
    /// What the recovery tests read after the step and what came of it
    /// (frames where a step ran: tracked and recovered).
    pub judgement: Option<Judgement>,
}

impl FrameOutput {
    /// `true` when the frame was lost.
    pub fn is_lost(&self) -> bool {
        matches!(self.status, FrameStatus::Lost(_))
    }
}

/// The segmented mask and point cloud of a frame: everything the tracking
/// step needs, ready before it starts.
#[derive(Debug, Clone)]
pub struct Observation {
    /// The rope mask after occlusion rectangles.
    pub mask: Mask,
    /// The downsampled cloud on the rope's centre line, metres: of the
    /// mask's parts no wider than the tracked rope allows (all of them when
    /// there is no tracked rope).
    pub cloud: Vec<Vec3>,
    /// The occlusion rectangles blacked out in this frame.
    pub occlusions: Vec<Rect>,
    /// Mask pixels in parts too wide to be the rope, left out of `cloud`.
    pub too_wide: usize,
    /// What the other ropes tracked in the frame
    /// ([`crate::several::MultiTracker`]) leave this one; `None` for one
    /// rope.
    pub others: Option<OtherRopes>,
}

impl Observation {
    /// An observation from [`Tracker::segment`]'s mask and
    /// [`Tracker::cloud`]'s cloud of it.
    pub fn new(mask: Mask, cloud: RopeCloud, occlusions: &[Rect]) -> Self {
        Self {
            mask,
            cloud: cloud.points,
            occlusions: occlusions.to_vec(),
            too_wide: cloud.too_wide,
            others: None,
        }
    }
}

/// The cloud of the parts of a mask that can be the tracked rope.
#[derive(Debug, Clone, PartialEq)]
pub struct RopeCloud {
    /// Points, metres.
    pub points: Vec<Vec3>,
    /// Mask pixels in parts too wide to be the rope, left out.
    pub too_wide: usize,
}

#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
struct TrackState {
    nodes: Vec<Vec3>,
    lost: bool,
    /// Rope-coloured points in view that were not this rope on the last
    /// frame it was wholly seen (`StepInput::not_rope`).
    #[cfg_attr(feature = "serde", serde(default))]
    not_rope: Vec<Vec3>,
}

/// Everything a tracker carries from one frame to the next, to go back to
/// an earlier frame (the page's timeline) without tracking from the start.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TrackerSnapshot {
    state: Option<TrackState>,
    known_length: Option<f64>,
    #[cfg_attr(feature = "serde", serde(default))]
    known_radius: Option<f64>,
    #[cfg_attr(feature = "serde", serde(default))]
    known_cover: Option<f64>,
    #[cfg_attr(feature = "serde", serde(default))]
    known_diameter: Option<f64>,
    #[cfg_attr(feature = "serde", serde(default))]
    rest_length: Option<f64>,
    #[cfg_attr(feature = "serde", serde(default))]
    rope_node_count: Option<usize>,
    #[cfg_attr(feature = "serde", serde(default))]
    refused_jump_cloud: Option<usize>,
    #[cfg_attr(feature = "serde", serde(default))]
    recovery: RecoveryBackoff,
    stepper: Stepper,
}

/// Tracks one rope across the frames of one camera.
#[derive(Debug, Clone)]
pub struct Tracker {
    params: Params,
    camera: CameraIntrinsics,
    hsv: HsvRange,
    state: Option<TrackState>,
    /// Length at the first initialisation, metres.
    known_length: Option<f64>,
    /// Radius measured at the first initialisation (its mask's), metres.
    known_radius: Option<f64>,
    /// The share of the rope's width its mask covered at the first
    /// initialisation, as the depth image showed it.
    known_cover: Option<f64>,
    /// The rope's diameter as the first initialisation measured it (the
    /// candidate taken), metres: what a recovery must find again.
    known_diameter: Option<f64>,
    /// Length of the node polyline at the first initialisation, metres
    /// (chords, as the tracked nodes measure it).
    rest_length: Option<f64>,
    /// The node count the first initialisation chose for this rope
    /// (`Params::node_spacing_diameters`), kept until a reset.
    rope_node_count: Option<usize>,
    /// Cloud size at the last refused jump re-initialisation, while fewer
    /// than `reinit_visible_fraction` of the nodes stay visible.
    refused_jump_cloud: Option<usize>,
    /// When the next recovery from a contradicting step may run.
    recovery: RecoveryBackoff,
    /// The per-frame step of `params.algorithm`.
    stepper: Stepper,
    /// What the user knows of the rope.
    prior: RopePrior,
    /// A pixel on the rope the user clicked, for the next initialisation.
    hint: Option<Vec2>,
    /// The camera's own motion: the last background, told or estimated.
    following: CameraFollowing,
    /// Seconds between frames (`1 / fps`).
    frame_interval: f64,
}

impl Tracker {
    /// A tracker for `camera`, segmenting with `hsv`.
    pub fn new(
        params: Params,
        camera: CameraIntrinsics,
        hsv: HsvRange,
    ) -> Result<Self, TrackerError> {
        params.validate()?;
        camera.validate()?;
        hsv.validate()?;
        Ok(Self {
            params,
            camera,
            hsv,
            state: None,
            known_length: None,
            known_radius: None,
            known_cover: None,
            known_diameter: None,
            rest_length: None,
            rope_node_count: None,
            refused_jump_cloud: None,
            recovery: RecoveryBackoff::default(),
            stepper: Stepper::new(params.algorithm),
            prior: RopePrior::default(),
            hint: None,
            following: CameraFollowing::default(),
            frame_interval: 1.0 / DEFAULT_FPS,
        })
    }

    /// The camera's frame rate, frames per second (a sequence's `fps`;
    /// [`DEFAULT_FPS`] until told): speeds in the parameters
    /// (`rest_speed_m_per_s`) become moves per frame with it. Effective
    /// next frame.
    pub fn set_frame_rate(&mut self, fps: f64) -> Result<(), TrackerError> {
        if !is_frame_rate(fps) {
            return Err(TrackerError::FrameRate { fps });
        }
        self.frame_interval = 1.0 / fps;
        Ok(())
    }

    /// The frame rate in force, frames per second.
    pub fn frame_rate(&self) -> f64 {
        1.0 / self.frame_interval
    }

    /// What the user knows of the rope (`dlo.json`'s `rope`): candidates
    /// are judged against it, its diameter is the radius in force and its
    /// length the one a re-initialisation must find. Takes effect at the
    /// next initialisation.
    pub fn set_rope_prior(&mut self, prior: RopePrior) -> Result<(), TrackerError> {
        prior.validate()?;
        self.prior = prior;
        Ok(())
    }

    /// The camera moved by `motion` since the last frame (where a point at
    /// rest in the world goes, from the last frame's camera coordinates to
    /// the next's: a robot arm's kinematics, an IMU, or the
    /// background's motion): the tracked rope is moved with it,
    /// so that the next step starts from where a rope at rest now is.
    pub fn move_camera(&mut self, motion: &RigidMotion) -> Result<(), TrackerError> {
        let reason = if !motion.is_finite() {
            Some("an entry is not finite")
        } else if !motion.is_rotation() {
            Some("its rotation is not orthonormal with determinant 1")
        } else {
            None
        };
        if let Some(reason) = reason {
            return Err(TrackerError::CameraMotion { reason });
        }
        self.following.given = true;
        self.carry_state(motion);
        Ok(())
    }

    /// The camera's motion for the next frame as followed outside this
    /// tracker (by a `MultiTracker`, once for all its ropes): the state is
    /// carried by `estimate`'s motion, if any.
    pub(crate) fn camera_followed(&mut self, estimate: Option<&CameraMotion>) {
        self.following.followed_outside(estimate);
        if let Some(m) = estimate {
            self.carry_state(&m.motion);
        }
    }

    /// Whether the caller gave the camera's motion for the next frame.
    pub(crate) fn camera_given(&self) -> bool {
        self.following.given
    }

    /// The tracked nodes moved as points at rest move under `motion`.
    fn carry_state(&mut self, motion: &RigidMotion) {
        if let Some(state) = self.state.as_mut() {
            for p in state.nodes.iter_mut().chain(state.not_rope.iter_mut()) {
                *p = motion.apply(p);
            }
        }
    }

    /// The camera's motion estimated from the background on the last
    /// frame (`follow_camera`), when one was significant.
    pub fn camera_motion(&self) -> Option<&CameraMotion> {
        self.following.estimated.as_ref()
    }

    /// With `follow_camera`: the camera's motion from the last frame's
    /// background to `frame`'s, applied to the state (unless the caller
    /// gave it), and `frame`'s background kept for the next.
    fn follow_camera(&mut self, frame: &Frame<'_>, obs: &Observation) {
        let tracking = self.state.is_some();
        let following = &mut self.following;
        let background = (&obs.mask, obs.occlusions.as_slice());
        if let Some(m) = following.follow(frame, background, &self.camera, &self.params, tracking) {
            self.carry_state(&m);
        }
    }

    /// The rope prior in force.
    pub fn rope_prior(&self) -> &RopePrior {
        &self.prior
    }

    /// A pixel `(u, v)` on the rope the user clicked: an initialisation
    /// without a state (the first, or the next after [`Tracker::reset`])
    /// takes the rope-shaped candidate through it; `None` forgets it.
    pub fn set_rope_hint(&mut self, hint: Option<[f64; 2]>) {
        self.hint = hint
            .filter(|h| h.iter().all(|c| c.is_finite()))
            .map(|[u, v]| Vec2::new(u, v));
    }

    /// The parameters in force.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// The camera.
    pub fn camera(&self) -> &CameraIntrinsics {
        &self.camera
    }

    /// The HSV range in force.
    pub fn hsv(&self) -> &HsvRange {
        &self.hsv
    }

    /// The current nodes (empty before the first initialisation).
    pub fn nodes(&self) -> &[Vec3] {
        self.state.as_ref().map_or(&[], |s| &s.nodes)
    }

    /// Replaces the parameters; takes effect at the next frame. A new node
    /// count resamples the current nodes along the same curve; a new node
    /// count or algorithm starts the step afresh from the current nodes.
    pub fn set_params(&mut self, params: Params) -> Result<(), TrackerError> {
        params.validate()?;
        let mut restart = params.algorithm != self.params.algorithm;
        let counted = |p: &Params| (p.node_count, p.node_spacing_diameters);
        if counted(&params) != counted(&self.params) {
            self.rope_node_count = self
                .rest_length
                .map(|l| node_count_for(&params.init(), l, self.rope_diameter()));
        }
        let m = self.rope_node_count.unwrap_or(params.node_count);
        if let Some(state) = self.state.as_mut() {
            if state.nodes.len() != m {
                state.nodes = resample_uniform(&state.nodes, m);
                restart = true;
            }
        }
        self.params = params;
        if restart {
            self.stepper = Stepper::new(params.algorithm);
            let nodes = self.nodes().to_vec();
            self.stepper.start(&nodes);
        }
        self.following.forget();
        Ok(())
    }

    /// Replaces the HSV range.
    pub fn set_hsv(&mut self, hsv: HsvRange) -> Result<(), TrackerError> {
        hsv.validate()?;
        self.hsv = hsv;
        Ok(())
    }

    /// Forgets the state: the next frame initialises again.
    pub fn reset(&mut self) {
        self.state = None;
        self.known_length = None;
        self.known_radius = None;
        self.known_cover = None;
        self.known_diameter = None;
        self.rest_length = None;
        self.rope_node_count = None;
        self.refused_jump_cloud = None;
        self.recovery = RecoveryBackoff::default();
        self.stepper = Stepper::new(self.params.algorithm);
        self.following.forget();
    }

    /// Segmentation and point cloud of `frame`, with `occlusions` blacked out.
    pub fn observe(
        &self,
        frame: &Frame<'_>,
        occlusions: &[Rect],
    ) -> Result<Observation, TrackerError> {
        let mask = self.segment(frame, occlusions)?;
        let cloud = self.cloud(frame, &mask);
        Ok(Observation::new(mask, cloud, occlusions))
    }

    /// The first stage of [`Tracker::observe`]: the rope's mask, with the
    /// colour range in force and `occlusions` blacked out.
    pub fn segment(&self, frame: &Frame<'_>, occlusions: &[Rect]) -> Result<Mask, TrackerError> {
        frame.check_camera(&self.camera)?;
        Ok(segment(frame, &self.hsv, occlusions))
    }

    /// The second stage of [`Tracker::observe`]: the point cloud of the
    /// masked pixels (`mask` from [`Tracker::segment`] on the same frame).
    /// While a rope is tracked, a part of the mask wider than
    /// [`DIAMETER_PRIOR_FACTOR`] times the rope (at its nearest node) is
    /// something else in the colour range, a phone beside a black cable or
    /// a hand: its pixels are left out and counted.
    pub fn cloud(&self, frame: &Frame<'_>, mask: &Mask) -> RopeCloud {
        let settings = self.cloud_settings();
        let nearest = match &self.state {
            Some(s) if !s.lost => s
                .nodes
                .iter()
                .map(|n| n.z)
                .filter(|z| *z > 0.0)
                .fold(f64::INFINITY, f64::min),
            _ => f64::INFINITY,
        };
        let cloud_of = |mask: &Mask, too_wide| RopeCloud {
            points: build_cloud(frame, mask, &self.camera, &settings),
            too_wide,
        };
        if !nearest.is_finite() {
            return cloud_of(mask, 0);
        }
        let f = self.camera.fx.max(self.camera.fy);
        let widest = DIAMETER_PRIOR_FACTOR * 2.0 * self.radius() * f / nearest;
        match without_wide_parts(mask, widest) {
            None => cloud_of(mask, 0),
            Some((rope, too_wide)) => cloud_of(&rope, too_wide),
        }
    }

    /// The rope's radius in force, metres: half the prior's diameter when
    /// known, else measured at the first initialisation
    /// (`Params::estimate_radius`) or `Params::dlo_radius`.
    pub fn radius(&self) -> f64 {
        if let Some(d) = self.prior.diameter {
            return 0.5 * d;
        }
        match (self.params.estimate_radius, self.known_radius) {
            (true, Some(r)) if self.params.dlo_radius > 0.0 => r,
            _ => self.params.dlo_radius,
        }
    }

    /// The rope's whole diameter, metres, when known: the prior's, or the
    /// first initialisation's measure.
    fn rope_diameter(&self) -> Option<f64> {
        whole_diameter(self.prior.diameter, self.known_radius, self.known_cover)
    }

    /// The number of nodes tracked: the one the first initialisation chose
    /// for this rope, else `Params::node_count`.
    pub fn node_count(&self) -> usize {
        self.rope_node_count.unwrap_or(self.params.node_count)
    }

    /// The cloud's settings: pushed from the surface the mask sees to the
    /// axis of the rope in force, wider than its mask where the mask
    /// covered only a strip of it at the first initialisation.
    fn cloud_settings(&self) -> crate::perception::point_cloud::CloudSettings {
        let radius = self.radius();
        match self.known_cover {
            Some(c) if self.params.estimate_radius => {
                // A prior's diameter is the rope's; a measured radius, its mask's.
                let rope = if self.prior.diameter.is_some() {
                    radius
                } else {
                    radius / c
                };
                self.params.cloud_with_push(strip_push(rope, c))
            }
            _ => self.params.cloud_for_radius(radius),
        }
    }

    /// The tracking step on an observation of `frame`. Never fails: a frame
    /// that cannot be tracked is reported as lost and the state is kept.
    pub fn update(&mut self, frame: &Frame<'_>, obs: &Observation) -> FrameOutput {
        self.follow_camera(frame, obs);
        let Some(state) = self.state.as_ref() else {
            return self.initialise_or_lose(frame, obs, Loss::NeverInitialised);
        };
        if state.lost {
            return self.initialise_or_lose(frame, obs, Loss::StillLost);
        }

        let prev = state.nodes.clone();
        let not_rope = state.not_rope.clone();
        let p = &self.params;
        let classes = self.visibility(&prev, &obs.cloud, &self.evidence(&self.camera, frame, obs));
        let visible = &classes.visible;
        if !visible.iter().any(|&v| v) {
            return self.initialise_or_lose(frame, obs, Loss::JustLost);
        }
        // Few nodes left on the rope: it may have jumped. A full-length rope
        // in view replaces the state; otherwise tracking goes on.
        // A refused attempt is tried again only once the cloud has grown.
        let seen = visible.iter().filter(|&&v| v).count() as f64;
        if seen < p.reinit_visible_fraction * prev.len() as f64 {
            let cloud = obs.cloud.len();
            let worth_trying = self
                .refused_jump_cloud
                .is_none_or(|n| cloud as f64 > n as f64 * (1.0 + JUMP_RETRY_GROWTH));
            if worth_trying {
                match self.try_initialise(frame, obs) {
                    Ok(out) => return out,
                    Err(_) => self.refused_jump_cloud = Some(cloud),
                }
            }
        } else {
            self.refused_jump_cloud = None;
        }
        let camera = self.camera;
        let input = self.step_input(&camera, frame, obs, &prev, &classes, &not_rope);
        let out = self.stepper.step(&input, &self.params);
        let (beside, judgement) = match self.judge_step(frame, obs, (&prev, &out), &not_rope) {
            core::ops::ControlFlow::Continue(kept) => kept,
            core::ops::ControlFlow::Break(again) => return again,
        };
        let mut not_rope = self.not_rope_after(&out.nodes, &classes.visible, &obs.cloud);
        if let Some(spacing) = self.rest_spacing(out.nodes.len()) {
            emerging::remember_not_rope(&mut not_rope, &beside, spacing);
        }
        self.state = Some(TrackState {
            nodes: out.nodes.clone(),
            lost: false,
            not_rope,
        });
        FrameOutput {
            nodes: self.reported(out.nodes, &out.visible, frame, obs),
            visible: out.visible,
            status: FrameStatus::Tracked,
            em: out.report.em,
            upe: out.report.upe,
            trackdlo: out.report.trackdlo,
            init: None,
            judgement: Some(judgement),
        }
    }

    /// The shared visibility test of the `previous` nodes against `cloud`;
    /// for UPETrack with `hidden_under_crossings`, a node under another
    /// stretch of the rope in `evidence` is hidden and partly seen.
    fn visibility(
        &self,
        previous: &[Vec3],
        cloud: &[Vec3],
        evidence: &Evidence<'_>,
    ) -> NodeVisibility {
        let p = &self.params;
        let mut classes = classify_nodes(
            previous,
            cloud,
            p.visibility_radius,
            p.visibility_min_points as usize,
            p.visibility_min_fraction,
        );
        if p.algorithm == Algorithm::Upetrack && p.upetrack.hidden_under_crossings {
            let rope_depth = |at: Vec2| evidence.rope_depth_near(at, CROSSING_DEPTH_WINDOW_PX);
            let under = under_other_strand(previous, &self.camera, self.radius(), &rope_depth);
            for ((visible, partly), under) in classes
                .visible
                .iter_mut()
                .zip(classes.partly_seen.iter_mut())
                .zip(under)
            {
                if under && *visible {
                    (*visible, *partly) = (false, true);
                }
            }
        }
        classes
    }

    /// The evidence of `frame` observed as `obs` for this tracker's rope,
    /// seen by `camera` (the tracker's, or a copy of it).
    fn evidence<'a>(
        &self,
        camera: &'a CameraIntrinsics,
        frame: &'a Frame<'a>,
        obs: &'a Observation,
    ) -> Evidence<'a> {
        Evidence {
            frame,
            mask: &obs.mask,
            occlusions: &obs.occlusions,
            camera,
            radius: self.radius(),
            others: obs.others.as_ref().map(|o| &o.pixels),
        }
    }

    /// What the step of a frame gets; `camera` is the tracker's, copied so
    /// that the step may borrow the tracker's stepper mutably.
    fn step_input<'a>(
        &self,
        camera: &'a CameraIntrinsics,
        frame: &'a Frame<'a>,
        obs: &'a Observation,
        previous: &'a [Vec3],
        classes: &'a NodeVisibility,
        not_rope: &'a [Vec3],
    ) -> StepInput<'a> {
        StepInput {
            previous,
            not_rope,
            cloud: &obs.cloud,
            visible: &classes.visible,
            partly_seen: &classes.partly_seen,
            camera,
            evidence: Some(self.evidence(camera, frame, obs)),
            rest_length: self.rest_length,
            frame_interval: self.frame_interval,
        }
    }

    /// What the next frames take for rope-coloured things beside this rope
    /// (`StepInput::not_rope`, `emerging::remembered_beside`).
    fn not_rope_after(&self, nodes: &[Vec3], visible: &[bool], cloud: &[Vec3]) -> Vec<Vec3> {
        let memory = self.state.as_ref().map_or(&[][..], |s| &s.not_rope);
        let spacing = self.rest_spacing(nodes.len());
        emerging::remembered_beside(memory, nodes, visible, cloud, spacing, self.radius())
    }

    /// The rope's rest spacing between `m` nodes, once its length is known.
    fn rest_spacing(&self, m: usize) -> Option<f64> {
        self.rest_length
            .map(|l| crate::upe::length::rest_spacing(l, m))
    }

    /// [`Tracker::observe`] then [`Tracker::update`].
    pub fn process(
        &mut self,
        frame: &Frame<'_>,
        occlusions: &[Rect],
    ) -> Result<FrameOutput, TrackerError> {
        let obs = self.observe(frame, occlusions)?;
        Ok(self.update(frame, &obs))
    }

    fn try_initialise(
        &mut self,
        frame: &Frame<'_>,
        obs: &Observation,
    ) -> Result<FrameOutput, ReinitFailure> {
        let init = self.find_rope(frame, obs)?;
        Ok(self.adopt(init, frame, obs))
    }

    /// Initialisation on this frame, judged against the rope's known
    /// length; after a loss, the candidate nearest the last known state
    /// among those long enough to be taken.
    fn find_rope(
        &self,
        frame: &Frame<'_>,
        obs: &Observation,
    ) -> Result<Initialisation, ReinitFailure> {
        let known = self.known_length.or(self.prior.length);
        let previous = match &self.state {
            Some(s) => s.nodes.as_slice(),
            None => &[],
        };
        // Once lost, the held nodes are no estimate: a rope most of whose
        // length is in view, as thick as the one tracked, is taken.
        let lost = self.state.as_ref().is_some_and(|s| s.lost);
        let f = self.params.reinit_length_fraction;
        let fraction = f.min(if lost { LOST_REINIT_LENGTH_FRACTION } else { f });
        // A click chooses the rope on the frame it was made on (a tracker
        // without a state); after a loss the rope is found near where it was.
        let (mask, taken) = match &obs.others {
            Some(o) => (&o.colour, o.taken.as_slice()),
            None => (&obs.mask, &[][..]),
        };
        let guide = InitGuide {
            prior: self.prior,
            hint: self.hint.filter(|_| self.state.is_none()),
            previous,
            min_length: known.map_or(0.0, |k| fraction * k),
            taken,
            alike_ropes: obs.others.as_ref().is_some_and(|o| o.alike),
        };
        // A re-initialisation places the rope's nodes, as many as before.
        let mut settings = self.params.init();
        if let Some(m) = self.rope_node_count {
            settings.node_count = m;
            settings.node_spacing_diameters = 0.0;
        }
        let init = initialise(frame, mask, &self.camera, &settings, &guide)
            .map_err(ReinitFailure::Init)?;
        if let Some(known) = known {
            if init.length < fraction * known || (lost && !self.as_thick_as_tracked(&init)) {
                return Err(ReinitFailure::Short {
                    found: init.length,
                    known,
                });
            }
        }
        Ok(init)
    }

    /// Initialises from this frame, or reports it lost (holding the nodes
    /// and marking the state lost, so that later frames keep trying).
    fn initialise_or_lose(
        &mut self,
        frame: &Frame<'_>,
        obs: &Observation,
        loss: Loss,
    ) -> FrameOutput {
        match self.try_initialise(frame, obs) {
            Ok(out) => out,
            Err(failure) => {
                if let Some(s) = self.state.as_mut() {
                    s.lost = true;
                }
                self.lost(loss.reason(failure))
            }
        }
    }

    fn lost(&self, reason: LostReason) -> FrameOutput {
        let nodes = self.nodes().to_vec();
        FrameOutput {
            visible: vec![false; nodes.len()],
            nodes,
            status: FrameStatus::Lost(reason),
            em: None,
            upe: None,
            trackdlo: None,
            init: None,
            judgement: None,
        }
    }

    /// `true` while a rope is tracked: initialised and not lost.
    pub fn is_tracking(&self) -> bool {
        self.state.as_ref().is_some_and(|s| !s.lost)
    }

    /// Length of the current node polyline, metres.
    pub fn current_length(&self) -> f64 {
        polyline_length(self.nodes())
    }
}

/// Why a re-initialisation attempt failed.
enum ReinitFailure {
    Init(InitError),
    Short { found: f64, known: f64 },
}

/// Where the tracker stood when (re)initialisation was attempted.
#[derive(Clone, Copy)]
enum Loss {
    NeverInitialised,
    JustLost,
    StillLost,
}

impl Loss {
    fn reason(self, f: ReinitFailure) -> LostReason {
        match (self, f) {
            (Loss::NeverInitialised, ReinitFailure::Init(e)) => LostReason::NotInitialised(e),
            (Loss::JustLost, ReinitFailure::Init(e)) => LostReason::NoVisibleNodes(e),
            (_, ReinitFailure::Init(e)) => LostReason::StillLost(e),
            (_, ReinitFailure::Short { found, known }) => LostReason::PartlyInView {
                found_mm: found * 1000.0,
                known_mm: known * 1000.0,
            },
        }
    }
}

#[cfg(test)]
impl Tracker {
    /// Makes the tracker track `nodes` (tests of what carries a state).
    pub(crate) fn track_for_test(&mut self, nodes: Vec<Vec3>) {
        self.state = Some(TrackState {
            nodes,
            lost: false,
            not_rope: Vec::new(),
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::MAX_NODES;

    /// A tracker with `params` whose state is a straight rope of
    /// `params.node_count` nodes 1 cm apart, 0.6 m away; and those nodes.
    fn tracking_a_line(params: Params) -> (Tracker, Vec<Vec3>) {
        let cam = CameraIntrinsics::D435I_640X480;
        let mut t = Tracker::new(params, cam, HsvRange::default()).expect("tracker");
        let nodes: Vec<Vec3> = (0..params.node_count)
            .map(|i| Vec3::new(i as f64 * 0.01, 0.0, 0.6))
            .collect();
        t.state = Some(TrackState {
            nodes: nodes.clone(),
            lost: false,
            not_rope: Vec::new(),
        });
        (t, nodes)
    }

    /// Recoveries in a row wait 1, 3, 7, ... frames between them, never more than
    /// [`MAX_RECOVERY_WAIT`]; a step that agrees with the images ends the row.
    #[test]
    fn a_camera_motion_carries_the_state_and_a_non_rigid_one_is_refused() {
        let (mut t, nodes) = tracking_a_line(Params::default());
        let mut bad = RigidMotion::identity();
        bad.translation.x = f64::NAN;
        let mut mirror = RigidMotion::identity();
        mirror.rotation[(0, 0)] = -1.0;
        let mut scaling = RigidMotion::identity();
        scaling.rotation *= 1.01;
        for refused in [bad, mirror, scaling] {
            assert!(matches!(
                t.move_camera(&refused),
                Err(TrackerError::CameraMotion { .. })
            ));
        }
        assert_eq!(t.nodes(), nodes.as_slice());
        let mut shift = RigidMotion::identity();
        shift.translation = Vec3::new(0.01, -0.02, 0.005);
        t.move_camera(&shift).expect("a finite motion");
        for (moved, was) in t.nodes().iter().zip(&nodes) {
            assert_eq!(*moved, was + shift.translation);
        }
    }

    #[test]
    fn restore_returns_to_a_snapshot_and_resamples_to_the_node_count() {
        let empty = {
            let cam = CameraIntrinsics::D435I_640X480;
            Tracker::new(Params::default(), cam, HsvRange::default())
                .expect("tracker")
                .snapshot()
        };
        let (mut t, nodes) = tracking_a_line(Params::default());
        assert_eq!(nodes.len(), 24);
        t.known_length = Some(0.23);
        let snap = t.snapshot();
        t.reset();
        assert_eq!(t.snapshot(), empty);
        t.restore(snap.clone()).expect("its own snapshot");
        assert_eq!(t.nodes(), &nodes[..]);
        assert_eq!(t.snapshot(), snap);
        let p = Params {
            node_count: 12,
            ..Params::default()
        };
        t.set_params(p).expect("params");
        t.restore(snap).expect("its own snapshot");
        assert_eq!(t.nodes().len(), 12);
    }

    #[test]
    fn a_frame_rate_that_is_no_positive_number_of_frames_per_second_is_refused() {
        let (mut t, _) = tracking_a_line(Params::default());
        assert_eq!(t.frame_rate(), DEFAULT_FPS);
        for fps in [0.0, -30.0, f64::NAN, f64::INFINITY, 2.0 * MAX_FPS] {
            let e = t.set_frame_rate(fps).expect_err("not a frame rate");
            assert!(matches!(e, TrackerError::FrameRate { .. }), "{e}");
        }
        assert_eq!(t.frame_rate(), DEFAULT_FPS);
        t.set_frame_rate(60.0).expect("60 fps");
        assert!((t.frame_rate() - 60.0).abs() < 1e-9);
    }

    #[test]
    fn a_snapshot_with_a_nan_node_is_refused_and_the_state_kept() {
        let (mut t, nodes) = tracking_a_line(Params::default());
        let mut bad = t.snapshot();
        if let Some(s) = bad.state.as_mut() {
            s.nodes[3].x = f64::NAN;
        }
        assert!(matches!(t.restore(bad), Err(TrackerError::Snapshot { .. })));
        assert_eq!(t.nodes(), &nodes[..]);
        let mut bad = t.snapshot();
        bad.known_length = Some(f64::INFINITY);
        assert!(t.restore(bad).is_err());
        // The tracker's snapshot with `edit` made, refused by a restore.
        let refused = |t: &mut Tracker, edit: &dyn Fn(&mut TrackerSnapshot)| {
            let mut bad = t.snapshot();
            edit(&mut bad);
            t.restore(bad).is_err()
        };
        // A cover of nothing would push the cloud infinitely far.
        for cover in [0.0, -0.5, 1.5, f64::NAN] {
            assert!(
                refused(&mut t, &|s| s.known_cover = Some(cover)),
                "cover {cover}"
            );
        }
        let mut fine = t.snapshot();
        fine.known_cover = Some(0.8);
        t.restore(fine).expect("a cover in (0, 1]");
        // A node count outside the accepted range would resample to it.
        for count in [0, 2, MAX_NODES + 1] {
            assert!(
                refused(&mut t, &|s| s.rope_node_count = Some(count)),
                "{count} nodes"
            );
        }
        let mut fine = t.snapshot();
        fine.rope_node_count = Some(30);
        t.restore(fine).expect("30 nodes");
        assert_eq!(t.nodes().len(), 30);
        assert_eq!(t.node_count(), 30);
        // With the rule turned off since, the parameters' count.
        let fixed = Params {
            node_spacing_diameters: 0.0,
            ..Params::default()
        };
        t.set_params(fixed).expect("params");
        let mut earlier = t.snapshot();
        earlier.rope_node_count = Some(30);
        t.restore(earlier).expect("30 nodes");
        assert_eq!((t.nodes().len(), t.node_count()), (24, 24));
    }

    #[test]
    fn a_snapshot_whose_step_state_is_of_another_rope_restarts_the_step() {
        let (mut t, nodes) = tracking_a_line(Params {
            algorithm: Algorithm::Trackdlo,
            ..Params::default()
        });
        let mut snap = t.snapshot();
        snap.stepper.start(&nodes[..3]);
        assert!(!snap.stepper.fits(&nodes));
        t.restore(snap).expect("restored");
        assert!(t.stepper.fits(&nodes));
    }
}
