//! What the estimators share: the weighted estimate `Σ_i W_i v_i` of per-particle sums
//! (eq. (6)) and its checks.

use crate::error::{Result, SmoothError};

/// `dst ← src`, reusing `dst`'s allocations.
pub(crate) fn copy_states<S: Clone>(dst: &mut Vec<S>, src: &[S]) {
    if dst.len() == src.len() {
        dst.clone_from_slice(src);
    } else {
        dst.clear();
        dst.extend_from_slice(src);
    }
}

/// `out ← Σ_i W_i v_i` for the per-particle sums `v` (N×d, particle-major) of an estimator
/// named `names.0` whose estimate is `names.1`, last at step `t`: the estimate of eq. (6),
/// and of forward-only smoothing.
pub(crate) fn weighted_estimate(
    names: (&'static str, &'static str),
    t: Option<usize>,
    (w, v, d): (&[f64], &[f64], usize),
    out: &mut [f64],
) -> Result<()> {
    let t = t.ok_or(SmoothError::NoSteps { what: names.0 })?;
    check_len(out.len(), d)?;
    weighted_sum(w, v, d, out);
    check_finite(names.1, t, out)
}

/// `out ← Σ_i w_i v_i` for particle-major `v` (N×d).
pub(crate) fn weighted_sum(w: &[f64], v: &[f64], d: usize, out: &mut [f64]) {
    out.fill(0.0);
    for (wi, vi) in w.iter().zip(v.chunks_exact(d)) {
        for (o, x) in out.iter_mut().zip(vi) {
            *o += wi * x;
        }
    }
}

pub(crate) fn check_len(got: usize, d: usize) -> Result<()> {
    if got == d {
        Ok(())
    } else {
        Err(pf_core::CoreError::DimensionMismatch {
            what: "estimate buffer (dimension of the statistic)",
            expected: d,
            got,
        }
        .into())
    }
}

pub(crate) fn check_finite(what: &'static str, t: usize, out: &[f64]) -> Result<()> {
    match out.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(component) => Err(SmoothError::NonFiniteEstimate { what, t, component }),
    }
}
