//! The dynamic sedimentation model of Section II, eqs. (1)–(8), run through one loading cycle
//! with the three phases of Fig. 4.
//!
//! States `V_t`, `m_t`, `m_s` follow
//! ```text
//! dV_t/dt = Q_i − Q_o                 (1)
//! dm_t/dt = Q_i ρ_i − Q_o ρ_o         (2)
//! dm_s/dt = f_s(ρ_m) f_e(Q_o, h_m)    (3)
//! ```
//! with `Q_o` from (4)/(5), `ρ_o` from the profile (6) at the overflow height `h_o`, and the
//! settling and scouring functions (7), (8). They are integrated by forward Euler with
//! `substeps` steps per sampling period `T_s`. The inputs `Q_i`, `ρ_i` and `h_o` are held
//! constant over each sampling period (zero-order hold), as the on-board logger records them.
//!
//! Phases: (1) filling, `h_t ≤ h_o`, no overflow; (2) overflow at constant volume once
//! `h_t > h_o`; (3) from the first sample with `m_t ≥ m_max`, a PID controller moves `h_o` to
//! hold `m_t` at the maximum laden mass `m_max`.
//!
//! Per-sample "true" overflow values are the averages over the sampling period that follows the
//! sample: `Q_o,k = (1/T_s) ∫ Q_o dt`, `ρ_o,k = ∫ Q_o ρ_o dt / ∫ Q_o dt`. With these the
//! discretised balances (9)–(10) hold exactly, which is what the estimator's model (13) assumes.
//!
//! The cycle is a deterministic function of the [`SimConfig`] and the random numbers it is
//! given: [`simulate`] draws the input fluctuations and then the measurement noise from one
//! generator, [`simulate_streams`] from two, so that the noise can be redrawn over the same
//! true cycle. The experiments use streams 0 and 1 of their seed
//! ([`crate::experiments::CycleConfig`]).

use crate::error::{DredgeError, Result};
use crate::sedimentation::HopperParams;
use pf_core::params::{ParamError, non_negative, positive};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

/// The incoming mixture (Fig. 3): each of `Q_i` and `ρ_i` is a stationary Ornstein–Uhlenbeck
/// fluctuation around its mean, sampled at `T_s`. The mean density ramps up from `ρ_w` over
/// `ramp` seconds while the drag head starts to take soil.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InflowProfile {
    /// Mean of `Q_i` (m³/s).
    pub q_i_mean: f64,
    /// Stationary standard deviation of `Q_i` (m³/s).
    pub q_i_std: f64,
    /// Correlation time of `Q_i` (s).
    pub q_i_tau: f64,
    /// Mean of `ρ_i` after the start-up ramp (kg/m³).
    pub rho_i_mean: f64,
    /// Stationary standard deviation of `ρ_i` (kg/m³).
    pub rho_i_std: f64,
    /// Correlation time of `ρ_i` (s).
    pub rho_i_tau: f64,
    /// Duration of the start-up ramp of the mean density from `ρ_w` (s).
    pub ramp: f64,
    /// Upper clip of `ρ_i` (kg/m³): a pump cannot move a denser mixture.
    pub rho_i_max: f64,
}

impl Default for InflowProfile {
    fn default() -> Self {
        InflowProfile {
            q_i_mean: 8.0,
            q_i_std: 0.6,
            q_i_tau: 60.0,
            rho_i_mean: 1300.0,
            rho_i_std: 80.0,
            rho_i_tau: 120.0,
            ramp: 300.0,
            rho_i_max: 1700.0,
        }
    }
}

/// Gains of the PID controller of phase 3: `h_o = h_o* − (K_p e + K_i ∫e dt + K_d de/dt)` with
/// `e = m_t − m_max`, run at the sampling period.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PidGains {
    /// `K_p` (m/kg).
    pub k_p: f64,
    /// `K_i` (m/(kg·s)).
    pub k_i: f64,
    /// `K_d` (m·s/kg).
    pub k_d: f64,
}

impl Default for PidGains {
    fn default() -> Self {
        PidGains {
            k_p: 2.0e-6,
            k_i: 4.0e-8,
            k_d: 2.0e-5,
        }
    }
}

/// Everything that defines a simulated loading cycle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimConfig {
    /// Hopper constants.
    pub hopper: HopperParams,
    /// Incoming mixture.
    pub inflow: InflowProfile,
    /// Phase-3 controller.
    pub pid: PidGains,
    /// `T_s`, sampling period of the logged data (s); the paper's 5 s.
    pub t_s: f64,
    /// Euler steps per sampling period.
    pub substeps: usize,
    /// Length of the cycle (s).
    pub t_end: f64,
    /// Initial content `V_t(0)`, clear water (m³).
    pub v_0: f64,
    /// Overflow height during phases 1 and 2, and the controller's upper limit (m).
    pub h_o_max: f64,
    /// Lowest overflow height the controller may set (m).
    pub h_o_min: f64,
    /// `m_max`, maximum laden mass held in phase 3 (kg).
    pub m_max: f64,
    /// `σ(ε_y) = [σ_V, σ_m]`, measurement noise of `V_t` (m³) and `m_t` (kg); the paper's
    /// `[10, 12000]`.
    pub sigma_y: [f64; 2],
    /// The cycle ends early when the mixture layer above the bed is thinner than this (m): the
    /// hopper is full of sand.
    pub h_m_stop: f64,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            hopper: HopperParams::default(),
            inflow: InflowProfile::default(),
            pid: PidGains::default(),
            t_s: 5.0,
            substeps: 20,
            t_end: 5400.0,
            v_0: 1000.0,
            h_o_max: 10.0,
            h_o_min: 2.0,
            m_max: 14.7e6,
            sigma_y: [10.0, 12000.0],
            h_m_stop: 0.5,
        }
    }
}

impl SimConfig {
    /// Check that the configuration describes a cycle that can run.
    ///
    /// # Errors
    /// [`DredgeError::Param`] naming the first bad field.
    pub fn validate(&self) -> Result<()> {
        self.hopper.validate()?;
        let f = &self.inflow;
        positive("q_i_mean", f.q_i_mean)?;
        non_negative("q_i_std", f.q_i_std)?;
        positive("q_i_tau", f.q_i_tau)?;
        non_negative("rho_i_std", f.rho_i_std)?;
        positive("rho_i_tau", f.rho_i_tau)?;
        non_negative("ramp", f.ramp)?;
        if !(f.rho_i_mean >= self.hopper.rho_w && f.rho_i_mean < self.hopper.rho_s) {
            return Err(DredgeError::Param(ParamError {
                name: "rho_i_mean",
                value: f.rho_i_mean,
                reason: "must lie in [rho_w, rho_s)",
            }));
        }
        if !(f.rho_i_max >= f.rho_i_mean && f.rho_i_max < self.hopper.rho_s) {
            return Err(DredgeError::Param(ParamError {
                name: "rho_i_max",
                value: f.rho_i_max,
                reason: "must lie in [rho_i_mean, rho_s)",
            }));
        }
        non_negative("k_p", self.pid.k_p)?;
        non_negative("k_i", self.pid.k_i)?;
        non_negative("k_d", self.pid.k_d)?;
        positive("T_s", self.t_s)?;
        if self.substeps == 0 {
            return Err(DredgeError::Param(ParamError {
                name: "substeps",
                value: 0.0,
                reason: "at least one Euler step per sampling period",
            }));
        }
        positive("t_end", self.t_end)?;
        let samples = self.t_end / self.t_s;
        if samples > 1e7 {
            return Err(DredgeError::Param(ParamError {
                name: "t_end",
                value: self.t_end,
                reason: "more than 10^7 samples (t_end / T_s)",
            }));
        }
        // Each sample takes `substeps` Euler steps: bounded too, or a huge count would run
        // for days instead of failing.
        if samples * self.substeps as f64 > 1e9 {
            return Err(DredgeError::Param(ParamError {
                name: "substeps",
                value: self.substeps as f64,
                reason: "more than 10^9 Euler steps in all (t_end / T_s · substeps)",
            }));
        }
        positive("v_0", self.v_0)?;
        positive("h_o_min", self.h_o_min)?;
        if !(self.h_o_max > self.h_o_min && self.h_o_max.is_finite()) {
            return Err(DredgeError::Param(ParamError {
                name: "h_o_max",
                value: self.h_o_max,
                reason: "must be finite and > h_o_min",
            }));
        }
        if self.v_0 / self.hopper.area >= self.h_o_max {
            return Err(DredgeError::Param(ParamError {
                name: "v_0",
                value: self.v_0,
                reason: "the hopper must start below the overflow (v_0 < A h_o_max)",
            }));
        }
        positive("m_max", self.m_max)?;
        non_negative("sigma_y[0]", self.sigma_y[0])?;
        non_negative("sigma_y[1]", self.sigma_y[1])?;
        non_negative("h_m_stop", self.h_m_stop)?;
        Ok(())
    }
}

/// One simulated loading cycle, sampled every `T_s`. Index `k` is the sample at `t_k`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Cycle {
    /// `t_k` (s).
    pub t: Vec<f64>,
    /// True `V_t` at `t_k` (m³).
    pub v_t: Vec<f64>,
    /// True `m_t` at `t_k` (kg).
    pub m_t: Vec<f64>,
    /// Sand-bed mass `m_s` at `t_k` (kg).
    pub m_s: Vec<f64>,
    /// Content height `h_t` (m).
    pub h_t: Vec<f64>,
    /// Bed height `h_s` (m).
    pub h_s: Vec<f64>,
    /// Overflow height `h_o` over `[t_k, t_{k+1})` (m).
    pub h_o: Vec<f64>,
    /// `Q_i` over `[t_k, t_{k+1})` (m³/s).
    pub q_i: Vec<f64>,
    /// `ρ_i` over `[t_k, t_{k+1})` (kg/m³).
    pub rho_i: Vec<f64>,
    /// Mean `Q_o` over `[t_k, t_{k+1})` (m³/s).
    pub q_o: Vec<f64>,
    /// Flux-weighted mean `ρ_o` over `[t_k, t_{k+1})`; where nothing overflows, the profile
    /// density (6) at `h_o` (kg/m³).
    pub rho_o: Vec<f64>,
    /// Mean mixture density `ρ_m` at `t_k` (kg/m³).
    pub rho_m: Vec<f64>,
    /// Loading phase (1, 2 or 3) of sample `k`.
    pub phase: Vec<u8>,
    /// Measured `V_t` (with `σ_V` noise).
    pub y_v: Vec<f64>,
    /// Measured `m_t` (with `σ_m` noise).
    pub y_m: Vec<f64>,
    /// First sample of phase 2 (first overflow), if reached.
    pub phase2_start: Option<usize>,
    /// First sample of phase 3 (controller on), if reached.
    pub phase3_start: Option<usize>,
    /// Whether the cycle ended early because the hopper was full of sand.
    pub filled_with_sand: bool,
}

impl Cycle {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether the cycle has no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Whether any overflow happened in the period after sample `k`.
    pub fn overflowing(&self, k: usize) -> bool {
        self.q_o[k] > 0.0
    }

    /// The cycle as measured on board (noisy `V_t`, `m_t`, exact inputs), with the true
    /// `Q_o`, `ρ_o` as truth columns (`ρ_o` empty where nothing overflows).
    pub fn to_data(&self) -> crate::data::DredgeData {
        self.data_with(&self.y_v, &self.y_m)
    }

    /// As [`to_data`](Self::to_data) but with the noise-free `V_t`, `m_t`.
    pub fn to_noise_free_data(&self) -> crate::data::DredgeData {
        self.data_with(&self.v_t, &self.m_t)
    }

    fn data_with(&self, v: &[f64], m: &[f64]) -> crate::data::DredgeData {
        let n = self.len();
        crate::data::DredgeData {
            t: self.t.clone(),
            v_t: v.iter().copied().map(Some).collect(),
            m_t: m.iter().copied().map(Some).collect(),
            q_i: self.q_i.iter().copied().map(Some).collect(),
            rho_i: self.rho_i.iter().copied().map(Some).collect(),
            truth: Some(crate::data::Truth {
                q_o: self.q_o.iter().copied().map(Some).collect(),
                rho_o: (0..n)
                    .map(|k| self.overflowing(k).then_some(self.rho_o[k]))
                    .collect(),
            }),
        }
    }
}

/// An Ornstein–Uhlenbeck step: `x' = μ + φ (x − μ) + σ √(1 − φ²) ξ`, exact for period `dt`.
fn ou_step<R: Rng + ?Sized>(x: f64, mean: f64, std: f64, tau: f64, dt: f64, rng: &mut R) -> f64 {
    let phi = (-dt / tau).exp();
    let xi: f64 = StandardNormal.sample(rng);
    mean + phi * (x - mean) + std * (1.0 - phi * phi).sqrt() * xi
}

/// The input sequences `(Q_i, ρ_i)` of Fig. 3 for `n` samples, drawn from `rng`.
fn inflow<R: Rng + ?Sized>(cfg: &SimConfig, n: usize, rng: &mut R) -> (Vec<f64>, Vec<f64>) {
    let f = &cfg.inflow;
    let rho_w = cfg.hopper.rho_w;
    let mut q_dev = 0.0;
    let mut rho_dev = 0.0;
    let mut q = Vec::with_capacity(n);
    let mut rho = Vec::with_capacity(n);
    for k in 0..n {
        let t = k as f64 * cfg.t_s;
        if k > 0 {
            q_dev = ou_step(q_dev, 0.0, f.q_i_std, f.q_i_tau, cfg.t_s, rng);
            rho_dev = ou_step(rho_dev, 0.0, f.rho_i_std, f.rho_i_tau, cfg.t_s, rng);
        }
        let ramp = if f.ramp > 0.0 {
            (t / f.ramp).min(1.0)
        } else {
            1.0
        };
        let rho_mean = rho_w + ramp * (f.rho_i_mean - rho_w);
        q.push((f.q_i_mean + q_dev).max(0.0));
        rho.push((rho_mean + ramp * rho_dev).clamp(rho_w, f.rho_i_max));
    }
    (q, rho)
}

/// Simulate one loading cycle, drawing the input fluctuations and then the measurement noise
/// from `rng`.
///
/// # Errors
/// An invalid configuration ([`SimConfig::validate`]).
pub fn simulate<R: Rng + ?Sized>(cfg: &SimConfig, rng: &mut R) -> Result<Cycle> {
    cfg.validate()?;
    let (q_i, rho_i) = inflow(cfg, samples(cfg), rng);
    run(cfg, &q_i, &rho_i, rng)
}

/// Simulate one loading cycle, the input fluctuations drawn from `inflow_rng` and the
/// measurement noise from `noise_rng`: the same `inflow_rng` gives the same true cycle
/// whatever the noise.
///
/// # Errors
/// An invalid configuration ([`SimConfig::validate`]).
pub fn simulate_streams<R: Rng + ?Sized, S: Rng + ?Sized>(
    cfg: &SimConfig,
    inflow_rng: &mut R,
    noise_rng: &mut S,
) -> Result<Cycle> {
    cfg.validate()?;
    let (q_i, rho_i) = inflow(cfg, samples(cfg), inflow_rng);
    run(cfg, &q_i, &rho_i, noise_rng)
}

/// Samples of a cycle of `t_end` seconds, the sample at 0 included.
fn samples(cfg: &SimConfig) -> usize {
    (cfg.t_end / cfg.t_s).floor() as usize + 1
}

/// The cycle driven by the inputs `q_i_all`, `ρ_i_all` (one per sample), measured with noise
/// from `noise`.
fn run<R: Rng + ?Sized>(
    cfg: &SimConfig,
    q_i_all: &[f64],
    rho_i_all: &[f64],
    noise: &mut R,
) -> Result<Cycle> {
    let p = &cfg.hopper;
    let n = q_i_all.len().min(rho_i_all.len());

    let mut c = Cycle {
        t: Vec::with_capacity(n),
        v_t: Vec::with_capacity(n),
        m_t: Vec::with_capacity(n),
        m_s: Vec::with_capacity(n),
        h_t: Vec::with_capacity(n),
        h_s: Vec::with_capacity(n),
        h_o: Vec::with_capacity(n),
        q_i: Vec::with_capacity(n),
        rho_i: Vec::with_capacity(n),
        q_o: Vec::with_capacity(n),
        rho_o: Vec::with_capacity(n),
        rho_m: Vec::with_capacity(n),
        phase: Vec::with_capacity(n),
        y_v: Vec::with_capacity(n),
        y_m: Vec::with_capacity(n),
        phase2_start: None,
        phase3_start: None,
        filled_with_sand: false,
    };

    let dt = cfg.t_s / cfg.substeps as f64;
    let (mut v, mut m, mut m_s) = (cfg.v_0, cfg.v_0 * p.rho_w, 0.0);
    let mut h_o = cfg.h_o_max;
    // PID state: reference height at switch-on, integral of e, previous e.
    let mut pid_on = false;
    let mut h_ref = h_o;
    let mut integral = 0.0;
    let mut e_prev = 0.0;

    for k in 0..n {
        let (h_t, h_s, h_m) = p.heights(v, m_s);
        let rho_m = p.mixture_density(v, m, m_s);
        if h_m < cfg.h_m_stop {
            c.filled_with_sand = true;
            break;
        }
        // Phase 3: the controller takes over at the first sample with m_t ≥ m_max.
        if !pid_on && m >= cfg.m_max {
            pid_on = true;
            h_ref = h_o;
            integral = 0.0;
            e_prev = m - cfg.m_max;
            c.phase3_start = Some(k);
        }
        if pid_on {
            let e = m - cfg.m_max;
            let de = (e - e_prev) / cfg.t_s;
            let candidate_integral = integral + e * cfg.t_s;
            let u = h_ref - (cfg.pid.k_p * e + cfg.pid.k_i * candidate_integral + cfg.pid.k_d * de);
            // Anti-windup: integrate only while the actuator is not saturated.
            if u > cfg.h_o_min && u < cfg.h_o_max {
                integral = candidate_integral;
            }
            h_o = u.clamp(cfg.h_o_min, cfg.h_o_max);
            e_prev = e;
        }

        let (q_i, rho_i) = (q_i_all[k], rho_i_all[k]);
        let (v_k, m_k, m_s_k) = (v, m, m_s);
        let mut int_q = 0.0;
        let mut int_q_rho = 0.0;
        let mut int_rho_profile = 0.0;
        for _ in 0..cfg.substeps {
            let (h_t, h_s, h_m) = p.heights(v, m_s);
            let rho_m = p.mixture_density(v, m, m_s);
            let q_o = p.overflow_rate(h_t, h_o);
            let rho_o = p.profile_density(p.k_rho(rho_m, h_m), h_o, h_s);
            let dm_s = if h_m > 0.0 {
                p.settling(rho_m) * p.scouring(q_o, h_m)
            } else {
                0.0
            };
            v += dt * (q_i - q_o);
            m += dt * (q_i * rho_i - q_o * rho_o);
            m_s += dt * dm_s;
            int_q += dt * q_o;
            int_q_rho += dt * q_o * rho_o;
            int_rho_profile += dt * rho_o;
        }
        let q_o_mean = int_q / cfg.t_s;
        let rho_o_mean = if int_q > 0.0 {
            int_q_rho / int_q
        } else {
            int_rho_profile / cfg.t_s
        };
        if c.phase2_start.is_none() && int_q > 0.0 {
            c.phase2_start = Some(k);
        }
        let phase = if pid_on {
            3
        } else if c.phase2_start.is_some() {
            2
        } else {
            1
        };
        let e_v: f64 = StandardNormal.sample(noise);
        let e_m: f64 = StandardNormal.sample(noise);
        c.t.push(k as f64 * cfg.t_s);
        c.v_t.push(v_k);
        c.m_t.push(m_k);
        c.m_s.push(m_s_k);
        c.h_t.push(h_t);
        c.h_s.push(h_s);
        c.h_o.push(h_o);
        c.q_i.push(q_i);
        c.rho_i.push(rho_i);
        c.q_o.push(q_o_mean);
        c.rho_o.push(rho_o_mean);
        c.rho_m.push(rho_m);
        c.phase.push(phase);
        c.y_v.push(v_k + cfg.sigma_y[0] * e_v);
        c.y_m.push(m_k + cfg.sigma_y[1] * e_m);
    }
    Ok(c)
}
