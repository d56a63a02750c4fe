//! Tables II (constant time) and III (constant velocity RMSE), Section IV-B/C.
//!
//! Every partition sees the same true trajectory and, in Monte Carlo run `r`, the same
//! measurement noise (stream `(seed, r)`), so the comparisons are paired. Times are the
//! thread's CPU time of one run ([`Stopwatch`]), the median over sequential timed runs: the
//! paper takes the minimum of wall times to avoid the operating system's interventions,
//! which the CPU clock leaves out by itself.
//!
//! Table II also carries what the calibrated EF model predicts: for each partition the `N`
//! at which eq. (11) costs what the standard PF costs with `N_PF` (`predicted_N`), the same
//! with the extended model [`ef_structural`], and the per-particle terms behind it, ours
//! beside the paper's.

use super::Scale;
use crate::calibrate::{CalibrateConfig, Calibration, CalibrationReport, Stopwatch, median};
use crate::complexity::{
    CtCase, EfCoefficients, PerParticleTerms, ef_structural, equal_cost_particles,
    equal_cost_particles_structural, fit_state_traffic, per_particle_terms, structural_terms,
};
use crate::error::{MpfError, Result};
use crate::mpf::MpfConfig;
use crate::radar::{Partition, RadarConfig, RadarState, run_partition};
use pf_core::mc::{Par, stream_rng, try_replicate};
use pf_core::metrics::{rmse, rmse_per_step};
use pf_core::params::ParamError;
use serde::{Deserialize, Serialize};

/// Configuration of Tables II and III.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TableConfig {
    /// The scenario.
    pub radar: RadarConfig,
    /// Particles of the standard PF, `N = 2000`.
    pub n_pf: usize,
    /// Monte Carlo runs `N_MC = 100`.
    pub n_mc: usize,
    /// Sequential timed runs per time measurement (minimum kept).
    pub timing_reps: usize,
    /// Smallest `N` the searches may return.
    pub n_min: usize,
    /// Partitions, the standard PF (`PPPPPP`) first.
    pub partitions: Vec<Partition>,
    /// Seed.
    pub seed: u64,
    /// The calibration behind Table II's predicted `N`.
    #[serde(default)]
    pub calibration: CalibrateConfig,
}

impl Default for TableConfig {
    fn default() -> Self {
        Self::at_scale(Scale::Full)
    }
}

impl TableConfig {
    /// A preset: `Full` is the paper's sizes.
    pub fn at_scale(scale: Scale) -> Self {
        let (n_pf, n_mc, reps, steps) = match scale {
            Scale::Quick => (150, 4, 1, 20),
            Scale::Default => (1000, 16, 3, 50),
            Scale::Full => (2000, 100, 10, 100),
        };
        Self {
            radar: RadarConfig {
                n_steps: steps,
                ..RadarConfig::default()
            },
            n_pf,
            n_mc,
            timing_reps: reps,
            n_min: 10,
            partitions: Partition::paper(),
            seed: 1,
            calibration: match scale {
                Scale::Quick => CalibrateConfig::quick(),
                _ => CalibrateConfig::default(),
            },
        }
    }

    /// Check the configuration.
    ///
    /// # Errors
    /// Any part invalid; the first partition not `PPPPPP`.
    pub fn validate(&self) -> Result<()> {
        self.radar.validate()?;
        self.calibration.validate()?;
        MpfConfig::new(self.n_pf).validate()?;
        for (name, v) in [
            ("N_MC", self.n_mc),
            ("timing_reps", self.timing_reps),
            ("n_min", self.n_min),
        ] {
            if v == 0 {
                return Err(MpfError::Param(ParamError {
                    name,
                    value: 0.0,
                    reason: "must be at least 1",
                }));
            }
        }
        if self.partitions.first().is_none_or(|p| p.k() != 0) {
            return Err(MpfError::Partition {
                partition: self
                    .partitions
                    .first()
                    .map(Partition::name)
                    .unwrap_or_default(),
                reason: "the first partition must be the standard PF, PPPPPP",
            });
        }
        Ok(())
    }
}

/// One column of Table II or III.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TableRow {
    /// `PPKKKK` etc.
    pub name: String,
    /// Particles `N`.
    #[serde(rename = "N")]
    pub n: usize,
    /// Position RMSE.
    pub rmse_pos: f64,
    /// Velocity RMSE.
    pub rmse_vel: f64,
    /// Acceleration RMSE.
    pub rmse_acc: f64,
    /// Filter time (s).
    pub time_s: f64,
}

impl TableRow {
    /// One line comparing this row with the paper's, the paper's values in brackets.
    pub fn against(&self, paper: &TableRow) -> String {
        format!(
            "{}: N = {} [{}], RMSE pos {:.2} [{:.2}] vel {:.2} [{:.2}] acc {:.2} [{:.2}], {:.3} s [{:.2}]",
            self.name,
            self.n,
            paper.n,
            self.rmse_pos,
            paper.rmse_pos,
            self.rmse_vel,
            paper.rmse_vel,
            self.rmse_acc,
            paper.rmse_acc,
            self.time_s,
            paper.time_s
        )
    }
}

/// A table as `pf-viz mpf table2|table3 --json` prints it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TableResult {
    /// One row per partition.
    pub partitions: Vec<TableRow>,
}

impl TableResult {
    /// The standard PF (the first row) and full marginalization (`PPKKKK`), if both are
    /// in the table.
    pub fn pf_and_full(&self) -> Option<(&TableRow, &TableRow)> {
        let pf = self.partitions.first()?;
        let full = self.partitions.iter().find(|r| r.name == "PPKKKK")?;
        Some((pf, full))
    }

    /// Whether full marginalization lowers both the position and the velocity RMSE of the
    /// standard PF, as the paper reports at equal time (Table II); `None` without both rows.
    pub fn full_marginalization_lowers_both(&self) -> Option<bool> {
        self.pf_and_full()
            .map(|(pf, full)| full.rmse_pos < pf.rmse_pos && full.rmse_vel < pf.rmse_vel)
    }
}

/// RMSE over time of one partition (per-step RMSE over the Monte Carlo runs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RmseCurve {
    /// Partition.
    pub name: String,
    /// Position.
    pub pos: Vec<f64>,
    /// Velocity.
    pub vel: Vec<f64>,
    /// Acceleration.
    pub acc: Vec<f64>,
}

/// Everything a table experiment computed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TableReport {
    /// Our table.
    pub table: TableResult,
    /// The paper's table.
    pub paper: TableResult,
    /// The target: the PF's time (Table II) or velocity RMSE (Table III).
    pub target: f64,
    /// Whether each row's search reached the target within its range.
    pub reached: Vec<bool>,
    /// RMSE over time per partition.
    pub rmse_over_time: Vec<RmseCurve>,
    /// Table II: what the calibrated EF model predicts (`None` for Table III).
    #[serde(default)]
    pub model: Option<ModelPrediction>,
}

/// One partition's per-particle EF, ours beside the paper's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PartitionTerms {
    /// `PPKKKK` etc.
    pub name: String,
    /// PF states.
    pub p: usize,
    /// KF states.
    pub k: usize,
    /// The extended model's coefficient of `N` with this machine's `c1, c2, c3`: Table I's
    /// flops on the radar model's nonzeros, and `c_m (p + k)`.
    pub ours: PerParticleTerms,
    /// The same with the paper's `c1 = 445, c2 = 487, c3 = 125` (no extension).
    pub paper: PerParticleTerms,
}

/// What the calibrated EF model says about Table II.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelPrediction {
    /// The calibration.
    pub calibration: Calibration,
    /// Per partition, the `N` with the standard PF's cost at `N_PF` under eq. (11) with the
    /// calibration (`predicted_N` of `pf-viz mpf table2 --json`).
    pub predicted_n: Vec<f64>,
    /// Its central 68 % interval over the calibration's bootstrap.
    pub predicted_n_range: Vec<(f64, f64)>,
    /// The same under the extended model [`ef_structural`], `c_m` fitted on the standard
    /// PF's measured time.
    pub predicted_n_ext: Vec<f64>,
    /// The extension's `c_m` (EF per state value per particle).
    pub c_m: f64,
    /// `(N − predicted_N)/predicted_N` per partition (eq. (11)).
    pub rel_error: Vec<f64>,
    /// `(N − predicted_N_ext)/predicted_N_ext` per partition.
    pub rel_error_ext: Vec<f64>,
    /// The per-particle terms of each partition, ours and the paper's.
    pub terms: Vec<PartitionTerms>,
    /// What the calibration fell back on, if anything.
    pub notes: Vec<String>,
}

fn row(name: &str, n: usize, pos: f64, vel: f64, acc: f64, time_s: f64) -> TableRow {
    TableRow {
        name: name.to_string(),
        n,
        rmse_pos: pos,
        rmse_vel: vel,
        rmse_acc: acc,
        time_s,
    }
}

/// The paper's Table II.
pub fn paper_table2() -> TableResult {
    TableResult {
        partitions: vec![
            row("PPPPPP", 2000, 7.10, 3.62, 0.52, 0.59),
            row("PPKKPP", 2029, 5.81, 3.27, 0.47, 0.58),
            row("PPPPKK", 1974, 5.76, 3.28, 0.45, 0.57),
            row("PPKKKK", 2574, 5.60, 3.21, 0.44, 0.60),
        ],
    }
}

/// The paper's Table III.
pub fn paper_table3() -> TableResult {
    TableResult {
        partitions: vec![
            row("PPPPPP", 2393, 7.07, 3.58, 0.50, 0.73),
            row("PPKKPP", 864, 6.98, 3.60, 0.51, 0.26),
            row("PPPPKK", 943, 7.12, 3.65, 0.49, 0.28),
            row("PPKKKK", 264, 7.27, 3.61, 0.48, 0.10),
        ],
    }
}

struct McOutcome {
    pos: f64,
    vel: f64,
    acc: f64,
    curve: RmseCurve,
}

fn monte_carlo(
    cfg: &TableConfig,
    part: &Partition,
    n: usize,
    truth: &[RadarState],
) -> Result<McOutcome> {
    let runs = try_replicate(cfg.seed, cfg.n_mc, Par::Rayon, |_, rng| {
        let ys = cfg.radar.measure(truth, rng);
        run_partition(part, &cfg.radar, MpfConfig::new(n), truth, &ys, rng)
    })?;
    let get = |f: fn(&crate::radar::RunErrors) -> &Vec<f64>| {
        runs.iter().map(|r| f(r).clone()).collect::<Vec<_>>()
    };
    let (p, v, a) = (get(|r| &r.sq_pos), get(|r| &r.sq_vel), get(|r| &r.sq_acc));
    Ok(McOutcome {
        pos: rmse(&p)?,
        vel: rmse(&v)?,
        acc: rmse(&a)?,
        curve: RmseCurve {
            name: part.name(),
            pos: rmse_per_step(&p)?,
            vel: rmse_per_step(&v)?,
            acc: rmse_per_step(&a)?,
        },
    })
}

fn time_of(cfg: &TableConfig, part: &Partition, n: usize, truth: &[RadarState]) -> Result<f64> {
    let mut times = Vec::with_capacity(cfg.timing_reps);
    for rep in 0..cfg.timing_reps {
        let mut rng = stream_rng(cfg.seed ^ 0x7157, rep as u64);
        let ys = cfg.radar.measure(truth, &mut rng);
        let watch = Stopwatch::start();
        run_partition(part, &cfg.radar, MpfConfig::new(n), truth, &ys, &mut rng)?;
        times.push(watch.elapsed_s());
    }
    Ok(median(&times))
}

/// The model's side of Table II for `partitions`, given the standard PF's measured time
/// `target_s` (which fits the extension's `c_m`) and the measured `N` per partition.
///
/// # Errors
/// A bad configuration (the radar model of a partition).
pub fn model_prediction(
    cfg: &TableConfig,
    report: &CalibrationReport,
    target_s: f64,
    measured_n: &[usize],
) -> Result<ModelPrediction> {
    let cal = report.calibration;
    let coef = cal.coefficients();
    let structure = cfg
        .partitions
        .iter()
        .map(|q| super::fig3::alg1_matrices(q, &cfg.radar))
        .collect::<Result<Vec<_>>>()?;
    let c_m = fit_state_traffic(
        &ef_structural(&structure[0], &coef, 0.0),
        6,
        cfg.n_pf,
        cfg.radar.n_steps,
        target_s,
        cal.flop_ns,
    );
    let n_pf = cfg.n_pf as f64;
    let eq = |p, k, c: &EfCoefficients| {
        if k == 0 {
            n_pf
        } else {
            equal_cost_particles(CtCase::Zero, p, k, n_pf, c)
        }
    };
    let pk: Vec<(usize, usize)> = cfg.partitions.iter().map(|q| (q.p(), q.k())).collect();
    let predicted_n: Vec<f64> = pk.iter().map(|&(p, k)| eq(p, k, &coef)).collect();
    let predicted_n_ext: Vec<f64> = structure
        .iter()
        .map(|m| {
            if m.k() == 0 {
                n_pf
            } else {
                equal_cost_particles_structural(&structure[0], m, n_pf, &coef, c_m)
            }
        })
        .collect();
    let rel = |pred: &[f64]| {
        measured_n
            .iter()
            .zip(pred)
            .map(|(&n, &p)| (n as f64 - p) / p)
            .collect()
    };
    Ok(ModelPrediction {
        calibration: cal,
        predicted_n_range: pk
            .iter()
            .map(|&(p, k)| report.interval(|c| eq(p, k, &c.coefficients())))
            .collect(),
        rel_error: rel(&predicted_n),
        rel_error_ext: rel(&predicted_n_ext),
        predicted_n,
        predicted_n_ext,
        c_m,
        terms: cfg
            .partitions
            .iter()
            .zip(&structure)
            .map(|(q, m)| PartitionTerms {
                name: q.name(),
                p: q.p(),
                k: q.k(),
                ours: structural_terms(m, &coef, c_m),
                paper: per_particle_terms(q.p(), q.k(), &EfCoefficients::default(), 0.0),
            })
            .collect(),
        notes: report.notes.clone(),
    })
}

/// Table II: the PF's time with `N_PF` particles is the target; for each MPF partition the
/// `N` whose time matches is found by proportional (secant through the origin) steps on
/// measured times, then the RMSEs come from `N_MC` runs.
///
/// The calibration is `cfg.calibration`'s; [`table2_with`] takes one already made.
///
/// # Errors
/// A bad configuration or a filter error; never the calibration's timings.
pub fn table2(cfg: &TableConfig) -> Result<TableReport> {
    cfg.validate()?;
    let report = crate::calibrate::calibrate_report(&cfg.calibration)?;
    table2_with(cfg, &report)
}

/// [`table2`] with a calibration already made.
///
/// # Errors
/// A bad configuration or a filter error.
pub fn table2_with(cfg: &TableConfig, calibration: &CalibrationReport) -> Result<TableReport> {
    cfg.validate()?;
    let truth = cfg.radar.truth();
    let target = time_of(cfg, &cfg.partitions[0], cfg.n_pf, &truth)?;
    let mut rows = Vec::new();
    let mut curves = Vec::new();
    let mut reached = Vec::new();
    for (j, part) in cfg.partitions.iter().enumerate() {
        let (n, time_s) = if j == 0 {
            (cfg.n_pf, target)
        } else {
            let mut n = cfg.n_pf;
            let mut t = time_of(cfg, part, n, &truth)?;
            for _ in 0..3 {
                let next = ((n as f64 * target / t).round() as usize).max(cfg.n_min);
                if next == n {
                    break;
                }
                n = next;
                t = time_of(cfg, part, n, &truth)?;
            }
            (n, t)
        };
        reached.push((time_s - target).abs() <= 0.1 * target);
        let mc = monte_carlo(cfg, part, n, &truth)?;
        rows.push(row(&part.name(), n, mc.pos, mc.vel, mc.acc, time_s));
        curves.push(mc.curve);
    }
    let measured_n: Vec<usize> = rows.iter().map(|r| r.n).collect();
    Ok(TableReport {
        table: TableResult { partitions: rows },
        paper: paper_table2(),
        target,
        reached,
        rmse_over_time: curves,
        model: Some(model_prediction(cfg, calibration, target, &measured_n)?),
    })
}

/// Table III: the PF's velocity RMSE with `N_PF` particles is the target; for each MPF
/// partition the smallest `N` in `[n_min, 2 N_PF]` whose velocity RMSE is at most the target
/// is found by bisection on `log N` (common random numbers keep the RMSE nearly monotone in
/// `N`), to within 5 %.
///
/// # Errors
/// A bad configuration or a filter error.
pub fn table3(cfg: &TableConfig) -> Result<TableReport> {
    cfg.validate()?;
    let truth = cfg.radar.truth();
    let pf = monte_carlo(cfg, &cfg.partitions[0], cfg.n_pf, &truth)?;
    let target = pf.vel;
    let mut rows = vec![row(
        &cfg.partitions[0].name(),
        cfg.n_pf,
        pf.pos,
        pf.vel,
        pf.acc,
        time_of(cfg, &cfg.partitions[0], cfg.n_pf, &truth)?,
    )];
    let mut curves = vec![pf.curve];
    let mut reached = vec![true];
    for part in &cfg.partitions[1..] {
        let (mut lo, mut hi) = (cfg.n_min, 2 * cfg.n_pf);
        let at_lo = monte_carlo(cfg, part, lo, &truth)?;
        let (best, ok) = if at_lo.vel <= target {
            (Some((lo, at_lo)), true)
        } else {
            let mut at_hi = monte_carlo(cfg, part, hi, &truth)?;
            let ok = at_hi.vel <= target;
            while ok && (hi as f64) > 1.05 * lo as f64 && hi - lo > 1 {
                let mid = ((lo as f64 * hi as f64).sqrt().round() as usize).clamp(lo + 1, hi - 1);
                let at_mid = monte_carlo(cfg, part, mid, &truth)?;
                if at_mid.vel <= target {
                    hi = mid;
                    at_hi = at_mid;
                } else {
                    lo = mid;
                }
            }
            (Some((hi, at_hi)), ok)
        };
        let (n, mc) = best.expect("set above");
        let time_s = time_of(cfg, part, n, &truth)?;
        rows.push(row(&part.name(), n, mc.pos, mc.vel, mc.acc, time_s));
        curves.push(mc.curve);
        reached.push(ok);
    }
    Ok(TableReport {
        table: TableResult { partitions: rows },
        paper: paper_table3(),
        target,
        reached,
        rmse_over_time: curves,
        model: None,
    })
}
