//! The engine's error type: every variant says what went wrong and where.

pub use crate::params::ParamError;
use thiserror::Error;

/// Errors returned by pf-core. Variants carry the time step, index or parameter at fault.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum CoreError {
    /// Every particle's weight underflowed to zero (or was −∞) at step `t`.
    #[error(
        "all particle weights are zero at step {t}: the likelihood underflowed for every particle"
    )]
    AllWeightsZero {
        /// Time step at which the weights collapsed.
        t: usize,
    },
    /// A log-weight was NaN or +∞ at step `t`, for particle `index`.
    #[error("non-finite log-weight {value} at step {t}, particle {index}")]
    NonFiniteWeight {
        /// Time step.
        t: usize,
        /// Particle index.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A matrix that must be symmetric positive definite is not; `pivot` is the failing column.
    #[error("{what} is not positive definite (Cholesky pivot {pivot} is {value})")]
    NotPositiveDefinite {
        /// Which matrix.
        what: &'static str,
        /// Column of the failing pivot.
        pivot: usize,
        /// The pivot value that was not positive.
        value: f64,
    },
    /// Two dimensions that must agree do not.
    #[error("dimension mismatch in {what}: expected {expected}, got {got}")]
    DimensionMismatch {
        /// What was being checked.
        what: &'static str,
        /// Expected size.
        expected: usize,
        /// Actual size.
        got: usize,
    },
    /// A parameter is outside its valid range (see [`crate::params`]).
    #[error(transparent)]
    Param(#[from] ParamError),
    /// Input data contain a NaN or infinite value.
    #[error("non-finite value {value} in {what} at index {index}")]
    NonFiniteData {
        /// Which input.
        what: &'static str,
        /// Position of the bad value.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// An error that happened while processing time step `t` of a sequence.
    #[error("at step {t}: {source}")]
    AtStep {
        /// Time step.
        t: usize,
        /// What went wrong there.
        source: Box<CoreError>,
    },
    /// An operation needed at least one element.
    #[error("{what} is empty")]
    Empty {
        /// What was empty.
        what: &'static str,
    },
    /// A count beyond [`MAX_COUNT`](crate::limits::MAX_COUNT), or buffers of `len` elements
    /// that could not be allocated.
    #[error("{what}: {len} is more than this machine can hold")]
    TooLarge {
        /// What was asked for.
        what: &'static str,
        /// How many.
        len: usize,
    },
}

impl CoreError {
    /// Attach the time step at which this error happened.
    pub fn at_step(self, t: usize) -> Self {
        CoreError::AtStep {
            t,
            source: Box::new(self),
        }
    }
}

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

/// Result alias for pf-core.
pub type Result<T, E = CoreError> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

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
}
