//! `pf-viz epf …`: El Abed et al.: the energetic particle filter for multiple targets.
//!
//! - `simulate` writes a scenario's detections (with a `target` truth column, −1 for
//!   clutter), init and truth CSVs;
//! - `track` tracks every init target through a detections CSV (EPF or NNSF), with `q` and
//!   `r` estimated from the init tracks unless given (the values used go to stderr, and to
//!   the JSON), and a status per target-frame (`associated`, `coasting`, `lost`);
//! - `energies` prints the E¹, E², E³ and E tables of one frame (the paper's Tables 1–2).

use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use pf_core::mc::stream_rng;
use pf_epf::EpfError;
use pf_epf::association::Association;
use pf_epf::data::{Detection, Detections, Init, InitRow};
use pf_epf::dynamics::SplineOrder;
use pf_epf::geometry::Vec2;
use pf_epf::scenario::{Scenario, ScenarioConfig, simulate};
use pf_epf::tracker::{
    NoiseChoice, NoiseSource, Record, TrackResult, TrackStatus, TrackerConfig, energies_at, track,
};
use serde::Serialize;

use crate::cmd::{print_json, print_line};
use crate::data::Table;
use crate::error::{Result, VizError};
use crate::io::{check_writable, prepare_out_dir, write_atomic};

/// The subcommands of `pf-viz epf`.
#[derive(Debug, Clone, Subcommand)]
pub enum EpfCommand {
    /// Simulate a scenario: DIR/detections.csv, DIR/init.csv (and DIR/truth.csv).
    Simulate(SimulateArgs),
    /// Track the init targets through unlabelled detections.
    Track(TrackArgs),
    /// The energies E¹, E², E³ and E of every target × detection at one frame.
    Energies(EnergiesArgs),
}

/// Arguments of `pf-viz epf simulate`.
#[derive(Debug, Clone, Args)]
pub struct SimulateArgs {
    /// The paper's van-plane (2 targets), walking-men (3) or ants (6, sparse frames); or a
    /// stress scene: crossing (2, noise sd 1), sparse-ants (6, every 5th frame) or
    /// simultaneous-turns (3).
    #[arg(long, value_name = "NAME")]
    pub scenario: Scenario,
    /// Mean number of clutter detections per tracked frame (Poisson), 0 to 10⁴.
    #[arg(long, value_name = "F", default_value_t = 0.0)]
    pub clutter: f64,
    /// Probability that a target's detection is missed at a tracked frame.
    #[arg(long, value_name = "F", default_value_t = 0.0)]
    pub miss: f64,
    /// Random seed.
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// Output directory.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Print the summary as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// The tracker's settings shared by `track` and `energies`.
#[derive(Debug, Clone, Args)]
pub struct TrackerArgs {
    /// Detections CSV: columns `frame`, `x`, `y` (others ignored), frames not decreasing.
    #[arg(long, value_name = "FILE.csv")]
    pub data: PathBuf,
    /// Init CSV: columns `target`, `frame`, `x`, `y`; at least two frames per target.
    #[arg(long, value_name = "FILE.csv")]
    pub init: PathBuf,
    /// Particles per target.
    #[arg(long, value_name = "N", default_value_t = 500)]
    pub particles: usize,
    /// Random seed.
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// Process noise standard deviation per √frame, q [default: estimated from the init
    /// tracks (a target with 4 init frames is needed), else 0.5].
    #[arg(long, value_name = "Q")]
    pub q: Option<f64>,
    /// Detection noise standard deviation, r [default: estimated from the init tracks
    /// (a target with 4 init frames is needed), else 0.5].
    #[arg(long, value_name = "R")]
    pub r: Option<f64>,
    /// Probability mass of the validation gates.
    #[arg(long, value_name = "P", default_value_t = TrackerConfig::default().gate_probability)]
    pub gate: f64,
    /// The dynamic model that moves the particles and centres the gates (EPF step 2):
    /// cubic_b_spline_end (the B-spline's end derivatives from the last detection),
    /// cubic_b_spline (its curve continued), linear (the chord) or quadratic.
    #[arg(long, value_name = "ORDER", default_value_t = TrackerConfig::default().spline)]
    pub spline: SplineOrder,
    /// The dynamic model behind E²'s predictions: cubic_b_spline, cubic_b_spline_end,
    /// linear or quadratic.
    #[arg(long, value_name = "ORDER", default_value_t = TrackerConfig::default().energy_spline)]
    pub energy_spline: SplineOrder,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `pf-viz epf track`.
#[derive(Debug, Clone, Args)]
pub struct TrackArgs {
    /// The data and tracker settings.
    #[command(flatten)]
    pub tracker: TrackerArgs,
    /// energy (optimal assignment on the energy E, the default), energy_per_measurement
    /// (eq. (1): each measurement to its least-energy target, the paper's EPF), nn (the
    /// paper's NNSF: nearest to the prediction Â(t)), nn_global (optimal assignment on the
    /// distance to Â(t)) or nn_previous (nearest to Â(t−1), what nn meant before).
    #[arg(long, value_name = "METHOD", default_value = "energy")]
    pub association: Association,
    /// A target without a detection for more than this many tracked frames in a row is
    /// reported lost.
    #[arg(long, value_name = "N", default_value_t = TrackerConfig::default().lost_after)]
    pub lost_after: usize,
    /// The paper's tracker: a target without a detection keeps extrapolating its dynamic
    /// model with a gate that grows only with its particles, and every target associates
    /// at once (by default a coasting target follows the line through its last detections,
    /// its gate grows with the time since its last association, and targets that had a
    /// detection at their previous step choose first).
    #[arg(long)]
    pub no_reacquire: bool,
    /// Also write the tracks as CSV: one row per target and tracked frame, columns
    /// target,frame,x,y,detection,status (detection: the row index, empty when none).
    #[arg(long, value_name = "FILE.csv")]
    pub out: Option<PathBuf>,
}

/// Arguments of `pf-viz epf energies`.
#[derive(Debug, Clone, Args)]
pub struct EnergiesArgs {
    /// The data and tracker settings.
    #[command(flatten)]
    pub tracker: TrackerArgs,
    /// The frame t (a detection frame after the init frames).
    #[arg(long, value_name = "F")]
    pub frame: i64,
}

/// Run a `pf-viz epf` subcommand.
///
/// # Errors
/// Bad input, as a one-line message naming what and where.
pub fn run(cmd: EpfCommand) -> Result<()> {
    match cmd {
        EpfCommand::Simulate(a) => run_simulate(&a),
        EpfCommand::Track(a) => run_track(&a),
        EpfCommand::Energies(a) => run_energies(&a),
    }
}

/// An error of the library's validation, mapped to the file and line at fault.
fn epf_data_err(table: &Table, e: EpfError) -> VizError {
    let line = match &e {
        EpfError::FrameBackwards { row, .. }
        | EpfError::FrameOutOfRange { row, .. }
        | EpfError::NonFiniteData { row, .. } => table.line(*row),
        _ => None,
    };
    table.error(line, e.to_string())
}

fn read_detections(path: &Path) -> Result<Detections> {
    let t = Table::read(path, &["frame", "x", "y"])?;
    let rows = t
        .rows()
        .map(|(line, r)| {
            Ok(Detection {
                frame: t.integer(line, "frame", &r[0])?,
                position: Vec2::new(t.number(line, "x", &r[1])?, t.number(line, "y", &r[2])?),
                target: None,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Detections::new(rows).map_err(|e| epf_data_err(&t, e))
}

fn read_init(path: &Path) -> Result<Init> {
    let t = Table::read(path, &["target", "frame", "x", "y"])?;
    let rows = t
        .rows()
        .map(|(line, r)| {
            Ok(InitRow {
                target: t.integer(line, "target", &r[0])?,
                frame: t.integer(line, "frame", &r[1])?,
                position: Vec2::new(t.number(line, "x", &r[2])?, t.number(line, "y", &r[3])?),
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Init::new(&rows).map_err(|e| epf_data_err(&t, e))
}

impl TrackerArgs {
    /// The tracker's settings, with `q` and `r` as given or estimated from `init`.
    fn config(&self, association: Association, init: &Init) -> (TrackerConfig, NoiseChoice) {
        let noise = NoiseChoice::new(init, self.q, self.r);
        let cfg = noise.apply(&TrackerConfig {
            association,
            n_particles: self.particles,
            gate_probability: self.gate,
            spline: self.spline,
            energy_spline: self.energy_spline,
            ..TrackerConfig::default()
        });
        (cfg, noise)
    }
}

/// The one stderr line saying which `q` and `r` the tracker used, by rank 0, after the
/// output was written (an error, a closed pipe included, is one stderr line and nothing
/// else).
fn noise_note(n: &NoiseChoice) {
    if !pf_core::mc::dist::is_root() {
        return;
    }
    eprintln!(
        "q = {} ({}), r = {} ({})",
        four_places(n.q),
        n.q_source.name(),
        four_places(n.r),
        n.r_source.name()
    );
}

/// Four decimals, or four in scientific notation where that would show none or too many
/// digits (a given `--r 1e-6` is not `0.0000`).
fn four_places(x: f64) -> String {
    if x != 0.0 && !(1e-3..1e5).contains(&x.abs()) {
        format!("{x:.4e}")
    } else {
        format!("{x:.4}")
    }
}

fn write_csv(path: &Path, header: &str, lines: impl Iterator<Item = String>) -> Result<()> {
    write_atomic(path, |w| {
        let io = VizError::io(path);
        writeln!(w, "{header}").map_err(io)?;
        for l in lines {
            writeln!(w, "{l}").map_err(VizError::io(path))?;
        }
        Ok(())
    })
}

#[derive(Serialize)]
struct SimulateSummary {
    scenario: &'static str,
    seed: u64,
    clutter: f64,
    miss: f64,
    frames: Vec<i64>,
    targets: usize,
    detections: usize,
    files: Vec<String>,
}

fn run_simulate(a: &SimulateArgs) -> Result<()> {
    let cfg = ScenarioConfig {
        scenario: a.scenario,
        clutter: a.clutter,
        miss: a.miss,
    };
    cfg.validate().map_err(|e| VizError::Argument {
        message: e.to_string(),
    })?;
    let sim = simulate(&cfg, &mut stream_rng(a.seed, 0)).map_err(VizError::paper("epf"))?;
    prepare_out_dir(&a.out)?;
    let det = a.out.join("detections.csv");
    let init = a.out.join("init.csv");
    let truth = a.out.join("truth.csv");
    check_writable([det.as_path(), init.as_path(), truth.as_path()])?;
    write_csv(
        &det,
        "frame,x,y,target",
        sim.detections.rows().iter().map(|d| {
            format!(
                "{},{},{},{}",
                d.frame,
                d.position.x,
                d.position.y,
                d.target.unwrap_or(-1)
            )
        }),
    )?;
    write_csv(
        &init,
        "target,frame,x,y",
        sim.init.targets().iter().flat_map(|t| {
            t.points
                .iter()
                .map(move |(f, p)| format!("{},{f},{},{}", t.id, p.x, p.y))
        }),
    )?;
    write_csv(
        &truth,
        "target,frame,x,y",
        sim.truth.iter().flat_map(|t| {
            sim.frames
                .iter()
                .zip(&t.position)
                .map(move |(f, p)| format!("{},{f},{},{}", t.target, p[0], p[1]))
        }),
    )?;
    let summary = SimulateSummary {
        scenario: a.scenario.name(),
        seed: a.seed,
        clutter: a.clutter,
        miss: a.miss,
        frames: sim.frames.clone(),
        targets: sim.truth.len(),
        detections: sim.detections.rows().len(),
        files: [&det, &init, &truth]
            .iter()
            .map(|p| p.display().to_string())
            .collect(),
    };
    if a.json {
        print_json(&summary)
    } else {
        print_line(format_args!(
            "{}: {} targets, {} detections over frames {:?}\nwrote {}",
            summary.scenario,
            summary.targets,
            summary.detections,
            summary.frames,
            summary.files.join(", ")
        ))?;
        Ok(())
    }
}

/// `track --json`: the result plus the `q` and `r` used and where they came from.
#[derive(Serialize)]
struct TrackJson<'a> {
    #[serde(flatten)]
    result: &'a TrackResult,
    q: f64,
    r: f64,
    q_source: &'static str,
    r_source: &'static str,
}

fn run_track(a: &TrackArgs) -> Result<()> {
    let detections = read_detections(&a.tracker.data)?;
    let init = read_init(&a.tracker.init)?;
    let (mut cfg, noise) = a.tracker.config(a.association, &init);
    cfg.lost_after = a.lost_after;
    cfg.reacquire = !a.no_reacquire;
    cfg.validate().map_err(|e| VizError::Argument {
        message: e.to_string(),
    })?;
    if let Some(out) = &a.out {
        check_writable([out.as_path()])?;
    }
    let result = track(
        &detections,
        &init,
        &cfg,
        Record::Tracks,
        &mut stream_rng(a.tracker.seed, 0),
    )
    .map_err(VizError::paper("epf"))?;
    if let Some(out) = &a.out {
        write_csv(
            out,
            "target,frame,x,y,detection,status",
            result.tracks.iter().flat_map(|t| {
                result.frames.iter().enumerate().map(move |(i, f)| {
                    format!(
                        "{},{f},{},{},{},{}",
                        t.target,
                        t.position[i][0],
                        t.position[i][1],
                        t.detection[i].map_or(String::new(), |j| j.to_string()),
                        t.status[i].name()
                    )
                })
            }),
        )?;
    }
    if a.tracker.json {
        print_json(&TrackJson {
            result: &result,
            q: noise.q,
            r: noise.r,
            q_source: source_key(noise.q_source),
            r_source: source_key(noise.r_source),
        })?;
        noise_note(&noise);
        return Ok(());
    }
    print_line(format_args!(
        "{} ({}): {} targets over {} frames ({}..={})",
        a.association.name(),
        cfg.n_particles,
        result.tracks.len(),
        result.frames.len(),
        result.frames[0],
        result.frames[result.frames.len() - 1]
    ))?;
    for t in &result.tracks {
        let hits = t.detection.iter().filter(|d| d.is_some()).count();
        let lost = t.status.iter().filter(|&&s| s == TrackStatus::Lost).count();
        let last = t.position[t.position.len() - 1];
        let last_status = t.status.last().map_or("", |s| s.name());
        print_line(format_args!(
            "  target {}: {hits}/{} frames associated, {lost} lost, last position ({:.3}, \
             {:.3}), {last_status}",
            t.target,
            t.detection.len(),
            last[0],
            last[1]
        ))?;
    }
    noise_note(&noise);
    Ok(())
}

/// The JSON value of a [`NoiseSource`].
fn source_key(s: NoiseSource) -> &'static str {
    match s {
        NoiseSource::Given => "given",
        NoiseSource::Estimated => "estimated",
        NoiseSource::Default => "default",
    }
}

#[derive(Serialize)]
struct EnergiesJson {
    frame: i64,
    targets: Vec<i64>,
    detections: Vec<usize>,
    positions: Vec<[f64; 2]>,
    #[serde(rename = "E1")]
    e1: Vec<Vec<f64>>,
    #[serde(rename = "E2")]
    e2: Vec<Vec<f64>>,
    #[serde(rename = "E3")]
    e3: Vec<Vec<f64>>,
    #[serde(rename = "E")]
    e: Vec<Vec<f64>>,
    #[serde(rename = "E1_raw")]
    e1_raw: Vec<Vec<f64>>,
    #[serde(rename = "E2_raw")]
    e2_raw: Vec<Vec<f64>>,
    #[serde(rename = "E3_raw")]
    e3_raw: Vec<Vec<f64>>,
    gated: Vec<Vec<bool>>,
    assignment: Vec<Option<usize>>,
}

fn run_energies(a: &EnergiesArgs) -> Result<()> {
    let detections = read_detections(&a.tracker.data)?;
    let init = read_init(&a.tracker.init)?;
    let (cfg, noise) = a.tracker.config(Association::Energy, &init);
    cfg.validate().map_err(|e| VizError::Argument {
        message: e.to_string(),
    })?;
    let t = energies_at(
        &detections,
        &init,
        &cfg,
        a.frame,
        &mut stream_rng(a.tracker.seed, 0),
    )
    .map_err(|e| match e {
        EpfError::UnknownFrame { .. } => VizError::Argument {
            message: format!("--frame: {e}"),
        },
        e => VizError::paper("epf")(e),
    })?;
    let [w1, w2, w3] = t.weighted;
    let [r1, r2, r3] = t.raw;
    let out = EnergiesJson {
        frame: t.frame,
        targets: t.targets,
        detections: t.detections,
        positions: t.positions,
        e1: w1,
        e2: w2,
        e3: w3,
        e: t.e,
        e1_raw: r1,
        e2_raw: r2,
        e3_raw: r3,
        gated: t.gated,
        assignment: t.assignment,
    };
    if a.tracker.json {
        print_json(&out)?;
        noise_note(&noise);
        return Ok(());
    }
    print_line(format_args!(
        "frame {}: α_l·E^l and E(k, y_j) (rows: targets, columns: detection rows {:?})",
        out.frame, out.detections
    ))?;
    for (k, id) in out.targets.iter().enumerate() {
        let cells: Vec<String> = (0..out.detections.len())
            .map(|j| {
                format!(
                    "{:.3} {:.3} {:.3} | {:.3}{}",
                    out.e1[k][j],
                    out.e2[k][j],
                    out.e3[k][j],
                    out.e[k][j],
                    if out.gated[k][j] {
                        ""
                    } else {
                        " (out of gate)"
                    }
                )
            })
            .collect();
        print_line(format_args!("  T{id}: {}", cells.join("   ")))?;
    }
    noise_note(&noise);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::four_places;

    #[test]
    fn noise_values_keep_their_digits_at_any_scale() {
        assert_eq!(four_places(0.25), "0.2500");
        assert_eq!(four_places(0.0), "0.0000");
        assert_eq!(four_places(1e-6), "1.0000e-6");
        assert_eq!(four_places(2.5e7), "2.5000e7");
    }
}
