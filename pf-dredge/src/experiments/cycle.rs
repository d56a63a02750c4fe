//! Figs. 3–4: one simulated loading cycle (inputs, `V_t`, `m_t`, `h_o`, phase boundaries).

use crate::error::Result;
use crate::simulator::{Cycle, SimConfig, simulate};
use serde::{Deserialize, Serialize};

/// Which cycle to simulate.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CycleConfig {
    /// The simulator.
    pub sim: SimConfig,
    /// Seed of the input fluctuations and measurement noise.
    pub seed: u64,
}

/// Figs. 3 and 4: the [`Cycle`] holds `Q_i`, `ρ_i` (Fig. 3), `V_t`, `m_t`, `h_o` and the
/// phase starts (Fig. 4), true and measured.
///
/// # Errors
/// An invalid simulator configuration.
pub fn cycle(cfg: &CycleConfig) -> Result<Cycle> {
    simulate(&cfg.sim, cfg.seed)
}
