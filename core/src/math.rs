//! Small numeric helpers shared by the pipeline, all through `libm` so that
//! every target computes bit-identical results.

/// A point or displacement in 3D (metres, colour camera frame: x right, y down, z forward).
pub type Vec3 = nalgebra::Vector3<f64>;

/// A point in the image plane (pixels, x right, y down).
pub type Vec2 = nalgebra::Vector2<f64>;

/// Lengths below this (metres or pixels) are treated as zero when dividing.
pub const LENGTH_EPSILON: f64 = 1e-12;

/// `e^x`, the same on every target.
#[inline]
pub fn exp(x: f64) -> f64 {
    libm::exp(x)
}

/// Square root, the same on every target.
#[inline]
pub fn sqrt(x: f64) -> f64 {
    libm::sqrt(x)
}

/// Largest integer not greater than `x`.
#[inline]
pub fn floor(x: f64) -> f64 {
    libm::floor(x)
}

/// Euclidean norm of a vector, through [`sqrt`].
#[inline]
pub fn norm(v: &Vec3) -> f64 {
    sqrt(v.norm_squared())
}

/// `true` when all three coordinates are finite.
#[inline]
pub fn is_finite(v: &Vec3) -> bool {
    v.x.is_finite() && v.y.is_finite() && v.z.is_finite()
}
