//! Taking a rope the initialisation found as the tracked state: the first
//! time, its length and radius become the rope's; on a re-initialisation
//! UPETrack lays the whole rest length.

use super::{FrameOutput, FrameStatus, Observation, TrackState, Tracker};
use crate::math::Vec3;
use crate::perception::frame::Frame;
use crate::perception::initialisation::{one_rope_thick, Initialisation};
use crate::perception::point_cloud::build_cloud;
use crate::polyline::polyline_length;
use crate::step::Algorithm;
use crate::upe::length::{laid_whole_length, rest_length};
use crate::visibility::visible_nodes_relative;

impl Tracker {
    /// Whether `init` found a rope as thick as the one tracked (the
    /// diameters the initialisation measures, within the factor its
    /// fragments are joined with): a recovery replaces a state that
    /// contradicts the images with the same rope only, not with a box's
    /// dark edge beside it (drawn scene 1032).
    pub(super) fn as_thick_as_tracked(&self, init: &Initialisation) -> bool {
        match (init.diameter(), self.known_diameter) {
            (Some(a), Some(b)) => one_rope_thick(a, b),
            _ => true,
        }
    }

    /// Takes `init` as the state. A re-initialisation of UPETrack (with
    /// `extend_short_ends`) lays the whole rest length: the part not found
    /// where something hides it.
    pub(super) fn adopt(
        &mut self,
        mut init: Initialisation,
        frame: &Frame<'_>,
        obs: &Observation,
    ) -> FrameOutput {
        let p = &self.params;
        if let (Some(rest), Algorithm::Upetrack, true) =
            (self.rest_length, p.algorithm, p.upetrack.extend_short_ends)
        {
            let e = self.evidence(&self.camera, frame, obs);
            let allows = |p: &Vec3| e.shows_rope_at(p) || e.hides_rope_at(p);
            init.nodes = laid_whole_length(&init.nodes, rest, &allows);
        }
        if self.known_length.is_none() {
            self.known_length = Some(init.length);
            self.known_radius = init.radius;
            self.known_cover = init.mask_cover;
            self.known_diameter = init.diameter();
            self.rest_length = Some(rest_length(polyline_length(&init.nodes), self.radius()));
            self.rope_node_count = Some(init.nodes.len());
        }
        // The cloud left out parts too wide for the old state's rope: the
        // new nodes are judged against the whole mask's.
        let whole;
        let cloud = if obs.too_wide > 0 {
            whole = build_cloud(frame, &obs.mask, &self.camera, &self.cloud_settings());
            &whole
        } else {
            &obs.cloud
        };
        let p = &self.params;
        let visible = visible_nodes_relative(
            &init.nodes,
            cloud,
            p.visibility_radius,
            p.visibility_min_points as usize,
            p.visibility_min_fraction,
        );
        self.refused_jump_cloud = None;
        self.state = Some(TrackState {
            nodes: init.nodes.clone(),
            lost: false,
            not_rope: self.not_rope_after(&init.nodes, &visible, cloud),
        });
        self.stepper.start(&init.nodes);
        FrameOutput {
            nodes: init.nodes,
            visible,
            status: FrameStatus::Initialised,
            em: None,
            upe: None,
            trackdlo: None,
            init: Some(init.report),
            judgement: None,
        }
    }
}
