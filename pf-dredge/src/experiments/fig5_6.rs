//! Figs. 5–6: the PF on simulated data, phase 3 only, and the distribution of its residuals.

use super::{Scale, filter_seed, phase3};
use crate::error::Result;
use crate::estimator::{EstimatorConfig, residuals_of, run_filter};
use crate::simulator::SimConfig;
use pf_core::mc::stream_rng;
use pf_core::metrics::{Histogram, ResidualSummary};
use serde::{Deserialize, Serialize};

/// Settings of Figs. 5–6.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fig56Config {
    /// The simulator.
    pub sim: SimConfig,
    /// The filter (the paper's N = 1000, σ(ε_x), σ(ε_y), N_T = 900).
    pub filter: EstimatorConfig,
    /// Seed of the cycle and the filter run.
    pub seed: u64,
    /// Histogram bins of Fig. 6.
    pub bins: usize,
}

impl Default for Fig56Config {
    fn default() -> Self {
        Fig56Config {
            sim: SimConfig::default(),
            filter: EstimatorConfig::default(),
            seed: 1,
            bins: 30,
        }
    }
}

impl Fig56Config {
    /// The preset of a [`Scale`]: `Quick` uses 300 particles, the others the paper's 1000.
    pub fn at_scale(scale: Scale) -> Self {
        let mut c = Self::default();
        if scale == Scale::Quick {
            c.filter = c.filter.with_particles(300);
        }
        c
    }
}

/// Residual statistics of one signal beside the paper's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ResidualReport {
    /// Ours: mean, std, max |·| of truth − estimate.
    pub ours: ResidualSummary,
    /// Range (max − min) of our true signal in phase 3.
    pub signal_range: f64,
    /// `ours.std / signal_range`.
    pub relative_std: f64,
    /// The paper's mean and std (Section V-B).
    pub paper: PaperResiduals,
}

/// The paper's reported residual figures.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PaperResiduals {
    /// Mean.
    pub mean: f64,
    /// Standard deviation.
    pub std: f64,
    /// Largest |error|, "about".
    pub max_abs_about: f64,
    /// The paper's nominal range (max |error| is "about 10 %" of it).
    pub nominal_range: f64,
}

/// Everything Figs. 5 and 6 show.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fig56Result {
    /// Phase-3 sample times (s).
    pub t: Vec<f64>,
    /// Simulated `Q_o` (thin line).
    pub q_o_true: Vec<f64>,
    /// Estimated `Q̂_o` (thick line).
    pub q_o_hat: Vec<f64>,
    /// Simulated `ρ_o`.
    pub rho_o_true: Vec<f64>,
    /// Estimated `ρ̂_o`.
    pub rho_o_hat: Vec<f64>,
    /// `Q_o` residual statistics.
    pub q_o: ResidualReport,
    /// `ρ_o` residual statistics.
    pub rho_o: ResidualReport,
    /// Fig. 6, left: `Q_o` residuals.
    pub q_o_hist: Histogram,
    /// Fig. 6, right: `ρ_o` residuals.
    pub rho_o_hist: Histogram,
}

fn report(truth: &[f64], r: &[f64], paper: PaperResiduals) -> Result<ResidualReport> {
    let ours = ResidualSummary::new(r)?;
    let lo = truth.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = truth.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let signal_range = hi - lo;
    Ok(ResidualReport {
        ours,
        signal_range,
        relative_std: if signal_range > 0.0 {
            ours.std / signal_range
        } else {
            0.0
        },
        paper,
    })
}

/// Figs. 5–6: simulate a cycle, run the PF on its noisy measurements, and compare in phase 3.
///
/// # Errors
/// Invalid settings, a cycle that never reaches phase 3, or a failed filter step.
pub fn fig5_6(cfg: &Fig56Config) -> Result<Fig56Result> {
    let c = super::cycle::simulated(&cfg.sim, cfg.seed)?;
    let p3 = phase3(&c)?;
    let run = run_filter(
        &c.to_data(),
        &cfg.filter,
        &mut stream_rng(filter_seed(cfg.seed), 0),
    )?;
    let e = &run.estimates;
    let sl = |v: &[f64]| v[p3.clone()].to_vec();
    let (q_true, q_hat) = (sl(&c.q_o), sl(&e.q_o));
    let (r_true, r_hat) = (sl(&c.rho_o), sl(&e.rho_o));
    let some = |v: &[f64]| v.iter().copied().map(Some).collect::<Vec<_>>();
    let rq = residuals_of(&some(&q_true), &q_hat);
    let rr = residuals_of(&some(&r_true), &r_hat);
    Ok(Fig56Result {
        t: sl(&c.t),
        q_o: report(
            &q_true,
            &rq,
            PaperResiduals {
                mean: -0.023,
                std: 0.345,
                max_abs_about: 1.0,
                nominal_range: 10.0,
            },
        )?,
        rho_o: report(
            &r_true,
            &rr,
            PaperResiduals {
                mean: 3.613,
                std: 13.226,
                max_abs_about: 40.0,
                nominal_range: 400.0,
            },
        )?,
        q_o_hist: Histogram::new(&rq, cfg.bins)?,
        rho_o_hist: Histogram::new(&rr, cfg.bins)?,
        q_o_true: q_true,
        q_o_hat: q_hat,
        rho_o_true: r_true,
        rho_o_hat: r_hat,
    })
}
