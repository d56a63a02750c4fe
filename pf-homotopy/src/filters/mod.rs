//! The four filters of Section 4: OHF and AOHF ([`ohf_tracker`]), UKF-LPC ([`ukf_lpc`]) and
//! the PF with the linearised optimal importance density ([`pf`]), plus a common driver.

pub mod ohf_tracker;
pub mod pf;
pub mod ukf_lpc;

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::model::{Realisation, ScenarioConfig};
use crate::ohf::OhfConfig;
use crate::quadrature::PolarGridConfig;
use pf_core::kalman::UkfParams;
use pf_core::params::ParamError;
use rand::{Rng, RngExt};

/// The algorithms compared in Fig. 3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Algorithm {
    /// The OHF (HΔE).
    #[serde(rename = "OHF")]
    Ohf,
    /// The approximate OHF (AHΔE).
    #[serde(rename = "AOHF")]
    Aohf,
    /// The unscented KF in log-polar coordinates.
    #[serde(rename = "UKF-LPC")]
    UkfLpc,
    /// The PF with the linearised optimal importance density.
    #[serde(rename = "PF")]
    Pf,
}

impl Algorithm {
    /// All four, in the order of the paper's legend.
    pub const ALL: [Algorithm; 4] = [
        Algorithm::UkfLpc,
        Algorithm::Pf,
        Algorithm::Ohf,
        Algorithm::Aohf,
    ];

    /// The name the CLI contract uses.
    pub fn name(self) -> &'static str {
        match self {
            Algorithm::Ohf => "OHF",
            Algorithm::Aohf => "AOHF",
            Algorithm::UkfLpc => "UKF-LPC",
            Algorithm::Pf => "PF",
        }
    }
}

/// Settings of every filter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilterSettings {
    /// The OHF's correction (HΔE).
    pub ohf: OhfConfig,
    /// The AOHF's correction (AHΔE).
    pub aohf: OhfConfig,
    /// The polar grid of both.
    pub grid: PolarGridConfig,
    /// UKF-LPC sigma-point scaling.
    pub ukf: UkfParams,
    /// PF sample size N (100 000).
    pub particles: usize,
}

impl Default for FilterSettings {
    fn default() -> Self {
        Self {
            ohf: OhfConfig::ohf(),
            aohf: OhfConfig::aohf(),
            grid: PolarGridConfig::default(),
            ukf: UkfParams::default(),
            particles: 100_000,
        }
    }
}

impl FilterSettings {
    /// Check every setting.
    pub fn validate(&self) -> Result<()> {
        self.ohf.validate()?;
        self.aohf.validate()?;
        self.grid.validate()?;
        if self.particles == 0 {
            return Err(crate::error::HomotopyError::Param(ParamError {
                name: "N (particles)",
                value: 0.0,
                reason: "the PF needs at least one particle",
            }));
        }
        pf_core::kalman::Ukf::new(self.ukf)?;
        Ok(())
    }
}

/// Run `alg` over a realisation's bearings and return its position estimates at
/// `k = 1, …, K` (at `k = 1`, the prior mean built from `y_1`).
///
/// # Errors
/// Bad settings or inputs, or a failure of the filter (see each filter).
pub fn track<R: Rng + ?Sized>(
    alg: Algorithm,
    scenario: &ScenarioConfig,
    settings: &FilterSettings,
    realisation: &Realisation,
    rng: &mut R,
) -> Result<Vec<[f64; 2]>> {
    scenario.validate()?;
    settings.validate()?;
    Realisation::validate_inputs(&realisation.observer, &realisation.bearings)?;
    match alg {
        Algorithm::Ohf => ohf_tracker::run(scenario, &settings.ohf, &settings.grid, realisation),
        Algorithm::Aohf => ohf_tracker::run(scenario, &settings.aohf, &settings.grid, realisation),
        Algorithm::UkfLpc => ukf_lpc::run(scenario, settings.ukf, realisation),
        Algorithm::Pf => pf::run(scenario, settings.particles, realisation, rng.random()),
    }
}
