//! The one error type for a rejected parameter, and the range check every
//! settings struct uses. A leaf module: each algorithm's settings validate
//! themselves with it, and [`crate::params::Params`] composes them.

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
    /// A choice this build does not include.
    #[error("parameter `{name}` = {value} needs the core built with its `{feature}` feature")]
    Unavailable {
        /// Field name.
        name: &'static str,
        /// The choice.
        value: &'static str,
        /// The feature it needs.
        feature: &'static str,
    },
}

/// `Ok` when `ok` holds and `value` is finite, else the error naming `name`.
pub fn check(
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

/// A weight or width in `(0, 1e9]`.
pub fn positive(name: &'static str, value: f64) -> Result<(), ParamsError> {
    check(name, value, value > 0.0 && value <= 1e9, "in (0, 1e9]")
}

/// A weight in `[0, 1e9]`.
pub fn non_negative(name: &'static str, value: f64) -> Result<(), ParamsError> {
    check(name, value, (0.0..=1e9).contains(&value), "in [0, 1e9]")
}

/// A share in `[0, 1]`.
pub fn unit(name: &'static str, value: f64) -> Result<(), ParamsError> {
    check(name, value, (0.0..=1.0).contains(&value), "in [0, 1]")
}

/// An outlier weight in `[0, 1)`.
pub fn below_one(name: &'static str, value: f64) -> Result<(), ParamsError> {
    check(name, value, (0.0..1.0).contains(&value), "in [0, 1)")
}
