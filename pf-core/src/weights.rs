//! Log-domain weights: the one log-sum-exp, normalisation and effective sample size.
//!
//! Weights live in the log domain throughout the engine. Normalising them is where
//! degeneracy shows up, so this is also where it becomes an error instead of a NaN.

use crate::error::{CoreError, Result};
use crate::simd::math::{exp_nonpositive_lanes, max_and_flag_lanes};
use crate::simd::{Simd, dispatch};

/// Weights exponentiated at a time: the lanes of one call of the vectorised `exp`.
const BLOCK: usize = 64;

/// `e^{l_i − max}` for the (at most [`BLOCK`]) values of `l`, all `≤ max`, by pf-core's
/// table-driven `exp` (within 2 ulp of the platform's, and about four times faster on
/// blocks of lanes; see [`crate::simd`]); the slots past `l.len()` hold 0.
#[inline(always)]
fn exp_block(l: &[f64], max: f64) -> [f64; BLOCK] {
    let mut x = [f64::NEG_INFINITY; BLOCK];
    for (xi, &li) in x.iter_mut().zip(l) {
        *xi = li - max;
    }
    exp_nonpositive_lanes(x)
}

/// `Σ_i e^{l_i − max}`, summed in index order, each term written to `w[i]` when `w` is
/// given. Compiled for AVX2 when the CPU has it; the bits are the same either way.
fn exp_sum(log_w: &[f64], max: f64, w: Option<&mut [f64]>) -> f64 {
    dispatch(
        Simd::Auto,
        #[inline(always)]
        || exp_sum_inline(log_w, max, w),
    )
}

/// [`exp_sum`]'s body, inlined into the AVX2 copy (a closure this size was not).
#[inline(always)]
fn exp_sum_inline(log_w: &[f64], max: f64, w: Option<&mut [f64]>) -> f64 {
    let mut sum = 0.0;
    match w {
        Some(w) => {
            for (wc, lc) in w.chunks_mut(BLOCK).zip(log_w.chunks(BLOCK)) {
                for (wi, &y) in wc.iter_mut().zip(&exp_block(lc, max)) {
                    *wi = y;
                    sum += y;
                }
            }
        }
        None => {
            for lc in log_w.chunks(BLOCK) {
                for &y in &exp_block(lc, max)[..lc.len()] {
                    sum += y;
                }
            }
        }
    }
    sum
}

/// `log Σ_i exp(l_i)`, stable for any finite maximum; `−∞` when every term is `−∞` or the
/// slice is empty. A NaN anywhere gives NaN (callers validate first).
pub fn log_sum_exp(log_w: &[f64]) -> f64 {
    let mut max = f64::NEG_INFINITY;
    for &l in log_w {
        if l.is_nan() {
            return f64::NAN;
        }
        max = max.max(l);
    }
    if !max.is_finite() {
        return max;
    }
    max + exp_sum(log_w, max, None).ln()
}

/// Normalise log-weights in place so that `Σ exp(log_w) = 1`, and write the normalised
/// weights into `w`. Returns `log Σ exp(log_w)` of the input, the log normalising constant.
///
/// A weight below `e^{−708}` times the largest is 0 in `w` (its log-weight stays exact):
/// nothing a sum or a resampler does could see it.
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
    let sum = exp_sum(log_w, max, Some(w));
    let inv = 1.0 / sum;
    let log_norm = max + sum.ln();
    for (wi, l) in w.iter_mut().zip(log_w.iter_mut()) {
        *wi *= inv;
        *l -= log_norm;
    }
    Ok(log_norm)
}

/// Interleaved partial results of [`normalise_into`]'s maximum and sum.
const LANES: usize = 8;

/// The normalised weights of `log_w` into `w`, leaving `log_w` as it is; returns
/// `log Σ exp(log_w)`. The same weights as [`normalise`] to a few ulp, for the inner loops of
/// the papers' filters (a quadrature's nodes, a backward kernel's row): the maximum and the
/// sum run over eight interleaved partial results (the sum's lanes added in order at the
/// end), `exp` over blocks of lanes, compiled for AVX2 where the CPU has it, so that the
/// loops vectorise instead of waiting on one running value.
///
/// # Errors
/// As [`normalise`]: [`CoreError::NonFiniteWeight`] for the first NaN or `+∞` log-weight,
/// [`CoreError::AllWeightsZero`] when every weight is zero or there is none.
pub fn normalise_into(t: usize, log_w: &[f64], w: &mut [f64]) -> Result<f64> {
    debug_assert_eq!(log_w.len(), w.len());
    let (max, bad) = dispatch(
        Simd::Auto,
        #[inline(always)]
        || max_and_flag_lanes::<LANES>(log_w),
    );
    if bad {
        let (index, &value) = log_w
            .iter()
            .enumerate()
            .find(|(_, l)| l.is_nan() || **l == f64::INFINITY)
            .expect("a lane saw a NaN or +∞");
        return Err(CoreError::NonFiniteWeight { t, index, value });
    }
    if max == f64::NEG_INFINITY {
        return Err(CoreError::AllWeightsZero { t });
    }
    let sum = dispatch(
        Simd::Auto,
        #[inline(always)]
        || exp_lanes_sum(log_w, max, w),
    );
    let inv = 1.0 / sum;
    for wi in w.iter_mut() {
        *wi *= inv;
    }
    Ok(max + sum.ln())
}

/// `w_i ← e^{l_i − max}` for every `i` (all `l_i ≤ max`), returning `Σ_i w_i` summed over
/// [`LANES`] interleaved partial sums, added in lane order at the end.
#[inline(always)]
fn exp_lanes_sum(l: &[f64], max: f64, w: &mut [f64]) -> f64 {
    let mut acc = [0.0f64; LANES];
    let mut lb = l.chunks_exact(LANES);
    let mut wb = w.chunks_exact_mut(LANES);
    // `exp` a block of lanes at a time, each step over every lane before the next (one
    // lane at a time, its table look-up kept the loop scalar); the same bits per value.
    for (lc, wc) in (&mut lb).zip(&mut wb) {
        let e = exp_nonpositive_lanes::<LANES>(std::array::from_fn(|i| lc[i] - max));
        wc.copy_from_slice(&e);
        for (a, y) in acc.iter_mut().zip(e) {
            *a += y;
        }
    }
    let (lr, wr) = (lb.remainder(), wb.into_remainder());
    let mut x = [f64::NEG_INFINITY; LANES];
    for (xi, &li) in x.iter_mut().zip(lr) {
        *xi = li - max;
    }
    let e = exp_nonpositive_lanes(x);
    for (i, wi) in wr.iter_mut().enumerate() {
        *wi = e[i];
        acc[i] += e[i];
    }
    acc.iter().sum()
}

/// Effective sample size `1 / Σ W_i²` of normalised weights (Kong, Liu & Wong 1994).
pub fn ess(w: &[f64]) -> f64 {
    1.0 / w.iter().map(|x| x * x).sum::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`normalise_into`] gives [`normalise`]'s weights and constant to a few ulp at every
    /// remainder of the lane count, leaves `log_w` alone, and fails where it fails.
    #[test]
    fn normalise_into_is_normalise_over_lanes() {
        for n in [1usize, 7, 8, 9, 100, 1000] {
            let l: Vec<f64> = (0..n)
                .map(|j| {
                    let e = j as f64 * 0.05 - 2.0;
                    if j % 6 == 1 { -1e3 } else { -0.5 * e * e }
                })
                .collect();
            let mut w = vec![0.0; n];
            let c = normalise_into(3, &l, &mut w).unwrap();
            let (mut lr, mut wr) = (l.clone(), vec![0.0; n]);
            let cr = normalise(3, &mut lr, &mut wr).unwrap();
            assert!(
                (c - cr).abs() <= 4.0 * f64::EPSILON * cr.abs().max(1.0),
                "n = {n}"
            );
            for (a, b) in w.iter().zip(&wr) {
                assert!(
                    (a - b).abs() <= 4.0 * f64::EPSILON * b,
                    "n = {n}: {a} against {b}"
                );
            }
        }
        let mut w = [0.0; 10];
        for bad in [f64::NAN, f64::INFINITY] {
            let mut l = [0.0; 10];
            l[9] = bad;
            l[4] = bad;
            match normalise_into(2, &l, &mut w) {
                Err(CoreError::NonFiniteWeight { t: 2, index: 4, .. }) => {}
                other => panic!("{other:?}"),
            }
        }
        for l in [&[f64::NEG_INFINITY; 10][..], &[]] {
            assert!(matches!(
                normalise_into(5, l, &mut w[..l.len()]),
                Err(CoreError::AllWeightsZero { t: 5 })
            ));
        }
    }

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

    /// The weights agree with the platform's `exp` to a few ulp, at any length (not only
    /// whole blocks of lanes), down to `e^{−708}` times the largest (and are 0 or that small
    /// below).
    #[test]
    fn normalised_weights_match_the_platform_exp() {
        for n in [1usize, 63, 64, 65, 1000] {
            let l0: Vec<f64> = (0..n)
                .map(|i| ((i * 7919) % 1000) as f64 * -0.709)
                .collect();
            let (mut l, mut w) = (l0.clone(), vec![0.0; n]);
            let c = normalise(0, &mut l, &mut w).unwrap();
            let max = l0.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let terms: Vec<f64> = l0.iter().map(|&x| (x - max).exp()).collect();
            let sum: f64 = terms.iter().sum();
            assert!((c - (max + sum.ln())).abs() <= 4.0 * f64::EPSILON * c.abs().max(1.0));
            assert!((log_sum_exp(&l0) - c).abs() <= 4.0 * f64::EPSILON * c.abs().max(1.0));
            for (i, (&wi, &t)) in w.iter().zip(&terms).enumerate() {
                let want = t / sum;
                // Below e^{−708} times the largest weight the kernel gives 0 (its docs).
                let tol = if l0[i] - max < -708.0 {
                    want
                } else {
                    4.0 * f64::EPSILON * want
                };
                assert!(
                    (wi - want).abs() <= tol,
                    "n = {n}, i = {i}: {wi} against {want}"
                );
            }
        }
        assert!(log_sum_exp(&[0.0, f64::NAN]).is_nan());
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
