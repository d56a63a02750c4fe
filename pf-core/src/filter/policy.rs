//! When to resample. The policy belongs to the filter's configuration, never to the model.

use crate::error::{CoreError, Result};
use crate::params::ParamError;
use serde::{Deserialize, Serialize};

/// When the filter resamples, judged on the weights left by the previous step.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ResamplePolicy {
    /// At every step (the bootstrap filter of Gordon, Salmond & Smith 1993).
    #[default]
    Always,
    /// When the effective sample size falls below a threshold.
    EssBelow(EssThreshold),
    /// Never: plain sequential importance sampling.
    Never,
}

/// A threshold on the effective sample size.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EssThreshold {
    /// Resample when ESS < `N_T` (an absolute number of particles).
    Absolute(f64),
    /// Resample when ESS < `r·N`, `0 < r ≤ 1`.
    Fraction(f64),
}

impl ResamplePolicy {
    /// Whether to resample with `n` particles whose effective sample size is `ess`.
    pub fn should_resample(&self, ess: f64, n: usize) -> bool {
        match *self {
            ResamplePolicy::Always => true,
            ResamplePolicy::Never => false,
            ResamplePolicy::EssBelow(EssThreshold::Absolute(n_t)) => ess < n_t,
            ResamplePolicy::EssBelow(EssThreshold::Fraction(r)) => ess < r * n as f64,
        }
    }

    /// Reject thresholds that cannot mean anything.
    pub fn validate(&self) -> Result<()> {
        match *self {
            ResamplePolicy::EssBelow(EssThreshold::Absolute(n_t)) if n_t.is_nan() || n_t < 0.0 => {
                Err(CoreError::Param(ParamError {
                    name: "N_T",
                    value: n_t,
                    reason: "ESS threshold must be a non-negative number",
                }))
            }
            ResamplePolicy::EssBelow(EssThreshold::Fraction(r))
                if r.is_nan() || r <= 0.0 || r > 1.0 =>
            {
                Err(CoreError::Param(ParamError {
                    name: "ESS fraction",
                    value: r,
                    reason: "must lie in (0, 1]",
                }))
            }
            _ => Ok(()),
        }
    }
}
