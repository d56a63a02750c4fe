//! Log-domain weights: the one log-sum-exp, normalisation and effective sample size.
//!
//! Weights live in the log domain throughout the engine. Normalising them is where
//! degeneracy shows up, so this is also where it becomes an error instead of a NaN.

use crate::error::{CoreError, Result};

/// `log Σ_i exp(l_i)`, stable for any finite maximum; `−∞` when every term is `−∞` or the
/// slice is empty. A NaN anywhere gives NaN (callers validate first).
pub fn log_sum_exp(log_w: &[f64]) -> f64 {
    let max = log_w.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !max.is_finite() {
        return max;
    }
    let sum: f64 = log_w.iter().map(|&l| (l - max).exp()).sum();
    max + sum.ln()
}

/// Normalise log-weights in place so that `Σ exp(log_w) = 1`, and write the normalised
/// weights into `w`. Returns `log Σ exp(log_w)` of the input, the log normalising constant.
///
/// # Errors
/// [`CoreError::NonFiniteWeight`] for a NaN or `+∞` log-weight, [`CoreError::AllWeightsZero`]
/// when every weight is zero. `t` only labels the error. On error, `log_w` is unchanged.
pub fn normalise(t: usize, log_w: &mut [f64], w: &mut [f64]) -> Result<f64> {
    debug_assert_eq!(log_w.len(), w.len());
    let mut max = f64::NEG_INFINITY;
    for (index, &l) in log_w.iter().enumerate() {
        if l.is_nan() || l == f64::INFINITY {
            return Err(CoreError::NonFiniteWeight { t, index, value: l });
        }
        max = max.max(l);
    }
    if max == f64::NEG_INFINITY {
        return Err(CoreError::AllWeightsZero { t });
    }
    let mut sum = 0.0;
    for (wi, &l) in w.iter_mut().zip(log_w.iter()) {
        *wi = (l - max).exp();
        sum += *wi;
    }
    let inv = 1.0 / sum;
    let log_norm = max + sum.ln();
    for (wi, l) in w.iter_mut().zip(log_w.iter_mut()) {
        *wi *= inv;
        *l -= log_norm;
    }
    Ok(log_norm)
}

/// Effective sample size `1 / Σ W_i²` of normalised weights (Kong, Liu & Wong 1994).
pub fn ess(w: &[f64]) -> f64 {
    1.0 / w.iter().map(|x| x * x).sum::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_sum_exp_handles_large_and_infinite_values() {
        // Naive exp would overflow at 1000; the result must be exact to rounding.
        let l = [1000.0, 1000.0];
        assert!((log_sum_exp(&l) - (1000.0 + 2f64.ln())).abs() < 1e-12);
        assert_eq!(log_sum_exp(&[f64::NEG_INFINITY; 3]), f64::NEG_INFINITY);
        assert_eq!(log_sum_exp(&[]), f64::NEG_INFINITY);
        assert!((log_sum_exp(&[f64::NEG_INFINITY, 0.0]) - 0.0).abs() < 1e-15);
    }

    #[test]
    fn normalise_gives_unit_sum_and_the_constant() {
        let mut l = vec![-1.0, -2.0, f64::NEG_INFINITY, -3.0];
        let mut w = vec![0.0; 4];
        let c = normalise(0, &mut l, &mut w).unwrap();
        let expected = ((-1f64).exp() + (-2f64).exp() + (-3f64).exp()).ln();
        assert!((c - expected).abs() < 1e-14);
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        assert_eq!(w[2], 0.0);
        assert!((log_sum_exp(&l)).abs() < 1e-15);
        assert!((ess(&[0.25; 4]) - 4.0).abs() < 1e-12);
    }

    #[test]
    fn degenerate_weights_are_errors_and_leave_input_untouched() {
        let mut l = vec![f64::NEG_INFINITY; 3];
        let mut w = vec![0.0; 3];
        assert_eq!(
            normalise(7, &mut l, &mut w),
            Err(CoreError::AllWeightsZero { t: 7 })
        );
        let mut l = vec![0.0, f64::NAN];
        let before = l.clone();
        let err = normalise(2, &mut l, &mut w[..2]).unwrap_err();
        assert!(matches!(
            err,
            CoreError::NonFiniteWeight { t: 2, index: 1, .. }
        ));
        assert_eq!(l[0], before[0]);
    }
}
