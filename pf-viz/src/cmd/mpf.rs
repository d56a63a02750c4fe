//! `pf-viz mpf …`: Karlsson, Schön & Gustafsson, the marginalized particle filter and its
//! complexity.
//!
//! | subcommand | prints |
//! |---|---|
//! | `calibrate` | this machine's EF model: `{"flop_ns", "c1", "c2", "c3"}` |
//! | `ratio` | Figs. 1–2: `{"m": [3..9], "curves": [{"k", "ct_zero", "ct_nonzero"}]}` |
//! | `table2` / `table3` | `{"partitions": [{"name", "N", "rmse_pos", "rmse_vel", "rmse_acc", "time_s"}]}` plus the paper's table, the target and whether each search reached it |
//! | `advise` | partitions ranked by predicted cost on this machine |

use clap::{Args, Subcommand, ValueEnum};
use pf_mpf::advisor::{AdviseConfig, advise};
use pf_mpf::calibrate::{CalibrateConfig, calibrate};
use pf_mpf::complexity::CtCase;
use pf_mpf::experiments::{RatioConfig, Scale, TableConfig, TableReport, ratio, table2, table3};
use serde::Serialize;

use super::{print_json, print_line};
use crate::error::{Result, VizError};

/// The subcommands of `pf-viz mpf`.
#[derive(Debug, Clone, Subcommand)]
pub enum MpfCommand {
    /// Measure this machine's flop time and c1, c2, c3 in EF units (Section IV-A).
    Calibrate(CalibrateArgs),
    /// N(k)/N_PF for m = 3…9, n = 2: Figs. 1 (C_t = 0) and 2 (C_t ≠ 0).
    Ratio(JsonArg),
    /// Table II: the N each partition affords in the standard PF's time, and its RMSE.
    Table2(TableArgs),
    /// Table III: the N each partition needs for the standard PF's velocity RMSE.
    Table3(TableArgs),
    /// Rank the PF/KF partitions of a model by this machine's predicted cost.
    Advise(AdviseArgs),
}

/// Only `--json`.
#[derive(Debug, Clone, Args)]
pub struct JsonArg {
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `pf-viz mpf calibrate`.
#[derive(Debug, Clone, Args)]
pub struct CalibrateArgs {
    /// A few-millisecond calibration with fewer sizes and repetitions.
    #[arg(long)]
    pub quick: bool,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `pf-viz mpf table2|table3`.
#[derive(Debug, Clone, Args)]
pub struct TableArgs {
    /// Monte Carlo runs per RMSE, N_MC (default: the scale's; the paper's is 100).
    #[arg(long, value_name = "N")]
    pub mc: Option<usize>,
    /// Seed of the measurement noise and of the filters.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    /// Problem size: `quick` (150 particles, 4 runs, 20 steps), `default` (1000 particles,
    /// 16 runs, 50 steps; about a second here) or `full` (the paper's: 2000 particles,
    /// N_MC = 100, 100 steps; 9–14 s here on two cores).
    #[arg(long, value_name = "SCALE", default_value = "default")]
    pub scale: Scale,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Which complexity expression the advice uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CtArg {
    /// C_t = 0: one Riccati recursion shared by all particles, eq. (11).
    Zero,
    /// C_t ≠ 0: a Riccati recursion per particle, eq. (12).
    Nonzero,
}

/// Arguments of `pf-viz mpf advise`: exactly one of `--budget-s` and `--particles`.
#[derive(Debug, Clone, Args)]
#[command(group(clap::ArgGroup::new("size").required(true).args(["budget_s", "particles"])))]
pub struct AdviseArgs {
    /// States that must stay in the PF (the nonlinear ones).
    #[arg(long, value_name = "P")]
    pub p: usize,
    /// Linear-Gaussian states that may go to the KF.
    #[arg(long, value_name = "K")]
    pub k: usize,
    /// Time budget per filter step, seconds: rank by the particles each partition affords.
    #[arg(long, value_name = "F")]
    pub budget_s: Option<f64>,
    /// Particle count: rank by predicted time per step.
    #[arg(long, value_name = "N")]
    pub particles: Option<usize>,
    /// Whether the measurement depends on the KF states (C_t ≠ 0).
    #[arg(long, value_enum, default_value_t = CtArg::Zero)]
    pub ct: CtArg,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Run a `pf-viz mpf` subcommand.
///
/// # Errors
/// Bad input, as a one-line message naming what and where.
pub fn run(cmd: MpfCommand) -> Result<()> {
    let mpf = VizError::paper("mpf");
    match cmd {
        MpfCommand::Calibrate(a) => {
            let cfg = if a.quick {
                CalibrateConfig::quick()
            } else {
                CalibrateConfig::default()
            };
            let c = calibrate(&cfg).map_err(mpf)?;
            if a.json {
                print_json(&c)
            } else {
                print_line(format_args!(
                    "one flop = {:.4} ns; c1 = {:.0} EF (likelihood), c2 = {:.0} EF (resampling), c3 = {:.0} EF (random number); the paper's Pentium: c1 = 445, c2 = 487, c3 = 125",
                    c.flop_ns, c.c1, c.c2, c.c3
                ))?;
                Ok(())
            }
        }
        MpfCommand::Ratio(a) => {
            let r = ratio(&RatioConfig::default()).map_err(mpf)?;
            if a.json {
                return print_json(&r);
            }
            print_line(format_args!(
                "N(k)/N_PF at N_PF = 2000 with the paper's c1, c2, c3 (C_t = 0 / C_t ≠ 0):"
            ))?;
            for c in &r.curves {
                let cells: Vec<String> = r
                    .m
                    .iter()
                    .zip(c.ct_zero.iter().zip(&c.ct_nonzero))
                    .filter_map(|(m, (z, nz))| Some(format!("m={m}: {:.2}/{:.2}", (*z)?, (*nz)?)))
                    .collect();
                print_line(format_args!("  k = {}: {}", c.k, cells.join(", ")))?;
            }
            Ok(())
        }
        MpfCommand::Table2(a) => table(a, table2, "II (constant time)"),
        MpfCommand::Table3(a) => table(a, table3, "III (constant velocity RMSE)"),
        MpfCommand::Advise(a) => {
            let cfg = AdviseConfig {
                p: a.p,
                k: a.k,
                budget_s: a.budget_s,
                particles: a.particles,
                ct: match a.ct {
                    CtArg::Zero => CtCase::Zero,
                    CtArg::Nonzero => CtCase::NonZero,
                },
            };
            // Check the request before spending a second on the calibration.
            cfg.validate().map_err(mpf)?;
            let cal = calibrate(&CalibrateConfig::default()).map_err(mpf)?;
            let advice = advise(&cfg, &cal).map_err(mpf)?;
            if a.json {
                return print_json(&advice);
            }
            print_line(format_args!(
                "partitions of {} PF + {} linear states, best first:",
                a.p, a.k
            ))?;
            for o in &advice.options {
                print_line(format_args!(
                    "  p = {}, k = {}: N = {}, {:.3} ms per step",
                    o.p,
                    o.k,
                    o.n_particles,
                    o.time_s * 1e3
                ))?;
            }
            Ok(())
        }
    }
}

/// `table2 --json` / `table3 --json`: the contract's `partitions`, plus the paper's values
/// and the search outcome.
#[derive(Serialize)]
struct TableJson<'a> {
    partitions: &'a [pf_mpf::experiments::TableRow],
    paper: &'a [pf_mpf::experiments::TableRow],
    target: f64,
    reached: &'a [bool],
}

fn table(
    a: TableArgs,
    run: fn(&TableConfig) -> pf_mpf::Result<TableReport>,
    which: &str,
) -> Result<()> {
    let mut cfg = TableConfig::at_scale(a.scale);
    cfg.seed = a.seed;
    if let Some(mc) = a.mc {
        if mc == 0 {
            return Err(VizError::Argument {
                message: "--mc must be at least 1".into(),
            });
        }
        cfg.n_mc = mc;
    }
    let r = run(&cfg).map_err(VizError::paper("mpf"))?;
    if a.json {
        return print_json(&TableJson {
            partitions: &r.table.partitions,
            paper: &r.paper.partitions,
            target: r.target,
            reached: &r.reached,
        });
    }
    print_line(format_args!(
        "Table {which}, N_MC = {} (paper's values in brackets):",
        cfg.n_mc
    ))?;
    for (ours, paper) in r.table.partitions.iter().zip(&r.paper.partitions) {
        print_line(format_args!("  {}", ours.against(paper)))?;
    }
    Ok(())
}
