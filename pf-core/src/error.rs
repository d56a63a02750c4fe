//! The engine's error type: every variant says what went wrong and where.

pub use crate::params::{ParamError, Shown};
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
    /// Replication `replication` of a Monte Carlo study dealt to MPI ranks failed (see
    /// [`mc::dist`](crate::mc::dist)); every rank reports it, with the failing rank's
    /// message, which is all that crosses ranks.
    #[error("replication {replication}: {message}")]
    Replication {
        /// The replication's index `r`.
        replication: usize,
        /// The error it failed with, as text.
        message: String,
    },
    /// The MPI ranks of a distributed run did not run the same study (their programs took
    /// different paths), or their results could not be exchanged or decoded.
    #[error("MPI: {message}")]
    Distributed {
        /// What went wrong, naming the ranks and studies involved.
        message: String,
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

/// Result alias for pf-core.
pub type Result<T, E = CoreError> = std::result::Result<T, E>;
