//! A camera on a robot arm (issue 28): the whole rope moves in the
//! camera's frame while part of it is hidden. Told the camera's motion
//! (`Tracker::move_camera`), estimating it from the background
//! (`follow_camera`), or told that the visible rope's shared motion is to
//! be followed (`follow_shared_motion`), the hidden nodes move with it
//! instead of staying where the camera left them.

use upetrack::{Frame, Params, Tracker};
use upetrack_synth::random::CameraPath;
use upetrack_synth::Scenario;

/// A drawn scene of the tuning range: a camera on an arm moving 2-8 cm
/// while a declared rectangle hides 57 % of a resting rope.
const ARM_SEED: u64 = 1066;

/// How the camera's motion reaches the tracker.
#[derive(Clone, Copy)]
enum Told {
    /// Not at all, or as `params` say (estimated, or the rope's own).
    ByParams,
    /// The simulator's true motion through `Tracker::move_camera`.
    Truth,
}

/// A drawn scene of the tuning range: a handheld camera (drift and
/// tremor) at 1280x720, 0.58 m from a resting rope 69 % hidden by a
/// declared rectangle.
const HANDHELD_SEED: u64 = 1052;

/// The mean error (mm) over the frames from the first occluded one.
fn after_occlusion(params: Params, told: Told) -> f64 {
    after_occlusion_of(ARM_SEED, params, told)
}

/// [`after_occlusion`] on the drawn scene of `seed`.
fn after_occlusion_of(seed: u64, params: Params, told: Told) -> f64 {
    let mut s = Scenario::random(seed, 48);
    let camera = s.camera();
    let mut tracker = Tracker::new(params, camera, s.hsv()).expect("tracker");
    let mut first_occluded = s.occlusions.first().map(|o| o.first);
    let mut last_pose = None;
    let mut errors = Vec::new();
    while let Some(f) = s.next_frame() {
        if first_occluded.is_none() && f.occluded.iter().any(|&o| o) {
            first_occluded = Some(f.index);
        }
        if let (Told::Truth, Some(last)) = (told, last_pose) {
            let moved = upetrack_synth::render::CameraPose::motion_to(&last, &f.camera_pose);
            tracker.move_camera(&moved).expect("a finite motion");
        }
        last_pose = Some(f.camera_pose);
        let frame =
            Frame::new(camera.width, camera.height, &f.rgb, &f.depth, 0.001).expect("frame");
        let out = tracker
            .process(&frame, &s.occlusions_at(f.index))
            .expect("process");
        assert!(!out.is_lost(), "frame {} lost", f.index);
        if first_occluded.is_some_and(|o| f.index >= o) {
            errors.push(
                upetrack::metrics::frame_error(&out.nodes, &f.groundtruth).expect("error") * 1000.0,
            );
        }
    }
    assert!(errors.len() > 10, "{} occluded frames", errors.len());
    errors.iter().sum::<f64>() / errors.len() as f64
}

/// The defaults without following the camera: the hidden rope is held
/// where the camera left it.
fn holding() -> Params {
    Params {
        follow_camera: false,
        ..Params::default()
    }
}

fn held() -> f64 {
    let draw = Scenario::random(ARM_SEED, 48).draw.expect("a drawn scene");
    assert!(matches!(draw.camera.motion, Some(CameraPath::Arm { .. })));
    after_occlusion(holding(), Told::ByParams)
}

/// The error after the occlusion on the drawn scene of `seed` with the
/// camera's motion estimated from the background (`follow_camera`, the
/// default).
fn from_background(seed: u64) -> f64 {
    after_occlusion_of(seed, Params::default(), Told::ByParams)
}

/// Prints both errors and checks that `got` (mm, the camera's motion
/// taken `how`) is below `bound` mm and below `share` of `held`.
fn assert_below(held: f64, got: f64, how: &str, (bound, share): (f64, f64)) {
    eprintln!("after occlusion: {held:.2} mm held, {got:.2} mm {how}");
    assert!(got < bound && got < share * held, "{held:.2} / {got:.2} mm");
}

#[test]
fn a_camera_on_an_arm_does_not_leave_the_hidden_rope_behind_when_followed() {
    let held = held();
    let mut followed = holding();
    followed.upetrack.follow_shared_motion = true;
    let followed = after_occlusion(followed, Told::ByParams);
    assert_below(held, followed, "followed", (3.0, 0.5));
}

#[test]
fn a_known_camera_motion_keeps_the_hidden_rope_where_it_lies() {
    let held = held();
    let told = after_occlusion(holding(), Told::Truth);
    assert_below(held, told, "told the camera's motion", (2.0, 0.3));
}

#[test]
fn a_camera_on_an_arm_is_followed_from_the_background() {
    let held = held();
    let followed = from_background(ARM_SEED);
    // 1.46 mm when the view was read at 160 px from each block's centre.
    assert_below(held, followed, "from the background", (1.4, 0.3));
}

#[test]
fn a_handheld_camera_at_1280x720_does_not_leave_the_hidden_rope_behind() {
    let draw = Scenario::random(HANDHELD_SEED, 48)
        .draw
        .expect("a drawn scene");
    assert!(matches!(
        draw.camera.motion,
        Some(CameraPath::Handheld { .. })
    ));
    let held = after_occlusion_of(HANDHELD_SEED, holding(), Told::ByParams);
    let followed = from_background(HANDHELD_SEED);
    assert_below(held, followed, "from the background", (2.0, 0.3));
}

/// Regression for "a handheld camera over a plain table slides the rope
/// away" (drawn scene 4046: a two-tone rope 0.87 m away on a dark table
/// with next to no texture, a handheld camera at 1280x720, a rectangle over
/// a fifth of the rope). The table's depth showed the camera's tilt and
/// nothing showed where along the table it went; the slide read from noisy
/// depth gradients ran to 15 cm a frame and carried the state off the rope
/// on most frames, lost twice: 31 mm after the occlusion. With a slide
/// taken only where the brightness shows it, 1.6 mm.
#[test]
fn a_handheld_camera_over_a_plain_table_does_not_slide_the_rope_away() {
    let followed = from_background(4046);
    eprintln!("after occlusion: {followed:.2} mm");
    assert!(followed < 3.0, "{followed:.2} mm");
}
