//! The paths users of the crate call keep working whatever the layout
//! inside: the root re-exports, used as the README shows them.

use upetrack::{Algorithm, CameraIntrinsics, Frame, HsvRange, Params, Rect, Tracker};

#[test]
fn the_readme_example_runs_through_the_root_re_exports() {
    let camera = CameraIntrinsics::D435I_640X480;
    let mut tracker =
        Tracker::new(Params::default(), camera, HsvRange::default()).expect("default tracker");
    let (w, h) = (camera.width as usize, camera.height as usize);
    let rgb = vec![0u8; w * h * 3];
    let depth = vec![0u16; w * h];
    let frame = Frame::new(camera.width, camera.height, &rgb, &depth, 0.001).expect("frame");
    let hide = Rect {
        x: 0,
        y: 0,
        w: 10,
        h: 10,
    };
    let out = tracker.process(&frame, &[hide]).expect("processed");
    // A black frame has no rope: reported lost, never a panic.
    assert!(out.is_lost() && out.nodes.is_empty());
    assert_eq!(Params::default().algorithm, Algorithm::Upetrack);
}
