//! Synthetic RGB-D sequences of a rope seen by a RealSense D435i, with exact
//! ground truth: a position-based (XPBD-style) rope simulation on a table,
//! a ray-casting renderer (capsule chain, table, occluder boxes) with a
//! D435i-like depth noise model, and the named scenarios of the evaluation
//! (of one rope, and of several: [`several`]).
//!
//! `no_std` with `alloc`, like the core, so that it also runs in a browser.
#![no_std]
#![warn(missing_docs)]

extern crate alloc;

pub mod camera_path;
mod drawn;
mod ease;
mod events;
mod layout;
mod plan;
pub mod random;
pub mod render;
pub mod rope;
pub mod scenario;
pub mod several;
mod several_drawn;
pub mod variant;

pub use random::{RandomScene, SeedRange};
pub use render::{RenderSettings, Rendered};
pub use rope::{Rope, RopeSettings};
pub use scenario::{Scenario, ScenarioKind, SceneKnobs, SynthFrame, SIMULATOR_VERSION};
pub use several::{SeveralFrame, SeveralKind, SeveralRopes};
pub use variant::Variant;

/// Most frames one scenario records.
pub const MAX_FRAMES: usize = 100_000;

/// Frames per second of a simulated sequence unless a drawn scene asks for
/// another rate ([`RandomScene::fps`]): the D435i's default.
pub const SIMULATED_FPS: f64 = 30.0;

/// Slowest and fastest frame rates a drawn scene may be simulated at (the
/// D435i's colour stream runs at 6 to 90 frames per second).
pub const FPS_RANGE: (f64, f64) = (6.0, 90.0);
