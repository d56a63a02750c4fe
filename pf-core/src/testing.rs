//! Exact references for tests: linear-Gaussian models and brute-force Gaussian posteriors.
//!
//! Compiled for pf-core's own tests and, in other crates, with the `testing` feature.
//! The brute-force functions never use a Kalman recursion: they write the joint Gaussian of
//! all states (or all observations) down as one dense matrix and factor it with faer, so
//! they are an independent check of [`kalman_filter`](crate::kalman::kalman_filter) and
//! [`rts_smoother`](crate::kalman::rts_smoother), at O((n·d)³) cost: keep n·d in the
//! hundreds.
//!
//! Inputs are not supported here: the brute-force functions take `u_t = 0` (for a model
//! with a B, that is the model driven by no input, as in `kalman_filter(…, None)`).

use faer::linalg::cholesky::llt::factor::LltError;
use faer::linalg::solvers::{DenseSolveCore, Solve};
use faer::{Mat, Side};
use nalgebra::{DMatrix, DVector};

use crate::error::{CoreError, Result};
use crate::gaussian::{LN_2PI, cholesky};
use crate::kalman::LinearGaussian;

/// The AR(1)-plus-noise model `X_{k+1} = φ X_k + σ U_k`, `Y_k = X_k + ρ V_k`
/// (U, V standard normal), started in its stationary law `X_0 ~ N(0, σ²/(1 − φ²))` so that
/// every `X_k` has the same marginal.
///
/// # Panics
/// If `|φ| ≥ 1` (no stationary law) or `σ`, `ρ` are not positive and finite: this is a test
/// helper, and a bad constant is a bug in the test.
pub fn ar1_noise(phi: f64, sigma: f64, rho: f64) -> LinearGaussian {
    assert!(
        phi.abs() < 1.0,
        "ar1_noise: |φ| = {} must be < 1",
        phi.abs()
    );
    assert!(
        sigma > 0.0 && rho > 0.0 && sigma.is_finite() && rho.is_finite(),
        "ar1_noise: σ = {sigma} and ρ = {rho} must be positive and finite"
    );
    let p0 = sigma * sigma / (1.0 - phi * phi);
    LinearGaussian::scalar(phi, 1.0, sigma * sigma, rho * rho, 0.0, p0)
        .unwrap_or_else(|e| panic!("ar1_noise(φ = {phi}, σ = {sigma}, ρ = {rho}): {e}"))
}

/// The exact joint posterior of `(X_0, …, X_n)` given the observations, stored densely.
#[derive(Debug, Clone, PartialEq)]
pub struct JointPosterior {
    d: usize,
    mean: DVector<f64>,
    cov: DMatrix<f64>,
}

impl JointPosterior {
    /// Number of time steps n + 1.
    pub fn len(&self) -> usize {
        self.mean.len() / self.d
    }

    /// Always false (a posterior has at least `X_0`).
    pub fn is_empty(&self) -> bool {
        self.mean.is_empty()
    }

    /// State dimension d.
    pub fn state_dim(&self) -> usize {
        self.d
    }

    /// `E[X_k | y]`.
    ///
    /// # Panics
    /// If `k > n`.
    pub fn mean(&self, k: usize) -> DVector<f64> {
        self.mean.rows(k * self.d, self.d).into_owned()
    }

    /// `Cov(X_k, X_j | y)`, the (k, j) block of the joint covariance.
    ///
    /// # Panics
    /// If `k > n` or `j > n`.
    pub fn cov(&self, k: usize, j: usize) -> DMatrix<f64> {
        self.cov
            .view((k * self.d, j * self.d), (self.d, self.d))
            .into_owned()
    }

    /// The full stacked mean, `(n + 1)·d` entries.
    pub fn full_mean(&self) -> &DVector<f64> {
        &self.mean
    }

    /// The full joint covariance.
    pub fn full_cov(&self) -> &DMatrix<f64> {
        &self.cov
    }
}

/// `M⁻¹` of a symmetric positive-definite `M`, from its Cholesky factor (test-only helper).
fn spd_inverse(what: &'static str, m: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    let l = cholesky(what, m)?;
    let mut inv = DMatrix::identity(m.nrows(), m.nrows());
    l.solve_lower_triangular_unchecked_mut(&mut inv);
    l.tr_solve_lower_triangular_unchecked_mut(&mut inv);
    Ok(inv)
}

fn to_faer(m: &DMatrix<f64>) -> Mat<f64> {
    Mat::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)])
}

fn faer_llt(what: &'static str, m: &Mat<f64>) -> Result<faer::linalg::solvers::Llt<f64>> {
    m.llt(Side::Lower).map_err(|e| match e {
        LltError::NonPositivePivot { index } => CoreError::NotPositiveDefinite {
            what,
            pivot: index,
            // faer does not report the pivot's value.
            value: f64::NAN,
        },
    })
}

fn check_ys(model: &LinearGaussian, ys: &[Option<DVector<f64>>]) -> Result<()> {
    if ys.is_empty() {
        return Err(CoreError::Empty {
            what: "observation sequence",
        });
    }
    ys.iter().flatten().try_for_each(|y| model.check_obs(y))
}

/// The exact posterior of the stacked `(X_0, …, X_n)` given `ys` (`None` = missing), by
/// brute force.
///
/// The joint log-density is `log N(x_0; m₀, P₀) + Σ_t log N(x_t; A x_{t−1}, Q) +
/// Σ_{observed t} log N(y_t; C x_t, R)`, a quadratic form in the stacked `x` with a
/// block-tridiagonal precision
/// `Λ_00 = P₀⁻¹ + AᵀQ⁻¹A`, `Λ_tt = Q⁻¹ + AᵀQ⁻¹A` (0 < t < n), `Λ_nn = Q⁻¹`,
/// `Λ_{t−1,t} = −AᵀQ⁻¹`, plus `CᵀR⁻¹C` on observed diagonal blocks, and linear term
/// `η_0 = P₀⁻¹m₀`, `η_t += CᵀR⁻¹y_t`. Then mean `= Λ⁻¹η` and covariance `= Λ⁻¹`, from one
/// dense faer LLᵀ of Λ. (For n = 0, `Λ_00 = P₀⁻¹` only.) Inputs are taken as zero.
pub fn joint_gaussian_posterior(
    model: &LinearGaussian,
    ys: &[Option<DVector<f64>>],
) -> Result<JointPosterior> {
    check_ys(model, ys)?;
    let n1 = ys.len();
    let d = model.state_dim();
    let big = n1 * d;
    let qi = spd_inverse("Q", model.q())?;
    let ri = spd_inverse("R", model.r())?;
    let p0i = spd_inverse("P0", model.p0())?;
    let a = model.a();
    let c = model.c();
    let atqia = a.transpose() * &qi * a;
    let atqi = a.transpose() * &qi;
    let ctric = c.transpose() * &ri * c;
    let ctri = c.transpose() * &ri;

    let mut lam = DMatrix::<f64>::zeros(big, big);
    let mut eta = DVector::<f64>::zeros(big);
    let add_block = |lam: &mut DMatrix<f64>, k: usize, j: usize, b: &DMatrix<f64>| {
        let mut v = lam.view_mut((k * d, j * d), (d, d));
        v += b;
    };
    add_block(&mut lam, 0, 0, &p0i);
    eta.rows_mut(0, d).gemv(1.0, &p0i, model.m0(), 1.0);
    for t in 1..n1 {
        // Transition t−1 → t contributes to blocks (t−1, t−1), (t, t), (t−1, t), (t, t−1).
        add_block(&mut lam, t - 1, t - 1, &atqia);
        add_block(&mut lam, t, t, &qi);
        add_block(&mut lam, t - 1, t, &(-&atqi));
        add_block(&mut lam, t, t - 1, &(-atqi.transpose()));
    }
    for (t, y) in ys.iter().enumerate() {
        if let Some(y) = y {
            add_block(&mut lam, t, t, &ctric);
            eta.rows_mut(t * d, d).gemv(1.0, &ctri, y, 1.0);
        }
    }
    let llt = faer_llt("joint precision of the stacked states", &to_faer(&lam))?;
    let eta_f = Mat::from_fn(big, 1, |i, _| eta[i]);
    let mean_f = llt.solve(&eta_f);
    let cov_f = llt.inverse();
    let mean = DVector::from_fn(big, |i, _| mean_f[(i, 0)]);
    let mut cov = DMatrix::from_fn(big, big, |i, j| cov_f[(i, j)]);
    crate::gaussian::symmetrise(&mut cov);
    Ok(JointPosterior { d, mean, cov })
}

/// `log p(y_{observed})`, the exact log-likelihood, by brute force: the observed `Y_t`
/// stacked are Gaussian with mean `C A^t m₀` and covariance blocks
/// `C Cov(X_t, X_s) Cᵀ + δ_ts R`, where `Cov(X_s, X_t) = A^{t−s} P_s` (t ≥ s),
/// `P_s = A P_{s−1} Aᵀ + Q`, `P_0 = P₀`. The density is evaluated with one dense faer LLᵀ
/// (`log det` from its diagonal, the quadratic form by a solve). Inputs are taken as zero.
/// Returns 0 if nothing is observed.
pub fn exact_log_likelihood_brute_force(
    model: &LinearGaussian,
    ys: &[Option<DVector<f64>>],
) -> Result<f64> {
    check_ys(model, ys)?;
    let n1 = ys.len();
    let m = model.obs_dim();
    let a = model.a();
    let c = model.c();
    // Prior moments of the states.
    let mut mu = Vec::with_capacity(n1);
    let mut p = Vec::with_capacity(n1);
    mu.push(model.m0().clone());
    p.push(model.p0().clone());
    for t in 1..n1 {
        mu.push(a * &mu[t - 1]);
        p.push(a * &p[t - 1] * a.transpose() + model.q());
    }
    // Cov(X_t, X_s) for t ≥ s: A^{t−s} P_s.
    let cross = |t: usize, s: usize| -> DMatrix<f64> {
        let mut b = p[s].clone();
        for _ in s..t {
            b = a * b;
        }
        b
    };
    let obs: Vec<usize> = (0..n1).filter(|&t| ys[t].is_some()).collect();
    if obs.is_empty() {
        return Ok(0.0);
    }
    let big = obs.len() * m;
    let mut sigma = DMatrix::<f64>::zeros(big, big);
    let mut resid = DVector::<f64>::zeros(big);
    for (bi, &t) in obs.iter().enumerate() {
        let y = ys[t].as_ref().expect("observed index");
        resid.rows_mut(bi * m, m).copy_from(&(y - c * &mu[t]));
        for (bj, &s) in obs.iter().enumerate().take(bi + 1) {
            let mut blk = c * cross(t, s) * c.transpose();
            if bi == bj {
                blk += model.r();
            }
            sigma.view_mut((bi * m, bj * m), (m, m)).copy_from(&blk);
            sigma
                .view_mut((bj * m, bi * m), (m, m))
                .copy_from(&blk.transpose());
        }
    }
    let llt = faer_llt("joint covariance of the observations", &to_faer(&sigma))?;
    let l = llt.L();
    let log_det: f64 = (0..big).map(|i| 2.0 * l[(i, i)].ln()).sum();
    let r_f = Mat::from_fn(big, 1, |i, _| resid[i]);
    let sol = llt.solve(&r_f);
    let quad: f64 = (0..big).map(|i| resid[i] * sol[(i, 0)]).sum();
    Ok(-0.5 * (big as f64 * LN_2PI + log_det + quad))
}

/// Pearson's chi-square statistic of `observed` counts of the outcomes `0, 1, 2, …` against
/// the probabilities `pmf(k)`, the outcomes pooled in order so that every bin expects at
/// least 5 (the last bin also takes every outcome past the observed ones). Returns the
/// statistic and its degrees of freedom (bins − 1).
pub fn pearson_pooled(observed: &[usize], pmf: impl Fn(usize) -> f64) -> (f64, usize) {
    let reps = observed.iter().sum::<usize>() as f64;
    let (mut stat, mut bins) = (0.0, 0);
    let (mut o, mut e, mut tail) = (0.0, 0.0, 1.0);
    for (k, &ok) in observed.iter().enumerate() {
        let p = pmf(k);
        tail -= p;
        o += ok as f64;
        e += p * reps;
        if e >= 5.0 && tail * reps >= 5.0 {
            stat += (o - e).powi(2) / e;
            bins += 1;
            (o, e) = (0.0, 0.0);
        }
    }
    let e = e + tail.max(0.0) * reps;
    stat += (o - e).powi(2) / e;
    (stat, bins)
}

/// `ln k!`, summed (exact enough for the small `k` of the law tests).
fn ln_factorial(k: usize) -> f64 {
    (2..=k).map(|i| (i as f64).ln()).sum()
}

/// `P(N = k)` for `N ~ Poisson(λ)`, `λ > 0`.
pub fn poisson_pmf(lambda: f64, k: usize) -> f64 {
    (k as f64 * lambda.ln() - lambda - ln_factorial(k)).exp()
}

/// `P(K = k)` for `K ~ Binomial(n, p)`, `0 < p < 1`, `k ≤ n`.
pub fn binomial_pmf(n: usize, p: f64, k: usize) -> f64 {
    multinomial_pmf(&[k, n - k], &[p, 1.0 - p])
}

/// `P(K = counts)` for `K ~ Multinomial(Σ counts; p)`, every `p_i > 0`.
pub fn multinomial_pmf(counts: &[usize], p: &[f64]) -> f64 {
    let n: usize = counts.iter().sum();
    let ln: f64 = counts
        .iter()
        .zip(p)
        .map(|(&k, &pi)| k as f64 * pi.ln() - ln_factorial(k))
        .sum();
    (ln_factorial(n) + ln).exp()
}

/// The 0.999 quantile of chi-square with `df ≥ 1` degrees of freedom (Wilson–Hilferty,
/// within 1 % for `df ≥ 2`; 10.83 exactly at `df = 1`).
pub fn chi2_quantile_999(df: usize) -> f64 {
    if df <= 1 {
        return 10.83;
    }
    let k = df as f64;
    let h = 2.0 / (9.0 * k);
    k * (1.0 - h + 3.090_232 * h.sqrt()).powi(3)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gaussian::log_normal_pdf_1d;

    #[test]
    fn ar1_noise_is_stationary() {
        let m = ar1_noise(0.9, 0.5, 0.3);
        // Stationarity: φ² p0 + σ² = p0, exact up to two roundings.
        let p0 = m.p0()[(0, 0)];
        assert!((0.81 * p0 + 0.25 - p0).abs() < 8.0 * f64::EPSILON * p0);
    }

    #[test]
    fn single_step_brute_force_is_closed_form() {
        // n = 0: Y_0 ~ N(m0, p0 + r); X_0 | y ~ N(m0 + p0/(p0+r)(y − m0), p0 r/(p0+r)).
        let (m0, p0, r, y) = (0.3, 2.0, 0.5, -1.2);
        let model = LinearGaussian::scalar(0.5, 1.0, 1.0, r, m0, p0).unwrap();
        let ys = vec![Some(DVector::from_element(1, y))];
        let ll = exact_log_likelihood_brute_force(&model, &ys).unwrap();
        // A few flops on O(1) numbers: a few ε.
        let tol = 32.0 * f64::EPSILON;
        assert!((ll - log_normal_pdf_1d(y, m0, p0 + r)).abs() < tol);
        let post = joint_gaussian_posterior(&model, &ys).unwrap();
        assert!((post.mean(0)[0] - (m0 + p0 / (p0 + r) * (y - m0))).abs() < tol);
        assert!((post.cov(0, 0)[(0, 0)] - p0 * r / (p0 + r)).abs() < tol);
    }

    #[test]
    fn prior_is_recovered_when_nothing_is_observed() {
        // With no observation, the posterior is the prior: E[X_2] = φ² m0,
        // Cov(X_1, X_2) = φ Var(X_1) = φ (φ² p0 + q).
        let (phi, q, m0, p0) = (0.8, 0.3, 1.5, 0.7);
        let model = LinearGaussian::scalar(phi, 1.0, q, 1.0, m0, p0).unwrap();
        let ys = vec![None, None, None];
        let post = joint_gaussian_posterior(&model, &ys).unwrap();
        assert_eq!(post.len(), 3);
        // Dense inverse of a 3×3 matrix with condition number O(10): ≲ 100 ε.
        let tol = 1e3 * f64::EPSILON;
        assert!((post.mean(2)[0] - phi * phi * m0).abs() < tol);
        assert!((post.cov(1, 2)[(0, 0)] - phi * (phi * phi * p0 + q)).abs() < tol);
        assert_eq!(exact_log_likelihood_brute_force(&model, &ys).unwrap(), 0.0);
        assert!(matches!(
            joint_gaussian_posterior(&model, &[]),
            Err(CoreError::Empty { .. })
        ));
    }

    /// The law helpers against hand-computed values, and each sums to 1.
    #[test]
    fn law_helpers_are_the_laws() {
        assert!((binomial_pmf(4, 0.5, 2) - 0.375).abs() < 1e-14);
        assert!((multinomial_pmf(&[1, 1, 2], &[0.25, 0.25, 0.5]) - 0.1875).abs() < 1e-14);
        assert!((poisson_pmf(2.0, 3) - 8.0 / 6.0 * (-2.0f64).exp()).abs() < 1e-14);
        let poisson: f64 = (0..60).map(|k| poisson_pmf(3.5, k)).sum();
        let binomial: f64 = (0..=20).map(|k| binomial_pmf(20, 0.3, k)).sum();
        assert!((poisson - 1.0).abs() < 1e-12 && (binomial - 1.0).abs() < 1e-12);
    }
}
