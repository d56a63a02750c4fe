//! The bearings-only PF as a benchmark (`pf-viz bench filter --model bearings`): Section 4's
//! scenario, one realisation, the PF with the linearised optimal proposal on the batch
//! filter.

use crate::error::Result;
use crate::filters::pf::{BotFilter, BotModel, particle_filter};
use crate::model::ScenarioConfig;
use pf_core::mc::{Par, stream_rng};

/// One realisation of Morelande et al.'s scenario (Fig. 1, the default
/// [`ScenarioConfig`] with `steps` sampling instants) and the PF that filters it.
pub struct BearingsBench {
    filter: BotFilter,
    /// The bearings as the filter takes them: `None` at `k = 1` (it builds the prior).
    ys: Vec<Option<f64>>,
}

impl BearingsBench {
    /// `particles` particles over `steps` sampling instants; the realisation is simulated
    /// from the stream `(seed, 0)` and the filter's chunk streams derive from `seed`.
    ///
    /// # Errors
    /// `particles = 0`, `steps < 2`, or sizes past pf-core's limits.
    pub fn new(particles: usize, steps: usize, seed: u64) -> Result<Self> {
        let scenario = ScenarioConfig {
            n_samples: steps,
            ..ScenarioConfig::default()
        };
        let real = scenario.simulate(&mut stream_rng(seed, 0))?;
        let observer = real.observer.iter().map(|o| o.pos).collect();
        let model = BotModel::new(&scenario, observer, real.bearings[0])?;
        let filter = particle_filter(model, particles, seed, Par::Rayon)?;
        let ys = real
            .bearings
            .iter()
            .enumerate()
            .map(|(k, &y)| (k > 0).then_some(y))
            .collect();
        Ok(BearingsBench { filter, ys })
    }

    /// Run pf-core's `simd` copy of the kernels (the same estimate, at that copy's speed).
    pub fn set_simd(&mut self, simd: pf_core::simd::Simd) {
        self.filter.set_simd(simd);
    }

    /// A full run from the start (chunks on the caller's rayon pool); the log-likelihood
    /// estimate `log p̂(y_2, …, y_K | y_1)`.
    ///
    /// # Errors
    /// A collapse of the weights.
    pub fn run(&mut self) -> Result<f64> {
        Ok(self.filter.run(&self.ys)?.log_lik)
    }
}
