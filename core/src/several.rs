//! Several ropes in one frame, above the tracker of one: one [`Tracker`] per rope, each stepping on
//! the pixels [`share_pixels`] gives it, the others' pixels hiding it as an
//! occluder does.

use alloc::vec::Vec;

use crate::math::Vec2;
use crate::perception::frame::Frame;
use crate::perception::initialisation::TakenRope;
use crate::perception::segmentation::{Mask, Rect};
use crate::perception::sharing::OtherRopes;
use crate::perception::sharing::{share_pixels, PixelShare, RopeLine, MAX_SHARED};
use crate::tracker::{
    CameraFollowing, FrameOutput, Observation, Tracker, TrackerError, UNEXPLAINED_REACH,
};

/// Most ropes one [`MultiTracker`] follows: as many as pixels are shared
/// between ([`MAX_SHARED`]).
pub const MAX_ROPES: usize = MAX_SHARED;

/// Tracks up to [`MAX_ROPES`] ropes seen by one camera.
///
/// Each frame is segmented once per colour range; the pixels several
/// ropes' colours accept are shared out by [`share_pixels`] (nearest
/// tracked rope in 3D), so a rope lying across another does not take its
/// points, and each rope's step then runs on its own share with the other
/// ropes' pixels as occluders (`Evidence::others`). Ropes tracked at the
/// start of the frame step first, on the shares of the last states; then
/// each rope not tracked (not yet found, or lost) is initialised in turn
/// from what the tracked ropes leave, so two ropes of one colour never
/// take the same shape. The camera's motion (`follow_camera`, the first
/// rope's parameters deciding) is followed once for all ropes, every
/// rope's mask left out of the background. With one rope it is exactly
/// [`Tracker::process`].
#[derive(Debug, Clone)]
pub struct MultiTracker {
    ropes: Vec<Tracker>,
    /// The camera's motion, followed for all ropes (with several).
    following: CameraFollowing,
    /// Every rope's mask, the background's hole (storage kept: a frame's
    /// worth of pixels allocated afresh each frame costs page faults).
    every: Mask,
}

impl MultiTracker {
    /// A tracker of `ropes`, one [`Tracker`] each (their own parameters,
    /// colour ranges and priors), all with the same camera.
    pub fn new(ropes: Vec<Tracker>) -> Result<Self, TrackerError> {
        if ropes.is_empty() || ropes.len() > MAX_ROPES {
            return Err(TrackerError::RopeCount { count: ropes.len() });
        }
        let camera = *ropes[0].camera();
        if let Some(rope) = ropes.iter().position(|t| *t.camera() != camera) {
            return Err(TrackerError::CameraMismatch { rope });
        }
        Ok(Self {
            ropes,
            following: CameraFollowing::default(),
            every: Mask::new(0, 0),
        })
    }

    /// The ropes' trackers, in the order given.
    pub fn ropes(&self) -> &[Tracker] {
        &self.ropes
    }

    /// Rope `k`'s tracker (to set a hint or a prior), if there is one.
    pub fn rope_mut(&mut self, k: usize) -> Option<&mut Tracker> {
        self.ropes.get_mut(k)
    }

    /// The first rope's tracker (there is always one).
    pub fn first(&self) -> &Tracker {
        &self.ropes[0]
    }

    /// The first rope's tracker, to change.
    pub fn first_mut(&mut self) -> &mut Tracker {
        &mut self.ropes[0]
    }

    /// Every rope's tracker, to change (parameters, the camera's motion).
    pub fn ropes_mut(&mut self) -> &mut [Tracker] {
        &mut self.ropes
    }

    /// Rope `k`'s observation of `frame` as its next update would see it
    /// (its share of the pixels beside the ropes as they stand), to
    /// explain that update; `None` when there is no rope `k`.
    pub fn observe_rope(
        &self,
        k: usize,
        frame: &Frame<'_>,
        occlusions: &[Rect],
    ) -> Result<Option<Observation>, TrackerError> {
        if k >= self.ropes.len() {
            return Ok(None);
        }
        if self.ropes.len() == 1 {
            return self.ropes[k].observe(frame, occlusions).map(Some);
        }
        let masks = self.segment(frame, occlusions)?;
        let refs: Vec<&Mask> = masks.iter().collect();
        let share = self.share(frame, &refs).swap_remove(k);
        Ok(Some(self.observation(k, frame, share, refs[k], occlusions)))
    }

    /// Forgets every rope's state.
    pub fn reset(&mut self) {
        self.ropes.iter_mut().for_each(Tracker::reset);
        self.following.forget();
    }

    /// Tracks every rope on `frame` (with `occlusions` blacked out): one
    /// output per rope, in order. Fails only on a frame that does not fit
    /// the camera. [`MultiTracker::segment`], [`MultiTracker::observe`],
    /// then [`MultiTracker::step`].
    pub fn process(
        &mut self,
        frame: &Frame<'_>,
        occlusions: &[Rect],
    ) -> Result<Vec<FrameOutput>, TrackerError> {
        let masks = self.segment(frame, occlusions)?;
        let observations = self.observe(frame, &masks, occlusions);
        Ok(self.step(frame, &masks, observations, occlusions))
    }

    /// The observations of the ropes tracked now, from
    /// [`MultiTracker::segment`]'s masks of `frame`: each one's share of
    /// the pixels and its cloud (`None` for a rope not tracked; with one
    /// rope, its whole mask).
    pub fn observe(
        &self,
        frame: &Frame<'_>,
        masks: &[Mask],
        occlusions: &[Rect],
    ) -> Vec<Option<Observation>> {
        let empty = Mask::new(frame.width, frame.height);
        let masks = padded(masks, self.ropes.len(), &empty);
        if let ([only], [mask]) = (self.ropes.as_slice(), masks.as_slice()) {
            // One rope: exactly `Tracker::process`.
            let cloud = only.cloud(frame, mask);
            return alloc::vec![Some(Observation::new((*mask).clone(), cloud, occlusions))];
        }
        if !self.ropes.iter().any(Tracker::is_tracking) {
            return self.ropes.iter().map(|_| None).collect();
        }
        self.share(frame, &masks)
            .into_iter()
            .enumerate()
            .map(|(k, share)| {
                self.ropes[k]
                    .is_tracking()
                    .then(|| self.observation(k, frame, share, masks[k], occlusions))
            })
            .collect()
    }

    /// The tracking of every rope: each with an observation (from
    /// [`MultiTracker::observe`]) steps on it; then each without one is
    /// looked for, in order, in what the ropes tracked by then leave.
    pub fn step(
        &mut self,
        frame: &Frame<'_>,
        masks: &[Mask],
        observations: Vec<Option<Observation>>,
        occlusions: &[Rect],
    ) -> Vec<FrameOutput> {
        let empty = Mask::new(frame.width, frame.height);
        let masks = padded(masks, self.ropes.len(), &empty);
        self.follow_camera(frame, &masks, occlusions);
        let mut observations = observations.into_iter();
        let mut outputs: Vec<Option<FrameOutput>> = self
            .ropes
            .iter_mut()
            .map(|rope| {
                let obs = observations.next().flatten()?;
                Some(rope.update(frame, &obs))
            })
            .collect();
        for k in 0..self.ropes.len() {
            if outputs[k].is_some() {
                continue;
            }
            let obs = if self.ropes.len() == 1 {
                let cloud = self.ropes[k].cloud(frame, masks[k]);
                Observation::new(masks[k].clone(), cloud, occlusions)
            } else {
                let share = self.share(frame, &masks).swap_remove(k);
                self.observation(k, frame, share, masks[k], occlusions)
            };
            outputs[k] = Some(self.ropes[k].update(frame, &obs));
        }
        outputs.into_iter().flatten().collect()
    }

    /// With several ropes and `follow_camera`: the camera's motion from the
    /// background with every rope's mask left out, estimated once and
    /// carried to each rope that follows the camera (a motion a caller
    /// gave any rope skips the estimate, as for one rope).
    fn follow_camera(&mut self, frame: &Frame<'_>, masks: &[&Mask], occlusions: &[Rect]) {
        let params = *self.ropes[0].params();
        if self.ropes.len() == 1 || !params.follow_camera {
            self.following.forget();
            return;
        }
        let every = &mut self.every;
        (every.width, every.height) = (frame.width, frame.height);
        every.data.clear();
        every.data.resize(frame.pixel_count(), false);
        masks.iter().for_each(|m| every.include(m));
        self.following.given = self.ropes.iter().any(Tracker::camera_given);
        let tracking = self.ropes.iter().any(Tracker::is_tracking);
        let camera = *self.ropes[0].camera();
        let background = (&self.every, occlusions);
        self.following
            .follow(frame, background, &camera, &params, tracking);
        let estimate = self.following.estimated;
        for rope in self.ropes.iter_mut().filter(|r| r.params().follow_camera) {
            rope.camera_followed(estimate.as_ref());
        }
    }

    /// Each rope's colour mask, with `occlusions` blacked out; ropes of one
    /// colour range share one.
    pub fn segment(
        &self,
        frame: &Frame<'_>,
        occlusions: &[Rect],
    ) -> Result<Vec<Mask>, TrackerError> {
        let mut masks: Vec<Mask> = Vec::with_capacity(self.ropes.len());
        for (k, rope) in self.ropes.iter().enumerate() {
            let same = self.ropes[..k].iter().position(|r| r.hsv() == rope.hsv());
            masks.push(match same {
                Some(j) => masks[j].clone(),
                None => rope.segment(frame, occlusions)?,
            });
        }
        Ok(masks)
    }

    /// The pixels shared out between the ropes as they stand now.
    fn share(&self, frame: &Frame<'_>, masks: &[&Mask]) -> Vec<PixelShare> {
        let lines: Vec<Option<RopeLine<'_>>> = self
            .ropes
            .iter()
            .map(|t| {
                t.is_tracking().then(|| RopeLine {
                    nodes: t.nodes(),
                    radius: t.radius(),
                })
            })
            .collect();
        // A point a node explains ([`UNEXPLAINED_REACH`]) is that rope's.
        let reach = self
            .ropes
            .iter()
            .map(|t| UNEXPLAINED_REACH * t.params().visibility_radius)
            .fold(0.0, f64::max);
        share_pixels(frame, self.ropes[0].camera(), masks, &lines, reach)
    }

    /// Rope `k`'s observation of its share (`colour`: its colour mask).
    fn observation(
        &self,
        k: usize,
        frame: &Frame<'_>,
        share: PixelShare,
        colour: &Mask,
        occlusions: &[Rect],
    ) -> Observation {
        let rope = &self.ropes[k];
        let cloud = rope.cloud(frame, &share.own);
        let mut obs = Observation::new(share.own, cloud, occlusions);
        let camera = rope.camera();
        let focal = camera.fx.max(camera.fy);
        let taken = self
            .ropes
            .iter()
            .enumerate()
            .filter(|(j, t)| *j != k && t.is_tracking())
            .map(|(_, t)| {
                let line: Vec<Vec2> = t.nodes().iter().filter_map(|p| camera.project(p)).collect();
                let depth =
                    t.nodes().iter().map(|p| p.z).sum::<f64>() / t.nodes().len().max(1) as f64;
                TakenRope {
                    line,
                    radius_px: if depth > 0.0 {
                        t.radius() * focal / depth
                    } else {
                        0.0
                    },
                }
            })
            .collect();
        obs.others = Some(OtherRopes {
            pixels: share.others,
            colour: colour.clone(),
            taken,
            alike: share.alike,
        });
        obs
    }
}

/// `masks` as `count` references, a rope without one given `empty`.
fn padded<'a>(masks: &'a [Mask], count: usize, empty: &'a Mask) -> Vec<&'a Mask> {
    (0..count).map(|k| masks.get(k).unwrap_or(empty)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::camera::CameraIntrinsics;
    use crate::perception::segmentation::HsvRange;
    use crate::Params;

    fn tracker(camera: CameraIntrinsics) -> Tracker {
        Tracker::new(Params::default(), camera, HsvRange::default()).expect("tracker")
    }

    #[test]
    fn a_multi_tracker_takes_one_to_eight_ropes_of_one_camera() {
        let camera = CameraIntrinsics::D435I_640X480;
        assert_eq!(
            MultiTracker::new(Vec::new()).err(),
            Some(TrackerError::RopeCount { count: 0 })
        );
        let nine = (0..9).map(|_| tracker(camera)).collect();
        assert_eq!(
            MultiTracker::new(nine).err(),
            Some(TrackerError::RopeCount { count: 9 })
        );
        let mut other = camera;
        other.fx += 1.0;
        assert_eq!(
            MultiTracker::new(alloc::vec![tracker(camera), tracker(other)]).err(),
            Some(TrackerError::CameraMismatch { rope: 1 })
        );
        let eight = MultiTracker::new((0..8).map(|_| tracker(camera)).collect()).expect("eight");
        assert_eq!(eight.ropes().len(), 8);
    }

    #[test]
    fn a_frame_with_no_rope_leaves_every_rope_lost_without_a_panic() {
        let camera = CameraIntrinsics::D435I_640X480;
        let mut ropes =
            MultiTracker::new(alloc::vec![tracker(camera), tracker(camera)]).expect("two");
        let rgb = alloc::vec![0u8; 640 * 480 * 3];
        let depth = alloc::vec![0u16; 640 * 480];
        let frame = Frame::new(640, 480, &rgb, &depth, 0.001).expect("frame");
        let out = ropes
            .process(&frame, &[])
            .expect("a frame of the camera's size");
        assert_eq!(out.len(), 2);
        assert!(out.iter().all(FrameOutput::is_lost));
        // Fewer masks than ropes: the rope without one sees nothing.
        let masks = ropes.segment(&frame, &[]).expect("masks");
        let out = ropes.step(&frame, &masks[..1], Vec::new(), &[]);
        assert_eq!(out.len(), 2);
    }

    #[test]
    fn the_ropes_carry_one_camera_motion_estimated_for_all() {
        use crate::math::Vec3;
        use crate::perception::ego_motion::fixture::{view, CAMERA, HOME};
        let still = Params {
            follow_camera: false,
            ..Params::default()
        };
        let ropes = [Params::default(), Params::default(), still]
            .into_iter()
            .map(|p| Tracker::new(p, CAMERA, HsvRange::default()).expect("tracker"))
            .collect();
        let mut multi = MultiTracker::new(ropes).expect("three");
        let px = HOME.z / CAMERA.fx;
        let at = [HOME, HOME + Vec3::new(3.0 * px, 0.0, 0.0)];
        for (k, centre) in at.into_iter().enumerate() {
            let images = view(centre, Vec3::zeros(), true, 2.0, k as u64, None);
            let frame = Frame::new(CAMERA.width, CAMERA.height, &images.0, &images.1, 0.001)
                .expect("frame");
            for rope in multi.ropes_mut() {
                rope.track_for_test(alloc::vec![Vec3::new(0.0, 0.0, 0.8); 24]);
            }
            multi.process(&frame, &[]).expect("frame fits");
        }
        let motions: Vec<_> = multi.ropes().iter().map(Tracker::camera_motion).collect();
        assert!(motions[0].is_some(), "no motion estimated");
        assert_eq!(motions[0], motions[1]);
        assert_eq!(
            motions[2], None,
            "a rope that does not follow the camera was moved"
        );
    }
}
