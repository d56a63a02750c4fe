//! `pf-viz dredge …`: Babuška et al.: on-line estimation of overflow losses in a hopper dredger.
//!
//! ```text
//! pf-viz dredge simulate --out FILE.csv [--seed S]
//! pf-viz dredge estimate --data FILE.csv [--particles N] [--seed S] [--runs R] [--json]
//! pf-viz dredge estimate --data - --online [--particles N] [--seed S] [--runs R]
//! ```
//! `--online` prints one JSON line per sample, so it conflicts with `--json`, whose
//! contract is exactly one object on stdout.
//! The CSV format (header `t,V_t,m_t,Q_i,rho_i[,Q_o,rho_o]`) is [`pf_dredge::logfile`]'s;
//! this module only wires files, stdin and stdout to it.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use pf_dredge::experiments::{CycleConfig, cycle};
use pf_dredge::logfile::{CsvSamples, read_csv, write_csv};
use pf_dredge::{DredgeError, EstimateConfig, EstimatorConfig, OnlineMean, estimate};

use crate::cmd::print_line;
use crate::error::{Result, VizError};

/// The subcommands of `pf-viz dredge`.
#[derive(Debug, Clone, Subcommand)]
pub enum DredgeCommand {
    /// Write a simulated loading cycle (Section II, all three phases) as CSV, truth included.
    Simulate(SimulateArgs),
    /// Estimate Q_o and ρ_o from logged data (a CSV file, or stdin with `--data -`).
    Estimate(EstimateArgs),
}

/// `pf-viz dredge simulate`.
#[derive(Debug, Clone, Args)]
pub struct SimulateArgs {
    /// Output CSV file: t, V_t, m_t, Q_i, rho_i, Q_o, rho_o.
    #[arg(long)]
    pub out: PathBuf,
    /// Seed of the measurement noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// `pf-viz dredge estimate`.
#[derive(Debug, Clone, Args)]
pub struct EstimateArgs {
    /// CSV data file with header `t,V_t,m_t,Q_i,rho_i` (optional truth `Q_o,rho_o`); `-`
    /// reads stdin.
    #[arg(long)]
    pub data: PathBuf,
    /// Particles N (the paper's 1000; N_T stays 0.9 N).
    #[arg(long, default_value_t = 1000)]
    pub particles: usize,
    /// Seed: filter run r uses stream r of this seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Independent filter runs; the estimate is their mean.
    #[arg(long, default_value_t = 1)]
    pub runs: usize,
    /// On-line: print one JSON line `{"t","Q_o","rho_o"}` per input sample as it arrives
    /// (not with `--json`: that promises one object).
    #[arg(long, conflicts_with = "json")]
    pub online: bool,
    /// Print one JSON object on stdout (the file mode's contract; not with `--online`).
    #[arg(long)]
    pub json: bool,
}

/// Run a `pf-viz dredge` subcommand.
///
/// # Errors
/// Bad input, as a one-line message naming the file, the line and the problem.
pub fn run(cmd: DredgeCommand) -> Result<()> {
    match cmd {
        DredgeCommand::Simulate(a) => run_simulate(&a),
        DredgeCommand::Estimate(a) => run_estimate(&a),
    }
}

/// A pf-dredge error on `path`: CSV problems become [`VizError::Data`] with their line.
fn data_err(path: &Path) -> impl Fn(DredgeError) -> VizError + '_ {
    move |e| match e {
        DredgeError::Csv { line, message } => VizError::Data {
            path: path.to_owned(),
            line: Some(line),
            message,
        },
        other => VizError::paper("dredge")(other),
    }
}

fn run_simulate(a: &SimulateArgs) -> Result<()> {
    let cycle = cycle(&CycleConfig {
        seed: a.seed,
        ..CycleConfig::default()
    })
    .map_err(VizError::paper("dredge"))?;
    let data = cycle.to_data();
    crate::io::write_atomic(&a.out, |w| {
        write_csv(&data, w).map_err(|e| VizError::Io {
            path: a.out.clone(),
            source: std::io::Error::other(e.to_string()),
        })
    })?;
    print_line(format_args!(
        "pf-viz dredge: wrote {} samples ({} s, phase 2 from sample {}, phase 3 from sample {}) to {}",
        data.len(),
        data.t.last().copied().unwrap_or_default(),
        cycle.phase2_start.map_or("-".into(), |k| k.to_string()),
        cycle.phase3_start.map_or("-".into(), |k| k.to_string()),
        a.out.display()
    ))?;
    Ok(())
}

fn config(a: &EstimateArgs) -> Result<EstimateConfig> {
    if a.particles == 0 {
        return Err(VizError::Argument {
            message: "--particles must be at least 1".into(),
        });
    }
    if a.runs == 0 {
        return Err(VizError::Argument {
            message: "--runs must be at least 1".into(),
        });
    }
    Ok(EstimateConfig {
        filter: EstimatorConfig::default().with_particles(a.particles),
        runs: a.runs,
        seed: a.seed,
        ..EstimateConfig::default()
    })
}

fn open(path: &Path) -> Result<Box<dyn BufRead>> {
    if path == Path::new("-") {
        Ok(Box::new(std::io::stdin().lock()))
    } else {
        let f = std::fs::File::open(path).map_err(VizError::io(path))?;
        Ok(Box::new(BufReader::new(f)))
    }
}

fn display_path(path: &Path) -> PathBuf {
    if path == Path::new("-") {
        PathBuf::from("<stdin>")
    } else {
        path.to_owned()
    }
}

fn run_estimate(a: &EstimateArgs) -> Result<()> {
    let cfg = config(a)?;
    let shown = display_path(&a.data);
    let input = open(&a.data)?;
    if a.online {
        return run_online(input, &shown, &cfg);
    }
    let data = read_csv(input).map_err(data_err(&shown))?;
    let out = estimate(&data, &cfg).map_err(data_err(&shown))?;
    if a.json {
        return crate::cmd::print_json(&out);
    }
    let n = out.t.len();
    print_line(format_args!(
        "pf-viz dredge: {n} samples, N = {}, {} run(s), seed {}; last estimate Q_o = {:.3} m³/s, rho_o = {:.1} kg/m³",
        a.particles,
        a.runs,
        a.seed,
        out.q_o[n - 1],
        out.rho_o[n - 1]
    ))?;
    if let Some(r) = &out.residuals {
        for (name, unit, s) in [("Q_o", "m³/s", r.q_o), ("rho_o", "kg/m³", r.rho_o)] {
            if let Some(s) = s {
                print_line(format_args!(
                    "  residual {name}: mean {:.3}, std {:.3}, max |·| {:.3} {unit}",
                    s.mean, s.std, s.max_abs
                ))?;
            }
        }
    }
    Ok(())
}

/// One estimator per run (run `r` on the stream `(seed, r)`, as the file mode), each sample
/// pushed through all of them and their mean printed and flushed at once: the same numbers
/// as the file mode ([`OnlineMean`]).
fn run_online(input: Box<dyn BufRead>, shown: &Path, cfg: &EstimateConfig) -> Result<()> {
    let err = data_err(shown);
    let mut rows = CsvSamples::new(input).map_err(&err)?;
    let mut mean = OnlineMean::new(cfg).map_err(&err)?;
    for row in &mut rows {
        let row = row.map_err(&err)?;
        let est = mean.push(&row.sample).map_err(|e| VizError::Data {
            path: shown.to_owned(),
            line: Some(row.line),
            message: e.to_string(),
        })?;
        let line = serde_json::to_string(&est).map_err(|e| VizError::Argument {
            message: format!("cannot serialise the estimate: {e}"),
        })?;
        print_line(line)?;
    }
    Ok(())
}
