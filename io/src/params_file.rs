//! Parameter files: any subset of [`Params`]' fields as JSON, the rest
//! taking their defaults, checked by name. The command's `--params` and the
//! page both read parameters through [`parse_params`], so both reject the
//! same values with the same message.

use upetrack::Params;

use crate::error::SequenceError;
use crate::sequence::parse_json;

/// Parses and validates parameters from JSON text; `path` names the source
/// in errors.
pub fn parse_params(text: &str, path: &str) -> Result<Params, SequenceError> {
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
}
