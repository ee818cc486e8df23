//! What the page's parameter panel shows of every parameter of every
//! algorithm: its path in a parameter file (`cpd.beta`), the paper's symbol,
//! a one-line meaning, the range offered and the unit it is shown in. The
//! core's `Params::validate` stays the judge of a value; a test checks that
//! this list covers every field and offers only values the core accepts.

use serde::Serialize;

/// Which section of the panel a parameter belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ParamGroup {
    /// The pipeline every algorithm shares (segmentation, cloud, visibility, loss).
    Shared,
    /// UPETrack's registration and occlusion estimate.
    Upetrack,
    /// The CPD baseline.
    Cpd,
    /// The TrackDLO baseline.
    Trackdlo,
    /// The CDCPD2 baseline.
    Cdcpd2,
}

/// What kind of value, and the range the panel offers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ParamKind {
    /// A real number from `min` to `max` in steps of `step` (in the shown unit).
    Number {
        /// Smallest value offered, shown unit.
        min: f64,
        /// Largest value offered, shown unit.
        max: f64,
        /// Step of the input, shown unit.
        step: f64,
    },
    /// A whole number from `min` to `max`.
    Integer {
        /// Smallest value offered.
        min: f64,
        /// Largest value offered.
        max: f64,
    },
    /// On or off.
    Bool,
    /// One of the names.
    Choice {
        /// The names accepted, as in a parameter file.
        choices: &'static [&'static str],
    },
}

/// One parameter as the panel shows it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ParamInfo {
    /// Its path in a parameter file: a top-level name, or `section.name`.
    pub path: &'static str,
    /// Its section of the panel.
    pub group: ParamGroup,
    /// The paper's symbol (`_x` marks a subscript), or a short name.
    pub symbol: &'static str,
    /// What it does, in one line.
    pub meaning: &'static str,
    /// Kind and range, in the shown unit.
    #[serde(flatten)]
    pub kind: ParamKind,
    /// The unit shown (`mm` for lengths kept in metres, `mm²`...), or empty.
    pub unit: &'static str,
    /// Shown value = stored value x `scale` (1000 for metres shown in mm).
    pub scale: f64,
}

impl ParamInfo {
    /// The same parameter kept in metres and shown in millimetres.
    const fn in_mm(self) -> Self {
        self.in_unit("mm", 1000.0)
    }

    /// The same parameter shown in `unit`, `scale` times the stored value.
    const fn in_unit(self, unit: &'static str, scale: f64) -> Self {
        ParamInfo {
            unit,
            scale,
            ..self
        }
    }
}

const fn number(min: f64, max: f64, step: f64) -> ParamKind {
    ParamKind::Number { min, max, step }
}

const fn integer(min: f64, max: f64) -> ParamKind {
    ParamKind::Integer { min, max }
}

const fn p(
    path: &'static str,
    group: ParamGroup,
    symbol: &'static str,
    meaning: &'static str,
    kind: ParamKind,
) -> ParamInfo {
    ParamInfo {
        path,
        group,
        symbol,
        meaning,
        kind,
        unit: "",
        scale: 1.0,
    }
}

use ParamGroup::{Cdcpd2, Cpd, Shared, Trackdlo, Upetrack};

/// Every parameter, in the panel's order (sections in `ParamGroup`'s order).
pub const PARAMETERS: &[ParamInfo] = &[
    p(
        "node_count",
        Shared,
        "M",
        "Number of nodes along the rope (the fewest, when spaced by diameters)",
        integer(4.0, 1000.0),
    ),
    p(
        "node_spacing_diameters",
        Shared,
        "s/d",
        "Nodes this many rope diameters apart, from the rope found first (0: always M)",
        number(0.0, 1000.0, 0.5),
    ),
    p(
        "visibility_radius",
        Shared,
        "r_vis",
        "A node is visible with enough cloud points this close",
        number(1.0, 1000.0, 1.0),
    )
    .in_mm(),
    p(
        "visibility_min_points",
        Shared,
        "V_lim",
        "Cloud points needed within r_vis for a node to be visible",
        integer(1.0, 100_000.0),
    ),
    p(
        "visibility_min_fraction",
        Shared,
        "f_vis",
        "Also needed: this fraction of the visible nodes' median count (0: the paper's rule)",
        number(0.0, 1.0, 0.05),
    ),
    p(
        "voxel_size",
        Shared,
        "leaf",
        "Leaf of the cloud's downsampling (0 keeps every point)",
        number(0.0, 100.0, 0.5),
    )
    .in_mm(),
    p(
        "downsampling",
        Shared,
        "cells",
        "Columns along the viewing rays (each point its pixels' mean depth) or a voxel grid; auto: columns for UPETrack, the grid for the baselines",
        ParamKind::Choice {
            choices: &["auto", "ray_columns", "voxel_grid"],
        },
    ),
    p(
        "dlo_radius",
        Shared,
        "r_DLO",
        "Rope radius: the cloud is pushed pi/4 of it to the centre line (0: off)",
        number(0.0, 100.0, 0.5),
    )
    .in_mm(),
    p(
        "estimate_radius",
        Shared,
        "r est.",
        "Measure the radius from the rope's width and depth at initialisation, and in depth how much of its width the colour range covers (a strip: pushed farther, to the strip's mean surface)",
        ParamKind::Bool,
    ),
    p(
        "follow_camera",
        Shared,
        "cam.",
        "Estimate the camera's own motion from the background and move the tracked rope with it",
        ParamKind::Bool,
    ),
    p(
        "min_depth",
        Shared,
        "z_min",
        "Nearest depth taken as a measurement",
        number(0.0, 99_000.0, 10.0),
    )
    .in_mm(),
    p(
        "max_depth",
        Shared,
        "z_max",
        "Farthest depth taken as a measurement (above z_min)",
        number(200.0, 100_000.0, 10.0),
    )
    .in_mm(),
    p(
        "min_blob_pixels",
        Shared,
        "blob",
        "Smallest mask blob taken as the rope at initialisation",
        integer(0.0, 1_000_000.0),
    ),
    p(
        "reinit_length_fraction",
        Shared,
        "l_re",
        "Re-initialise after a loss only with this fraction of the first length",
        number(0.0, 1.0, 0.05),
    ),
    p(
        "reinit_visible_fraction",
        Shared,
        "v_re",
        "Try to re-initialise when fewer nodes than this fraction are visible (0: off)",
        number(0.0, 1.0, 0.05),
    ),
    p(
        "displacement_decay",
        Upetrack,
        "γ",
        "Distance attenuation of the local displacement term (Eq. 6)",
        number(0.0, 1.0, 0.05),
    ),
    p(
        "curvature_retention",
        Upetrack,
        "a",
        "Historical curvature retention (Eq. 10)",
        number(0.0, 1.0, 0.05),
    ),
    p(
        "bending_resistance",
        Upetrack,
        "b",
        "Bending resistance of the proximal linear constraint (Eq. 8)",
        number(0.0, 2.0, 0.05),
    ),
    p(
        "displacement_weight",
        Upetrack,
        "α",
        "Weight of the displacement estimate against the shape estimate (Eq. 11)",
        number(0.0, 1.0, 0.05),
    ),
    p(
        "end_displacement_weight",
        Upetrack,
        "α_end",
        "α for a hidden run at an end of the rope (this project's addition)",
        number(0.0, 1.0, 0.05),
    ),
    p(
        "hidden_motion",
        Upetrack,
        "motion",
        "How hidden nodes move: end runs slide along the rope, or Eq. 6-7 everywhere",
        ParamKind::Choice {
            choices: &["slide_ends", "paper", "slide"],
        },
    ),
    p(
        "conserve_length",
        Upetrack,
        "length",
        "The rope does not stretch: hidden runs give up what the rope has over its rest length (a hidden end is cut to it, a hidden bend tightens)",
        ParamKind::Bool,
    ),
    p(
        "free_space",
        Upetrack,
        "free space",
        "Move hidden nodes out of places the images show empty",
        ParamKind::Bool,
    ),
    p(
        "across_rope_displacement",
        Upetrack,
        "D_k across",
        "Hidden nodes follow the known nodes' motion across the rope, not their slide along it (Eq. 6)",
        ParamKind::Bool,
    ),
    p(
        "smooth_resampling",
        Upetrack,
        "smooth",
        "Resample along a smooth curve through the nodes, not their polyline (Eq. 12-15)",
        ParamKind::Bool,
    ),
    p(
        "follow_shared_motion",
        Upetrack,
        "shared motion",
        "Hidden nodes move with the rigid motion most visible nodes share (a moving camera, the rope carried whole) before the rules for a resting rope judge the rest",
        ParamKind::Bool,
    ),
    p(
        "anchor_across_only",
        Upetrack,
        "anchors across",
        "A visible node beside a hidden run keeps only EM's move across the rope, not its pull away from the occlusion's edge",
        ParamKind::Bool,
    ),
    p(
        "hidden_nodes_absorb",
        Upetrack,
        "hidden absorb",
        "Hidden nodes explain the points near them in EM without moving (off: the paper's EM)",
        ParamKind::Bool,
    ),
    p(
        "extend_short_ends",
        Upetrack,
        "ends' length",
        "A rope shorter than its length gets it back along its ends, over rope pixels or out of the image",
        ParamKind::Bool,
    ),
    p(
        "extend_under_occluders",
        Upetrack,
        "ends under occluders",
        "The ends' length may also go on under something that hides the rope (depth in front, a rectangle)",
        ParamKind::Bool,
    ),
    p(
        "keep_end_run_spacing",
        Upetrack,
        "hidden ends' spacing",
        "A hidden run at an end keeps the rest spacing when the nodes are resampled (off: the paper's even spacing of the whole rope)",
        ParamKind::Bool,
    ),
    p(
        "follow_emerged_ends",
        Upetrack,
        "emerged ends",
        "A hidden end follows rope in view that came out from under its occluder and no node explains, and a rope found short goes on along such rope past an end (off: the paper's step)",
        ParamKind::Bool,
    ),
    p(
        "hidden_under_crossings",
        Upetrack,
        "crossings hide",
        "A node under another stretch of the rope where it crosses itself is hidden, the stretch on top read from the depth beside the crossing (off: the paper's visibility)",
        ParamKind::Bool,
    ),
    p(
        "report_on_arcs",
        Upetrack,
        "nodes on their bends",
        "Visible nodes are reported on their bend's arc, not at the centroid of the points they explain, which lies inside it (off: the paper's nodes)",
        ParamKind::Bool,
    ),
    p(
        "report_seen_tips",
        Upetrack,
        "ends at their tips",
        "An end node in view is reported where the rope's tip is seen, not where EM leaves it, inside the tip (off: the paper's nodes)",
        ParamKind::Bool,
    ),
    p(
        "rest_speed_m_per_s",
        Upetrack,
        "rest speed",
        "Below this speed of its known neighbours (a move per frame at the sequence's frame rate) a hidden run rests: alpha rises to 1 (Eq. 11); 0 keeps alpha",
        number(0.0, 600.0, 1.0),
    )
    .in_unit("mm/s", 1000.0),
    p(
        "outlier_weight",
        Upetrack,
        "w",
        "Weight of the uniform outlier component of the GMM (Eq. 3)",
        number(0.0, 0.99, 0.01),
    ),
    p(
        "em_tolerance",
        Upetrack,
        "ε",
        "EM stops when no node moves more than this",
        number(0.01, 1000.0, 0.01),
    )
    .in_mm(),
    p(
        "em_max_iterations",
        Upetrack,
        "K",
        "Most EM iterations per frame",
        integer(1.0, 1000.0),
    ),
    p(
        "min_variance",
        Upetrack,
        "σ²_min",
        "Floor of the GMM variance",
        number(0.01, 100.0, 0.01),
    )
    .in_unit("mm²", 1e6),
    p(
        "cpd.beta",
        Cpd,
        "β",
        "Width of the Gaussian coherence kernel, metres",
        number(0.001, 10.0, 0.01),
    ),
    p(
        "cpd.lambda",
        Cpd,
        "λ",
        "Weight of the smoothness regulariser",
        number(0.001, 1e7, 100.0),
    ),
    p(
        "cpd.outlier_weight",
        Cpd,
        "w",
        "Weight of the uniform outlier component",
        number(0.0, 0.99, 0.01),
    ),
    p(
        "cpd.max_iterations",
        Cpd,
        "iterations",
        "Most EM iterations",
        integer(1.0, 10_000.0),
    ),
    p(
        "cpd.tolerance",
        Cpd,
        "tol",
        "Stop when σ² changes by no more than this, m²",
        number(0.0, 1.0, 1e-8),
    ),
    p(
        "trackdlo.beta",
        Trackdlo,
        "β",
        "Width of the kernel on the distance along the rope, metres",
        number(0.001, 10.0, 0.01),
    ),
    p(
        "trackdlo.lambda",
        Trackdlo,
        "λ",
        "Smoothness weight",
        number(0.001, 1e7, 100.0),
    ),
    p(
        "trackdlo.alpha",
        Trackdlo,
        "α",
        "Weight of the correspondence priors",
        number(0.0, 1000.0, 0.5),
    ),
    p(
        "trackdlo.mu",
        Trackdlo,
        "μ",
        "Outlier weight",
        number(0.0, 0.99, 0.01),
    ),
    p(
        "trackdlo.max_iterations",
        Trackdlo,
        "iterations",
        "Most iterations of each CPD-LLE",
        integer(1.0, 1000.0),
    ),
    p(
        "trackdlo.tolerance",
        Trackdlo,
        "tol",
        "Stop when the mean node displacement of an iteration is below this",
        number(0.001, 100.0, 0.01),
    )
    .in_mm(),
    p(
        "trackdlo.k_vis",
        Trackdlo,
        "k_vis",
        "Strength of the visibility weighting, 1/metres",
        number(0.0, 10_000.0, 1.0),
    ),
    p(
        "trackdlo.d_vis",
        Trackdlo,
        "d_vis",
        "Gaps between visible nodes up to this along the rope count as visible",
        number(0.0, 1000.0, 1.0),
    )
    .in_mm(),
    p(
        "trackdlo.visibility_threshold",
        Trackdlo,
        "τ_vis",
        "A node is visible when a point lies this close",
        number(0.1, 1000.0, 0.5),
    )
    .in_mm(),
    p(
        "trackdlo.dlo_pixel_width",
        Trackdlo,
        "w_px",
        "Projected rope width of the self-occlusion test, pixels at 1280 px",
        number(0.0, 1000.0, 1.0),
    ),
    p(
        "trackdlo.beta_pre_proc",
        Trackdlo,
        "β_pre",
        "Kernel width of the pre-registration, metres",
        number(0.001, 100.0, 0.1),
    ),
    p(
        "trackdlo.lambda_pre_proc",
        Trackdlo,
        "λ_pre",
        "Smoothness weight of the pre-registration",
        number(0.001, 1e7, 0.5),
    ),
    p(
        "trackdlo.lle_weight",
        Trackdlo,
        "γ",
        "Weight of the LLE term of the pre-registration",
        number(0.0, 1e6, 1.0),
    ),
    p(
        "cdcpd2.alpha",
        Cdcpd2,
        "α",
        "Smoothness weight of the CPD step",
        number(0.0, 1000.0, 0.1),
    ),
    p(
        "cdcpd2.lambda",
        Cdcpd2,
        "λ",
        "Weight of the LLE term",
        number(0.0, 1000.0, 0.1),
    ),
    p(
        "cdcpd2.beta",
        Cdcpd2,
        "β",
        "Width of the Gaussian kernel on the template, metres",
        number(0.001, 100.0, 0.1),
    ),
    p(
        "cdcpd2.zeta",
        Cdcpd2,
        "ζ",
        "Weight holding the nodes to their prediction (the previous nodes)",
        number(0.0, 10_000.0, 1.0),
    ),
    p(
        "cdcpd2.outlier_weight",
        Cdcpd2,
        "w",
        "Outlier weight",
        number(0.0, 0.99, 0.01),
    ),
    p(
        "cdcpd2.k_vis",
        Cdcpd2,
        "k_vis",
        "Strength of the visibility prior",
        number(0.0, 1e6, 10.0),
    ),
    p(
        "cdcpd2.lle_neighbours",
        Cdcpd2,
        "k",
        "Neighbours of each node in the LLE weights",
        integer(1.0, 64.0),
    ),
    p(
        "cdcpd2.tolerance",
        Cdcpd2,
        "tol",
        "CPD stops when σ² changes by no more than this",
        number(1e-9, 1.0, 1e-5),
    ),
    p(
        "cdcpd2.max_iterations",
        Cdcpd2,
        "iterations",
        "Most CPD iterations",
        integer(1.0, 1000.0),
    ),
    p(
        "cdcpd2.initial_sigma_scale",
        Cdcpd2,
        "σ²_0",
        "Start of σ² as a fraction of the all-pairs mean",
        number(0.001, 10.0, 0.005),
    ),
    p(
        "cdcpd2.stretch_factor",
        Cdcpd2,
        "s",
        "An edge may be at most this times its rest length",
        number(1.0, 10.0, 0.05),
    ),
    p(
        "cdcpd2.table_constraint",
        Cdcpd2,
        "table",
        "Keep the nodes above the table plane fitted to the depth image",
        ParamKind::Bool,
    ),
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params_file::parse_params;
    use upetrack::Params;

    /// Every leaf of a default parameter file, as `path -> value`.
    fn leaves() -> Vec<(String, serde_json::Value)> {
        let v = serde_json::to_value(Params::default()).expect("params as JSON");
        let mut out = Vec::new();
        for (k, v) in v.as_object().expect("object") {
            match v.as_object() {
                Some(section) => {
                    for (k2, v2) in section {
                        out.push((format!("{k}.{k2}"), v2.clone()));
                    }
                }
                None if k != "algorithm" => out.push((k.clone(), v.clone())),
                None => {}
            }
        }
        out
    }

    /// A one-parameter file setting `path` to `value`.
    fn file_with(path: &str, value: serde_json::Value) -> String {
        match path.split_once('.') {
            Some((section, name)) => serde_json::json!({ section: { name: value } }).to_string(),
            None => serde_json::json!({ path: value }).to_string(),
        }
    }

    #[test]
    fn the_panel_lists_every_parameter_once_and_nothing_else() {
        let mut listed: Vec<&str> = PARAMETERS.iter().map(|p| p.path).collect();
        listed.sort_unstable();
        let before = listed.len();
        listed.dedup();
        assert_eq!(listed.len(), before, "a parameter is listed twice");
        let mut fields: Vec<String> = leaves().into_iter().map(|(k, _)| k).collect();
        fields.sort_unstable();
        assert_eq!(
            listed,
            fields.iter().map(String::as_str).collect::<Vec<_>>()
        );
    }

    /// The panel never offers a value the core refuses: both ends of every
    /// range and every choice pass validation, and each default lies inside.
    #[test]
    fn every_offered_value_is_accepted_and_defaults_lie_in_range() {
        let defaults: std::collections::HashMap<String, serde_json::Value> =
            leaves().into_iter().collect();
        for info in PARAMETERS {
            let default = &defaults[info.path];
            let offered: Vec<serde_json::Value> = match info.kind {
                ParamKind::Number { min, max, step } => {
                    assert!(step > 0.0 && min < max, "{}", info.path);
                    let shown = default.as_f64().expect("number") * info.scale;
                    assert!(
                        shown >= min - 1e-9 && shown <= max + 1e-9,
                        "{}: default {shown} outside {min}..{max}",
                        info.path
                    );
                    vec![(min / info.scale).into(), (max / info.scale).into()]
                }
                ParamKind::Integer { min, max } => {
                    let d = default.as_f64().expect("integer");
                    assert!(d >= min && d <= max, "{}: default {d}", info.path);
                    vec![(min as u64).into(), (max as u64).into()]
                }
                ParamKind::Bool => vec![true.into(), false.into()],
                ParamKind::Choice { choices } => {
                    assert!(
                        choices.contains(&default.as_str().expect("name")),
                        "{}",
                        info.path
                    );
                    choices.iter().map(|&c| c.into()).collect()
                }
            };
            for value in offered {
                // min_depth must stay below max_depth: try it with max_depth's largest.
                let text = file_with(info.path, value.clone());
                let text = if info.path == "min_depth" {
                    text.replace('}', r#", "max_depth": 100.0}"#)
                } else {
                    text
                };
                parse_params(&text, "panel").unwrap_or_else(|e| {
                    panic!("{} = {value} is offered but refused: {e}", info.path)
                });
            }
        }
    }
}
