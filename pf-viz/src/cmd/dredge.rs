//! `pf-viz dredge …`: Babuška et al., on-line estimation of overflow losses in a hopper
//! dredger.
//!
//! The data file is CSV with a header and the columns `t` (s), `V_t` (m³), `m_t` (kg),
//! `Q_i` (m³/s) and `rho_i` (kg/m³); the optional truth columns `Q_o`, `rho_o` turn on
//! residual statistics. An empty cell is a missing measurement (no reweighting for `V_t`,
//! `m_t`; the last value held for `Q_i`, `ρ_i`).

use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use pf_core::mc::stream_rng;
use pf_dredge::{
    DredgeData, DredgeError, EstimateConfig, EstimatorConfig, OnlineEstimator, Sample, SimConfig,
    Truth, estimate, simulate,
};

use super::print_json;
use crate::error::{Result, VizError};
use crate::io::write_atomic;

/// The subcommands of `pf-viz dredge`.
#[derive(Debug, Clone, Subcommand)]
pub enum DredgeCommand {
    /// Simulate a loading cycle and write it as CSV, truth columns included.
    Simulate(SimulateArgs),
    /// Estimate Q_o and ρ_o from logged data (off-line from a file, or on-line from stdin).
    Estimate(EstimateArgs),
}

/// Arguments of `pf-viz dredge simulate`.
#[derive(Debug, Clone, Args)]
pub struct SimulateArgs {
    /// The CSV file to write (atomically).
    #[arg(long, value_name = "FILE.csv")]
    pub out: PathBuf,
    /// Seed of the measurement noise.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
}

/// Arguments of `pf-viz dredge estimate`.
#[derive(Debug, Clone, Args)]
pub struct EstimateArgs {
    /// The CSV data file, or `-` for standard input.
    #[arg(long, value_name = "FILE.csv")]
    pub data: PathBuf,
    /// Particles N (the paper's 1000).
    #[arg(long, value_name = "N", default_value_t = 1000)]
    pub particles: usize,
    /// Seed: filter run r uses stream (S, r).
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    /// Independent filter runs R; the estimate is their mean.
    #[arg(long, value_name = "R", default_value_t = 1)]
    pub runs: usize,
    /// Read samples one at a time and print each estimate as a JSON line as it arrives.
    #[arg(long, conflicts_with_all = ["runs", "json"])]
    pub online: bool,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

const COLUMNS: [&str; 5] = ["t", "V_t", "m_t", "Q_i", "rho_i"];

/// Where each column sits in the header.
struct Layout {
    at: [usize; 5],
    q_o: Option<usize>,
    rho_o: Option<usize>,
}

impl Layout {
    fn new(header: &csv::StringRecord, path: &Path) -> Result<Self> {
        let find = |name: &str| header.iter().position(|h| h.trim() == name);
        let mut at = [0; 5];
        for (slot, name) in at.iter_mut().zip(COLUMNS) {
            *slot = find(name).ok_or_else(|| VizError::Data {
                path: path.to_owned(),
                line: Some(1),
                message: format!(
                    "missing column {name:?} (the header needs t, V_t, m_t, Q_i, rho_i)"
                ),
            })?;
        }
        Ok(Layout {
            at,
            q_o: find("Q_o"),
            rho_o: find("rho_o"),
        })
    }
}

/// One parsed row: the sample and its truth cells.
type Row = (Sample, Option<f64>, Option<f64>);

fn parse_row(rec: &csv::StringRecord, layout: &Layout, path: &Path, line: u64) -> Result<Row> {
    let cell = |i: usize, name: &str| -> Result<Option<f64>> {
        let s = rec.get(i).unwrap_or("").trim();
        if s.is_empty() {
            return Ok(None);
        }
        match s.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Some(v)),
            _ => Err(VizError::Data {
                path: path.to_owned(),
                line: Some(line),
                message: format!("column {name}: {s:?} is not a finite number"),
            }),
        }
    };
    let t = cell(layout.at[0], "t")?.ok_or_else(|| VizError::Data {
        path: path.to_owned(),
        line: Some(line),
        message: "column t: the time is empty".into(),
    })?;
    let sample = Sample {
        t,
        v_t: cell(layout.at[1], "V_t")?,
        m_t: cell(layout.at[2], "m_t")?,
        q_i: cell(layout.at[3], "Q_i")?,
        rho_i: cell(layout.at[4], "rho_i")?,
    };
    let q_o = layout.q_o.map(|i| cell(i, "Q_o")).transpose()?.flatten();
    let rho_o = layout
        .rho_o
        .map(|i| cell(i, "rho_o"))
        .transpose()?
        .flatten();
    Ok((sample, q_o, rho_o))
}

/// A library error about sample `index` as a data error on its line (header = line 1).
fn at_line(path: &Path) -> impl Fn(DredgeError) -> VizError + '_ {
    move |e| {
        let index = match &e {
            DredgeError::NonFinite { index, .. }
            | DredgeError::Negative { index, .. }
            | DredgeError::TimeNotIncreasing { index, .. }
            | DredgeError::FilterStep { index, .. } => Some(*index),
            _ => None,
        };
        match index {
            Some(i) => VizError::Data {
                path: path.to_owned(),
                line: Some(i as u64 + 2),
                message: e.to_string(),
            },
            None => VizError::Data {
                path: path.to_owned(),
                line: None,
                message: e.to_string(),
            },
        }
    }
}

fn reader<R: std::io::Read>(input: R) -> csv::Reader<R> {
    csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(input)
}

fn csv_err(path: &Path) -> impl Fn(csv::Error) -> VizError + '_ {
    move |e| {
        let line = e.position().map(|p| p.line());
        VizError::Data {
            path: path.to_owned(),
            line,
            message: e.to_string(),
        }
    }
}

/// Read a whole data file.
///
/// # Errors
/// A missing file or column, a non-numeric value (naming its line), an empty file, negative
/// flows or densities, or time that does not increase.
pub fn read_data(path: &Path) -> Result<DredgeData> {
    let file = std::fs::File::open(path).map_err(VizError::io(path))?;
    let mut rdr = reader(std::io::BufReader::new(file));
    let header = rdr.headers().map_err(csv_err(path))?.clone();
    let layout = Layout::new(&header, path)?;
    let mut data = DredgeData {
        t: Vec::new(),
        v_t: Vec::new(),
        m_t: Vec::new(),
        q_i: Vec::new(),
        rho_i: Vec::new(),
        truth: (layout.q_o.is_some() || layout.rho_o.is_some()).then(|| Truth {
            q_o: Vec::new(),
            rho_o: Vec::new(),
        }),
    };
    for (i, rec) in rdr.records().enumerate() {
        let rec = rec.map_err(csv_err(path))?;
        let (s, q_o, rho_o) = parse_row(&rec, &layout, path, i as u64 + 2)?;
        data.t.push(s.t);
        data.v_t.push(s.v_t);
        data.m_t.push(s.m_t);
        data.q_i.push(s.q_i);
        data.rho_i.push(s.rho_i);
        if let Some(tr) = &mut data.truth {
            tr.q_o.push(q_o);
            tr.rho_o.push(rho_o);
        }
    }
    if data.is_empty() {
        return Err(VizError::Data {
            path: path.to_owned(),
            line: None,
            message: "no samples: the file has a header but no data rows".into(),
        });
    }
    data.validate(2).map_err(at_line(path))?;
    Ok(data)
}

/// Run a `pf-viz dredge` subcommand.
///
/// # Errors
/// Bad input, as a one-line message naming the file, line and problem.
pub fn run(cmd: DredgeCommand) -> Result<()> {
    match cmd {
        DredgeCommand::Simulate(a) => simulate_cmd(&a),
        DredgeCommand::Estimate(a) if a.online => online(&a),
        DredgeCommand::Estimate(a) => offline(&a),
    }
}

fn simulate_cmd(a: &SimulateArgs) -> Result<()> {
    let cycle = simulate(&SimConfig::default(), a.seed).map_err(VizError::paper("dredge"))?;
    let data = cycle.to_data();
    write_atomic(&a.out, |w| {
        let mut out = csv::Writer::from_writer(w);
        let io = |e: csv::Error| VizError::Data {
            path: a.out.clone(),
            line: None,
            message: e.to_string(),
        };
        out.write_record(["t", "V_t", "m_t", "Q_i", "rho_i", "Q_o", "rho_o"])
            .map_err(io)?;
        let opt = |v: Option<f64>| v.map(|x| format!("{x}")).unwrap_or_default();
        let truth = data.truth.as_ref();
        for k in 0..data.len() {
            out.write_record([
                format!("{}", data.t[k]),
                opt(data.v_t[k]),
                opt(data.m_t[k]),
                opt(data.q_i[k]),
                opt(data.rho_i[k]),
                opt(truth.and_then(|t| t.q_o[k])),
                opt(truth.and_then(|t| t.rho_o[k])),
            ])
            .map_err(io)?;
        }
        out.flush().map_err(VizError::io(&a.out))
    })?;
    eprintln!(
        "pf-viz: wrote {} samples ({} s of loading) to {}",
        data.len(),
        data.t.last().copied().unwrap_or(0.0),
        a.out.display()
    );
    Ok(())
}

fn filter_config(a: &EstimateArgs) -> Result<EstimatorConfig> {
    if a.particles == 0 {
        return Err(VizError::Argument {
            message: "--particles must be at least 1".into(),
        });
    }
    Ok(EstimatorConfig::default().with_particles(a.particles))
}

fn offline(a: &EstimateArgs) -> Result<()> {
    if a.runs == 0 {
        return Err(VizError::Argument {
            message: "--runs must be at least 1".into(),
        });
    }
    let filter = filter_config(a)?;
    let data = if a.data.as_os_str() == "-" {
        return Err(VizError::Argument {
            message: "--data - (standard input) needs --online".into(),
        });
    } else {
        read_data(&a.data)?
    };
    let cfg = EstimateConfig {
        filter,
        runs: a.runs,
        seed: a.seed,
        ..EstimateConfig::default()
    };
    let out = estimate(&data, &cfg).map_err(at_line(&a.data))?;
    if a.json {
        return print_json(&out);
    }
    let last = out.t.len() - 1;
    println!(
        "{} samples, N = {}, {} run(s): final Q_o = {:.3} m³/s, ρ_o = {:.1} kg/m³",
        out.t.len(),
        a.particles,
        a.runs,
        out.q_o[last],
        out.rho_o[last]
    );
    if let Some(r) = &out.residuals {
        for (name, s, unit) in [("Q_o", &r.q_o, "m³/s"), ("rho_o", &r.rho_o, "kg/m³")] {
            if let Some(s) = s {
                println!(
                    "  residual {name}: mean {:.3}, std {:.3}, max |·| {:.3} {unit}",
                    s.mean, s.std, s.max_abs
                );
            }
        }
    }
    Ok(())
}

/// On-line mode: each sample is estimated and printed (and flushed) as soon as its line
/// arrives on standard input, so the output can drive a live display.
fn online(a: &EstimateArgs) -> Result<()> {
    let filter = filter_config(a)?;
    let path = a.data.clone();
    let stdin = std::io::stdin();
    let input: Box<dyn BufRead> = if path.as_os_str() == "-" {
        Box::new(stdin.lock())
    } else {
        let f = std::fs::File::open(&path).map_err(VizError::io(&path))?;
        Box::new(std::io::BufReader::new(f))
    };
    let mut rdr = reader(input);
    let header = rdr.headers().map_err(csv_err(&path))?.clone();
    let layout = Layout::new(&header, &path)?;
    let mut est = OnlineEstimator::new(&filter).map_err(VizError::paper("dredge"))?;
    // The same stream as run 0 of the file mode, so both give the same estimates.
    let mut rng = stream_rng(a.seed, 0);
    let stdout = std::io::stdout();
    let mut rec = csv::StringRecord::new();
    let mut line = 1u64;
    loop {
        let more = rdr.read_record(&mut rec).map_err(csv_err(&path))?;
        if !more {
            break;
        }
        line += 1;
        let (sample, _, _) = parse_row(&rec, &layout, &path, line)?;
        let e = est.push(&sample, &mut rng).map_err(|e| VizError::Data {
            path: path.clone(),
            line: Some(line),
            message: e.to_string(),
        })?;
        let json = serde_json::to_string(&e).map_err(|e| VizError::Argument {
            message: format!("cannot serialise the estimate: {e}"),
        })?;
        let mut out = stdout.lock();
        writeln!(out, "{json}")
            .and_then(|()| out.flush())
            .map_err(VizError::io("<stdout>"))?;
    }
    if est.samples_seen() == 0 {
        return Err(VizError::Data {
            path,
            line: None,
            message: "no samples: the input has a header but no data rows".into(),
        });
    }
    Ok(())
}
