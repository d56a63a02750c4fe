//! Fig. 2: error ellipses of the OHF parameterisation θ_k(λ) at one sampling instant.

use serde::{Deserialize, Serialize};

use super::Scale;
use crate::error::{HomotopyError, Result};
use crate::filters::ohf_tracker::OhfTracker;
use crate::model::ScenarioConfig;
use crate::ohf::OhfConfig;
use crate::param::Gaussian;
use crate::quadrature::PolarGridConfig;
use pf_core::mc::stream_rng;
use pf_core::params::ParamError;

/// Settings of Fig. 2.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EllipsesConfig {
    /// The scenario.
    pub scenario: ScenarioConfig,
    /// The homotopy (the paper shows the OHF, i.e. the HΔE).
    pub ohf: OhfConfig,
    /// The polar grid.
    pub grid: PolarGridConfig,
    /// Sampling instant K (17).
    pub step: usize,
    /// Seed of the realisation (realisation 0 of this seed).
    pub seed: u64,
    /// The λ values shown (0, ¼, ½, ¾, 1). Each joins the λ grid as a node, so that θ(λ)
    /// is recorded there exactly rather than interpolated; the extra nodes refine the Euler
    /// integration a little, so the list moves the λ = 1 ellipse slightly (its major
    /// semi-axis is 1950.02 m with this list, 1949.92 m with `[1.0]` alone).
    pub lambda: Vec<f64>,
    /// Probability mass inside each ellipse (unstated; 0.95).
    pub mass: f64,
}

impl Default for EllipsesConfig {
    fn default() -> Self {
        Self {
            scenario: ScenarioConfig::default(),
            ohf: OhfConfig::ohf(),
            grid: PolarGridConfig::default(),
            step: 17,
            seed: 0,
            lambda: vec![0.0, 0.25, 0.5, 0.75, 1.0],
            mass: 0.95,
        }
    }
}

impl EllipsesConfig {
    /// The paper's settings at every scale: one realisation costs the same at each.
    pub fn at_scale(_scale: Scale) -> Self {
        Self::default()
    }

    /// Check the settings.
    pub fn validate(&self) -> Result<()> {
        self.scenario.validate()?;
        self.ohf.validate()?;
        self.grid.validate()?;
        if self.step < 2 || self.step > self.scenario.n_samples {
            return Err(HomotopyError::InstantOutOfRange {
                k: self.step,
                n_samples: self.scenario.n_samples,
            });
        }
        if self.lambda.is_empty() {
            return Err(HomotopyError::Param(ParamError {
                name: "lambda",
                value: 0.0,
                reason: "give at least one λ in [0, 1]",
            }));
        }
        for &l in &self.lambda {
            if !(0.0..=1.0).contains(&l) {
                return Err(HomotopyError::Param(ParamError {
                    name: "lambda",
                    value: l,
                    reason: "each λ must lie in [0, 1]",
                }));
            }
        }
        if !(self.mass > 0.0 && self.mass < 1.0) {
            return Err(HomotopyError::Param(ParamError {
                name: "mass",
                value: self.mass,
                reason: "must lie in (0, 1)",
            }));
        }
        Ok(())
    }
}

/// One error ellipse, in the CLI contract's shape.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Ellipse {
    /// Centre (the mean of θ_k(λ)).
    pub center: [f64; 2],
    /// Semi-axes, major first, m.
    pub semi_axes: [f64; 2],
    /// Angle of the major axis from the x-axis, rad, in (−π/2, π/2].
    pub angle: f64,
}

/// Fig. 2 / `pf-viz homotopy ellipses --json`: `{"truth", "lambda", "ellipses"}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EllipsesResult {
    /// True target position at instant K.
    pub truth: [f64; 2],
    /// The λ values, in the order of `ellipses`.
    pub lambda: Vec<f64>,
    /// One ellipse per λ.
    pub ellipses: Vec<Ellipse>,
}

/// Run the OHF on realisation 0 of `seed` up to instant K and record θ_K(λ).
///
/// # Errors
/// Invalid settings or a failure of the filter.
pub fn ellipses(cfg: &EllipsesConfig) -> Result<EllipsesResult> {
    cfg.validate()?;
    let sc = &cfg.scenario;
    let real = sc.simulate(&mut stream_rng(cfg.seed, 0))?;
    let mut tr = OhfTracker::new(
        sc,
        cfg.ohf,
        cfg.grid,
        real.bearings[0],
        real.observer[0].pos,
    )?;
    for k in 2..cfg.step {
        tr.predict();
        tr.update(k, real.bearings[k - 1], real.observer[k - 1].pos)?;
    }
    tr.predict();
    let mut recorded: Vec<(f64, Gaussian<2>)> = Vec::new();
    tr.update_recording(
        cfg.step,
        real.bearings[cfg.step - 1],
        real.observer[cfg.step - 1].pos,
        &cfg.lambda,
        |l, g| recorded.push((l, *g)),
    )?;
    let mut out = Vec::with_capacity(cfg.lambda.len());
    for &l in &cfg.lambda {
        let (_, g) = recorded
            .iter()
            .min_by(|a, b| (a.0 - l).abs().total_cmp(&(b.0 - l).abs()))
            .ok_or(HomotopyError::Param(ParamError {
                name: "lambda",
                value: l,
                reason: "not reached by the flow",
            }))?;
        let e = pf_core::gaussian::error_ellipse(
            [g.mean[0], g.mean[1]],
            [
                [g.cov[(0, 0)], g.cov[(0, 1)]],
                [g.cov[(1, 0)], g.cov[(1, 1)]],
            ],
            cfg.mass,
        )?;
        out.push(Ellipse {
            center: e.centre,
            semi_axes: e.semi_axes,
            angle: e.angle,
        });
    }
    let x = real.target[cfg.step - 1];
    Ok(EllipsesResult {
        truth: [x[0], x[1]],
        lambda: cfg.lambda.clone(),
        ellipses: out,
    })
}
