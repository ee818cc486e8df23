//! What the tracker keeps to follow the camera's own motion: the last
//! frame's background (`follow_camera`) and whether the caller told the
//! motion for the next frame (`Tracker::move_camera`).

use crate::motion::RigidMotion;
use crate::params::Params;
use crate::perception::camera::CameraIntrinsics;
use crate::perception::ego_motion::{camera_motion, BackgroundView, CameraMotion};
use crate::perception::frame::Frame;
use crate::perception::segmentation::{Mask, Rect};

/// The camera-following state of a tracker.
#[derive(Debug, Clone, Default)]
pub(super) struct CameraFollowing {
    /// The last frame's background, for the camera's motion since.
    background: Option<BackgroundView>,
    /// A view whose storage the next frame's is built in (a view is a few
    /// megabytes: allocated afresh every frame it costs page faults).
    spare: BackgroundView,
    /// The camera's motion was given for the next frame (`move_camera`).
    pub(super) given: bool,
    /// The camera's motion estimated on the last frame.
    pub(super) estimated: Option<CameraMotion>,
}

impl CameraFollowing {
    /// With `params.follow_camera`: the camera's motion from the last
    /// frame's background to `frame`'s (the `rope` mask and the declared
    /// `occluders` left out; none when the caller gave it, or there is no
    /// state to move), and `frame`'s background kept for the next.
    pub(super) fn follow(
        &mut self,
        frame: &Frame<'_>,
        (rope, occluders): (&Mask, &[Rect]),
        camera: &CameraIntrinsics,
        params: &Params,
        tracking: bool,
    ) -> Option<RigidMotion> {
        self.estimated = None;
        if !params.follow_camera {
            *self = Self::default();
            return None;
        }
        let mut view = core::mem::take(&mut self.spare);
        let depth_range = (params.min_depth, params.max_depth);
        view.rebuild(frame, camera, rope, occluders, depth_range);
        if !self.given && tracking {
            if let Some(last) = &self.background {
                self.estimated = camera_motion(last, &view);
            }
        }
        self.given = false;
        if let Some(last) = self.background.replace(view) {
            self.spare = last;
        }
        self.estimated.map(|m| m.motion)
    }

    /// The next frame is not the last one's successor (a reset, a
    /// snapshot restored): no camera motion is estimated across them.
    pub(super) fn forget(&mut self) {
        if let Some(last) = self.background.take() {
            self.spare = last;
        }
        self.given = false;
        self.estimated = None;
    }
}
