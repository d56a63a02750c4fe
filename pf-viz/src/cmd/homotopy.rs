//! `pf-viz homotopy …`: Morelande et al., the optimal homotopy filter for bearings-only
//! tracking.
//!
//! | subcommand | prints |
//! |---|---|
//! | `rmse` | `{"time", "rmse": {"OHF", "AOHF", "UKF-LPC", "PF"}, "seconds_per_run": {…}, "final_errors": {…}}` (Fig. 3) |
//! | `ellipses` | `{"truth": [x, y], "lambda", "ellipses": [{"center", "semi_axes", "angle"}]}` (Fig. 2) |
//!
//! Both take `--turn clockwise|counter-clockwise` and `--sigma-deg`, the scenario values the
//! paper leaves unstated (defaults: clockwise, ½°).

use clap::{Args, Subcommand, ValueEnum};
use pf_homotopy::experiments::{EllipsesConfig, RmseConfig, Scale, ellipses, rmse};
use pf_homotopy::filters::Algorithm;
use pf_homotopy::model::ScenarioConfig;

use super::{print_json, print_line};
use crate::error::{Result, VizError};

/// The subcommands of `pf-viz homotopy`.
#[derive(Debug, Clone, Subcommand)]
pub enum HomotopyCommand {
    /// RMS position error against time for UKF-LPC, PF, OHF and AOHF (Fig. 3), and the cost.
    Rmse(RmseArgs),
    /// Error ellipses of the OHF parameterisation over λ at one sample (Fig. 2).
    Ellipses(EllipsesArgs),
}

/// Direction of the observer's 30°/s turn (the paper does not say).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Turn {
    /// Clockwise: the default, the geometry of the paper's Section 4.1 (see the README).
    Clockwise,
    /// Counter-clockwise.
    CounterClockwise,
}

/// The scenario values the paper leaves unstated.
#[derive(Debug, Clone, Args)]
pub struct ScenarioArgs {
    /// Direction of the observer's turn.
    #[arg(long, value_enum, default_value_t = Turn::Clockwise)]
    pub turn: Turn,
    /// Bearing noise standard deviation σ, degrees (default ½).
    #[arg(long, value_name = "DEG")]
    pub sigma_deg: Option<f64>,
}

impl ScenarioArgs {
    /// The default scenario with these values.
    fn scenario(&self) -> ScenarioConfig {
        let base = ScenarioConfig::default();
        let rate = base.turn_rate_deg.abs();
        ScenarioConfig {
            turn_rate_deg: match self.turn {
                Turn::Clockwise => -rate,
                Turn::CounterClockwise => rate,
            },
            sigma_deg: self.sigma_deg.unwrap_or(base.sigma_deg),
            ..base
        }
    }
}

/// Arguments of `pf-viz homotopy rmse`.
#[derive(Debug, Clone, Args)]
pub struct RmseArgs {
    /// Monte Carlo realisations (default: the scale's).
    #[arg(long, value_name = "R")]
    pub realisations: Option<usize>,
    /// Particles of the PF (default: the scale's).
    #[arg(long, value_name = "N")]
    pub particles: Option<usize>,
    /// Seed: realisation r uses stream (S, r).
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// Size preset for what the flags leave unset: `quick` (8 realisations, a
    /// 2 000-particle PF), `default` (40 realisations, the paper's 100 000-particle PF) or
    /// `full` (the paper's: 500 realisations, a 100 000-particle PF).
    #[arg(long, value_name = "SCALE", default_value = "default")]
    pub scale: Scale,
    /// The unstated scenario values.
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `pf-viz homotopy ellipses`.
#[derive(Debug, Clone, Args)]
pub struct EllipsesArgs {
    /// The sampling instant K (the paper's is 17).
    #[arg(long, value_name = "K", default_value_t = 17)]
    pub step: usize,
    /// Seed of the realisation.
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// The unstated scenario values.
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Run a `pf-viz homotopy` subcommand.
///
/// # Errors
/// Bad arguments, as a one-line message.
pub fn run(cmd: HomotopyCommand) -> Result<()> {
    let homotopy = VizError::paper("homotopy");
    match cmd {
        HomotopyCommand::Rmse(a) => {
            let mut cfg = RmseConfig::at_scale(a.scale);
            cfg.seed = a.seed;
            cfg.scenario = a.scenario.scenario();
            if let Some(r) = a.realisations {
                cfg.realisations = r;
            }
            if let Some(n) = a.particles {
                cfg.filters.particles = n;
            }
            let r = rmse(&cfg).map_err(homotopy)?;
            if a.json {
                return print_json(&r);
            }
            let last = r.time.len() - 1;
            print_line(format_args!(
                "RMS position error at t = {} s over {} realisations (PF: N = {}):",
                r.time[last], cfg.realisations, cfg.filters.particles
            ))?;
            for alg in Algorithm::ALL {
                let worst = r.final_errors.get(alg).iter().copied().fold(0.0, f64::max);
                print_line(format_args!(
                    "  {:8} {:8.0} m   {:.4} s per run   worst final error {worst:.0} m",
                    alg.name(),
                    r.rmse.get(alg)[last],
                    r.seconds_per_run.get(alg)
                ))?;
            }
            Ok(())
        }
        HomotopyCommand::Ellipses(a) => {
            let cfg = EllipsesConfig {
                step: a.step,
                seed: a.seed,
                scenario: a.scenario.scenario(),
                ..EllipsesConfig::default()
            };
            let r = ellipses(&cfg).map_err(homotopy)?;
            if a.json {
                return print_json(&r);
            }
            print_line(format_args!(
                "OHF at sample {}: truth ({:.0}, {:.0}) m",
                a.step, r.truth[0], r.truth[1]
            ))?;
            for (l, e) in r.lambda.iter().zip(&r.ellipses) {
                print_line(format_args!(
                    "  λ = {l:.2}: centre ({:.0}, {:.0}) m, semi-axes {:.0} × {:.0} m",
                    e.center[0], e.center[1], e.semi_axes[0], e.semi_axes[1]
                ))?;
            }
            Ok(())
        }
    }
}
