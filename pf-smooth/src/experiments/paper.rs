//! Section 5 as one experiment: Fig. 1's genealogy, the EM updates of Figs. 2–3, the SEM
//! chains of Fig. 4 and the lag sweep, all on one simulated data set, with the numbers that
//! judge the paper's claim "F2 ≈ J3" and the forward-only reference.
//!
//! Every run is the bootstrap filter with systematic resampling at every step and the diffuse
//! prior (`φ_0 = N(Y_0, ρ²)`). The data use stream `data_stream` of the seed; each part
//! runs under a seed of its own drawn from the seed, so that no two parts share a stream.

use super::{
    CoalescenceConfig, CoalescenceResult, EmConfig, EmResult, LagSweepConfig, LagSweepResult,
    Observations, Scale, SemConfig, SemResult, coalescence, em, lag_sweep, sem,
};
use crate::ar1::{Ar1Data, Theta};
use crate::em::paper_filter_config;
use crate::error::Result;
use pf_core::filter::{FilterConfig, ParticleFilter};
use pf_core::genealogy::{Genealogy, GenealogyData, RecordedRun};
use pf_core::mc::{mean_and_sd, mean_and_se, stream_rng};
use pf_core::params::at_least_one;
use pf_core::resample::Resampler;
use rand::Rng;
use serde::{Deserialize, Serialize};

/// Section 5's experiments; [`SmoothConfig::at_scale`] gives the paper's values with the
/// replication counts of each scale.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SmoothConfig {
    /// Data-generating θ (paper: φ = 0.98, σ = 0.2, ρ = 1).
    pub truth: Theta,
    /// The current estimate of Figs. 2–3 and the start of Fig. 4 (paper: 0.8, 0.5, 2).
    pub start: Theta,
    /// Data length n (paper: 500).
    pub n: usize,
    /// The short length of Fig. 2 (paper: 50; the first 51 observations of the same data).
    pub n_short: usize,
    /// Particles of Fig. 2 (paper: J1 = 10, J2 = 100, J3 = 1000).
    pub particles: Vec<usize>,
    /// Lag δ of Fig. 3 (paper: 20).
    pub lag: usize,
    /// Replications of Figs. 2–3 (paper: 5000).
    pub replications: usize,
    /// Particles of Fig. 1 (paper: 50).
    pub genealogy_particles: usize,
    /// Steps shown in Fig. 1 (the paper does not say; we show all 500, since with Section
    /// 5's systematic resampling the N = 50 paths have a common ancestor a median 215–230
    /// steps back: [`CoalescenceResult`]).
    pub genealogy_steps: usize,
    /// Fig. 1's resampling scheme (Section 5: systematic).
    #[serde(default)]
    pub genealogy_resampler: Resampler,
    /// Steps of the second Fig. 1, with multinomial resampling (the paper's 100-step look).
    #[serde(default = "default_multinomial_steps")]
    pub genealogy_multinomial_steps: usize,
    /// Seeded runs per setting of the coalescence experiment (not in the paper).
    #[serde(default = "default_coalescence_runs")]
    pub coalescence_runs: usize,
    /// SEM particles (paper: 25).
    pub sem_particles: usize,
    /// SEM iterations (paper: 50).
    pub sem_iterations: usize,
    /// SEM chains (paper: 4).
    pub sem_chains: usize,
    /// Lags of the sweep (not in the paper).
    pub sweep_lags: Vec<usize>,
    /// Particles of the sweep.
    pub sweep_particles: Vec<usize>,
    /// Replications of the sweep.
    pub sweep_replications: usize,
    /// The N of the long Fig. 3 runs that also feed forward-only smoothing (not in the
    /// paper; O(N²) per step), the spread table's reference without path degeneracy.
    pub forward_particles: Vec<usize>,
    /// Random stream (under the seed) of the data.
    pub data_stream: u64,
    /// The seed (the result states it, so the configuration leaves it out of its JSON).
    #[serde(skip)]
    pub seed: u64,
}

fn default_multinomial_steps() -> usize {
    100
}

fn default_coalescence_runs() -> usize {
    CoalescenceConfig::at_scale(Scale::Default).runs
}

impl Default for SmoothConfig {
    /// The paper's sizes ([`Scale::Full`]).
    fn default() -> Self {
        Self::at_scale(Scale::Full)
    }
}

impl SmoothConfig {
    /// The paper's setting, with 5000 replications at `Full`, 200 at `Default` and 4 at
    /// `Quick`; seed 0.
    pub fn at_scale(scale: Scale) -> Self {
        let (replications, sweep_replications, sweep_lags) = match scale {
            Scale::Quick => (4, 4, vec![1, 5, 20, 100]),
            Scale::Default => (200, 100, vec![1, 2, 5, 10, 20, 50, 100, 200]),
            Scale::Full => (5000, 1000, vec![1, 2, 5, 10, 20, 50, 100, 200]),
        };
        SmoothConfig {
            truth: Theta::paper_truth(),
            start: Theta::paper_start(),
            n: 500,
            n_short: 50,
            particles: vec![10, 100, 1000],
            lag: 20,
            replications,
            genealogy_particles: 50,
            genealogy_steps: 500,
            genealogy_resampler: Resampler::Systematic,
            genealogy_multinomial_steps: 100,
            coalescence_runs: CoalescenceConfig::at_scale(scale).runs,
            sem_particles: 25,
            sem_iterations: 50,
            sem_chains: 4,
            sweep_lags,
            sweep_particles: vec![100, 1000],
            sweep_replications,
            forward_particles: vec![100],
            data_stream: 0,
            seed: 0,
        }
    }

    /// How many times [`smooth_with_progress`] ticks: once for Fig. 1, once for the
    /// coalescence experiment, twice per N of Fig. 2, once for Fig. 4 and once per N of the
    /// sweep.
    pub fn ticks(&self) -> u64 {
        (3 + 2 * self.particles.len() + self.sweep_particles.len()) as u64
    }

    /// Check what the parts do not check themselves: at least one N in Fig. 2 and in the
    /// sweep, and a short length within the data.
    ///
    /// # Errors
    /// [`SmoothError::Param`](crate::SmoothError::Param) or
    /// [`SmoothError::TooFewObservations`](crate::SmoothError::TooFewObservations).
    pub fn validate(&self) -> Result<()> {
        self.truth.validate()?;
        self.start.validate()?;
        at_least_one("number of Fig. 2 particle counts", self.particles.len())?;
        at_least_one(
            "number of sweep particle counts",
            self.sweep_particles.len(),
        )?;
        at_least_one("n_short", self.n_short)?;
        if self.n_short > self.n {
            return Err(crate::SmoothError::TooFewObservations {
                got: self.n + 1,
                need: self.n_short + 1,
            });
        }
        Ok(())
    }

    /// The observations every part runs on.
    fn observations(&self) -> Observations {
        Observations::Simulated {
            truth: self.truth,
            n: self.n,
            seed: self.seed,
            stream: self.data_stream,
        }
    }
}

/// Fig. 2/3 runs at one (n, N): joint and, at the long n, fixed-lag updates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UpdateRuns {
    /// Particles N.
    pub particles: usize,
    /// The replicated updates (`fixed_lag` only at the long n).
    pub result: EmResult,
}

/// Every number behind Section 5's figures.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SmoothResult {
    /// The configuration that was run.
    pub config: SmoothConfig,
    /// The seed.
    pub seed: u64,
    /// The simulated observations `Y_0…Y_n`.
    pub observations: Vec<f64>,
    /// Fig. 1's genealogy.
    pub genealogy: Fig1Result,
    /// Fig. 1 with multinomial resampling over `genealogy_multinomial_steps` steps.
    pub genealogy_multinomial: Fig1Result,
    /// The coalescence delay over seeded runs (not in the paper): why Fig. 1 looks as it
    /// does.
    pub coalescence: CoalescenceResult,
    /// Fig. 2 at `n_short`, per N.
    pub fig2_short: Vec<UpdateRuns>,
    /// Figs. 2 and 3 at `n`, per N (joint and fixed-lag from the same particles).
    pub fig2_long: Vec<UpdateRuns>,
    /// Fig. 4.
    pub sem: SemResult,
    /// The lag sweep, per N.
    pub lag_sweep: Vec<LagSweepResult>,
}

impl SmoothResult {
    /// Fig. 3's claim measured on the long runs ([`fixed_lag_claim`]).
    pub fn fixed_lag_claim(&self) -> Option<FixedLagClaim> {
        fixed_lag_claim(&self.fig2_long, self.config.replications)
    }

    /// The forward-only reference of the long runs ([`forward_reference`]).
    pub fn forward_reference(&self) -> Option<ForwardReference> {
        forward_reference(&self.fig2_long)
    }
}

/// A seed per experiment, derived from the seed, so experiments never share streams.
fn sub_seed(seed: u64, experiment: u64) -> u64 {
    stream_rng(seed, 1000 + experiment).next_u64()
}

/// Run Section 5's experiments.
///
/// # Errors
/// An invalid configuration, a filter failure or a degenerate update (the first failing
/// part).
pub fn smooth(cfg: &SmoothConfig) -> Result<SmoothResult> {
    smooth_with_progress(cfg, &|| {})
}

/// [`smooth`], calling `tick` after each part ([`SmoothConfig::ticks`] times in all).
///
/// # Errors
/// As [`smooth`].
pub fn smooth_with_progress(cfg: &SmoothConfig, tick: &(dyn Fn() + Sync)) -> Result<SmoothResult> {
    cfg.validate()?;
    let (xs, data) = cfg.observations().draw()?;
    let seed = cfg.seed;

    let genealogy = fig1_on(
        &data,
        xs.as_deref(),
        &Fig1Config {
            data: Observations::Given(Vec::new()),
            theta: cfg.truth,
            particles: cfg.genealogy_particles,
            steps: cfg.genealogy_steps,
            resampler: cfg.genealogy_resampler,
            seed: sub_seed(seed, 1),
        },
    )?;
    let genealogy_multinomial = fig1_on(
        &data,
        xs.as_deref(),
        &Fig1Config {
            data: Observations::Given(Vec::new()),
            theta: cfg.truth,
            particles: cfg.genealogy_particles,
            steps: cfg.genealogy_multinomial_steps,
            resampler: Resampler::Multinomial,
            seed: sub_seed(seed, 2),
        },
    )?;
    tick();
    let coalescence_result = coalescence(&CoalescenceConfig {
        data: Observations::Given(data.y().to_vec()),
        particles: cfg.genealogy_particles,
        runs: cfg.coalescence_runs,
        seed: sub_seed(seed, 3),
        ..CoalescenceConfig::at_scale(Scale::Default)
    })?;
    tick();

    let s = cfg.start;
    let exp = |y: &Ar1Data, particles: usize, lag: Option<usize>, tag: u64| EmConfig {
        data: Observations::Given(y.y().to_vec()),
        phi: s.phi,
        sigma: s.sigma2.sqrt(),
        rho: s.rho2.sqrt(),
        particles,
        replications: cfg.replications,
        lag,
        // The smoother draws nothing, so the joint and fixed-lag runs stay the same.
        forward: lag.is_some() && cfg.forward_particles.contains(&particles),
        seed: sub_seed(seed, tag),
    };
    let short = data.prefix(cfg.n_short)?;
    let mut fig2_short = Vec::new();
    let mut fig2_long = Vec::new();
    for (j, &particles) in cfg.particles.iter().enumerate() {
        let result = em(&exp(&short, particles, None, 10 + j as u64))?;
        fig2_short.push(UpdateRuns { particles, result });
        tick();
        let result = em(&exp(&data, particles, Some(cfg.lag), 20 + j as u64))?;
        fig2_long.push(UpdateRuns { particles, result });
        tick();
    }

    let sem_result = sem(&SemConfig {
        data: Observations::Given(data.y().to_vec()),
        phi: s.phi,
        sigma: s.sigma2.sqrt(),
        rho: s.rho2.sqrt(),
        particles: cfg.sem_particles,
        iterations: cfg.sem_iterations,
        chains: cfg.sem_chains,
        seed: sub_seed(seed, 30),
    })?;
    tick();

    let mut sweeps = Vec::new();
    for (j, &particles) in cfg.sweep_particles.iter().enumerate() {
        sweeps.push(lag_sweep(&LagSweepConfig {
            data: Observations::Given(data.y().to_vec()),
            phi: s.phi,
            sigma: s.sigma2.sqrt(),
            rho: s.rho2.sqrt(),
            particles,
            replications: cfg.sweep_replications,
            lags: cfg.sweep_lags.clone(),
            seed: sub_seed(seed, 40 + j as u64),
        })?);
        tick();
    }

    Ok(SmoothResult {
        config: cfg.clone(),
        seed,
        observations: data.y().to_vec(),
        genealogy,
        genealogy_multinomial,
        coalescence: coalescence_result,
        fig2_short,
        fig2_long,
        sem: sem_result,
        lag_sweep: sweeps,
    })
}

/// Fig. 1: a bootstrap filter at `theta` on the first `steps` steps of the data, with its
/// genealogy recorded.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fig1Config {
    /// The observations.
    pub data: Observations,
    /// The θ the filter runs at (the paper: the true one).
    pub theta: Theta,
    /// Particles N (paper: 50).
    pub particles: usize,
    /// Steps shown (the paper does not say; all 500 of Section 5's data).
    pub steps: usize,
    /// The resampling scheme, at every step (Section 5: systematic).
    #[serde(default)]
    pub resampler: Resampler,
    /// Seed: the filter runs on the stream `(seed, 0)`.
    pub seed: u64,
}

impl Default for Fig1Config {
    fn default() -> Self {
        Self::at_scale(Scale::Full)
    }
}

impl Fig1Config {
    /// The paper's setting on Section 5's data (seed 0) at every scale: one filter of 50
    /// particles costs the same at each.
    pub fn at_scale(_scale: Scale) -> Self {
        Fig1Config {
            data: Observations::paper(0),
            theta: Theta::paper_truth(),
            particles: 50,
            steps: 500,
            resampler: Resampler::Systematic,
            seed: 0,
        }
    }
}

/// Fig. 1: the particles and their genealogy as plain numbers, with what the recordings add.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fig1Result {
    /// Positions, ancestors, survivors, coalescence time and (simulated data only) the
    /// hidden states, at the top level of the JSON.
    #[serde(flatten)]
    pub paths: GenealogyData,
    /// `weights[k][i] = W_k^i`, normalised (for recordings).
    #[serde(skip)]
    pub weights: Vec<Vec<f64>>,
    /// The effective sample size of every step (for recordings).
    #[serde(skip)]
    pub ess: Vec<f64>,
    /// The engine's genealogy (for recordings).
    #[serde(skip)]
    pub lineage: Genealogy,
}

/// Run Fig. 1.
///
/// # Errors
/// N or the number of steps 0, bad data, or a filter failure.
pub fn fig1(cfg: &Fig1Config) -> Result<Fig1Result> {
    at_least_one("particles", cfg.particles)?;
    at_least_one("steps", cfg.steps)?;
    cfg.theta.validate()?;
    let (xs, data) = cfg.data.draw()?;
    fig1_on(&data, xs.as_deref(), cfg)
}

/// Fig. 1 on `data` (with hidden states `xs` when known); `cfg.data` is not used.
fn fig1_on(data: &Ar1Data, xs: Option<&[f64]>, cfg: &Fig1Config) -> Result<Fig1Result> {
    let d = data.prefix(cfg.steps.min(data.n()))?;
    let model = cfg.theta.model(d.y()[0])?;
    let fc = FilterConfig {
        resampler: cfg.resampler,
        ..paper_filter_config(cfg.particles)
    };
    let mut pf = ParticleFilter::bootstrap(model, fc)?;
    let truth = xs.and_then(|x| x.get(..=d.n())).map(<[f64]>::to_vec);
    let run = RecordedRun::of(
        &mut pf,
        &d.filter_input(),
        &mut stream_rng(cfg.seed, 0),
        truth,
    )?;
    Ok(Fig1Result {
        paths: run.paths,
        weights: run.weights,
        ess: run.ess,
        lineage: run.lineage,
    })
}

/// How F2's spread compares with J3's, beyond what the replications can resolve.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Spread {
    /// F2 is wider than J3.
    Wider,
    /// F2 is narrower than J3.
    Narrower,
    /// The two cannot be told apart: "roughly equivalent", as the paper says.
    Equivalent,
}

/// Fig. 3's claim "F2 is roughly equivalent to J3" measured on φ̂: the standard deviations
/// of the fixed-lag update at N = 100 (F2) and the joint ones at N = 100 (J2) and 1000 (J3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FixedLagClaim {
    /// sd of F2's φ̂.
    pub f2_sd: f64,
    /// sd of J3's φ̂.
    pub j3_sd: f64,
    /// sd of J2's φ̂.
    pub j2_sd: f64,
    /// `f2_sd / j3_sd`.
    pub ratio: f64,
    /// The factor by which fixed-lag cuts J2's variance, `(j2_sd / f2_sd)²`.
    pub variance_cut: f64,
    /// The relative standard error of a sample sd from R replications, `1/√(2(R − 1))`.
    pub sd_rel_se: f64,
    /// The verdict on `ratio`.
    pub spread: Spread,
}

/// Fig. 3's claim from the long runs (F2: the fixed-lag update at N = 100, J2, J3: the
/// joint ones at N = 100, 1000), over `replications` replications; `None` without those
/// runs.
///
/// A sample sd from R replications of a normal estimate has a relative standard error of
/// about `1/√(2(R − 1))`; F2 and J3 come from separate particle runs, so the log of their
/// ratio has √2 times that. Within 2 of those the two cannot be told apart.
pub fn fixed_lag_claim(long: &[UpdateRuns], replications: usize) -> Option<FixedLagClaim> {
    let j3 = long.iter().find(|u| u.particles == 1000)?;
    let n100 = long.iter().find(|u| u.particles == 100)?;
    let f = n100.result.fixed_lag.as_ref()?;
    let (f2_sd, j3_sd, j2_sd) = (
        mean_and_sd(&f.phi).1,
        mean_and_sd(&j3.result.joint.phi).1,
        mean_and_sd(&n100.result.joint.phi).1,
    );
    let ratio = f2_sd / j3_sd;
    let sd_rel_se = 1.0 / (2.0 * (replications.max(2) - 1) as f64).sqrt();
    let band = 2.0 * std::f64::consts::SQRT_2 * sd_rel_se;
    let spread = if ratio.ln() > band {
        Spread::Wider
    } else if ratio.ln() < -band {
        Spread::Narrower
    } else {
        Spread::Equivalent
    };
    Some(FixedLagClaim {
        f2_sd,
        j3_sd,
        j2_sd,
        ratio,
        variance_cut: (j2_sd / f2_sd).powi(2),
        sd_rel_se,
        spread,
    })
}

/// Forward-only smoothing (not in the paper) beside F2 and J3, on φ̂: its spread, and its
/// mean's distance from the exact update in standard errors (it is biased by O(1/N), like
/// every normalised particle estimate, but has no forgetting bias).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ForwardReference {
    /// N of the runs.
    pub particles: usize,
    /// The exact update's φ.
    pub exact: f64,
    /// sd of the forward-only φ̂.
    pub sd: f64,
    /// Mean of the forward-only φ̂.
    pub mean: f64,
    /// Its standard error.
    pub se: f64,
    /// `mean − exact`.
    pub offset: f64,
    /// Whether `|offset| ≤ 2 se`.
    pub within_two_se: bool,
    /// `|offset| / se`.
    pub offset_in_se: f64,
    /// The joint estimate's mean minus the exact update, same runs.
    pub joint_offset: f64,
    /// The fixed-lag estimate's mean minus the exact update, same runs (if it ran).
    pub fixed_lag_offset: Option<f64>,
    /// sd of the fixed-lag φ̂ of the same runs (F2), if it ran.
    pub fixed_lag_sd: Option<f64>,
    /// sd of the joint φ̂ at N = 1000 (J3), if it ran.
    pub j3_sd: Option<f64>,
}

/// The forward-only reference of the first long run that has one; `None` if none has.
pub fn forward_reference(long: &[UpdateRuns]) -> Option<ForwardReference> {
    let runs = long.iter().find(|u| u.result.forward.is_some())?;
    let f = runs.result.forward.as_ref()?;
    let exact = runs.result.exact.phi;
    let (mean, se) = mean_and_se(&f.phi);
    let offset = mean - exact;
    let mean_off = |v: &[f64]| mean_and_se(v).0 - exact;
    Some(ForwardReference {
        particles: runs.particles,
        exact,
        sd: mean_and_sd(&f.phi).1,
        mean,
        se,
        offset,
        within_two_se: offset.abs() <= 2.0 * se,
        offset_in_se: offset.abs() / se.max(f64::MIN_POSITIVE),
        joint_offset: mean_off(&runs.result.joint.phi),
        fixed_lag_offset: runs.result.fixed_lag.as_ref().map(|l| mean_off(&l.phi)),
        fixed_lag_sd: runs
            .result
            .fixed_lag
            .as_ref()
            .map(|l| mean_and_sd(&l.phi).1),
        j3_sd: long
            .iter()
            .find(|u| u.particles == 1000)
            .map(|u| mean_and_sd(&u.result.joint.phi).1),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ar1::ThetaSamples;

    /// Updates whose φ̂ are `phi`, with σ̂², ρ̂² fixed.
    fn samples(phi: &[f64]) -> ThetaSamples {
        ThetaSamples {
            phi: phi.to_vec(),
            sigma2: vec![0.25; phi.len()],
            rho2: vec![4.0; phi.len()],
        }
    }

    fn runs(
        particles: usize,
        joint: &[f64],
        fixed: Option<&[f64]>,
        forward: Option<&[f64]>,
    ) -> UpdateRuns {
        UpdateRuns {
            particles,
            result: EmResult {
                n: 500,
                exact: Theta {
                    phi: 0.8,
                    sigma2: 0.25,
                    rho2: 4.0,
                },
                joint: samples(joint),
                fixed_lag: fixed.map(samples),
                forward: forward.map(samples),
            },
        }
    }

    /// The forward reference states the spreads beside F2 and J3, and calls its offset from
    /// the exact update a bias only beyond 2 standard errors.
    #[test]
    fn the_forward_reference_judges_the_offset_by_its_standard_error() {
        assert_eq!(
            forward_reference(&[runs(100, &[0.8, 0.81], None, None)]),
            None
        );
        // Mean 0.801, sd 0.0084, s.e. 0.0042: an offset of 0.001 is within 2 s.e.
        let near = [0.79, 0.80, 0.81, 0.804];
        let wide = [0.78, 0.82, 0.76, 0.84];
        let long = [
            runs(100, &wide, Some(&wide), Some(&near)),
            runs(1000, &near, None, None),
        ];
        let r = forward_reference(&long).expect("a reference");
        assert!(r.within_two_se, "{r:?}");
        assert!((r.offset - 0.001).abs() < 1e-12, "{r:?}");
        assert!((r.fixed_lag_sd.unwrap() - 0.036515).abs() < 1e-6, "{r:?}");
        assert!((r.j3_sd.unwrap() - 0.008406).abs() < 1e-6, "{r:?}");
        // All 0.01 low with a tiny spread: far beyond 2 standard errors.
        let low = [0.789, 0.7891, 0.7889, 0.79];
        let r = forward_reference(&[runs(100, &wide, Some(&wide), Some(&low))]).expect("one");
        assert!(!r.within_two_se && r.offset_in_se > 2.0, "{r:?}");
        assert_eq!(r.j3_sd, None);
    }

    /// F2 twice as wide as J3 is "wider" with 200 replications, "equivalent" with 4 (whose
    /// sds are uncertain by ±41 %), and half as wide is "narrower".
    #[test]
    fn the_fixed_lag_claim_is_judged_against_the_sd_uncertainty() {
        let j3 = [0.79, 0.81, 0.79, 0.81];
        let f2 = [0.78, 0.82, 0.78, 0.82];
        let long = [
            runs(100, &[0.7, 0.9, 0.7, 0.9], Some(&f2), None),
            runs(1000, &j3, None, None),
        ];
        let c = fixed_lag_claim(&long, 200).expect("a claim");
        assert!(
            (c.ratio - 2.0).abs() < 1e-9 && c.spread == Spread::Wider,
            "{c:?}"
        );
        assert!((c.variance_cut - 25.0).abs() < 1e-9, "{c:?}");
        assert_eq!(
            fixed_lag_claim(&long, 4).map(|c| c.spread),
            Some(Spread::Equivalent)
        );
        let swapped = [
            runs(100, &[0.7, 0.9, 0.7, 0.9], Some(&j3), None),
            runs(1000, &f2, None, None),
        ];
        assert_eq!(
            fixed_lag_claim(&swapped, 200).map(|c| c.spread),
            Some(Spread::Narrower)
        );
        assert_eq!(fixed_lag_claim(&long[..1], 200), None);
    }

    /// Fig. 1 shows the first `steps` steps with the hidden states beside them, and its
    /// survivors all descend from the coalescence step's one ancestor.
    #[test]
    fn fig1_records_the_genealogy_of_the_first_steps() {
        let cfg = Fig1Config {
            data: Observations::Simulated {
                truth: Theta::paper_truth(),
                n: 60,
                seed: 4,
                stream: 0,
            },
            particles: 20,
            steps: 30,
            ..Fig1Config::default()
        };
        let r = fig1(&cfg).unwrap();
        assert_eq!(r.paths.positions.len(), 31);
        assert!(r.paths.positions.iter().all(|p| p.len() == 20));
        assert_eq!(r.paths.ancestors.len(), 31);
        assert!(
            r.paths.ancestors[0].is_empty() && r.paths.ancestors[1..].iter().all(|a| a.len() == 20)
        );
        assert_eq!(r.paths.truth.as_ref().map(Vec::len), Some(31));
        assert_eq!((r.weights.len(), r.ess.len()), (31, 31));
        let t = r
            .paths
            .coalescence_time
            .expect("20 particles' paths coalesce within 30 steps");
        assert_eq!(r.paths.surviving[t].iter().filter(|&&s| s).count(), 1);
        // The most recent such step: the one after it has more than one survivor.
        assert!(r.paths.surviving[t + 1].iter().filter(|&&s| s).count() > 1);
        assert_eq!(fig1(&cfg).unwrap(), r, "deterministic for its seed");
        let bad = Fig1Config {
            particles: 0,
            ..cfg
        };
        assert!(fig1(&bad).unwrap_err().to_string().contains("particles"));
    }
}
