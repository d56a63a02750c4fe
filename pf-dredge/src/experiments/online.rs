//! One simulated cycle estimated on line, sample by sample, with the particle cloud of
//! `(Q_o, ρ_o)` kept every few samples: what `dredge.rrd` shows.

use pf_core::mc::{Scale, stream_rng};
use serde::{Deserialize, Serialize};

use super::cycle::{CycleConfig, simulated};
use crate::error::Result;
use crate::estimator::{EstimatorConfig, OnlineEstimator};
use crate::model::{Q_O, RHO_O};
use crate::simulator::Cycle;
use pf_core::params::at_least_one;

/// Which cycle, which filter, and how often to keep the cloud.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OnlineConfig {
    /// The cycle (its seed also seeds the filter, on stream `(seed, 0)`).
    pub cycle: CycleConfig,
    /// The filter (the paper's by default).
    pub filter: EstimatorConfig,
    /// Keep the cloud after every `cloud_every`-th sample (2: about 540 clouds a cycle).
    pub cloud_every: usize,
}

impl Default for OnlineConfig {
    fn default() -> Self {
        OnlineConfig {
            cycle: CycleConfig::default(),
            filter: EstimatorConfig::default(),
            cloud_every: 2,
        }
    }
}

impl OnlineConfig {
    /// The same run at every scale: one cycle costs the same at each.
    pub fn at_scale(_scale: Scale) -> Self {
        Self::default()
    }
}

/// The cloud of `(Q_o, ρ_o)` after sample `k`'s update.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Cloud {
    /// The sample.
    pub k: usize,
    /// One `[Q_o, ρ_o]` per particle.
    pub points: Vec<[f64; 2]>,
}

/// The cycle, the estimate after every sample, and the clouds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OnlineResult {
    /// The simulated cycle (truth and measurements).
    pub cycle: Cycle,
    /// `[Q̂_o, ρ̂_o]` after each sample, as [`OnlineEstimator::push`] emits them.
    pub estimates: Vec<[f64; 2]>,
    /// How often a cloud was kept (the config's `cloud_every`).
    pub cloud_every: usize,
    /// The clouds, every `cloud_every` samples from sample 0, once the filter has started.
    pub clouds: Vec<Cloud>,
}

/// Simulate `cfg.cycle` and estimate it on line with `cfg.filter`, the filter drawing from
/// stream `(seed, 0)` of the cycle's seed.
///
/// # Errors
/// An invalid configuration (`cloud_every` of 0 among them), or a failed filter step.
pub fn online(cfg: &OnlineConfig) -> Result<OnlineResult> {
    let every = at_least_one("cloud_every", cfg.cloud_every)?;
    let cycle = simulated(&cfg.cycle.sim, cfg.cycle.seed)?;
    let data = cycle.to_data();
    let mut estimator = OnlineEstimator::new(&cfg.filter)?;
    let mut rng = stream_rng(cfg.cycle.seed, 0);
    let mut estimates = Vec::with_capacity(data.len());
    let mut clouds = Vec::new();
    for k in 0..data.len() {
        let est = estimator.push(&data.sample(k), &mut rng)?;
        estimates.push([est.q_o, est.rho_o]);
        if k % every == 0
            && let Some(pf) = estimator.filter()
        {
            let points = pf.particles().iter().map(|x| [x[Q_O], x[RHO_O]]).collect();
            clouds.push(Cloud { k, points });
        }
    }
    Ok(OnlineResult {
        cycle,
        estimates,
        cloud_every: every,
        clouds,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulator::SimConfig;

    /// A short cycle: an estimate per sample, a cloud of N particles every other sample, and
    /// the same numbers as the estimator run by hand on the same streams.
    #[test]
    fn the_run_is_the_estimator_sample_by_sample() {
        let cfg = OnlineConfig {
            cycle: CycleConfig {
                sim: SimConfig {
                    t_end: 200.0,
                    ..SimConfig::default()
                },
                seed: 3,
            },
            filter: EstimatorConfig::default().with_particles(50),
            cloud_every: 2,
        };
        let run = online(&cfg).unwrap();
        let n = run.cycle.len();
        assert_eq!(run.estimates.len(), n);
        assert!(!run.clouds.is_empty());
        assert!(
            run.clouds
                .iter()
                .all(|c| c.k % 2 == 0 && c.points.len() == 50)
        );
        let mut by_hand = OnlineEstimator::new(&cfg.filter).unwrap();
        let mut rng = stream_rng(3, 0);
        let data = run.cycle.to_data();
        for k in 0..n {
            let e = by_hand.push(&data.sample(k), &mut rng).unwrap();
            assert_eq!(run.estimates[k], [e.q_o, e.rho_o], "sample {k}");
        }
        let zero = OnlineConfig {
            cloud_every: 0,
            ..cfg
        };
        assert!(online(&zero).is_err());
    }
}
