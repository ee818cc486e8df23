//! Easing curves shared by the scripted motions (pulls, boxes, the camera).

/// Cubic ease in and out of `x` clamped to [0, 1]: zero speed at both ends,
/// so a scripted motion starts and stops without a jolt.
pub(crate) fn smoothstep(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}
