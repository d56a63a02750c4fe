//! `pf-viz homotopy …`: Morelande et al.: the optimal homotopy filter for bearings-only tracking.
//!
//! ```text
//! pf-viz homotopy rmse [--realisations R] [--particles N] [--seed S] --json
//!   -> {"time": [..], "rmse": {"OHF": [..], "AOHF": [..], "UKF-LPC": [..], "PF": [..]},
//!       "seconds_per_run": {"OHF": f, "AOHF": f, "UKF-LPC": f, "PF": f}}
//! pf-viz homotopy ellipses [--step K] [--seed S] --json
//!   -> {"truth": [x, y], "lambda": [..], "ellipses": [{"center": [x,y], "semi_axes": [a,b], "angle": f}, ...]}
//! ```

use clap::{Args, Subcommand};
use pf_homotopy::experiments::{
    EllipsesConfig, EllipsesResult, RmseConfig, RmseResult, Scale, ellipses, rmse,
};

use crate::error::{Result, VizError};

/// The subcommands of `pf-viz homotopy`.
#[derive(Debug, Clone, Subcommand)]
pub enum HomotopyCommand {
    /// Fig. 3: RMS position error against time for OHF, AOHF, UKF-LPC and the PF, and the
    /// seconds per filter run.
    Rmse(RmseArgs),
    /// Fig. 2: error ellipses of the OHF parameterisation θ_K(λ) for λ = 0, ¼, ½, ¾, 1.
    Ellipses(EllipsesArgs),
}

/// Arguments of `pf-viz homotopy rmse`.
#[derive(Debug, Clone, Args)]
pub struct RmseArgs {
    /// Number of realisations R (the paper: 500).
    #[arg(long, default_value_t = 40)]
    pub realisations: usize,
    /// Particles N of the PF (the paper: 100 000).
    #[arg(long, default_value_t = 10_000)]
    pub particles: usize,
    /// Seed: realisation r uses stream r of this seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `pf-viz homotopy ellipses`.
#[derive(Debug, Clone, Args)]
pub struct EllipsesArgs {
    /// Sampling instant K (the paper: 17, just after the observer's manoeuvre).
    #[arg(long, default_value_t = 17)]
    pub step: usize,
    /// Seed of the realisation.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Run a `pf-viz homotopy` subcommand.
///
/// # Errors
/// Bad input, as a one-line message naming what and where.
pub fn run(cmd: HomotopyCommand) -> Result<()> {
    match cmd {
        HomotopyCommand::Rmse(a) => run_rmse(&a),
        HomotopyCommand::Ellipses(a) => run_ellipses(&a),
    }
}

fn argument(message: String) -> VizError {
    VizError::Argument { message }
}

fn run_rmse(a: &RmseArgs) -> Result<()> {
    if a.realisations == 0 {
        return Err(argument("--realisations must be at least 1".into()));
    }
    if a.particles == 0 {
        return Err(argument("--particles must be at least 1".into()));
    }
    let mut cfg = RmseConfig::at_scale(Scale::Default);
    cfg.realisations = a.realisations;
    cfg.filters.particles = a.particles;
    cfg.seed = a.seed;
    let res = rmse(&cfg).map_err(VizError::paper("homotopy"))?;
    if a.json {
        crate::cmd::print_json(&res)
    } else {
        print_rmse(&cfg, &res);
        Ok(())
    }
}

fn print_rmse(cfg: &RmseConfig, res: &RmseResult) {
    println!(
        "homotopy rmse: {} realisations, PF with N = {}, seed {}",
        cfg.realisations, cfg.filters.particles, cfg.seed
    );
    println!(
        "{:<8} {:>16} {:>16}",
        "filter", "final RMS (m)", "s per run"
    );
    for (name, r, s) in [
        ("OHF", &res.rmse.ohf, res.seconds_per_run.ohf),
        ("AOHF", &res.rmse.aohf, res.seconds_per_run.aohf),
        ("UKF-LPC", &res.rmse.ukf_lpc, res.seconds_per_run.ukf_lpc),
        ("PF", &res.rmse.pf, res.seconds_per_run.pf),
    ] {
        let last = r.last().copied().unwrap_or(f64::NAN);
        println!("{name:<8} {last:>16.1} {s:>16.4}");
    }
}

fn run_ellipses(a: &EllipsesArgs) -> Result<()> {
    let mut cfg = EllipsesConfig {
        step: a.step,
        seed: a.seed,
        ..EllipsesConfig::default()
    };
    let n = cfg.scenario.n_samples;
    if a.step < 2 || a.step > n {
        return Err(argument(format!(
            "--step {} is outside the scenario: it must lie in 2..={n} (sample 1 only initialises)",
            a.step
        )));
    }
    cfg.step = a.step;
    let res = ellipses(&cfg).map_err(VizError::paper("homotopy"))?;
    if a.json {
        crate::cmd::print_json(&res)
    } else {
        print_ellipses(&cfg, &res);
        Ok(())
    }
}

fn print_ellipses(cfg: &EllipsesConfig, res: &EllipsesResult) {
    println!(
        "homotopy ellipses at sample {} (seed {}), {:.0}% ellipses; truth ({:.1}, {:.1}) m",
        cfg.step,
        cfg.seed,
        100.0 * cfg.mass,
        res.truth[0],
        res.truth[1]
    );
    println!(
        "{:>6} {:>12} {:>12} {:>10} {:>10} {:>9}",
        "λ", "x (m)", "y (m)", "a (m)", "b (m)", "angle°"
    );
    for (l, e) in res.lambda.iter().zip(&res.ellipses) {
        println!(
            "{l:>6.2} {:>12.1} {:>12.1} {:>10.1} {:>10.1} {:>9.1}",
            e.center[0],
            e.center[1],
            e.semi_axes[0],
            e.semi_axes[1],
            e.angle.to_degrees()
        );
    }
}
