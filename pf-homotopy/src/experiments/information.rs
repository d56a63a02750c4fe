//! Information brought by each bearing (beyond the paper), the evidence for the turn
//! direction the paper leaves unstated.
//!
//! Section 4.1 says the bearing "received at the end of the observer manoeuvre results in a
//! dramatic increase in information" at the 17th sample. The information a bearing brings
//! is measured here as `½ log(det Σ_pred / det Σ_post)` of the position (nats: the log-ratio
//! of the areas of the error ellipses), with the KL-optimal Gaussian correction
//! ([`Scheme::Direct`](crate::ohf::Scheme::Direct), the HΔE's limit), averaged over
//! realisations, for each turn direction and bearing noise σ: the clockwise turn with
//! σ = ½° (our defaults) puts the largest gain after the initial transient at sample 17.

use serde::{Deserialize, Serialize};

use super::Scale;
use crate::error::{HomotopyError, Result};
use crate::filters::ohf_tracker::OhfTracker;
use crate::model::ScenarioConfig;
use crate::ohf::OhfConfig;
use crate::quadrature::PolarGridConfig;
use pf_core::mc::{Par, try_replicate};
use pf_core::params::ParamError;

/// Settings of the information curves.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InformationConfig {
    /// The base scenario; each curve overrides the turn rate and σ.
    pub scenario: ScenarioConfig,
    /// The polar grid of the correction.
    pub grid: PolarGridConfig,
    /// Realisations averaged (40).
    pub realisations: usize,
    /// Seed.
    pub seed: u64,
    /// The curves: `[turn rate (degrees/s, counter-clockwise positive), σ (degrees)]`.
    pub curves: Vec<[f64; 2]>,
}

impl Default for InformationConfig {
    fn default() -> Self {
        Self {
            scenario: ScenarioConfig::default(),
            grid: PolarGridConfig::default(),
            realisations: 40,
            seed: 3,
            curves: vec![[-30.0, 0.5], [30.0, 0.5], [-30.0, 1.0], [-30.0, 0.25]],
        }
    }
}

impl InformationConfig {
    /// The default's 40 realisations at `Default` and `Full`, 4 at `Quick`.
    pub fn at_scale(scale: Scale) -> Self {
        Self {
            realisations: if scale == Scale::Quick { 4 } else { 40 },
            ..Self::default()
        }
    }
}

/// Mean information per bearing, one curve per (turn rate, σ).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InformationResult {
    /// Sampling instants `k = 2, …, K`.
    pub sample: Vec<usize>,
    /// The curves' `[turn rate, σ]`.
    pub curves: Vec<[f64; 2]>,
    /// `gain[c][i]`: mean `½ log det Σ_pred / det Σ_post` at `sample[i]` for curve `c`.
    pub gain: Vec<Vec<f64>>,
}

impl InformationResult {
    /// The sample of curve `c` with the largest gain from sample `from` on (past the
    /// initial transient, when the first bearings shrink the diffuse prior).
    pub fn peak(&self, c: usize, from: usize) -> Option<usize> {
        self.sample
            .iter()
            .zip(&self.gain[c])
            .filter(|(k, _)| **k >= from)
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(k, _)| *k)
    }
}

/// Run the curves.
///
/// # Errors
/// Invalid settings or a failing correction.
pub fn information(cfg: &InformationConfig) -> Result<InformationResult> {
    if cfg.realisations == 0 {
        return Err(HomotopyError::Param(ParamError {
            name: "realisations R",
            value: 0.0,
            reason: "at least one realisation is needed",
        }));
    }
    let mut gain = Vec::new();
    for &[turn, sigma] in &cfg.curves {
        let sc = ScenarioConfig {
            turn_rate_deg: turn,
            sigma_deg: sigma,
            ..cfg.scenario
        };
        sc.validate()?;
        let runs = try_replicate(cfg.seed, cfg.realisations, Par::Rayon, |_, rng| {
            let real = sc.simulate(rng)?;
            let obs = &real.observer;
            let mut tr = OhfTracker::new(
                &sc,
                OhfConfig::direct(),
                cfg.grid,
                real.bearings[0],
                obs[0].pos,
            )?;
            let mut out = Vec::with_capacity(real.bearings.len() - 1);
            for (k, (&y, o)) in real.bearings.iter().zip(obs).enumerate().skip(1) {
                tr.predict();
                let before = tr.position().cov.determinant();
                tr.update(k + 1, y, o.pos)?;
                out.push(0.5 * (before / tr.position().cov.determinant()).ln());
            }
            Ok::<_, HomotopyError>(out)
        })?;
        let n = runs.len() as f64;
        gain.push(
            (0..cfg.scenario.n_samples - 1)
                .map(|i| runs.iter().map(|r| r[i]).sum::<f64>() / n)
                .collect(),
        );
    }
    Ok(InformationResult {
        sample: (2..=cfg.scenario.n_samples).collect(),
        curves: cfg.curves.clone(),
        gain,
    })
}
