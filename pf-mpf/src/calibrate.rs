//! Measuring this machine the way Section IV-A does: the time of one flop by linear
//! regression over matrix products of several sizes, then the time per particle of the
//! likelihood, of resampling and of one random number, converted to EF units `c1, c2, c3`.

use crate::complexity::EfCoefficients;
use crate::error::{MpfError, Result};
use crate::model::Measurement;
use crate::radar::{RadarObs, RangeAzimuth};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat};
use nalgebra::SVector;
use pf_core::params::{self, ParamError};
use pf_core::resample::{Resample, Resampler};
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use std::hint::black_box;
use std::time::Instant;

/// What to time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrateConfig {
    /// Particle counts `N` of the regressions.
    pub n_values: Vec<usize>,
    /// Matrix sizes `d` of the `d×d · d×N` products of the flop regression.
    pub dims: Vec<usize>,
    /// Repetitions per point; the minimum time is kept ("to avoid intervention from the
    /// operating system the minimum value is chosen", Section IV-B).
    pub reps: usize,
    /// Seed of the random inputs.
    pub seed: u64,
}

impl Default for CalibrateConfig {
    fn default() -> Self {
        Self {
            n_values: vec![500, 1000, 2000, 4000],
            dims: vec![2, 3, 4, 6],
            reps: 15,
            seed: 0,
        }
    }
}

impl CalibrateConfig {
    /// A few-millisecond calibration for tests.
    pub fn quick() -> Self {
        Self {
            n_values: vec![200, 400, 800],
            dims: vec![2, 4, 6],
            reps: 5,
            seed: 0,
        }
    }

    /// Check the sizes.
    ///
    /// # Errors
    /// Fewer than two distinct `N`, an empty `dims`, a zero size or `reps = 0`.
    pub fn validate(&self) -> Result<()> {
        let mut n = self.n_values.clone();
        n.sort_unstable();
        n.dedup();
        if n.len() < 2 || n[0] == 0 {
            return Err(MpfError::Param(ParamError {
                name: "n_values",
                value: n.len() as f64,
                reason: "need at least two distinct positive particle counts for a regression",
            }));
        }
        if self.dims.is_empty() || self.dims.contains(&0) {
            return Err(MpfError::Param(ParamError {
                name: "dims",
                value: self.dims.len() as f64,
                reason: "need at least one positive matrix size",
            }));
        }
        params::at_least_one("reps", self.reps)?;
        Ok(())
    }
}

/// The calibrated EF model, as `pf-viz mpf calibrate --json` prints it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Time of one flop (ns).
    pub flop_ns: f64,
    /// `c1` (EF): Gaussian likelihood of the radar measurement, per particle.
    pub c1: f64,
    /// `c2` (EF): systematic resampling, per particle.
    pub c2: f64,
    /// `c3` (EF): one standard normal random number.
    pub c3: f64,
}

impl Calibration {
    /// The coefficients alone.
    pub fn coefficients(&self) -> EfCoefficients {
        EfCoefficients {
            c1: self.c1,
            c2: self.c2,
            c3: self.c3,
        }
    }

    /// Check every field is positive and finite.
    ///
    /// # Errors
    /// [`MpfError::Param`] naming the field.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("flop_ns", self.flop_ns),
            ("c1", self.c1),
            ("c2", self.c2),
            ("c3", self.c3),
        ] {
            params::positive(name, v)?;
        }
        Ok(())
    }
}

/// A least-squares line `y = intercept + slope·x`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LineFit {
    /// Intercept.
    pub intercept: f64,
    /// Slope.
    pub slope: f64,
    /// Coefficient of determination.
    pub r2: f64,
}

/// Ordinary least squares of `y` on `x` with an intercept.
pub fn fit_line(x: &[f64], y: &[f64]) -> LineFit {
    let n = x.len() as f64;
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    let syy: f64 = y.iter().map(|b| (b - my).powi(2)).sum();
    let slope = sxy / sxx;
    LineFit {
        intercept: my - slope * mx,
        slope,
        r2: if syy > 0.0 {
            sxy * sxy / (sxx * syy)
        } else {
            1.0
        },
    }
}

/// Every measurement behind a [`Calibration`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibrationReport {
    /// The result.
    pub calibration: Calibration,
    /// Flop counts of the timed products.
    pub flops: Vec<f64>,
    /// Their minimum times (ns).
    pub flop_times_ns: Vec<f64>,
    /// Time against flops.
    pub flop_fit: LineFit,
    /// Likelihood time against `N` (slope: ns per particle).
    pub likelihood_fit: LineFit,
    /// Resampling time against `N`.
    pub resample_fit: LineFit,
    /// Random-number time against the count of numbers.
    pub randn_fit: LineFit,
}

fn min_time_ns(reps: usize, mut f: impl FnMut()) -> f64 {
    f();
    (0..reps)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_nanos() as f64
        })
        .fold(f64::INFINITY, f64::min)
}

/// Calibrate the EF model on this machine (Section IV-A, steps 1–3).
///
/// # Errors
/// A bad configuration, or a non-positive slope (timer too coarse for the sizes given).
pub fn calibrate_report(cfg: &CalibrateConfig) -> Result<CalibrationReport> {
    cfg.validate()?;
    let mut rng = pf_core::mc::stream_rng(cfg.seed, 0);
    // 1. one flop: d×d · d×N products cost d·N·(2d − 1) flops (Table I's count).
    let (mut flops, mut times) = (Vec::new(), Vec::new());
    for &d in &cfg.dims {
        for &n in &cfg.n_values {
            let a = Mat::<f64>::from_fn(d, d, |i, j| 1.0 / (1 + i + j) as f64);
            let b = Mat::<f64>::from_fn(d, n, |i, j| ((i * 7 + j) % 13) as f64);
            let mut c = Mat::<f64>::zeros(d, n);
            let t = min_time_ns(cfg.reps, || {
                matmul(
                    c.as_mut(),
                    Accum::Replace,
                    a.as_ref(),
                    b.as_ref(),
                    1.0,
                    faer::Par::Seq,
                );
                black_box(&c);
            });
            flops.push((d * n * (2 * d - 1)) as f64);
            times.push(t);
        }
    }
    let flop_fit = fit_line(&flops, &times);
    let ns: Vec<f64> = cfg.n_values.iter().map(|&n| n as f64).collect();
    // 2. likelihood (with its share of the normalisation), resampling and randn per particle.
    let r_chol = nalgebra::Matrix2::new(10.0, 0.0, 0.0, 1e-3);
    let y = RadarObs::new(2500.0, 0.64);
    let (mut lik, mut res, mut rnd) = (Vec::new(), Vec::new(), Vec::new());
    for &n in &cfg.n_values {
        let xs: Vec<SVector<f64, 2>> = (0..n)
            .map(|_| {
                let a: f64 = StandardNormal.sample(&mut rng);
                let b: f64 = StandardNormal.sample(&mut rng);
                SVector::<f64, 2>::new(2000.0 + 30.0 * a, 1500.0 + 30.0 * b)
            })
            .collect();
        let mut lw = vec![0.0; n];
        let mut w = vec![0.0; n];
        lik.push(min_time_ns(cfg.reps, || {
            for (l, x) in lw.iter_mut().zip(&xs) {
                let h = Measurement::<2, 2>::h(&RangeAzimuth, 0, x);
                let e = Measurement::<2, 2>::residual(&RangeAzimuth, &y, &h);
                let z = r_chol.solve_lower_triangular(&e).unwrap_or_default();
                *l = -0.5 * z.norm_squared();
            }
            let _ = pf_core::weights::normalise(0, &mut lw, &mut w);
            black_box(&w);
        }));
        let mut anc = vec![0usize; n];
        let wu = vec![1.0 / n as f64; n];
        res.push(min_time_ns(cfg.reps, || {
            Resampler::Systematic.resample(&wu, &mut rng, &mut anc);
            black_box(&anc);
        }));
        let mut buf = vec![0.0; n];
        rnd.push(min_time_ns(cfg.reps, || {
            for z in &mut buf {
                *z = StandardNormal.sample(&mut rng);
            }
            black_box(&buf);
        }));
    }
    let likelihood_fit = fit_line(&ns, &lik);
    let resample_fit = fit_line(&ns, &res);
    let randn_fit = fit_line(&ns, &rnd);
    let flop_ns = flop_fit.slope;
    let calibration = Calibration {
        flop_ns,
        c1: likelihood_fit.slope / flop_ns,
        c2: resample_fit.slope / flop_ns,
        c3: randn_fit.slope / flop_ns,
    };
    calibration.validate()?;
    Ok(CalibrationReport {
        calibration,
        flops,
        flop_times_ns: times,
        flop_fit,
        likelihood_fit,
        resample_fit,
        randn_fit,
    })
}

/// `pf-viz mpf calibrate`: [`calibrate_report`]'s [`Calibration`].
///
/// # Errors
/// As [`calibrate_report`].
pub fn calibrate(cfg: &CalibrateConfig) -> Result<Calibration> {
    calibrate_report(cfg).map(|r| r.calibration)
}
