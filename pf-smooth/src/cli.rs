//! Library side of the `pf-viz smooth em|sem|score` commands.
//!
//! Each function takes the observations `Y_0…Y_n` (the CSV's `y` column, parsed by the
//! CLI) and the command's arguments, validates both, and returns a serde struct whose JSON
//! is exactly the contract of the issue. Reading files and mapping errors to file/line
//! messages is the CLI's job.

use crate::ar1::{Ar1Data, Theta, ThetaSamples};
use crate::em::{
    Estimator, ParticleSchedule, StochasticEm, paper_filter_config, particle_statistics,
};
use crate::error::{Result, at_least_one};
use crate::exact::{exact_em, exact_em_step, exact_statistics};
use pf_core::mc::{Par, try_replicate};
use serde::{Deserialize, Serialize};

/// Arguments of `pf-viz smooth em`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EmArgs {
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
    /// Seed; replication r uses stream (seed, r).
    pub seed: u64,
}

impl Default for EmArgs {
    /// The paper's Fig. 3 setting: θ = (0.8, 0.5², 2²), N = 100, δ = 20, 100 replications.
    fn default() -> Self {
        EmArgs {
            phi: 0.8,
            sigma: 0.5,
            rho: 2.0,
            particles: 100,
            replications: 100,
            lag: Some(20),
            seed: 0,
        }
    }
}

impl EmArgs {
    /// Check σ, ρ > 0, φ finite, N, R ≥ 1, δ ≥ 1.
    ///
    /// # Errors
    /// [`SmoothError::InvalidParameter`](crate::SmoothError::InvalidParameter) naming the argument.
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

/// Output of `smooth em`: `{"n", "exact", "joint", "fixed_lag"?}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EmOutput {
    /// n (there are n + 1 observations).
    pub n: usize,
    /// The exact EM update (10)–(12) from the given θ.
    pub exact: Theta,
    /// The update with the joint estimator, per replication.
    pub joint: ThetaSamples,
    /// The update with the fixed-lag estimator (same particle runs), only with a lag.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixed_lag: Option<ThetaSamples>,
}

/// One EM update (10)–(12) from θ, exact and with R independent particle estimates.
///
/// # Errors
/// Bad data or arguments, a filter failure, or a degenerate update (first failing
/// replication).
pub fn em(y: &[f64], args: &EmArgs) -> Result<EmOutput> {
    let theta = args.validate()?;
    let data = Ar1Data::from_slice(y)?;
    let exact = exact_em_step(&data, &theta)?;
    let cfg = paper_filter_config(args.particles);
    let reps = try_replicate(args.seed, args.replications, Par::Rayon, |_, rng| {
        let (j, f) = particle_statistics(&data, &theta, cfg, args.lag, rng)?;
        Ok::<_, crate::SmoothError>((j.m_step()?, f.map(|f| f.m_step()).transpose()?))
    })?;
    let joint: Vec<Theta> = reps.iter().map(|r| r.0).collect();
    let fixed: Option<Vec<Theta>> = reps.iter().map(|r| r.1).collect();
    Ok(EmOutput {
        n: data.n(),
        exact,
        joint: ThetaSamples::from_thetas(&joint),
        fixed_lag: args.lag.and(fixed).map(|f| ThetaSamples::from_thetas(&f)),
    })
}

/// Arguments of `pf-viz smooth sem`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SemArgs {
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

impl Default for SemArgs {
    /// Fig. 4: N = 25, 50 iterations, 4 chains, from θ = (0.8, 0.5², 2²).
    fn default() -> Self {
        SemArgs {
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

impl SemArgs {
    /// Check σ, ρ > 0, φ finite, N, C ≥ 1.
    ///
    /// # Errors
    /// [`SmoothError::InvalidParameter`](crate::SmoothError::InvalidParameter) naming the argument.
    pub fn validate(&self) -> Result<Theta> {
        let theta = Theta::from_std(self.phi, self.sigma, self.rho)?;
        at_least_one("particles", self.particles)?;
        at_least_one("chains", self.chains)?;
        Ok(theta)
    }
}

/// Output of `smooth sem`: `{"exact": [θ per iteration], "sem": [[θ per iteration] per chain]}`,
/// each trajectory starting with the starting point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SemOutput {
    /// The exact EM trajectory θ_0…θ_I.
    pub exact: Vec<Theta>,
    /// One SEM trajectory θ_0…θ_I per chain.
    pub sem: Vec<Vec<Theta>>,
}

/// SEM chains (joint estimator, fixed N) over the exact EM trajectory, as in Fig. 4.
///
/// # Errors
/// Bad data or arguments, or the first failing chain (with its iteration).
pub fn sem(y: &[f64], args: &SemArgs) -> Result<SemOutput> {
    let theta = args.validate()?;
    let data = Ar1Data::from_slice(y)?;
    let exact = exact_em(&data, &theta, args.iterations)?;
    let algo = StochasticEm {
        particles: ParticleSchedule::Fixed(args.particles),
        estimator: Estimator::Joint,
        iterations: args.iterations,
    };
    let sem = try_replicate(args.seed, args.chains, Par::Rayon, |c, rng| {
        algo.run(&data, &theta, c, rng)
    })?;
    Ok(SemOutput { exact, sem })
}

/// Arguments of `pf-viz smooth score`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScoreArgs {
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

impl Default for ScoreArgs {
    /// The current estimate of Figs. 2–3, N = 100, 100 replications.
    fn default() -> Self {
        ScoreArgs {
            phi: 0.8,
            sigma: 0.5,
            rho: 2.0,
            particles: 100,
            replications: 100,
            seed: 0,
        }
    }
}

impl ScoreArgs {
    /// Check σ, ρ > 0, φ finite, N, R ≥ 1.
    ///
    /// # Errors
    /// [`SmoothError::InvalidParameter`](crate::SmoothError::InvalidParameter) naming the argument.
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
pub struct ScoreOutput {
    /// The exact score (Fisher's identity with Kalman/RTS statistics).
    pub exact: Theta,
    /// The particle score (joint estimator) per replication.
    pub particle: ThetaSamples,
}

/// The score `∇ℓ_n(θ)` by Fisher's identity, exact and from R particle runs.
///
/// # Errors
/// Bad data or arguments, or a filter failure.
pub fn score(y: &[f64], args: &ScoreArgs) -> Result<ScoreOutput> {
    let theta = args.validate()?;
    let data = Ar1Data::from_slice(y)?;
    let exact = exact_statistics(&data, &theta)?.score(&theta);
    let cfg = paper_filter_config(args.particles);
    let reps = try_replicate(args.seed, args.replications, Par::Rayon, |_, rng| {
        Ok::<_, crate::SmoothError>(
            particle_statistics(&data, &theta, cfg, None, rng)?
                .0
                .score(&theta),
        )
    })?;
    Ok(ScoreOutput {
        exact,
        particle: ThetaSamples::from_thetas(&reps),
    })
}
