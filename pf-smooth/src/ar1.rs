//! The noisy AR(1) model of Section 5: its EM statistics `τ_{n,1…4}`, the M-step
//! (10)–(12) and the score by Fisher's identity.
//!
//! `X_{k+1} = φ X_k + σ U_k`, `Y_k = X_k + ρ V_k`, with the diffuse (flat) prior on `X_0`, so
//! that the first filtering law is `N(Y_0, ρ²)`. The model itself is
//! [`pf_core::models::NoisyAr1`]; [`Theta::model`] builds it with that prior, to be filtered
//! with `y_0` missing (it is already in the prior).

use crate::error::{Result, SmoothError};
use crate::functional::AdditiveFunctional;
use pf_core::models::NoisyAr1;
use pf_core::params::{finite, positive};
use serde::{Deserialize, Serialize};

/// The parameter `θ = (φ, σ², ρ²)`, in the variances the EM updates produce.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Theta {
    /// φ, the autoregression coefficient.
    pub phi: f64,
    /// σ², the state noise variance.
    pub sigma2: f64,
    /// ρ², the observation noise variance.
    pub rho2: f64,
}

impl Theta {
    /// `θ` from the standard deviations σ and ρ, as the paper and the CLI give them.
    ///
    /// # Errors
    /// φ not finite, or σ, ρ not positive and finite.
    pub fn from_std(phi: f64, sigma: f64, rho: f64) -> Result<Self> {
        let t = Theta {
            phi,
            sigma2: sigma * sigma,
            rho2: rho * rho,
        };
        finite("phi", phi)?;
        positive("sigma", sigma)?;
        positive("rho", rho)?;
        t.validate()?;
        Ok(t)
    }

    /// The data-generating parameter of Section 5: φ = 0.98, σ = 0.2, ρ = 1.
    pub fn paper_truth() -> Self {
        Theta {
            phi: 0.98,
            sigma2: 0.04,
            rho2: 1.0,
        }
    }

    /// The current estimate of Figs. 2–3: φ = 0.8, σ = 0.5, ρ = 2.
    pub fn paper_start() -> Self {
        Theta {
            phi: 0.8,
            sigma2: 0.25,
            rho2: 4.0,
        }
    }

    /// Check φ finite and σ², ρ² positive and finite.
    ///
    /// # Errors
    /// [`SmoothError::Param`] naming the parameter.
    pub fn validate(&self) -> Result<()> {
        finite("phi", self.phi)?;
        positive("sigma2", self.sigma2)?;
        positive("rho2", self.rho2)?;
        Ok(())
    }

    /// The model at `θ` with the diffuse prior, `X_0 ~ N(y_0, ρ²)` (filter it with `y_0`
    /// missing). φ need not lie in (−1, 1): no stationary law is used.
    ///
    /// # Errors
    /// As [`validate`](Self::validate), or a non-finite `y0`.
    pub fn model(&self, y0: f64) -> Result<NoisyAr1> {
        self.validate()?;
        let rho = self.rho2.sqrt();
        Ok(NoisyAr1::with_prior(self.phi, self.sigma2.sqrt(), rho, 0.0, rho)?.diffuse(y0)?)
    }
}

/// Observations `Y_0, …, Y_n` (n ≥ 1), checked finite.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Ar1Data {
    y: Vec<f64>,
}

impl Ar1Data {
    /// Check and wrap `Y_0…Y_n`.
    ///
    /// # Errors
    /// Fewer than 2 values ([`SmoothError::TooFewObservations`]) or a NaN/infinite one
    /// ([`SmoothError::NonFiniteObservation`] with its index).
    pub fn new(y: Vec<f64>) -> Result<Self> {
        if y.len() < 2 {
            return Err(SmoothError::TooFewObservations {
                got: y.len(),
                need: 2,
            });
        }
        if let Some((index, &value)) = y.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(SmoothError::NonFiniteObservation { index, value });
        }
        Ok(Ar1Data { y })
    }

    /// [`new`](Self::new) from a slice.
    ///
    /// # Errors
    /// As [`new`](Self::new).
    pub fn from_slice(y: &[f64]) -> Result<Self> {
        Self::new(y.to_vec())
    }

    /// `n`: the index of the last observation (there are n + 1).
    pub fn n(&self) -> usize {
        self.y.len() - 1
    }

    /// `Y_0…Y_n`.
    pub fn y(&self) -> &[f64] {
        &self.y
    }

    /// The first `n + 1` observations `Y_0…Y_n`.
    ///
    /// # Errors
    /// `n` = 0 or beyond the data.
    pub fn prefix(&self, n: usize) -> Result<Self> {
        if n + 1 > self.y.len() {
            return Err(SmoothError::TooFewObservations {
                got: self.y.len(),
                need: n + 1,
            });
        }
        Self::new(self.y[..=n].to_vec())
    }

    /// The sequence to filter under the diffuse prior: `y_0` missing (it is in the prior),
    /// then `Some(Y_k)`.
    pub fn filter_input(&self) -> Vec<Option<f64>> {
        std::iter::once(None)
            .chain(self.y[1..].iter().copied().map(Some))
            .collect()
    }
}

/// The four statistics of Section 5 as one additive functional of dimension 4:
/// `Σ_{k=0}^{n−1} X_k²`, `Σ_{k=0}^{n−1} X_k X_{k+1}`, `Σ_{k=1}^n X_k²`, `Σ_{k=0}^n (Y_k − X_k)²`.
#[derive(Debug, Clone, Copy)]
pub struct Ar1Statistics<'a> {
    y: &'a [f64],
}

impl<'a> Ar1Statistics<'a> {
    /// The statistics of the data `y`.
    pub fn new(data: &'a Ar1Data) -> Self {
        Ar1Statistics { y: data.y() }
    }
}

impl AdditiveFunctional<f64> for Ar1Statistics<'_> {
    fn dim(&self) -> usize {
        4
    }

    fn initial(&self, x0: &f64, out: &mut [f64]) {
        let e = self.y[0] - x0;
        out[3] += e * e;
    }

    #[inline]
    fn increment(&self, k: usize, x_prev: &f64, x: &f64, out: &mut [f64]) {
        // A step beyond the data has no Y_k: NaN, which the estimate reports as an error.
        let y = self.y.get(k).copied().unwrap_or(f64::NAN);
        let e = y - x;
        out[0] += x_prev * x_prev;
        out[1] += x_prev * x;
        out[2] += x * x;
        out[3] += e * e;
    }

    /// `Σ_j β_j s(x_j, x) = (Σ β_j x_j², x Σ β_j x_j, x² Σ β_j, (Y_k − x)² Σ β_j)`: three
    /// sums over `j` instead of `N` terms of four components (`x_j` is finite, so a zero
    /// `β_j` adds nothing, as if skipped).
    #[inline]
    fn add_weighted_increments(
        &self,
        k: usize,
        x_prev: &[f64],
        beta: &[f64],
        x: &f64,
        _scratch: &mut [f64],
        out: &mut [f64],
    ) {
        let y = self.y.get(k).copied().unwrap_or(f64::NAN);
        // Four interleaved partial sums of each (lane `l` takes `j ≡ l mod 4`), added in
        // lane order at the end: the loop vectorises instead of waiting on each sum's
        // latency at every `j`.
        const L: usize = 4;
        let (mut sb, mut s1, mut s2) = ([0.0; L], [0.0; L], [0.0; L]);
        let m = beta.len().min(x_prev.len());
        let (bc, xc) = (beta[..m].chunks_exact(L), x_prev[..m].chunks_exact(L));
        let (b_tail, x_tail) = (bc.remainder(), xc.remainder());
        for (b, xj) in bc.zip(xc) {
            for l in 0..L {
                let bx = b[l] * xj[l];
                sb[l] += b[l];
                s1[l] += bx;
                s2[l] += bx * xj[l];
            }
        }
        for (l, (&b, &xj)) in b_tail.iter().zip(x_tail).enumerate() {
            let bx = b * xj;
            sb[l] += b;
            s1[l] += bx;
            s2[l] += bx * xj;
        }
        let lanes = |s: [f64; L]| (s[0] + s[1]) + (s[2] + s[3]);
        let (sb, s1, s2) = (lanes(sb), lanes(s1), lanes(s2));
        let e = y - x;
        out[0] += s2;
        out[1] += x * s1;
        out[2] += x * x * sb;
        out[3] += e * e * sb;
    }
}

/// Estimates of `τ_{n,1}, …, τ_{n,4}` for `Y_{0:n}`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SuffStats {
    /// n.
    pub n: usize,
    /// `[τ_{n,1}, τ_{n,2}, τ_{n,3}, τ_{n,4}]`.
    pub tau: [f64; 4],
}

impl SuffStats {
    /// From a 4-vector estimate.
    ///
    /// # Errors
    /// A vector that is not of length 4.
    pub fn from_slice(n: usize, v: &[f64]) -> Result<Self> {
        let tau: [f64; 4] = v
            .try_into()
            .map_err(|_| pf_core::CoreError::DimensionMismatch {
                what: "AR(1) statistics",
                expected: 4,
                got: v.len(),
            })?;
        Ok(SuffStats { n, tau })
    }

    /// The EM update, eqs. (10)–(12): `φ̂ = τ₂/τ₁`, `σ̂² = (τ₃ − φ̂ τ₂)/n`,
    /// `ρ̂² = τ₄/(n + 1)`.
    ///
    /// # Errors
    /// [`SmoothError::DegenerateUpdate`] if the result is not a valid parameter (`τ₁ = 0`,
    /// `σ̂² ≤ 0`, or a non-finite value).
    pub fn m_step(&self) -> Result<Theta> {
        let [t1, t2, t3, t4] = self.tau;
        let n = self.n as f64;
        let phi = t2 / t1;
        let sigma2 = (t3 - phi * t2) / n;
        let rho2 = t4 / (n + 1.0);
        let bad = |what, value: f64, ok: bool| {
            if ok && value.is_finite() {
                Ok(())
            } else {
                Err(SmoothError::DegenerateUpdate { what, value })
            }
        };
        bad("phi (eq. 10)", phi, true)?;
        bad("sigma2 (eq. 11)", sigma2, sigma2 > 0.0)?;
        bad("rho2 (eq. 12)", rho2, rho2 > 0.0)?;
        Ok(Theta { phi, sigma2, rho2 })
    }

    /// The score `∇ℓ_n(θ)` with respect to `(φ, σ², ρ²)` by Fisher's identity: the
    /// conditional expectation of the complete-data score, linear in the statistics:
    /// ```text
    /// ∂ℓ/∂φ  = (τ₂ − φ τ₁)/σ²
    /// ∂ℓ/∂σ² = −n/(2σ²) + (τ₃ − 2φ τ₂ + φ² τ₁)/(2σ⁴)
    /// ∂ℓ/∂ρ² = −(n + 1)/(2ρ²) + τ₄/(2ρ⁴)
    /// ```
    /// The statistics must have been computed at the same `θ`.
    pub fn score(&self, theta: &Theta) -> Theta {
        let [t1, t2, t3, t4] = self.tau;
        let n = self.n as f64;
        let Theta { phi, sigma2, rho2 } = *theta;
        Theta {
            phi: (t2 - phi * t1) / sigma2,
            sigma2: -n / (2.0 * sigma2)
                + (t3 - 2.0 * phi * t2 + phi * phi * t1) / (2.0 * sigma2 * sigma2),
            rho2: -(n + 1.0) / (2.0 * rho2) + t4 / (2.0 * rho2 * rho2),
        }
    }
}

/// Replicated values of the three parameters, one entry per replication; the JSON shape
/// `{"phi": [...], "sigma2": [...], "rho2": [...]}` of the CLI contract.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThetaSamples {
    /// φ per replication.
    pub phi: Vec<f64>,
    /// σ² per replication.
    pub sigma2: Vec<f64>,
    /// ρ² per replication.
    pub rho2: Vec<f64>,
}

impl ThetaSamples {
    /// Gather per-replication values.
    pub fn from_thetas(thetas: &[Theta]) -> Self {
        ThetaSamples {
            phi: thetas.iter().map(|t| t.phi).collect(),
            sigma2: thetas.iter().map(|t| t.sigma2).collect(),
            rho2: thetas.iter().map(|t| t.rho2).collect(),
        }
    }

    /// Number of replications.
    pub fn len(&self) -> usize {
        self.phi.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.phi.is_empty()
    }

    /// The three samples in the order (φ, σ², ρ²).
    pub fn columns(&self) -> [&[f64]; 3] {
        [&self.phi, &self.sigma2, &self.rho2]
    }

    /// The mean and sample standard deviation (divisor `R − 1`) of each of (φ, σ², ρ²) over
    /// the replications: an estimator's centre and spread.
    pub fn mean_and_sd(&self) -> [(f64, f64); 3] {
        self.columns().map(pf_core::mc::mean_and_sd)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three replications of (φ, σ², ρ²) = (1, 2, 3), (2, 4, 6), (3, 6, 9): means 2, 4, 6 and
    /// sample deviations 1, 2, 3 (divisor 2).
    #[test]
    fn samples_summarise_each_parameter() {
        let t = |a: f64| Theta {
            phi: a,
            sigma2: 2.0 * a,
            rho2: 3.0 * a,
        };
        let s = ThetaSamples::from_thetas(&[t(1.0), t(2.0), t(3.0)]);
        assert_eq!(
            s.columns(),
            [&[1.0, 2.0, 3.0][..], &[2.0, 4.0, 6.0], &[3.0, 6.0, 9.0]]
        );
        assert_eq!(s.mean_and_sd(), [(2.0, 1.0), (4.0, 2.0), (6.0, 3.0)]);
    }

    #[test]
    fn bad_parameters_and_data_are_errors_not_panics() {
        assert!(Theta::from_std(0.8, 0.0, 1.0).is_err());
        assert!(Theta::from_std(0.8, 0.5, -1.0).is_err());
        assert!(Theta::from_std(f64::NAN, 0.5, 1.0).is_err());
        assert!(matches!(
            Ar1Data::new(vec![1.0]),
            Err(SmoothError::TooFewObservations { got: 1, need: 2 })
        ));
        assert!(matches!(
            Ar1Data::new(vec![1.0, f64::NAN, 2.0]),
            Err(SmoothError::NonFiniteObservation { index: 1, .. })
        ));
        let degenerate = SuffStats {
            n: 2,
            tau: [0.0, 0.0, 1.0, 1.0],
        };
        assert!(matches!(
            degenerate.m_step(),
            Err(SmoothError::DegenerateUpdate { .. })
        ));
    }

    /// The closed form of `Σ_j β_j s(x_j, x)` is the sum of the terms (seven of them: a
    /// group of four lanes and a tail of three).
    #[test]
    fn weighted_increments_in_closed_form_are_the_sum_of_the_terms() {
        let data = Ar1Data::new(vec![0.3, -1.2, 0.8]).unwrap();
        let stats = Ar1Statistics::new(&data);
        let xs = [0.5, -2.0, 1.5, 0.0, 0.9, -0.3, 2.2];
        let beta = [0.25, 0.0, 0.3, 0.15, 0.1, 0.05, 0.15];
        let x = -0.7;
        let mut direct = [1.0, 2.0, 3.0, 4.0];
        for (xj, b) in xs.iter().zip(beta) {
            let mut s = [0.0; 4];
            stats.increment(2, xj, &x, &mut s);
            for (d, v) in direct.iter_mut().zip(s) {
                *d += b * v;
            }
        }
        let mut closed = [1.0, 2.0, 3.0, 4.0];
        stats.add_weighted_increments(2, &xs, &beta, &x, &mut [0.0; 16], &mut closed);
        for (a, b) in closed.iter().zip(direct) {
            assert!((a - b).abs() < 1e-14, "{closed:?} vs {direct:?}");
        }
    }

    #[test]
    fn m_step_and_score_by_hand() {
        // τ = (2, 1, 3, 6), n = 2: φ̂ = 1/2, σ̂² = (3 − 1/2)/2 = 5/4, ρ̂² = 6/3 = 2.
        let s = SuffStats {
            n: 2,
            tau: [2.0, 1.0, 3.0, 6.0],
        };
        let t = s.m_step().unwrap();
        assert_eq!((t.phi, t.sigma2, t.rho2), (0.5, 1.25, 2.0));
        // The score vanishes at the M-step's own fixed point.
        let g = s.score(&t);
        assert!(g.phi.abs() < 1e-12 && g.sigma2.abs() < 1e-12 && g.rho2.abs() < 1e-12);
    }
}
