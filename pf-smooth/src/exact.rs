//! Exact references for the noisy AR(1) model, from pf-core's Kalman filter and RTS
//! smoother: the statistics `τ_{n,1…4}`, the EM recursion, the log-likelihood and its
//! gradient.
//!
//! With smoothed means `m_k`, variances `P_k` and lag-one covariances `C_k = Cov(X_k, X_{k+1})`:
//! ```text
//! τ₁ = Σ_{k<n} (m_k² + P_k),  τ₂ = Σ_{k<n} (m_k m_{k+1} + C_k),
//! τ₃ = Σ_{k≥1} (m_k² + P_k),  τ₄ = Σ_{k≤n} ((Y_k − m_k)² + P_k).
//! ```
//! The diffuse prior is the Gaussian prior `N(Y_0, ρ²)` with `y_0` treated as missing: the
//! flat-prior likelihood `∫ g_0(x_0) Π q g dx` equals `p(y_{1:n} | X_0 ~ N(Y_0, ρ²))`.

use crate::ar1::{Ar1Data, SuffStats, Theta};
use crate::error::{Result, SmoothError};
use nalgebra::DVector;
use pf_core::kalman::{KalmanOutput, LinearGaussian, SmootherOutput, kalman_filter, rts_smoother};
use std::ops::RangeInclusive;

fn filter(data: &Ar1Data, theta: &Theta) -> Result<(LinearGaussian, KalmanOutput)> {
    theta.validate()?;
    let y = data.y();
    let model = LinearGaussian::scalar(theta.phi, 1.0, theta.sigma2, theta.rho2, y[0], theta.rho2)?;
    let ys: Vec<Option<DVector<f64>>> = data
        .filter_input()
        .into_iter()
        .map(|v| v.map(|v| DVector::from_element(1, v)))
        .collect();
    let kf = kalman_filter(&model, &ys, None)?;
    Ok((model, kf))
}

/// The exact `τ_{n,1…4}` at `θ`.
///
/// # Errors
/// An invalid `θ` or a Kalman/RTS failure.
pub fn exact_statistics(data: &Ar1Data, theta: &Theta) -> Result<SuffStats> {
    let (model, kf) = filter(data, theta)?;
    let sm = rts_smoother(&model, &kf)?;
    let mut tau = [0.0; 4];
    add_terms(&mut tau, data.y(), &sm, 0, 0..=data.n());
    Ok(SuffStats { n: data.n(), tau })
}

/// Add to `tau` the terms of steps `js` (`s_{j−1}(X_{j−1}, X_j)`: `X_{j−1}²`, `X_{j−1}X_j`,
/// `X_j²`, `(Y_j − X_j)²`, and `(Y_0 − X_0)²` alone for `j = 0`) under the smoothed moments
/// `sm`, whose entry 0 is step `lo`.
fn add_terms(
    tau: &mut [f64; 4],
    y: &[f64],
    sm: &SmootherOutput,
    lo: usize,
    js: RangeInclusive<usize>,
) {
    let m = |k: usize| sm.means[k - lo][0];
    let var = |k: usize| sm.covs[k - lo][(0, 0)];
    for j in js {
        if j >= 1 {
            tau[0] += m(j - 1) * m(j - 1) + var(j - 1);
            tau[1] += m(j - 1) * m(j) + sm.cross_covs[j - 1 - lo][(0, 0)];
            tau[2] += m(j) * m(j) + var(j);
        }
        let e = y[j] - m(j);
        tau[3] += e * e + var(j);
    }
}

/// The limit of the fixed-lag estimator `τ̂_n^{δ,N}` (eqs. (8)–(9)) as `N → ∞`: the term of
/// step `j` (`s_{j−1}(X_{j−1}, X_j)`, and `(Y_0 − X_0)²` for `j = 0`) under the smoothing
/// distribution given `Y_{0:t}` with `t = min(j + δ − 1, n)`, the step at which the
/// estimator freezes it; `τ_n` ([`exact_statistics`]) takes every term given `Y_{0:n}`. The
/// difference between the two is the fixed-lag approximation's own bias, which no number of
/// particles removes. Exact: one Kalman filter pass, then for each freezing step `t` the RTS
/// smoother over the window of steps its terms need, `O(n·min(δ, n))` smoother steps.
///
/// # Errors
/// `δ = 0`, an invalid `θ` or a Kalman/RTS failure.
pub fn exact_fixed_lag_statistics(
    data: &Ar1Data,
    theta: &Theta,
    delta: usize,
) -> Result<SuffStats> {
    pf_core::params::at_least_one("lag", delta)?;
    let (model, kf) = filter(data, theta)?;
    let (y, n) = (data.y(), data.n());
    let mut tau = [0.0; 4];
    let mut freeze = |t: usize, js: RangeInclusive<usize>| -> Result<()> {
        let lo = js.start().saturating_sub(1);
        let sm = rts_smoother(&model, &kf.steps(lo, t)?)?;
        add_terms(&mut tau, y, &sm, lo, js);
        Ok(())
    };
    // Terms j ≤ n − δ are frozen at t = j + δ − 1 < n, one each; the rest at t = n.
    let first_at_n = (n + 1).saturating_sub(delta);
    for j in 0..first_at_n {
        freeze(j + delta - 1, j..=j)?;
    }
    freeze(n, first_at_n..=n)?;
    Ok(SuffStats { n, tau })
}

/// `ℓ_n(θ)`, the exact log-likelihood under the diffuse prior.
///
/// # Errors
/// An invalid `θ` or a Kalman failure.
pub fn exact_log_likelihood(data: &Ar1Data, theta: &Theta) -> Result<f64> {
    Ok(filter(data, theta)?.1.log_likelihood)
}

/// The exact score `∇ℓ_n(θ)` w.r.t. `(φ, σ², ρ²)`: Fisher's identity with the exact
/// statistics.
///
/// # Errors
/// As [`exact_statistics`].
pub fn exact_score(data: &Ar1Data, theta: &Theta) -> Result<Theta> {
    Ok(exact_statistics(data, theta)?.score(theta))
}

/// One exact EM update (10)–(12) from `θ`.
///
/// # Errors
/// As [`exact_statistics`], or a degenerate update.
pub fn exact_em_step(data: &Ar1Data, theta: &Theta) -> Result<Theta> {
    exact_statistics(data, theta)?.m_step()
}

/// The exact EM trajectory `θ_0, θ_1, …, θ_I` (I + 1 points, starting point first).
///
/// # Errors
/// [`SmoothError::Iteration`] naming the iteration that failed.
pub fn exact_em(data: &Ar1Data, theta0: &Theta, iterations: usize) -> Result<Vec<Theta>> {
    theta0.validate()?;
    pf_core::limits::check_count("iterations", iterations)?;
    let mut path = pf_core::limits::try_with_capacity("the EM path", iterations + 1)?;
    path.push(*theta0);
    for it in 1..=iterations {
        let next = exact_em_step(data, &path[it - 1]).map_err(|e| SmoothError::Iteration {
            chain: 0,
            iteration: it,
            source: Box::new(e),
        })?;
        path.push(next);
    }
    Ok(path)
}
