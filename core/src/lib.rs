//! UPETrack: tracking a deformable linear object (rope, cable, thread) seen by
//! an RGB-D camera, with Unidirectional Position Estimation of occluded nodes.
//!
//! The modules follow the pipeline of one frame, in order:
//!
//! 1. [`perception`], the stages every algorithm shares: [`perception::camera`]
//!    and [`perception::frame`] (intrinsics, the input images),
//!    [`perception::segmentation`] (HSV thresholds after the occlusion
//!    rectangles), [`perception::point_cloud`] (deprojection, voxel grid,
//!    pushed to the rope's axis) and [`perception::initialisation`] (the
//!    ordered centre line and `M` nodes when there is no state).
//!    Below them, shared by every stage: [`math`], [`polyline`] (arc
//!    length, even spacing by arc length) and [`visibility`] (`q >= V_lim`
//!    within `r_vis`, the shared loss test).
//! 2. [`upe`], UPETrack's own step: [`upe::registration`] (GMM-EM of the visible nodes,
//!    Eq. 1-5), [`upe::occlusion`] (Unidirectional Position Estimation of
//!    the hidden nodes, Eq. 6-11) and [`upe::resampling`] (Eq. 12-15).
//! 3. [`baselines`], the other tracking steps on the same pipeline:
//!    [`baselines::cpd`] and [`baselines::trackdlo`].
//! 4. [`metrics`]: the frame error (Eq. 16-18) in metres and pixels.
//!
//! At the top: [`tracker::Tracker`] holds the state between frames and runs
//! the stages; [`step`] is the interface every algorithm implements;
//! [`params::Params`] composes the shared settings with each algorithm's
//! own; [`validation`] is the one error type of a rejected parameter.
//! Above it, [`several::MultiTracker`] tracks several ropes at once, one
//! `Tracker` each, on the pixels [`perception::sharing`] shares out.
//!
//! **Where a new tracking algorithm goes, and what it implements.** A new
//! algorithm is a folder (or a file) under `baselines/`, beside CPD and
//! TrackDLO. It implements [`step::TrackingStep`]: `start` (forget per-track
//! state when the nodes are (re)initialised) and `step` (the previous nodes
//! and this frame's cloud in, new nodes and their visibility out), with its
//! own `Settings` struct (a `Default` with its published values and a
//! `validate` using [`validation::check`]) and `Report`. It never imports
//! [`params`] or [`tracker`]: to use it, add a variant to [`step::Algorithm`],
//! a settings field to [`params::Params`], and a variant to
//! [`tracker::Stepper`], which hands the step its settings. Segmentation,
//! the point cloud, initialisation and loss handling come for free.
//!
//! The crate is `no_std` with `alloc`; `std` is a default feature. It has no
//! clock and no hidden randomness, and all transcendental functions go
//! through `libm`, so native and WebAssembly builds compute the same numbers.
#![no_std]
#![warn(missing_docs)]

extern crate alloc;
#[cfg(feature = "std")]
extern crate std;

pub mod baselines;
pub mod curve;
pub mod math;
pub mod metrics;
pub mod motion;
pub mod params;
pub mod perception;
pub mod polyline;
pub mod rng;
pub mod several;
pub mod step;
pub mod tracker;
pub mod upe;
pub mod validation;
pub mod visibility;

pub use math::Vec3;
pub use params::Params;
pub use perception::camera::CameraIntrinsics;
pub use perception::frame::Frame;
pub use perception::segmentation::{HsvRange, Rect};
pub use several::MultiTracker;
pub use step::Algorithm;
pub use tracker::{FrameOutput, FrameStatus, Tracker};
