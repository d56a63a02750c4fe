//! The Kalman filter (Kalman 1960) for [`LinearGaussian`], with inputs and missing
//! observations.
//!
//! Prediction: `m_{t|t−1} = A m_{t−1|t−1} + B u_t`, `P_{t|t−1} = A P_{t−1|t−1} Aᵀ + Q`.
//! Update (when `y_t` is observed):
//! `e = y_t − C m_{t|t−1}`, `S = C P_{t|t−1} Cᵀ + R = L_S L_Sᵀ`, `K = P_{t|t−1} Cᵀ S⁻¹`,
//! `m_{t|t} = m_{t|t−1} + K e`, and the Joseph form
//! `P_{t|t} = (I − KC) P_{t|t−1} (I − KC)ᵀ + K R Kᵀ`, which stays symmetric positive
//! semi-definite under round-off where `(I − KC) P` need not. The log-likelihood increment
//! is `log p(y_t | y_{0:t−1}) = log N(e; 0, S)`. At `t = 0` the "prediction" is the prior
//! `N(m₀, P₀)`; a missing `y_t` skips the update and adds 0.

use nalgebra::{DMatrix, DVector};

use super::LinearGaussian;
use crate::error::{CoreError, Result};
use crate::gaussian::{cholesky_into, log_normal_chol_in_place, symmetrise};

/// Scratch buffers of the step API, sized on first use and reused afterwards.
#[derive(Debug, Clone, Default)]
struct Workspace {
    /// d-vectors.
    vd: DVector<f64>,
    vd2: DVector<f64>,
    /// m-vectors.
    e: DVector<f64>,
    vm: DVector<f64>,
    /// d×d.
    pd: DMatrix<f64>,
    ikc: DMatrix<f64>,
    /// m×m: S and its factor.
    s: DMatrix<f64>,
    ls: DMatrix<f64>,
    /// m×d: Kᵀ; d×m: K.
    kt: DMatrix<f64>,
    k: DMatrix<f64>,
}

impl Workspace {
    fn ensure(&mut self, d: usize, m: usize) {
        if self.pd.shape() != (d, d) {
            self.vd = DVector::zeros(d);
            self.vd2 = DVector::zeros(d);
            self.pd = DMatrix::zeros(d, d);
            self.ikc = DMatrix::zeros(d, d);
        }
        if self.kt.shape() != (m, d) {
            self.e = DVector::zeros(m);
            self.vm = DVector::zeros(m);
            self.s = DMatrix::zeros(m, m);
            self.ls = DMatrix::zeros(m, m);
            self.kt = DMatrix::zeros(m, d);
            self.k = DMatrix::zeros(d, m);
        }
    }
}

/// A Gaussian belief `N(m, P)` about the state, with the buffers its steps reuse.
///
/// The same type carries the [`Ukf`](super::Ukf)'s belief. Equality compares `m` and `P`
/// only, not the scratch buffers.
#[derive(Debug, Clone)]
pub struct KalmanState {
    /// Mean m.
    pub m: DVector<f64>,
    /// Covariance P.
    pub p: DMatrix<f64>,
    ws: Workspace,
}

impl PartialEq for KalmanState {
    fn eq(&self, other: &Self) -> bool {
        self.m == other.m && self.p == other.p
    }
}

impl KalmanState {
    /// `N(m, P)`. Shapes are checked by the steps.
    pub fn new(m: DVector<f64>, p: DMatrix<f64>) -> Self {
        Self {
            m,
            p,
            ws: Workspace::default(),
        }
    }

    /// The prior `N(m₀, P₀)` of `model`: the predicted belief at `t = 0`.
    pub fn prior(model: &LinearGaussian) -> Self {
        Self::new(model.m0().clone(), model.p0().clone())
    }

    fn check_dims(&self, d: usize) -> Result<()> {
        if self.m.len() != d {
            return Err(CoreError::DimensionMismatch {
                what: "Kalman mean length (state dimension)",
                expected: d,
                got: self.m.len(),
            });
        }
        if self.p.shape() != (d, d) {
            return Err(CoreError::DimensionMismatch {
                what: "Kalman covariance size (state dimension)",
                expected: d,
                got: if self.p.nrows() != d {
                    self.p.nrows()
                } else {
                    self.p.ncols()
                },
            });
        }
        Ok(())
    }

    /// Time update `N(m, P) → N(A m + B u, A P Aᵀ + Q)`, allocation-free after the first call.
    pub fn predict(&mut self, model: &LinearGaussian, u: Option<&DVector<f64>>) -> Result<()> {
        let d = model.state_dim();
        self.check_dims(d)?;
        if let Some(u) = u {
            model.check_input(u)?;
        }
        self.ws.ensure(d, model.obs_dim());
        let ws = &mut self.ws;
        model.transition_mean_into(&self.m, u, &mut ws.vd);
        std::mem::swap(&mut self.m, &mut ws.vd);
        ws.pd.copy_from(model.q());
        ws.pd
            .quadform_tr_with_workspace(&mut ws.vd2, 1.0, model.a(), &self.p, 1.0);
        std::mem::swap(&mut self.p, &mut ws.pd);
        symmetrise(&mut self.p);
        Ok(())
    }

    /// Measurement update with `y`; returns `log p(y_t | y_{0:t−1}) = log N(y; C m, S)`.
    ///
    /// Errors: a mismatched or non-finite `y`, or an innovation covariance `S` that is not
    /// positive definite ([`CoreError::NotPositiveDefinite`] with `what` =
    /// "innovation covariance S"; the caller knows the step). On error the belief is unchanged.
    pub fn update(&mut self, model: &LinearGaussian, y: &DVector<f64>) -> Result<f64> {
        let d = model.state_dim();
        let m = model.obs_dim();
        self.check_dims(d)?;
        model.check_obs(y)?;
        self.ws.ensure(d, m);
        let ws = &mut self.ws;
        let c = model.c();
        // e = y − C m
        ws.e.copy_from(y);
        ws.e.gemv(-1.0, c, &self.m, 1.0);
        // S = C P Cᵀ + R
        ws.s.copy_from(model.r());
        ws.s.quadform_tr_with_workspace(&mut ws.vm, 1.0, c, &self.p, 1.0);
        symmetrise(&mut ws.s);
        cholesky_into("innovation covariance S", &ws.s, &mut ws.ls)?;
        // Kᵀ = S⁻¹ C P (P symmetric), by two triangular solves.
        ws.kt.gemm(1.0, c, &self.p, 0.0);
        ws.ls.solve_lower_triangular_unchecked_mut(&mut ws.kt);
        ws.ls.tr_solve_lower_triangular_unchecked_mut(&mut ws.kt);
        ws.k.tr_copy_from(&ws.kt);
        // m ← m + K e (before e is overwritten by the log-density).
        self.m.gemv(1.0, &ws.k, &ws.e, 1.0);
        let ll = log_normal_chol_in_place(&ws.ls, &mut ws.e);
        // Joseph form: P ← (I − KC) P (I − KC)ᵀ + K R Kᵀ.
        ws.ikc.fill_with_identity();
        ws.ikc.gemm(-1.0, &ws.k, c, 1.0);
        ws.pd
            .quadform_tr_with_workspace(&mut ws.vd, 1.0, &ws.ikc, &self.p, 0.0);
        ws.pd
            .quadform_tr_with_workspace(&mut ws.vd, 1.0, &ws.k, model.r(), 1.0);
        std::mem::swap(&mut self.p, &mut ws.pd);
        symmetrise(&mut self.p);
        Ok(ll)
    }
}

/// Everything the filter computed, per time step `t = 0..=n`.
#[derive(Debug, Clone, PartialEq)]
pub struct KalmanOutput {
    /// `m_{t|t−1}` (`m₀` at `t = 0`).
    pub predicted_means: Vec<DVector<f64>>,
    /// `P_{t|t−1}` (`P₀` at `t = 0`).
    pub predicted_covs: Vec<DMatrix<f64>>,
    /// `m_{t|t}` (equal to the prediction where `y_t` is missing).
    pub filtered_means: Vec<DVector<f64>>,
    /// `P_{t|t}`.
    pub filtered_covs: Vec<DMatrix<f64>>,
    /// `log p(y_t | y_{0:t−1})`, 0 where `y_t` is missing.
    pub log_lik_increments: Vec<f64>,
    /// `log p(y_{0:n})`, the sum of the increments: the exact log-likelihood.
    pub log_likelihood: f64,
}

impl KalmanOutput {
    /// Number of time steps n + 1.
    pub fn len(&self) -> usize {
        self.filtered_means.len()
    }

    /// Whether no step was filtered (never true for an output of [`kalman_filter`]).
    pub fn is_empty(&self) -> bool {
        self.filtered_means.is_empty()
    }

    /// The filter's output for the steps `lo..=t` alone (`log_likelihood` is their
    /// increments' sum). Each filtered moment already conditions on the data up to its step,
    /// so [`rts_smoother`](super::rts_smoother) on it gives the moments of those steps given
    /// `y_{0:t}`: a fixed-lag smoother's window, `O(t − lo)` instead of a pass from step 0.
    ///
    /// # Errors
    /// [`CoreError::DimensionMismatch`]: `lo > t` or `t` beyond the last step.
    pub fn steps(&self, lo: usize, t: usize) -> Result<KalmanOutput> {
        if lo > t || t >= self.len() {
            return Err(CoreError::DimensionMismatch {
                what: "Kalman output steps lo..=t",
                expected: self.len(),
                got: t + 1,
            });
        }
        let r = lo..t + 1;
        let increments = self.log_lik_increments[r.clone()].to_vec();
        Ok(KalmanOutput {
            predicted_means: self.predicted_means[r.clone()].to_vec(),
            predicted_covs: self.predicted_covs[r.clone()].to_vec(),
            filtered_means: self.filtered_means[r.clone()].to_vec(),
            filtered_covs: self.filtered_covs[r].to_vec(),
            log_likelihood: increments.iter().sum(),
            log_lik_increments: increments,
        })
    }
}

/// Run the Kalman filter over `ys` (`ys[t] = None` for a missing `y_t`), with inputs `us`
/// (`us[t] = u_t`, one per step, `us[0]` unused; `None` means no input).
///
/// Errors: empty `ys`, bad shapes or non-finite data (checked up front), or a non-PD
/// innovation covariance (from [`KalmanState::update`]).
pub fn kalman_filter(
    model: &LinearGaussian,
    ys: &[Option<DVector<f64>>],
    us: Option<&[DVector<f64>]>,
) -> Result<KalmanOutput> {
    let n1 = ys.len();
    if n1 == 0 {
        return Err(CoreError::Empty {
            what: "observation sequence",
        });
    }
    for y in ys.iter().flatten() {
        model.check_obs(y)?;
    }
    if let Some(us) = us {
        model.check_inputs(us, n1)?;
    }
    let mut out = KalmanOutput {
        predicted_means: Vec::with_capacity(n1),
        predicted_covs: Vec::with_capacity(n1),
        filtered_means: Vec::with_capacity(n1),
        filtered_covs: Vec::with_capacity(n1),
        log_lik_increments: Vec::with_capacity(n1),
        log_likelihood: 0.0,
    };
    let mut st = KalmanState::prior(model);
    for (t, y) in ys.iter().enumerate() {
        if t > 0 {
            st.predict(model, us.map(|us| &us[t]))
                .map_err(|e| e.at_step(t))?;
        }
        out.predicted_means.push(st.m.clone());
        out.predicted_covs.push(st.p.clone());
        let ll = match y {
            Some(y) => st.update(model, y).map_err(|e| e.at_step(t))?,
            None => 0.0,
        };
        out.log_lik_increments.push(ll);
        out.log_likelihood += ll;
        out.filtered_means.push(st.m.clone());
        out.filtered_covs.push(st.p.clone());
    }
    Ok(out)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::gaussian::log_normal_pdf_1d;
    use crate::testing::{exact_log_likelihood_brute_force, joint_gaussian_posterior};
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    /// 2-D state (position, velocity-like), 1-D observation of a mix of both.
    pub(crate) fn model_2d() -> LinearGaussian {
        LinearGaussian::new(
            DMatrix::from_row_slice(2, 2, &[0.95, 0.2, -0.1, 0.8]),
            None,
            DMatrix::from_row_slice(1, 2, &[1.0, 0.5]),
            DMatrix::from_row_slice(2, 2, &[0.3, 0.05, 0.05, 0.2]),
            DMatrix::from_element(1, 1, 0.5),
            DVector::from_vec(vec![0.5, -0.3]),
            DMatrix::from_row_slice(2, 2, &[1.0, 0.2, 0.2, 0.7]),
        )
        .unwrap()
    }

    pub(crate) fn observations(
        model: &LinearGaussian,
        n: usize,
        missing: &[usize],
        seed: u64,
    ) -> Vec<Option<DVector<f64>>> {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let (_, ys) = model.simulate(n, None, &mut rng).unwrap();
        ys.into_iter()
            .enumerate()
            .map(|(t, y)| (!missing.contains(&t)).then_some(y))
            .collect()
    }

    #[test]
    fn log_likelihood_and_last_mean_match_brute_force() {
        let model = model_2d();
        let n = 10;
        let ys = observations(&model, n, &[4], 21);
        let kf = kalman_filter(&model, &ys, None).unwrap();
        assert_eq!(kf.len(), n + 1);
        assert_eq!(kf.log_lik_increments[4], 0.0);
        let exact = exact_log_likelihood_brute_force(&model, &ys).unwrap();
        // Both sides are backward-stable factorisations of matrices whose condition numbers
        // are O(10) here (noise eigenvalues in [0.15, 1.2], |eig A| < 1), over N = 10 observed
        // scalars: error ≲ κ·N·ε·|ℓ| ≈ 10·10·ε·|ℓ|; 1e4·ε·max(1,|ℓ|) leaves a ×100 margin.
        let tol = 1e4 * f64::EPSILON * exact.abs().max(1.0);
        assert!(
            (kf.log_likelihood - exact).abs() < tol,
            "KF {} vs brute force {exact}",
            kf.log_likelihood
        );
        let post = joint_gaussian_posterior(&model, &ys).unwrap();
        // Same conditioning argument for the mean and covariance of X_n.
        let tol = 1e4 * f64::EPSILON;
        assert!((&kf.filtered_means[n] - post.mean(n)).amax() < tol);
        assert!((&kf.filtered_covs[n] - post.cov(n, n)).amax() < tol);
    }

    #[test]
    fn scalar_first_step_is_closed_form() {
        // t = 0 with X_0 ~ N(m0, p0), Y_0 = X_0 + V: Y_0 ~ N(m0, p0 + r) and
        // m_{0|0} = m0 + p0/(p0 + r)·(y − m0), P_{0|0} = p0·r/(p0 + r).
        let (m0, p0, r) = (0.4, 2.0, 0.5);
        let model = LinearGaussian::scalar(0.9, 1.0, 0.1, r, m0, p0).unwrap();
        let y = 1.7;
        let kf = kalman_filter(&model, &[Some(DVector::from_element(1, y))], None).unwrap();
        // A handful of flops on O(1) numbers.
        let tol = 16.0 * f64::EPSILON;
        assert!((kf.log_likelihood - log_normal_pdf_1d(y, m0, p0 + r)).abs() < tol);
        assert!((kf.filtered_means[0][0] - (m0 + p0 / (p0 + r) * (y - m0))).abs() < tol);
        assert!((kf.filtered_covs[0][(0, 0)] - p0 * r / (p0 + r)).abs() < tol);
    }

    #[test]
    fn inputs_shift_the_prediction() {
        let model = LinearGaussian::new(
            DMatrix::from_element(1, 1, 0.5),
            Some(DMatrix::from_element(1, 1, 2.0)),
            DMatrix::from_element(1, 1, 1.0),
            DMatrix::from_element(1, 1, 0.1),
            DMatrix::from_element(1, 1, 0.2),
            DVector::from_element(1, 1.0),
            DMatrix::from_element(1, 1, 0.3),
        )
        .unwrap();
        let ys = vec![None, None];
        let us = vec![
            DVector::from_element(1, 99.0),
            DVector::from_element(1, 3.0),
        ];
        let kf = kalman_filter(&model, &ys, Some(&us)).unwrap();
        // m_{1|0} = 0.5·1 + 2·3 (us[0] unused), P_{1|0} = 0.25·0.3 + 0.1: exact in binary
        // up to one rounding each.
        assert_eq!(kf.predicted_means[1][0], 6.5);
        assert!((kf.predicted_covs[1][(0, 0)] - 0.175).abs() < 4.0 * f64::EPSILON);
        assert_eq!(kf.log_likelihood, 0.0);
        // Wrong input length and wrong number of inputs are errors, not panics.
        let bad = vec![DVector::zeros(1), DVector::zeros(2)];
        assert!(matches!(
            kalman_filter(&model, &ys, Some(&bad)),
            Err(CoreError::DimensionMismatch { .. })
        ));
        assert!(kalman_filter(&model, &ys, Some(&us[..1])).is_err());
        assert!(matches!(
            kalman_filter(&model, &[], None),
            Err(CoreError::Empty { .. })
        ));
        let nan = vec![Some(DVector::from_element(1, f64::NAN))];
        assert!(matches!(
            kalman_filter(&model, &nan, None),
            Err(CoreError::NonFiniteData { .. })
        ));
    }
}
