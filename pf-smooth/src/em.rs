//! Particle estimates of the AR(1) statistics and the simulation-based EM algorithms built
//! on them: one update of (10)–(12) with particle estimates substituted for the exact
//! expectations, and its iteration, SEM (Celeux & Diebolt 1985, as in Fig. 4) or Monte
//! Carlo EM with a growing number of particles.

use crate::ar1::{Ar1Data, Ar1Statistics, SuffStats, Theta};
use crate::batch::{FixedLagTerms, SmoothedAr1};
use crate::error::{Result, SmoothError};
use crate::forward::ForwardSmoothing;
use pf_core::filter::{BatchConfig, BatchFilter, FilterConfig, ResamplePolicy};
use pf_core::mc::Par;
use pf_core::params::{ParamError, at_least_one};
use pf_core::resample::Resampler;
use rand::Rng;
use serde::{Deserialize, Serialize};

/// Which particle estimator of `τ_n`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Estimator {
    /// The path-space ("joint") estimator, eqs. (6)–(7).
    Joint,
    /// The fixed-lag estimator with lag δ, eqs. (8)–(9).
    FixedLag(usize),
    /// Forward-only (FFBSm) smoothing, O(N²) per step (not in the paper; see
    /// [`forward`](crate::forward)).
    Forward,
}

/// The estimates of `τ_{n,1…4}` that one filter run gives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunStatistics {
    /// The path-space ("joint") estimate, eqs. (6)–(7).
    pub joint: SuffStats,
    /// The fixed-lag estimate, if a lag was given.
    pub fixed_lag: Option<SuffStats>,
    /// The forward-only smoothing estimate, if asked for.
    pub forward: Option<SuffStats>,
}

/// The bootstrap filter of Section 5: `N` particles, systematic resampling at every step.
pub fn paper_filter_config(n_particles: usize) -> FilterConfig {
    FilterConfig {
        n_particles,
        resampler: Resampler::Systematic,
        policy: ResamplePolicy::Always,
    }
}

/// One run of the bootstrap filter at `θ` on `data`, giving the joint estimate of
/// `τ_{n,1…4}` and, if `lag` is given, the fixed-lag estimate from the same particles.
///
/// # Errors
/// Bad `θ`, `N = 0`, `δ = 0`, a filter failure or a non-finite estimate.
pub fn particle_statistics<R: Rng + ?Sized>(
    data: &Ar1Data,
    theta: &Theta,
    filter: FilterConfig,
    lag: Option<usize>,
    rng: &mut R,
) -> Result<(SuffStats, Option<SuffStats>)> {
    let run = run_statistics(data, theta, filter, lag, false, rng)?;
    Ok((run.joint, run.fixed_lag))
}

/// One run of the bootstrap filter at `θ` on `data` (on pf-core's batch engine, with
/// [`SmoothedAr1`]), feeding the joint estimator, the fixed-lag one if `lag` is given, and
/// forward-only smoothing if `forward`. The filter runs on the calling thread
/// ([`Par::Seq`]): replications are what runs in parallel. Its chunk streams come from one
/// `u64` drawn from `rng`.
///
/// # Errors
/// Bad `θ`, `N = 0`, `δ = 0`, a filter failure or a non-finite estimate.
pub fn run_statistics<R: Rng + ?Sized>(
    data: &Ar1Data,
    theta: &Theta,
    filter: FilterConfig,
    lag: Option<usize>,
    forward: bool,
    rng: &mut R,
) -> Result<RunStatistics> {
    let lags: Vec<usize> = lag.into_iter().collect();
    let run = lag_statistics(data, theta, filter, &lags, forward, rng)?;
    Ok(RunStatistics {
        joint: run.joint,
        fixed_lag: run.fixed_lag.first().copied(),
        forward: run.forward,
    })
}

/// The estimates of `τ_{n,1…4}` that one filter run gives for several lags.
#[derive(Debug, Clone, PartialEq)]
pub struct LagStatistics {
    /// The path-space ("joint") estimate, eqs. (6)–(7).
    pub joint: SuffStats,
    /// The fixed-lag estimate of each lag, in the order given.
    pub fixed_lag: Vec<SuffStats>,
    /// The forward-only smoothing estimate, if asked for.
    pub forward: Option<SuffStats>,
}

/// The batch filter's configuration for `filter` on the calling thread, its streams from
/// `seed`.
pub fn batch_config(filter: FilterConfig, seed: u64) -> BatchConfig {
    BatchConfig {
        resampler: filter.resampler,
        policy: filter.policy,
        par: Par::Seq,
        ..BatchConfig::new(filter.n_particles, seed)
    }
}

/// [`run_statistics`] with any number of lags: one run of the batch filter whose model
/// carries a register of the largest lag within the data ([`SmoothedAr1`]), every lag's
/// estimate read from it ([`FixedLagTerms`]). A lag beyond `n` freezes nothing and gives
/// the joint estimate.
///
/// # Errors
/// As [`run_statistics`].
pub fn lag_statistics<R: Rng + ?Sized>(
    data: &Ar1Data,
    theta: &Theta,
    filter: FilterConfig,
    lags: &[usize],
    forward: bool,
    rng: &mut R,
) -> Result<LagStatistics> {
    let n = data.n();
    for &d in lags {
        at_least_one("lag", d)?;
    }
    let register = lags.iter().copied().filter(|&d| d <= n).max().unwrap_or(0);
    let model = SmoothedAr1::new(theta, data, register)?;
    let mut terms = FixedLagTerms::new(&model, lags)?;
    let mut smoother =
        forward.then(|| ForwardSmoothing::new(*model.model(), Ar1Statistics::new(data)));
    let mut pf = BatchFilter::new(model, batch_config(filter, rng.next_u64()))?;
    pf.run_observed(
        None,
        &data.filter_input(),
        &mut (&mut terms, smoother.as_mut()),
    )?;
    let view = pf.view().ok_or(SmoothError::NoSteps {
        what: "batch filter",
    })?;
    let (joint, fixed_lag) = terms.estimates(&view)?;
    let forward = smoother
        .map(|f| f.estimate().and_then(|v| SuffStats::from_slice(n, &v)))
        .transpose()?;
    Ok(LagStatistics {
        joint,
        fixed_lag,
        forward,
    })
}

/// The statistics estimated by one estimator.
///
/// # Errors
/// As [`particle_statistics`].
pub fn estimate_statistics<R: Rng + ?Sized>(
    data: &Ar1Data,
    theta: &Theta,
    filter: FilterConfig,
    estimator: Estimator,
    rng: &mut R,
) -> Result<SuffStats> {
    match estimator {
        Estimator::Joint => Ok(particle_statistics(data, theta, filter, None, rng)?.0),
        Estimator::FixedLag(delta) => {
            let (_, f) = particle_statistics(data, theta, filter, Some(delta), rng)?;
            f.ok_or(SmoothError::NoSteps {
                what: "fixed-lag estimator",
            })
        }
        Estimator::Forward => run_statistics(data, theta, filter, None, true, rng)?
            .forward
            .ok_or(SmoothError::NoSteps {
                what: "forward-only smoothing estimator",
            }),
    }
}

/// How many particles each iteration of a simulation-based EM uses.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ParticleSchedule {
    /// The same `N` at every iteration: SEM as in Fig. 4.
    Fixed(usize),
    /// `N_i = min(⌈n0 · ratio^{i−1}⌉, max)` at iteration i: Monte Carlo EM, whose growing
    /// simulation size makes the iterates settle at the EM fixed point.
    Geometric {
        /// Particles at the first iteration.
        n0: usize,
        /// Growth factor per iteration (≥ 1).
        ratio: f64,
        /// Cap.
        max: usize,
    },
}

impl ParticleSchedule {
    /// Particles at iteration `i ≥ 1`.
    pub fn at(&self, i: usize) -> usize {
        match *self {
            ParticleSchedule::Fixed(n) => n,
            ParticleSchedule::Geometric { n0, ratio, max } => {
                let v = n0 as f64 * ratio.powi(i.saturating_sub(1).min(i32::MAX as usize) as i32);
                if v.is_finite() && v < max as f64 {
                    (v.ceil() as usize).max(1)
                } else {
                    max
                }
            }
        }
    }

    /// Check that every iteration has at least one particle.
    ///
    /// # Errors
    /// `N = 0`, `n0 = 0`, `max < n0`, or a ratio below 1 or not finite.
    pub fn validate(&self) -> Result<()> {
        match *self {
            ParticleSchedule::Fixed(n) => {
                at_least_one("N", n)?;
                Ok(())
            }
            ParticleSchedule::Geometric { n0, ratio, max } => {
                at_least_one("n0", n0)?;
                if !(ratio >= 1.0 && ratio.is_finite()) {
                    return Err(SmoothError::Param(ParamError {
                        name: "ratio",
                        value: ratio,
                        reason: "the growth factor must be finite and at least 1",
                    }));
                }
                if max < n0 {
                    return Err(SmoothError::Param(ParamError {
                        name: "max",
                        value: max as f64,
                        reason: "the cap must be at least n0",
                    }));
                }
                Ok(())
            }
        }
    }
}

/// A simulation-based EM run: SEM (`ParticleSchedule::Fixed`) or MCEM.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StochasticEm {
    /// Particles per iteration.
    pub particles: ParticleSchedule,
    /// Estimator of `τ_n` at each iteration.
    pub estimator: Estimator,
    /// Number of updates I.
    pub iterations: usize,
}

impl StochasticEm {
    /// Check the configuration.
    ///
    /// # Errors
    /// A bad schedule, `δ = 0`, or more iterations than
    /// [`MAX_COUNT`](pf_core::limits::MAX_COUNT).
    pub fn validate(&self) -> Result<()> {
        self.particles.validate()?;
        if let Estimator::FixedLag(d) = self.estimator {
            at_least_one("delta", d)?;
        }
        pf_core::limits::check_count("iterations", self.iterations)?;
        Ok(())
    }

    /// The trajectory `θ_0, …, θ_I` of one chain: at each iteration a fresh bootstrap
    /// filter at the current `θ` estimates `τ_n`, and (10)–(12) give the next `θ`.
    ///
    /// # Errors
    /// [`SmoothError::Iteration`] naming the failed iteration (`chain` is as given).
    pub fn run<R: Rng + ?Sized>(
        &self,
        data: &Ar1Data,
        theta0: &Theta,
        chain: usize,
        rng: &mut R,
    ) -> Result<Vec<Theta>> {
        self.validate()?;
        theta0.validate()?;
        let mut path = pf_core::limits::try_with_capacity("the EM path", self.iterations + 1)?;
        path.push(*theta0);
        for it in 1..=self.iterations {
            let cfg = paper_filter_config(self.particles.at(it));
            let next = estimate_statistics(data, &path[it - 1], cfg, self.estimator, rng)
                .and_then(|s| s.m_step())
                .map_err(|e| SmoothError::Iteration {
                    chain,
                    iteration: it,
                    source: Box::new(e),
                })?;
            path.push(next);
        }
        Ok(path)
    }
}
