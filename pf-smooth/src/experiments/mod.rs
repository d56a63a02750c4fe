//! The paper's experiments, each a function from a serde configuration to a serde result:
//! replicated EM updates (Figs. 2–3), SEM chains over exact EM (Fig. 4), the
//! Fisher-identity score, the lag sweep (not in the paper), Fig. 1's genealogy, and the
//! whole of Section 5 at a [`Scale`] ([`smooth()`]).
//!
//! Each configuration says where its observations come from ([`Observations`]: given, or
//! simulated from Section 5's model on a stream of a seed). The function validates the
//! configuration, then the data, and returns data whose JSON is the
//! `pf-viz smooth em|sem|score` contract. Replication `r` (or chain `c`) uses the stream
//! `(seed, r)`, so results do not depend on the thread count.

mod coalescence;
mod paper;

pub use coalescence::{
    AncestorLog, CoalescenceConfig, CoalescenceResult, CoalescenceRow, CoalescenceRun,
    CoalescenceSetting, QUANTILE_LEVELS, coalescence, coalescence_delay,
};

pub use paper::{
    Fig1Config, Fig1Result, FixedLagClaim, ForwardReference, SmoothConfig, SmoothResult, Spread,
    UpdateRuns, fig1, fixed_lag_claim, forward_reference, smooth, smooth_with_progress,
};
pub use pf_core::mc::Scale;

use crate::ar1::{Ar1Data, SuffStats, Theta, ThetaSamples};
use crate::em::{
    Estimator, ParticleSchedule, StochasticEm, lag_statistics, paper_filter_config,
    particle_statistics, run_statistics,
};
use crate::error::Result;
use crate::exact::{exact_em, exact_em_step, exact_statistics};
use pf_core::mc::{Par, stream_rng, try_replicate};
use pf_core::models::NoisyAr1;
use pf_core::params::at_least_one;
use serde::{Deserialize, Serialize};

/// Where an experiment's observations `Y_0…Y_n` come from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Observations {
    /// Given values, at least `Y_0, Y_1`.
    Given(Vec<f64>),
    /// `n + 1` observations of Section 5's model at `truth`, `X_0` from its stationary law,
    /// drawn from the stream `(seed, stream)`.
    Simulated {
        /// The data-generating θ.
        truth: Theta,
        /// The index of the last observation.
        n: usize,
        /// The seed.
        seed: u64,
        /// The stream under `seed`.
        stream: u64,
    },
}

impl Default for Observations {
    /// [`Observations::paper`] under seed 0.
    fn default() -> Self {
        Observations::paper(0)
    }
}

impl Observations {
    /// Section 5's data: `n = 500` at φ = 0.98, σ = 0.2, ρ = 1, from stream 0 of `seed`.
    pub fn paper(seed: u64) -> Self {
        Observations::Simulated {
            truth: Theta::paper_truth(),
            n: 500,
            seed,
            stream: 0,
        }
    }

    /// The hidden states `X_0…X_n` (simulated data only) and the checked observations.
    ///
    /// # Errors
    /// Fewer than two or non-finite observations, or an invalid data-generating θ.
    pub fn draw(&self) -> Result<(Option<Vec<f64>>, Ar1Data)> {
        match self {
            Observations::Given(y) => Ok((None, Ar1Data::from_slice(y)?)),
            Observations::Simulated {
                truth,
                n,
                seed,
                stream,
            } => {
                let model = NoisyAr1::new(truth.phi, truth.sigma2.sqrt(), truth.rho2.sqrt())?;
                let (xs, ys) = model.simulate(*n, &mut stream_rng(*seed, *stream));
                Ok((Some(xs), Ar1Data::new(ys)?))
            }
        }
    }
}

/// Arguments of `pf-viz smooth em`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EmConfig {
    /// The observations.
    pub data: Observations,
    /// Current φ.
    pub phi: f64,
    /// Current σ (standard deviation).
    pub sigma: f64,
    /// Current ρ (standard deviation).
    pub rho: f64,
    /// Particles N.
    pub particles: usize,
    /// Replications R.
    pub replications: usize,
    /// Lag δ of the fixed-lag estimator, if wanted.
    pub lag: Option<usize>,
    /// Whether to add forward-only smoothing (not in the paper; O(N²) per step) from the
    /// same particle runs.
    #[serde(default)]
    pub forward: bool,
    /// Seed; replication r uses stream (seed, r).
    pub seed: u64,
}

impl Default for EmConfig {
    /// The paper's Fig. 3 setting: θ = (0.8, 0.5², 2²), N = 100, δ = 20, 100 replications,
    /// on Section 5's data.
    fn default() -> Self {
        EmConfig {
            data: Observations::default(),
            phi: 0.8,
            sigma: 0.5,
            rho: 2.0,
            particles: 100,
            replications: 100,
            lag: Some(20),
            forward: false,
            seed: 0,
        }
    }
}

impl EmConfig {
    /// Check σ, ρ > 0, φ finite, N, R ≥ 1, δ ≥ 1.
    ///
    /// # Errors
    /// [`SmoothError::Param`](crate::SmoothError::Param) naming the argument.
    pub fn validate(&self) -> Result<Theta> {
        let theta = Theta::from_std(self.phi, self.sigma, self.rho)?;
        at_least_one("particles", self.particles)?;
        at_least_one("replications", self.replications)?;
        if let Some(d) = self.lag {
            at_least_one("lag", d)?;
        }
        Ok(theta)
    }
}

/// Output of `smooth em`: `{"n", "exact", "joint", "fixed_lag"?, "forward"?}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EmResult {
    /// n (there are n + 1 observations).
    pub n: usize,
    /// The exact EM update (10)–(12) from the given θ.
    pub exact: Theta,
    /// The update with the joint estimator, per replication.
    pub joint: ThetaSamples,
    /// The update with the fixed-lag estimator (same particle runs), only with a lag.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixed_lag: Option<ThetaSamples>,
    /// The update with forward-only smoothing (same particle runs), only if asked for.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub forward: Option<ThetaSamples>,
}

/// One EM update (10)–(12) from θ, exact and with R independent particle estimates.
///
/// # Errors
/// Bad data or arguments, a filter failure, or a degenerate update (first failing
/// replication).
pub fn em(cfg: &EmConfig) -> Result<EmResult> {
    let theta = cfg.validate()?;
    let (_, data) = cfg.data.draw()?;
    let exact = exact_em_step(&data, &theta)?;
    let filter = paper_filter_config(cfg.particles);
    let reps = try_replicate(cfg.seed, cfg.replications, Par::Rayon, |_, rng| {
        let run = run_statistics(&data, &theta, filter, cfg.lag, cfg.forward, rng)?;
        let update = |s: Option<SuffStats>| s.map(|s| s.m_step()).transpose();
        Ok::<_, crate::SmoothError>((
            run.joint.m_step()?,
            update(run.fixed_lag)?,
            update(run.forward)?,
        ))
    })?;
    let joint: Vec<Theta> = reps.iter().map(|r| r.0).collect();
    let samples = |v: Option<Vec<Theta>>| v.map(|v| ThetaSamples::from_thetas(&v));
    Ok(EmResult {
        n: data.n(),
        exact,
        joint: ThetaSamples::from_thetas(&joint),
        fixed_lag: samples(cfg.lag.and(reps.iter().map(|r| r.1).collect())),
        forward: samples(
            cfg.forward
                .then(|| reps.iter().map(|r| r.2).collect())
                .flatten(),
        ),
    })
}

/// Arguments of `pf-viz smooth sem`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SemConfig {
    /// The observations.
    pub data: Observations,
    /// Starting φ.
    pub phi: f64,
    /// Starting σ.
    pub sigma: f64,
    /// Starting ρ.
    pub rho: f64,
    /// Particles N per iteration.
    pub particles: usize,
    /// Iterations I.
    pub iterations: usize,
    /// Independent chains C.
    pub chains: usize,
    /// Seed; chain c uses stream (seed, c).
    pub seed: u64,
}

impl Default for SemConfig {
    /// Fig. 4: N = 25, 50 iterations, 4 chains, from θ = (0.8, 0.5², 2²), on Section 5's
    /// data.
    fn default() -> Self {
        SemConfig {
            data: Observations::default(),
            phi: 0.8,
            sigma: 0.5,
            rho: 2.0,
            particles: 25,
            iterations: 50,
            chains: 4,
            seed: 0,
        }
    }
}

impl SemConfig {
    /// Check σ, ρ > 0, φ finite, N, C ≥ 1, and C no more than a machine can hold.
    ///
    /// # Errors
    /// [`SmoothError::Param`](crate::SmoothError::Param) naming the argument.
    pub fn validate(&self) -> Result<Theta> {
        let theta = Theta::from_std(self.phi, self.sigma, self.rho)?;
        at_least_one("particles", self.particles)?;
        at_least_one("chains", self.chains)?;
        // Named here: the replication runner would call them "replications". Its first
        // reservation, one result per chain, is checked against the machine's memory too.
        const CHAINS: &str = "the number of SEM chains";
        pf_core::limits::check_count(CHAINS, self.chains)?;
        let per_chain = size_of::<Result<Vec<Theta>>>();
        pf_core::limits::check_memory(CHAINS, self.chains, self.chains.saturating_mul(per_chain))?;
        Ok(theta)
    }
}

/// Output of `smooth sem`: `{"exact": [θ per iteration], "sem": [[θ per iteration] per chain]}`,
/// each trajectory starting with the starting point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SemResult {
    /// The exact EM trajectory θ_0…θ_I.
    pub exact: Vec<Theta>,
    /// One SEM trajectory θ_0…θ_I per chain.
    pub sem: Vec<Vec<Theta>>,
}

/// SEM chains (joint estimator, fixed N) over the exact EM trajectory, as in Fig. 4.
///
/// # Errors
/// Bad data or arguments, or the first failing chain (with its iteration).
pub fn sem(cfg: &SemConfig) -> Result<SemResult> {
    let theta = cfg.validate()?;
    let (_, data) = cfg.data.draw()?;
    let exact = exact_em(&data, &theta, cfg.iterations)?;
    let algo = StochasticEm {
        particles: ParticleSchedule::Fixed(cfg.particles),
        estimator: Estimator::Joint,
        iterations: cfg.iterations,
    };
    let sem = try_replicate(cfg.seed, cfg.chains, Par::Rayon, |c, rng| {
        algo.run(&data, &theta, c, rng)
    })?;
    Ok(SemResult { exact, sem })
}

/// Arguments of `pf-viz smooth score`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScoreConfig {
    /// The observations.
    pub data: Observations,
    /// φ at which to evaluate the score.
    pub phi: f64,
    /// σ.
    pub sigma: f64,
    /// ρ.
    pub rho: f64,
    /// Particles N.
    pub particles: usize,
    /// Replications R.
    pub replications: usize,
    /// Seed; replication r uses stream (seed, r).
    pub seed: u64,
}

impl Default for ScoreConfig {
    /// The current estimate of Figs. 2–3, N = 100, 100 replications, on Section 5's data.
    fn default() -> Self {
        ScoreConfig {
            data: Observations::default(),
            phi: 0.8,
            sigma: 0.5,
            rho: 2.0,
            particles: 100,
            replications: 100,
            seed: 0,
        }
    }
}

impl ScoreConfig {
    /// Check σ, ρ > 0, φ finite, N, R ≥ 1.
    ///
    /// # Errors
    /// [`SmoothError::Param`](crate::SmoothError::Param) naming the argument.
    pub fn validate(&self) -> Result<Theta> {
        let theta = Theta::from_std(self.phi, self.sigma, self.rho)?;
        at_least_one("particles", self.particles)?;
        at_least_one("replications", self.replications)?;
        Ok(theta)
    }
}

/// Output of `smooth score`: `{"exact": ∇ℓ, "particle": {"phi": [R], "sigma2": [R], "rho2": [R]}}`,
/// gradients with respect to (φ, σ², ρ²).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScoreResult {
    /// The exact score (Fisher's identity with Kalman/RTS statistics).
    pub exact: Theta,
    /// The particle score (joint estimator) per replication.
    pub particle: ThetaSamples,
}

/// The score `∇ℓ_n(θ)` by Fisher's identity, exact and from R particle runs.
///
/// # Errors
/// Bad data or arguments, or a filter failure.
pub fn score(cfg: &ScoreConfig) -> Result<ScoreResult> {
    let theta = cfg.validate()?;
    let (_, data) = cfg.data.draw()?;
    let exact = exact_statistics(&data, &theta)?.score(&theta);
    let filter = paper_filter_config(cfg.particles);
    let reps = try_replicate(cfg.seed, cfg.replications, Par::Rayon, |_, rng| {
        Ok::<_, crate::SmoothError>(
            particle_statistics(&data, &theta, filter, None, rng)?
                .0
                .score(&theta),
        )
    })?;
    Ok(ScoreResult {
        exact,
        particle: ThetaSamples::from_thetas(&reps),
    })
}

/// The lag sweep (not in the paper): the fixed-lag updates (10)–(12) for a list of lags δ,
/// all from the same particle runs, against the exact update.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LagSweepConfig {
    /// The observations.
    pub data: Observations,
    /// Current φ.
    pub phi: f64,
    /// Current σ.
    pub sigma: f64,
    /// Current ρ.
    pub rho: f64,
    /// Particles N.
    pub particles: usize,
    /// Replications R.
    pub replications: usize,
    /// The lags δ (each ≥ 1).
    pub lags: Vec<usize>,
    /// Seed; replication r uses stream (seed, r).
    pub seed: u64,
}

impl LagSweepConfig {
    /// Check σ, ρ > 0, φ finite, N, R ≥ 1, at least one lag, every lag ≥ 1.
    ///
    /// # Errors
    /// [`SmoothError::Param`](crate::SmoothError::Param) naming the argument.
    pub fn validate(&self) -> Result<Theta> {
        let theta = Theta::from_std(self.phi, self.sigma, self.rho)?;
        at_least_one("particles", self.particles)?;
        at_least_one("replications", self.replications)?;
        at_least_one("number of lags", self.lags.len())?;
        for &d in &self.lags {
            at_least_one("lag", d)?;
        }
        Ok(theta)
    }
}

/// Output of [`lag_sweep`]: per lag, the updates over the replications.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LagSweepResult {
    /// n.
    pub n: usize,
    /// The exact EM update.
    pub exact: Theta,
    /// The lags δ, as given.
    pub lags: Vec<usize>,
    /// The fixed-lag update per lag (same order as `lags`), per replication.
    pub fixed_lag: Vec<ThetaSamples>,
    /// The joint update from the same runs (the limit δ → ∞).
    pub joint: ThetaSamples,
    /// Per lag, the update from the fixed-lag estimator's `N → ∞` limit
    /// ([`exact_fixed_lag_statistics`](crate::exact::exact_fixed_lag_statistics)): its
    /// difference from `exact` is the lag's own bias (forgetting), apart from the particles'.
    #[serde(default)]
    pub exact_fixed_lag: Vec<Theta>,
}

/// Run the lag sweep.
///
/// # Errors
/// Bad data or configuration (a lag of 0, no lags), a filter failure or a degenerate update.
pub fn lag_sweep(cfg: &LagSweepConfig) -> Result<LagSweepResult> {
    let theta = cfg.validate()?;
    let (_, data) = cfg.data.draw()?;
    let n = data.n();
    let exact = exact_em_step(&data, &theta)?;
    let filter = paper_filter_config(cfg.particles);
    let reps = try_replicate(cfg.seed, cfg.replications, Par::Rayon, |_, rng| {
        let run = lag_statistics(&data, &theta, filter, &cfg.lags, false, rng)?;
        let f = run
            .fixed_lag
            .iter()
            .map(SuffStats::m_step)
            .collect::<Result<Vec<_>>>()?;
        Ok::<_, crate::SmoothError>((run.joint.m_step()?, f))
    })?;
    let exact_fixed_lag = cfg
        .lags
        .iter()
        .map(|&d| crate::exact::exact_fixed_lag_statistics(&data, &theta, d)?.m_step())
        .collect::<Result<Vec<_>>>()?;
    let joint: Vec<Theta> = reps.iter().map(|r| r.0).collect();
    let fixed_lag = (0..cfg.lags.len())
        .map(|l| ThetaSamples::from_thetas(&reps.iter().map(|r| r.1[l]).collect::<Vec<_>>()))
        .collect();
    Ok(LagSweepResult {
        n,
        exact,
        lags: cfg.lags.clone(),
        fixed_lag,
        joint: ThetaSamples::from_thetas(&joint),
        exact_fixed_lag,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Too many chains are refused by name, before any chain runs: more than the count
    /// limit, and (on Linux, where the machine's memory is known) fewer whose results would
    /// not fit in it.
    #[test]
    fn too_many_sem_chains_are_named_as_chains() {
        let mut counts = vec![usize::MAX];
        if cfg!(target_os = "linux") {
            counts.push(pf_core::limits::MAX_COUNT);
        }
        for chains in counts {
            let cfg = SemConfig {
                data: Observations::Given(vec![0.1, 0.2, 0.3]),
                phi: 0.9,
                sigma: 0.5,
                rho: 1.0,
                particles: 10,
                iterations: 1,
                chains,
                seed: 1,
            };
            let e = sem(&cfg).unwrap_err().to_string();
            assert!(e.contains("SEM chains"), "{chains}: {e}");
        }
    }
}
