//! Beyond the paper: the phase-3 residual std of `Q̂_o` and `ρ̂_o` against the number of
//! particles `N`, so a user can pick `N` for the on-board time budget (the time per step is
//! measured by the `filter_step` bench; it grows linearly in `N`).

use super::{Scale, filter_seed, phase3};
use crate::error::{DredgeError, Result};
use crate::estimator::{EstimatorConfig, residuals_of, run_filter};
use crate::simulator::SimConfig;
use pf_core::mc::{Par, mean_and_se, try_replicate};
use pf_core::metrics::ResidualSummary;
use pf_core::params::ParamError;
use serde::{Deserialize, Serialize};

/// Settings of the `N` sweep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NSweepConfig {
    /// The simulator.
    pub sim: SimConfig,
    /// The filter; `N_T / N` is kept at its ratio (0.9).
    pub filter: EstimatorConfig,
    /// The values of `N`.
    pub n_particles: Vec<usize>,
    /// Filter runs per `N` on the same cycle.
    pub reps: usize,
    /// Seed.
    pub seed: u64,
}

impl Default for NSweepConfig {
    fn default() -> Self {
        Self::at_scale(Scale::Default)
    }
}

impl NSweepConfig {
    /// Presets: `Quick` N ∈ {100, 300}, 2 runs; `Default` N ∈ {100, 300, 1000, 3000, 10000}, 4 runs;
    /// `Full` N ∈ {100, 300, 1000, 3000, 10000}, 10 runs.
    pub fn at_scale(scale: Scale) -> Self {
        let (n_particles, reps) = match scale {
            Scale::Quick => (vec![100, 300], 2),
            Scale::Default => (vec![100, 300, 1000, 3000, 10_000], 4),
            Scale::Full => (vec![100, 300, 1000, 3000, 10_000], 10),
        };
        NSweepConfig {
            sim: SimConfig::default(),
            filter: EstimatorConfig::default(),
            n_particles,
            reps,
            seed: 1,
        }
    }
}

/// One `N`: mean and standard error over the runs of the phase-3 residual std.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NSweepRow {
    /// `N`.
    pub n: usize,
    /// Mean over runs of std(`Q_o − Q̂_o`) (m³/s).
    pub q_o_std: f64,
    /// Its standard error.
    pub q_o_std_se: f64,
    /// Mean over runs of std(`ρ_o − ρ̂_o`) (kg/m³).
    pub rho_o_std: f64,
    /// Its standard error.
    pub rho_o_std_se: f64,
}

/// The sweep's result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NSweepResult {
    /// One row per `N`, in the config's order.
    pub rows: Vec<NSweepRow>,
}

/// Run the sweep.
///
/// # Errors
/// Invalid settings, an empty list, no phase 3, or a failed filter step.
pub fn n_sweep(cfg: &NSweepConfig) -> Result<NSweepResult> {
    if cfg.n_particles.is_empty() || cfg.reps == 0 {
        return Err(DredgeError::Param(ParamError {
            name: "n_particles/reps",
            value: 0.0,
            reason: "at least one N and one run",
        }));
    }
    let c = super::cycle::simulated(&cfg.sim, cfg.seed)?;
    let p3 = phase3(&c)?;
    let data = c.to_data();
    let truth = |v: &[f64]| v[p3.clone()].iter().copied().map(Some).collect::<Vec<_>>();
    let (tq, tr) = (truth(&c.q_o), truth(&c.rho_o));
    let mut rows = Vec::with_capacity(cfg.n_particles.len());
    for (i, &n) in cfg.n_particles.iter().enumerate() {
        let f = cfg.filter.with_particles(n);
        let seed = filter_seed(cfg.seed).wrapping_add(1000 * i as u64);
        let stds = try_replicate(seed, cfg.reps, Par::Rayon, |_, rng| -> Result<(f64, f64)> {
            let e = run_filter(&data, &f, rng)?.estimates;
            let sq = ResidualSummary::new(&residuals_of(&tq, &e.q_o[p3.clone()]))?;
            let sr = ResidualSummary::new(&residuals_of(&tr, &e.rho_o[p3.clone()]))?;
            Ok((sq.std, sr.std))
        })?;
        let (q, r): (Vec<f64>, Vec<f64>) = stds.into_iter().unzip();
        let (q_o_std, q_o_std_se) = mean_and_se(&q);
        let (rho_o_std, rho_o_std_se) = mean_and_se(&r);
        rows.push(NSweepRow {
            n,
            q_o_std,
            q_o_std_se,
            rho_o_std,
            rho_o_std_se,
        });
    }
    Ok(NSweepResult { rows })
}
