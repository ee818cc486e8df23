//! The contract's rules the page needs, made by the command's own code: the
//! result JSON from the records the tracker produced per frame, and the
//! occluders in force on a frame.

use upetrack::Params;
use upetrack_io::result::FrameRecord;
use upetrack_io::run::{several_result, track_result};
use upetrack_io::sequence::OcclusionConfig;
use wasm_bindgen::prelude::*;

use crate::js_err;

/// The result JSON (text) of `params` and the frames' `record`s, in order:
/// what `upetrack track` writes for the same frames. With several ropes,
/// `ropes` is `[{name, records}]` (every rope's, the first's repeating
/// `records`); `null` or absent for one.
#[wasm_bindgen(js_name = resultFile)]
pub fn result_file(params: JsValue, records: JsValue, ropes: JsValue) -> Result<String, JsError> {
    let params: Params = serde_wasm_bindgen::from_value(params).map_err(js_err)?;
    let records: Vec<FrameRecord> = serde_wasm_bindgen::from_value(records).map_err(js_err)?;
    let ropes: Option<Vec<RopeRecords>> = serde_wasm_bindgen::from_value(ropes).map_err(js_err)?;
    let result = match ropes {
        Some(ropes) if ropes.len() > 1 => several_result(
            params,
            ropes.into_iter().map(|r| (r.name, r.records)).collect(),
        ),
        _ => track_result(params, records),
    };
    serde_json::to_string(&result).map_err(js_err)
}

/// One rope's records, for [`result_file`].
#[derive(serde::Deserialize)]
struct RopeRecords {
    name: String,
    records: Vec<FrameRecord>,
}

/// The rectangles of `occlusions` (a `dlo.json`'s list) in force on frame
/// `index`, flat `[x, y, w, h, ...]`.
#[wasm_bindgen(js_name = activeOcclusions)]
pub fn active_occlusions(occlusions: JsValue, index: usize) -> Result<Vec<f64>, JsError> {
    let list: Vec<OcclusionConfig> = serde_wasm_bindgen::from_value(occlusions).map_err(js_err)?;
    Ok(list
        .iter()
        .filter(|o| o.active_at(index))
        .flat_map(|o| o.rect.map(|v| v as f64))
        .collect())
}

/// What a file given to the page is, from its first bytes (`HEAD_BYTES` of
/// them are enough): `{kind: "recording" | "zip" | "other", what}`, `what`
/// naming an other file ("a JPEG image") — the command's rule.
#[wasm_bindgen(js_name = inputKind)]
pub fn input_kind(head: &[u8]) -> Result<JsValue, JsError> {
    use upetrack_io::open::InputKind;
    #[derive(serde::Serialize)]
    struct Kind {
        kind: &'static str,
        what: &'static str,
    }
    let k = match upetrack_io::open::input_kind(head) {
        InputKind::Recording => Kind {
            kind: "recording",
            what: "a recording",
        },
        InputKind::Zip => Kind {
            kind: "zip",
            what: "a zip archive",
        },
        InputKind::Other(what) => Kind {
            kind: "other",
            what,
        },
    };
    crate::to_js(&k)
}

/// How many of a file's first bytes `inputKind` needs.
#[wasm_bindgen(js_name = inputHeadBytes)]
pub fn input_head_bytes() -> usize {
    upetrack_io::open::HEAD_BYTES
}
