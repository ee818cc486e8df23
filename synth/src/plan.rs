//! What a scene of several ropes is made of before it is made: each rope
//! laid (shape, colour, size, the ropes it lies on), the grasps that move
//! them and the boxes that pass.

use alloc::string::String;
use alloc::vec::Vec;

use upetrack::math::Vec3;

use crate::events::MovingBox;

/// The blue of the single-rope scenarios.
pub(crate) const BLUE: [f64; 3] = [0.08, 0.22, 0.55];
/// A red rope's albedo.
pub(crate) const RED: [f64; 3] = [0.60, 0.10, 0.08];
/// A green rope's albedo.
pub(crate) const GREEN: [f64; 3] = [0.10, 0.42, 0.14];

/// Length of each rope, metres (three fit side by side in view at 0.6 m).
pub(crate) const ROPE_LENGTH: f64 = 0.42;
/// Diameter of each rope, metres.
pub(crate) const ROPE_THICKNESS: f64 = 0.010;

/// A grasp of a scene being made: rope `rope`'s particle `particle`
/// (clamped to its last) moved by `offset` from `start` to `end` (shares
/// of the frames), from its settled position moved by `from` (where an
/// earlier grasp of it left it; zero for the first).
pub(crate) struct Grasp {
    pub(crate) rope: usize,
    pub(crate) particle: usize,
    pub(crate) offset: Vec3,
    pub(crate) start: f64,
    pub(crate) end: f64,
    pub(crate) from: Vec3,
}

/// One rope of a scene before it is made: where it lies and how it looks.
pub(crate) struct Laid {
    pub(crate) shape: Vec<Vec3>,
    pub(crate) color: [f64; 3],
    pub(crate) name: String,
    /// Indices of the ropes (among those laid before it) it lies on.
    pub(crate) over: Vec<usize>,
    /// Length and diameter, metres.
    pub(crate) length: f64,
    pub(crate) thickness: f64,
}

/// A rope of the described scenes: [`ROPE_LENGTH`] by [`ROPE_THICKNESS`].
pub(crate) fn laid(shape: Vec<Vec3>, color: [f64; 3], name: &str, over: &[usize]) -> Laid {
    Laid {
        shape,
        color,
        name: String::from(name),
        over: over.to_vec(),
        length: ROPE_LENGTH,
        thickness: ROPE_THICKNESS,
    }
}

/// What a scene is made of before it is made.
pub(crate) struct Plan {
    pub(crate) laid: Vec<Laid>,
    pub(crate) grasps: Vec<Grasp>,
    pub(crate) boxes: Vec<MovingBox>,
}

/// 200 points from `a` to `b` (table plane, metres) bowed sideways by
/// `bow` at the middle, shifted by `shift`.
pub(crate) fn bowed(a: [f64; 2], b: [f64; 2], bow: f64, shift: Vec3) -> Vec<Vec3> {
    (0..200)
        .map(|i| {
            let t = i as f64 / 199.0;
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len = libm::sqrt(dx * dx + dy * dy).max(1e-9);
            let off = bow * libm::sin(core::f64::consts::PI * t);
            Vec3::new(
                a[0] + dx * t - dy / len * off,
                a[1] + dy * t + dx / len * off,
                0.0,
            ) + shift
        })
        .collect()
}
