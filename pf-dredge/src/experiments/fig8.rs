//! Fig. 8: the spread of the PF's estimates over independent runs on the same data.

use super::{Scale, filter_seed};
use crate::error::{DredgeError, Result};
use crate::estimator::{EstimatorConfig, run_filter};
use crate::simulator::SimConfig;
use pf_core::mc::{Par, try_replicate};
use pf_core::params::ParamError;
use serde::{Deserialize, Serialize};

/// Settings of Fig. 8.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fig8Config {
    /// The simulator.
    pub sim: SimConfig,
    /// The filter ("the same as with the simulated data").
    pub filter: EstimatorConfig,
    /// Independent runs (25).
    pub runs: usize,
    /// Seed of the data; run `r` uses stream `r` of the filter seed.
    pub seed: u64,
}

impl Default for Fig8Config {
    fn default() -> Self {
        Fig8Config {
            sim: SimConfig::default(),
            filter: EstimatorConfig::default(),
            runs: 25,
            seed: 1,
        }
    }
}

impl Fig8Config {
    /// The preset of a [`Scale`]: `Quick` is 5 runs of 300 particles.
    pub fn at_scale(scale: Scale) -> Self {
        let mut c = Self::default();
        if scale == Scale::Quick {
            c.runs = 5;
            c.filter = c.filter.with_particles(300);
        }
        c
    }
}

/// Min, max and mean over runs, per sample.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Band {
    /// Pointwise minimum (lower edge of the grey band).
    pub min: Vec<f64>,
    /// Pointwise maximum.
    pub max: Vec<f64>,
    /// Pointwise mean (bold line).
    pub mean: Vec<f64>,
}

impl Band {
    fn of(rows: &[&[f64]]) -> Band {
        let n = rows.first().map_or(0, |r| r.len());
        let r = rows.len() as f64;
        let col = |k: usize| rows.iter().map(move |row| row[k]);
        Band {
            min: (0..n)
                .map(|k| col(k).fold(f64::INFINITY, f64::min))
                .collect(),
            max: (0..n)
                .map(|k| col(k).fold(f64::NEG_INFINITY, f64::max))
                .collect(),
            mean: (0..n).map(|k| col(k).sum::<f64>() / r).collect(),
        }
    }
}

/// Everything Fig. 8 shows (the paper plots `ρ_o`; `Q_o` is given too).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fig8Result {
    /// Sample times (s).
    pub t: Vec<f64>,
    /// First phase-3 sample, if any.
    pub phase3_start: Option<usize>,
    /// Band of `ρ̂_o`.
    pub rho_o: Band,
    /// Band of `Q̂_o`.
    pub q_o: Band,
    /// True `ρ_o`, for reference.
    pub rho_o_true: Vec<f64>,
    /// Mean over phase 3 of the band width `max − min` of `ρ̂_o` (kg/m³).
    pub mean_rho_o_width_phase3: f64,
}

/// Fig. 8.
///
/// # Errors
/// Invalid settings, `runs = 0`, or a failed filter step.
pub fn fig8(cfg: &Fig8Config) -> Result<Fig8Result> {
    if cfg.runs == 0 {
        return Err(DredgeError::Param(ParamError {
            name: "runs",
            value: 0.0,
            reason: "at least one run",
        }));
    }
    let c = super::cycle::simulated(&cfg.sim, cfg.seed)?;
    let data = c.to_data();
    let runs = try_replicate(filter_seed(cfg.seed), cfg.runs, Par::Rayon, |_, rng| {
        run_filter(&data, &cfg.filter, rng)
    })?;
    let rho: Vec<&[f64]> = runs.iter().map(|r| r.estimates.rho_o.as_slice()).collect();
    let q: Vec<&[f64]> = runs.iter().map(|r| r.estimates.q_o.as_slice()).collect();
    let rho_o = Band::of(&rho);
    let start = c.phase3_start.unwrap_or(0);
    let widths: Vec<f64> = (start..c.len())
        .map(|k| rho_o.max[k] - rho_o.min[k])
        .collect();
    Ok(Fig8Result {
        t: c.t.clone(),
        phase3_start: c.phase3_start,
        mean_rho_o_width_phase3: widths.iter().sum::<f64>() / widths.len().max(1) as f64,
        rho_o,
        q_o: Band::of(&q),
        rho_o_true: c.rho_o,
    })
}
