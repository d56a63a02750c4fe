//! Fig. 3 (RMS position error against time) and the cost comparison.

use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::Scale;
use crate::error::{HomotopyError, Result};
use crate::filters::{Algorithm, FilterSettings, track};
use crate::model::ScenarioConfig;
use pf_core::mc::{Par, try_replicate};
use pf_core::params::ParamError;

/// One value per algorithm, serialised with the CLI contract's keys.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PerAlgorithm<T> {
    /// OHF (HΔE).
    #[serde(rename = "OHF")]
    pub ohf: T,
    /// AOHF (AHΔE).
    #[serde(rename = "AOHF")]
    pub aohf: T,
    /// UKF-LPC.
    #[serde(rename = "UKF-LPC")]
    pub ukf_lpc: T,
    /// PF with the linearised optimal importance density.
    #[serde(rename = "PF")]
    pub pf: T,
}

impl<T> PerAlgorithm<T> {
    /// The entry of `alg`.
    pub fn get(&self, alg: Algorithm) -> &T {
        match alg {
            Algorithm::Ohf => &self.ohf,
            Algorithm::Aohf => &self.aohf,
            Algorithm::UkfLpc => &self.ukf_lpc,
            Algorithm::Pf => &self.pf,
        }
    }

    /// The entry of `alg`, mutably.
    pub fn get_mut(&mut self, alg: Algorithm) -> &mut T {
        match alg {
            Algorithm::Ohf => &mut self.ohf,
            Algorithm::Aohf => &mut self.aohf,
            Algorithm::UkfLpc => &mut self.ukf_lpc,
            Algorithm::Pf => &mut self.pf,
        }
    }
}

/// Settings of Fig. 3.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RmseConfig {
    /// The scenario.
    pub scenario: ScenarioConfig,
    /// The filters (the PF's N is `filters.particles`).
    pub filters: FilterSettings,
    /// Number of realisations (500).
    pub realisations: usize,
    /// Seed: realisation r uses `stream_rng(seed, r)`.
    pub seed: u64,
}

impl Default for RmseConfig {
    fn default() -> Self {
        Self::at_scale(Scale::Full)
    }
}

/// The checks every Monte Carlo experiment over realisations of the scenario shares.
pub(crate) fn validate_runs(
    scenario: &ScenarioConfig,
    filters: &FilterSettings,
    realisations: usize,
) -> Result<()> {
    scenario.validate()?;
    filters.validate()?;
    if realisations == 0 {
        return Err(HomotopyError::Param(ParamError {
            name: "realisations R",
            value: 0.0,
            reason: "at least one realisation is needed",
        }));
    }
    Ok(())
}

impl RmseConfig {
    /// The paper's settings at a size preset: quick 8 realisations with N = 2000,
    /// default 40 realisations and full 500, both with the paper's N = 100 000 (with 10 000
    /// particles the PF loses the target on a fifth of the realisations after the turn, see
    /// the crate README; a run costs half a second).
    pub fn at_scale(scale: Scale) -> Self {
        let (realisations, particles) = match scale {
            Scale::Quick => (8, 2_000),
            Scale::Default => (40, 100_000),
            Scale::Full => (500, 100_000),
        };
        Self {
            scenario: ScenarioConfig::default(),
            filters: FilterSettings {
                particles,
                ..FilterSettings::default()
            },
            realisations,
            seed: 0,
        }
    }

    /// Check the settings.
    pub fn validate(&self) -> Result<()> {
        validate_runs(&self.scenario, &self.filters, self.realisations)
    }
}

/// Fig. 3 / `pf-viz homotopy rmse --json`: `{"time", "rmse", "seconds_per_run",
/// "final_errors"}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RmseResult {
    /// Times `(k − 1)T`, s, of the sampling instants.
    pub time: Vec<f64>,
    /// RMS position error at each instant, m.
    pub rmse: PerAlgorithm<Vec<f64>>,
    /// Mean wall-clock seconds per filter run (one realisation).
    pub seconds_per_run: PerAlgorithm<f64>,
    /// Position error at the last instant, m, per realisation: a few lost tracks can make
    /// the RMS error (see the crate README on the PF with 10 000 particles).
    pub final_errors: PerAlgorithm<Vec<f64>>,
}

/// Per algorithm: squared errors `[r][k]` and seconds `[r]`.
type ErrorsAndTimes = (Vec<Vec<Vec<f64>>>, Vec<Vec<f64>>);

/// Squared position errors and run times of `algs` over `cfg.realisations` realisations:
/// `(sq[alg][r][k], seconds[alg][r])`.
pub(crate) fn replicate_errors(cfg: &RmseConfig, algs: &[Algorithm]) -> Result<ErrorsAndTimes> {
    let runs = try_replicate(cfg.seed, cfg.realisations, Par::Rayon, |_, rng| {
        let real = cfg.scenario.simulate(rng)?;
        let mut out = Vec::with_capacity(algs.len());
        for &alg in algs {
            let t0 = Instant::now();
            let est = track(alg, &cfg.scenario, &cfg.filters, &real, rng)?;
            let secs = t0.elapsed().as_secs_f64();
            let sq: Vec<f64> = est
                .iter()
                .zip(&real.target)
                .map(|(e, x)| (e[0] - x[0]).powi(2) + (e[1] - x[1]).powi(2))
                .collect();
            out.push((sq, secs));
        }
        Ok::<_, HomotopyError>(out)
    })?;
    let mut sq = vec![Vec::with_capacity(runs.len()); algs.len()];
    let mut secs = vec![Vec::with_capacity(runs.len()); algs.len()];
    for run in runs {
        for (a, (s, t)) in run.into_iter().enumerate() {
            sq[a].push(s);
            secs[a].push(t);
        }
    }
    Ok((sq, secs))
}

/// Final squared position errors `e²[alg][r]` of `algs`, one per realisation (for paired
/// comparisons between filters on the same realisations).
///
/// # Errors
/// Invalid settings, or a filter failing on some realisation.
pub fn final_squared_errors(cfg: &RmseConfig, algs: &[Algorithm]) -> Result<Vec<Vec<f64>>> {
    cfg.validate()?;
    let (sq, _) = replicate_errors(cfg, algs)?;
    Ok(sq
        .into_iter()
        .map(|runs| {
            runs.iter()
                .map(|r| *r.last().unwrap_or(&f64::NAN))
                .collect()
        })
        .collect())
}

/// Fig. 3 and the cost table.
///
/// # Errors
/// Invalid settings, or a filter failing on some realisation (the first, in order of r).
pub fn rmse(cfg: &RmseConfig) -> Result<RmseResult> {
    cfg.validate()?;
    let (sq, secs) = replicate_errors(cfg, &Algorithm::ALL)?;
    let mut rm = PerAlgorithm::<Vec<f64>>::default();
    let mut sp = PerAlgorithm::<f64>::default();
    let mut fe = PerAlgorithm::<Vec<f64>>::default();
    for (a, &alg) in Algorithm::ALL.iter().enumerate() {
        *rm.get_mut(alg) = pf_core::metrics::rmse_per_step(&sq[a])?;
        *sp.get_mut(alg) = secs[a].iter().sum::<f64>() / secs[a].len() as f64;
        *fe.get_mut(alg) = sq[a]
            .iter()
            .map(|run| run.last().map_or(f64::NAN, |e2| e2.sqrt()))
            .collect();
    }
    Ok(RmseResult {
        time: (0..cfg.scenario.n_samples)
            .map(|k| k as f64 * cfg.scenario.t)
            .collect(),
        rmse: rm,
        seconds_per_run: sp,
        final_errors: fe,
    })
}
