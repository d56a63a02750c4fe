//! The crate's error type: every variant says what went wrong and where (sample `k`, `λ`).

use pf_core::params::ParamError;
use thiserror::Error;

/// Errors of pf-homotopy.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum HomotopyError {
    /// An error of the engine (a non-positive-definite covariance, degenerate weights …).
    #[error(transparent)]
    Core(#[from] pf_core::CoreError),
    /// A parameter is outside its valid range (see [`pf_core::params`]).
    #[error(transparent)]
    Param(#[from] ParamError),
    /// An input value (bearing, observer position, prior moment) is NaN or infinite.
    #[error("non-finite {what} at sample {k}: {value}")]
    NonFiniteData {
        /// Which input.
        what: &'static str,
        /// 1-based sampling instant (or index) of the bad value.
        k: usize,
        /// The offending value.
        value: f64,
    },
    /// Too few observations to initialise and then run a filter.
    #[error("too few observations: {got} given, at least {needed} needed")]
    TooFewObservations {
        /// Number given.
        got: usize,
        /// Minimum number.
        needed: usize,
    },
    /// A sampling instant outside the scenario.
    #[error(
        "sampling instant K = {k} is outside 2..={n_samples}: the scenario has {n_samples} samples, and instant 1 only initialises"
    )]
    InstantOutOfRange {
        /// The instant asked for.
        k: usize,
        /// The scenario's number of samples.
        n_samples: usize,
    },
    /// Two sequences that must have the same length do not.
    #[error("length mismatch: {what}: expected {expected}, got {got}")]
    LengthMismatch {
        /// What was compared.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// The λ-flow lost positive definiteness of Σ(λ) even after halving the step
    /// `max_halvings` times.
    #[error(
        "homotopy step at λ = {lambda} (sample {k}) left a non-positive-definite Σ after {halvings} step halvings"
    )]
    FlowNotPositiveDefinite {
        /// 1-based sampling instant (0 when the correction is used on its own).
        k: usize,
        /// λ at the start of the failing step.
        lambda: f64,
        /// Halvings tried.
        halvings: u32,
    },
    /// The quadrature approximation of the Hessian H (25) is not positive definite, so the
    /// HΔE direction `−H⁻¹d` is undefined.
    #[error("Hessian H(λ, θ) of eq. (25) is not positive definite at λ = {lambda} (sample {k})")]
    HessianNotPositiveDefinite {
        /// 1-based sampling instant (0 when the correction is used on its own).
        k: usize,
        /// λ at which it failed.
        lambda: f64,
    },
    /// The quadrature weights all vanished: the likelihood is negligible wherever the
    /// Gaussian has mass (an outlying bearing, for example).
    #[error(
        "quadrature weights all zero at λ = {lambda} (sample {k}): the measurement is incompatible with the Gaussian"
    )]
    DegenerateQuadrature {
        /// 1-based sampling instant (0 when the correction is used on its own).
        k: usize,
        /// λ at which it failed.
        lambda: f64,
    },
}

/// Result alias for pf-homotopy.
pub type Result<T, E = HomotopyError> = std::result::Result<T, E>;

/// Reject a non-finite data value: element `k` of `what` (a bearing `y_k`, an observer
/// state, a mean).
pub(crate) fn check_data(what: &'static str, k: usize, value: f64) -> Result<()> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(HomotopyError::NonFiniteData { what, k, value })
    }
}
