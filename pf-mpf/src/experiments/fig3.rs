//! Fig. 3: the time eq. (11) predicts against the time measured, for every partition of the
//! radar model's linear states at a fixed `N`.
//!
//! Two predictions per partition: the paper's, eq. (11) with this machine's calibration
//! (Section IV-A), and the extension [`ef_ct_zero_extended`], whose one more coefficient
//! `c_m` (state values moved per particle) is fitted on the standard PF's measured time
//! alone, so the other 15 partitions test it. Times are the thread's CPU time
//! ([`Stopwatch`]), the median over interleaved rounds: each round runs every partition once,
//! in turn.

use super::Scale;
use crate::calibrate::{
    CalibrateConfig, Calibration, CalibrationReport, CalibrationSpread, Stopwatch,
    calibrate_report, median,
};
use crate::complexity::{ef_ct_zero, ef_ct_zero_extended, fit_state_traffic};
use crate::error::{MpfError, Result};
use crate::mpf::MpfConfig;
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
    /// The extension's prediction, `T_f · C_ext(p, k, N) · flop_ns` (s).
    #[serde(default)]
    pub predicted_ext_s: f64,
    /// `(predicted_ext − measured)/measured`.
    #[serde(default)]
    pub rel_error_ext: f64,
    /// Fastest and slowest round (s).
    #[serde(default)]
    pub measured_range_s: (f64, f64),
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
    /// The extension's `c_m` (EF per state value per particle), fitted on `PPPPPP`.
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
/// calibration and the extension's `c_m` (`0`: eq. (11)).
pub fn predicted_time_s(
    cal: &Calibration,
    p: usize,
    k: usize,
    n: usize,
    t_f: usize,
    c_m: f64,
) -> f64 {
    let ef = if c_m == 0.0 {
        ef_ct_zero(p, k, &cal.coefficients()).at(n as f64)
    } else {
        ef_ct_zero_extended(p, k, &cal.coefficients(), c_m).at(n as f64)
    };
    ef * cal.flop_ns * 1e-9 * t_f as f64
}

/// Fig. 3: calibrate, then time every partition (interleaved rounds on one thread).
///
/// # Errors
/// A bad configuration or a filter error; never the calibration's timings.
pub fn fig3(cfg: &Fig3Config) -> Result<Fig3Result> {
    cfg.validate()?;
    let report = calibrate_report(&cfg.calibration)?;
    fig3_with(cfg, &report)
}

/// [`fig3`] with a calibration already made.
///
/// # Errors
/// A bad configuration or a filter error.
pub fn fig3_with(cfg: &Fig3Config, report: &CalibrationReport) -> Result<Fig3Result> {
    cfg.validate()?;
    let calibration = report.calibration;
    let truth = cfg.radar.truth();
    let ys = cfg.radar.measure(&truth, &mut stream_rng(cfg.seed, 0));
    let parts = Partition::all();
    let mut times = vec![Vec::with_capacity(cfg.reps); parts.len()];
    for rep in 0..cfg.reps {
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
    let t_f = truth.len();
    let n = cfg.n_particles;
    let measured: Vec<f64> = times.iter().map(|t| median(t)).collect();
    // The extension's one coefficient, from the standard PF (the first partition, k = 0).
    let c_m = fit_state_traffic(
        6,
        n,
        t_f,
        measured[0],
        calibration.flop_ns,
        &calibration.coefficients(),
    );
    let rows: Vec<Fig3Row> = parts
        .iter()
        .zip(&measured)
        .zip(&times)
        .map(|((part, &measured_s), t)| {
            let (p, k) = (part.p(), part.k());
            let predicted_s = predicted_time_s(&calibration, p, k, n, t_f, 0.0);
            let predicted_ext_s = predicted_time_s(&calibration, p, k, n, t_f, c_m);
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
                predicted_range_s: report.interval(|c| predicted_time_s(c, p, k, n, t_f, 0.0)),
                predicted_ext_s,
                rel_error_ext: (predicted_ext_s - measured_s) / measured_s,
                measured_range_s: lo_hi,
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
