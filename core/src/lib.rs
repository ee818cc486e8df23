//! UPETrack: tracking a deformable linear object (rope, cable, thread) seen by
//! an RGB-D camera, with Unidirectional Position Estimation of occluded nodes.
//!
//! The modules follow the pipeline of one frame, in order:
//!
//! 1. [`camera`] and [`frame`]: intrinsics, deprojection, the input images.
//! 2. [`segmentation`]: HSV thresholds (OpenCV convention) after the
//!    occlusion rectangles are blacked out.
//! 3. [`point_cloud`]: masked pixels with valid depth, voxel-grid downsampling.
//! 4. [`initialisation`]: the rope's ordered centre line from a mask, M nodes
//!    placed evenly along it.
//! 5. [`visibility`]: which nodes still have points within `r_vis`.
//! 6. [`registration`]: GMM-EM of the visible nodes (Eq. 1-5).
//! 7. [`occlusion`]: Unidirectional Position Estimation of hidden nodes (Eq. 6-11).
//! 8. [`resampling`]: uniform arc-length resampling (Eq. 12-15).
//! 9. [`metrics`]: the frame error (Eq. 16-18) in metres and pixels.
//!
//! Steps 5-8 are UPETrack's per-frame [`step`]; the baselines replace them
//! with [`cpd`] (deformable coherent point drift) or [`trackdlo`]
//! (TrackDLO, reimplemented), sharing everything else.
//!
//! [`tracker::Tracker`] holds the state between frames and runs the stages.
//! [`params::Params`] gathers every tunable number with the paper's defaults.
//!
//! The crate is `no_std` with `alloc`; `std` is a default feature. It has no
//! clock and no hidden randomness, and all transcendental functions go
//! through `libm`, so native and WebAssembly builds compute the same numbers.
#![no_std]
#![warn(missing_docs)]

extern crate alloc;
#[cfg(feature = "std")]
extern crate std;

pub mod camera;
pub mod cpd;
pub mod frame;
pub mod initialisation;
pub mod math;
pub mod metrics;
pub mod occlusion;
pub mod params;
pub mod point_cloud;
pub mod registration;
pub mod resampling;
pub mod rng;
pub mod segmentation;
pub mod step;
pub mod trackdlo;
pub mod tracker;
pub mod visibility;

pub use camera::CameraIntrinsics;
pub use frame::Frame;
pub use math::Vec3;
pub use params::Params;
pub use segmentation::{HsvRange, Rect};
pub use step::Algorithm;
pub use tracker::{FrameOutput, FrameStatus, Tracker};
