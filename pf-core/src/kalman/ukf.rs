//! The unscented Kalman filter for additive-noise models `x' = f(x) + w`, `y = h(x) + v`
//! (Julier & Uhlmann 1997/2004; scaled sigma points as in Wan & van der Merwe 2000).
//!
//! With `n` the state dimension, `λ = α²(n + κ) − n` and `γ = √(n + λ)`, the `2n + 1` sigma
//! points of `N(m, P = L Lᵀ)` are `m`, `m ± γ L_{:,i}`, with weights
//! `W₀ᵐ = λ/(n + λ)`, `W₀ᶜ = W₀ᵐ + 1 − α² + β`, `Wᵢᵐ = Wᵢᶜ = 1/(2(n + λ))`.
//! The transformed points give the predicted moments; in the update, the cross-covariance
//! `P_xz` and innovation covariance `S` give the gain `K = P_xz S⁻¹`, and
//! `P ← P − K S Kᵀ = P − WᵀW` with `W = L_S⁻¹ P_xzᵀ`, so no inverse is formed.
//!
//! Residuals go through a user function so that bearings can be wrapped: the predicted
//! measurement is formed as `ẑ = z₀ + Σ Wᵢᵐ r(zᵢ, z₀)`, which equals `Σ Wᵢᵐ zᵢ` for the
//! plain difference but stays correct when the `zᵢ` straddle the ±π cut.

use nalgebra::{DMatrix, DVector};

use super::KalmanState;
use crate::error::{CoreError, Result};
use crate::gaussian::{cholesky_into, log_normal_chol_in_place, symmetrise};
use crate::params::ParamError;

/// Sigma-point scaling `(α, β, κ)`.
///
/// The default `α = 1, β = 2, κ = 0` gives `λ = 0`: every weight is non-negative
/// (`W₀ᵐ = 0`, `W₀ᶜ = 2`, `Wᵢ = 1/2n`), so the predicted and posterior covariances are
/// positive semi-definite by construction, and the points sit at `±√n` standard deviations.
/// The often-quoted `α = 10⁻³` makes `W₀ᵐ ≈ −10⁶`, and the covariance then comes out of a
/// cancellation between O(10⁶) terms: on a linear model that loses about six digits, and on
/// a nonlinear one it can produce an indefinite `P`. β = 2 is optimal for Gaussian priors
/// (it matches the fourth moment along each axis).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UkfParams {
    /// α > 0: spread of the sigma points.
    pub alpha: f64,
    /// β: prior-distribution correction of the central covariance weight (2 for Gaussians).
    pub beta: f64,
    /// κ: secondary scaling; `n + κ` must be positive.
    pub kappa: f64,
}

impl Default for UkfParams {
    fn default() -> Self {
        Self {
            alpha: 1.0,
            beta: 2.0,
            kappa: 0.0,
        }
    }
}

/// The plain residual `a − b`, for measurements without angles.
pub fn plain_residual(a: &DVector<f64>, b: &DVector<f64>) -> DVector<f64> {
    a - b
}

/// An unscented Kalman filter: sigma-point weights (computed once per state dimension) and
/// the buffers its steps reuse. The belief itself is a [`KalmanState`] owned by the caller.
#[derive(Debug, Clone)]
pub struct Ukf {
    params: UkfParams,
    /// State dimension the weights were computed for (0: none yet).
    n: usize,
    /// γ = √(n + λ).
    gamma: f64,
    /// Wᵐ, Wᶜ (2n + 1 each).
    wm: Vec<f64>,
    wc: Vec<f64>,
    /// Cholesky factor of P; sigma points; transformed points; their residuals.
    l: DMatrix<f64>,
    chi: Vec<DVector<f64>>,
    fx: Vec<DVector<f64>>,
    dz: Vec<DVector<f64>>,
    /// Buffers: state deviation, S and its factor, P_xz, W.
    dx: DVector<f64>,
    s: DMatrix<f64>,
    ls: DMatrix<f64>,
    pxz: DMatrix<f64>,
    w: DMatrix<f64>,
}

fn check_matrix(what: &'static str, m: &DMatrix<f64>, n: usize) -> Result<()> {
    if m.shape() != (n, n) {
        return Err(CoreError::DimensionMismatch {
            what,
            expected: n,
            got: if m.nrows() != n { m.nrows() } else { m.ncols() },
        });
    }
    if let Some((index, &value)) = m.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        // nalgebra iterates column-major; report the row-major index like `cholesky`.
        return Err(CoreError::NonFiniteData {
            what,
            index: (index % n) * n + index / n,
            value,
        });
    }
    Ok(())
}

fn check_vector(what: &'static str, v: &DVector<f64>, n: usize, at: usize) -> Result<()> {
    if v.len() != n {
        return Err(CoreError::DimensionMismatch {
            what,
            expected: n,
            got: v.len(),
        });
    }
    if let Some(&value) = v.iter().find(|v| !v.is_finite()) {
        return Err(CoreError::NonFiniteData {
            what,
            index: at,
            value,
        });
    }
    Ok(())
}

impl Ukf {
    /// A UKF with the given scaling. Errors if α ≤ 0 or a parameter is not finite.
    pub fn new(params: UkfParams) -> Result<Self> {
        let UkfParams { alpha, beta, kappa } = params;
        crate::params::positive("alpha", alpha)?;
        crate::params::finite("beta", beta)?;
        crate::params::finite("kappa", kappa)?;
        Ok(Self {
            params,
            n: 0,
            gamma: 0.0,
            wm: Vec::new(),
            wc: Vec::new(),
            l: DMatrix::zeros(0, 0),
            chi: Vec::new(),
            fx: Vec::new(),
            dz: Vec::new(),
            dx: DVector::zeros(0),
            s: DMatrix::zeros(0, 0),
            ls: DMatrix::zeros(0, 0),
            pxz: DMatrix::zeros(0, 0),
            w: DMatrix::zeros(0, 0),
        })
    }

    /// The scaling parameters.
    pub fn params(&self) -> UkfParams {
        self.params
    }

    /// Mean weights `Wᵐ` (empty until the first step fixes the dimension).
    pub fn mean_weights(&self) -> &[f64] {
        &self.wm
    }

    /// Covariance weights `Wᶜ` (empty until the first step fixes the dimension).
    pub fn cov_weights(&self) -> &[f64] {
        &self.wc
    }

    /// Compute the weights for dimension `n`, unless already done.
    fn ensure_weights(&mut self, n: usize) -> Result<()> {
        if n == self.n {
            return Ok(());
        }
        if n == 0 {
            return Err(CoreError::Empty { what: "UKF state" });
        }
        let UkfParams { alpha, beta, kappa } = self.params;
        let nf = n as f64;
        let n_lambda = alpha * alpha * (nf + kappa);
        // α, κ finite (checked in `new`), so n_lambda is finite.
        if n_lambda <= 0.0 {
            return Err(CoreError::Param(ParamError {
                name: "kappa",
                value: kappa,
                reason: "n + κ must be positive (n is the state dimension)",
            }));
        }
        let lambda = n_lambda - nf;
        let wi = 0.5 / n_lambda;
        self.wm = vec![wi; 2 * n + 1];
        self.wc = vec![wi; 2 * n + 1];
        self.wm[0] = lambda / n_lambda;
        self.wc[0] = self.wm[0] + 1.0 - alpha * alpha + beta;
        self.gamma = n_lambda.sqrt();
        self.l = DMatrix::zeros(n, n);
        self.chi = vec![DVector::zeros(n); 2 * n + 1];
        self.dx = DVector::zeros(n);
        self.n = n;
        Ok(())
    }

    /// Sigma points of `state` into `self.chi`.
    fn sigma_points(&mut self, state: &KalmanState) -> Result<()> {
        let n = state.m.len();
        check_vector("UKF mean", &state.m, n, 0)?;
        check_matrix("UKF covariance P", &state.p, n)?;
        self.ensure_weights(n)?;
        cholesky_into("UKF covariance P", &state.p, &mut self.l)?;
        self.chi[0].copy_from(&state.m);
        for i in 0..n {
            let (lo, hi) = self.chi.split_at_mut(n + 1);
            let plus = &mut lo[1 + i];
            plus.copy_from(&state.m);
            plus.axpy(self.gamma, &self.l.column(i), 1.0);
            let minus = &mut hi[i];
            minus.copy_from(&state.m);
            minus.axpy(-self.gamma, &self.l.column(i), 1.0);
        }
        Ok(())
    }

    /// Time update through `x' = f(x) + w`, `w ~ N(0, q)`: the unscented transform of
    /// `N(m, P)` by `f`, plus `q`. `q` may be singular (it is only added).
    pub fn predict(
        &mut self,
        state: &mut KalmanState,
        f: impl Fn(&DVector<f64>) -> DVector<f64>,
        q: &DMatrix<f64>,
    ) -> Result<()> {
        let n = state.m.len();
        check_matrix("UKF process noise Q", q, n)?;
        self.sigma_points(state)?;
        self.fx.clear();
        for (i, chi) in self.chi.iter().enumerate() {
            let fx = f(chi);
            check_vector("UKF propagated sigma point f(χ)", &fx, n, i)?;
            self.fx.push(fx);
        }
        state.m.fill(0.0);
        for (fx, &w) in self.fx.iter().zip(&self.wm) {
            state.m.axpy(w, fx, 1.0);
        }
        state.p.copy_from(q);
        for (fx, &w) in self.fx.iter().zip(&self.wc) {
            self.dx.copy_from(fx);
            self.dx -= &state.m;
            state.p.ger(w, &self.dx, &self.dx, 1.0);
        }
        symmetrise(&mut state.p);
        Ok(())
    }

    /// Measurement update with `y = h(x) + v`, `v ~ N(0, r)`; `residual(a, b)` forms `a − b`
    /// in measurement space (wrap angles there; use [`plain_residual`] otherwise).
    /// Returns the log-likelihood increment `log N(residual(y, ẑ); 0, S)`.
    ///
    /// Errors: shape or finiteness problems, a non-PD `P` or `S`. On error `state` is
    /// unchanged.
    pub fn update(
        &mut self,
        state: &mut KalmanState,
        h: impl Fn(&DVector<f64>) -> DVector<f64>,
        r: &DMatrix<f64>,
        y: &DVector<f64>,
        residual: impl Fn(&DVector<f64>, &DVector<f64>) -> DVector<f64>,
    ) -> Result<f64> {
        let n = state.m.len();
        let m = y.len();
        if m == 0 {
            return Err(CoreError::Empty {
                what: "UKF observation",
            });
        }
        check_vector("UKF observation", y, m, 0)?;
        check_matrix("UKF observation noise R", r, m)?;
        self.sigma_points(state)?;
        self.fx.clear();
        for (i, chi) in self.chi.iter().enumerate() {
            let z = h(chi);
            check_vector("UKF observed sigma point h(χ)", &z, m, i)?;
            self.fx.push(z);
        }
        // ẑ = z₀ + Σ Wᵢᵐ r(zᵢ, z₀)
        let mut z_hat = self.fx[0].clone();
        for (i, (z, &w)) in self.fx.iter().zip(&self.wm).enumerate().skip(1) {
            let d = residual(z, &self.fx[0]);
            check_vector("UKF residual r(zᵢ, z₀)", &d, m, i)?;
            z_hat.axpy(w, &d, 1.0);
        }
        self.dz.clear();
        for (i, z) in self.fx.iter().enumerate() {
            let d = residual(z, &z_hat);
            check_vector("UKF residual r(zᵢ, ẑ)", &d, m, i)?;
            self.dz.push(d);
        }
        let mut e = residual(y, &z_hat);
        check_vector("UKF innovation r(y, ẑ)", &e, m, 0)?;
        if self.s.shape() != (m, m) {
            self.s = DMatrix::zeros(m, m);
            self.ls = DMatrix::zeros(m, m);
        }
        if self.pxz.shape() != (n, m) {
            self.pxz = DMatrix::zeros(n, m);
            self.w = DMatrix::zeros(m, n);
        }
        // S = R + Σ Wᶜ dz dzᵀ,  P_xz = Σ Wᶜ (χ − m) dzᵀ
        self.s.copy_from(r);
        self.pxz.fill(0.0);
        for ((chi, dz), &w) in self.chi.iter().zip(&self.dz).zip(&self.wc) {
            self.s.ger(w, dz, dz, 1.0);
            self.dx.copy_from(chi);
            self.dx -= &state.m;
            self.pxz.ger(w, &self.dx, dz, 1.0);
        }
        symmetrise(&mut self.s);
        cholesky_into("UKF innovation covariance S", &self.s, &mut self.ls)?;
        // W = L_S⁻¹ P_xzᵀ; e ← L_S⁻¹ e inside the log-density.
        self.w.tr_copy_from(&self.pxz);
        self.ls.solve_lower_triangular_unchecked_mut(&mut self.w);
        let ll = log_normal_chol_in_place(&self.ls, &mut e);
        // m ← m + P_xz S⁻¹ e = m + Wᵀ (L_S⁻¹ e);  P ← P − Wᵀ W.
        state.m.gemv_tr(1.0, &self.w, &e, 1.0);
        state.p.gemm_tr(-1.0, &self.w, &self.w, 1.0);
        symmetrise(&mut state.p);
        Ok(ll)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kalman::kf::tests::{model_2d, observations};
    use std::f64::consts::PI;

    #[test]
    fn linear_model_reproduces_kalman_filter() {
        let model = model_2d();
        let ys = observations(&model, 6, &[2], 9);
        let (a, c) = (model.a().clone(), model.c().clone());
        for params in [
            UkfParams::default(),
            UkfParams {
                alpha: 0.5,
                beta: 2.0,
                kappa: 1.0,
            },
        ] {
            let mut ukf = Ukf::new(params).unwrap();
            let mut kf = KalmanState::prior(&model);
            let mut us = KalmanState::prior(&model);
            for (t, y) in ys.iter().enumerate() {
                if t > 0 {
                    kf.predict(&model, None).unwrap();
                    ukf.predict(&mut us, |x| &a * x, model.q()).unwrap();
                }
                if let Some(y) = y {
                    let l1 = kf.update(&model, y).unwrap();
                    let l2 = ukf
                        .update(&mut us, |x| &c * x, model.r(), y, plain_residual)
                        .unwrap();
                    // The unscented transform is exact for linear maps; the two differ by
                    // round-off only: sums of 2n + 1 = 5 terms of size ≤ γ²‖P‖ ≈ 4 with
                    // weights ≤ 1, over 7 steps, ≲ 100ε; 1e3·ε leaves a ×10 margin.
                    assert!((l1 - l2).abs() < 1e3 * f64::EPSILON * l1.abs().max(1.0));
                }
                assert!((&kf.m - &us.m).amax() < 1e3 * f64::EPSILON, "t = {t}");
                assert!((&kf.p - &us.p).amax() < 1e3 * f64::EPSILON, "t = {t}");
            }
        }
    }

    #[test]
    fn polar_to_cartesian_mean_is_second_order_accurate() {
        // (r, θ) ~ N((r̄, θ̄), diag(σr², s²)) mapped to (r cos θ, r sin θ). Exactly,
        // E[x] = r̄ e^{−s²/2} (cos θ̄, sin θ̄). With α = 1, κ = 0 (λ = 0, γ = √2, W₀ᵐ = 0,
        // Wᵢ = ¼) the unscented mean is r̄ (1 + cos √2 s)/2 (cos θ̄, sin θ̄), whose factor
        // differs from e^{−s²/2} by s⁴/24 + O(s⁶) (Taylor); linearisation errs by r̄ s²/2.
        let (rbar, theta, sr, s) = (10.0_f64, 0.7_f64, 0.2_f64, 0.1_f64);
        let mut st = KalmanState::new(
            DVector::from_vec(vec![rbar, theta]),
            DMatrix::from_diagonal(&DVector::from_vec(vec![sr * sr, s * s])),
        );
        let mut ukf = Ukf::new(UkfParams::default()).unwrap();
        ukf.predict(
            &mut st,
            |x| DVector::from_vec(vec![x[0] * x[1].cos(), x[0] * x[1].sin()]),
            &DMatrix::zeros(2, 2),
        )
        .unwrap();
        let ut = rbar * (1.0 + (2.0_f64.sqrt() * s).cos()) / 2.0;
        let exact = rbar * (-s * s / 2.0).exp();
        let (sn, cs) = theta.sin_cos();
        // The UKF's own formula: exact algebra on O(10) numbers, a few ε·10.
        assert!((st.m[0] - ut * cs).abs() < 64.0 * f64::EPSILON * rbar);
        assert!((st.m[1] - ut * sn).abs() < 64.0 * f64::EPSILON * rbar);
        // Against the true mean: within r̄·s⁴/24 times 1.1 (the O(s⁶) remainder is
        // ≈ 0.37 s² ≈ 0.4% of the leading term at s = 0.1), and far from linearisation.
        let bound = 1.1 * rbar * s.powi(4) / 24.0;
        assert!((st.m[0] - exact * cs).abs() < bound);
        assert!((st.m[1] - exact * sn).abs() < bound);
        assert!(bound < 0.01 * rbar * s * s / 2.0);
        // Trace of the covariance: exactly E‖X − EX‖² = r̄² + σr² − r̄² e^{−s²}. The UT agrees
        // to second order; its O(s⁴) remainder is ≈ 0.6 r̄² s⁴ here (mostly the β-weighted
        // centre term 2·(r̄ s²/2)²), so r̄² s⁴ bounds it. A sanity check of P, not a sharp one.
        let tr_exact = rbar * rbar + sr * sr - rbar * rbar * (-s * s).exp();
        assert!((st.p.trace() - tr_exact).abs() < rbar * rbar * s.powi(4));
    }

    fn wrap(a: f64) -> f64 {
        let w = (a + PI).rem_euclid(2.0 * PI) - PI;
        if w == -PI { PI } else { w }
    }

    fn range_bearing(x: &DVector<f64>) -> DVector<f64> {
        DVector::from_vec(vec![x[0].hypot(x[1]), x[1].atan2(x[0])])
    }

    fn wrapped(a: &DVector<f64>, b: &DVector<f64>) -> DVector<f64> {
        DVector::from_vec(vec![a[0] - b[0], wrap(a[1] - b[1])])
    }

    #[test]
    fn bearing_residual_wrapping_is_rotation_invariant() {
        // A target at (−10, 0) sits on the ±π bearing cut: its sigma points' bearings
        // straddle it. Rotating the whole problem by π (target at (10, 0), bearing 0, no cut)
        // must give the rotated posterior, to round-off, if and only if residuals wrap.
        let p = DMatrix::from_row_slice(2, 2, &[1.0, 0.3, 0.3, 2.0]);
        let r = DMatrix::from_diagonal(&DVector::from_vec(vec![0.1, 0.01]));
        let run = |m: [f64; 2], y: [f64; 2], wrap_it: bool| {
            let mut ukf = Ukf::new(UkfParams::default()).unwrap();
            let mut st = KalmanState::new(DVector::from_row_slice(&m), p.clone());
            let y = DVector::from_row_slice(&y);
            let ll = if wrap_it {
                ukf.update(&mut st, range_bearing, &r, &y, wrapped)
            } else {
                ukf.update(&mut st, range_bearing, &r, &y, plain_residual)
            }
            .unwrap();
            (st, ll)
        };
        let (east, ll_e) = run([10.0, 0.0], [10.2, 0.05], true);
        let (west, ll_w) = run([-10.0, 0.0], [10.2, wrap(0.05 + PI)], true);
        // Rotation by π negates means and preserves P (R_π P R_πᵀ = P). atan2 and the
        // wrap are accurate to a few ε·π; errors propagate through O(10)-sized gains.
        let tol = 1e3 * f64::EPSILON * 10.0;
        assert!((&east.m + &west.m).amax() < tol, "{} vs {}", east.m, west.m);
        assert!((&east.p - &west.p).amax() < tol);
        assert!((ll_e - ll_w).abs() < tol);
        // Without wrapping, the sigma bearings near ±π give ≈ 2π spreads: S is inflated, the
        // bearing is nearly ignored (cross-range variance ≈ 1.56 instead of ≈ 0.67) and the
        // log-likelihood drops by ≈ 3.5. Margins of ≈ 2× on both.
        let (bad, ll_bad) = run([-10.0, 0.0], [10.2, wrap(0.05 + PI)], false);
        assert!(bad.p[(1, 1)] - east.p[(1, 1)] > 0.5);
        assert!(ll_e - ll_bad > 1.5);
    }

    #[test]
    fn rejects_bad_parameters_and_shapes() {
        assert!(matches!(
            Ukf::new(UkfParams {
                alpha: 0.0,
                ..UkfParams::default()
            }),
            Err(CoreError::Param(ParamError { name: "alpha", .. }))
        ));
        let mut ukf = Ukf::new(UkfParams {
            kappa: -3.0,
            ..UkfParams::default()
        })
        .unwrap();
        let mut st = KalmanState::new(DVector::zeros(2), DMatrix::identity(2, 2));
        assert!(matches!(
            ukf.predict(&mut st, |x| x.clone(), &DMatrix::identity(2, 2)),
            Err(CoreError::Param(ParamError { name: "kappa", .. }))
        ));
        let mut ukf = Ukf::new(UkfParams::default()).unwrap();
        assert!(matches!(
            ukf.predict(&mut st, |x| x.clone(), &DMatrix::identity(3, 3)),
            Err(CoreError::DimensionMismatch { .. })
        ));
        assert!(matches!(
            ukf.predict(&mut st, |_| DVector::zeros(3), &DMatrix::identity(2, 2)),
            Err(CoreError::DimensionMismatch { .. })
        ));
        let mut bad = KalmanState::new(DVector::zeros(2), DMatrix::zeros(2, 2));
        assert!(matches!(
            ukf.predict(&mut bad, |x| x.clone(), &DMatrix::identity(2, 2)),
            Err(CoreError::NotPositiveDefinite { pivot: 0, .. })
        ));
        // The weights sum to one (mean) and the defaults are non-negative.
        let s: f64 = ukf.mean_weights().iter().sum();
        assert!((s - 1.0).abs() < 8.0 * f64::EPSILON);
        assert!(ukf.cov_weights().iter().all(|&w| w >= 0.0));
    }
}
