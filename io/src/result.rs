//! The result JSON of the contract: the algorithm, every parameter in force,
//! and one entry per frame.

use serde::{Deserialize, Serialize};
use upetrack::perception::initialisation::InitReport;
use upetrack::tracker::{Contradiction, FoundAgain, Judgement};
use upetrack::Params;

/// One frame of a result.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct FrameRecord {
    /// Frame index.
    pub frame: usize,
    /// Nodes in metres, in order along the rope.
    pub nodes: Vec<[f64; 3]>,
    /// Visibility decision per node.
    pub visible: Vec<bool>,
    /// Tracking step time, milliseconds.
    pub track_ms: f64,
    /// Whole frame time from decoded images, milliseconds.
    pub total_ms: f64,
    /// `true` when tracking could not run on this frame.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub lost: bool,
    /// Why, when lost.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// `true` when the tracked state contradicted the images and the rope
    /// was found again from what is visible.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub recovered: bool,
    /// On a recovered frame: which recovery tests fired and what they
    /// measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub recovery: Option<RecoveryRecord>,
    /// On a frame where the rope was found (initialised or recovered):
    /// the rope-shaped candidates, the one taken and why, and what was
    /// set aside.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub init: Option<InitReport>,
    /// On a frame where a step ran (tracked or recovered): what the
    /// recovery tests measured after it and what came of it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checks: Option<ChecksRecord>,
}

/// Why a tracked state was replaced: the recovery tests that fired and
/// the three measures they read.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct RecoveryRecord {
    /// `stretched`, `free_space`, `unexplained`: the tests that fired.
    pub fired: Vec<String>,
    /// The measures.
    #[serde(flatten)]
    pub measured: Contradiction,
}

impl RecoveryRecord {
    /// The record of `c`.
    pub fn of(c: &Contradiction) -> Self {
        Self {
            fired: c.fired().map(String::from).collect(),
            measured: *c,
        }
    }
}

/// What the recovery tests read after a step, and what came of it: a
/// state kept although a test fired says why here.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct ChecksRecord {
    /// `agreed` (no test fired), `waited` (recoveries back off),
    /// `nothing_found`, `other_thickness` (the rope found is not as thick
    /// as the one tracked), `beside_the_rope` (what contradicted lies
    /// beside the rope tracked), `leaves_seen_rope_out` (the rope found
    /// leaves out rope the state sees), `recovered`.
    pub verdict: String,
    /// The tests that fired and what they measured, as on a recovered
    /// frame.
    #[serde(flatten)]
    pub tests: RecoveryRecord,
    /// Cloud points the tests read.
    pub cloud_points: usize,
    /// The rope found when the images were searched: `{length, diameter,
    /// seen_left_out}` (metres; the seen nodes it leaves out).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub found: Option<FoundAgain>,
}

impl ChecksRecord {
    /// The record of `j`.
    pub fn of(j: &Judgement) -> Self {
        Self {
            verdict: j.verdict.name().to_string(),
            tests: RecoveryRecord::of(&j.measured),
            cloud_points: j.cloud_points,
            found: j.found,
        }
    }
}

/// The recovery tests that fired in `c`, comma-separated, with what they
/// measured: a recovered frame's reason as the page shows it.
pub fn recovery_causes(c: &Contradiction) -> String {
    let mut said = Vec::new();
    if c.stretched() {
        let s = c.stretch.unwrap_or(f64::NAN);
        said.push(format!("stretched to {:.0} % of its length", 100.0 * s));
    }
    if c.in_free_space() {
        said.push(format!(
            "{} of {} hidden nodes in free space",
            c.left_in_free_space, c.hidden_in_free_space
        ));
    }
    if c.unexplained_cloud() {
        said.push(format!(
            "{:.0} % of the rope seen unexplained",
            100.0 * c.unexplained
        ));
    }
    said.join(", ")
}

/// A whole result file.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct TrackResult {
    /// Algorithm name.
    pub algorithm: String,
    /// Parameters in force.
    pub params: Params,
    /// One entry per frame, in order (of the first rope, when there are
    /// several).
    pub frames: Vec<FrameRecord>,
    /// With several ropes, every rope's frames, the first's repeating
    /// `frames` (an extension; absent for one rope).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ropes: Vec<RopeResult>,
}

/// One rope's frames in a result of several ropes.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct RopeResult {
    /// The rope's name (`dlo.json`'s).
    pub name: String,
    /// One entry per frame, in order.
    pub frames: Vec<FrameRecord>,
}

impl TrackResult {
    /// Number of ropes tracked.
    pub fn rope_count(&self) -> usize {
        self.ropes.len().max(1)
    }

    /// Rope `k`'s frames as a result of one rope (the result itself for
    /// the first rope of a one-rope result); `None` past the last rope.
    pub fn rope(&self, k: usize) -> Option<TrackResult> {
        let frames = match (self.ropes.is_empty(), k) {
            (true, 0) => self.frames.clone(),
            (true, _) => return None,
            (false, k) => self.ropes.get(k)?.frames.clone(),
        };
        Some(TrackResult {
            algorithm: self.algorithm.clone(),
            params: self.params,
            frames,
            ropes: Vec::new(),
        })
    }
}

/// Reads a result file: this project's, or another tracker's written in the
/// contract's layout (`params` may be `{}`: missing parameters read as the
/// defaults). Every node must be finite.
pub fn read_result(path: &std::path::Path) -> Result<TrackResult, crate::SequenceError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| crate::write::io_err(path, e))?;
    let result: TrackResult =
        serde_json::from_str(&text).map_err(|e| crate::write::json_error(&name, e))?;
    if result.ropes.len() > upetrack::several::MAX_ROPES {
        return Err(crate::SequenceError::too_large(
            name,
            "number of ropes",
            result.ropes.len() as u64,
            upetrack::several::MAX_ROPES as u64,
        ));
    }
    let every_frame = result
        .frames
        .iter()
        .chain(result.ropes.iter().flat_map(|r| &r.frames));
    for f in every_frame {
        if f.nodes.iter().flatten().any(|c| !c.is_finite()) {
            return Err(crate::SequenceError::invalid(
                &name,
                format!("frame {}: a node is not finite", f.frame),
            ));
        }
    }
    Ok(result)
}
