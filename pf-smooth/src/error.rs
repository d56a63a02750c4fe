//! The crate's error type: every variant says what went wrong and where.

use pf_core::CoreError;
use pf_core::params::ParamError;
use thiserror::Error;

/// Errors of pf-smooth. Bad user input (parameters, data) is reported here, never by a panic.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum SmoothError {
    /// An error of the engine (filter degeneracy, Kalman failure, bad filter configuration).
    #[error(transparent)]
    Core(#[from] CoreError),
    /// A parameter is outside its valid range (see [`pf_core::params`]).
    #[error(transparent)]
    Param(#[from] ParamError),
    /// The observation sequence `Y_0…Y_n` is too short.
    #[error("too few observations: got {got}, need at least {need} (Y_0…Y_n with n ≥ 1)")]
    TooFewObservations {
        /// How many were given.
        got: usize,
        /// The minimum.
        need: usize,
    },
    /// An observation is NaN or infinite.
    #[error("non-finite observation y[{index}] = {value}")]
    NonFiniteObservation {
        /// Index `k` of `Y_k`.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// An estimator was asked for its estimate before it saw any step.
    #[error("{what}: no filter step observed yet")]
    NoSteps {
        /// Which estimator.
        what: &'static str,
    },
    /// An estimate came out NaN or infinite (it is never returned as a number).
    #[error("non-finite {what} at step {t}, component {component}")]
    NonFiniteEstimate {
        /// Which estimate.
        what: &'static str,
        /// The last step the estimator saw.
        t: usize,
        /// Component of the vector-valued statistic.
        component: usize,
    },
    /// The EM update (10)–(12) is not a valid parameter (e.g. `σ̂² ≤ 0`).
    #[error("degenerate EM update: {what} = {value}")]
    DegenerateUpdate {
        /// Which updated quantity.
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// A step of an iterative algorithm (SEM/MCEM chain, exact EM) failed.
    #[error("chain {chain}, iteration {iteration}: {source}")]
    Iteration {
        /// Chain index (0 for exact EM).
        chain: usize,
        /// Iteration (1 = the first update).
        iteration: usize,
        /// What failed.
        #[source]
        source: Box<SmoothError>,
    },
}

/// Result alias for pf-smooth.
pub type Result<T, E = SmoothError> = std::result::Result<T, E>;
