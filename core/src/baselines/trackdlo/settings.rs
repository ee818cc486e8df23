//! TrackDLO's parameters, with the values of its published evaluation.

use crate::validation::{below_one, check, non_negative, positive, ParamsError};

/// Most iterations accepted for each of TrackDLO's registrations.
pub const MAX_TRACKDLO_ITERATIONS: u32 = 1000;

/// Image width (pixels) at which [`TrackDloParams::dlo_pixel_width`] is given:
/// the 1280 x 720 stream of TrackDLO's evaluation.
pub const REFERENCE_IMAGE_WIDTH: f64 = 1280.0;

/// TrackDLO's parameters, with the values of its published evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct TrackDloParams {
    /// Width of the kernel on the distance along the rope (`beta`), metres. 0.35.
    pub beta: f64,
    /// Smoothness weight (`lambda`). 50000.
    pub lambda: f64,
    /// Weight of the correspondence priors (`alpha`). 3.
    pub alpha: f64,
    /// Outlier weight (`mu`). 0.1.
    pub mu: f64,
    /// Most iterations of each CPD-LLE. 50.
    pub max_iterations: u32,
    /// Stop when the mean node displacement of an iteration is below this, metres. 0.0002.
    pub tolerance: f64,
    /// Strength of the visibility weighting (`k_vis`), 1/metres. 50.
    pub k_vis: f64,
    /// Gaps between visible nodes up to this distance along the rope are
    /// taken as visible (`d_vis`), metres. 0.06.
    pub d_vis: f64,
    /// A node is visible when a point lies within this (`tau_vis`), metres. 0.008.
    pub visibility_threshold: f64,
    /// Projected rope width of the self-occlusion test (`w`), pixels at
    /// 1280 px image width, scaled to the camera's width. 40.
    pub dlo_pixel_width: f64,
    /// Kernel width of the pre-registration, metres. 3.
    pub beta_pre_proc: f64,
    /// Smoothness weight of the pre-registration. 1.
    pub lambda_pre_proc: f64,
    /// Weight of the LLE term of the pre-registration (`gamma`). 10.
    pub lle_weight: f64,
}

impl Default for TrackDloParams {
    /// TrackDLO's published demo values (`trackdlo.launch`), the set made
    /// for an 8 mm voxel leaf, this project's voxel size (see
    /// `docs/algorithm-notes.md` for the evaluation set on this pipeline).
    fn default() -> Self {
        Self::DEMO
    }
}

impl TrackDloParams {
    /// The values of upstream's evaluation launch file
    /// (`trackdlo_eval.launch`, RMDLO/trackdlo c05921e), made for a 5 mm
    /// voxel leaf; the goldens of `tests/data/trackdlo-upstream` use them.
    pub const EVALUATION: Self = Self {
        beta: 0.5,
        lambda: 50_000.0,
        alpha: 3.0,
        mu: 0.1,
        max_iterations: 50,
        tolerance: 0.0002,
        k_vis: 500.0,
        d_vis: 0.06,
        visibility_threshold: 0.005,
        dlo_pixel_width: 30.0,
        beta_pre_proc: 3.0,
        lambda_pre_proc: 1.0,
        lle_weight: 10.0,
    };

    /// The values of upstream's demo launch file (`trackdlo.launch`, leaf
    /// 8 mm): the defaults.
    pub const DEMO: Self = Self {
        beta: 0.35,
        k_vis: 50.0,
        visibility_threshold: 0.008,
        dlo_pixel_width: 40.0,
        ..Self::EVALUATION
    };
}

impl TrackDloParams {
    /// Checks every field (named `trackdlo.<field>` in errors).
    pub fn validate(&self) -> Result<(), ParamsError> {
        let t = self;
        positive("trackdlo.beta", t.beta)?;
        positive("trackdlo.lambda", t.lambda)?;
        positive("trackdlo.beta_pre_proc", t.beta_pre_proc)?;
        positive("trackdlo.lambda_pre_proc", t.lambda_pre_proc)?;
        positive("trackdlo.tolerance", t.tolerance)?;
        positive("trackdlo.visibility_threshold", t.visibility_threshold)?;
        non_negative("trackdlo.alpha", t.alpha)?;
        non_negative("trackdlo.k_vis", t.k_vis)?;
        non_negative("trackdlo.d_vis", t.d_vis)?;
        non_negative("trackdlo.lle_weight", t.lle_weight)?;
        non_negative("trackdlo.dlo_pixel_width", t.dlo_pixel_width)?;
        below_one("trackdlo.mu", t.mu)?;
        let it = t.max_iterations;
        check(
            "trackdlo.max_iterations",
            it as f64,
            (1..=MAX_TRACKDLO_ITERATIONS).contains(&it),
            "an integer in 1..=1000",
        )
    }
}
