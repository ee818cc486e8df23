//! Every tunable number of the tracker in one plain struct that composes
//! the shared pipeline's settings with each algorithm's own
//! ([`UpeTrackParams`], [`CpdSettings`], [`TrackDloParams`]). Invalid values
//! are rejected with [`ParamsError`], never clamped.
//!
//! In a parameter file UPETrack's fields sit at the top level beside the
//! shared ones (the file format predates the split), the baselines' under
//! `"cpd"` and `"trackdlo"`.

#[cfg(feature = "cdcpd2")]
use crate::baselines::cdcpd2::Cdcpd2Settings;
use crate::baselines::cpd::CpdSettings;
use crate::baselines::trackdlo::TrackDloParams;
use crate::perception::initialisation::InitSettings;
use crate::perception::point_cloud::{CloudSettings, Downsampling, SURFACE_TO_AXIS_RATIO};
use crate::step::Algorithm;
pub use crate::upe::registration::MAX_EM_ITERATIONS;
use crate::upe::UpeTrackParams;
pub use crate::validation::ParamsError;
use crate::validation::{check, unit};

/// Fewest nodes accepted: UPE needs three known nodes and one to estimate.
pub const MIN_NODES: usize = 4;
/// Most nodes accepted; every per-frame cost grows with it.
pub const MAX_NODES: usize = 1000;

/// The tracker's parameters. Lengths are in metres.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct Params {
    /// Number of nodes along the rope (`M`), the fewest when
    /// `node_spacing_diameters` sets it from the rope. Paper: 24.
    pub node_count: usize,
    /// Set the node count from the rope the first initialisation finds:
    /// nodes this many of its diameters apart (measured, or the prior's),
    /// at least `node_count` and at most
    /// [`crate::perception::initialisation::MAX_SPACED_NODES`]; kept for
    /// the rest of the sequence. 0 keeps `node_count` for any rope. Shared
    /// by every algorithm. Default 4 (a 0.3-1.5 m rope 3-20 mm thick gets
    /// 24-48 nodes); 0 in [`Params::paper`]. See `docs/algorithm-notes.md`,
    /// "The node count from the rope".
    pub node_spacing_diameters: f64,
    /// Visibility radius (`r_vis`), metres. Paper: 20 mm.
    pub visibility_radius: f64,
    /// Points needed within `r_vis` for a node to be visible (`V_lim`). Paper: 3.
    pub visibility_min_points: u32,
    /// A node is visible only if it also has at least this fraction of the
    /// median neighbour count of the visible nodes, so that a node at the
    /// edge of an occlusion counts as hidden (0: the paper's rule alone).
    /// Default 0.5; see `docs/algorithm-notes.md`.
    pub visibility_min_fraction: f64,
    /// Voxel-grid leaf size for downsampling the cloud, metres (0 keeps all points). Default 8 mm.
    pub voxel_size: f64,
    /// How the cloud is downsampled at that leaf size. Default `auto`: ray
    /// columns for UPETrack (each point the mean depth of its pixels), the
    /// voxel grid for the baselines (their published pipelines').
    pub downsampling: Downsampling,
    /// Radius of the rope, metres: the cloud (its visible surface) is moved
    /// `pi/4` of it away from the camera to lie on the centre line. 0 turns
    /// the correction off. Default 7.5 mm (the paper's 15 mm thick rope);
    /// used until, and unless, `estimate_radius` measures the rope.
    pub dlo_radius: f64,
    /// Measure the rope's radius at initialisation from its width in the
    /// image and its depth (5-20 mm ropes alike), and use that instead of
    /// `dlo_radius`; and read across the rope in depth how much of its
    /// width the mask covers (a grey or white rope's shaded edges fall out
    /// of its colour range), the cloud pushed from that strip's mean
    /// surface to the axis (`perception::initialisation::mask_cover`).
    /// Default true; false keeps `dlo_radius` throughout.
    pub estimate_radius: bool,
    /// Nearest valid depth, metres. Default 0.1 m.
    pub min_depth: f64,
    /// Farthest valid depth, metres. Default 3 m.
    pub max_depth: f64,
    /// Smallest blob of mask pixels taken as the rope at initialisation. Default 150.
    pub min_blob_pixels: u32,
    /// After tracking is lost, re-initialise only once the centre line found
    /// is at least this fraction of the first initialisation's length. Default 0.8.
    pub reinit_length_fraction: f64,
    /// When fewer than this fraction of the nodes are visible, try to
    /// re-initialise (accepted under `reinit_length_fraction`): the rope may
    /// have jumped. 0 turns it off. Default 0.5.
    pub reinit_visible_fraction: f64,
    /// Follow the camera's own motion: estimate it from the background
    /// ([`crate::perception::ego_motion`]: the textured pixels that are
    /// neither rope nor declared occluder) and move the tracked rope with
    /// it before each step, so that a rope at rest stays at rest in the
    /// world when the camera is on an arm or in a hand. Shared by every
    /// algorithm. Default true: a glance at the background
    /// ([`crate::perception::glance`], about 0.1 ms) tells a still camera
    /// first, and only the frames it does not read still pay for the
    /// estimate (about 1.3 ms). On the randomised report range it takes
    /// UPETrack's median error from 2.44 to 2.26 mm and the sequences with
    /// a frame above 20 mm from 13 to 7 (see `docs/algorithm-notes.md`,
    /// "The camera's own motion"); the hand-made scenes (still cameras)
    /// are unchanged. `false` in [`Params::paper`].
    /// [`crate::Tracker::move_camera`] takes a known motion instead.
    pub follow_camera: bool,
    /// UPETrack's registration and occlusion-estimate parameters (in a
    /// file: at the top level).
    #[cfg_attr(feature = "serde", serde(flatten))]
    pub upetrack: UpeTrackParams,
    /// The per-frame tracking step. Default UPETrack; CPD and TrackDLO are
    /// the baselines, sharing everything else.
    pub algorithm: Algorithm,
    /// CPD's settings (used when `algorithm` is CPD).
    pub cpd: CpdSettings,
    /// TrackDLO's parameters (used when `algorithm` is TrackDLO).
    pub trackdlo: TrackDloParams,
    /// CDCPD2's settings (used when `algorithm` is CDCPD2).
    #[cfg(feature = "cdcpd2")]
    pub cdcpd2: Cdcpd2Settings,
}

impl Default for Params {
    /// The paper's values (M = 24, gamma = 0.8, a = 0.6, b = 0.8,
    /// alpha = 0.75, r_vis = 20 mm, V_lim = 3) and this project's choices for
    /// what the paper leaves open (see `docs/algorithm-notes.md`).
    fn default() -> Self {
        Self {
            node_count: 24,
            node_spacing_diameters: 4.0,
            visibility_radius: 0.020,
            visibility_min_points: 3,
            visibility_min_fraction: 0.5,
            voxel_size: 0.008,
            downsampling: Downsampling::Auto,
            dlo_radius: 0.0075,
            estimate_radius: true,
            min_depth: 0.1,
            max_depth: 3.0,
            min_blob_pixels: 150,
            reinit_length_fraction: 0.8,
            reinit_visible_fraction: 0.5,
            follow_camera: true,
            upetrack: UpeTrackParams::default(),
            algorithm: Algorithm::Upetrack,
            cpd: CpdSettings::default(),
            trackdlo: TrackDloParams::default(),
            #[cfg(feature = "cdcpd2")]
            cdcpd2: Cdcpd2Settings::default(),
        }
    }
}

impl Params {
    /// The paper's tracking rules exactly (`--params paper`): visibility by
    /// `q >= V_lim` alone, Eq. 6-11 with `alpha = 0.75` for every hidden
    /// run (ends too), and nothing of this project's additions to the
    /// tracking step, the camera's motion included (`follow_camera` off),
    /// and the paper's `M` = 24 for any rope (`node_spacing_diameters` 0).
    /// The rest of the shared pipeline (segmentation, cloud, radius,
    /// initialisation) is the same as the defaults'.
    pub fn paper() -> Self {
        let upe = UpeTrackParams::default();
        Self {
            visibility_min_fraction: 0.0,
            upetrack: UpeTrackParams {
                end_displacement_weight: upe.displacement_weight,
                hidden_motion: crate::upe::occlusion::HiddenMotion::Paper,
                free_space: false,
                conserve_length: false,
                across_rope_displacement: false,
                smooth_resampling: false,
                rest_speed_m_per_s: 0.0,
                anchor_across_only: false,
                hidden_nodes_absorb: false,
                extend_short_ends: false,
                extend_under_occluders: false,
                keep_end_run_spacing: false,
                follow_shared_motion: false,
                follow_emerged_ends: false,
                hidden_under_crossings: false,
                report_on_arcs: false,
                report_seen_tips: false,
                ..upe
            },
            follow_camera: false,
            node_spacing_diameters: 0.0,
            ..Self::default()
        }
    }

    /// TrackDLO with upstream's own pipeline settings
    /// (`--params trackdlo-upstream`): its evaluation parameters, its 5 mm
    /// voxel grid, and the cloud left on the rope's surface (no push to the
    /// axis, no radius estimate), as `trackdlo_node.cpp` builds it.
    pub fn trackdlo_upstream() -> Self {
        Self {
            algorithm: Algorithm::Trackdlo,
            voxel_size: 0.005,
            downsampling: Downsampling::VoxelGrid,
            dlo_radius: 0.0,
            estimate_radius: false,
            trackdlo: TrackDloParams::EVALUATION,
            ..Self::default()
        }
    }

    /// A named preset: `default`, `paper` or `trackdlo-upstream`.
    pub fn preset(name: &str) -> Option<Self> {
        match name {
            "default" => Some(Self::default()),
            "paper" => Some(Self::paper()),
            "trackdlo-upstream" => Some(Self::trackdlo_upstream()),
            _ => None,
        }
    }

    /// Checks every field against its documented range.
    pub fn validate(&self) -> Result<(), ParamsError> {
        let m = self.node_count;
        check(
            "node_count",
            m as f64,
            (MIN_NODES..=MAX_NODES).contains(&m),
            "an integer in 4..=1000",
        )?;
        let k = self.node_spacing_diameters;
        check(
            "node_spacing_diameters",
            k,
            (0.0..=1000.0).contains(&k),
            "in [0, 1000] rope diameters",
        )?;
        let r = self.visibility_radius;
        check(
            "visibility_radius",
            r,
            r > 0.0 && r <= 1.0,
            "in (0, 1] metres",
        )?;
        let v = self.visibility_min_points;
        check(
            "visibility_min_points",
            v as f64,
            (1..=100_000).contains(&v),
            "an integer in 1..=100000",
        )?;
        let vf = self.visibility_min_fraction;
        unit("visibility_min_fraction", vf)?;
        let vx = self.voxel_size;
        check(
            "voxel_size",
            vx,
            (0.0..=0.1).contains(&vx),
            "in [0, 0.1] metres",
        )?;
        let rad = self.dlo_radius;
        check(
            "dlo_radius",
            rad,
            (0.0..=0.1).contains(&rad),
            "in [0, 0.1] metres",
        )?;
        let (lo, hi) = (self.min_depth, self.max_depth);
        check(
            "max_depth",
            hi,
            hi > 0.0 && hi <= 100.0,
            "in (0, 100] metres",
        )?;
        check(
            "min_depth",
            lo,
            lo >= 0.0 && lo < hi,
            "at least 0 and below max_depth",
        )?;
        let f = self.reinit_length_fraction;
        unit("reinit_length_fraction", f)?;
        let rv = self.reinit_visible_fraction;
        unit("reinit_visible_fraction", rv)?;
        self.upetrack.validate()?;
        self.cpd.validate()?;
        #[cfg(feature = "cdcpd2")]
        self.cdcpd2.validate()?;
        #[cfg(not(feature = "cdcpd2"))]
        if self.algorithm == Algorithm::Cdcpd2 {
            return Err(ParamsError::Unavailable {
                name: "algorithm",
                value: "cdcpd2",
                feature: "cdcpd2",
            });
        }
        self.trackdlo.validate()
    }

    /// The point cloud settings, for a rope of radius `dlo_radius`.
    pub fn cloud(&self) -> CloudSettings {
        self.cloud_for_radius(self.dlo_radius)
    }

    /// The point cloud settings for a rope of radius `radius`, metres, seen
    /// over its whole width.
    pub fn cloud_for_radius(&self, radius: f64) -> CloudSettings {
        self.cloud_with_push(radius * SURFACE_TO_AXIS_RATIO)
    }

    /// The point cloud settings with the points pushed `axis_offset` metres
    /// along their rays.
    pub fn cloud_with_push(&self, axis_offset: f64) -> CloudSettings {
        CloudSettings {
            min_depth: self.min_depth,
            max_depth: self.max_depth,
            voxel_size: self.voxel_size,
            axis_offset,
            downsampling: self.downsampling(),
        }
    }

    /// The downsampling in force: `auto` resolved for `algorithm`.
    pub fn downsampling(&self) -> Downsampling {
        match (self.downsampling, self.algorithm) {
            (Downsampling::Auto, Algorithm::Upetrack) => Downsampling::RayColumns,
            (Downsampling::Auto, _) => Downsampling::VoxelGrid,
            (chosen, _) => chosen,
        }
    }

    /// The initialisation settings.
    pub fn init(&self) -> InitSettings {
        InitSettings {
            node_count: self.node_count,
            node_spacing_diameters: self.node_spacing_diameters,
            min_blob_pixels: self.min_blob_pixels,
            cloud: self.cloud(),
            estimate_radius: self.estimate_radius && self.dlo_radius > 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_papers_and_valid() {
        let p = Params::default();
        assert_eq!(p.node_count, 24);
        assert_eq!(
            (
                p.upetrack.displacement_decay,
                p.upetrack.curvature_retention,
                p.upetrack.bending_resistance,
                p.upetrack.displacement_weight
            ),
            (0.8, 0.6, 0.8, 0.75)
        );
        assert_eq!((p.visibility_radius, p.visibility_min_points), (0.020, 3));
        assert!(p.validate().is_ok());
    }

    #[test]
    fn the_paper_preset_is_the_papers_rules_and_presets_are_found_by_name() {
        let p = Params::paper();
        assert_eq!(p.visibility_min_fraction, 0.0);
        assert_eq!(
            p.upetrack.end_displacement_weight,
            p.upetrack.displacement_weight
        );
        assert_eq!(
            p.upetrack.hidden_motion,
            crate::upe::occlusion::HiddenMotion::Paper
        );
        assert!(!p.upetrack.free_space && !p.upetrack.conserve_length);
        assert!(!p.upetrack.across_rope_displacement && !p.upetrack.smooth_resampling);
        assert!(!p.upetrack.hidden_nodes_absorb && !p.upetrack.extend_short_ends);
        assert!(!p.upetrack.extend_under_occluders && !p.upetrack.keep_end_run_spacing);
        // Everything else is the defaults'.
        let d = Params::default();
        assert_eq!(
            (p.node_count, p.visibility_radius, p.voxel_size),
            (d.node_count, d.visibility_radius, d.voxel_size)
        );
        assert_eq!(
            p.upetrack.displacement_weight,
            d.upetrack.displacement_weight
        );
        assert!(p.validate().is_ok());
        assert_eq!(Params::preset("paper"), Some(p));
        assert_eq!(Params::preset("default"), Some(d));
        assert_eq!(Params::preset("papers"), None);
        let t = Params::preset("trackdlo-upstream").expect("preset");
        assert_eq!(
            (t.algorithm, t.voxel_size, t.downsampling, t.dlo_radius),
            (Algorithm::Trackdlo, 0.005, Downsampling::VoxelGrid, 0.0)
        );
        assert_eq!(t.trackdlo, TrackDloParams::EVALUATION);
        // Said in the preset itself, not only implied by the zero radius.
        assert!(!t.estimate_radius);
        assert!(t.validate().is_ok());
    }

    #[test]
    fn the_radius_is_estimated_unless_turned_off_or_the_push_is_off() {
        assert!(Params::default().init().estimate_radius);
        let off = Params {
            estimate_radius: false,
            ..Params::default()
        };
        assert!(!off.init().estimate_radius);
        let no_push = Params {
            dlo_radius: 0.0,
            ..Params::default()
        };
        assert!(!no_push.init().estimate_radius);
        assert_eq!(no_push.init().cloud.axis_offset, 0.0);
    }

    #[test]
    fn boundary_values_are_accepted_and_the_cloud_follows_the_radius() {
        let p = Params {
            visibility_radius: 1.0,
            max_depth: 100.0,
            min_depth: 0.0,
            voxel_size: 0.0,
            reinit_visible_fraction: 1.0,
            ..Params::default()
        };
        assert_eq!(p.validate(), Ok(()));
        let c = Params::default().cloud();
        assert!((c.axis_offset - 0.0075 * core::f64::consts::FRAC_PI_4).abs() < 1e-15);
        assert_eq!((c.min_depth, c.max_depth, c.voxel_size), (0.1, 3.0, 0.008));
        // Each algorithm's own downsampling unless one is chosen.
        assert_eq!(c.downsampling, Downsampling::RayColumns);
        for algorithm in [Algorithm::Cpd, Algorithm::Trackdlo] {
            let b = Params {
                algorithm,
                ..Params::default()
            };
            assert_eq!(b.cloud().downsampling, Downsampling::VoxelGrid);
            let chosen = Params {
                downsampling: Downsampling::RayColumns,
                ..b
            };
            assert_eq!(chosen.cloud().downsampling, Downsampling::RayColumns);
        }
    }

    #[test]
    fn invalid_values_are_rejected_by_name() {
        type Case = (&'static str, fn(&mut Params));
        let cases: [Case; 27] = [
            ("reinit_visible_fraction", |p| {
                p.reinit_visible_fraction = -5.0
            }),
            ("reinit_visible_fraction", |p| {
                p.reinit_visible_fraction = 1e300
            }),
            ("visibility_radius", |p| p.visibility_radius = 0.0),
            ("visibility_radius", |p| p.visibility_radius = 2.0),
            ("max_depth", |p| p.max_depth = 0.0),
            ("max_depth", |p| p.max_depth = 200.0),
            ("min_depth", |p| p.min_depth = -0.1),
            ("min_depth", |p| p.min_depth = p.max_depth),
            ("em_tolerance", |p| p.upetrack.em_tolerance = 0.0),
            ("em_tolerance", |p| p.upetrack.em_tolerance = 2.0),
            ("min_variance", |p| p.upetrack.min_variance = 0.0),
            ("min_variance", |p| p.upetrack.min_variance = 2.0),
            ("voxel_size", |p| p.voxel_size = 0.2),
            ("dlo_radius", |p| p.dlo_radius = -0.001),
            ("cpd.beta", |p| p.cpd.beta = 0.0),
            ("trackdlo.mu", |p| p.trackdlo.mu = 1.0),
            ("trackdlo.alpha", |p| p.trackdlo.alpha = -1.0),
            ("trackdlo.max_iterations", |p| p.trackdlo.max_iterations = 0),
            ("visibility_min_fraction", |p| {
                p.visibility_min_fraction = 1.5
            }),
            ("node_count", |p| p.node_count = 3),
            ("node_count", |p| p.node_count = 5_000_000),
            ("displacement_decay", |p| {
                p.upetrack.displacement_decay = f64::NAN
            }),
            ("bending_resistance", |p| {
                p.upetrack.bending_resistance = -0.1
            }),
            ("visibility_radius", |p| p.visibility_radius = f64::INFINITY),
            ("outlier_weight", |p| p.upetrack.outlier_weight = 1.0),
            ("visibility_min_points", |p| p.visibility_min_points = 0),
            ("max_depth", |p| p.max_depth = f64::NAN),
        ];
        for (name, set) in cases {
            let mut p = Params::default();
            set(&mut p);
            match p.validate() {
                Err(ParamsError::OutOfRange { name: n, .. }) => assert_eq!(n, name),
                other => panic!("{name}: {other:?}"),
            }
        }
    }
}
