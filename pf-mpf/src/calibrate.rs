//! Measuring this machine the way Section IV-A does: the time of one flop by linear
//! regression over matrix products of several sizes, then the time per particle of the
//! likelihood, of resampling and of one random number, converted to EF units `c1, c2, c3`.
//!
//! The paper times each part and keeps the minimum "to avoid intervention from the operating
//! system". On a shared machine that is not enough, so the design here is:
//! - **CPU time, not wall time.** [`Stopwatch`] reads the calling thread's CPU clock where the
//!   platform has one (the `cpu-time` crate), so time spent waiting for a core does not count.
//! - **Interleaved rounds.** Every configuration (a product size, a particle count) is timed
//!   in turn, and the whole sweep is repeated `rounds` times, so a slow spell of the machine
//!   falls on all configurations alike instead of on one. Within a round a configuration is
//!   timed `reps` times over blocks of at least [`MIN_BLOCK_NS`] and the minimum is kept.
//! - **Medians** over rounds, then a **non-negative least-squares** line ([`nnls`]) through
//!   them: a time can only grow with the work, so neither intercept nor slope may be negative.
//! - **Uncertainty** by a bootstrap over rounds: the fit is repeated on rounds drawn with
//!   replacement, and [`CalibrationReport::samples`] keeps every refitted calibration so a
//!   prediction can carry the spread ([`CalibrationReport::spread`] summarises it).
//! - **No failure on timings.** A degenerate fit (zero or non-finite slope) falls back to a
//!   line through the origin, then to the paper's coefficients, with a note in
//!   [`CalibrationReport::notes`]; only a bad configuration is an error.

use crate::complexity::EfCoefficients;
use crate::error::{MpfError, Result};
use crate::model::{Measurement, TILE};
use crate::radar::{RadarObs, RangeAzimuth};
use pf_core::filter::batch::{BatchModel, Cols, ColsMut};
use pf_core::metrics::quantile_sorted;
use pf_core::params::{self, ParamError};
use pf_core::resample::{Resample, Resampler};
use pf_core::simd::widest;
use rand::RngExt;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use std::hint::black_box;
use std::time::Instant;

/// Shortest timed block (ns of CPU time): a configuration is repeated within one timing until
/// the block lasts this long, so the clock's resolution and the cost of reading it stay below
/// about 1 % of what is measured.
pub const MIN_BLOCK_NS: f64 = 200_000.0;

/// State values moved per resampled particle in the `c2` timing: the radar model's
/// `m = p + k = 6`, the same for every partition.
pub const RESAMPLED_STATE_DIM: usize = 6;

/// CPU time of the calling thread (ns), `None` where the platform cannot read that clock.
fn thread_cpu_ns() -> Option<f64> {
    cpu_time::ThreadTime::try_now()
        .ok()
        .map(|t| t.as_duration().as_nanos() as f64)
}

/// A stopwatch on the calling thread's CPU time where the platform has that clock (Linux,
/// macOS, Windows, the BSDs), on wall time otherwise ([`Stopwatch::clock`] says which). CPU
/// time leaves out the time the thread waits for a core, which on a shared machine is most
/// of the noise; it also leaves out work done on other threads, so time single-threaded
/// code with it.
#[derive(Debug, Clone, Copy)]
pub struct Stopwatch {
    cpu_start: Option<f64>,
    wall_start: Instant,
}

impl Stopwatch {
    /// Start now.
    pub fn start() -> Self {
        Self {
            cpu_start: thread_cpu_ns(),
            wall_start: Instant::now(),
        }
    }

    /// Nanoseconds since [`Stopwatch::start`].
    pub fn elapsed_ns(&self) -> f64 {
        match (self.cpu_start, thread_cpu_ns()) {
            (Some(a), Some(b)) => (b - a).max(0.0),
            _ => self.wall_start.elapsed().as_nanos() as f64,
        }
    }

    /// Seconds since [`Stopwatch::start`].
    pub fn elapsed_s(&self) -> f64 {
        self.elapsed_ns() * 1e-9
    }

    /// `"thread CPU time"` or `"wall time"`.
    pub fn clock() -> &'static str {
        if thread_cpu_ns().is_some() {
            "thread CPU time"
        } else {
            "wall time"
        }
    }
}

/// What to time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrateConfig {
    /// Particle counts `N` of the regressions.
    pub n_values: Vec<usize>,
    /// Matrix sizes `d` of the `d×d · d×N` products of the flop regression.
    pub dims: Vec<usize>,
    /// Timings per configuration within one round; the minimum is kept ("to avoid
    /// intervention from the operating system the minimum value is chosen", Section IV-B).
    pub reps: usize,
    /// Seed of the random inputs and of the bootstrap.
    pub seed: u64,
    /// Interleaved rounds: every configuration is timed once per round, in turn; the median
    /// over rounds enters the fit.
    #[serde(default = "default_rounds")]
    pub rounds: usize,
    /// Bootstrap resamples of the rounds behind [`CalibrationReport::spread`] (0: none).
    #[serde(default = "default_bootstrap")]
    pub bootstrap: usize,
}

fn default_rounds() -> usize {
    15
}

fn default_bootstrap() -> usize {
    200
}

impl Default for CalibrateConfig {
    fn default() -> Self {
        Self {
            n_values: vec![500, 1000, 2000, 4000],
            dims: vec![2, 3, 4, 6],
            reps: 3,
            seed: 0,
            rounds: default_rounds(),
            bootstrap: default_bootstrap(),
        }
    }
}

impl CalibrateConfig {
    /// A calibration of a fraction of a second for tests.
    pub fn quick() -> Self {
        Self {
            n_values: vec![200, 400, 800],
            dims: vec![2, 4, 6],
            reps: 1,
            seed: 0,
            rounds: 3,
            bootstrap: 50,
        }
    }

    /// Check the sizes.
    ///
    /// # Errors
    /// Fewer than two distinct `N`, an empty `dims`, a zero size, `reps = 0` or `rounds = 0`.
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
        params::at_least_one("rounds", self.rounds)?;
        pf_core::limits::check_count("rounds", self.rounds)?;
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
    /// The fallback when the timings say nothing: the paper's `c1, c2, c3` (Section IV-A)
    /// with a nominal flop time of 1 ns. Predicted times from it are not this machine's;
    /// particle ratios are the paper's.
    pub const FALLBACK: Calibration = Calibration {
        flop_ns: 1.0,
        c1: 445.0,
        c2: 487.0,
        c3: 125.0,
    };

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

/// The relative spread of each coefficient over the bootstrap: half the width of the central
/// 68 % interval divided by the calibrated value (0.05 = ±5 %). Zero without a bootstrap.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct CalibrationSpread {
    /// Of `flop_ns`.
    pub flop_ns: f64,
    /// Of `c1`.
    pub c1: f64,
    /// Of `c2`.
    pub c2: f64,
    /// Of `c3`.
    pub c3: f64,
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

fn r_squared(x: &[f64], y: &[f64], intercept: f64, slope: f64) -> f64 {
    let n = y.len() as f64;
    let my = y.iter().sum::<f64>() / n;
    let syy: f64 = y.iter().map(|b| (b - my).powi(2)).sum();
    let sse: f64 = x
        .iter()
        .zip(y)
        .map(|(a, b)| (b - intercept - slope * a).powi(2))
        .sum();
    if syy > 0.0 { 1.0 - sse / syy } else { 1.0 }
}

/// Ordinary least squares of `y` on `x` with an intercept (unconstrained: the slope may be
/// negative; [`fit_line_nonneg`] is the calibration's fit).
pub fn fit_line(x: &[f64], y: &[f64]) -> LineFit {
    let n = x.len() as f64;
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    LineFit {
        intercept,
        slope,
        r2: r_squared(x, y, intercept, slope),
    }
}

/// Least squares of `y` on `x` with an intercept, both constrained to be non-negative
/// ([`nnls`] on the columns `[1, x]`). `None` when the data are not finite or empty.
pub fn fit_line_nonneg(x: &[f64], y: &[f64]) -> Option<LineFit> {
    let ones = vec![1.0; x.len()];
    let c = nnls(&[&ones, x], y).ok()?;
    Some(LineFit {
        intercept: c[0],
        slope: c[1],
        r2: r_squared(x, y, c[0], c[1]),
    })
}

/// Solve `A c = b` for a small dense system by Gaussian elimination with partial pivoting;
/// `None` if singular.
fn solve_small(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    let scale = a
        .iter()
        .flat_map(|r| r.iter())
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    for col in 0..n {
        let piv = (col..n).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].abs() <= 1e-13 * scale {
            return None;
        }
        a.swap(col, piv);
        b.swap(col, piv);
        let (top, rest) = a.split_at_mut(col + 1);
        let pivot_row = &top[col];
        for (off, r) in rest.iter_mut().enumerate() {
            let f = r[col] / pivot_row[col];
            for (x, p) in r[col..].iter_mut().zip(&pivot_row[col..]) {
                *x -= f * p;
            }
            b[col + 1 + off] -= f * b[col];
        }
    }
    let mut x = vec![0.0; n];
    for row in (0..n).rev() {
        let s: f64 = (row + 1..n).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - s) / a[row][row];
    }
    Some(x)
}

/// Non-negative least squares: `argmin ‖A c − y‖₂` subject to `c ≥ 0`, by the active-set
/// method of Lawson & Hanson (*Solving Least Squares Problems*, 1974, ch. 23), for the small
/// problems of the calibration (a few columns). `columns` are the columns of `A`, each as
/// long as `y`. The columns are scaled to unit norm internally, so regressors of very
/// different sizes (an intercept of 1 and flop counts of 10⁵) are handled alike.
///
/// # Errors
/// No columns, columns of different lengths from `y`, or a non-finite entry.
pub fn nnls(columns: &[&[f64]], y: &[f64]) -> Result<Vec<f64>> {
    let bad = |value: f64, reason| {
        Err(MpfError::Param(ParamError {
            name: "nnls",
            value,
            reason,
        }))
    };
    let n = columns.len();
    if n == 0 || y.is_empty() {
        return bad(n as f64, "need at least one column and one row");
    }
    if let Some(c) = columns.iter().find(|c| c.len() != y.len()) {
        return bad(c.len() as f64, "every column must be as long as y");
    }
    if let Some(&v) = columns
        .iter()
        .flat_map(|c| c.iter())
        .chain(y)
        .find(|v| !v.is_finite())
    {
        return bad(v, "entries must be finite");
    }
    let norms: Vec<f64> = columns
        .iter()
        .map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt())
        .collect();
    // Scaled columns; an all-zero column stays zero and its coefficient 0.
    let a: Vec<Vec<f64>> = columns
        .iter()
        .zip(&norms)
        .map(|(c, &s)| {
            c.iter()
                .map(|v| if s > 0.0 { v / s } else { 0.0 })
                .collect()
        })
        .collect();
    let dot = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(a, b)| a * b).sum::<f64>();
    let residual = |x: &[f64]| -> Vec<f64> {
        (0..y.len())
            .map(|i| y[i] - (0..n).map(|j| a[j][i] * x[j]).sum::<f64>())
            .collect()
    };
    let y_norm = dot(y, y).sqrt();
    let tol = 1e-12 * y_norm.max(f64::MIN_POSITIVE);
    // Least squares on the passive set, zero elsewhere.
    let solve_passive = |passive: &[bool]| -> Option<Vec<f64>> {
        let idx: Vec<usize> = (0..n).filter(|&j| passive[j]).collect();
        let gram = idx
            .iter()
            .map(|&i| idx.iter().map(|&j| dot(&a[i], &a[j])).collect())
            .collect();
        let rhs = idx.iter().map(|&i| dot(&a[i], y)).collect();
        let s = solve_small(gram, rhs)?;
        let mut full = vec![0.0; n];
        for (k, &j) in idx.iter().enumerate() {
            full[j] = s[k];
        }
        Some(full)
    };
    let mut x = vec![0.0; n];
    let mut passive = vec![false; n];
    for _ in 0..3 * n + 3 {
        let r = residual(&x);
        let w: Vec<f64> = (0..n).map(|j| dot(&a[j], &r)).collect();
        let Some(j) = (0..n)
            .filter(|&j| !passive[j] && norms[j] > 0.0 && w[j] > tol)
            .max_by(|&i, &k| w[i].total_cmp(&w[k]))
        else {
            break;
        };
        passive[j] = true;
        loop {
            let Some(s) = solve_passive(&passive) else {
                // A column dependent on the passive ones: leave it out.
                passive[j] = false;
                break;
            };
            if (0..n).all(|i| !passive[i] || s[i] > 0.0) {
                x = s;
                break;
            }
            // Step from x towards s until the first passive coefficient reaches zero.
            let alpha = (0..n)
                .filter(|&i| passive[i] && s[i] <= 0.0)
                .map(|i| x[i] / (x[i] - s[i]))
                .fold(f64::INFINITY, f64::min);
            for i in 0..n {
                x[i] += alpha * (s[i] - x[i]);
                if passive[i] && x[i] <= 1e-15 {
                    passive[i] = false;
                    x[i] = 0.0;
                }
            }
            if !passive.iter().any(|&p| p) {
                break;
            }
        }
    }
    Ok(x.iter()
        .zip(&norms)
        .map(|(c, &s)| if s > 0.0 { (c / s).max(0.0) } else { 0.0 })
        .collect())
}

/// The raw timings of a calibration: for each configuration, one time per round (ns per
/// call, the minimum of the round's `reps` blocks).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Timings {
    /// Flop counts of the timed products, `d·N·(2d − 1)` (Table I's count).
    pub flops: Vec<f64>,
    /// Time of each product, `[configuration][round]`.
    pub product_ns: Vec<Vec<f64>>,
    /// Particle counts of the likelihood, resampling and random-number timings.
    pub n: Vec<f64>,
    /// Likelihood and weight normalisation of `N` particles, `[N][round]`.
    pub likelihood_ns: Vec<Vec<f64>>,
    /// Systematic resampling of `N` particles and moving their states, `[N][round]`.
    pub resample_ns: Vec<Vec<f64>>,
    /// `N` standard normal draws, `[N][round]`.
    pub randn_ns: Vec<Vec<f64>>,
}

impl Timings {
    /// Add the rounds of `other`, timed on the same configurations (a later stretch of one
    /// interleaved calibration).
    ///
    /// # Errors
    /// Different configurations.
    pub fn append(&mut self, other: &Timings) -> Result<()> {
        if self.flops != other.flops || self.n != other.n {
            return Err(MpfError::Param(ParamError {
                name: "timings",
                value: other.flops.len() as f64,
                reason: "rounds of different configurations cannot be pooled",
            }));
        }
        for (mine, theirs) in [
            (&mut self.product_ns, &other.product_ns),
            (&mut self.likelihood_ns, &other.likelihood_ns),
            (&mut self.resample_ns, &other.resample_ns),
            (&mut self.randn_ns, &other.randn_ns),
        ] {
            for (a, b) in mine.iter_mut().zip(theirs) {
                a.extend_from_slice(b);
            }
        }
        Ok(())
    }

    /// The number of rounds (the shortest row's length).
    pub fn rounds(&self) -> usize {
        self.product_ns
            .iter()
            .chain(&self.likelihood_ns)
            .chain(&self.resample_ns)
            .chain(&self.randn_ns)
            .map(Vec::len)
            .min()
            .unwrap_or(0)
    }
}

/// Every measurement behind a [`Calibration`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibrationReport {
    /// The result.
    pub calibration: Calibration,
    /// Flop counts of the timed products.
    pub flops: Vec<f64>,
    /// Their median times over rounds (ns).
    pub flop_times_ns: Vec<f64>,
    /// Time against flops (non-negative least squares on the medians).
    pub flop_fit: LineFit,
    /// Likelihood time against `N` (slope: ns per particle).
    pub likelihood_fit: LineFit,
    /// Resampling time against `N`.
    pub resample_fit: LineFit,
    /// Random-number time against the count of numbers.
    pub randn_fit: LineFit,
    /// Interleaved rounds timed.
    #[serde(default)]
    pub rounds: usize,
    /// The clock: `"thread CPU time"` or `"wall time"`.
    #[serde(default)]
    pub clock: String,
    /// Relative spread of each coefficient over the bootstrap over rounds.
    #[serde(default)]
    pub spread: CalibrationSpread,
    /// The bootstrap's calibrations, one per resample of the rounds, for predictions that
    /// carry the calibration's uncertainty (empty without a bootstrap).
    #[serde(default)]
    pub samples: Vec<Calibration>,
    /// What fell back and why (empty when every fit was regular).
    #[serde(default)]
    pub notes: Vec<String>,
    /// The raw timings.
    #[serde(default)]
    pub timings: Option<Timings>,
}

impl CalibrationReport {
    /// The central 68 % interval of `f` over the bootstrap's calibrations, or `f` of the
    /// calibration itself at both ends when there is no bootstrap.
    pub fn interval(&self, f: impl Fn(&Calibration) -> f64) -> (f64, f64) {
        let mut v: Vec<f64> = self
            .samples
            .iter()
            .map(&f)
            .filter(|x| x.is_finite())
            .collect();
        if v.is_empty() {
            let x = f(&self.calibration);
            return (x, x);
        }
        v.sort_by(f64::total_cmp);
        (quantile_sorted(&v, 0.16), quantile_sorted(&v, 0.84))
    }
}

/// Median of the finite values, NaN if none.
pub fn median(v: &[f64]) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    s.sort_by(f64::total_cmp);
    quantile_sorted(&s, 0.5)
}

/// A slope that is positive and finite, or why not: the non-negative fit first, then the
/// median of `y/x` (a line through the origin, which counts any fixed overhead as work).
fn positive_slope(what: &str, x: &[f64], y: &[f64], notes: &mut Vec<String>) -> (LineFit, f64) {
    let keep: Vec<(f64, f64)> = x
        .iter()
        .zip(y)
        .filter(|(a, b)| a.is_finite() && b.is_finite() && **a > 0.0)
        .map(|(a, b)| (*a, *b))
        .collect();
    let (xs, ys): (Vec<f64>, Vec<f64>) = keep.into_iter().unzip();
    let fit = fit_line_nonneg(&xs, &ys);
    if let Some(f) = fit
        && f.slope.is_finite()
        && f.slope > 0.0
    {
        return (f, f.slope);
    }
    let through_origin = median(
        &xs.iter()
            .zip(&ys)
            .map(|(a, b)| b / a)
            .filter(|r| *r > 0.0)
            .collect::<Vec<_>>(),
    );
    let zero = LineFit {
        intercept: 0.0,
        slope: 0.0,
        r2: 0.0,
    };
    if through_origin.is_finite() && through_origin > 0.0 {
        notes.push(format!(
            "{what}: the non-negative fit has no positive slope; the median time per unit \
             ({through_origin:.4e} ns) is used instead"
        ));
        let f = LineFit {
            intercept: 0.0,
            slope: through_origin,
            r2: r_squared(&xs, &ys, 0.0, through_origin),
        };
        (f, through_origin)
    } else {
        notes.push(format!(
            "{what}: no positive time was measured; the paper's value is used instead"
        ));
        (fit.unwrap_or(zero), f64::NAN)
    }
}

/// The fit of one set of per-configuration times (one median per configuration).
struct Fitted {
    calibration: Calibration,
    fits: [LineFit; 4],
    notes: Vec<String>,
}

fn fit_medians(flops: &[f64], n: &[f64], med: [&[f64]; 4]) -> Fitted {
    let mut notes = Vec::new();
    let (flop_fit, flop_ns) = positive_slope("flop time", flops, med[0], &mut notes);
    let (lik, lik_ns) = positive_slope("c1 (likelihood)", n, med[1], &mut notes);
    let (res, res_ns) = positive_slope("c2 (resampling)", n, med[2], &mut notes);
    let (rnd, rnd_ns) = positive_slope("c3 (random numbers)", n, med[3], &mut notes);
    let fb = Calibration::FALLBACK;
    let calibration = if flop_ns.is_nan() {
        // Without a flop time the EF units are undefined: the paper's model throughout.
        fb
    } else {
        let ef = |ns: f64, paper: f64| if ns.is_nan() { paper } else { ns / flop_ns };
        Calibration {
            flop_ns,
            c1: ef(lik_ns, fb.c1),
            c2: ef(res_ns, fb.c2),
            c3: ef(rnd_ns, fb.c3),
        }
    };
    Fitted {
        calibration,
        fits: [flop_fit, lik, res, rnd],
        notes,
    }
}

/// Fit a calibration to raw timings: medians over rounds, non-negative least-squares lines,
/// the fall-backs (a line through the origin, then the paper's coefficients), and a
/// bootstrap over rounds (`bootstrap` resamples drawn from
/// `pf_core::mc::stream_rng(seed, …)`). Never fails and never returns a non-positive or
/// non-finite coefficient: what could not be fitted is said in `notes`.
pub fn fit_timings(t: &Timings, bootstrap: usize, seed: u64) -> CalibrationReport {
    let rows = [&t.product_ns, &t.likelihood_ns, &t.resample_ns, &t.randn_ns];
    let medians = |pick: &dyn Fn(&[f64]) -> f64| -> [Vec<f64>; 4] {
        rows.map(|r| r.iter().map(|v| pick(v)).collect())
    };
    let med = medians(&median);
    let main = fit_medians(&t.flops, &t.n, [&med[0], &med[1], &med[2], &med[3]]);
    let rounds = t.rounds();
    let mut samples = Vec::new();
    if rounds >= 2 {
        let mut rng = pf_core::mc::stream_rng(seed, 0xb007);
        for _ in 0..bootstrap {
            let pick: Vec<usize> = (0..rounds).map(|_| rng.random_range(0..rounds)).collect();
            let m = medians(&|v: &[f64]| median(&pick.iter().map(|&i| v[i]).collect::<Vec<_>>()));
            samples.push(fit_medians(&t.flops, &t.n, [&m[0], &m[1], &m[2], &m[3]]).calibration);
        }
    }
    let mut report = CalibrationReport {
        calibration: main.calibration,
        flops: t.flops.clone(),
        flop_times_ns: med[0].clone(),
        flop_fit: main.fits[0],
        likelihood_fit: main.fits[1],
        resample_fit: main.fits[2],
        randn_fit: main.fits[3],
        rounds,
        clock: Stopwatch::clock().to_string(),
        spread: CalibrationSpread::default(),
        samples,
        notes: main.notes,
        timings: Some(t.clone()),
    };
    let rel = |f: fn(&Calibration) -> f64| {
        let (lo, hi) = report.interval(f);
        let v = f(&report.calibration);
        if v > 0.0 { 0.5 * (hi - lo) / v } else { 0.0 }
    };
    report.spread = CalibrationSpread {
        flop_ns: rel(|c| c.flop_ns),
        c1: rel(|c| c.c1),
        c2: rel(|c| c.c2),
        c3: rel(|c| c.c3),
    };
    if rounds < 2 && bootstrap > 0 {
        report
            .notes
            .push("one round only: no bootstrap, the spread is zero".into());
    }
    report
}

/// Time `f` once per block of `inner` calls; the block's time per call (ns).
fn block_ns(inner: usize, f: &mut dyn FnMut()) -> f64 {
    let s = Stopwatch::start();
    for _ in 0..inner {
        f();
    }
    s.elapsed_ns() / inner as f64
}

/// Calls per timed block so that one block lasts at least [`MIN_BLOCK_NS`].
fn calls_per_block(f: &mut dyn FnMut()) -> usize {
    f(); // warm the caches
    let mut inner = 1usize;
    loop {
        let t = block_ns(inner, f) * inner as f64;
        if t >= MIN_BLOCK_NS || inner >= 1 << 20 {
            return inner;
        }
        let grow = if t > 0.0 {
            (MIN_BLOCK_NS / t * 1.2).ceil() as usize
        } else {
            16
        };
        inner = inner.saturating_mul(grow.clamp(2, 1024)).min(1 << 20);
    }
}

/// Time every configuration in turn, `rounds` times over; `[configuration][round]`, each
/// the minimum over `reps` blocks. The first configuration of a round rotates, so no
/// configuration always runs first.
fn interleaved(reps: usize, rounds: usize, jobs: &mut [Box<dyn FnMut() + '_>]) -> Vec<Vec<f64>> {
    let inner: Vec<usize> = jobs.iter_mut().map(|f| calls_per_block(f)).collect();
    let m = jobs.len();
    // Grown round by round, so a huge `rounds` is never asked for up front.
    let mut out = vec![Vec::new(); m];
    for r in 0..rounds {
        for j in (0..m).map(|j| (j + r) % m) {
            let t = (0..reps)
                .map(|_| block_ns(inner[j], &mut jobs[j]))
                .fold(f64::INFINITY, f64::min);
            out[j].push(t);
        }
    }
    out
}

/// `out_r = Σ_c a[r][c] · x_c` for the `d` columns `x` of `N` particles: a `d×d · d×N`
/// product written as the batch filters write theirs, column by column over the particles,
/// `d·N·(2d − 1)` flops (Table I's count).
#[inline(always)]
fn product_columns(a: &[f64], x: &[Vec<f64>], out: &mut [Vec<f64>]) {
    let d = x.len();
    for (r, o) in out.iter_mut().enumerate() {
        let a0 = a[r * d];
        for (o, &x0) in o.iter_mut().zip(&x[0]) {
            *o = a0 * x0;
        }
        for (c, xc) in x.iter().enumerate().skip(1) {
            let ac = a[r * d + c];
            for (o, &xi) in o.iter_mut().zip(xc) {
                *o += ac * xi;
            }
        }
    }
}

/// Eq. (13b)'s Gaussian log-likelihood of `N` particles as the filters compute it: tile by
/// tile ([`TILE`] particles), the residuals from the radar measurement's own
/// [`Measurement::residuals`] (range, azimuth, the azimuth wrapped), then `−½ eᵀR⁻¹e`
/// with the radar's diagonal `R`.
#[inline(always)]
fn radar_log_lik(y: &RadarObs, r_inv: [f64; 2], px: &[f64], py: &[f64], lw: &mut [f64]) {
    let mut e = [[0.0; TILE]; 2];
    for ((lw, px), py) in lw
        .chunks_mut(TILE)
        .zip(px.chunks(TILE))
        .zip(py.chunks(TILE))
    {
        let m = lw.len();
        Measurement::<2, 2>::residuals(&RangeAzimuth, 0, y, &[px, py], m, &mut e);
        for (q, l) in lw.iter_mut().enumerate() {
            *l = -0.5 * (e[0][q] * e[0][q] * r_inv[0] + e[1][q] * e[1][q] * r_inv[1]);
        }
    }
}

/// Measure the raw [`Timings`] (Section IV-A, steps 1–2), every configuration interleaved.
///
/// Each part is timed on the kernel the filters run: products column by column over the
/// particles, the radar likelihood over columns with the weights' normalisation, systematic
/// resampling with the gather of [`RESAMPLED_STATE_DIM`] state columns, and the batch
/// engine's standard normals ([`LaneRng::fill_normal`](pf_core::simd::LaneRng::fill_normal)).
///
/// # Errors
/// A bad configuration.
pub fn measure(cfg: &CalibrateConfig) -> Result<Timings> {
    cfg.validate()?;
    let mut rng = pf_core::mc::stream_rng(cfg.seed, 0);
    // 1. one flop: d×d · d×N products cost d·N·(2d − 1) flops (Table I's count).
    let mut flops = Vec::new();
    let mut mats = Vec::new();
    for &d in &cfg.dims {
        for &n in &cfg.n_values {
            let a: Vec<f64> = (0..d * d)
                .map(|i| 1.0 / (1 + i / d + i % d) as f64)
                .collect();
            let x: Vec<Vec<f64>> = (0..d)
                .map(|r| (0..n).map(|j| ((r * 7 + j) % 13) as f64).collect())
                .collect();
            mats.push((a, x, vec![vec![0.0; n]; d]));
            flops.push((d * n * (2 * d - 1)) as f64);
        }
    }
    // 2. likelihood (with its share of the normalisation), resampling and randn per particle.
    let r_inv = [1.0 / 100.0, 1.0 / 1e-6];
    let y = RadarObs::new(2500.0, 0.64);
    let m = RESAMPLED_STATE_DIM;
    struct PerN {
        px: Vec<f64>,
        py: Vec<f64>,
        lw: Vec<f64>,
        w: Vec<f64>,
        anc: Vec<usize>,
        wr: Vec<f64>,
        states: Vec<Vec<f64>>,
        moved: Vec<Vec<f64>>,
        buf: Vec<f64>,
    }
    let mut per_n: Vec<PerN> = cfg
        .n_values
        .iter()
        .map(|&n| {
            let mut draw = |centre: f64| -> Vec<f64> {
                (0..n)
                    .map(|_| {
                        let z: f64 = StandardNormal.sample(&mut rng);
                        centre + 30.0 * z
                    })
                    .collect()
            };
            let (px, py) = (draw(2000.0), draw(1500.0));
            // Uneven weights, as after a measurement update, so resampling moves particles.
            let mut wr: Vec<f64> = (0..n)
                .map(|_| {
                    let z: f64 = StandardNormal.sample(&mut rng);
                    (-0.5 * z * z).exp()
                })
                .collect();
            let s: f64 = wr.iter().sum();
            wr.iter_mut().for_each(|w| *w /= s);
            PerN {
                px,
                py,
                lw: vec![0.0; n],
                w: vec![0.0; n],
                anc: vec![0; n],
                wr,
                states: (0..m)
                    .map(|c| (0..n).map(|i| (i * m + c) as f64).collect())
                    .collect(),
                moved: vec![vec![0.0; n]; m],
                buf: vec![0.0; n],
            }
        })
        .collect();
    let mut jobs: Vec<Box<dyn FnMut() + '_>> = Vec::new();
    for (a, x, out) in &mut mats {
        let (a, x) = (&*a, &*x);
        jobs.push(Box::new(move || {
            widest(
                #[inline(always)]
                || product_columns(a, x, out),
            );
            black_box(&*out);
        }));
    }
    let n_prod = jobs.len();
    let n_n = per_n.len();
    let mut streams = (1..).map(|s| pf_core::mc::stream_rng(cfg.seed, s));
    let mut lik_jobs: Vec<Box<dyn FnMut() + '_>> = Vec::new();
    let mut res_jobs: Vec<Box<dyn FnMut() + '_>> = Vec::new();
    let mut rnd_jobs: Vec<Box<dyn FnMut() + '_>> = Vec::new();
    for p in &mut per_n {
        let PerN {
            px,
            py,
            lw,
            w,
            anc,
            wr,
            states,
            moved,
            buf,
        } = p;
        let (px, py) = (&*px, &*py);
        lik_jobs.push(Box::new(move || {
            widest(
                #[inline(always)]
                || {
                    radar_log_lik(&y, r_inv, px, py, lw);
                    let _ = pf_core::weights::normalise_into(0, lw, w);
                },
            );
            black_box(&*w);
        }));
        let mut rng_res = streams.next().expect("endless");
        let wr = &*wr;
        let states = &*states;
        res_jobs.push(Box::new(move || {
            widest(
                #[inline(always)]
                || {
                    Resampler::Systematic.resample(wr, &mut rng_res, anc);
                    for (dst, src) in moved.iter_mut().zip(states) {
                        for (d, &a) in dst.iter_mut().zip(anc.iter()) {
                            *d = src[a];
                        }
                    }
                },
            );
            black_box(&*moved);
        }));
        let mut lanes = pf_core::simd::LaneRng::from_rng(&mut streams.next().expect("endless"));
        rnd_jobs.push(Box::new(move || {
            lanes.fill_normal(buf);
            black_box(&*buf);
        }));
    }
    jobs.extend(lik_jobs);
    jobs.extend(res_jobs);
    jobs.extend(rnd_jobs);
    let mut all = interleaved(cfg.reps, cfg.rounds, &mut jobs);
    let randn_ns = all.split_off(n_prod + 2 * n_n);
    let resample_ns = all.split_off(n_prod + n_n);
    let likelihood_ns = all.split_off(n_prod);
    Ok(Timings {
        flops,
        product_ns: all,
        n: cfg.n_values.iter().map(|&n| n as f64).collect(),
        likelihood_ns,
        resample_ns,
        randn_ns,
    })
}

/// The time of each stage of one filter step, per particle (ns), measured on a
/// [`BatchModel`]: what Table I and `c1, c2, c3` stand for, on the filter's own code.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct StageTimes {
    /// The step's standard normals, `noise_dim` per particle (pf-core's `LaneRng`):
    /// eq. (11)'s `p c3`.
    pub normals_ns: f64,
    /// `propagate` from the resampled parents: eq. (11)'s flops (Table I's time update).
    pub propagate_ns: f64,
    /// `add_log_likelihood` and the weights' normalisation: eq. (11)'s `c1`.
    pub likelihood_ns: f64,
    /// Systematic resampling and the gather of the `dim` state columns: eq. (11)'s `c2`.
    pub resample_ns: f64,
}

impl StageTimes {
    /// Their sum.
    pub fn total_ns(&self) -> f64 {
        self.normals_ns + self.propagate_ns + self.likelihood_ns + self.resample_ns
    }
}

/// Time each stage of a step of `model` with `n` particles at time `t` (observation `y`),
/// each stage on its own over all particles, interleaved over `rounds` rounds, median per
/// stage ([`Stopwatch`]: the thread's CPU time). The particles start from the model's
/// `initial` draw. Single-threaded; meant for a model whose `propagate` and likelihood are
/// plain loops over the particle columns, as the batch engine calls them.
///
/// # Errors
/// `n = 0` or `rounds = 0`.
pub fn stage_times<M>(
    model: &M,
    t: usize,
    y: &M::Obs,
    n: usize,
    rounds: usize,
    seed: u64,
) -> Result<StageTimes>
where
    M: BatchModel<Input = ()>,
{
    params::at_least_one("N", n)?;
    params::at_least_one("rounds", rounds)?;
    let (dim, q) = (model.dim(), model.noise_dim());
    let mut lanes = pf_core::simd::LaneRng::from_rng(&mut pf_core::mc::stream_rng(seed, 1));
    let mut z0 = vec![0.0; model.initial_noise_dim() * n];
    lanes.fill_normal(&mut z0);
    let mut parents = vec![0.0; dim * n];
    model.initial(
        Cols::new(&z0, model.initial_noise_dim(), n),
        ColsMut::new(&mut parents, dim, n),
    );
    let mut z = vec![0.0; q * n];
    let mut x = vec![0.0; dim * n];
    let (mut lw, mut w) = (vec![0.0; n], vec![1.0 / n as f64; n]);
    let mut anc = vec![0usize; n];
    let mut gathered = vec![0.0; dim * n];
    let mut rng = pf_core::mc::stream_rng(seed, 2);
    let mut times: Vec<Vec<f64>> = (0..4).map(|_| Vec::with_capacity(rounds)).collect();
    let mut inner = [0usize; 4];
    // Each stage is timed over blocks of at least MIN_BLOCK_NS, the stages in turn.
    let mut time = |j: usize, f: &mut dyn FnMut(), first: bool| {
        if first {
            inner[j] = calls_per_block(f);
        }
        times[j].push(block_ns(inner[j], f));
    };
    for r in 0..rounds {
        time(
            0,
            &mut || {
                lanes.fill_normal(&mut z);
                black_box(&z);
            },
            r == 0,
        );
        time(
            1,
            &mut || {
                widest(
                    #[inline(always)]
                    || {
                        model.propagate(
                            t,
                            &(),
                            Cols::new(&parents, dim, n),
                            Cols::new(&z, q, n),
                            ColsMut::new(&mut x, dim, n),
                        )
                    },
                );
                black_box(&x);
            },
            r == 0,
        );
        time(
            2,
            &mut || {
                widest(
                    #[inline(always)]
                    || {
                        lw.fill(0.0);
                        model.add_log_likelihood(t, y, Cols::new(&x, dim, n), &mut lw);
                        let _ = pf_core::weights::normalise_into(t, &lw, &mut w);
                    },
                );
                black_box(&w);
            },
            r == 0,
        );
        time(
            3,
            &mut || {
                widest(
                    #[inline(always)]
                    || {
                        Resampler::Systematic.resample(&w, &mut rng, &mut anc);
                        for (src, dst) in x.chunks_exact(n).zip(gathered.chunks_exact_mut(n)) {
                            for (d, &a) in dst.iter_mut().zip(&anc) {
                                *d = src[a];
                            }
                        }
                    },
                );
                black_box(&gathered);
            },
            r == 0,
        );
    }
    let per = |v: &[f64]| median(v) / n as f64;
    Ok(StageTimes {
        normals_ns: per(&times[0]),
        propagate_ns: per(&times[1]),
        likelihood_ns: per(&times[2]),
        resample_ns: per(&times[3]),
    })
}

/// Calibrate the EF model on this machine (Section IV-A, steps 1–3): [`measure`], then
/// [`fit_timings`].
///
/// # Errors
/// A bad configuration only; degenerate timings fall back with a note.
pub fn calibrate_report(cfg: &CalibrateConfig) -> Result<CalibrationReport> {
    let t = measure(cfg)?;
    Ok(fit_timings(&t, cfg.bootstrap, cfg.seed))
}

/// `pf-viz mpf calibrate`: [`calibrate_report`]'s [`Calibration`].
///
/// # Errors
/// As [`calibrate_report`].
pub fn calibrate(cfg: &CalibrateConfig) -> Result<Calibration> {
    calibrate_report(cfg).map(|r| r.calibration)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On Linux the stopwatch reads the thread's CPU clock: a 100 ms sleep counts as
    /// (almost) nothing, and 30 ms of busy work counts, never more than the wall time.
    #[cfg(target_os = "linux")]
    #[test]
    fn the_stopwatch_counts_cpu_time_not_sleep() {
        assert_eq!(Stopwatch::clock(), "thread CPU time");
        let sleep = Stopwatch::start();
        std::thread::sleep(std::time::Duration::from_millis(100));
        let slept = sleep.elapsed_s();
        assert!(slept < 0.02, "{slept} s of CPU time while sleeping");
        let (busy, wall) = (Stopwatch::start(), Instant::now());
        let mut x = 0u64;
        while wall.elapsed().as_secs_f64() < 0.03 {
            x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
        }
        let (cpu, wall) = (busy.elapsed_s(), wall.elapsed().as_secs_f64());
        assert!(
            cpu > 0.0 && cpu <= wall + 1e-3,
            "CPU {cpu} s in {wall} s of wall time"
        );
    }

    /// KKT conditions of NNLS: `c ≥ 0`, gradient `Aᵀr ≤ 0` where `c = 0`, `≈ 0` where `c > 0`.
    fn assert_kkt(cols: &[&[f64]], y: &[f64], c: &[f64]) {
        let r: Vec<f64> = (0..y.len())
            .map(|i| y[i] - cols.iter().zip(c).map(|(col, cj)| col[i] * cj).sum::<f64>())
            .collect();
        let scale = y.iter().map(|v| v * v).sum::<f64>().sqrt();
        for (j, col) in cols.iter().enumerate() {
            let norm = col.iter().map(|v| v * v).sum::<f64>().sqrt();
            let g = col.iter().zip(&r).map(|(a, b)| a * b).sum::<f64>() / norm;
            assert!(c[j] >= 0.0, "c[{j}] = {}", c[j]);
            if c[j] > 0.0 {
                assert!(g.abs() <= 1e-8 * scale, "gradient {g} on positive c[{j}]");
            } else {
                assert!(g <= 1e-8 * scale, "gradient {g} > 0 on zero c[{j}]");
            }
        }
    }

    /// A 2-D random walk observed in its first component, for the stage profiler.
    struct Walk;

    impl BatchModel for Walk {
        type Obs = f64;
        type Input = ();
        fn dim(&self) -> usize {
            2
        }
        fn noise_dim(&self) -> usize {
            2
        }
        fn initial(&self, z: Cols<'_>, mut x: ColsMut<'_>) {
            for k in 0..2 {
                x.col_mut(k).copy_from_slice(z.col(k));
            }
        }
        fn propagate(&self, _t: usize, _u: &(), p: Cols<'_>, z: Cols<'_>, mut x: ColsMut<'_>) {
            for k in 0..2 {
                for ((x, &p), &z) in x.col_mut(k).iter_mut().zip(p.col(k)).zip(z.col(k)) {
                    *x = p + z;
                }
            }
        }
        fn add_log_likelihood(&self, _t: usize, y: &f64, x: Cols<'_>, lw: &mut [f64]) {
            for (l, &x) in lw.iter_mut().zip(x.col(0)) {
                *l += -0.5 * (y - x) * (y - x);
            }
        }
    }

    /// The profiler runs every stage of a step on a model and reports a non-negative,
    /// finite cost per particle for each (no assertion on the times themselves).
    #[test]
    fn stage_times_cover_every_stage() {
        let st = stage_times(&Walk, 1, &0.3, 256, 2, 7).unwrap();
        for v in [
            st.normals_ns,
            st.propagate_ns,
            st.likelihood_ns,
            st.resample_ns,
        ] {
            assert!(v.is_finite() && v >= 0.0, "{st:?}");
        }
        assert!(
            (st.total_ns() - st.normals_ns - st.propagate_ns - st.likelihood_ns - st.resample_ns)
                .abs()
                < 1e-9
        );
        assert!(stage_times(&Walk, 1, &0.3, 0, 2, 7).is_err());
        assert!(stage_times(&Walk, 1, &0.3, 8, 0, 7).is_err());
    }

    #[test]
    fn nnls_recovers_known_nonnegative_coefficients() {
        // y = 2 + 3·x1 + 0.5·x2 exactly, regressors of very different sizes.
        let x1: Vec<f64> = (0..12).map(|i| 1e4 * (1 + i) as f64).collect();
        let x2: Vec<f64> = (0..12).map(|i| ((i * 7) % 5) as f64).collect();
        let ones = vec![1.0; 12];
        let y: Vec<f64> = (0..12).map(|i| 2.0 + 3.0 * x1[i] + 0.5 * x2[i]).collect();
        let c = nnls(&[&ones, &x1, &x2], &y).unwrap();
        for (got, want) in c.iter().zip([2.0, 3.0, 0.5]) {
            assert!((got - want).abs() < 1e-6 * want, "{c:?}");
        }
    }

    #[test]
    fn nnls_clamps_where_least_squares_goes_negative() {
        // Falling times: least squares gives a negative slope, NNLS a flat line at the mean.
        let x = [1.0, 2.0, 3.0, 4.0, 5.0];
        let y = [5.0, 4.2, 3.9, 3.1, 2.8];
        let ols = fit_line(&x, &y);
        assert!(ols.slope < 0.0);
        let f = fit_line_nonneg(&x, &y).unwrap();
        assert_eq!(f.slope, 0.0);
        assert!((f.intercept - y.iter().sum::<f64>() / 5.0).abs() < 1e-12);
        // A large negative intercept under least squares: NNLS puts the line through the
        // origin with slope Σxy/Σx².
        let y = [0.5, 3.1, 5.0, 7.2, 9.1];
        assert!(fit_line(&x, &y).intercept < 0.0);
        let f = fit_line_nonneg(&x, &y).unwrap();
        assert_eq!(f.intercept, 0.0);
        let sxy: f64 = x.iter().zip(&y).map(|(a, b)| a * b).sum();
        let sxx: f64 = x.iter().map(|a| a * a).sum();
        assert!((f.slope - sxy / sxx).abs() < 1e-12);
        // Three columns, one coefficient negative under least squares: KKT holds.
        let a1 = [1.0, 0.0, 1.0, 2.0, 0.5, 1.5];
        let a2 = [0.0, 1.0, 1.0, 1.0, 2.0, 0.2];
        let a3 = [1.0, 1.0, 2.0, 3.0, 2.5, 1.7];
        let y = [1.0, 2.0, 0.5, 0.3, 3.0, 0.1];
        let c = nnls(&[&a1, &a2, &a3], &y).unwrap();
        assert_kkt(&[&a1, &a2, &a3], &y, &c);
        assert!(c.contains(&0.0), "{c:?}");
    }

    #[test]
    fn nnls_rejects_bad_input() {
        assert!(nnls(&[], &[1.0]).is_err());
        assert!(nnls(&[&[1.0, 2.0]], &[1.0]).is_err());
        assert!(nnls(&[&[1.0, f64::NAN]], &[1.0, 2.0]).is_err());
        // An all-zero column gets coefficient 0, no NaN.
        let c = nnls(&[&[0.0, 0.0], &[1.0, 2.0]], &[2.0, 4.0]).unwrap();
        assert_eq!(c[0], 0.0);
        assert!((c[1] - 2.0).abs() < 1e-12, "{c:?}");
    }

    fn synthetic(rounds: usize, f: impl Fn(f64, usize) -> f64) -> Timings {
        let flops: Vec<f64> = [3000.0, 6000.0, 12000.0, 42000.0].to_vec();
        let n = vec![200.0, 400.0, 800.0];
        let rows = |xs: &[f64], per: f64| -> Vec<Vec<f64>> {
            xs.iter()
                .map(|&x| (0..rounds).map(|r| f(per * x, r)).collect())
                .collect()
        };
        Timings {
            product_ns: rows(&flops, 0.05),
            flops,
            likelihood_ns: rows(&n, 20.0),
            resample_ns: rows(&n, 3.0),
            randn_ns: rows(&n, 2.5),
            n,
        }
    }

    #[test]
    fn fit_recovers_a_noise_free_machine_and_ignores_an_outlying_round() {
        // Round 2 is three times slower everywhere (the machine was busy): the median ignores it.
        let t = synthetic(5, |x, r| 100.0 + x * if r == 2 { 3.0 } else { 1.0 });
        let rep = fit_timings(&t, 100, 1);
        let c = rep.calibration;
        assert!((c.flop_ns - 0.05).abs() < 1e-9, "{c:?}");
        for (got, want) in [(c.c1, 400.0), (c.c2, 60.0), (c.c3, 50.0)] {
            assert!((got - want).abs() < 1e-6 * want, "{c:?}");
        }
        assert!(rep.notes.is_empty(), "{:?}", rep.notes);
        assert_eq!(rep.samples.len(), 100);
        // Only a bootstrap draw that takes round 2 three or more times of five moves the
        // median, about 6 % of draws (0.2³ binomial tail), so the central 68 % of the draws
        // agree exactly: one slow round does not widen the interval.
        assert_eq!(rep.spread, CalibrationSpread::default(), "{:?}", rep.spread);
    }

    #[test]
    fn degenerate_timings_fall_back_without_error_or_nan() {
        type Machine = fn(f64, usize) -> f64;
        let cases: [(&str, Machine); 4] = [
            ("all zero", |_, _| 0.0),
            ("constant", |_, _| 1000.0),
            ("falling", |x, _| 1e6 / (1.0 + x)),
            ("not finite", |_, r| {
                if r % 2 == 0 { f64::NAN } else { f64::INFINITY }
            }),
        ];
        for (name, f) in cases {
            let rep = fit_timings(&synthetic(4, f), 20, 0);
            let c = rep.calibration;
            assert!(c.validate().is_ok(), "{name}: {c:?}");
            assert!(!rep.notes.is_empty(), "{name}: a fall-back must say so");
            for s in &rep.samples {
                assert!(s.validate().is_ok(), "{name}: bootstrap {s:?}");
            }
            let sp = rep.spread;
            for v in [sp.flop_ns, sp.c1, sp.c2, sp.c3] {
                assert!(v.is_finite() && v >= 0.0, "{name}: spread {sp:?}");
            }
            assert!(serde_json::to_string(&rep).is_ok());
        }
        // No time at all: the paper's coefficients.
        let rep = fit_timings(&synthetic(3, |_, _| 0.0), 0, 0);
        assert_eq!(rep.calibration, Calibration::FALLBACK);
        // One round: no bootstrap, a note, still a calibration.
        let rep = fit_timings(&synthetic(1, |x, _| 10.0 + x), 50, 0);
        assert!(rep.samples.is_empty() && rep.calibration.validate().is_ok());
        assert!(rep.notes.iter().any(|n| n.contains("one round")));
    }
}
