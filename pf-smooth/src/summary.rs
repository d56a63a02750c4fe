//! Box-plot summaries of replicated values, so that report tools draw without computing.

use serde::{Deserialize, Serialize};

/// Tukey box-plot numbers of a sample (quartiles by linear interpolation, type 7).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BoxSummary {
    /// Sample size.
    pub count: usize,
    /// Mean.
    pub mean: f64,
    /// Standard deviation (divisor R − 1).
    pub std: f64,
    /// Smallest value.
    pub min: f64,
    /// First quartile.
    pub q1: f64,
    /// Median.
    pub median: f64,
    /// Third quartile.
    pub q3: f64,
    /// Largest value.
    pub max: f64,
    /// Lowest value ≥ q1 − 1.5·IQR.
    pub whisker_low: f64,
    /// Highest value ≤ q3 + 1.5·IQR.
    pub whisker_high: f64,
}

impl BoxSummary {
    /// Summarise `x`; `None` if it is empty or holds a non-finite value.
    pub fn of(x: &[f64]) -> Option<Self> {
        if x.is_empty() || x.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let mut s = x.to_vec();
        s.sort_by(f64::total_cmp);
        let q = |p: f64| {
            let h = p * (s.len() - 1) as f64;
            let lo = h.floor() as usize;
            let hi = h.ceil() as usize;
            s[lo] + (h - lo as f64) * (s[hi] - s[lo])
        };
        let (q1, median, q3) = (q(0.25), q(0.5), q(0.75));
        let iqr = q3 - q1;
        let (mean, se) = pf_core::mc::mean_and_se(&s);
        let std = se * (s.len() as f64).sqrt();
        Some(BoxSummary {
            count: s.len(),
            mean,
            std,
            min: s[0],
            q1,
            median,
            q3,
            max: s[s.len() - 1],
            whisker_low: *s.iter().find(|&&v| v >= q1 - 1.5 * iqr).unwrap_or(&s[0]),
            whisker_high: *s
                .iter()
                .rev()
                .find(|&&v| v <= q3 + 1.5 * iqr)
                .unwrap_or(&s[s.len() - 1]),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quartiles_of_a_known_sample() {
        // 1..=9 plus an outlier 100: q1 = 3.25, median 5.5, q3 = 7.75 (type 7), IQR 4.5,
        // upper fence 14.5, so the high whisker stops at 9.
        let x: Vec<f64> = (1..=9).map(f64::from).chain([100.0]).collect();
        let b = BoxSummary::of(&x).unwrap();
        assert_eq!((b.q1, b.median, b.q3), (3.25, 5.5, 7.75));
        assert_eq!((b.whisker_low, b.whisker_high, b.max), (1.0, 9.0, 100.0));
        assert!(BoxSummary::of(&[]).is_none());
        assert!(BoxSummary::of(&[1.0, f64::NAN]).is_none());
    }
}
