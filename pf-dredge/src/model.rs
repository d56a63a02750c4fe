//! The estimator's state-space model, eq. (13): the Euler-discretised volume and mass balances
//! (9)–(10), augmented with random walks (11)–(12) for `Q_o` and `ρ_o`.
//!
//! ```text
//! x = (V_t, m_t, Q_o, ρ_o),  u = (Q_i, ρ_i),  y = (V_t, m_t)
//! x₁' = x₁ + T_s (u₁ − x₃)        + ε_x1
//! x₂' = x₂ + T_s (u₁ u₂ − x₃ x₄)  + ε_x2
//! x₃' = x₃ + ε_x3
//! x₄' = x₄ + ε_x4
//! y   = (x₁, x₂) + ε_y
//! ```
//! with zero-mean Gaussian `ε_x`, `ε_y` of standard deviations `σ(ε_x)`, `σ(ε_y)`. The model
//! avoids the uncertain overflow and sedimentation laws (4)–(8) altogether.
//!
//! Time convention (pf-core's): the input of step `k` is the one that drives `x_{k−1} → x_k`,
//! i.e. `u_{k−1}` held over `[t_{k−1}, t_k)`, and it carries that interval's length as its
//! `T_s`, so irregular logs are handled.

use crate::error::{DredgeError, Result};
use pf_core::StateSpaceModel;
use pf_core::gaussian::LN_2PI;
use pf_core::params::{ParamError, finite, non_negative, positive};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

/// `x = (V_t, m_t, Q_o, ρ_o)`.
pub type State = [f64; 4];

/// Index of `V_t` in [`State`].
pub const V_T: usize = 0;
/// Index of `m_t` in [`State`].
pub const M_T: usize = 1;
/// Index of `Q_o` in [`State`].
pub const Q_O: usize = 2;
/// Index of `ρ_o` in [`State`].
pub const RHO_O: usize = 3;

/// The input `u_k = (Q_i, ρ_i)` and the period `T_s` over which it acts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Inflow {
    /// `Q_i` (m³/s).
    pub q_i: f64,
    /// `ρ_i` (kg/m³).
    pub rho_i: f64,
    /// `T_s` (s).
    pub t_s: f64,
}

/// The measurement `y_k = (V_t, m_t)`; a `None` component is missing and not weighed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Measurement {
    /// Measured `V_t` (m³).
    pub v_t: Option<f64>,
    /// Measured `m_t` (kg).
    pub m_t: Option<f64>,
}

/// The prior `p(x_0)`, which the paper does not give: independent Gaussians, with `V_t` and
/// `m_t` centred on the first measurement with the measurement's standard deviation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Prior {
    /// Mean of `Q_o,0` (m³/s). A cycle starts without overflow.
    pub q_o_mean: f64,
    /// Standard deviation of `Q_o,0` (m³/s).
    pub q_o_std: f64,
    /// Mean of `ρ_o,0` (kg/m³): sea water.
    pub rho_o_mean: f64,
    /// Standard deviation of `ρ_o,0` (kg/m³).
    pub rho_o_std: f64,
}

impl Default for Prior {
    fn default() -> Self {
        Prior {
            q_o_mean: 0.0,
            q_o_std: 1.0,
            rho_o_mean: 1025.0,
            rho_o_std: 50.0,
        }
    }
}

/// The model (13) with its noise levels and prior.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OverflowModel {
    /// `σ(ε_x)` for `(V_t, m_t, Q_o, ρ_o)`.
    pub sigma_x: [f64; 4],
    /// `σ(ε_y)` for `(V_t, m_t)`.
    pub sigma_y: [f64; 2],
    /// Mean of `x_0`.
    pub x0_mean: State,
    /// Standard deviation of `x_0` (independent components).
    pub x0_std: State,
    /// `T_s` used when a step has no input (s).
    pub t_s: f64,
}

impl OverflowModel {
    /// The model with prior centred on a first measurement `(V_t,0, m_t,0)`.
    ///
    /// # Errors
    /// [`DredgeError::Param`] for a negative or non-finite `σ(ε_x)`, a
    /// non-positive `σ(ε_y)` or `T_s`, or a bad prior.
    pub fn new(
        sigma_x: [f64; 4],
        sigma_y: [f64; 2],
        prior: &Prior,
        y0: (f64, f64),
        t_s: f64,
    ) -> Result<Self> {
        for (name, s) in [
            "sigma_x[V_t]",
            "sigma_x[m_t]",
            "sigma_x[Q_o]",
            "sigma_x[rho_o]",
        ]
        .into_iter()
        .zip(sigma_x)
        {
            non_negative(name, s)?;
        }
        positive("sigma_y[V_t]", sigma_y[0])?;
        positive("sigma_y[m_t]", sigma_y[1])?;
        positive("T_s", t_s)?;
        prior.validate()?;
        for (name, v) in [("V_t,0", y0.0), ("m_t,0", y0.1)] {
            if !v.is_finite() {
                return Err(DredgeError::Param(ParamError {
                    name,
                    value: v,
                    reason: "the first measurement must be finite",
                }));
            }
        }
        Ok(OverflowModel {
            sigma_x,
            sigma_y,
            x0_mean: [y0.0, y0.1, prior.q_o_mean, prior.rho_o_mean],
            x0_std: [sigma_y[0], sigma_y[1], prior.q_o_std, prior.rho_o_std],
            t_s,
        })
    }

    /// The noise-free part of (13): `f(x, u)`.
    #[inline]
    pub fn drift(x: &State, u: &Inflow) -> State {
        [
            x[V_T] + u.t_s * (u.q_i - x[Q_O]),
            x[M_T] + u.t_s * (u.q_i * u.rho_i - x[Q_O] * x[RHO_O]),
            x[Q_O],
            x[RHO_O],
        ]
    }
}

impl Prior {
    /// Check the prior's numbers.
    ///
    /// # Errors
    /// [`DredgeError::Param`] naming the field.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("prior.q_o_mean", self.q_o_mean),
            ("prior.rho_o_mean", self.rho_o_mean),
        ] {
            finite(name, v)?;
        }
        non_negative("prior.q_o_std", self.q_o_std)?;
        non_negative("prior.rho_o_std", self.rho_o_std)?;
        Ok(())
    }
}

fn gauss_log_pdf(x: f64, mean: f64, sigma: f64) -> f64 {
    let z = (x - mean) / sigma;
    -0.5 * z * z - sigma.ln() - 0.5 * LN_2PI
}

impl StateSpaceModel for OverflowModel {
    type State = State;
    type Obs = Measurement;
    type Input = Inflow;

    /// `x_0 ~ N(x0_mean, diag(x0_std²))` (Alg. 1, "Initialize").
    fn sample_initial<R: Rng + ?Sized>(&self, rng: &mut R) -> State {
        let mut x = self.x0_mean;
        for (xi, s) in x.iter_mut().zip(self.x0_std) {
            let z: f64 = StandardNormal.sample(rng);
            *xi += s * z;
        }
        x
    }

    /// `x_k ~ p(x_k | x_{k−1})` of eq. (13); without an input, `Q_i = 0` over the default `T_s`.
    fn sample_transition<R: Rng + ?Sized>(
        &self,
        _t: usize,
        x_prev: &State,
        u: Option<&Inflow>,
        rng: &mut R,
    ) -> State {
        let none = Inflow {
            q_i: 0.0,
            rho_i: 0.0,
            t_s: self.t_s,
        };
        let mut x = Self::drift(x_prev, u.unwrap_or(&none));
        for (xi, s) in x.iter_mut().zip(self.sigma_x) {
            if s > 0.0 {
                let z: f64 = StandardNormal.sample(rng);
                *xi += s * z;
            }
        }
        x
    }

    /// `log p(y_k | x_k)`: Gaussian in each present component of `y = (V_t, m_t)`.
    fn log_likelihood(&self, _t: usize, x: &State, y: &Measurement) -> f64 {
        let mut ll = 0.0;
        if let Some(v) = y.v_t {
            ll += gauss_log_pdf(v, x[V_T], self.sigma_y[0]);
        }
        if let Some(m) = y.m_t {
            ll += gauss_log_pdf(m, x[M_T], self.sigma_y[1]);
        }
        ll
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pf_core::mc::stream_rng;

    fn model() -> OverflowModel {
        OverflowModel::new(
            [0.0, 3000.0, 0.2, 5.0],
            [10.0, 12000.0],
            &Prior::default(),
            (1000.0, 1.0e6),
            5.0,
        )
        .unwrap()
    }

    #[test]
    fn transition_mean_and_spread_follow_eq_13() {
        let m = model();
        let x = [5000.0, 6.0e6, 7.0, 1100.0];
        let u = Inflow {
            q_i: 8.0,
            rho_i: 1300.0,
            t_s: 5.0,
        };
        let f = OverflowModel::drift(&x, &u);
        assert_eq!(
            f,
            [
                5000.0 + 5.0,
                6.0e6 + 5.0 * (8.0 * 1300.0 - 7.0 * 1100.0),
                7.0,
                1100.0
            ]
        );
        // σ(ε_x1) = 0: the volume moves deterministically given Q_o.
        let mut rng = stream_rng(0, 0);
        let r = 20_000;
        let mut sum = [0.0; 4];
        let mut sum2 = [0.0; 4];
        for _ in 0..r {
            let x1 = m.sample_transition(1, &x, Some(&u), &mut rng);
            assert_eq!(x1[V_T], f[V_T]);
            for i in 0..4 {
                sum[i] += x1[i] - f[i];
                sum2[i] += (x1[i] - f[i]).powi(2);
            }
        }
        for i in 1..4 {
            let s = m.sigma_x[i];
            // Mean of R draws: |mean| < 5 σ/√R; the variance estimate's relative sd is √(2/R),
            // so 5·√(2/20000) = 5 % bounds it.
            assert!(
                (sum[i] / r as f64).abs() < 5.0 * s / (r as f64).sqrt(),
                "mean {i}"
            );
            let sd = (sum2[i] / r as f64).sqrt();
            assert!((sd / s - 1.0).abs() < 0.05, "sd {i}: {sd}");
        }
    }

    #[test]
    fn likelihood_skips_missing_components() {
        let m = model();
        let x = [1000.0, 1.0e6, 0.0, 1025.0];
        let both = m.log_likelihood(
            0,
            &x,
            &Measurement {
                v_t: Some(1010.0),
                m_t: Some(1.0e6),
            },
        );
        let v_only = m.log_likelihood(
            0,
            &x,
            &Measurement {
                v_t: Some(1010.0),
                m_t: None,
            },
        );
        let none = m.log_likelihood(
            0,
            &x,
            &Measurement {
                v_t: None,
                m_t: None,
            },
        );
        assert_eq!(none, 0.0);
        let expected_v = -0.5 - 10f64.ln() - 0.5 * (2.0 * std::f64::consts::PI).ln();
        assert!((v_only - expected_v).abs() < 1e-12);
        let expected_m = -12000f64.ln() - 0.5 * (2.0 * std::f64::consts::PI).ln();
        assert!((both - expected_v - expected_m).abs() < 1e-12);
    }

    #[test]
    fn bad_noise_levels_are_rejected() {
        let p = Prior::default();
        assert!(
            OverflowModel::new([0.0, -1.0, 0.2, 5.0], [10.0, 1.0], &p, (0.0, 0.0), 5.0).is_err()
        );
        assert!(OverflowModel::new([0.0, 1.0, 0.2, 5.0], [0.0, 1.0], &p, (0.0, 0.0), 5.0).is_err());
        assert!(
            OverflowModel::new([0.0, 1.0, 0.2, 5.0], [1.0, 1.0], &p, (f64::NAN, 0.0), 5.0).is_err()
        );
    }
}
