//! Fig. 7: the PF against the direct computation (15)–(16) on the same measurements.
//!
//! The paper shows this on real data, which we do not have; we use a simulated cycle, which
//! also lets us report both methods' residuals against the truth.

use super::{Scale, filter_seed, phase3};
use crate::direct::{DirectConfig, direct_computation};
use crate::error::Result;
use crate::estimator::{EstimatorConfig, Residuals, run_filter, summarise};
use crate::simulator::SimConfig;
use pf_core::mc::stream_rng;
use serde::{Deserialize, Serialize};

/// Settings of Fig. 7.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fig7Config {
    /// The simulator.
    pub sim: SimConfig,
    /// The filter.
    pub filter: EstimatorConfig,
    /// The direct computation (0.001 Hz zero-phase low-pass).
    pub direct: DirectConfig,
    /// Seed.
    pub seed: u64,
}

impl Default for Fig7Config {
    fn default() -> Self {
        Fig7Config {
            sim: SimConfig::default(),
            filter: EstimatorConfig::default(),
            direct: DirectConfig::default(),
            seed: 1,
        }
    }
}

impl Fig7Config {
    /// The preset of a [`Scale`]: `Quick` uses 300 particles.
    pub fn at_scale(scale: Scale) -> Self {
        let mut c = Self::default();
        if scale == Scale::Quick {
            c.filter = c.filter.with_particles(300);
        }
        c
    }
}

/// Everything Fig. 7 shows, over the whole cycle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fig7Result {
    /// Sample times (s).
    pub t: Vec<f64>,
    /// First phase-3 sample.
    pub phase3_start: usize,
    /// PF `Q̂_o` (thick line).
    pub q_o_pf: Vec<f64>,
    /// PF `ρ̂_o`.
    pub rho_o_pf: Vec<f64>,
    /// Direct `Q̄_o` (thin line); `None` where undefined.
    pub q_o_direct: Vec<Option<f64>>,
    /// Direct `ρ̄_o`; `None` where undefined.
    pub rho_o_direct: Vec<Option<f64>>,
    /// True `Q_o`.
    pub q_o_true: Vec<f64>,
    /// True `ρ_o`.
    pub rho_o_true: Vec<f64>,
    /// PF residuals in phase 3.
    pub pf_residuals: Residuals,
    /// Direct-computation residuals in phase 3 (where defined).
    pub direct_residuals: Residuals,
}

/// Fig. 7.
///
/// # Errors
/// Invalid settings, no phase 3, or a failed filter step.
pub fn fig7(cfg: &Fig7Config) -> Result<Fig7Result> {
    let c = super::cycle::simulated(&cfg.sim, cfg.seed)?;
    let p3 = phase3(&c)?;
    let data = c.to_data();
    let direct = direct_computation(&data, &cfg.direct)?;
    let run = run_filter(
        &data,
        &cfg.filter,
        &mut stream_rng(filter_seed(cfg.seed), 0),
    )?;
    let e = run.estimates;
    let truth = |v: &[f64]| v[p3.clone()].iter().copied().map(Some).collect::<Vec<_>>();
    // Direct residuals only where the direct value is defined.
    let masked = |tr: &[f64], d: &[Option<f64>]| -> (Vec<Option<f64>>, Vec<f64>) {
        p3.clone()
            .map(|k| (d[k].map(|_| tr[k]), d[k].unwrap_or(0.0)))
            .unzip()
    };
    let (tq, dq) = masked(&c.q_o, &direct.q_o);
    let (tr, dr) = masked(&c.rho_o, &direct.rho_o);
    Ok(Fig7Result {
        t: c.t.clone(),
        phase3_start: p3.start,
        pf_residuals: Residuals {
            q_o: summarise(&truth(&c.q_o), &e.q_o[p3.clone()])?,
            rho_o: summarise(&truth(&c.rho_o), &e.rho_o[p3.clone()])?,
        },
        direct_residuals: Residuals {
            q_o: summarise(&tq, &dq)?,
            rho_o: summarise(&tr, &dr)?,
        },
        q_o_pf: e.q_o,
        rho_o_pf: e.rho_o,
        q_o_direct: direct.q_o,
        rho_o_direct: direct.rho_o,
        q_o_true: c.q_o,
        rho_o_true: c.rho_o,
    })
}
