//! The partition advisor (beyond the paper): rank the ways of splitting the linear states
//! between PF and KF by this machine's calibrated EF model.

use crate::calibrate::Calibration;
use crate::complexity::{CtCase, ef_cost};
use crate::error::{MpfError, Result};
use pf_core::params::ParamError;
use serde::{Deserialize, Serialize};

/// What to advise on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdviseConfig {
    /// States that must be in the PF (the nonlinear ones, `n`).
    pub p: usize,
    /// Linear states that may go to the KF (`l`).
    pub k: usize,
    /// Time budget per filter step (s); give this or `particles`.
    pub budget_s: Option<f64>,
    /// Particle count; give this or `budget_s`.
    pub particles: Option<usize>,
    /// Which complexity expression applies.
    pub ct: CtCase,
}

impl Default for AdviseConfig {
    /// The radar example: `n = 2`, `l = 4`, `N = 2000`, `C_t = 0`.
    fn default() -> Self {
        Self {
            p: 2,
            k: 4,
            budget_s: None,
            particles: Some(2000),
            ct: CtCase::Zero,
        }
    }
}

impl AdviseConfig {
    /// Check the request.
    ///
    /// # Errors
    /// `p = 0`, both or neither of budget and particles, a bad budget, zero particles.
    pub fn validate(&self) -> Result<()> {
        if self.p == 0 {
            return Err(MpfError::Param(ParamError {
                name: "p",
                value: 0.0,
                reason: "at least one state must be in the PF",
            }));
        }
        // One option per k is weighed, so the dimensions bound the work; a million state
        // components is far beyond what the flop model (eqs. (11)-(12)) was fitted for.
        if self.p.saturating_add(self.k) > MAX_DIMENSION {
            return Err(MpfError::Param(ParamError {
                name: "p + k",
                value: self.p.saturating_add(self.k) as f64,
                reason: "the state may have at most 10⁶ components",
            }));
        }
        if let Some(n) = self.particles {
            pf_core::limits::check_count("particles", n)?;
        }
        match (self.budget_s, self.particles) {
            (Some(b), None) if !(b.is_finite() && b > 0.0) => Err(MpfError::Param(ParamError {
                name: "budget_s",
                value: b,
                reason: "must be positive and finite",
            })),
            (None, Some(0)) => Err(MpfError::Param(ParamError {
                name: "particles",
                value: 0.0,
                reason: "must be at least 1",
            })),
            (Some(_), Some(_)) | (None, None) => Err(MpfError::Param(ParamError {
                name: "budget_s/particles",
                value: f64::NAN,
                reason: "give exactly one of a time budget and a particle count",
            })),
            _ => Ok(()),
        }
    }
}

/// The largest state dimension `p + k` the advisor weighs.
pub const MAX_DIMENSION: usize = 1_000_000;

/// One partition's predicted cost.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AdviceOption {
    /// States in the PF.
    pub p: usize,
    /// States in the KF.
    pub k: usize,
    /// Particles (given, or the most the budget allows).
    pub n_particles: usize,
    /// Predicted time per filter step (s).
    pub time_s: f64,
    /// EF per step.
    pub ef: f64,
}

/// The ranking: by particles (most first) under a budget, by time (least first) otherwise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Advice {
    /// The calibration used.
    pub calibration: Calibration,
    /// Options, best first.
    pub options: Vec<AdviceOption>,
}

/// `pf-viz mpf advise`.
///
/// # Errors
/// A bad request or calibration, or a budget too small for one particle in any partition.
pub fn advise(cfg: &AdviseConfig, calibration: &Calibration) -> Result<Advice> {
    cfg.validate()?;
    calibration.validate()?;
    let c = calibration.coefficients();
    let secs = |ef: f64| ef * calibration.flop_ns * 1e-9;
    let mut options = Vec::with_capacity(cfg.k + 1);
    for kk in 0..=cfg.k {
        let p = cfg.p + cfg.k - kk;
        // The standard PF (kk = 0) has no Riccati recursion: eq. (11) applies to it.
        let case = if kk == 0 { CtCase::Zero } else { cfg.ct };
        let cost = ef_cost(case, p, kk, &c);
        let n = match (cfg.budget_s, cfg.particles) {
            (_, Some(n)) => n,
            (Some(b), None) => {
                let n = ((b / (calibration.flop_ns * 1e-9) - cost.constant) / cost.per_particle)
                    .floor();
                if n < 1.0 {
                    continue;
                }
                if n > pf_core::limits::MAX_COUNT as f64 {
                    return Err(MpfError::Param(ParamError {
                        name: "budget_s",
                        value: cfg.budget_s.unwrap_or(f64::NAN),
                        reason: "the budget allows more than 2³² particles",
                    }));
                }
                n as usize
            }
            (None, None) => unreachable!("validated"),
        };
        let ef = cost.at(n as f64);
        options.push(AdviceOption {
            p,
            k: kk,
            n_particles: n,
            time_s: secs(ef),
            ef,
        });
    }
    if options.is_empty() {
        let cost = ef_cost(CtCase::Zero, cfg.p + cfg.k, 0, &c);
        return Err(MpfError::BudgetTooSmall {
            budget_s: cfg.budget_s.unwrap_or(0.0),
            per_particle_s: secs(cost.at(1.0)),
            p: cfg.p + cfg.k,
            k: 0,
        });
    }
    if cfg.budget_s.is_some() {
        options.sort_by_key(|o| std::cmp::Reverse(o.n_particles));
    } else {
        options.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    }
    Ok(Advice {
        calibration: *calibration,
        options,
    })
}
