//! The bearings-only tracking model of Section 3 and the scenario of Section 4.
//!
//! State `x_k = [x_k, y_k, ẋ_k, ẏ_k]'` (eq. (18) ff.), nearly-constant-velocity dynamics
//! `x_k ~ N(F x_{k−1}, Q)` with F (19) and Q (20), and a bearing
//! `y_k ~ N(h(x_k, ρ_k), σ²)` (21)–(22) taken from an observer at `ρ_k`.
//!
//! Angle convention (the paper gives none): bearings and headings are measured
//! counter-clockwise from the x-axis, as the `arctan((y − ζ)/(x − ξ))` of (22) implies, and a
//! positive turn rate turns the observer counter-clockwise. The paper gives the turn rate
//! (30°/s) but not its direction; the default turns the observer clockwise (−30°/s), the
//! direction under which the 17th bearing brings the "dramatic increase in information"
//! of Section 4.1 (the crate README measures both). Sampling instant `k = 1, …, K` is at
//! time `(k − 1)T`.

use nalgebra::{Matrix4, SMatrix, Vector4};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::error::{HomotopyError, Result, check_data};
use pf_core::geometry::wrap_angle;
use pf_core::params::{ParamError, finite, positive};

/// The target state `[x, y, ẋ, ẏ]`.
pub type State = Vector4<f64>;

/// The prior of Section 4: range, speed and heading, with the first bearing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PriorConfig {
    /// Mean range, m (8000).
    pub range_mean: f64,
    /// Range standard deviation, m (3500).
    pub range_sd: f64,
    /// Mean speed, m/s (150).
    pub speed_mean: f64,
    /// Speed standard deviation, m/s (50).
    pub speed_sd: f64,
    /// Mean heading, rad (−5π/9).
    pub heading_mean: f64,
    /// Heading standard deviation, rad (π/√12, i.e. variance π²/12).
    pub heading_sd: f64,
}

impl Default for PriorConfig {
    fn default() -> Self {
        use std::f64::consts::PI;
        Self {
            range_mean: 8000.0,
            range_sd: 3500.0,
            speed_mean: 150.0,
            speed_sd: 50.0,
            heading_mean: -5.0 * PI / 9.0,
            heading_sd: PI / 12f64.sqrt(),
        }
    }
}

impl PriorConfig {
    /// Check the prior.
    pub fn validate(&self) -> Result<()> {
        positive("range_mean", self.range_mean)?;
        positive("range_sd", self.range_sd)?;
        finite("speed_mean", self.speed_mean)?;
        positive("speed_sd", self.speed_sd)?;
        finite("heading_mean", self.heading_mean)?;
        positive("heading_sd", self.heading_sd)?;
        Ok(())
    }
}

/// The simulation scenario of Section 4 (Fig. 1). `Default` is the paper's, with the
/// unstated bearing noise and number of samples chosen as the README explains.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioConfig {
    /// Initial target range from the observer, m (5000).
    pub target_range: f64,
    /// Initial target bearing, degrees (80).
    pub target_bearing_deg: f64,
    /// Initial target speed, m/s (123.5).
    pub target_speed: f64,
    /// Initial target heading, degrees (−130).
    pub target_heading_deg: f64,
    /// Process noise intensity q of (20) (0.01).
    pub q: f64,
    /// Sampling period T, s (1).
    pub t: f64,
    /// Observer speed, m/s (154).
    pub observer_speed: f64,
    /// Observer initial heading, degrees (−45).
    pub observer_heading_deg: f64,
    /// Observer turn rate, degrees/s, counter-clockwise positive (−30: the paper's 30°/s,
    /// clockwise; see the module docs).
    pub turn_rate_deg: f64,
    /// Sampling instant at which the turn starts (13).
    pub turn_start: usize,
    /// Sampling instant at which the turn ends (17).
    pub turn_end: usize,
    /// Bearing noise standard deviation σ, degrees (unstated; ½, see the README).
    pub sigma_deg: f64,
    /// Number of sampling instants K (unstated; 40).
    pub n_samples: usize,
    /// The prior.
    pub prior: PriorConfig,
}

impl Default for ScenarioConfig {
    fn default() -> Self {
        Self {
            target_range: 5000.0,
            target_bearing_deg: 80.0,
            target_speed: 123.5,
            target_heading_deg: -130.0,
            q: 0.01,
            t: 1.0,
            observer_speed: 154.0,
            observer_heading_deg: -45.0,
            turn_rate_deg: -30.0,
            turn_start: 13,
            turn_end: 17,
            sigma_deg: 0.5,
            n_samples: 40,
            prior: PriorConfig::default(),
        }
    }
}

/// The observer's own state at one sampling instant (known to every filter).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ObserverState {
    /// Position ρ_k = (ξ_k, ζ_k).
    pub pos: [f64; 2],
    /// Velocity.
    pub vel: [f64; 2],
}

impl ScenarioConfig {
    /// Check the scenario.
    pub fn validate(&self) -> Result<()> {
        positive("target_range", self.target_range)?;
        finite("target_bearing_deg", self.target_bearing_deg)?;
        finite("target_speed", self.target_speed)?;
        finite("target_heading_deg", self.target_heading_deg)?;
        positive("q", self.q)?;
        positive("T", self.t)?;
        finite("observer_speed", self.observer_speed)?;
        finite("observer_heading_deg", self.observer_heading_deg)?;
        finite("turn_rate_deg", self.turn_rate_deg)?;
        positive("sigma_deg", self.sigma_deg)?;
        if self.turn_start < 1 || self.turn_end < self.turn_start {
            return Err(HomotopyError::Param(ParamError {
                name: "turn_start/turn_end",
                value: self.turn_start as f64,
                reason: "need 1 ≤ turn_start ≤ turn_end",
            }));
        }
        if self.n_samples < 2 {
            return Err(HomotopyError::TooFewObservations {
                got: self.n_samples,
                needed: 2,
            });
        }
        // The target's and observer's states and a bearing per instant, about 72 bytes
        // (more with each filter's estimates): past the limit or the memory, an error here.
        const WHAT: &str = "K (sampling instants)";
        let k = pf_core::limits::check_count(WHAT, self.n_samples)?;
        pf_core::limits::check_memory(WHAT, k, k.saturating_mul(128))?;
        self.prior.validate()
    }

    /// σ in radians.
    pub fn sigma(&self) -> f64 {
        self.sigma_deg.to_radians()
    }

    /// F of eq. (19).
    pub fn f(&self) -> Matrix4<f64> {
        transition_matrix(self.t)
    }

    /// Q of eq. (20).
    pub fn q_matrix(&self) -> Matrix4<f64> {
        process_noise(self.q, self.t)
    }

    /// Observer states at `k = 1, …, K`: straight at `observer_heading`, a coordinated turn
    /// (exact circular arc) from instant `turn_start` to `turn_end`, then straight again.
    pub fn observer_track(&self) -> Vec<ObserverState> {
        let v = self.observer_speed;
        let h0 = self.observer_heading_deg.to_radians();
        let w = self.turn_rate_deg.to_radians();
        let ts = (self.turn_start as f64 - 1.0) * self.t;
        let te = (self.turn_end as f64 - 1.0) * self.t;
        let h1 = h0 + w * (te - ts);
        let arc = |tau: f64| -> ([f64; 2], f64) {
            let ps = [v * h0.cos() * ts, v * h0.sin() * ts];
            let h = h0 + w * tau;
            if w.abs() < 1e-12 {
                ([ps[0] + v * h0.cos() * tau, ps[1] + v * h0.sin() * tau], h)
            } else {
                (
                    [
                        ps[0] + v / w * (h.sin() - h0.sin()),
                        ps[1] + v / w * (h0.cos() - h.cos()),
                    ],
                    h,
                )
            }
        };
        (1..=self.n_samples)
            .map(|k| {
                let tau = (k as f64 - 1.0) * self.t;
                let (pos, h) = if tau <= ts {
                    ([v * h0.cos() * tau, v * h0.sin() * tau], h0)
                } else if tau <= te {
                    arc(tau - ts)
                } else {
                    let (pe, _) = arc(te - ts);
                    let dt = tau - te;
                    ([pe[0] + v * h1.cos() * dt, pe[1] + v * h1.sin() * dt], h1)
                };
                ObserverState {
                    pos,
                    vel: [v * h.cos(), v * h.sin()],
                }
            })
            .collect()
    }

    /// The target state at `k = 1`.
    pub fn initial_target(&self) -> State {
        let b = self.target_bearing_deg.to_radians();
        let h = self.target_heading_deg.to_radians();
        let o = self.observer_track()[0].pos;
        Vector4::new(
            o[0] + self.target_range * b.cos(),
            o[1] + self.target_range * b.sin(),
            self.target_speed * h.cos(),
            self.target_speed * h.sin(),
        )
    }

    /// The noise-free ("nominal") target trajectory of Fig. 1.
    pub fn nominal_target(&self) -> Vec<State> {
        let f = self.f();
        let mut x = self.initial_target();
        let mut out = Vec::with_capacity(self.n_samples);
        for _ in 0..self.n_samples {
            out.push(x);
            x = f * x;
        }
        out
    }

    /// Simulate one realisation: the target by (18), bearings by (21).
    ///
    /// # Errors
    /// An invalid scenario.
    pub fn simulate<R: Rng + ?Sized>(&self, rng: &mut R) -> Result<Realisation> {
        self.validate()?;
        let f = self.f();
        let lq = self
            .q_matrix()
            .cholesky()
            .ok_or(HomotopyError::Param(ParamError {
                name: "q",
                value: self.q,
                reason: "Q must be positive definite",
            }))?
            .l();
        let observer = self.observer_track();
        let sigma = self.sigma();
        let mut x = self.initial_target();
        let mut target = Vec::with_capacity(self.n_samples);
        let mut bearings = Vec::with_capacity(self.n_samples);
        for (k, o) in observer.iter().enumerate() {
            if k > 0 {
                let z = Vector4::from_fn(|_, _| StandardNormal.sample(rng));
                x = f * x + lq * z;
            }
            target.push(x);
            let v: f64 = StandardNormal.sample(rng);
            bearings.push(wrap_angle(bearing([x[0], x[1]], o.pos) + sigma * v));
        }
        Ok(Realisation {
            target,
            observer,
            bearings,
        })
    }
}

/// One realisation of the scenario: truth, observer and bearings at `k = 1, …, K`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Realisation {
    /// True target states.
    pub target: Vec<State>,
    /// Observer states.
    pub observer: Vec<ObserverState>,
    /// Bearings `y_k`, rad, in (−π, π].
    pub bearings: Vec<f64>,
}

impl Realisation {
    /// Check that a (possibly user-supplied) realisation can be filtered: equal lengths,
    /// at least two bearings, all values finite.
    pub fn validate_inputs(observer: &[ObserverState], bearings: &[f64]) -> Result<()> {
        if bearings.len() < 2 {
            return Err(HomotopyError::TooFewObservations {
                got: bearings.len(),
                needed: 2,
            });
        }
        if observer.len() != bearings.len() {
            return Err(HomotopyError::LengthMismatch {
                what: "observer states against bearings",
                expected: bearings.len(),
                got: observer.len(),
            });
        }
        for (i, (&y, o)) in bearings.iter().zip(observer).enumerate() {
            let k = i + 1;
            check_data("bearing", k, y)?;
            for &v in o.pos.iter().chain(&o.vel) {
                check_data("observer state", k, v)?;
            }
        }
        Ok(())
    }
}

/// F of eq. (19): `[[1, T], [0, 1]] ⊗ I₂`.
pub fn transition_matrix(t: f64) -> Matrix4<f64> {
    let mut f = Matrix4::identity();
    f[(0, 2)] = t;
    f[(1, 3)] = t;
    f
}

/// Q of eq. (20): `q [[T³/3, T²/2], [T²/2, T]] ⊗ I₂`.
pub fn process_noise(q: f64, t: f64) -> Matrix4<f64> {
    let a = SMatrix::<f64, 2, 2>::new(t.powi(3) / 3.0, t * t / 2.0, t * t / 2.0, t);
    let mut m = Matrix4::zeros();
    for i in 0..2 {
        for j in 0..2 {
            m[(2 * i, 2 * j)] = q * a[(i, j)];
            m[(2 * i + 1, 2 * j + 1)] = q * a[(i, j)];
        }
    }
    m
}

/// The bearing `h(x, ρ) = atan2(y − ζ, x − ξ)` of eq. (22): angle of the target position
/// `p` seen from the observer `ρ`, counter-clockwise from the x-axis, in (−π, π]. The
/// paper's `arctan((y − ζ)/(x − ξ))` is taken in its four-quadrant form. Residuals are
/// wrapped with [`pf_core::geometry::wrap_angle`].
pub fn bearing(p: [f64; 2], rho: [f64; 2]) -> f64 {
    (p[1] - rho[1]).atan2(p[0] - rho[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kronecker_forms_of_f_and_q() {
        let f = transition_matrix(2.0);
        assert_eq!(
            f * Vector4::new(1.0, 2.0, 3.0, 4.0),
            Vector4::new(7.0, 10.0, 3.0, 4.0)
        );
        let q = process_noise(0.5, 2.0);
        assert_eq!(q[(0, 0)], 0.5 * 8.0 / 3.0);
        assert_eq!(q[(0, 2)], 0.5 * 2.0);
        assert_eq!(q[(1, 3)], 0.5 * 2.0);
        assert_eq!(q[(3, 3)], 0.5 * 2.0);
        assert_eq!(q[(0, 1)], 0.0);
        assert_eq!(q[(0, 3)], 0.0);
    }

    #[test]
    fn observer_turns_through_120_degrees_between_13_and_17() {
        let s = ScenarioConfig::default();
        let tr = s.observer_track();
        assert_eq!(tr[0].pos, [0.0, 0.0]);
        let head = |k: usize| tr[k - 1].vel[1].atan2(tr[k - 1].vel[0]).to_degrees();
        // Headings are exact up to round-off in to_degrees/atan2; the default turn is
        // clockwise, from −45° through −105° to −165°.
        assert!((head(13) + 45.0).abs() < 1e-9);
        assert!((head(15) + 105.0).abs() < 1e-9);
        assert!((head(17) + 165.0).abs() < 1e-9);
        assert!((head(30) + 165.0).abs() < 1e-9);
        // A positive rate turns the other way.
        let ccw = ScenarioConfig {
            turn_rate_deg: 30.0,
            ..s
        }
        .observer_track();
        let head_ccw = |k: usize| ccw[k - 1].vel[1].atan2(ccw[k - 1].vel[0]).to_degrees();
        assert!((head_ccw(17) - 75.0).abs() < 1e-9);
        // Constant speed: consecutive positions 154 m apart on straight legs, and the chord
        // 2(v/ω) sin(ωT/2) on the arc.
        let dist = |a: usize, b: usize| {
            let (p, q) = (tr[a - 1].pos, tr[b - 1].pos);
            (p[0] - q[0]).hypot(p[1] - q[1])
        };
        assert!((dist(5, 6) - 154.0).abs() < 1e-9);
        let w = 30f64.to_radians();
        assert!((dist(14, 15) - 2.0 * 154.0 / w * (w / 2.0).sin()).abs() < 1e-9);
        assert!((dist(20, 21) - 154.0).abs() < 1e-9);
    }
}
