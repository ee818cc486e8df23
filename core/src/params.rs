//! Every tunable number of the tracker in one plain struct, with the paper's
//! defaults. Invalid values are rejected with [`ParamsError`], never clamped.

use crate::cpd::CpdSettings;
use crate::occlusion::UpeCoefficients;
use crate::point_cloud::{CloudSettings, SURFACE_TO_AXIS_RATIO};
use crate::registration::EmSettings;
use crate::step::Algorithm;
use crate::trackdlo::TrackDloParams;

/// Fewest nodes accepted: UPE needs three known nodes and one to estimate.
pub const MIN_NODES: usize = 4;
/// Most nodes accepted; every per-frame cost grows with it.
pub const MAX_NODES: usize = 1000;
/// Most EM iterations accepted per frame.
pub const MAX_EM_ITERATIONS: u32 = 1000;

/// A rejected parameter.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamsError {
    /// A parameter is outside its documented range (or not finite).
    #[error("parameter `{name}` = {value} is invalid: it must be {expected}")]
    OutOfRange {
        /// Field name.
        name: &'static str,
        /// The rejected value.
        value: f64,
        /// The accepted range, in words.
        expected: &'static str,
    },
}

/// The tracker's parameters. Lengths are in metres.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct Params {
    /// Number of nodes along the rope (`M`). Paper: 24.
    pub node_count: usize,
    /// Distance attenuation factor of the local displacement term (`gamma`, Eq. 6). Paper: 0.8.
    pub displacement_decay: f64,
    /// Historical curvature retention (`a`, Eq. 10). Paper: 0.6.
    pub curvature_retention: f64,
    /// Bending resistance of the proximal linear constraint (`b`, Eq. 8). Paper: 0.8.
    pub bending_resistance: f64,
    /// Weight of the displacement estimate (`alpha`, Eq. 11). Paper: 0.75.
    pub displacement_weight: f64,
    /// `alpha` for a hidden run of two or more nodes that includes an end of
    /// the rope (`occlusion::MIN_END_RUN`). Default 1
    /// (the displacement term alone: a hidden tip moves with its visible
    /// neighbours and keeps its shape); `displacement_weight` gives the
    /// paper's rule. See `docs/algorithm-notes.md`.
    pub end_displacement_weight: f64,
    /// Visibility radius (`r_vis`), metres. Paper: 20 mm.
    pub visibility_radius: f64,
    /// Points needed within `r_vis` for a node to be visible (`V_lim`). Paper: 3.
    pub visibility_min_points: u32,
    /// A node is visible only if it also has at least this fraction of the
    /// median neighbour count of the visible nodes, so that a node at the
    /// edge of an occlusion counts as hidden (0: the paper's rule alone).
    /// Default 0.5; see `docs/algorithm-notes.md`.
    pub visibility_min_fraction: f64,
    /// Weight of the uniform outlier component (`w`, Eq. 3). Default 0.1.
    pub outlier_weight: f64,
    /// EM stops when no node moves more than this in an iteration, metres. Default 0.1 mm.
    pub em_tolerance: f64,
    /// Most EM iterations per frame. Default 10 (30 costs three times as much and was no more accurate on the synthetic scenarios).
    pub em_max_iterations: u32,
    /// Floor of the GMM variance (`sigma^2`), square metres. Default (1 mm)^2.
    pub min_variance: f64,
    /// Voxel-grid leaf size for downsampling the cloud, metres (0 keeps all points). Default 8 mm.
    pub voxel_size: f64,
    /// Radius of the rope, metres: the cloud (its visible surface) is moved
    /// `pi/4` of it away from the camera to lie on the centre line. 0 turns
    /// the correction off. Default 7.5 mm (the paper's 15 mm thick rope).
    pub dlo_radius: f64,
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
    /// The per-frame tracking step. Default UPETrack; CPD and TrackDLO are
    /// the baselines, sharing everything else.
    pub algorithm: Algorithm,
    /// CPD's settings (used when `algorithm` is CPD).
    pub cpd: CpdSettings,
    /// TrackDLO's parameters (used when `algorithm` is TrackDLO).
    pub trackdlo: TrackDloParams,
}

impl Default for Params {
    /// The paper's values (M = 24, gamma = 0.8, a = 0.6, b = 0.8,
    /// alpha = 0.75, r_vis = 20 mm, V_lim = 3) and this project's choices for
    /// what the paper leaves open (see `docs/algorithm-notes.md`).
    fn default() -> Self {
        Self {
            node_count: 24,
            displacement_decay: 0.8,
            curvature_retention: 0.6,
            bending_resistance: 0.8,
            displacement_weight: 0.75,
            end_displacement_weight: 1.0,
            visibility_radius: 0.020,
            visibility_min_points: 3,
            visibility_min_fraction: 0.5,
            outlier_weight: 0.1,
            em_tolerance: 1e-4,
            em_max_iterations: 10,
            min_variance: 1e-6,
            voxel_size: 0.008,
            dlo_radius: 0.0075,
            min_depth: 0.1,
            max_depth: 3.0,
            min_blob_pixels: 150,
            reinit_length_fraction: 0.8,
            reinit_visible_fraction: 0.5,
            algorithm: Algorithm::Upetrack,
            cpd: CpdSettings::default(),
            trackdlo: TrackDloParams::default(),
        }
    }
}

/// `Ok` when `ok` holds and `value` is finite, else the error naming `name`.
pub(crate) fn check(
    name: &'static str,
    value: f64,
    ok: bool,
    expected: &'static str,
) -> Result<(), ParamsError> {
    if ok && value.is_finite() {
        Ok(())
    } else {
        Err(ParamsError::OutOfRange {
            name,
            value,
            expected,
        })
    }
}

impl Params {
    /// Checks every field against its documented range.
    pub fn validate(&self) -> Result<(), ParamsError> {
        let m = self.node_count;
        check(
            "node_count",
            m as f64,
            (MIN_NODES..=MAX_NODES).contains(&m),
            "an integer in 4..=1000",
        )?;
        let unit = |name, v: f64| check(name, v, (0.0..=1.0).contains(&v), "in [0, 1]");
        unit("displacement_decay", self.displacement_decay)?;
        unit("curvature_retention", self.curvature_retention)?;
        unit("displacement_weight", self.displacement_weight)?;
        unit("end_displacement_weight", self.end_displacement_weight)?;
        let b = self.bending_resistance;
        check(
            "bending_resistance",
            b,
            (0.0..=2.0).contains(&b),
            "in [0, 2]",
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
        check(
            "visibility_min_fraction",
            vf,
            (0.0..=1.0).contains(&vf),
            "in [0, 1]",
        )?;
        let w = self.outlier_weight;
        check("outlier_weight", w, (0.0..1.0).contains(&w), "in [0, 1)")?;
        let t = self.em_tolerance;
        check("em_tolerance", t, t > 0.0 && t <= 1.0, "in (0, 1] metres")?;
        let it = self.em_max_iterations;
        check(
            "em_max_iterations",
            it as f64,
            (1..=MAX_EM_ITERATIONS).contains(&it),
            "an integer in 1..=1000",
        )?;
        let s = self.min_variance;
        check(
            "min_variance",
            s,
            s > 0.0 && s <= 1.0,
            "in (0, 1] square metres",
        )?;
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
        check(
            "reinit_length_fraction",
            f,
            (0.0..=1.0).contains(&f),
            "in [0, 1]",
        )?;
        self.cpd.validate()?;
        self.trackdlo.validate()
    }

    /// The UPE coefficients.
    pub fn upe(&self) -> UpeCoefficients {
        UpeCoefficients {
            displacement_decay: self.displacement_decay,
            curvature_retention: self.curvature_retention,
            bending_resistance: self.bending_resistance,
            displacement_weight: self.displacement_weight,
            end_displacement_weight: self.end_displacement_weight,
        }
    }

    /// The EM settings.
    pub fn em(&self) -> EmSettings {
        EmSettings {
            outlier_weight: self.outlier_weight,
            tolerance: self.em_tolerance,
            max_iterations: self.em_max_iterations,
            min_variance: self.min_variance,
        }
    }

    /// The point cloud settings.
    pub fn cloud(&self) -> CloudSettings {
        CloudSettings {
            min_depth: self.min_depth,
            max_depth: self.max_depth,
            voxel_size: self.voxel_size,
            axis_offset: self.dlo_radius * SURFACE_TO_AXIS_RATIO,
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
                p.displacement_decay,
                p.curvature_retention,
                p.bending_resistance,
                p.displacement_weight
            ),
            (0.8, 0.6, 0.8, 0.75)
        );
        assert_eq!((p.visibility_radius, p.visibility_min_points), (0.020, 3));
        assert!(p.validate().is_ok());
    }

    #[test]
    fn invalid_values_are_rejected_by_name() {
        type Case = (&'static str, fn(&mut Params));
        let cases: [Case; 12] = [
            ("cpd.beta", |p| p.cpd.beta = 0.0),
            ("trackdlo.mu", |p| p.trackdlo.mu = 1.0),
            ("trackdlo.max_iterations", |p| p.trackdlo.max_iterations = 0),
            ("visibility_min_fraction", |p| {
                p.visibility_min_fraction = 1.5
            }),
            ("node_count", |p| p.node_count = 3),
            ("node_count", |p| p.node_count = 5_000_000),
            ("displacement_decay", |p| p.displacement_decay = f64::NAN),
            ("bending_resistance", |p| p.bending_resistance = -0.1),
            ("visibility_radius", |p| p.visibility_radius = f64::INFINITY),
            ("outlier_weight", |p| p.outlier_weight = 1.0),
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
