//! `pf-viz smooth …`: Cappé & Moulines, particle estimates of smoothed additive functionals
//! for maximum-likelihood estimation in the noisy AR(1) model.
//!
//! The data file is CSV with a header; its `y` column holds `Y_0 … Y_n` (other columns are
//! ignored). θ is given by φ and the standard deviations σ, ρ; the outputs use the
//! variances (φ, σ², ρ²) that the EM updates (10)–(12) produce.
//!
//! | subcommand | prints |
//! |---|---|
//! | `em` | `{"n", "exact": θ, "joint": {"phi": [R], "sigma2": [R], "rho2": [R]}, "fixed_lag"?}` |
//! | `sem` | `{"exact": [θ per iteration], "sem": [[θ per iteration] per chain]}` |
//! | `score` | `{"exact": ∇ℓ, "particle": {"phi": [R], "sigma2": [R], "rho2": [R]}}` |

use std::path::PathBuf;

use clap::{Args, Subcommand};
use pf_smooth::cli::{EmArgs, ScoreArgs, SemArgs, em, score, sem};

use super::print_json;
use crate::data::read_y;
use crate::error::{Result, VizError};

/// The subcommands of `pf-viz smooth`.
#[derive(Debug, Clone, Subcommand)]
pub enum SmoothCommand {
    /// One EM update (10)–(12) from θ: exact, and from R particle runs (joint, fixed-lag).
    Em(EmCmd),
    /// Stochastic EM chains over the exact EM trajectory (Fig. 4).
    Sem(SemCmd),
    /// The score ∇ℓ_n(θ) by Fisher's identity: exact, and from R particle runs.
    Score(ScoreCmd),
}

/// θ and the data, common to every subcommand.
#[derive(Debug, Clone, Args)]
pub struct Common {
    /// CSV file with a header and a `y` column holding Y_0…Y_n.
    #[arg(long, value_name = "FILE")]
    pub data: PathBuf,
    /// φ, the autoregression coefficient.
    #[arg(long, value_name = "F", allow_negative_numbers = true)]
    pub phi: f64,
    /// σ, the state noise standard deviation (> 0).
    #[arg(long, value_name = "F", allow_negative_numbers = true)]
    pub sigma: f64,
    /// ρ, the observation noise standard deviation (> 0).
    #[arg(long, value_name = "F", allow_negative_numbers = true)]
    pub rho: f64,
    /// Particles N.
    #[arg(long, value_name = "N")]
    pub particles: usize,
    /// Seed: replication (or chain) r uses stream (S, r).
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `pf-viz smooth em`.
#[derive(Debug, Clone, Args)]
pub struct EmCmd {
    /// The data, θ, N, seed and output format.
    #[command(flatten)]
    pub common: Common,
    /// Independent particle runs R.
    #[arg(long, value_name = "R")]
    pub replications: usize,
    /// Lag δ of the fixed-lag estimator (adds `fixed_lag` to the output).
    #[arg(long, value_name = "D")]
    pub lag: Option<usize>,
}

/// Arguments of `pf-viz smooth sem`.
#[derive(Debug, Clone, Args)]
pub struct SemCmd {
    /// The data, θ, N, seed and output format.
    #[command(flatten)]
    pub common: Common,
    /// SEM iterations I.
    #[arg(long, value_name = "I")]
    pub iterations: usize,
    /// Independent chains C.
    #[arg(long, value_name = "C", default_value_t = 4)]
    pub chains: usize,
}

/// Arguments of `pf-viz smooth score`.
#[derive(Debug, Clone, Args)]
pub struct ScoreCmd {
    /// The data, θ, N, seed and output format.
    #[command(flatten)]
    pub common: Common,
    /// Independent particle runs R.
    #[arg(long, value_name = "R")]
    pub replications: usize,
}

/// Run a `pf-viz smooth` subcommand.
///
/// # Errors
/// A bad data file (naming the file and line) or a bad argument, as one line.
pub fn run(cmd: SmoothCommand) -> Result<()> {
    let smooth = VizError::paper("smooth");
    match cmd {
        SmoothCommand::Em(a) => {
            let c = &a.common;
            let args = EmArgs {
                phi: c.phi,
                sigma: c.sigma,
                rho: c.rho,
                particles: c.particles,
                replications: a.replications,
                lag: a.lag,
                seed: c.seed,
            };
            // Arguments first: a bad σ is reported before the file is read.
            args.validate().map_err(smooth)?;
            let y = read_y(&c.data, 2)?;
            let out = em(&y, &args).map_err(smooth)?;
            if c.json {
                return print_json(&out);
            }
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
            println!(
                "EM update from θ = ({}, {}², {}²), n = {}:",
                c.phi, c.sigma, c.rho, out.n
            );
            println!(
                "  exact:            φ = {:.4}, σ² = {:.4}, ρ² = {:.4}",
                out.exact.phi, out.exact.sigma2, out.exact.rho2
            );
            println!(
                "  joint (mean of {}): φ = {:.4}, σ² = {:.4}, ρ² = {:.4}",
                a.replications,
                mean(&out.joint.phi),
                mean(&out.joint.sigma2),
                mean(&out.joint.rho2)
            );
            if let Some(f) = &out.fixed_lag {
                println!(
                    "  fixed lag δ = {}: φ = {:.4}, σ² = {:.4}, ρ² = {:.4}",
                    a.lag.unwrap_or(0),
                    mean(&f.phi),
                    mean(&f.sigma2),
                    mean(&f.rho2)
                );
            }
            Ok(())
        }
        SmoothCommand::Sem(a) => {
            let c = &a.common;
            let args = SemArgs {
                phi: c.phi,
                sigma: c.sigma,
                rho: c.rho,
                particles: c.particles,
                iterations: a.iterations,
                chains: a.chains,
                seed: c.seed,
            };
            args.validate().map_err(smooth)?;
            let y = read_y(&c.data, 2)?;
            let out = sem(&y, &args).map_err(smooth)?;
            if c.json {
                return print_json(&out);
            }
            let last = out.exact.len() - 1;
            let e = out.exact[last];
            println!(
                "after {} iterations: exact EM φ = {:.4}, σ² = {:.4}, ρ² = {:.4}",
                a.iterations, e.phi, e.sigma2, e.rho2
            );
            for (i, chain) in out.sem.iter().enumerate() {
                let t = chain[last];
                println!(
                    "  SEM chain {i}: φ = {:.4}, σ² = {:.4}, ρ² = {:.4}",
                    t.phi, t.sigma2, t.rho2
                );
            }
            Ok(())
        }
        SmoothCommand::Score(a) => {
            let c = &a.common;
            let args = ScoreArgs {
                phi: c.phi,
                sigma: c.sigma,
                rho: c.rho,
                particles: c.particles,
                replications: a.replications,
                seed: c.seed,
            };
            args.validate().map_err(smooth)?;
            let y = read_y(&c.data, 2)?;
            let out = score(&y, &args).map_err(smooth)?;
            if c.json {
                return print_json(&out);
            }
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
            println!(
                "score ∂ℓ/∂(φ, σ², ρ²): exact ({:.3}, {:.3}, {:.3}); particle mean of {} ({:.3}, {:.3}, {:.3})",
                out.exact.phi,
                out.exact.sigma2,
                out.exact.rho2,
                a.replications,
                mean(&out.particle.phi),
                mean(&out.particle.sigma2),
                mean(&out.particle.rho2)
            );
            Ok(())
        }
    }
}
