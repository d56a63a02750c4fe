//! The noisy AR(1) model of Cappé & Moulines, Section 5.

use crate::error::Result;
use crate::filter::{BatchTransitionDensity, Cols, ScalarModel};
use crate::gaussian::LN_2PI;
use crate::model::{StateSpaceModel, TransitionDensity};
use crate::params::{self, ParamError, positive};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

/// `X_{k+1} = φ X_k + σ U_k`, `Y_k = X_k + ρ V_k`, with `U_k, V_k ~ N(0, 1)` and
/// `X_0 ~ N(m_0, s_0²)`.
///
/// The default initial law is the stationary one, `N(0, σ²/(1 − φ²))` when `|φ| < 1`.
/// Cappé & Moulines' diffuse prior (`φ_0 = N(Y_0, ρ²)`) is [`NoisyAr1::diffuse`]; filter
/// with `y_0` missing then, since `Y_0` is already in the prior.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoisyAr1 {
    phi: f64,
    sigma: f64,
    rho: f64,
    m0: f64,
    s0: f64,
    /// `1/ρ` and `−log ρ − ½ log 2π`, so that the likelihood costs no division or logarithm.
    inv_rho: f64,
    log_norm_g: f64,
    /// `1/σ` and `−log σ − ½ log 2π`, the same for the transition density (which forward
    /// smoothing evaluates N² times a step).
    inv_sigma: f64,
    log_norm_f: f64,
}

impl NoisyAr1 {
    /// The model with its stationary initial law (needs `|φ| < 1`).
    ///
    /// # Errors
    /// σ or ρ not positive, or φ not in (−1, 1).
    pub fn new(phi: f64, sigma: f64, rho: f64) -> Result<Self> {
        if phi.is_nan() || phi.abs() >= 1.0 {
            return Err(ParamError::new(
                "phi",
                phi,
                "must lie in (-1, 1) for the stationary initial law; use with_initial",
            )
            .into());
        }
        let model = Self::build(phi, positive("sigma", sigma)?, positive("rho", rho)?);
        Ok(NoisyAr1 {
            s0: sigma / (1.0 - phi * phi).sqrt(),
            ..model
        })
    }

    /// Any finite φ (no stationarity needed) with the initial law `N(m0, s0²)`; for
    /// parameter searches such as EM, whose iterates may leave (−1, 1).
    ///
    /// # Errors
    /// φ or `m0` not finite, or σ, ρ, `s0` not positive.
    pub fn with_prior(phi: f64, sigma: f64, rho: f64, m0: f64, s0: f64) -> Result<Self> {
        params::finite("phi", phi)?;
        Self::build(phi, positive("sigma", sigma)?, positive("rho", rho)?).with_initial(m0, s0)
    }

    /// Validated parameters in, cached constants out; initial law `N(0, 1)`.
    fn build(phi: f64, sigma: f64, rho: f64) -> Self {
        NoisyAr1 {
            phi,
            sigma,
            rho,
            m0: 0.0,
            s0: 1.0,
            inv_rho: 1.0 / rho,
            log_norm_g: -rho.ln() - 0.5 * LN_2PI,
            inv_sigma: 1.0 / sigma,
            log_norm_f: -sigma.ln() - 0.5 * LN_2PI,
        }
    }

    /// φ, the autoregression coefficient.
    pub fn phi(&self) -> f64 {
        self.phi
    }

    /// σ, the state noise standard deviation.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// ρ, the observation noise standard deviation.
    pub fn rho(&self) -> f64 {
        self.rho
    }

    /// `m_0`, the initial mean.
    pub fn m0(&self) -> f64 {
        self.m0
    }

    /// `s_0`, the initial standard deviation.
    pub fn s0(&self) -> f64 {
        self.s0
    }

    /// Replace the initial law by `N(m0, s0²)`.
    ///
    /// # Errors
    /// `s0` not positive, or `m0` not finite.
    pub fn with_initial(mut self, m0: f64, s0: f64) -> Result<Self> {
        self.m0 = params::finite("m0", m0)?;
        self.s0 = positive("s0", s0)?;
        Ok(self)
    }

    /// Cappé & Moulines' diffuse prior: `X_0 ~ N(y_0, ρ²)`.
    ///
    /// # Errors
    /// As [`with_initial`](Self::with_initial).
    pub fn diffuse(self, y0: f64) -> Result<Self> {
        let rho = self.rho;
        self.with_initial(y0, rho)
    }

    /// Simulate `x_0…x_n` and `y_0…y_n` (n + 1 of each).
    pub fn simulate<R: Rng + ?Sized>(&self, n: usize, rng: &mut R) -> (Vec<f64>, Vec<f64>) {
        let mut xs = Vec::with_capacity(n + 1);
        let mut ys = Vec::with_capacity(n + 1);
        let mut x = self.sample_initial(rng);
        for k in 0..=n {
            if k > 0 {
                x = self.sample_transition(k, &x, None, rng);
            }
            let v: f64 = StandardNormal.sample(rng);
            xs.push(x);
            ys.push(x + self.rho * v);
        }
        (xs, ys)
    }
}

impl StateSpaceModel for NoisyAr1 {
    type State = f64;
    type Obs = f64;
    type Input = ();

    fn sample_initial<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        let z: f64 = StandardNormal.sample(rng);
        self.m0 + self.s0 * z
    }

    #[inline]
    fn sample_transition<R: Rng + ?Sized>(
        &self,
        _t: usize,
        x_prev: &f64,
        _u: Option<&()>,
        rng: &mut R,
    ) -> f64 {
        let z: f64 = StandardNormal.sample(rng);
        self.phi * x_prev + self.sigma * z
    }

    #[inline]
    fn log_likelihood(&self, _t: usize, x: &f64, y: &f64) -> f64 {
        let e = (y - x) * self.inv_rho;
        self.log_norm_g - 0.5 * e * e
    }
}

impl TransitionDensity for NoisyAr1 {
    /// Inlined: forward smoothing evaluates it N² times a step (a call per pair was 12 % of
    /// its time).
    #[inline]
    fn log_transition_density(&self, _t: usize, x_prev: &f64, x: &f64, _u: Option<&()>) -> f64 {
        let e = (x - self.phi * x_prev) * self.inv_sigma;
        self.log_norm_f - 0.5 * e * e
    }
}

impl ScalarModel for NoisyAr1 {
    #[inline]
    fn initial_from_normal(&self, z: f64) -> f64 {
        self.m0 + self.s0 * z
    }

    #[inline]
    fn transition_from_normal(&self, _t: usize, x_prev: f64, z: f64) -> f64 {
        self.phi * x_prev + self.sigma * z
    }

    #[inline]
    fn log_likelihood_scalar(&self, t: usize, x: f64, y: f64) -> f64 {
        StateSpaceModel::log_likelihood(self, t, &x, &y)
    }
}

/// `log f(x | x_prev)` over a chunk, for guided batch proposals.
impl BatchTransitionDensity for NoisyAr1 {
    #[inline]
    fn add_log_transition(
        &self,
        _t: usize,
        _u: &(),
        parents: Cols<'_>,
        x: Cols<'_>,
        out: &mut [f64],
    ) {
        for ((o, &x), &xp) in out.iter_mut().zip(x.col(0)).zip(parents.col(0)) {
            let e = (x - self.phi * xp) * self.inv_sigma;
            *o += self.log_norm_f - 0.5 * e * e;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_parameters() {
        assert!(NoisyAr1::new(0.98, 0.0, 1.0).is_err());
        assert!(NoisyAr1::new(0.98, 0.2, -1.0).is_err());
        assert!(NoisyAr1::new(1.0, 0.2, 1.0).is_err());
        assert!(
            NoisyAr1::new(0.5, 0.2, 1.0)
                .unwrap()
                .with_initial(0.0, 0.0)
                .is_err()
        );
        assert!(NoisyAr1::with_prior(1.2, 0.2, 1.0, 0.0, 1.0).is_ok());
        assert!(NoisyAr1::with_prior(f64::NAN, 0.2, 1.0, 0.0, 1.0).is_err());
        assert!(NoisyAr1::with_prior(0.5, 0.2, 0.0, 0.0, 1.0).is_err());
    }

    #[test]
    fn densities_are_normal() {
        let m = NoisyAr1::new(0.5, 2.0, 3.0).unwrap();
        // N(y; x, ρ²) at y = x: −½ log(2π) − log ρ.
        assert!((m.log_likelihood(0, &1.0, &1.0) - (-0.5 * LN_2PI - 3f64.ln())).abs() < 1e-14);
        let lf = m.log_transition_density(1, &2.0, &3.0, None);
        let e: f64 = (3.0 - 1.0) / 2.0;
        assert!((lf - (-0.5 * (e * e + LN_2PI) - 2f64.ln())).abs() < 1e-14);
    }
}
