//! Parameter checks shared by every crate of the workspace.
//!
//! Each check returns the value when it is valid, so a constructor can check and bind in one
//! line (`let sigma = params::positive("sigma", sigma)?;`), or a [`ParamError`] that names
//! the parameter, its value and the valid range. Every crate's error enum wraps
//! [`ParamError`] (`#[error(transparent)] Param(#[from] ParamError)`), so `?` converts it.

use thiserror::Error;

/// A parameter's value in an error message: as written for ordinary magnitudes, in
/// exponent form for extreme ones (`1e-300`, not three hundred digits; `1.8446744073709552e19`
/// for a count that came in as `usize::MAX`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shown(pub f64);

impl std::fmt::Display for Shown {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let a = self.0.abs();
        if a == 0.0 || !a.is_finite() || (1e-4..1e15).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

/// A parameter outside its valid range: `invalid parameter {name} = {value}: {reason}`.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
#[error("invalid parameter {name} = {}: {reason}", Shown(*value))]
pub struct ParamError {
    /// Parameter name, as the paper writes it where possible.
    pub name: &'static str,
    /// The offending value (a count is shown as a float).
    pub value: f64,
    /// What the valid range is.
    pub reason: &'static str,
}

impl ParamError {
    /// `name = value` is invalid because of `reason` (for ranges the checks below do not cover).
    pub fn new(name: &'static str, value: f64, reason: &'static str) -> Self {
        ParamError {
            name,
            value,
            reason,
        }
    }
}

/// Result of a parameter check.
pub type Checked<T> = std::result::Result<T, ParamError>;

/// `Ok(value)` if `value` is finite and `> 0`.
pub fn positive(name: &'static str, value: f64) -> Checked<f64> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(ParamError::new(name, value, "must be positive and finite"))
    }
}

/// `Ok(value)` if `value` is finite and `≥ 0`.
pub fn non_negative(name: &'static str, value: f64) -> Checked<f64> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(ParamError::new(
            name,
            value,
            "must be non-negative and finite",
        ))
    }
}

/// `Ok(value)` if `value` is finite (neither NaN nor ±∞).
pub fn finite(name: &'static str, value: f64) -> Checked<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ParamError::new(name, value, "must be finite"))
    }
}

/// `Ok(value)` if `value` is a probability, in `[0, 1]`.
pub fn probability(name: &'static str, value: f64) -> Checked<f64> {
    if (0.0..=1.0).contains(&value) {
        Ok(value)
    } else {
        Err(ParamError::new(name, value, "must lie in [0, 1]"))
    }
}

/// `Ok(n)` if the count `n` is at least 1.
pub fn at_least_one(name: &'static str, n: usize) -> Checked<usize> {
    if n >= 1 {
        Ok(n)
    } else {
        Err(ParamError::new(name, n as f64, "must be at least 1"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::CoreError;

    /// Ordinary values read as written; extreme ones in exponent form, not hundreds of digits.
    #[test]
    fn parameter_values_are_shown_readably() {
        let shown = |v: f64| Shown(v).to_string();
        assert_eq!(shown(0.0), "0");
        assert_eq!(shown(-2.5), "-2.5");
        assert_eq!(shown(1000.0), "1000");
        assert_eq!(shown(f64::NAN), "NaN");
        assert_eq!(shown(1e-300), "1e-300");
        assert_eq!(shown(usize::MAX as f64), "1.8446744073709552e19");
        let e = CoreError::Param(ParamError {
            name: "budget",
            value: 1e308,
            reason: "too large",
        });
        assert_eq!(e.to_string(), "invalid parameter budget = 1e308: too large");
    }

    /// Each check passes its valid values through unchanged and rejects the edges of its
    /// range, NaN and the infinities, naming the parameter and the value.
    #[test]
    fn checks_accept_their_range_and_name_what_they_reject() {
        assert_eq!(positive("sigma", 0.5), Ok(0.5));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(positive("sigma", bad).unwrap_err().name, "sigma");
        }
        assert_eq!(non_negative("q", 0.0), Ok(0.0));
        for bad in [-1e-300, f64::NAN, f64::INFINITY] {
            assert!(non_negative("q", bad).is_err(), "{bad}");
        }
        assert_eq!(finite("phi", -3.0), Ok(-3.0));
        for bad in [f64::NAN, f64::NEG_INFINITY] {
            assert!(finite("phi", bad).is_err(), "{bad}");
        }
        assert_eq!(probability("p", 1.0), Ok(1.0));
        assert_eq!(probability("p", 0.0), Ok(0.0));
        for bad in [-0.1, 1.1, f64::NAN] {
            assert!(probability("p", bad).is_err(), "{bad}");
        }
        assert_eq!(at_least_one("N", 1), Ok(1));
        assert_eq!(
            at_least_one("N", 0).unwrap_err().to_string(),
            "invalid parameter N = 0: must be at least 1"
        );
        assert_eq!(
            positive("rho", -2.0).unwrap_err().to_string(),
            "invalid parameter rho = -2: must be positive and finite"
        );
    }
}
