//! Figs. 1 and 2: how many more particles the MPF can afford at the cost of the standard PF.

use super::Scale;
use crate::complexity::{CtCase, EfCoefficients, particle_ratio};
use crate::error::{MpfError, Result};
use pf_core::params::ParamError;
use serde::{Deserialize, Serialize};

/// Configuration of the ratio curves.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RatioConfig {
    /// EF coefficients (the paper's by default).
    pub coefficients: EfCoefficients,
    /// Nonlinear states `n` (2 in the figures).
    pub n: usize,
    /// Smallest state dimension `m` (3).
    pub m_min: usize,
    /// Largest `m` (9).
    pub m_max: usize,
    /// `N_PF`, which sets the weight of the `N`-independent terms (2000, as in Section IV-B).
    pub n_pf: f64,
}

impl Default for RatioConfig {
    fn default() -> Self {
        Self {
            coefficients: EfCoefficients::default(),
            n: 2,
            m_min: 3,
            m_max: 9,
            n_pf: 2000.0,
        }
    }
}

impl RatioConfig {
    /// The paper's curves at every scale: they are closed-form, so the scale changes nothing.
    pub fn at_scale(_scale: Scale) -> Self {
        Self::default()
    }

    /// Check the ranges.
    ///
    /// # Errors
    /// `m_min ≤ n`, `m_max < m_min`, `N_PF ≤ 0`, bad coefficients.
    pub fn validate(&self) -> Result<()> {
        self.coefficients.validate()?;
        if self.m_min <= self.n || self.m_max < self.m_min {
            return Err(MpfError::Param(ParamError {
                name: "m_min",
                value: self.m_min as f64,
                reason: "need n < m_min ≤ m_max",
            }));
        }
        if !(self.n_pf.is_finite() && self.n_pf > 0.0) {
            return Err(MpfError::Param(ParamError {
                name: "N_PF",
                value: self.n_pf,
                reason: "must be positive",
            }));
        }
        Ok(())
    }
}

/// One curve: `N(k)/N_PF` against `m`, `None` where `k > m − n`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RatioCurve {
    /// Marginalized states `k`.
    pub k: usize,
    /// Fig. 1 (`C_t = 0`, eq. (11)).
    pub ct_zero: Vec<Option<f64>>,
    /// Fig. 2 (`C_t ≠ 0`, eq. (12)).
    pub ct_nonzero: Vec<Option<f64>>,
}

/// The data of Figs. 1 and 2, in the shape `pf-viz mpf ratio --json` prints.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RatioResult {
    /// `m = m_min … m_max`.
    pub m: Vec<usize>,
    /// One curve per `k = 1 … m_max − n`.
    pub curves: Vec<RatioCurve>,
}

/// Figs. 1 and 2 from eqs. (11) and (12).
///
/// # Errors
/// A bad configuration.
pub fn ratio(cfg: &RatioConfig) -> Result<RatioResult> {
    cfg.validate()?;
    let m: Vec<usize> = (cfg.m_min..=cfg.m_max).collect();
    let c = &cfg.coefficients;
    let curves = (1..=cfg.m_max - cfg.n)
        .map(|k| {
            let at = |case| {
                m.iter()
                    .map(|&mm| {
                        (k <= mm - cfg.n).then(|| particle_ratio(case, mm - k, k, cfg.n_pf, c))
                    })
                    .collect()
            };
            RatioCurve {
                k,
                ct_zero: at(CtCase::Zero),
                ct_nonzero: at(CtCase::NonZero),
            }
        })
        .collect();
    Ok(RatioResult { m, curves })
}
