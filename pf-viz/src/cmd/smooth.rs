//! `pf-viz smooth em|sem|score`: Cappé & Moulines, smoothed sum functionals, EM, SEM and the
//! score by Fisher's identity, on the `y` column of a CSV file.
//!
//! The JSON shapes are the contract of the issue:
//! ```text
//! em    -> {"n", "exact": θ, "joint": {"phi": [R], "sigma2": [R], "rho2": [R]}, "fixed_lag"?: same,
//!           "forward"?: same}
//! sem   -> {"exact": [θ per iteration], "sem": [[θ per iteration] per chain]}
//! score -> {"exact": ∇ℓ, "particle": {"phi": [R], "sigma2": [R], "rho2": [R]}}
//! ```

use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use pf_smooth::experiments::{EmConfig, Observations, ScoreConfig, SemConfig, em, score, sem};
use pf_smooth::{SmoothError, Theta, ThetaSamples};

use super::{print_json, print_line};
use crate::error::{Result, VizError};

/// The subcommands of `pf-viz smooth`.
#[derive(Debug, Clone, Subcommand)]
pub enum SmoothCommand {
    /// One EM update (10)–(12) from θ: exact, and from R particle runs (joint and fixed-lag).
    Em(EmArgs),
    /// SEM chains (Fig. 4) over the exact EM trajectory.
    Sem(SemArgs),
    /// The score ∇ℓ_n(θ) w.r.t. (φ, σ², ρ²) by Fisher's identity: exact and particle.
    Score(ScoreArgs),
}

/// Arguments shared by the three subcommands: data and the current θ.
#[derive(Debug, Clone, Args)]
pub struct ThetaArgs {
    /// CSV file with a header and a `y` column holding Y_0…Y_n (other columns ignored).
    #[arg(long, value_name = "FILE")]
    pub data: PathBuf,
    /// Current φ (AR coefficient).
    #[arg(long, allow_negative_numbers = true)]
    pub phi: f64,
    /// Current σ, the state noise standard deviation (> 0).
    #[arg(long, allow_negative_numbers = true)]
    pub sigma: f64,
    /// Current ρ, the observation noise standard deviation (> 0).
    #[arg(long, allow_negative_numbers = true)]
    pub rho: f64,
    /// Number of particles N (≥ 1).
    #[arg(long)]
    pub particles: usize,
    /// Master seed (replication r uses the stream (seed, r)).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Print one JSON object on stdout instead of a summary.
    #[arg(long)]
    pub json: bool,
}

/// `pf-viz smooth em`.
#[derive(Debug, Clone, Args)]
pub struct EmArgs {
    /// Data, θ, N, seed and output format.
    #[command(flatten)]
    pub common: ThetaArgs,
    /// Independent replications R (≥ 1).
    #[arg(long)]
    pub replications: usize,
    /// Lag δ of the fixed-lag estimator (eqs. (8)–(9)); adds `fixed_lag` to the output.
    #[arg(long)]
    pub lag: Option<usize>,
    /// Add forward-only (FFBSm) smoothing from the same particle runs, an O(N²)-per-step
    /// reference not in the paper; adds `forward` to the output.
    #[arg(long)]
    pub forward: bool,
}

/// `pf-viz smooth sem`.
#[derive(Debug, Clone, Args)]
pub struct SemArgs {
    /// Data, θ, N, seed and output format.
    #[command(flatten)]
    pub common: ThetaArgs,
    /// EM iterations I.
    #[arg(long)]
    pub iterations: usize,
    /// Independent SEM chains C (≥ 1).
    #[arg(long, default_value_t = 4)]
    pub chains: usize,
}

/// `pf-viz smooth score`.
#[derive(Debug, Clone, Args)]
pub struct ScoreArgs {
    /// Data, θ, N, seed and output format.
    #[command(flatten)]
    pub common: ThetaArgs,
    /// Independent replications R (≥ 1).
    #[arg(long)]
    pub replications: usize,
}

const PAPER: &str = "smooth";

/// Argument errors (σ ≤ 0, N = 0, …) are [`VizError::Argument`]; the rest is the paper's.
fn wrap(e: SmoothError) -> VizError {
    match e {
        SmoothError::Param(_) => VizError::Argument {
            message: format!("{PAPER}: {e}"),
        },
        e => VizError::paper(PAPER)(e),
    }
}

/// The `y` column, at least `Y_0, Y_1`; the arguments are validated before, so that a bad
/// value is named even when the file is also bad.
fn read(path: &Path) -> Result<Vec<f64>> {
    crate::data::read_y(path, 2)
}

/// Run a `pf-viz smooth` subcommand.
///
/// # Errors
/// Bad input, as a one-line message naming what and where.
pub fn run(cmd: SmoothCommand) -> Result<()> {
    match cmd {
        SmoothCommand::Em(a) => {
            let c = &a.common;
            let mut cfg = EmConfig {
                data: Observations::Given(Vec::new()),
                phi: c.phi,
                sigma: c.sigma,
                rho: c.rho,
                particles: c.particles,
                replications: a.replications,
                lag: a.lag,
                forward: a.forward,
                seed: c.seed,
            };
            cfg.validate().map_err(wrap)?;
            cfg.data = Observations::Given(read(&c.data)?);
            let out = em(&cfg).map_err(wrap)?;
            if c.json {
                return print_json(&out);
            }
            print_line(format_args!(
                "EM update (10)–(12) from φ = {}, σ = {}, ρ = {}; n = {}, N = {}, R = {}",
                c.phi, c.sigma, c.rho, out.n, c.particles, a.replications
            ))?;
            print_theta("exact", &out.exact)?;
            print_samples("joint (6)–(7)", &out.joint)?;
            if let (Some(f), Some(d)) = (&out.fixed_lag, a.lag) {
                print_samples(&format!("fixed-lag δ = {d}"), f)?;
            }
            if let Some(f) = &out.forward {
                print_samples("forward-only (FFBSm)", f)?;
            }
            Ok(())
        }
        SmoothCommand::Sem(a) => {
            let c = &a.common;
            let mut cfg = SemConfig {
                data: Observations::Given(Vec::new()),
                phi: c.phi,
                sigma: c.sigma,
                rho: c.rho,
                particles: c.particles,
                iterations: a.iterations,
                chains: a.chains,
                seed: c.seed,
            };
            cfg.validate().map_err(wrap)?;
            cfg.data = Observations::Given(read(&c.data)?);
            let out = sem(&cfg).map_err(wrap)?;
            if c.json {
                return print_json(&out);
            }
            print_line(format_args!(
                "SEM, N = {}, {} iteration(s), {} chain(s), from φ = {}, σ = {}, ρ = {}",
                c.particles, a.iterations, a.chains, c.phi, c.sigma, c.rho
            ))?;
            if let Some(last) = out.exact.last() {
                print_theta("exact EM, last iterate", last)?;
            }
            for (i, chain) in out.sem.iter().enumerate() {
                if let Some(last) = chain.last() {
                    print_theta(&format!("SEM chain {i}, last iterate"), last)?;
                }
            }
            Ok(())
        }
        SmoothCommand::Score(a) => {
            let c = &a.common;
            let mut cfg = ScoreConfig {
                data: Observations::Given(Vec::new()),
                phi: c.phi,
                sigma: c.sigma,
                rho: c.rho,
                particles: c.particles,
                replications: a.replications,
                seed: c.seed,
            };
            cfg.validate().map_err(wrap)?;
            cfg.data = Observations::Given(read(&c.data)?);
            let out = score(&cfg).map_err(wrap)?;
            if c.json {
                return print_json(&out);
            }
            print_line(format_args!(
                "Score ∇ℓ_n w.r.t. (φ, σ², ρ²) at φ = {}, σ = {}, ρ = {}; N = {}, R = {}",
                c.phi, c.sigma, c.rho, c.particles, a.replications
            ))?;
            print_theta("exact (Kalman/RTS)", &out.exact)?;
            print_samples("particle (Fisher's identity)", &out.particle)?;
            Ok(())
        }
    }
}

fn print_theta(label: &str, t: &Theta) -> Result<()> {
    print_line(format_args!(
        "  {label:<30} φ = {:>10.5}  σ² = {:>10.5}  ρ² = {:>10.5}",
        t.phi, t.sigma2, t.rho2
    ))
}

fn print_samples(label: &str, s: &ThetaSamples) -> Result<()> {
    let [(p, ps), (s2, s2s), (r2, r2s)] = s.mean_and_sd();
    print_line(format_args!(
        "  {label:<30} φ = {p:>10.5} ± {ps:.5}  σ² = {s2:>10.5} ± {s2s:.5}  ρ² = {r2:>10.5} ± {r2s:.5}  (mean ± sd)"
    ))
}
