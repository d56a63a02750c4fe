//! One target's state-space model (Section 3) and the proposal of EPF steps 4–5.
//!
//! State `X_{k,t}` = position in the image plane; observation `Y_{k,t}` = its associated
//! detection. Between observed frames `Δ` apart the target moves by the dynamic model's
//! displacement `d` ([`crate::dynamics`]) plus noise:
//!
//! `X_{k,t} = X_{k,t−Δ} + d + U_{k,t}`, `U ~ N(0, (q²Δ + s²)·I)`;  `Y_{k,t} = X_{k,t} + V_{k,t}`,
//! `V ~ N(0, r²·I)`; `s² = 0` except at a re-acquisition ([`Drift::extra_var`]).

use crate::geometry::Vec2;
use pf_core::filter::{Mutation, StepAt};
use pf_core::{StateSpaceModel, TransitionDensity};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

/// `u_t`: the dynamic model's displacement `d` over the `Δ` frames since the last step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drift {
    /// Displacement `d = v·Δ + ½·a·Δ²`.
    pub d: Vec2,
    /// Frames elapsed `Δ > 0`.
    pub dt: f64,
    /// Variance added to the step's process noise `q²Δ` (per coordinate, ≥ 0): the
    /// tracker sets it when a target takes a detection after coasting, to the growth of
    /// the dynamic model's velocity error over the frames without one
    /// ([`crate::tracker`]); 0 otherwise.
    pub extra_var: f64,
}

/// The model of one target; `x0` is its last init position, the mean of `P(X_{k,0})`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetModel {
    /// Mean of the initial distribution `P(X_{k,0}) = N(x0, r²I)` (EPF step 3).
    pub x0: Vec2,
    /// Process noise standard deviation per √frame, `q`.
    pub q: f64,
    /// Observation noise standard deviation, `r`.
    pub r: f64,
}

fn normal2<R: Rng + ?Sized>(rng: &mut R) -> Vec2 {
    Vec2::new(StandardNormal.sample(rng), StandardNormal.sample(rng))
}

/// `log N(x; m, s²I)` in 2-D.
fn log_normal2(x: &Vec2, m: &Vec2, s2: f64) -> f64 {
    -(x - m).norm_squared() / (2.0 * s2) - (std::f64::consts::TAU * s2).ln()
}

impl TargetModel {
    fn prior(&self, x_prev: &Vec2, u: Option<&Drift>) -> (Vec2, f64) {
        let (d, dt, extra) = u.map_or((Vec2::zeros(), 1.0, 0.0), |u| (u.d, u.dt, u.extra_var));
        (x_prev + d, self.q * self.q * dt + extra)
    }
}

impl StateSpaceModel for TargetModel {
    type State = Vec2;
    type Obs = Vec2;
    type Input = Drift;

    fn sample_initial<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec2 {
        self.x0 + normal2(rng) * self.r
    }

    fn sample_transition<R: Rng + ?Sized>(
        &self,
        _t: usize,
        x_prev: &Vec2,
        u: Option<&Drift>,
        rng: &mut R,
    ) -> Vec2 {
        let (m, p) = self.prior(x_prev, u);
        m + normal2(rng) * p.sqrt()
    }

    fn log_likelihood(&self, _t: usize, x: &Vec2, y: &Vec2) -> f64 {
        log_normal2(y, x, self.r * self.r)
    }
}

impl TransitionDensity for TargetModel {
    fn log_transition_density(&self, _t: usize, x_prev: &Vec2, x: &Vec2, u: Option<&Drift>) -> f64 {
        let (m, p) = self.prior(x_prev, u);
        log_normal2(x, &m, p)
    }
}

/// EPF steps 4–5 with `f = P(X_{k,t} | X_{k,t−1}, y_j)`, the optimal proposal, which is
/// Gaussian here: mean `(r²m + q²Δ·y)/(q²Δ + r²)`, variance `q²Δr²/(q²Δ + r²)`, where
/// `m = x_prev + d`. The weight `P(s̃|s)P(y|s̃)/f(s̃|s, y)` is then `N(y; m, (q²Δ + r²)I)`,
/// which does not depend on the draw. Without an associated detection it moves by the prior
/// and leaves the weights alone.
#[derive(Debug, Clone, Copy, Default)]
pub struct OptimalProposal;

impl Mutation<TargetModel> for OptimalProposal {
    fn reweights_without_observation(&self) -> bool {
        false
    }

    fn mutate<R: Rng + ?Sized>(
        &self,
        model: &TargetModel,
        at: StepAt<'_, TargetModel>,
        x_prev: &Vec2,
        x: &mut Vec2,
        rng: &mut R,
    ) -> f64 {
        let Some(y) = at.y else {
            *x = model.sample_transition(at.t, x_prev, at.u, rng);
            return 0.0;
        };
        let (m, p) = model.prior(x_prev, at.u);
        let r2 = model.r * model.r;
        let s = p + r2;
        let mean = (m * r2 + y * p) / s;
        let var = p * r2 / s;
        *x = mean + normal2(rng) * var.sqrt();
        log_normal2(y, &m, s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pf_core::filter::{Bootstrap, FilterConfig, ParticleFilter};
    use pf_core::mc::stream_rng;

    /// The optimal proposal's weight equals `g·f/q` evaluated with the model's densities.
    #[test]
    fn optimal_weight_is_g_f_over_q() {
        let model = TargetModel {
            x0: Vec2::zeros(),
            q: 1.5,
            r: 2.0,
        };
        let u = Drift {
            d: Vec2::new(3.0, -1.0),
            dt: 4.0,
            extra_var: 0.5,
        };
        let (xp, y) = (Vec2::new(1.0, 1.0), Vec2::new(5.0, 2.0));
        let at = StepAt {
            t: 1,
            u: Some(&u),
            y: Some(&y),
        };
        let mut x = Vec2::zeros();
        let lw = OptimalProposal.mutate(&model, at, &xp, &mut x, &mut stream_rng(0, 0));
        let (m, p) = model.prior(&xp, Some(&u));
        let s = p + 4.0;
        let log_q = log_normal2(&x, &((m * 4.0 + y * p) / s), p * 4.0 / s);
        let expected = model.log_likelihood(1, &x, &y)
            + model.log_transition_density(1, &xp, &x, Some(&u))
            - log_q;
        assert!((lw - expected).abs() < 1e-12);
    }

    /// The position model is linear-Gaussian, so the exact posterior is a Kalman filter per
    /// coordinate; the PF mean must agree within Monte Carlo error.
    #[test]
    fn filter_mean_matches_the_kalman_posterior() {
        let model = TargetModel {
            x0: Vec2::new(10.0, 20.0),
            q: 1.0,
            r: 2.0,
        };
        let u = Drift {
            d: Vec2::new(2.0, 1.0),
            dt: 3.0,
            extra_var: 0.0,
        };
        let ys = [
            Vec2::new(13.0, 20.0),
            Vec2::new(14.0, 23.5),
            Vec2::new(17.0, 24.0),
        ];
        // Kalman: P₀ = r², then predict P += q²Δ, update with gain P/(P + r²).
        let (mut mean, mut var) = (model.x0, 4.0);
        for y in &ys {
            mean += u.d;
            var += 3.0;
            let k = var / (var + 4.0);
            mean += (y - mean) * k;
            var *= 1.0 - k;
        }
        let n = 4000;
        let cfg = FilterConfig::new(n);
        let mut pf = ParticleFilter::new(model, OptimalProposal, cfg).unwrap();
        let mut rng = stream_rng(3, 0);
        pf.step(None, None, &mut rng).unwrap();
        for y in &ys {
            pf.step(Some(&u), Some(y), &mut rng).unwrap();
        }
        let est = Vec2::new(pf.expectation(|x| x.x), pf.expectation(|x| x.y));
        // Posterior sd √var ≈ 1.3; MC sd of the mean ≈ √(var/N)·√(1 + resampling inflation
        // over 3 steps ≲ 4) ≈ 0.04; 5 of those ≈ 0.2 bounds both coordinates.
        let tol = 5.0 * (var * 4.0 / n as f64).sqrt();
        assert!(
            (est - mean).abs().max() < tol,
            "{est:?} vs {mean:?} (tol {tol})"
        );
        // The bootstrap filter over the same model agrees with it too (same tolerance).
        let mut boot = ParticleFilter::bootstrap(model, cfg).unwrap();
        boot.step(None, None, &mut rng).unwrap();
        for y in &ys {
            boot.step(Some(&u), Some(y), &mut rng).unwrap();
        }
        assert!((boot.expectation(|x| x.x) - mean.x).abs() < tol);
        let _ = Bootstrap;
    }
}
