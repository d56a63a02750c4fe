//! The engine's own experiment, behind `pf-viz report`'s core section: the genealogy of a
//! bootstrap filter (Cappé & Moulines, Fig. 1) on simulated data.
//!
//! The noisy AR(1) model `X_{k+1} = φ X_k + σ U_k`, `Y_k = X_k + ρ V_k` with the paper's
//! `φ = 0.98, σ = 0.2, ρ = 1` (Section 5), stationary initial law, `n = 100` (observations
//! `y_0 … y_n`), filtered by the bootstrap filter with `N = 50` particles and multinomial
//! resampling at every step. The data are drawn from stream `data_stream` of the seed and
//! the filter from stream `filter_stream`, so changing the filter never changes the data.

use crate::error::Result;
use crate::filter::{FilterConfig, ParticleFilter, ResamplePolicy};
use crate::genealogy::{Genealogy, GenealogyData, RecordedRun};
use crate::mc::stream_rng;
use crate::models::NoisyAr1;
use crate::resample::Resampler;
use serde::{Deserialize, Serialize};

/// The experiment's configuration; `Default` is the paper's model with the figure's `N`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GenealogyConfig {
    /// φ, the AR coefficient.
    pub phi: f64,
    /// σ, the state noise standard deviation.
    pub sigma: f64,
    /// ρ, the observation noise standard deviation.
    pub rho: f64,
    /// `n`: observations `y_0 … y_n`, so `n + 1` filter steps.
    pub n: usize,
    /// The particle filter.
    pub filter: FilterConfig,
    /// Random stream (under `seed`) of the simulated data.
    pub data_stream: u64,
    /// Random stream (under `seed`) of the filter.
    pub filter_stream: u64,
    /// The seed both streams derive from (the report's master seed).
    #[serde(default)]
    pub seed: u64,
}

impl Default for GenealogyConfig {
    fn default() -> Self {
        GenealogyConfig {
            phi: 0.98,
            sigma: 0.2,
            rho: 1.0,
            n: 100,
            filter: FilterConfig {
                n_particles: 50,
                resampler: Resampler::Multinomial,
                policy: ResamplePolicy::Always,
            },
            data_stream: 0,
            filter_stream: 1,
            seed: 0,
        }
    }
}

/// Every number behind the genealogy and ESS figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GenealogyResult {
    /// The configuration that was run (its seed included).
    pub config: GenealogyConfig,
    /// The filter's log-likelihood estimate `log p̂(y_{0:n})`.
    pub log_lik: f64,
    /// Most recent step at which all surviving lineages share one ancestor.
    pub coalescence_time: Option<usize>,
    /// Number of distinct surviving ancestors at each step.
    pub surviving_per_step: Vec<usize>,
    /// Effective sample size at each step (after reweighting).
    pub ess: Vec<f64>,
    /// Whether each step resampled.
    pub resampled: Vec<bool>,
    /// The simulated observations `y_k`.
    pub observations: Vec<f64>,
    /// The genealogy figure's data (positions, ancestors, survival flags, true states).
    pub genealogy: GenealogyData,
    /// Normalised weights `W_k^i`.
    pub weights: Vec<Vec<f64>>,
    /// The engine's genealogy (for recordings).
    #[serde(skip)]
    pub lineage: Genealogy,
}

/// Simulate the data and run the filter with its genealogy recorded.
///
/// # Errors
/// A bad model parameter or filter configuration, or a filter failure (weight collapse).
pub fn genealogy(config: &GenealogyConfig) -> Result<GenealogyResult> {
    let seed = config.seed;
    let model = NoisyAr1::new(config.phi, config.sigma, config.rho)?;
    let (xs, ys) = model.simulate(config.n, &mut stream_rng(seed, config.data_stream));
    let obs: Vec<Option<f64>> = ys.iter().copied().map(Some).collect();
    let mut pf = ParticleFilter::bootstrap(model, config.filter)?;
    let run = RecordedRun::of(
        &mut pf,
        &obs,
        &mut stream_rng(seed, config.filter_stream),
        Some(xs),
    )?;
    Ok(GenealogyResult {
        config: *config,
        log_lik: run.log_lik,
        coalescence_time: run.paths.coalescence_time,
        surviving_per_step: run.lineage.surviving_counts(),
        ess: run.ess,
        resampled: run.resampled,
        observations: ys,
        genealogy: run.paths,
        weights: run.weights,
        lineage: run.lineage,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The recorded run is internally consistent: one row per step, the survivors counted
    /// from the same genealogy the paths carry, resampling before every step but the first
    /// (which has no particles to resample) as configured, and a coalescence time at which
    /// exactly one ancestor survives.
    #[test]
    fn the_default_run_records_a_consistent_genealogy() {
        let config = GenealogyConfig::default();
        let r = genealogy(&GenealogyConfig { seed: 7, ..config }).unwrap();
        let steps = config.n + 1;
        assert_eq!(r.observations.len(), steps);
        assert_eq!(r.genealogy.n_steps(), steps);
        assert_eq!(r.genealogy.n_particles(), config.filter.n_particles);
        assert_eq!(r.weights.len(), steps);
        assert_eq!(r.ess.len(), steps);
        assert!(!r.resampled[0] && r.resampled[1..].iter().all(|&b| b));
        for (k, s) in r.genealogy.surviving.iter().enumerate() {
            assert_eq!(s.iter().filter(|&&b| b).count(), r.surviving_per_step[k]);
        }
        // Every final particle survives. Under neutral multinomial resampling the lineages of
        // N = 50 particles coalesce about 2N = 100 steps back, and unequal weights make it
        // sooner: with this seed, at step 53 of 0…100.
        assert_eq!(r.surviving_per_step[steps - 1], config.filter.n_particles);
        let tc = r.coalescence_time.expect("the lineages coalesce");
        assert_eq!(r.surviving_per_step[tc], 1);
        assert!(r.surviving_per_step[tc + 1..].iter().all(|&c| c > 1));
        assert!(r.log_lik.is_finite());
        assert_eq!(r.genealogy.truth.as_ref().map(Vec::len), Some(steps));
    }

    /// The data come from their own stream: a different filter stream changes the filter's
    /// particles, never the observations.
    #[test]
    fn the_filter_stream_never_changes_the_data() {
        let config = GenealogyConfig {
            seed: 3,
            ..GenealogyConfig::default()
        };
        let a = genealogy(&config).unwrap();
        let b = genealogy(&GenealogyConfig {
            filter_stream: 9,
            ..config
        })
        .unwrap();
        assert_eq!(a.observations, b.observations);
        assert_eq!(a.genealogy.truth, b.genealogy.truth);
        assert_ne!(a.genealogy.positions, b.genealogy.positions);
    }

    /// A bad parameter is an error, not a panic.
    #[test]
    fn a_bad_parameter_is_an_error() {
        let bad = GenealogyConfig {
            sigma: -1.0,
            ..GenealogyConfig::default()
        };
        assert!(genealogy(&bad).is_err());
    }
}
