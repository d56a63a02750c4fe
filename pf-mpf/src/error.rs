//! The crate's error type: every variant says what went wrong and where.

use pf_core::CoreError;
use pf_core::params::ParamError;
use thiserror::Error;

/// Errors returned by pf-mpf.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum MpfError {
    /// An error from the engine (weights, resampling, dimensions, parameters).
    #[error(transparent)]
    Core(#[from] CoreError),
    /// A partition string (such as `PPKKPP`) that cannot be used.
    #[error("invalid partition '{partition}': {reason}")]
    Partition {
        /// The partition as given.
        partition: String,
        /// Why it was rejected.
        reason: &'static str,
    },
    /// A parameter is outside its valid range (see [`pf_core::params`]).
    #[error(transparent)]
    Param(#[from] ParamError),
    /// Alg. 1 (one Riccati recursion shared by all particles) was asked for, but `C_t ≠ 0`.
    #[error("Alg. 1 shares one Riccati recursion and needs C_t = 0, but max |C_t| = {max_abs}")]
    SharedRiccatiNeedsZeroC {
        /// Largest absolute entry of `C_t`.
        max_abs: f64,
    },
    /// The process noises of the PF and KF parts are correlated; model (5) needs them
    /// independent.
    #[error("model (5) needs independent noises, but Cov(w^p_{row}, w^k_{col}) = {value}")]
    CorrelatedNoise {
        /// Index within `x^p`.
        row: usize,
        /// Index within `x^k`.
        col: usize,
        /// The covariance.
        value: f64,
    },
    /// A covariance that must be positive definite is not, during filtering.
    #[error("{what} is not positive definite at step {t}, particle {particle}")]
    NotPositiveDefinite {
        /// Which matrix (`M_t`, `S_t`, …).
        what: &'static str,
        /// Time step.
        t: usize,
        /// Particle index.
        particle: usize,
    },
    /// A step beyond the tabulated shared Riccati recursion, which had not converged.
    #[error(
        "step {t} is beyond the {horizon} steps of the shared Riccati recursion, which has not converged"
    )]
    RiccatiHorizon {
        /// The step asked for.
        t: usize,
        /// Steps tabulated.
        horizon: usize,
    },
    /// An observation holds a NaN or infinite value.
    #[error("non-finite observation y_{t}[{index}] = {value}")]
    NonFiniteObservation {
        /// Time step.
        t: usize,
        /// Component.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// Not enough observations for the requested analysis.
    #[error("too few observations: got {got}, need at least {need}")]
    TooFewObservations {
        /// Number given.
        got: usize,
        /// Number needed.
        need: usize,
    },
    /// No particle count fits the requested time budget.
    #[error(
        "time budget {} s is below the cost of one particle ({} s) for p = {p}, k = {k}",
        pf_core::error::Shown(*budget_s),
        pf_core::error::Shown(*per_particle_s)
    )]
    BudgetTooSmall {
        /// The budget.
        budget_s: f64,
        /// Predicted time of one particle (and the constant part).
        per_particle_s: f64,
        /// PF states.
        p: usize,
        /// KF states.
        k: usize,
    },
}

/// Result alias for pf-mpf.
pub type Result<T, E = MpfError> = std::result::Result<T, E>;
