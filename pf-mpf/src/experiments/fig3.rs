//! Fig. 3: the time eq. (11) predicts against the time measured, for every partition of the
//! radar model's linear states at a fixed `N`.

use super::Scale;
use crate::calibrate::{CalibrateConfig, Calibration, calibrate};
use crate::complexity::ef_ct_zero;
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
    /// Timed runs per partition; the minimum is kept.
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
            Scale::Default => (2000, 3, 50, CalibrateConfig::default()),
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
    /// `T_f · C(p, k, N) · flop_ns` (s).
    pub predicted_s: f64,
    /// Minimum measured filter time (s).
    pub measured_s: f64,
    /// `(predicted − measured)/measured`.
    pub rel_error: f64,
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
}

/// Fig. 3: calibrate, then time every partition (sequentially, so runs do not compete).
///
/// # Errors
/// A bad configuration or a filter error.
pub fn fig3(cfg: &Fig3Config) -> Result<Fig3Result> {
    cfg.validate()?;
    let calibration = calibrate(&cfg.calibration)?;
    let coef = calibration.coefficients();
    let truth = cfg.radar.truth();
    let ys = cfg.radar.measure(&truth, &mut stream_rng(cfg.seed, 0));
    let mut rows = Vec::new();
    for part in Partition::all() {
        let mut measured = f64::INFINITY;
        for rep in 0..cfg.reps {
            let run = run_partition(
                &part,
                &cfg.radar,
                MpfConfig::new(cfg.n_particles),
                &truth,
                &ys,
                &mut stream_rng(cfg.seed, 1 + rep as u64),
            )?;
            measured = measured.min(run.time_s);
        }
        let ef = ef_ct_zero(part.p(), part.k(), &coef).at(cfg.n_particles as f64);
        let predicted = ef * calibration.flop_ns * 1e-9 * truth.len() as f64;
        rows.push(Fig3Row {
            name: part.name(),
            p: part.p(),
            k: part.k(),
            predicted_s: predicted,
            measured_s: measured,
            rel_error: (predicted - measured) / measured,
        });
    }
    let mean_abs_rel_error =
        rows.iter().map(|r| r.rel_error.abs()).sum::<f64>() / rows.len() as f64;
    Ok(Fig3Result {
        calibration,
        n_particles: cfg.n_particles,
        rows,
        mean_abs_rel_error,
    })
}
