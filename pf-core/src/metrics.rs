//! Error metrics: RMSE as Karlsson et al. define it, REC curves, residual summaries, and
//! the summaries a figure shows of replicated estimates: equal-width histograms and Tukey's
//! box-plot numbers.

use crate::error::{CoreError, Result};
use crate::params::ParamError;
use serde::{Deserialize, Serialize};

/// `‖a − b‖²`.
///
/// # Errors
/// Vectors of different lengths.
pub fn squared_error(a: &[f64], b: &[f64]) -> Result<f64> {
    if a.len() != b.len() {
        return Err(CoreError::DimensionMismatch {
            what: "estimate against truth",
            expected: a.len(),
            got: b.len(),
        });
    }
    Ok(a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum())
}

fn check_rectangular(sq: &[Vec<f64>]) -> Result<usize> {
    let t_f = sq
        .first()
        .ok_or(CoreError::Empty {
            what: "replications",
        })?
        .len();
    if t_f == 0 {
        return Err(CoreError::Empty { what: "time steps" });
    }
    for row in sq {
        if row.len() != t_f {
            return Err(CoreError::DimensionMismatch {
                what: "time steps of a replication",
                expected: t_f,
                got: row.len(),
            });
        }
        if let Some(index) = row.iter().position(|v| !v.is_finite()) {
            return Err(CoreError::NonFiniteData {
                what: "squared errors",
                index,
                value: row[index],
            });
        }
    }
    Ok(t_f)
}

/// RMSE at each time step: `(1/N_MC Σ_j ‖x_i^true − x̂_i^(j)‖²)^{1/2}`, from squared errors
/// `sq[j][i]` of replication `j` at step `i`.
///
/// # Errors
/// No replications, ragged rows, or non-finite errors.
pub fn rmse_per_step(sq: &[Vec<f64>]) -> Result<Vec<f64>> {
    let t_f = check_rectangular(sq)?;
    let n_mc = sq.len() as f64;
    Ok((0..t_f)
        .map(|i| (sq.iter().map(|row| row[i]).sum::<f64>() / n_mc).sqrt())
        .collect())
}

/// Karlsson, Schön & Gustafsson's RMSE over a run:
/// `(1/T_f Σ_i 1/N_MC Σ_j ‖x_i^true − x̂_i^(j)‖²)^{1/2}`.
///
/// # Errors
/// As [`rmse_per_step`].
pub fn rmse(sq: &[Vec<f64>]) -> Result<f64> {
    let t_f = check_rectangular(sq)?;
    let total: f64 = sq.iter().flatten().sum();
    Ok((total / (t_f as f64 * sq.len() as f64)).sqrt())
}

/// A regression error characteristic curve (Bi & Bennett 2003): the fraction of errors
/// within each tolerance, as El Abed et al. plot in their Fig. 4(c).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecCurve {
    /// Tolerances, increasing.
    pub tolerance: Vec<f64>,
    /// Fraction of `|error| ≤ tolerance`, in `[0, 1]`.
    pub accuracy: Vec<f64>,
}

/// The REC curve of `errors` (absolute values are taken) over `tolerances` (sorted here).
///
/// # Errors
/// No errors, or a non-finite error or tolerance.
pub fn rec_curve(errors: &[f64], tolerances: &[f64]) -> Result<RecCurve> {
    if errors.is_empty() {
        return Err(CoreError::Empty { what: "errors" });
    }
    let mut abs: Vec<f64> = Vec::with_capacity(errors.len());
    for (index, &e) in errors.iter().enumerate() {
        if !e.is_finite() {
            return Err(CoreError::NonFiniteData {
                what: "errors",
                index,
                value: e,
            });
        }
        abs.push(e.abs());
    }
    if let Some(index) = tolerances.iter().position(|t| !t.is_finite()) {
        return Err(CoreError::NonFiniteData {
            what: "tolerances",
            index,
            value: tolerances[index],
        });
    }
    abs.sort_by(f64::total_cmp);
    let mut tolerance = tolerances.to_vec();
    tolerance.sort_by(f64::total_cmp);
    let n = abs.len() as f64;
    let accuracy = tolerance
        .iter()
        .map(|&tol| abs.partition_point(|&e| e <= tol) as f64 / n)
        .collect();
    Ok(RecCurve {
        tolerance,
        accuracy,
    })
}

/// `m` evenly spaced tolerances from 0 to `max`.
pub fn tolerance_grid(max: f64, m: usize) -> Vec<f64> {
    let m = m.max(2);
    // The last point is exactly `max` (the product can round one ulp below it, and a REC
    // curve would then stop short of 1).
    (0..m)
        .map(|i| {
            if i + 1 == m {
                max
            } else {
                max * i as f64 / (m - 1) as f64
            }
        })
        .collect()
}

/// Mean, standard deviation and largest magnitude of residuals.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ResidualSummary {
    /// Sample mean.
    pub mean: f64,
    /// Sample standard deviation (divisor `n − 1`; 0 for one residual).
    pub std: f64,
    /// `max |r_i|`.
    pub max_abs: f64,
}

impl ResidualSummary {
    /// Summarise residuals.
    ///
    /// # Errors
    /// No residuals, or a non-finite one.
    pub fn new(r: &[f64]) -> Result<Self> {
        if r.is_empty() {
            return Err(CoreError::Empty { what: "residuals" });
        }
        if let Some(index) = r.iter().position(|v| !v.is_finite()) {
            return Err(CoreError::NonFiniteData {
                what: "residuals",
                index,
                value: r[index],
            });
        }
        let n = r.len() as f64;
        let mean = r.iter().sum::<f64>() / n;
        let var = if r.len() > 1 {
            r.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)
        } else {
            0.0
        };
        let max_abs = r.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        Ok(ResidualSummary {
            mean,
            std: var.sqrt(),
            max_abs,
        })
    }
}

/// Counts in equal-width bins: `bins + 1` increasing edges and a count per bin.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Histogram {
    /// `bins + 1` edges, from the smallest value to the largest.
    pub edges: Vec<f64>,
    /// Count per bin; the largest value falls in the last bin.
    pub counts: Vec<usize>,
}

impl Histogram {
    /// `bins` equal-width bins over `[min, max]` of `x`; a constant sample gets one unit of
    /// width centred on its value, so that the edges still increase.
    ///
    /// # Errors
    /// No values, a non-finite value (which would otherwise land silently in a bin), or
    /// `bins = 0`.
    pub fn new(x: &[f64], bins: usize) -> Result<Self> {
        if x.is_empty() {
            return Err(CoreError::Empty {
                what: "histogram values",
            });
        }
        if bins == 0 {
            return Err(CoreError::Param(ParamError {
                name: "bins",
                value: 0.0,
                reason: "a histogram needs at least one bin",
            }));
        }
        if let Some(index) = x.iter().position(|v| !v.is_finite()) {
            return Err(CoreError::NonFiniteData {
                what: "histogram values",
                index,
                value: x[index],
            });
        }
        let lo = x.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = x.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let (lo, hi) = if hi > lo {
            (lo, hi)
        } else {
            (lo - 0.5, lo + 0.5)
        };
        let w = (hi - lo) / bins as f64;
        let edges = (0..=bins).map(|i| lo + w * i as f64).collect();
        let mut counts = vec![0; bins];
        for &v in x {
            counts[(((v - lo) / w) as usize).min(bins - 1)] += 1;
        }
        Ok(Histogram { edges, counts })
    }
}

/// The `p`-quantile of values sorted in ascending order, by linear interpolation between
/// order statistics (type 7, R's default `quantile`); NaN for no values.
pub fn quantile_sorted(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let h = p.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let (lo, hi) = (h.floor() as usize, h.ceil() as usize);
    sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
}

/// Tukey's box-plot numbers of a sample: quartiles by linear interpolation (type 7, R's
/// default `quantile`), whiskers to the furthest values within 1.5·IQR of the box, and the
/// values beyond them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BoxStats {
    /// First quartile (bottom of the box).
    pub q1: f64,
    /// Median (the bar inside the box).
    pub median: f64,
    /// Third quartile (top of the box).
    pub q3: f64,
    /// Lowest value ≥ q1 − 1.5·IQR (end of the lower whisker).
    pub whisker_low: f64,
    /// Highest value ≤ q3 + 1.5·IQR (end of the upper whisker).
    pub whisker_high: f64,
    /// Values beyond the whiskers.
    pub outliers: Vec<f64>,
    /// Sample size.
    pub count: usize,
    /// Sample mean (not drawn; kept for tables).
    pub mean: f64,
}

impl BoxStats {
    /// The box-plot numbers of `x`.
    ///
    /// # Errors
    /// No values, or a non-finite value (whose place in the order would be arbitrary).
    pub fn new(x: &[f64]) -> Result<Self> {
        if x.is_empty() {
            return Err(CoreError::Empty {
                what: "box-plot values",
            });
        }
        if let Some(index) = x.iter().position(|v| !v.is_finite()) {
            return Err(CoreError::NonFiniteData {
                what: "box-plot values",
                index,
                value: x[index],
            });
        }
        let mut s = x.to_vec();
        s.sort_by(f64::total_cmp);
        let q = |p: f64| quantile_sorted(&s, p);
        let (q1, median, q3) = (q(0.25), q(0.5), q(0.75));
        let iqr = q3 - q1;
        let (lo_fence, hi_fence) = (q1 - 1.5 * iqr, q3 + 1.5 * iqr);
        let inside = |v: &&f64| **v >= lo_fence && **v <= hi_fence;
        // With few values the nearest value inside a fence can lie inside the box (an
        // interpolated quartile sits between an outlier and it): the whisker then has length 0.
        let whisker_low = s.iter().find(inside).copied().unwrap_or(q1).min(q1);
        let whisker_high = s.iter().rev().find(inside).copied().unwrap_or(q3).max(q3);
        Ok(BoxStats {
            q1,
            median,
            q3,
            whisker_low,
            whisker_high,
            outliers: s
                .iter()
                .copied()
                .filter(|v| *v < lo_fence || *v > hi_fence)
                .collect(),
            count: s.len(),
            mean: s.iter().sum::<f64>() / s.len() as f64,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 10, 20, 30, 40: the quartile positions 0.75 and 2.25 interpolate to 17.5 and 32.5;
    /// the ends are the extremes; one value is every quantile; none is NaN.
    #[test]
    fn quantiles_interpolate_between_order_statistics() {
        let s = [10.0, 20.0, 30.0, 40.0];
        assert_eq!(quantile_sorted(&s, 0.25), 17.5);
        assert_eq!(quantile_sorted(&s, 0.5), 25.0);
        assert_eq!(quantile_sorted(&s, 0.75), 32.5);
        assert_eq!(
            (quantile_sorted(&s, 0.0), quantile_sorted(&s, 1.0)),
            (10.0, 40.0)
        );
        assert_eq!(quantile_sorted(&[7.0], 0.3), 7.0);
        assert!(quantile_sorted(&[], 0.5).is_nan());
    }

    #[test]
    fn tukey_numbers_of_a_known_sample() {
        // 1..=9 plus 100: q1 = 3.25, median 5.5, q3 = 7.75 (type 7), IQR 4.5, fences
        // −3.5 and 14.5, so the upper whisker stops at 9 and 100 is an outlier.
        let x: Vec<f64> = (1..=9).map(f64::from).chain([100.0]).collect();
        let b = BoxStats::new(&x).unwrap();
        assert_eq!((b.q1, b.median, b.q3), (3.25, 5.5, 7.75));
        assert_eq!((b.whisker_low, b.whisker_high), (1.0, 9.0));
        assert_eq!(b.outliers, vec![100.0]);
        assert_eq!(b.count, 10);
        assert_eq!(b.mean, 14.5);
        assert!(BoxStats::new(&[]).is_err());
        let e = BoxStats::new(&[1.0, f64::NAN]).unwrap_err().to_string();
        assert!(e.contains("box-plot values") && e.contains('1'), "{e}");
    }

    #[test]
    fn rmse_matches_the_definition() {
        // Two replications, two steps: squared errors 1, 4 / 9, 16.
        let sq = vec![vec![1.0, 4.0], vec![9.0, 16.0]];
        assert_eq!(rmse_per_step(&sq).unwrap(), vec![5f64.sqrt(), 10f64.sqrt()]);
        assert!((rmse(&sq).unwrap() - 7.5f64.sqrt()).abs() < 1e-15);
        assert!(rmse(&[vec![1.0], vec![]]).is_err());
        assert!(rmse(&[]).is_err());
        assert_eq!(squared_error(&[1.0, 2.0], &[0.0, 0.0]).unwrap(), 5.0);
    }

    #[test]
    fn rec_counts_errors_within_tolerance() {
        let c = rec_curve(&[0.5, -1.0, 2.0, 3.0], &[0.0, 1.0, 2.5, 10.0]).unwrap();
        assert_eq!(c.accuracy, vec![0.0, 0.5, 0.75, 1.0]);
        assert!(rec_curve(&[f64::NAN], &[1.0]).is_err());
        assert_eq!(tolerance_grid(2.0, 3), vec![0.0, 1.0, 2.0]);
    }

    #[test]
    fn residual_summary() {
        let s = ResidualSummary::new(&[1.0, -3.0, 2.0]).unwrap();
        assert_eq!(s.mean, 0.0);
        assert_eq!(s.max_abs, 3.0);
        assert!((s.std - 7f64.sqrt()).abs() < 1e-15);
        assert!(ResidualSummary::new(&[]).is_err());
    }

    #[test]
    fn histogram_counts_every_value_once_between_its_edges() {
        let x = [0.0, 0.1, 0.5, 0.9, 1.0, 0.25];
        let h = Histogram::new(&x, 4).unwrap();
        assert_eq!(h.edges, vec![0.0, 0.25, 0.5, 0.75, 1.0]);
        // [0, .25): 0, .1; [.25, .5): .25; [.5, .75): .5; [.75, 1]: .9, 1 (max in last bin).
        assert_eq!(h.counts, vec![2, 1, 1, 2]);
        let c = Histogram::new(&[3.0, 3.0], 2).unwrap();
        assert_eq!(c.edges, vec![2.5, 3.0, 3.5]);
        assert_eq!(c.counts, vec![0, 2]);
        assert!(Histogram::new(&[], 3).is_err());
        assert!(Histogram::new(&[1.0], 0).is_err());
        assert!(matches!(
            Histogram::new(&[1.0, f64::NAN], 3),
            Err(CoreError::NonFiniteData { index: 1, .. })
        ));
    }
}
