//! Several ropes in one sequence: `dlo.json`'s `ropes`, each rope's colour
//! range, prior and ground truth, with what it does not say taken from
//! the top-level keys.

use serde::{Deserialize, Serialize};
use upetrack::math::Vec3;
use upetrack::perception::initialisation::RopePrior;
use upetrack::tracker::MAX_ROPES;
use upetrack::HsvRange;

use crate::error::SequenceError;
use crate::sequence::{read_groundtruth, DloConfig, RopeConfig, SegmentationConfig, Truth};
use crate::source::{is_inside_name, Source};

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
}

impl SequenceRope {
    /// The first frame its ground truth marks part of it hidden.
    pub fn first_occluded_frame(&self) -> Option<usize> {
        self.groundtruth_occluded.iter().position(|&o| o)
    }
}

/// Checks `config.ropes` (`path` names `dlo.json` in errors).
pub(crate) fn check_ropes(config: &DloConfig, path: &str) -> Result<(), SequenceError> {
    if config.ropes.len() > MAX_ROPES {
        return Err(SequenceError::too_large(
            path,
            "number of ropes",
            config.ropes.len() as u64,
            MAX_ROPES as u64,
        ));
    }
    for (k, rope) in config.ropes.iter().enumerate() {
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
        if let Some(name) = &rope.name {
            if name.is_empty() || name.len() > MAX_ROPE_NAME_BYTES {
                return Err(invalid(format!(
                    "a name of 1 to {MAX_ROPE_NAME_BYTES} bytes, not {}",
                    name.len()
                )));
            }
        }
    }
    let names: Vec<String> = (0..config.ropes.len())
        .map(|k| rope_name(config, k))
        .collect();
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

/// Rope `k`'s name in `config`.
fn rope_name(config: &DloConfig, k: usize) -> String {
    config
        .ropes
        .get(k)
        .and_then(|r| r.name.clone())
        .unwrap_or_else(|| format!("rope-{k}"))
}

/// The ropes of a sequence of `frames` frames: `config.ropes`, or the one
/// rope of its top-level keys (`hsv` the top-level range in force).
/// `known(k)` may give rope `k`'s ground truth already read (the first
/// rope's, when it is the top-level file).
pub(crate) fn sequence_ropes<S: Source>(
    source: &S,
    config: &DloConfig,
    hsv: HsvRange,
    frames: usize,
    known: impl Fn(usize) -> Option<Truth>,
) -> Result<Vec<SequenceRope>, SequenceError> {
    let shared_prior = config.rope.map(|r| r.prior()).unwrap_or_default();
    if config.ropes.is_empty() {
        let truth = known(0).unwrap_or_else(|| Truth::none(frames));
        return Ok(vec![SequenceRope {
            name: rope_name(config, 0),
            hsv,
            prior: shared_prior,
            groundtruth: truth.points,
            groundtruth_occluded: truth.occluded,
        }]);
    }
    config
        .ropes
        .iter()
        .enumerate()
        .map(|(k, rope)| {
            let truth = match (&rope.groundtruth, known(k)) {
                (Some(name), _) => read_groundtruth(source, name, true, frames)?,
                (None, Some(read)) => read,
                (None, None) => Truth::none(frames),
            };
            Ok(SequenceRope {
                name: rope_name(config, k),
                hsv: rope
                    .segmentation
                    .as_ref()
                    .map_or(hsv, SegmentationConfig::range),
                prior: rope.rope.map_or(shared_prior, |r| r.prior()),
                groundtruth: truth.points,
                groundtruth_occluded: truth.occluded,
            })
        })
        .collect()
}
