//! The radar benchmark of `pf-viz bench filter --model radar`: Karlsson et al.'s model
//! (13) with every state in the particle filter (`PPPPPP`), bootstrap proposal, systematic
//! resampling at every step, on pf-core's batch engine.
//!
//! The scenario is [`RadarConfig::default`] (its true trajectory, its `Q`, `R` and prior);
//! the measurements are simulated from stream `(seed, 0)` or given
//! ([`RadarBench::with_observations`]; `pf-viz bench filter --data` reads them from a CSV
//! file with `range` and `azimuth` columns), so that other implementations can run on the
//! same data.

use crate::error::{MpfError, Result};
use crate::mpf::{MpfConfig, SharedMpf};
use crate::radar::{Partition, RadarConfig, RadarObs, RangeAzimuth};
use pf_core::filter::{BatchFilter, Bootstrap};
use pf_core::mc::{Par, stream_rng};

/// One benchmark: the filter and its observations. [`run`](Self::run) runs the filter from
/// the start over all of them.
pub struct RadarBench {
    filter: BatchFilter<SharedMpf<6, 0, 2, RangeAzimuth>, Bootstrap>,
    ys: Vec<Option<RadarObs>>,
}

impl std::fmt::Debug for RadarBench {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RadarBench")
            .field("steps", &self.ys.len())
            .finish_non_exhaustive()
    }
}

impl RadarBench {
    /// `steps` measurements of the default scenario's true trajectory, simulated from
    /// stream `(seed, 0)`, and a filter of `particles` particles whose streams come from
    /// `seed`.
    ///
    /// # Errors
    /// Fewer than two steps, no particles, or more than the machine holds.
    pub fn new(particles: usize, steps: usize, seed: u64) -> Result<Self> {
        let cfg = RadarConfig {
            n_steps: steps,
            ..RadarConfig::default()
        };
        cfg.validate()?;
        let truth = cfg.truth();
        let ys = cfg.measure(&truth, &mut stream_rng(seed, 0));
        Self::with_observations(ys, particles, seed)
    }

    /// The filter on given measurements `ys` (`None` = missing) of the default scenario.
    ///
    /// # Errors
    /// No observation, a non-finite one, no particles, or more than the machine holds.
    pub fn with_observations(
        ys: Vec<Option<RadarObs>>,
        particles: usize,
        seed: u64,
    ) -> Result<Self> {
        if ys.is_empty() {
            return Err(MpfError::TooFewObservations { got: 0, need: 1 });
        }
        crate::model::check_observations(&ys)?;
        let mpf = MpfConfig::new(particles);
        mpf.validate()?;
        let part: Partition = "PPPPPP".parse()?;
        let model = SharedMpf::new(part.model::<6, 0>(&RadarConfig::default())?)?;
        let filter = BatchFilter::new(model, mpf.batch(seed, Par::Rayon))?;
        Ok(Self { filter, ys })
    }

    /// Run pf-core's `simd` copy of the kernels (the same estimate, at that copy's speed).
    pub fn set_simd(&mut self, simd: pf_core::simd::Simd) {
        self.filter.set_simd(simd);
    }

    /// The observations.
    pub fn observations(&self) -> &[Option<RadarObs>] {
        &self.ys
    }

    /// One full run from the start (the same random streams every time), on the caller's
    /// rayon pool; returns the log-likelihood estimate `log p̂(y_{0:T})`.
    ///
    /// # Errors
    /// From the engine (all weights zero).
    pub fn run(&mut self) -> Result<f64> {
        self.filter.reset();
        Ok(self.filter.run(&self.ys)?.log_lik)
    }
}
