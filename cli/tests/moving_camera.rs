//! A camera on a robot arm (issue 28): the whole rope moves in the
//! camera's frame while part of it is hidden. Told that the visible rope's
//! shared motion is to be followed (`follow_shared_motion`), the hidden
//! nodes move with it instead of staying where the camera left them.

use upetrack::Params;
use upetrack_synth::random::CameraPath;
use upetrack_synth::Scenario;

mod common;
use common::scenes::each_frame_of;

/// A drawn scene of the tuning range: a camera on an arm moving 2-8 cm
/// while a declared rectangle hides 57 % of a resting rope.
const ARM_SEED: u64 = 1066;

/// The mean error (mm) over the frames from the first occluded one.
fn after_occlusion(params: Params) -> f64 {
    let mut errors = Vec::new();
    each_frame_of(
        Scenario::random(ARM_SEED, 48),
        params,
        |f, out, occluded| {
            if occluded {
                errors.push(
                    upetrack::metrics::frame_error(&out.nodes, &f.groundtruth).expect("error")
                        * 1000.0,
                );
            }
        },
    );
    assert!(errors.len() > 10, "{} occluded frames", errors.len());
    errors.iter().sum::<f64>() / errors.len() as f64
}

#[test]
fn a_camera_on_an_arm_does_not_leave_the_hidden_rope_behind_when_followed() {
    let draw = Scenario::random(ARM_SEED, 48).draw.expect("a drawn scene");
    assert!(matches!(draw.camera.motion, Some(CameraPath::Arm { .. })));
    let held = after_occlusion(Params::default());
    let mut followed = Params::default();
    followed.upetrack.follow_shared_motion = true;
    let followed = after_occlusion(followed);
    eprintln!("after occlusion: {held:.2} mm held, {followed:.2} mm followed");
    assert!(
        followed < 3.0 && followed < 0.5 * held,
        "{held:.2} / {followed:.2} mm"
    );
}
