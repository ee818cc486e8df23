//! The result JSON of the contract: the algorithm, every parameter in force,
//! and one entry per frame.

use serde::{Deserialize, Serialize};
use upetrack::perception::initialisation::InitReport;
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
    /// On a frame where the rope was found (initialised or recovered):
    /// the rope-shaped candidates, the one taken and why, and what was
    /// set aside.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub init: Option<InitReport>,
}

/// A whole result file.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct TrackResult {
    /// Algorithm name.
    pub algorithm: String,
    /// Parameters in force.
    pub params: Params,
    /// One entry per frame, in order.
    pub frames: Vec<FrameRecord>,
}

/// Reads a result file: this project's, or another tracker's written in the
/// contract's layout (`params` may be `{}`: missing parameters read as the
/// defaults). Every node must be finite.
pub fn read_result(path: &std::path::Path) -> Result<TrackResult, crate::SequenceError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| crate::write::io_err(path, e))?;
    let result: TrackResult =
        serde_json::from_str(&text).map_err(|e| crate::write::json_error(&name, e))?;
    for f in &result.frames {
        if f.nodes.iter().flatten().any(|c| !c.is_finite()) {
            return Err(crate::SequenceError::invalid(
                &name,
                format!("frame {}: a node is not finite", f.frame),
            ));
        }
    }
    Ok(result)
}
