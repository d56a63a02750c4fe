//! The crate's error type. Every variant says what was wrong and where (parameter name, sample
//! index, column), so the CLI can turn it into a one-line message.

use pf_core::CoreError;
use pf_core::params::ParamError;
use thiserror::Error;

/// Errors returned by pf-dredge.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum DredgeError {
    /// An error from the SMC engine (degenerate weights, bad filter configuration, …).
    #[error(transparent)]
    Core(#[from] CoreError),
    /// A parameter is outside its valid range (see [`pf_core::params`]).
    #[error(transparent)]
    Param(#[from] ParamError),
    /// The data set has fewer samples than the operation needs.
    #[error("the data set has {got} sample(s): at least {needed} are needed")]
    TooFewSamples {
        /// How many samples the operation needs.
        needed: usize,
        /// How many it got.
        got: usize,
    },
    /// Two columns of the data set have different lengths.
    #[error("column {column} has {got} values, but t has {expected}")]
    ColumnLength {
        /// The column at fault.
        column: &'static str,
        /// Length of `t`.
        expected: usize,
        /// Length of the column.
        got: usize,
    },
    /// A value is NaN or infinite.
    #[error("non-finite value {value} in column {column} at sample {index}")]
    NonFinite {
        /// The column at fault.
        column: &'static str,
        /// Sample index (0-based, data rows only).
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A flow-rate or density is negative.
    #[error(
        "negative value {value} in column {column} at sample {index}: flows and densities cannot be negative"
    )]
    Negative {
        /// The column at fault.
        column: &'static str,
        /// Sample index.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// Time does not strictly increase.
    #[error("time does not increase at sample {index}: t = {t} after {t_prev}")]
    TimeNotIncreasing {
        /// Sample index of the later time.
        index: usize,
        /// The previous time.
        t_prev: f64,
        /// The time at `index`.
        t: f64,
    },
    /// A value that the first sample must carry is missing.
    #[error(
        "the first sample has no {column}: the filter needs it to start (the prior is centred on the first V_t and m_t, and Q_i, rho_i drive the first transition)"
    )]
    MissingFirstValue {
        /// The column that is empty at the first sample.
        column: &'static str,
    },
    /// The filter step failed at a sample.
    #[error("particle filter failed at sample {index}: {source}")]
    FilterStep {
        /// Sample index at which the filter failed.
        index: usize,
        /// What the engine reported.
        source: CoreError,
    },
    /// A line of a CSV data file is malformed (see [`crate::logfile`]).
    #[error("line {line}: {message}")]
    Csv {
        /// 1-based line number, the header being line 1.
        line: u64,
        /// What is wrong.
        message: String,
    },
    /// Writing data failed.
    #[error("cannot write: {message}")]
    Io {
        /// What the writer said.
        message: String,
    },
    /// The simulated cycle did not reach the phase an experiment needs.
    #[error("the simulated cycle never reached phase {phase}; lengthen t_end or change the inputs")]
    PhaseNotReached {
        /// The loading phase (1, 2 or 3).
        phase: u8,
    },
}

/// Result alias for pf-dredge.
pub type Result<T, E = DredgeError> = std::result::Result<T, E>;
