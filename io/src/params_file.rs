//! Parameter files: any subset of [`Params`]' fields as JSON, the rest
//! taking their defaults, checked by name. The command's `--params` and the
//! page both read parameters through [`parse_params`], so both reject the
//! same values with the same message.

use upetrack::Params;

use crate::error::SequenceError;
use crate::sequence::parse_json;

/// Fields of earlier parameter files whose meaning changed, refused with
/// what replaced them rather than read in the new unit.
const REPLACED_FIELDS: [(&str, &str); 1] = [(
    "rest_speed",
    "`rest_speed` was in metres per frame; `rest_speed_m_per_s` replaced it, in metres per second: \
     multiply by the frame rate (0.002 at 30 fps is 0.06)",
)];

/// Parses and validates parameters from JSON text; `path` names the source
/// in errors.
pub fn parse_params(text: &str, path: &str) -> Result<Params, SequenceError> {
    if let Ok(fields) = serde_json::from_str::<serde_json::Map<String, serde_json::Value>>(text) {
        if let Some((_, why)) = REPLACED_FIELDS
            .iter()
            .find(|(k, _)| fields.contains_key(*k))
        {
            return Err(SequenceError::invalid(path, *why));
        }
    }
    let params: Params = parse_json(text.as_bytes(), path)?;
    params
        .validate()
        .map_err(|e| SequenceError::invalid(path, e.to_string()))?;
    Ok(params)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_subset_takes_defaults_and_bad_values_are_named() {
        let p = parse_params(
            r#"{"node_count": 30, "displacement_weight": 0.5}"#,
            "p.json",
        )
        .expect("valid");
        assert_eq!((p.node_count, p.upetrack.displacement_weight), (30, 0.5));
        assert_eq!(p.visibility_radius, Params::default().visibility_radius);
        let e = parse_params(r#"{"reinit_visible_fraction": -5}"#, "p.json")
            .expect_err("negative fraction")
            .to_string();
        assert!(
            e.starts_with("p.json: ") && e.contains("reinit_visible_fraction"),
            "{e}"
        );
        let e = parse_params(r#"{"no_such": 1}"#, "p.json").expect_err("unknown");
        assert!(e.to_string().contains("unknown field `no_such`"), "{e}");
    }

    #[test]
    fn a_rest_speed_per_frame_is_refused_not_read_per_second() {
        let e = parse_params(r#"{"rest_speed": 0.002}"#, "old.json")
            .expect_err("per frame")
            .to_string();
        assert!(
            e.starts_with("old.json: ") && e.contains("rest_speed_m_per_s"),
            "{e}"
        );
        let p = parse_params(r#"{"rest_speed_m_per_s": 0.03}"#, "new.json").expect("per second");
        assert_eq!(p.upetrack.rest_speed_m_per_s, 0.03);
    }
}
