//! Pictures of a frame for people, drawn the same way by the command's
//! `overlay` and by the page: the depth image as a colour ramp.

/// Depth as RGB8, one colour per pixel: near red, far blue (the ramp spans
/// the frame's own valid range), black where there is no measurement.
pub fn depth_to_rgb(depth: &[u16]) -> Vec<u8> {
    let valid = depth.iter().filter(|&&d| d > 0);
    let lo = valid.clone().min().copied().unwrap_or(0) as f64;
    let hi = valid.max().copied().unwrap_or(1) as f64;
    let mut out = Vec::with_capacity(depth.len() * 3);
    for &d in depth {
        if d == 0 {
            out.extend([0, 0, 0]);
        } else {
            let t = (d as f64 - lo) / (hi - lo).max(1.0);
            out.extend([
                (255.0 * (1.0 - t)) as u8,
                (80.0 + 120.0 * (1.0 - (2.0 * t - 1.0).abs())) as u8,
                (255.0 * t) as u8,
            ]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_is_red_far_is_blue_and_holes_are_black() {
        let rgb = depth_to_rgb(&[500, 0, 1500, 1000]);
        assert_eq!(&rgb[0..3], &[255, 80, 0]);
        assert_eq!(&rgb[3..6], &[0, 0, 0]);
        assert_eq!(&rgb[6..9], &[0, 80, 255]);
        assert_eq!(&rgb[9..12], &[127, 200, 127]);
    }
}
