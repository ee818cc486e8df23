//! Several ropes in one sequence: `dlo.json`'s `ropes`, each rope's colour
//! range, prior and ground truth, with what it does not say taken from
//! the top-level keys.

use serde::{Deserialize, Serialize};
use upetrack::math::Vec3;
use upetrack::perception::initialisation::RopePrior;
use upetrack::several::MAX_ROPES;
use upetrack::HsvRange;

use crate::error::SequenceError;
use crate::source::is_inside_name;

/// HSV thresholds in `dlo.json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SegmentationConfig {
    /// `[h, s, v]` lower bounds.
    pub hsv_lower: [u8; 3],
    /// `[h, s, v]` upper bounds.
    pub hsv_upper: [u8; 3],
    /// Colour noise allowed for when the saturation is tested, in 8-bit
    /// levels of chroma (`max - min` of a pixel's R, G, B); absent: 0,
    /// OpenCV's `inRange` exactly ([`HsvRange::chroma_noise`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub chroma_noise: Option<u8>,
}

impl SegmentationConfig {
    /// The `dlo.json` form of a range (`chroma_noise` left out when 0).
    pub fn of(range: &HsvRange) -> Self {
        Self {
            hsv_lower: range.lower,
            hsv_upper: range.upper,
            chroma_noise: (range.chroma_noise > 0).then_some(range.chroma_noise),
        }
    }

    /// The range it describes.
    pub fn range(&self) -> HsvRange {
        HsvRange {
            lower: self.hsv_lower,
            upper: self.hsv_upper,
            chroma_noise: self.chroma_noise.unwrap_or(0),
        }
    }
}

/// What the user knows of the rope, in `dlo.json`'s `rope` (both optional).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Default)]
pub struct RopeConfig {
    /// Length, metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length_m: Option<f64>,
    /// Diameter, metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diameter_m: Option<f64>,
}

impl RopeConfig {
    /// The core's prior.
    pub fn prior(&self) -> RopePrior {
        RopePrior {
            length: self.length_m,
            diameter: self.diameter_m,
        }
    }
}

/// One rope's ground truth as read: per frame index its points (when
/// given) and whether part of it is hidden.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct Truth {
    pub(crate) points: Vec<Option<Vec<Vec3>>>,
    pub(crate) occluded: Vec<bool>,
}

impl Truth {
    /// No ground truth for `frames` frames.
    pub(crate) fn none(frames: usize) -> Self {
        Self {
            points: vec![None; frames],
            occluded: vec![false; frames],
        }
    }
}

/// Longest rope name, bytes.
pub const MAX_ROPE_NAME_BYTES: usize = 64;

/// One rope of `dlo.json`'s `ropes`; every key optional.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, Default)]
pub struct RopeEntry {
    /// A name for it (default `rope-<k>`, counting from 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Its colour range (default: the top-level `segmentation`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub segmentation: Option<SegmentationConfig>,
    /// What the user knows of it (default: the top-level `rope`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rope: Option<RopeConfig>,
    /// Its ground-truth file (default: the top-level `groundtruth` for
    /// the first rope, none for the others).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub groundtruth: Option<String>,
    /// A pixel `[u, v]` on this rope in the first frame: the candidate
    /// through it is this rope (as a click on the page). Ropes of one
    /// colour are otherwise taken longest first, in this list's order.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hint: Option<[f64; 2]>,
}

/// One rope of an opened sequence.
#[derive(Debug, Clone, PartialEq)]
pub struct SequenceRope {
    /// Its name.
    pub name: String,
    /// The colour range in force.
    pub hsv: HsvRange,
    /// What is known of it.
    pub prior: RopePrior,
    /// Its ground truth per frame index, when available.
    pub groundtruth: Vec<Option<Vec<Vec3>>>,
    /// Per frame index: an occluder (or another rope) hides part of it.
    pub groundtruth_occluded: Vec<bool>,
    /// A pixel on it in the first frame, for its first initialisation.
    pub hint: Option<[f64; 2]>,
}

impl SequenceRope {
    /// The first frame its ground truth marks part of it hidden.
    pub fn first_occluded_frame(&self) -> Option<usize> {
        self.groundtruth_occluded.iter().position(|&o| o)
    }
}

/// Checks `config.ropes` (`path` names `dlo.json` in errors).
pub(crate) fn check_ropes(ropes: &[RopeEntry], path: &str) -> Result<(), SequenceError> {
    if ropes.len() > MAX_ROPES {
        return Err(SequenceError::too_large(
            path,
            "number of ropes",
            ropes.len() as u64,
            MAX_ROPES as u64,
        ));
    }
    for (k, rope) in ropes.iter().enumerate() {
        let invalid = |what: String| SequenceError::invalid(path, format!("ropes[{k}]: {what}"));
        if let Some(s) = &rope.segmentation {
            s.range()
                .validate()
                .map_err(|e| invalid(format!("segmentation: {e}")))?;
        }
        if let Some(r) = &rope.rope {
            r.prior()
                .validate()
                .map_err(|e| invalid(format!("rope: {e}")))?;
        }
        if let Some(gt) = &rope.groundtruth {
            if !is_inside_name(gt) {
                return Err(invalid(format!(
                    "groundtruth {gt:?} must name a file inside the sequence folder"
                )));
            }
        }
        if let Some(h) = rope.hint {
            if !h.iter().all(|c| c.is_finite()) {
                return Err(invalid(format!("hint {h:?} is not a pixel")));
            }
        }
        if let Some(name) = &rope.name {
            if name.is_empty() || name.len() > MAX_ROPE_NAME_BYTES {
                return Err(invalid(format!(
                    "a name of 1 to {MAX_ROPE_NAME_BYTES} bytes, not {}",
                    name.len()
                )));
            }
        }
    }
    let names: Vec<String> = (0..ropes.len()).map(|k| rope_name(ropes, k)).collect();
    if let Some(k) = (1..names.len()).find(|&k| names[..k].contains(&names[k])) {
        return Err(SequenceError::invalid(
            path,
            format!(
                "ropes[{k}]: the name {:?} is taken by an earlier rope",
                names[k]
            ),
        ));
    }
    Ok(())
}

/// Rope `k`'s name among `ropes`.
fn rope_name(ropes: &[RopeEntry], k: usize) -> String {
    ropes
        .get(k)
        .and_then(|r| r.name.clone())
        .unwrap_or_else(|| format!("rope-{k}"))
}

/// The ropes of a sequence of `frames` frames: `ropes` (`dlo.json`'s), or
/// the one rope of its top-level keys (`top`: the top-level colour range
/// in force and `rope`). `read` reads a ground-truth file a rope names;
/// `known(k)` may give rope `k`'s ground truth already read (the first
/// rope's, when it is the top-level file).
pub(crate) fn sequence_ropes(
    ropes: &[RopeEntry],
    (hsv, top_rope): (HsvRange, Option<RopeConfig>),
    frames: usize,
    read: &dyn Fn(&str) -> Result<Truth, SequenceError>,
    known: impl Fn(usize) -> Option<Truth>,
) -> Result<Vec<SequenceRope>, SequenceError> {
    let shared_prior = top_rope.map(|r| r.prior()).unwrap_or_default();
    if ropes.is_empty() {
        let truth = known(0).unwrap_or_else(|| Truth::none(frames));
        return Ok(vec![SequenceRope {
            name: rope_name(ropes, 0),
            hsv,
            prior: shared_prior,
            groundtruth: truth.points,
            groundtruth_occluded: truth.occluded,
            hint: None,
        }]);
    }
    ropes
        .iter()
        .enumerate()
        .map(|(k, rope)| {
            let truth = match (&rope.groundtruth, known(k)) {
                (Some(name), _) => read(name)?,
                (None, Some(read)) => read,
                (None, None) => Truth::none(frames),
            };
            Ok(SequenceRope {
                name: rope_name(ropes, k),
                hsv: rope
                    .segmentation
                    .as_ref()
                    .map_or(hsv, SegmentationConfig::range),
                prior: rope.rope.map_or(shared_prior, |r| r.prior()),
                groundtruth: truth.points,
                groundtruth_occluded: truth.occluded,
                hint: rope.hint,
            })
        })
        .collect()
}
