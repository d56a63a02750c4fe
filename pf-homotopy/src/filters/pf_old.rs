//! The PF benchmark: importance density the linearised optimal one (Doucet, Godsill &
//! Andrieu 2000, §II.D.2), used through pf-core's [`Guided`] mutation.
//!
//! For `x_k | x_{k−1} ~ N(F x_{k−1}, Q)` and `y_k = h(x_k) + v`, linearising `h` at
//! `x̄ = F x_{k−1}` (`H = ∂h/∂x(x̄)`, a 1 × 4 row) gives the Gaussian proposal
//! `q(x | x_{k−1}, y_k) = N(x; x̄ + K e, Σ*)` with `e = wrap_angle(y_k − h(x̄))`,
//! `S = H Q Hᵀ + σ²`, `K = Q Hᵀ / S`, `Σ* = Q − K S Kᵀ` and `Σ*⁻¹ = Q⁻¹ + HᵀH/σ²`. The weight
//! is the exact `g(y_k|x) f(x|x_{k−1}) / q(x|x_{k−1}, y_k)` for the nonlinear model.
//!
//! Sampling uses the Kalman form of the draw (Matheron's rule): `x₀ = x̄ + L_Q z`,
//! `x = x₀ + K(e − H(x₀ − x̄) − σ ε)` is exactly `N(x̄ + K e, Σ*)`, so no per-particle
//! Cholesky factor is needed; `log det Σ* = log det Q − log(S/σ²)` (determinant lemma).
//!
//! ## References
//! - A. Doucet, S. Godsill, C. Andrieu, "On sequential Monte Carlo sampling methods for
//!   Bayesian filtering", *Statistics and Computing* 10(3), 2000.

use nalgebra::{Matrix4, RowVector4, Vector4};
use pf_core::filter::{EssThreshold, FilterConfig, Guided, ParticleFilter, ResamplePolicy};
use pf_core::resample::Resampler;
use pf_core::{Proposal, StateSpaceModel, StepAt, TransitionDensity};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::error::{HomotopyError, Result, check_data};
use crate::model::bearing;
use crate::model::{PriorConfig, Realisation, ScenarioConfig, State};
use crate::prior::sample_prior;
use pf_core::gaussian::LN_2PI;
use pf_core::geometry::wrap_angle;
use pf_core::params::ParamError;

/// The BOT state-space model for pf-core: `t = 0` is sampling instant `k = 1`, whose
/// bearing `y_1` builds the prior (so the filter is given `None` there).
#[derive(Debug, Clone)]
pub struct OldBotModel {
    f: Matrix4<f64>,
    lq: Matrix4<f64>,
    q: Matrix4<f64>,
    q_inv: Matrix4<f64>,
    ln_det_q: f64,
    sigma: f64,
    ln_sigma: f64,
    /// Observer positions ρ at `t = 0, 1, …`.
    observer: Vec<[f64; 2]>,
    prior: PriorConfig,
    y1: f64,
}

impl OldBotModel {
    /// The model for a scenario, observer positions `ρ_1, …, ρ_K` and first bearing `y1`.
    ///
    /// # Errors
    /// An invalid scenario, or non-finite inputs.
    pub fn new(scenario: &ScenarioConfig, observer: Vec<[f64; 2]>, y1: f64) -> Result<Self> {
        scenario.validate()?;
        check_data("bearing", 1, y1)?;
        let q = scenario.q_matrix();
        let chol = q.cholesky().ok_or(HomotopyError::Param(ParamError {
            name: "q",
            value: scenario.q,
            reason: "Q must be positive definite",
        }))?;
        let lq = chol.l();
        let ln_det_q = 2.0 * (0..4).map(|i| lq[(i, i)].ln()).sum::<f64>();
        Ok(Self {
            f: scenario.f(),
            q_inv: chol.inverse(),
            lq,
            q,
            ln_det_q,
            sigma: scenario.sigma(),
            ln_sigma: scenario.sigma().ln(),
            observer,
            prior: scenario.prior,
            y1,
        })
    }

    fn rho(&self, t: usize) -> [f64; 2] {
        self.observer[t.min(self.observer.len() - 1)]
    }

    /// The linearisation at `x̄ = F x_prev`: `(x̄, H, e, S)`.
    fn linearise(&self, t: usize, x_prev: &State, y: f64) -> (State, RowVector4<f64>, f64, f64) {
        let xb = self.f * x_prev;
        let rho = self.rho(t);
        let (dx, dy) = (xb[0] - rho[0], xb[1] - rho[1]);
        let r2 = dx * dx + dy * dy;
        let h = RowVector4::new(-dy / r2, dx / r2, 0.0, 0.0);
        let e = wrap_angle(y - dy.atan2(dx));
        let s = (h * self.q * h.transpose())[(0, 0)] + self.sigma * self.sigma;
        (xb, h, e, s)
    }
}

impl StateSpaceModel for OldBotModel {
    type State = State;
    type Obs = f64;
    type Input = ();

    fn sample_initial<R: Rng + ?Sized>(&self, rng: &mut R) -> State {
        sample_prior(&self.prior, self.y1, self.sigma, self.rho(0), rng)
    }

    fn sample_transition<R: Rng + ?Sized>(
        &self,
        _t: usize,
        x_prev: &State,
        _u: Option<&()>,
        rng: &mut R,
    ) -> State {
        let z = Vector4::from_fn(|_, _| StandardNormal.sample(rng));
        self.f * x_prev + self.lq * z
    }

    /// `log N(wrap_angle(y − h(x, ρ_t)); 0, σ²)`, eqs. (21)–(22).
    fn log_likelihood(&self, t: usize, x: &State, y: &f64) -> f64 {
        let e = wrap_angle(y - bearing([x[0], x[1]], self.rho(t))) / self.sigma;
        -0.5 * (LN_2PI + e * e) - self.ln_sigma
    }
}

impl TransitionDensity for OldBotModel {
    /// `log N(x; F x_prev, Q)`, eq. (18).
    fn log_transition_density(&self, _t: usize, x_prev: &State, x: &State, _u: Option<&()>) -> f64 {
        let d = x - self.f * x_prev;
        -0.5 * (4.0 * LN_2PI + self.ln_det_q + d.dot(&(self.q_inv * d)))
    }
}

/// The linearised optimal importance density (module docs).
#[derive(Debug, Clone, Copy, Default)]
pub struct OldLinearisedOptimal;

impl OldLinearisedOptimal {
    /// The gain `K = Q·Hᵀ/S` of the linearisation `(x̄, H, e, S)` at `x_prev`.
    fn gain(model: &OldBotModel, h: &RowVector4<f64>, s: f64) -> Vector4<f64> {
        model.q * h.transpose() / s
    }

    /// The log-density of `x` about the proposal's mean `x̄ + K·e`, from the linearisation
    /// `(x̄, H, e, S)` at `x_prev` and its gain `K` (eqs. of the module docs).
    fn log_density_at(
        model: &OldBotModel,
        (xb, h, e, s): (State, RowVector4<f64>, f64, f64),
        k: &Vector4<f64>,
        x: &State,
    ) -> f64 {
        let d = x - (xb + k * e);
        let s2 = model.sigma * model.sigma;
        // dᵀ Σ*⁻¹ d with Σ*⁻¹ = Q⁻¹ + HᵀH/σ², without forming the matrix.
        let hd = (h * d)[(0, 0)];
        let quad = d.dot(&(model.q_inv * d)) + hd * hd / s2;
        let ln_det = model.ln_det_q - (s / s2).ln();
        -0.5 * (4.0 * LN_2PI + ln_det + quad)
    }
}

impl Proposal<OldBotModel> for OldLinearisedOptimal {
    fn sample<R: Rng + ?Sized>(
        &self,
        model: &OldBotModel,
        at: StepAt<'_, OldBotModel>,
        x_prev: &State,
        x: &mut State,
        rng: &mut R,
    ) -> f64 {
        let Some(&y) = at.y else {
            *x = model.sample_transition(at.t, x_prev, at.u, rng);
            return model.log_transition_density(at.t, x_prev, x, at.u);
        };
        let lin = model.linearise(at.t, x_prev, y);
        let (xb, h, e, s) = lin;
        let k = Self::gain(model, &h, s);
        let z = Vector4::from_fn(|_, _| StandardNormal.sample(rng));
        let eps: f64 = StandardNormal.sample(rng);
        let x0 = xb + model.lq * z;
        let innov = e - (h * (x0 - xb))[(0, 0)] - model.sigma * eps;
        *x = x0 + k * innov;
        Self::log_density_at(model, lin, &k, x)
    }

    fn log_density(
        &self,
        model: &OldBotModel,
        at: StepAt<'_, OldBotModel>,
        x_prev: &State,
        x: &State,
    ) -> f64 {
        let Some(&y) = at.y else {
            return model.log_transition_density(at.t, x_prev, x, at.u);
        };
        let lin = model.linearise(at.t, x_prev, y);
        Self::log_density_at(model, lin, &Self::gain(model, &lin.1, lin.3), x)
    }
}

/// The PF of Section 4 for a scenario: `n` particles, systematic resampling when the ESS
/// falls below N/2 (the paper does not say; see the README).
///
/// # Errors
/// `n = 0`, or an invalid model.
pub fn particle_filter(
    model: OldBotModel,
    n: usize,
) -> Result<ParticleFilter<OldBotModel, Guided<OldLinearisedOptimal>>> {
    let cfg = FilterConfig {
        n_particles: n,
        resampler: Resampler::Systematic,
        policy: ResamplePolicy::EssBelow(EssThreshold::Fraction(0.5)),
    };
    Ok(ParticleFilter::guided(model, OldLinearisedOptimal, cfg)?)
}

/// Filter a realisation with `n` particles; position means at `k = 1, …, K`.
///
/// # Errors
/// As [`particle_filter`], or a collapse of the weights.
pub fn run<R: Rng + ?Sized>(
    scenario: &ScenarioConfig,
    n: usize,
    real: &Realisation,
    rng: &mut R,
) -> Result<Vec<[f64; 2]>> {
    let observer: Vec<[f64; 2]> = real.observer.iter().map(|o| o.pos).collect();
    let model = OldBotModel::new(scenario, observer, real.bearings[0])?;
    let mut pf = particle_filter(model, n)?;
    let mut out = Vec::with_capacity(real.bearings.len());
    for (k, y) in real.bearings.iter().enumerate() {
        let y = (k > 0).then_some(y);
        pf.step(None, y, rng)?;
        let m = pf.mean()?;
        out.push([m[0], m[1]]);
    }
    Ok(out)
}
