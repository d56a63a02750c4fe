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
use pf_core::kalman::{KalmanOutput, LinearGaussian, kalman_filter, rts_smoother};

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
    let y = data.y();
    let n = data.n();
    let m = |k: usize| sm.means[k][0];
    let second = |k: usize| m(k) * m(k) + sm.covs[k][(0, 0)];
    let mut tau = [0.0; 4];
    for k in 0..n {
        tau[0] += second(k);
        tau[1] += m(k) * m(k + 1) + sm.cross_covs[k][(0, 0)];
    }
    for k in 1..=n {
        tau[2] += second(k);
    }
    for (k, yk) in y.iter().enumerate() {
        let e = yk - m(k);
        tau[3] += e * e + sm.covs[k][(0, 0)];
    }
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
