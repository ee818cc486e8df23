//! What the tracker keeps to follow the camera's own motion: the
//! background of the frame the state last agreed with (`follow_camera`)
//! and whether the caller told the motion for the next frame
//! (`Tracker::move_camera`).

use crate::motion::RigidMotion;
use crate::params::Params;
use crate::perception::camera::CameraIntrinsics;
use crate::perception::ego_motion::{camera_motion, BackgroundView, CameraMotion};
use crate::perception::frame::Frame;
use crate::perception::glance::BackgroundGlance;
use crate::perception::segmentation::{Mask, Rect};

/// The camera-following state of a tracker (or of a
/// [`crate::MultiTracker`]'s ropes together).
#[derive(Debug, Clone, Default)]
pub(crate) struct CameraFollowing {
    /// The reference: the background of the last frame whose glance did
    /// not show the camera still (or the first), for its motion since.
    background: Option<BackgroundView>,
    /// A view whose storage the next frame's is built in (a view is a few
    /// megabytes: allocated afresh every frame it costs page faults).
    spare: BackgroundView,
    /// The reference frame's glance, and a spare.
    glance: Option<BackgroundGlance>,
    spare_glance: BackgroundGlance,
    /// The camera's motion was given for the next frame (`move_camera`).
    pub(crate) given: bool,
    /// The camera's motion for the next frame was followed outside (by a
    /// `MultiTracker`, once for all its ropes).
    pub(crate) outside: bool,
    /// The camera's motion estimated on the last frame.
    pub(crate) estimated: Option<CameraMotion>,
}

impl CameraFollowing {
    /// With `params.follow_camera`: the camera's motion from the
    /// reference's background to `frame`'s (the `rope` mask and the
    /// declared `occluders` left out; none when the caller gave it - then
    /// nothing is built and the reference is dropped - or there is no
    /// state to move). A frame whose glance shows the camera
    /// still since the reference's costs no estimate and keeps the
    /// reference (a drift too slow to see from one frame to the next adds
    /// up against it until the glance sees it); any other becomes the
    /// reference.
    pub(crate) fn follow(
        &mut self,
        frame: &Frame<'_>,
        (rope, occluders): (&Mask, &[Rect]),
        camera: &CameraIntrinsics,
        params: &Params,
        tracking: bool,
    ) -> Option<RigidMotion> {
        if core::mem::take(&mut self.outside) {
            return None;
        }
        self.estimated = None;
        if !params.follow_camera {
            *self = Self::default();
            return None;
        }
        if self.given {
            // The caller gave this frame's motion (a robot's kinematics
            // give every frame's): nothing is built, and the next estimate
            // starts from a new reference.
            self.forget();
            return None;
        }
        let depth_range = (params.min_depth, params.max_depth);
        let mut glance = core::mem::take(&mut self.spare_glance);
        glance.rebuild(frame, rope, occluders, depth_range);
        let estimate = tracking && self.background.is_some();
        if estimate
            && self
                .glance
                .as_ref()
                .is_some_and(|g| glance.still_since(g, camera))
        {
            self.spare_glance = glance;
            return None;
        }
        let mut view = core::mem::take(&mut self.spare);
        view.rebuild(frame, camera, rope, occluders, depth_range);
        if estimate {
            if let Some(last) = &self.background {
                self.estimated = camera_motion(last, &view);
            }
        }
        if let Some(last) = self.background.replace(view) {
            self.spare = last;
        }
        if let Some(last) = self.glance.replace(glance) {
            self.spare_glance = last;
        }
        self.estimated.map(|m| m.motion)
    }

    /// The camera's motion for the next frame was followed outside (by a
    /// `MultiTracker`, once for all its ropes; `estimate` its estimate):
    /// the next [`CameraFollowing::follow`] does nothing.
    pub(crate) fn followed_outside(&mut self, estimate: Option<&CameraMotion>) {
        self.given = false;
        self.outside = true;
        self.estimated = estimate.copied();
    }

    /// The next frame is not the last one's successor (a reset, a
    /// snapshot restored): no camera motion is estimated across them.
    pub(crate) fn forget(&mut self) {
        if let Some(last) = self.background.take() {
            self.spare = last;
        }
        if let Some(last) = self.glance.take() {
            self.spare_glance = last;
        }
        self.given = false;
        self.outside = false;
        self.estimated = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::perception::ego_motion::fixture::{no_rope, view, CAMERA, HOME};

    /// Follows the camera on the fixture's table seen from `centre`.
    fn follow_at(following: &mut CameraFollowing, centre: Vec3, seed: u64) -> Option<RigidMotion> {
        let images = view(centre, Vec3::zeros(), true, 2.0, seed, None);
        let frame =
            Frame::new(CAMERA.width, CAMERA.height, &images.0, &images.1, 0.001).expect("frame");
        let params = Params::default();
        following.follow(&frame, (&no_rope(), &[]), &CAMERA, &params, true)
    }

    #[test]
    fn a_still_camera_keeps_its_reference_and_a_moved_one_is_estimated_against_it() {
        let mut following = CameraFollowing::default();
        assert_eq!(follow_at(&mut following, HOME, 1), None);
        let reference = following.glance.clone();
        assert!(reference.is_some(), "the first frame is the reference");
        // Still: no view is built, the reference stays.
        assert_eq!(follow_at(&mut following, HOME, 2), None);
        assert_eq!(following.glance, reference);
        // Moved by three pixels: estimated, and the new frame is the reference.
        let px = HOME.z / CAMERA.fx;
        let moved = follow_at(&mut following, HOME + Vec3::new(3.0 * px, 0.0, 0.0), 3);
        assert!(moved.is_some(), "the move was not estimated");
        assert_ne!(following.glance, reference);
    }

    #[test]
    fn a_motion_the_caller_gives_builds_nothing_and_drops_the_reference() {
        let mut following = CameraFollowing::default();
        follow_at(&mut following, HOME, 1);
        following.given = true;
        let px = HOME.z / CAMERA.fx;
        assert_eq!(
            follow_at(&mut following, HOME + Vec3::new(3.0 * px, 0.0, 0.0), 2),
            None
        );
        assert!(following.background.is_none() && following.glance.is_none());
        assert!(!following.given);
        // The next frame is a new reference: nothing to estimate against.
        assert_eq!(
            follow_at(&mut following, HOME + Vec3::new(6.0 * px, 0.0, 0.0), 3),
            None
        );
        assert!(following.glance.is_some());
    }
}
