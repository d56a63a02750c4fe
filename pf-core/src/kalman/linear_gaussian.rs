//! The linear-Gaussian state-space model, the one model with exact answers.
//!
//! ```text
//! X_0 ~ N(m₀, P₀)
//! X_t = A·X_{t−1} + B·u_t + W_t,   W_t ~ N(0, Q)      (t ≥ 1)
//! Y_t = C·X_t + V_t,               V_t ~ N(0, R)      (t ≥ 0)
//! ```
//!
//! Inputs are indexed like states: `u_t` enters the transition that produces `X_t`, so an
//! input sequence `us` has one entry per time step `0..=n` and `us[0]` is never used.

use nalgebra::{DMatrix, DVector};
use rand::Rng;
use std::cell::RefCell;
use std::thread::LocalKey;

use crate::error::{CoreError, Result};
use crate::gaussian::{MvNormal, cholesky};
use crate::model::{StateSpaceModel, TransitionDensity};
use crate::params::ParamError;

/// A simulated path: states `X_0..X_n` and observations `Y_0..Y_n` (n + 1 of each).
pub type Simulated = (Vec<DVector<f64>>, Vec<DVector<f64>>);

/// A linear-Gaussian model `(A, B, C, Q, R, m₀, P₀)`; see the [module docs](crate::kalman).
///
/// The matrices are read through accessors named as in the maths (`a()` is A, …). They are
/// not public fields because the Cholesky factors of Q, R and P₀ are computed once, in
/// [`LinearGaussian::new`], and must not go stale: to change a parameter, build a new model.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearGaussian {
    /// A (d×d).
    a: DMatrix<f64>,
    /// Aᵀ, kept for allocation-free products.
    at: DMatrix<f64>,
    /// B (d×p), if the model has inputs.
    b: Option<DMatrix<f64>>,
    /// C (m×d).
    c: DMatrix<f64>,
    /// W ~ N(0, Q), factored.
    w: MvNormal,
    /// V ~ N(0, R), factored.
    v: MvNormal,
    /// X₀ ~ N(m₀, P₀), factored.
    x0: MvNormal,
    /// Q, R, P₀ as given (symmetrised).
    q: DMatrix<f64>,
    r: DMatrix<f64>,
    p0: DMatrix<f64>,
}

fn check_shape(
    what_rows: &'static str,
    what_cols: &'static str,
    m: &DMatrix<f64>,
    rows: usize,
    cols: usize,
) -> Result<()> {
    if m.nrows() != rows {
        return Err(CoreError::DimensionMismatch {
            what: what_rows,
            expected: rows,
            got: m.nrows(),
        });
    }
    if m.ncols() != cols {
        return Err(CoreError::DimensionMismatch {
            what: what_cols,
            expected: cols,
            got: m.ncols(),
        });
    }
    Ok(())
}

fn check_finite(what: &'static str, m: &DMatrix<f64>) -> Result<()> {
    let n = m.ncols();
    for i in 0..m.nrows() {
        for j in 0..n {
            let value = m[(i, j)];
            if !value.is_finite() {
                return Err(CoreError::NonFiniteData {
                    what,
                    index: i * n + j,
                    value,
                });
            }
        }
    }
    Ok(())
}

/// Symmetric within a relative 1e-10 (round-off from the caller's own products), then
/// symmetrised exactly.
fn check_symmetric(name: &'static str, m: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    let scale = m.amax();
    for j in 0..m.ncols() {
        for i in (j + 1)..m.nrows() {
            let gap = m[(i, j)] - m[(j, i)];
            if gap.abs() > 1e-10 * scale {
                return Err(CoreError::Param(ParamError {
                    name,
                    value: gap,
                    reason: "covariance must be symmetric (value is M_ij − M_ji)",
                }));
            }
        }
    }
    let mut s = m.clone();
    crate::gaussian::symmetrise(&mut s);
    Ok(s)
}

impl LinearGaussian {
    /// Build and validate `(A, B, C, Q, R, m₀, P₀)`.
    ///
    /// Shapes: A d×d, B d×p, C m×d, Q d×d, R m×m, m₀ of length d, P₀ d×d. All entries must be
    /// finite; Q, R and P₀ symmetric and positive **definite** (a singular Q, e.g. a noise-free
    /// state component, is rejected: the transition density would not exist and
    /// [`TransitionDensity`] is implemented). Q, R and P₀ are factored here, once.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        a: DMatrix<f64>,
        b: Option<DMatrix<f64>>,
        c: DMatrix<f64>,
        q: DMatrix<f64>,
        r: DMatrix<f64>,
        m0: DVector<f64>,
        p0: DMatrix<f64>,
    ) -> Result<Self> {
        let d = a.nrows();
        if d == 0 {
            return Err(CoreError::Empty { what: "state (A)" });
        }
        check_shape("A rows", "A columns (A must be square)", &a, d, d)?;
        if let Some(b) = &b {
            check_shape("B rows (state dimension)", "B columns", b, d, b.ncols())?;
            check_finite("B", b)?;
        }
        let m = c.nrows();
        if m == 0 {
            return Err(CoreError::Empty {
                what: "observation (C)",
            });
        }
        check_shape("C rows", "C columns (state dimension)", &c, m, d)?;
        check_shape("Q rows (state dimension)", "Q columns", &q, d, d)?;
        check_shape("R rows (observation dimension)", "R columns", &r, m, m)?;
        if m0.len() != d {
            return Err(CoreError::DimensionMismatch {
                what: "m0 length (state dimension)",
                expected: d,
                got: m0.len(),
            });
        }
        check_shape("P0 rows (state dimension)", "P0 columns", &p0, d, d)?;
        check_finite("A", &a)?;
        check_finite("C", &c)?;
        check_finite("Q", &q)?;
        check_finite("R", &r)?;
        check_finite("P0", &p0)?;
        let q = check_symmetric("Q", &q)?;
        let r = check_symmetric("R", &r)?;
        let p0 = check_symmetric("P0", &p0)?;
        let lq = cholesky("Q", &q)?;
        let lr = cholesky("R", &r)?;
        let lp0 = cholesky("P0", &p0)?;
        if let Some((index, &value)) = m0.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(CoreError::NonFiniteData {
                what: "m0",
                index,
                value,
            });
        }
        let x0 = MvNormal::from_parts(m0, lp0);
        Ok(Self {
            at: a.transpose(),
            a,
            b,
            c,
            w: MvNormal::from_parts(DVector::zeros(d), lq),
            v: MvNormal::from_parts(DVector::zeros(m), lr),
            x0,
            q,
            r,
            p0,
        })
    }

    /// A scalar model `X_t = a·X_{t−1} + W_t`, `Y_t = c·X_t + V_t`, `W ~ N(0, q)`,
    /// `V ~ N(0, r)`, `X_0 ~ N(m0, p0)`. For example, the AR(1)-plus-noise model
    /// `X_{k+1} = φX_k + σU_k`, `Y_k = X_k + ρV_k` is `scalar(φ, 1, σ², ρ², m0, p0)`.
    pub fn scalar(a: f64, c: f64, q: f64, r: f64, m0: f64, p0: f64) -> Result<Self> {
        let s = |v: f64| DMatrix::from_element(1, 1, v);
        Self::new(
            s(a),
            None,
            s(c),
            s(q),
            s(r),
            DVector::from_element(1, m0),
            s(p0),
        )
    }

    /// State dimension d.
    pub fn state_dim(&self) -> usize {
        self.a.nrows()
    }

    /// Observation dimension m.
    pub fn obs_dim(&self) -> usize {
        self.c.nrows()
    }

    /// Input dimension p (0 if the model has no B).
    pub fn input_dim(&self) -> usize {
        self.b.as_ref().map_or(0, |b| b.ncols())
    }

    /// A, the state transition matrix.
    pub fn a(&self) -> &DMatrix<f64> {
        &self.a
    }

    /// Aᵀ (precomputed).
    pub fn a_transpose(&self) -> &DMatrix<f64> {
        &self.at
    }

    /// B, the input matrix, if any.
    pub fn b(&self) -> Option<&DMatrix<f64>> {
        self.b.as_ref()
    }

    /// C, the observation matrix.
    pub fn c(&self) -> &DMatrix<f64> {
        &self.c
    }

    /// Q, the process-noise covariance.
    pub fn q(&self) -> &DMatrix<f64> {
        &self.q
    }

    /// R, the observation-noise covariance.
    pub fn r(&self) -> &DMatrix<f64> {
        &self.r
    }

    /// m₀, the initial mean.
    pub fn m0(&self) -> &DVector<f64> {
        self.x0.mean()
    }

    /// P₀, the initial covariance.
    pub fn p0(&self) -> &DMatrix<f64> {
        &self.p0
    }

    /// Lower Cholesky factor of Q.
    pub fn chol_q(&self) -> &DMatrix<f64> {
        self.w.chol()
    }

    /// Lower Cholesky factor of R.
    pub fn chol_r(&self) -> &DMatrix<f64> {
        self.v.chol()
    }

    /// Lower Cholesky factor of P₀.
    pub fn chol_p0(&self) -> &DMatrix<f64> {
        self.x0.chol()
    }

    /// Check an observation `y_t` (length m, finite).
    pub fn check_obs(&self, y: &DVector<f64>) -> Result<()> {
        if y.len() != self.obs_dim() {
            return Err(CoreError::DimensionMismatch {
                what: "observation length",
                expected: self.obs_dim(),
                got: y.len(),
            });
        }
        if let Some((index, &value)) = y.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(CoreError::NonFiniteData {
                what: "observation",
                index,
                value,
            });
        }
        Ok(())
    }

    /// Check an input `u_t`: the model must have a B, and `u` must have length p and be finite.
    pub fn check_input(&self, u: &DVector<f64>) -> Result<()> {
        if u.len() != self.input_dim() {
            return Err(CoreError::DimensionMismatch {
                what: "input length (columns of B; 0 if the model has no B)",
                expected: self.input_dim(),
                got: u.len(),
            });
        }
        if let Some((index, &value)) = u.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(CoreError::NonFiniteData {
                what: "input",
                index,
                value,
            });
        }
        Ok(())
    }

    /// Check an input sequence against `n_steps` time steps (`us[t]` is `u_t`, `us[0]` unused).
    pub fn check_inputs(&self, us: &[DVector<f64>], n_steps: usize) -> Result<()> {
        if us.len() != n_steps {
            return Err(CoreError::DimensionMismatch {
                what: "number of inputs (one per time step, us[0] unused)",
                expected: n_steps,
                got: us.len(),
            });
        }
        us.iter().skip(1).try_for_each(|u| self.check_input(u))
    }

    /// `out ← A·x + B·u` (the transition mean), without allocating.
    ///
    /// A `u` of the wrong length makes `out` NaN rather than panicking (see
    /// [`check_input`](Self::check_input)).
    pub fn transition_mean_into(
        &self,
        x: &DVector<f64>,
        u: Option<&DVector<f64>>,
        out: &mut DVector<f64>,
    ) {
        let d = self.state_dim();
        if out.len() != d {
            *out = DVector::zeros(d);
        }
        if x.len() != d {
            out.fill(f64::NAN);
            return;
        }
        out.gemv(1.0, &self.a, x, 0.0);
        if let Some(u) = u {
            match &self.b {
                Some(b) if u.len() == b.ncols() => out.gemv(1.0, b, u, 1.0),
                _ => out.fill(f64::NAN),
            }
        }
    }

    /// Simulate `X_0..X_n` and `Y_0..Y_n` (n + 1 of each). `us`, if given, holds one input per
    /// time step (`us[t]` is `u_t`; `us[0]` is unused), so it has length n + 1.
    pub fn simulate<R: Rng + ?Sized>(
        &self,
        n: usize,
        us: Option<&[DVector<f64>]>,
        rng: &mut R,
    ) -> Result<Simulated> {
        if let Some(us) = us {
            self.check_inputs(us, n + 1)?;
        }
        let mut xs = Vec::with_capacity(n + 1);
        let mut ys = Vec::with_capacity(n + 1);
        let mut x = self.sample_initial(rng);
        for t in 0..=n {
            if t > 0 {
                x = self.sample_transition(t, &x, us.map(|us| &us[t]), rng);
            }
            let mut y = self.v.sample(rng);
            y.gemv(1.0, &self.c, &x, 1.0);
            ys.push(y);
            xs.push(x.clone());
        }
        Ok((xs, ys))
    }
}

impl StateSpaceModel for LinearGaussian {
    type State = DVector<f64>;
    type Obs = DVector<f64>;
    type Input = DVector<f64>;

    fn sample_initial<R: Rng + ?Sized>(&self, rng: &mut R) -> DVector<f64> {
        self.x0.sample(rng)
    }

    /// `A·x_prev + B·u + W`, one allocation (the returned state); see
    /// [`sample_transition_into`](StateSpaceModel::sample_transition_into).
    fn sample_transition<R: Rng + ?Sized>(
        &self,
        t: usize,
        x_prev: &DVector<f64>,
        u: Option<&DVector<f64>>,
        rng: &mut R,
    ) -> DVector<f64> {
        let mut x = DVector::zeros(self.state_dim());
        self.sample_transition_into(t, x_prev, u, &mut x, rng);
        x
    }

    /// `A·x_prev + B·u + W` into `x`, allocating only if `x` is not of length d. A
    /// mismatched `u` (or a `u` given to a model without B) gives a NaN state, which a filter
    /// reports as a non-finite weight; validate inputs up front with
    /// [`LinearGaussian::check_inputs`].
    fn sample_transition_into<R: Rng + ?Sized>(
        &self,
        _t: usize,
        x_prev: &DVector<f64>,
        u: Option<&DVector<f64>>,
        x: &mut DVector<f64>,
        rng: &mut R,
    ) {
        self.w.sample_into(rng, x);
        if x_prev.len() != self.state_dim() {
            x.fill(f64::NAN);
            return;
        }
        x.gemv(1.0, &self.a, x_prev, 1.0);
        if let Some(u) = u {
            match &self.b {
                Some(b) if u.len() == b.ncols() => x.gemv(1.0, b, u, 1.0),
                _ => x.fill(f64::NAN),
            }
        }
    }

    /// `log N(y; C·x, R)`; NaN if `y` or `x` has the wrong length. Allocates nothing after a
    /// thread's first call (the residual goes to a per-thread scratch vector).
    fn log_likelihood(&self, _t: usize, x: &DVector<f64>, y: &DVector<f64>) -> f64 {
        if y.len() != self.obs_dim() || x.len() != self.state_dim() {
            return f64::NAN;
        }
        with_scratch(&OBS_RESIDUAL, y.len(), |r| {
            r.copy_from(y);
            r.gemv(-1.0, &self.c, x, 1.0);
            self.v.log_density_residual_in_place(r)
        })
    }
}

thread_local! {
    /// Per-thread storage for the residual `y − C·x`, so that weighting a particle allocates
    /// nothing.
    static OBS_RESIDUAL: RefCell<DVector<f64>> = RefCell::new(DVector::zeros(0));
    /// The same for `x − A·x_prev − B·u`: a vector of its own, since a guided step evaluates
    /// both densities and one shared vector would be resized back and forth.
    static STATE_RESIDUAL: RefCell<DVector<f64>> = RefCell::new(DVector::zeros(0));
}

/// `f` on `scratch`, of length `len` (resized only when the length changes).
fn with_scratch<T>(
    scratch: &'static LocalKey<RefCell<DVector<f64>>>,
    len: usize,
    f: impl FnOnce(&mut DVector<f64>) -> T,
) -> T {
    scratch.with_borrow_mut(|r| {
        if r.len() != len {
            *r = DVector::zeros(len);
        }
        f(r)
    })
}

impl TransitionDensity for LinearGaussian {
    /// `log N(x; A·x_prev + B·u, Q)`; NaN on a dimension mismatch.
    fn log_transition_density(
        &self,
        _t: usize,
        x_prev: &DVector<f64>,
        x: &DVector<f64>,
        u: Option<&DVector<f64>>,
    ) -> f64 {
        if x.len() != self.state_dim() {
            return f64::NAN;
        }
        with_scratch(&STATE_RESIDUAL, x.len(), |r| {
            self.transition_mean_into(x_prev, u, r);
            // r ← x − (A·x_prev + B·u)
            r.axpy(1.0, x, -1.0);
            self.w.log_density_residual_in_place(r)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gaussian::log_normal_pdf_1d;
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    fn mat(r: usize, c: usize, v: &[f64]) -> DMatrix<f64> {
        DMatrix::from_row_slice(r, c, v)
    }

    /// (A, C, Q, R, m₀, P₀) of a valid 2-D model.
    type Parts = (
        DMatrix<f64>,
        DMatrix<f64>,
        DMatrix<f64>,
        DMatrix<f64>,
        DVector<f64>,
        DMatrix<f64>,
    );

    fn two_d() -> Parts {
        (
            mat(2, 2, &[1.0, 0.1, 0.0, 0.9]),
            mat(1, 2, &[1.0, 0.5]),
            mat(2, 2, &[0.2, 0.05, 0.05, 0.1]),
            mat(1, 1, &[0.3]),
            DVector::from_vec(vec![0.0, 1.0]),
            DMatrix::identity(2, 2),
        )
    }

    #[test]
    fn new_rejects_bad_shapes_and_non_pd() {
        let (a, c, q, r, m0, p0) = two_d();
        assert!(
            LinearGaussian::new(
                a.clone(),
                None,
                c.clone(),
                q.clone(),
                r.clone(),
                m0.clone(),
                p0.clone()
            )
            .is_ok()
        );
        let e = LinearGaussian::new(
            a.clone(),
            None,
            mat(1, 3, &[1.0, 0.0, 0.0]),
            q.clone(),
            r.clone(),
            m0.clone(),
            p0.clone(),
        );
        assert_eq!(
            e,
            Err(CoreError::DimensionMismatch {
                what: "C columns (state dimension)",
                expected: 2,
                got: 3
            })
        );
        let e = LinearGaussian::new(
            a.clone(),
            Some(mat(3, 1, &[1.0, 0.0, 0.0])),
            c.clone(),
            q.clone(),
            r.clone(),
            m0.clone(),
            p0.clone(),
        );
        assert!(matches!(
            e,
            Err(CoreError::DimensionMismatch {
                expected: 2,
                got: 3,
                ..
            })
        ));
        let e = LinearGaussian::new(
            a.clone(),
            None,
            c.clone(),
            q.clone(),
            r.clone(),
            DVector::zeros(3),
            p0.clone(),
        );
        assert!(matches!(
            e,
            Err(CoreError::DimensionMismatch { got: 3, .. })
        ));
        // Q with a negative second pivot: 0.1 − 0.5²/1 = −0.15.
        let bad_q = mat(2, 2, &[1.0, 0.5, 0.5, 0.1]);
        let e = LinearGaussian::new(
            a.clone(),
            None,
            c.clone(),
            bad_q,
            r.clone(),
            m0.clone(),
            p0.clone(),
        );
        match e {
            Err(CoreError::NotPositiveDefinite { what, pivot, value }) => {
                assert_eq!((what, pivot), ("Q", 1));
                assert!((value + 0.15).abs() < 1e-15);
            }
            other => panic!("expected NotPositiveDefinite, got {other:?}"),
        }
        let e = LinearGaussian::new(
            a.clone(),
            None,
            c.clone(),
            mat(2, 2, &[1.0, 0.5, 0.4, 1.0]),
            r.clone(),
            m0.clone(),
            p0.clone(),
        );
        assert!(matches!(
            e,
            Err(CoreError::Param(ParamError { name: "Q", .. }))
        ));
        let e = LinearGaussian::new(a, None, c, q, mat(1, 1, &[0.0]), m0, p0);
        assert!(matches!(
            e,
            Err(CoreError::NotPositiveDefinite {
                what: "R",
                pivot: 0,
                ..
            })
        ));
    }

    #[test]
    fn scalar_densities_match_closed_form() {
        let (phi, sigma, rho) = (0.9_f64, 0.5_f64, 0.3_f64);
        let m = LinearGaussian::scalar(phi, 1.0, sigma * sigma, rho * rho, 0.0, 1.0).unwrap();
        let x = DVector::from_element(1, 0.7);
        let xp = DVector::from_element(1, -0.2);
        let y = DVector::from_element(1, 1.1);
        // Same formula evaluated two ways on O(1) numbers: a few ε.
        let tol = 16.0 * f64::EPSILON;
        let ll = m.log_likelihood(3, &x, &y);
        assert!((ll - log_normal_pdf_1d(1.1, 0.7, rho * rho)).abs() < tol);
        let lt = m.log_transition_density(3, &xp, &x, None);
        assert!((lt - log_normal_pdf_1d(0.7, phi * -0.2, sigma * sigma)).abs() < tol);
        assert!(m.log_likelihood(0, &x, &DVector::zeros(2)).is_nan());
    }

    #[test]
    fn simulate_with_inputs_has_right_mean() {
        // X_t = 0.5 X_{t−1} + u_t + W: with u_t = 2 for all t and X_0 = 0 ± tiny, the mean of
        // X_n is 2·(1 − 0.5ⁿ)/(1 − 0.5), and Var(X_n) ≤ q/(1 − 0.25).
        let m = LinearGaussian::new(
            mat(1, 1, &[0.5]),
            Some(mat(1, 1, &[1.0])),
            mat(1, 1, &[1.0]),
            mat(1, 1, &[0.04]),
            mat(1, 1, &[1.0]),
            DVector::zeros(1),
            mat(1, 1, &[1e-6]),
        )
        .unwrap();
        let n = 6;
        let us = vec![DVector::from_element(1, 2.0); n + 1];
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        let reps = 4000;
        let mut s = 0.0;
        for _ in 0..reps {
            let (xs, ys) = m.simulate(n, Some(&us), &mut rng).unwrap();
            assert_eq!((xs.len(), ys.len()), (n + 1, n + 1));
            s += xs[n][0];
        }
        let mean = s / reps as f64;
        let want = 2.0 * (1.0 - 0.5_f64.powi(n as i32)) / 0.5;
        // z = 4 with SE ≤ √(0.04/0.75/reps).
        let se = (0.04 / 0.75 / reps as f64).sqrt();
        assert!((mean - want).abs() < 4.0 * se, "mean = {mean}, want {want}");
        assert!(m.simulate(n, Some(&us[..n]), &mut rng).is_err());
    }
}
