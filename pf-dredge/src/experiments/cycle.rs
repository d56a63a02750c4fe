//! Figs. 3–4: one simulated loading cycle (inputs, `V_t`, `m_t`, `h_o`, phase boundaries).

use super::Scale;
use crate::error::Result;
use crate::simulator::{Cycle, SimConfig, simulate_streams};
use pf_core::mc::stream_rng;
use serde::{Deserialize, Serialize};

/// Which cycle to simulate.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CycleConfig {
    /// The simulator.
    pub sim: SimConfig,
    /// Seed: the input fluctuations use stream `(seed, 0)`, the measurement noise
    /// `(seed, 1)`.
    pub seed: u64,
}

impl CycleConfig {
    /// The default simulator at every scale: one cycle costs the same at each.
    pub fn at_scale(_scale: Scale) -> Self {
        Self::default()
    }
}

/// Figs. 3 and 4: the [`Cycle`] holds `Q_i`, `ρ_i` (Fig. 3), `V_t`, `m_t`, `h_o` and the
/// phase starts (Fig. 4), true and measured.
///
/// # Errors
/// An invalid simulator configuration.
pub fn cycle(cfg: &CycleConfig) -> Result<Cycle> {
    simulated(&cfg.sim, cfg.seed)
}

/// The cycle of `sim` under `seed`, as every experiment simulates it.
pub(crate) fn simulated(sim: &SimConfig, seed: u64) -> Result<Cycle> {
    simulate_streams(sim, &mut stream_rng(seed, 0), &mut stream_rng(seed, 1))
}
