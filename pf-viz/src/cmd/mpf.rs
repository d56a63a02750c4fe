//! `pf-viz mpf …`: Karlsson, Schön & Gustafsson, the marginalized particle filter and its
//! complexity.
//!
//! | subcommand | prints |
//! |---|---|
//! | `calibrate` | this machine's EF model: `{"flop_ns", "c1", "c2", "c3"}`, plus `"spread"` (relative, bootstrap over rounds), `"rounds"`, `"clock"`, `"notes"` |
//! | `ratio` | Figs. 1–2: `{"m": [3..9], "curves": [{"k", "ct_zero", "ct_nonzero"}]}` |
//! | `table2` / `table3` | `{"partitions": [{"name", "N", "rmse_pos", "rmse_vel", "rmse_acc", "time_s"}]}` plus the paper's table, the target and whether each search reached it; `table2` adds to each partition `"predicted_N"` (eq. (11), calibrated) and `"predicted_N_ext"` (the extended model), and `"model"` (calibration, `c_m`, per-particle terms) |
//! | `advise` | partitions ranked by predicted cost on this machine |

use clap::{Args, Subcommand, ValueEnum};
use pf_mpf::advisor::{AdviseConfig, advise};
use pf_mpf::calibrate::{CalibrateConfig, CalibrationReport, calibrate, calibrate_report};
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
    /// Interleaved timing rounds (default: 15, with --quick 3); the median over rounds is fitted.
    #[arg(long, value_name = "R")]
    pub rounds: Option<usize>,
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
            let mut cfg = if a.quick {
                CalibrateConfig::quick()
            } else {
                CalibrateConfig::default()
            };
            if let Some(r) = a.rounds {
                cfg.rounds = r;
            }
            let r = calibrate_report(&cfg).map_err(mpf)?;
            if a.json {
                return print_json(&CalibrateJson::from(&r));
            }
            let (c, s) = (r.calibration, r.spread);
            print_line(format_args!(
                "one flop = {:.4} ns (±{:.1} %); c1 = {:.0} EF (likelihood, ±{:.1} %), c2 = {:.0} EF (resampling, ±{:.1} %), c3 = {:.0} EF (random number, ±{:.1} %); the paper's Sun Blade 100: c1 = 445, c2 = 487, c3 = 125",
                c.flop_ns,
                100.0 * s.flop_ns,
                c.c1,
                100.0 * s.c1,
                c.c2,
                100.0 * s.c2,
                c.c3,
                100.0 * s.c3
            ))?;
            print_line(format_args!(
                "({} interleaved rounds on the {}; ± is the bootstrap over rounds)",
                r.rounds, r.clock
            ))?;
            for n in &r.notes {
                print_line(format_args!("note: {n}"))?;
            }
            Ok(())
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

/// `calibrate --json`: the contract's four numbers, then how they were measured.
#[derive(Serialize)]
struct CalibrateJson<'a> {
    #[serde(flatten)]
    calibration: pf_mpf::calibrate::Calibration,
    spread: pf_mpf::calibrate::CalibrationSpread,
    rounds: usize,
    clock: &'a str,
    notes: &'a [String],
}

impl<'a> From<&'a CalibrationReport> for CalibrateJson<'a> {
    fn from(r: &'a CalibrationReport) -> Self {
        Self {
            calibration: r.calibration,
            spread: r.spread,
            rounds: r.rounds,
            clock: &r.clock,
            notes: &r.notes,
        }
    }
}

/// One partition of `table2|table3 --json`: the contract's keys, then Table II's model.
#[derive(Serialize)]
struct RowJson<'a> {
    #[serde(flatten)]
    row: &'a pf_mpf::experiments::TableRow,
    #[serde(rename = "predicted_N", skip_serializing_if = "Option::is_none")]
    predicted_n: Option<u64>,
    #[serde(rename = "predicted_N_ext", skip_serializing_if = "Option::is_none")]
    predicted_n_ext: Option<u64>,
}

/// `table2 --json` / `table3 --json`: the contract's `partitions`, plus the paper's values
/// and the search outcome.
#[derive(Serialize)]
struct TableJson<'a> {
    partitions: Vec<RowJson<'a>>,
    paper: &'a [pf_mpf::experiments::TableRow],
    target: f64,
    reached: &'a [bool],
    #[serde(skip_serializing_if = "Option::is_none")]
    model: Option<&'a pf_mpf::experiments::ModelPrediction>,
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
    let model = r.model.as_ref();
    let at = |v: Option<&Vec<f64>>, j: usize| {
        v.and_then(|v| v.get(j))
            .filter(|x| x.is_finite() && **x >= 0.0)
            .map(|x| x.round() as u64)
    };
    if a.json {
        let partitions = r
            .table
            .partitions
            .iter()
            .enumerate()
            .map(|(j, row)| RowJson {
                row,
                predicted_n: at(model.map(|m| &m.predicted_n), j),
                predicted_n_ext: at(model.map(|m| &m.predicted_n_ext), j),
            })
            .collect();
        return print_json(&TableJson {
            partitions,
            paper: &r.paper.partitions,
            target: r.target,
            reached: &r.reached,
            model,
        });
    }
    print_line(format_args!(
        "Table {which}, N_MC = {} (paper's values in brackets):",
        cfg.n_mc
    ))?;
    for (j, (ours, paper)) in r
        .table
        .partitions
        .iter()
        .zip(&r.paper.partitions)
        .enumerate()
    {
        match (
            at(model.map(|m| &m.predicted_n), j),
            at(model.map(|m| &m.predicted_n_ext), j),
        ) {
            (Some(n), Some(e)) => print_line(format_args!(
                "  {}; the calibrated model predicts N = {n} (eq. (11)), {e} (extended)",
                ours.against(paper)
            ))?,
            _ => print_line(format_args!("  {}", ours.against(paper)))?,
        }
    }
    for n in model.map_or(&[][..], |m| &m.notes[..]) {
        print_line(format_args!("note: {n}"))?;
    }
    Ok(())
}
