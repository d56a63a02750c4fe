//! Model (5): a state split into a part `x^p` handled by the particle filter and a part
//! `x^k` handled by Kalman filters.
//!
//! ```text
//! x^p_{t+1} = A^p x^p_t + A^k x^k_t + w^p_t,   w^p ~ N(0, Q^p)      (5a)
//! x^k_{t+1} = F^p x^p_t + F^k x^k_t + w^k_t,   w^k ~ N(0, Q^k)      (5b)
//! y_t       = h_t(x^p_t) + C_t x^k_t + e_t,    e   ~ N(0, R)        (5c)
//! ```
//!
//! The noises are independent (the paper reduces the dependent case to this one by
//! Gram–Schmidt). The matrices are time-invariant here; the paper allows `A_t`, `C_t`, … to
//! vary, which the radar example does not need. Dimensions are const generics: `P` = p,
//! `K` = k and `NY` = the measurement dimension. The model is built and checked with
//! nalgebra matrices; the filter ([`crate::mpf`]) copies them into plain arrays and works on
//! particles held as columns.

use crate::error::{MpfError, Result};
use nalgebra::{Cholesky, SMatrix, SVector};
use pf_core::CoreError;
use pf_core::gaussian::LN_2PI;
use pf_core::params::ParamError;
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

/// Particles per tile: the filter's per-particle algebra runs on `TILE` particles at a time,
/// each quantity an array of `TILE` lanes on the stack, so that its loops vectorise.
pub const TILE: usize = 32;

/// One quantity of every particle of a tile.
pub type Lanes = [f64; TILE];

/// The nonlinear measurement `h_t(x^p)` of eq. (5c), and how to form its residual.
pub trait Measurement<const P: usize, const NY: usize>: Send + Sync {
    /// `h_t(x^p_t)`.
    fn h(&self, t: usize, xp: &SVector<f64, P>) -> SVector<f64, NY>;

    /// The residual `y − ŷ`. Override to wrap angles (the radar's azimuth).
    fn residual(&self, y: &SVector<f64, NY>, y_hat: &SVector<f64, NY>) -> SVector<f64, NY> {
        y - y_hat
    }

    /// `e[j][i] = residual(y, h_t(x^{p,(i)}))_j` for the first `m ≤ TILE` particles of a
    /// tile, `xp[c]` holding component `c` of each (at least `m` values). By default one
    /// particle at a time through [`h`](Self::h) and [`residual`](Self::residual); override
    /// it with loops over the columns (as [`RangeAzimuth`](crate::radar::RangeAzimuth) and
    /// [`LinearMeasurement`] do) for a filter whose loops vectorise.
    #[inline(always)]
    fn residuals(
        &self,
        t: usize,
        y: &SVector<f64, NY>,
        xp: &[&[f64]; P],
        m: usize,
        e: &mut [Lanes; NY],
    ) {
        for i in 0..m.min(TILE) {
            let x = SVector::<f64, P>::from_fn(|c, _| xp[c][i]);
            let r = self.residual(y, &self.h(t, &x));
            for (j, e) in e.iter_mut().enumerate() {
                e[i] = r[j];
            }
        }
    }
}

/// A linear measurement `h(x^p) = H x^p`, for tests and fully linear models.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearMeasurement<const P: usize, const NY: usize> {
    /// H.
    pub h: SMatrix<f64, NY, P>,
}

impl<const P: usize, const NY: usize> Measurement<P, NY> for LinearMeasurement<P, NY> {
    fn h(&self, _t: usize, xp: &SVector<f64, P>) -> SVector<f64, NY> {
        self.h * xp
    }

    #[inline(always)]
    fn residuals(
        &self,
        _t: usize,
        y: &SVector<f64, NY>,
        xp: &[&[f64]; P],
        m: usize,
        e: &mut [Lanes; NY],
    ) {
        let m = m.min(TILE);
        for (j, e) in e.iter_mut().enumerate() {
            let e = &mut e[..m];
            e.fill(y[j]);
            for (c, x) in xp.iter().enumerate() {
                let h = self.h[(j, c)];
                for (e, &x) in e.iter_mut().zip(&x[..m]) {
                    *e -= h * x;
                }
            }
        }
    }
}

/// Gaussian `N(mean, cov)` with its lower Cholesky factor, computed once: the fields are
/// private so that the factor always belongs to the covariance.
#[derive(Debug, Clone, PartialEq)]
pub struct FactoredGaussian<const D: usize> {
    mean: SVector<f64, D>,
    cov: SMatrix<f64, D, D>,
    /// Lower Cholesky factor of `cov`.
    chol: SMatrix<f64, D, D>,
}

impl<const D: usize> FactoredGaussian<D> {
    /// Factor `cov`; `what` names it in the error.
    ///
    /// # Errors
    /// A non-finite entry, an asymmetric or non-positive-definite covariance.
    pub fn new(what: &'static str, mean: SVector<f64, D>, cov: SMatrix<f64, D, D>) -> Result<Self> {
        check_finite(what, cov.as_slice())?;
        check_finite(what, mean.as_slice())?;
        let chol = spd_chol(what, &cov)?;
        Ok(Self { mean, cov, chol })
    }

    /// The mean.
    pub fn mean(&self) -> &SVector<f64, D> {
        &self.mean
    }

    /// The covariance.
    pub fn cov(&self) -> &SMatrix<f64, D, D> {
        &self.cov
    }

    /// The lower Cholesky factor `L` of the covariance, `L Lᵀ = cov`.
    pub fn chol(&self) -> &SMatrix<f64, D, D> {
        &self.chol
    }

    /// Draw `mean + L z`, `z` from `D` standard normals in order.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> SVector<f64, D> {
        let z = SVector::<f64, D>::from_fn(|_, _| StandardNormal.sample(rng));
        self.mean + self.chol * z
    }
}

pub(crate) fn check_finite(what: &'static str, v: &[f64]) -> Result<()> {
    if let Some((index, &value)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        return Err(CoreError::NonFiniteData { what, index, value }.into());
    }
    Ok(())
}

/// Lower Cholesky factor of a symmetric positive definite matrix (0×0 gives 0×0).
pub(crate) fn spd_chol<const D: usize>(
    what: &'static str,
    m: &SMatrix<f64, D, D>,
) -> Result<SMatrix<f64, D, D>> {
    let scale = m.amax();
    for j in 0..D {
        for i in (j + 1)..D {
            let gap = m[(i, j)] - m[(j, i)];
            if gap.abs() > 1e-10 * scale {
                return Err(CoreError::Param(ParamError {
                    name: what,
                    value: gap,
                    reason: "covariance must be symmetric (value is M_ij − M_ji)",
                })
                .into());
            }
        }
    }
    Cholesky::new(*m).map(|c| c.l()).ok_or_else(|| {
        CoreError::NotPositiveDefinite {
            what,
            pivot: (0..D).find(|&i| m[(i, i)] <= 0.0).unwrap_or(0),
            value: (0..D).map(|i| m[(i, i)]).fold(f64::INFINITY, f64::min),
        }
        .into()
    })
}

/// Model (5) with time-invariant matrices and a nonlinear measurement `H`.
///
/// Built and validated once by [`new`](Self::new), which also factors the covariances; the
/// fields are private and read through getters, so a factor never goes stale.
#[derive(Debug, Clone)]
pub struct MixedLinearGaussian<const P: usize, const K: usize, const NY: usize, H> {
    /// `A^p` (p×p).
    a_p: SMatrix<f64, P, P>,
    /// `A^k` (p×k).
    a_k: SMatrix<f64, P, K>,
    /// `F^p` (k×p).
    f_p: SMatrix<f64, K, P>,
    /// `F^k` (k×k).
    f_k: SMatrix<f64, K, K>,
    /// `Q^p`.
    q_p: SMatrix<f64, P, P>,
    /// `Q^k`.
    q_k: SMatrix<f64, K, K>,
    /// `C_t` (ny×k).
    c: SMatrix<f64, NY, K>,
    /// `e ~ N(0, R)`, factored.
    e: FactoredGaussian<NY>,
    /// `x^p_0 ~ p_{x_0^p}`, a Gaussian here.
    x0_p: FactoredGaussian<P>,
    /// `x̄^k_0` of Alg. 1, step 1.
    x0_k: SVector<f64, K>,
    /// `P̄_0`.
    p0_k: SMatrix<f64, K, K>,
    /// `h_t`.
    h: H,
}

/// The matrices of model (5), as given by the user (see [`MixedLinearGaussian::new`]).
#[derive(Debug, Clone)]
pub struct Model5Matrices<const P: usize, const K: usize, const NY: usize> {
    /// `A^p`.
    pub a_p: SMatrix<f64, P, P>,
    /// `A^k`.
    pub a_k: SMatrix<f64, P, K>,
    /// `F^p`.
    pub f_p: SMatrix<f64, K, P>,
    /// `F^k`.
    pub f_k: SMatrix<f64, K, K>,
    /// `Q^p`.
    pub q_p: SMatrix<f64, P, P>,
    /// `Q^k`.
    pub q_k: SMatrix<f64, K, K>,
    /// `C_t`.
    pub c: SMatrix<f64, NY, K>,
    /// `R`.
    pub r: SMatrix<f64, NY, NY>,
    /// Mean of `x^p_0`.
    pub x0_p: SVector<f64, P>,
    /// Covariance of `x^p_0`.
    pub p0_p: SMatrix<f64, P, P>,
    /// `x̄^k_0`.
    pub x0_k: SVector<f64, K>,
    /// `P̄_0`.
    pub p0_k: SMatrix<f64, K, K>,
}

/// Read access: the matrices of model (5) as built, and the factored laws.
impl<const P: usize, const K: usize, const NY: usize, H> MixedLinearGaussian<P, K, NY, H> {
    /// `A^p` (p×p), eq. (5a).
    pub fn a_p(&self) -> &SMatrix<f64, P, P> {
        &self.a_p
    }

    /// `A^k` (p×k), eq. (5a).
    pub fn a_k(&self) -> &SMatrix<f64, P, K> {
        &self.a_k
    }

    /// `F^p` (k×p), eq. (5b).
    pub fn f_p(&self) -> &SMatrix<f64, K, P> {
        &self.f_p
    }

    /// `F^k` (k×k), eq. (5b).
    pub fn f_k(&self) -> &SMatrix<f64, K, K> {
        &self.f_k
    }

    /// `Q^p`, the covariance of `w^p`, eq. (5a).
    pub fn q_p(&self) -> &SMatrix<f64, P, P> {
        &self.q_p
    }

    /// `Q^k`, the covariance of `w^k`, eq. (5b).
    pub fn q_k(&self) -> &SMatrix<f64, K, K> {
        &self.q_k
    }

    /// `C_t` (ny×k), eq. (5c).
    pub fn c(&self) -> &SMatrix<f64, NY, K> {
        &self.c
    }

    /// The law of `x^p_0`, factored.
    pub fn x0_p(&self) -> &FactoredGaussian<P> {
        &self.x0_p
    }

    /// `x̄^k_0` of Alg. 1, step 1.
    pub fn x0_k(&self) -> &SVector<f64, K> {
        &self.x0_k
    }

    /// `P̄_0` of Alg. 1, step 1.
    pub fn p0_k(&self) -> &SMatrix<f64, K, K> {
        &self.p0_k
    }

    /// The law of `e_t`, `N(0, R)`, factored, eq. (5c).
    pub fn e(&self) -> &FactoredGaussian<NY> {
        &self.e
    }

    /// The measurement function `h_t`, eq. (5c).
    pub fn h(&self) -> &H {
        &self.h
    }
}

impl<const P: usize, const K: usize, const NY: usize, H: Measurement<P, NY>>
    MixedLinearGaussian<P, K, NY, H>
{
    /// Build and validate model (5): finite entries; `Q^p`, `R`, `P^p_0` positive definite;
    /// `Q^k`, `P̄_0` symmetric positive definite (when `k > 0`).
    ///
    /// # Errors
    /// [`MpfError::Core`] naming the matrix at fault.
    pub fn new(m: Model5Matrices<P, K, NY>, h: H) -> Result<Self> {
        for (what, v) in [
            ("A^p", m.a_p.as_slice()),
            ("A^k", m.a_k.as_slice()),
            ("F^p", m.f_p.as_slice()),
            ("F^k", m.f_k.as_slice()),
            ("C_t", m.c.as_slice()),
            ("x̄^k_0", m.x0_k.as_slice()),
        ] {
            check_finite(what, v)?;
        }
        FactoredGaussian::new("Q^p", SVector::<f64, P>::zeros(), m.q_p)?;
        if K > 0 {
            FactoredGaussian::new("Q^k", SVector::<f64, K>::zeros(), m.q_k)?;
            FactoredGaussian::new("P̄_0", m.x0_k, m.p0_k)?;
        }
        let e = FactoredGaussian::new("R", SVector::zeros(), m.r)?;
        let x0_p = FactoredGaussian::new("P^p_0", m.x0_p, m.p0_p)?;
        Ok(Self {
            a_p: m.a_p,
            a_k: m.a_k,
            f_p: m.f_p,
            f_k: m.f_k,
            q_p: m.q_p,
            q_k: m.q_k,
            c: m.c,
            e,
            x0_p,
            x0_k: m.x0_k,
            p0_k: m.p0_k,
            h,
        })
    }

    /// Whether `C_t = 0`, so Alg. 1's shared Riccati recursion applies.
    pub fn c_is_zero(&self) -> bool {
        self.c.iter().all(|&v| v == 0.0)
    }

    /// `R`.
    pub fn r(&self) -> &SMatrix<f64, NY, NY> {
        &self.e.cov
    }
}

/// `½ log det(2π L Lᵀ)`.
pub(crate) fn half_log_det_2pi<const D: usize>(l: &SMatrix<f64, D, D>) -> f64 {
    let log_diag: f64 = (0..D).map(|i| l[(i, i)].ln()).sum();
    log_diag + 0.5 * D as f64 * LN_2PI
}

/// Check an observation sequence: finite values. Returns the number of observed steps.
///
/// # Errors
/// [`MpfError::NonFiniteObservation`] at the first bad value.
pub fn check_observations<const NY: usize>(ys: &[Option<SVector<f64, NY>>]) -> Result<usize> {
    let mut n = 0;
    for (t, y) in ys.iter().enumerate() {
        if let Some(y) = y {
            if let Some((index, &value)) = y.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(MpfError::NonFiniteObservation { t, index, value });
            }
            n += 1;
        }
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The getters give back what was built, and each factor belongs to its covariance:
    /// `L Lᵀ` is the covariance it was computed from.
    #[test]
    fn factors_belong_to_their_covariances() {
        let q_p = SMatrix::<f64, 2, 2>::new(2.0, 0.5, 0.5, 1.0);
        let r = SMatrix::<f64, 1, 1>::new(0.25);
        let p0_p = SMatrix::<f64, 2, 2>::new(4.0, -1.0, -1.0, 3.0);
        let m = Model5Matrices::<2, 1, 1> {
            a_p: SMatrix::identity(),
            a_k: SMatrix::from_element(0.1),
            f_p: SMatrix::zeros(),
            f_k: SMatrix::identity(),
            q_p,
            q_k: SMatrix::identity(),
            c: SMatrix::zeros(),
            r,
            x0_p: SVector::<f64, 2>::new(1.0, -1.0),
            p0_p,
            x0_k: SVector::zeros(),
            p0_k: SMatrix::identity(),
        };
        let h = LinearMeasurement {
            h: SMatrix::<f64, 1, 2>::new(1.0, 0.0),
        };
        let model = MixedLinearGaussian::new(m, h).unwrap();
        assert_eq!(model.q_p(), &q_p);
        assert_eq!(model.r(), &r);
        assert_eq!(model.a_k(), &SMatrix::<f64, 2, 1>::from_element(0.1));
        assert_eq!(model.x0_p().mean(), &SVector::<f64, 2>::new(1.0, -1.0));
        assert_eq!(model.x0_p().cov(), &p0_p);
        let l = model.x0_p().chol();
        assert!((l * l.transpose() - p0_p).amax() < 1e-12);
        let l = model.e().chol();
        assert!((l * l.transpose() - r).amax() < 1e-12);
        // A covariance that is not positive definite is refused, naming it.
        let bad = Model5Matrices {
            q_p: SMatrix::<f64, 2, 2>::new(1.0, 2.0, 2.0, 1.0),
            ..Model5Matrices {
                a_p: SMatrix::identity(),
                a_k: SMatrix::zeros(),
                f_p: SMatrix::zeros(),
                f_k: SMatrix::identity(),
                q_p,
                q_k: SMatrix::identity(),
                c: SMatrix::zeros(),
                r,
                x0_p: SVector::zeros(),
                p0_p,
                x0_k: SVector::zeros(),
                p0_k: SMatrix::identity(),
            }
        };
        let h = LinearMeasurement {
            h: SMatrix::<f64, 1, 2>::new(1.0, 0.0),
        };
        let e = MixedLinearGaussian::<2, 1, 1, _>::new(bad, h).unwrap_err();
        assert!(
            matches!(
                e,
                MpfError::Core(CoreError::NotPositiveDefinite { what: "Q^p", .. })
            ),
            "{e}"
        );
    }
}
