//! Fig. 3: the time eq. (11) predicts against the time measured, for every partition of the
//! radar model's linear states at a fixed `N`.
//!
//! Two predictions per partition: the paper's, eq. (11) with this machine's calibration
//! (Section IV-A), and the extended model [`ef_structural`]: Table I's flops counted on the
//! radar model's nonzeros, plus `c_m` EF per state value per particle, fitted on the
//! standard PF's measured time alone, so the other 15 partitions test it. Times are the thread's CPU time
//! ([`Stopwatch`]), the median over interleaved rounds: each round runs every partition once,
//! in turn.

use super::Scale;
use crate::calibrate::{
    CalibrateConfig, Calibration, CalibrationReport, CalibrationSpread, StageTimes, Stopwatch,
    Timings, fit_timings, measure, median, stage_times,
};
use crate::complexity::{Alg1Matrices, ef_ct_zero, ef_structural, fit_state_traffic};
use crate::error::{MpfError, Result};
use crate::mpf::MpfConfig;
use crate::mpf::SharedMpf;
use crate::radar::RadarObs;
use crate::radar::{Partition, RadarConfig, run_partition};
use pf_core::mc::stream_rng;
use pf_core::params::ParamError;
use serde::{Deserialize, Serialize};

/// Configuration of Fig. 3.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fig3Config {
    /// The scenario.
    pub radar: RadarConfig,
    /// Particles `N` (the paper does not say; 2000 as in Section IV-B).
    pub n_particles: usize,
    /// Interleaved rounds: each times every partition once; the median is kept.
    pub reps: usize,
    /// The calibration to run first.
    pub calibration: CalibrateConfig,
    /// Seed.
    pub seed: u64,
}

impl Default for Fig3Config {
    fn default() -> Self {
        Self::at_scale(Scale::Full)
    }
}

impl Fig3Config {
    /// The preset of `scale`: `Full` is the paper's sizes.
    pub fn at_scale(scale: Scale) -> Self {
        let (n, reps, steps, cal) = match scale {
            Scale::Quick => (300, 2, 20, CalibrateConfig::quick()),
            Scale::Default => (2000, 5, 50, CalibrateConfig::default()),
            Scale::Full => (2000, 10, 100, CalibrateConfig::default()),
        };
        Self {
            radar: RadarConfig {
                n_steps: steps,
                ..RadarConfig::default()
            },
            n_particles: n,
            reps,
            calibration: cal,
            seed: 3,
        }
    }

    /// Check the configuration.
    ///
    /// # Errors
    /// Any part invalid.
    pub fn validate(&self) -> Result<()> {
        self.radar.validate()?;
        self.calibration.validate()?;
        MpfConfig::new(self.n_particles).validate()?;
        if self.reps == 0 {
            return Err(MpfError::Param(ParamError {
                name: "reps",
                value: 0.0,
                reason: "must be at least 1",
            }));
        }
        Ok(())
    }
}

/// One partition of Fig. 3.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fig3Row {
    /// `PPKKPP` etc.
    pub name: String,
    /// PF states.
    pub p: usize,
    /// KF states.
    pub k: usize,
    /// `T_f · C(p, k, N) · flop_ns` (s), eq. (11) as the paper writes it.
    pub predicted_s: f64,
    /// Median measured filter time (s): CPU time of one run, median over rounds.
    pub measured_s: f64,
    /// `(predicted − measured)/measured`.
    pub rel_error: f64,
    /// The central 68 % interval of `predicted_s` over the calibration's bootstrap.
    #[serde(default)]
    pub predicted_range_s: (f64, f64),
    /// The extended model's prediction, `T_f · C_ext(p, k, N) · flop_ns` (s),
    /// [`ef_structural`].
    #[serde(default)]
    pub predicted_ext_s: f64,
    /// `(predicted_ext − measured)/measured`.
    #[serde(default)]
    pub rel_error_ext: f64,
    /// Fastest and slowest round (s).
    #[serde(default)]
    pub measured_range_s: (f64, f64),
    /// Table I's per-particle flops counted on the partition's nonzeros
    /// ([`Alg1Matrices::flops_per_particle`]), against eq. (11)'s dense count.
    #[serde(default)]
    pub flops_structural: f64,
    /// Each stage of a step of this partition's filter timed on its own, per particle
    /// ([`stage_times`](crate::calibrate::stage_times)); `None` where the partition's filter
    /// is not a [`BatchModel`](pf_core::filter::batch::BatchModel).
    #[serde(default)]
    pub stages: Option<StageTimes>,
}

/// Fig. 3's data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fig3Result {
    /// The calibration behind the predictions.
    pub calibration: Calibration,
    /// `N`.
    pub n_particles: usize,
    /// One row per partition, in the order of [`Partition::all`].
    pub rows: Vec<Fig3Row>,
    /// Mean `|rel_error|`: the predicted-against-measured error the crate reports.
    pub mean_abs_rel_error: f64,
    /// Largest `|rel_error|` (the paper's form).
    #[serde(default)]
    pub max_abs_rel_error: f64,
    /// The extended model's `c_m` (EF per state value per particle), fitted on `PPPPPP`.
    #[serde(default)]
    pub c_m: f64,
    /// Largest `|rel_error_ext|` over the 15 partitions the fit did not see.
    #[serde(default)]
    pub max_abs_rel_error_ext: f64,
    /// Relative spread of the calibration's coefficients (bootstrap over rounds).
    #[serde(default)]
    pub calibration_spread: CalibrationSpread,
    /// What the calibration fell back on, if anything.
    #[serde(default)]
    pub calibration_notes: Vec<String>,
    /// `"thread CPU time"` or `"wall time"`.
    #[serde(default)]
    pub clock: String,
}

/// The predicted time (s) of `t_f` steps of partition `(p, k)` with `N` particles under a
/// calibration: eq. (11) without `structure`, the extended model [`ef_structural`] with the
/// partition's matrices and `c_m`.
pub fn predicted_time_s(
    cal: &Calibration,
    (p, k): (usize, usize),
    structure: Option<(&Alg1Matrices, f64)>,
    n: usize,
    t_f: usize,
) -> f64 {
    let c = cal.coefficients();
    let ef = match structure {
        None => ef_ct_zero(p, k, &c).at(n as f64),
        Some((m, c_m)) => ef_structural(m, &c, c_m).at(n as f64),
    };
    ef * cal.flop_ns * 1e-9 * t_f as f64
}

fn to_dynamic<const R: usize, const C: usize>(
    m: &nalgebra::SMatrix<f64, R, C>,
) -> nalgebra::DMatrix<f64> {
    nalgebra::DMatrix::from_column_slice(R, C, m.as_slice())
}

fn matrices_pk<const P: usize, const K: usize>(
    part: &Partition,
    radar: &RadarConfig,
) -> Result<Alg1Matrices> {
    let m = part.model::<P, K>(radar)?;
    Alg1Matrices::from_model(
        to_dynamic(m.a_p()),
        to_dynamic(m.a_k()),
        to_dynamic(m.f_p()),
        to_dynamic(m.f_k()),
        &to_dynamic(m.q_p()),
        &to_dynamic(m.q_k()),
        &to_dynamic(m.p0_k()),
        radar.n_steps.min(10),
    )
    .ok_or(MpfError::NotPositiveDefinite {
        what: "M_t of the structural flop count",
        t: 0,
        particle: 0,
    })
}

fn stages_pk<const P: usize, const K: usize>(
    part: &Partition,
    radar: &RadarConfig,
    y: &RadarObs,
    n: usize,
    rounds: usize,
    seed: u64,
) -> Result<StageTimes> {
    let model = SharedMpf::new(part.model::<P, K>(radar)?)?;
    stage_times(&model, 1, y, n, rounds, seed)
}

/// Each stage of one step of partition `part`'s filter ([`SharedMpf`], Alg. 1), timed on
/// its own with `n` particles and observation `y` ([`stage_times`]).
///
/// # Errors
/// A bad configuration or partition.
pub fn partition_stage_times(
    part: &Partition,
    radar: &RadarConfig,
    y: &RadarObs,
    n: usize,
    rounds: usize,
    seed: u64,
) -> Result<StageTimes> {
    match part.k() {
        0 => stages_pk::<6, 0>(part, radar, y, n, rounds, seed),
        1 => stages_pk::<5, 1>(part, radar, y, n, rounds, seed),
        2 => stages_pk::<4, 2>(part, radar, y, n, rounds, seed),
        3 => stages_pk::<3, 3>(part, radar, y, n, rounds, seed),
        _ => stages_pk::<2, 4>(part, radar, y, n, rounds, seed),
    }
}

/// The matrices of Alg. 1 for one partition of the radar model, eq. (13), behind the
/// extended model's flop count ([`Alg1Matrices::flops_per_particle`]).
///
/// # Errors
/// A bad configuration, or a Riccati recursion that loses positive definiteness.
pub fn alg1_matrices(part: &Partition, radar: &RadarConfig) -> Result<Alg1Matrices> {
    match part.k() {
        0 => matrices_pk::<6, 0>(part, radar),
        1 => matrices_pk::<5, 1>(part, radar),
        2 => matrices_pk::<4, 2>(part, radar),
        3 => matrices_pk::<3, 3>(part, radar),
        _ => matrices_pk::<2, 4>(part, radar),
    }
}

/// Fig. 3: calibrate and time every partition, interleaved on one thread: each of the
/// `reps` rounds runs a share of the calibration's rounds, then every partition once, so the
/// calibration and the filters see the machine in the same state.
///
/// # Errors
/// A bad configuration or a filter error; never the calibration's timings.
pub fn fig3(cfg: &Fig3Config) -> Result<Fig3Result> {
    fig3_calibrated(cfg).map(|(f, _)| f)
}

/// [`fig3`], also returning the calibration it made (for Table II's predictions).
///
/// # Errors
/// As [`fig3`].
pub fn fig3_calibrated(cfg: &Fig3Config) -> Result<(Fig3Result, CalibrationReport)> {
    cfg.validate()?;
    let share = CalibrateConfig {
        rounds: cfg.calibration.rounds.div_ceil(cfg.reps),
        ..cfg.calibration.clone()
    };
    let mut timings: Option<Timings> = None;
    let times = time_partitions(cfg, &mut || {
        // The same inputs in every share; only the clock differs.
        let t = measure(&share)?;
        match timings.as_mut() {
            Some(all) => all.append(&t),
            None => {
                timings = Some(t);
                Ok(())
            }
        }
    })?;
    let timings = timings.ok_or(MpfError::Param(ParamError {
        name: "reps",
        value: 0.0,
        reason: "must be at least 1",
    }))?;
    let report = fit_timings(&timings, cfg.calibration.bootstrap, cfg.calibration.seed);
    let result = fig3_from(cfg, &report, &times)?;
    Ok((result, report))
}

/// [`fig3`] with a calibration already made.
///
/// # Errors
/// A bad configuration or a filter error.
pub fn fig3_with(cfg: &Fig3Config, report: &CalibrationReport) -> Result<Fig3Result> {
    cfg.validate()?;
    let times = time_partitions(cfg, &mut || Ok(()))?;
    fig3_from(cfg, report, &times)
}

/// `reps` rounds: `between()`, then every partition once; CPU times (s) per partition.
fn time_partitions(
    cfg: &Fig3Config,
    between: &mut dyn FnMut() -> Result<()>,
) -> Result<Vec<Vec<f64>>> {
    let truth = cfg.radar.truth();
    let ys = cfg.radar.measure(&truth, &mut stream_rng(cfg.seed, 0));
    let parts = Partition::all();
    let mut times = vec![Vec::with_capacity(cfg.reps); parts.len()];
    for rep in 0..cfg.reps {
        between()?;
        for (j, part) in parts.iter().enumerate() {
            let watch = Stopwatch::start();
            run_partition(
                part,
                &cfg.radar,
                MpfConfig::new(cfg.n_particles),
                &truth,
                &ys,
                &mut stream_rng(cfg.seed, 1 + rep as u64),
            )?;
            times[j].push(watch.elapsed_s());
        }
    }
    Ok(times)
}

fn fig3_from(
    cfg: &Fig3Config,
    report: &CalibrationReport,
    times: &[Vec<f64>],
) -> Result<Fig3Result> {
    let calibration = report.calibration;
    let parts = Partition::all();
    let t_f = cfg.radar.n_steps;
    let n = cfg.n_particles;
    let measured: Vec<f64> = times.iter().map(|t| median(t)).collect();
    let truth = cfg.radar.truth();
    let y = cfg
        .radar
        .measure(&truth[1..2], &mut stream_rng(cfg.seed, 0))[0]
        .unwrap_or_else(|| RadarObs::new(2500.0, 0.64));
    let stages = parts
        .iter()
        .map(|q| partition_stage_times(q, &cfg.radar, &y, cfg.n_particles, cfg.reps, cfg.seed))
        .collect::<Result<Vec<_>>>()?;
    let structure: Vec<Alg1Matrices> = parts
        .iter()
        .map(|q| alg1_matrices(q, &cfg.radar))
        .collect::<Result<_>>()?;
    // The extension's one coefficient, from the standard PF (the first partition, k = 0).
    let c_m = fit_state_traffic(
        &ef_structural(&structure[0], &calibration.coefficients(), 0.0),
        6,
        n,
        t_f,
        measured[0],
        calibration.flop_ns,
    );
    let rows: Vec<Fig3Row> = parts
        .iter()
        .zip(&measured)
        .zip(times)
        .zip(&structure)
        .zip(&stages)
        .map(|((((part, &measured_s), t), m), &stages)| {
            let (p, k) = (part.p(), part.k());
            let predicted_s = predicted_time_s(&calibration, (p, k), None, n, t_f);
            let predicted_ext_s = predicted_time_s(&calibration, (p, k), Some((m, c_m)), n, t_f);
            let lo_hi = t
                .iter()
                .fold((f64::INFINITY, 0.0_f64), |(a, b), &x| (a.min(x), b.max(x)));
            Fig3Row {
                name: part.name(),
                p,
                k,
                predicted_s,
                measured_s,
                rel_error: (predicted_s - measured_s) / measured_s,
                predicted_range_s: report.interval(|c| predicted_time_s(c, (p, k), None, n, t_f)),
                predicted_ext_s,
                rel_error_ext: (predicted_ext_s - measured_s) / measured_s,
                measured_range_s: lo_hi,
                flops_structural: m.flops_per_particle(),
                stages: Some(stages),
            }
        })
        .collect();
    let abs = |f: fn(&Fig3Row) -> f64, skip: usize| {
        rows.iter()
            .skip(skip)
            .map(|r| f(r).abs())
            .fold(0.0_f64, f64::max)
    };
    let mean_abs_rel_error =
        rows.iter().map(|r| r.rel_error.abs()).sum::<f64>() / rows.len() as f64;
    Ok(Fig3Result {
        calibration,
        n_particles: n,
        mean_abs_rel_error,
        max_abs_rel_error: abs(|r| r.rel_error, 0),
        c_m,
        max_abs_rel_error_ext: abs(|r| r.rel_error_ext, 1),
        calibration_spread: report.spread,
        calibration_notes: report.notes.clone(),
        clock: report.clock.clone(),
        rows,
    })
}
