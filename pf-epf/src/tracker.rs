//! The energetic particle filter (Section 3, steps 1–6) and the NNSF baseline: one pf-core
//! particle filter per target, fed by the association of each frame.
//!
//! At each tracked frame `t`, `Δ_k` frames after target `k`'s last one:
//! 1. predict `Â(t) = Â(t−1) + d_k`, `d_k` the dynamic model's displacement over `Δ_k`, and
//!    `Â₁(t+1) = Â(t) + d_k(t → t + Δ_k)` (the next observation is assumed `Δ_k` later);
//! 2. the target's covariance `Σ̂_k = Cov(particles) + (q²Δ_k + r² + r²Σc²)·I`, the
//!    covariance of the predicted detection (particle spread, process noise, detection
//!    noise, and the noise the dynamic model's displacement inherits from the detections it
//!    was fitted to, [`SplineDynamics::displacement_noise_factor`]), gives its validation
//!    gate and its Mahalanobis distances;
//! 3. associate (step 1: energy or nearest neighbour, [`crate::association`]);
//! 4. step the target's filter with the associated detection (steps 3–6: optimal proposal,
//!    multinomial resampling when `N_eff < ess_fraction·N`), or with none;
//! 5. push the detection into the dynamic model (step 2, the B-spline update);
//! 6. the estimate `X̂_{k,t}` is the weighted particle mean; it becomes `Â(t−1)` next.
//!
//! ## Coasting, lost tracks and re-acquisition
//!
//! A target that takes no detection at a frame *coasts*. The dynamic model's velocity
//! comes from the last two or three detections and carries their noise (`√2·r` per frame
//! for the chord); extrapolated over several frames without a detection, a velocity error
//! beyond the gate's grows as fast as the gate does, and the target is never found again.
//! So from its first frame without a detection, a coasting target is predicted by the
//! least-squares line through its last [`HISTORY`] associated detections (init positions
//! included), `Â(t) = ȳ + v̂(t − τ̄)`, whose velocity averages their noise, and the gate's
//! `r²Σc²` term becomes that prediction's variance factor,
//! `r²(1/n + (t − τ̄)²/Σ_i(τ_i − τ̄)²)`, plus the variance of a velocity that keeps
//! changing while nothing is seen, `q²s(n(n+1)(2n+1)/6 − n)` (`s` the detections' mean
//! spacing, `n` the spacings since the last one: a velocity random walk of `q²s` per
//! spacing, the model behind `q̂`, beyond the `q²Δ` per step the particles carry). So the
//! gate grows with the time since the last association, faster than any fixed velocity
//! error, and its centre does not run away with one noisy chord. The particles are moved
//! onto the line (the drift `d = Â(t) − Â(t−1)`); when the target takes a detection again,
//! its particles' process noise at that step gets the same variance
//! ([`Drift::extra_var`]), so that the estimate can reach the detection. With consecutive associations none of this
//! applies and the tracker is the paper's ([`TrackerConfig::reacquire`] `= false` turns it
//! off altogether).
//!
//! Targets associated at their previous step (or at init) choose first; the others (coasting
//! or lost), whose wider gates would otherwise take a detection from a target that holds
//! it, choose among the detections left. Each target-frame has a [`TrackStatus`]:
//! `associated`, `coasting` (no detection for at most [`TrackerConfig::lost_after`] tracked
//! frames in a row) or `lost` (longer); a lost track keeps its prediction and its growing
//! gate and is re-acquired by the first detection that falls in it.

use crate::association::{Association, Associator, Cost, gate_threshold};
use crate::data::{Detections, Init};
use crate::dynamics::{SplineDynamics, SplineOrder};
use crate::energy::{EnergyConfig, TargetGeometry};
use crate::error::{EpfError, Result};
use crate::geometry::Vec2;
use crate::model::{Drift, OptimalProposal, TargetModel};
use nalgebra::Matrix2;
use pf_core::filter::{EssThreshold, FilterConfig, ParticleFilter, ResamplePolicy};
use pf_core::gaussian::{ErrorEllipse, error_ellipse};
use pf_core::params::ParamError;
use pf_core::resample::Resampler;
use rand::Rng;
use serde::{Deserialize, Serialize};

/// Everything the tracker needs besides the data.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrackerConfig {
    /// Energy (EPF) or nearest neighbour (NNSF).
    pub association: Association,
    /// Particles per target, `N`.
    pub n_particles: usize,
    /// Resample (multinomial) when `N_eff < ess_fraction · N`.
    pub ess_fraction: f64,
    /// Probability mass of the validation gate, `P_G`.
    pub gate_probability: f64,
    /// Process noise standard deviation per √frame, `q`.
    pub q: f64,
    /// Detection noise standard deviation, `r`.
    pub r: f64,
    /// The choices left open in the energies.
    pub energy: EnergyConfig,
    /// End behaviour of the dynamic model that moves the particles and centres the gates
    /// (`Â(t)`): by default the B-spline's end derivatives applied from the last detection
    /// ([`SplineOrder::CubicBSplineEnd`], EPF step 2). The B-spline's curve continued past
    /// its end, like the quadratic, carries 7 times the chord's detection-noise variance one
    /// step ahead and loses tracks (see the crate README).
    pub spline: SplineOrder,
    /// End behaviour of the model behind E²'s predictions `Â₁(t+1)` and `Â₂(t+1)`. With
    /// [`SplineOrder::Linear`] the triangle `(Â(t−1), y_j, Â₂(t+1))` is always straight
    /// (`Â₂(t+1)` extends the chord through `y_j`), so E² would carry no information; the
    /// cubic B-spline's curve (the default, EPF step 2) and the quadratic give it the
    /// curvature the paper's Fig. 1c–d compares. The B-spline's end derivatives applied from
    /// `y_j` give the chord's displacement on evenly spaced frames, and so a straight
    /// triangle, too.
    pub energy_spline: SplineOrder,
    /// A target without a detection for more than this many tracked frames in a row is
    /// reported [`TrackStatus::Lost`] (up to it, [`TrackStatus::Coasting`]).
    #[serde(default = "default_lost_after")]
    pub lost_after: usize,
    /// Coast on the least-squares line with a growing gate, and let targets that took a
    /// detection at their previous step choose first (the module docs); `false` is the
    /// paper's tracker, which extrapolates the dynamic model whatever happened and
    /// associates every target at once.
    #[serde(default = "default_reacquire")]
    pub reacquire: bool,
}

fn default_reacquire() -> bool {
    true
}

fn default_lost_after() -> usize {
    TrackerConfig::default().lost_after
}

impl Default for TrackerConfig {
    /// The paper states none of these values; see the crate README for why these.
    fn default() -> Self {
        TrackerConfig {
            association: Association::Energy,
            n_particles: 500,
            ess_fraction: 0.5,
            gate_probability: 0.99,
            q: 0.5,
            r: 0.5,
            energy: EnergyConfig::default(),
            spline: SplineOrder::CubicBSplineEnd,
            energy_spline: SplineOrder::CubicBSpline,
            lost_after: 3,
            reacquire: true,
        }
    }
}

impl TrackerConfig {
    /// Check that the configuration can run.
    ///
    /// # Errors
    /// [`EpfError::Param`] naming the parameter.
    pub fn validate(&self) -> Result<()> {
        let bad = |name, value, reason| {
            Err(EpfError::Param(ParamError {
                name,
                value,
                reason,
            }))
        };
        if self.n_particles == 0 {
            return bad("N", 0.0, "at least one particle per target");
        }
        if !(self.ess_fraction >= 0.0 && self.ess_fraction <= 1.0) {
            return bad("ess_fraction", self.ess_fraction, "must lie in [0, 1]");
        }
        if !(self.q > 0.0 && self.q.is_finite()) {
            return bad("q", self.q, "must be positive and finite");
        }
        if !(self.r > 0.0 && self.r.is_finite()) {
            return bad("r", self.r, "must be positive and finite");
        }
        gate_threshold(self.gate_probability)?;
        self.energy.validate()
    }
}

/// What a target's track is at a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TrackStatus {
    /// It took a detection at this frame.
    Associated,
    /// No detection at this frame, for at most [`TrackerConfig::lost_after`] tracked frames
    /// in a row: the position is the prediction.
    Coasting,
    /// No detection for more than [`TrackerConfig::lost_after`] tracked frames in a row:
    /// the position is a prediction that nothing has confirmed for that long.
    Lost,
}

impl TrackStatus {
    /// The name in CSV and JSON output.
    pub fn name(self) -> &'static str {
        match self {
            TrackStatus::Associated => "associated",
            TrackStatus::Coasting => "coasting",
            TrackStatus::Lost => "lost",
        }
    }
}

/// One target at one frame, as figures and recordings show it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TargetFrame {
    /// `Â(t)`, the prediction before association.
    pub predicted: [f64; 2],
    /// The validation gate around `Â(t)`.
    pub gate: ErrorEllipse,
    /// `X̂_{k,t}`, the estimate after the update.
    pub estimate: [f64; 2],
    /// The associated detection (row index), if any.
    pub detection: Option<usize>,
    /// The track's status at this frame.
    #[serde(default = "associated")]
    pub status: TrackStatus,
    /// The particles after the update (empty unless recorded).
    pub particles: Vec<[f64; 2]>,
}

/// One tracked frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameRecord {
    /// The frame.
    pub frame: i64,
    /// Per target, in init order.
    pub targets: Vec<TargetFrame>,
}

/// One target's track.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Track {
    /// Target id (from the init data).
    pub target: i64,
    /// `X̂_{k,t}` per tracked frame.
    pub position: Vec<[f64; 2]>,
    /// The associated detection's row index (0-based, header excluded) per tracked frame.
    pub detection: Vec<Option<usize>>,
    /// The track's status per tracked frame.
    #[serde(default)]
    pub status: Vec<TrackStatus>,
}

fn associated() -> TrackStatus {
    TrackStatus::Associated
}

/// The tracker's output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrackResult {
    /// The tracked frames: every detection frame after the last init frame.
    pub frames: Vec<i64>,
    /// One track per target, in init order.
    pub tracks: Vec<Track>,
    /// Per-frame details (predictions, gates; particles when asked for).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub records: Vec<FrameRecord>,
}

/// How much per-frame detail [`track`] keeps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Record {
    /// Tracks only.
    #[default]
    Tracks,
    /// Plus predictions and gates per frame.
    Gates,
    /// Plus the particle clouds.
    Particles,
}

type TargetFilter = ParticleFilter<TargetModel, OptimalProposal>;

/// One target's filter and dynamic model.
struct TargetState {
    pf: TargetFilter,
    dynamics: SplineDynamics,
    /// The same control points under `energy_spline`, for E².
    shape: SplineDynamics,
    /// `Â(t−2)`, `Â(t−1)`.
    a_tm2: Vec2,
    a_tm1: Vec2,
    last_frame: i64,
    /// Tracked frames in a row without a detection.
    misses: usize,
    /// The last associated detections, for the coasting prediction.
    history: History,
}

/// How many associated detections a target keeps for its coasting prediction.
pub const HISTORY: usize = 6;

/// A target's last [`HISTORY`] associated detections `(frame, position)`, oldest first, in a
/// fixed array (no allocation per step).
#[derive(Debug, Clone, Copy)]
struct History {
    points: [(f64, Vec2); HISTORY],
    len: usize,
}

impl History {
    fn new() -> Self {
        History {
            points: [(0.0, Vec2::zeros()); HISTORY],
            len: 0,
        }
    }

    fn push(&mut self, t: f64, y: Vec2) {
        if self.len == HISTORY {
            self.points.rotate_left(1);
            self.len -= 1;
        }
        self.points[self.len] = (t, y);
        self.len += 1;
    }

    /// The variance factor of a velocity random walk since the last point, in units of
    /// `q²`: with `s` the mean spacing of the points and `n = (t − τ_last)/s` spacings
    /// elapsed, `s·(Σ_{i=1}^{n} i² − n) = s·(n(n+1)(2n+1)/6 − n)`, the position variance
    /// a velocity taking `q²s` per spacing adds beyond the `q²Δ` per step the particles
    /// already carry (0 for one spacing).
    fn velocity_walk(&self, t: f64) -> f64 {
        let pts = &self.points[..self.len];
        let (Some(first), Some(last)) = (pts.first(), pts.last()) else {
            return 0.0;
        };
        if pts.len() < 2 {
            return 0.0;
        }
        let s = (last.0 - first.0) / (pts.len() - 1) as f64;
        let n = (t - last.0) / s;
        (s * (n * (n + 1.0) * (2.0 * n + 1.0) / 6.0 - n)).max(0.0)
    }

    /// The least-squares line's value at `t` and its variance factor
    /// `1/n + (t − τ̄)²/Σ(τ_i − τ̄)²` (per unit detection variance); the last point, factor
    /// 1, with fewer than two.
    fn predict(&self, t: f64) -> (Vec2, f64) {
        let pts = &self.points[..self.len];
        let n = pts.len() as f64;
        if pts.len() < 2 {
            return (pts.last().map_or(Vec2::zeros(), |p| p.1), 1.0);
        }
        let tm = pts.iter().map(|p| p.0).sum::<f64>() / n;
        let ym = pts.iter().fold(Vec2::zeros(), |a, p| a + p.1) / n;
        let stt: f64 = pts.iter().map(|p| (p.0 - tm).powi(2)).sum();
        let sty = pts
            .iter()
            .fold(Vec2::zeros(), |a, p| a + (p.1 - ym) * (p.0 - tm));
        let v = sty / stt;
        (ym + v * (t - tm), 1.0 / n + (t - tm).powi(2) / stt)
    }
}

/// Each target's filter (Section 3): `N` particles, multinomial resampling in the adaptive
/// way, when `N_eff = 1/Σ_n (w_n)²` falls below `ess_fraction · N`.
pub fn filter_config(cfg: &TrackerConfig) -> FilterConfig {
    FilterConfig {
        n_particles: cfg.n_particles,
        resampler: Resampler::Multinomial,
        policy: ResamplePolicy::EssBelow(EssThreshold::Fraction(cfg.ess_fraction)),
    }
}

/// The multi-target tracker, stepped frame by frame.
pub struct Tracker {
    cfg: TrackerConfig,
    gamma: f64,
    ids: Vec<i64>,
    targets: Vec<TargetState>,
    associator: Associator,
    geometry: Vec<TargetGeometry>,
    /// `Σ̂_k` of the last step.
    sigma: Vec<Matrix2<f64>>,
    drift: Vec<Drift>,
    /// Per target, the process-noise growth it gets if it takes a detection now.
    extra_var: Vec<f64>,
    out: Vec<Option<usize>>,
    status: Vec<TrackStatus>,
    /// The second round's association buffers (targets without a detection at their
    /// previous step).
    associator_late: Associator,
    /// One round's targets (indices into `targets`), their geometry, the detections it
    /// chooses from (indices into `ys`) and its answers; reused frame to frame.
    round_targets: Vec<usize>,
    round_geometry: Vec<TargetGeometry>,
    round_ys: Vec<usize>,
    round_positions: Vec<Vec2>,
    round_out: Vec<Option<usize>>,
    last_frame: i64,
}

/// Weighted mean and covariance of 2-D particles (no allocation).
fn moments(x: &[Vec2], w: &[f64]) -> (Vec2, Matrix2<f64>) {
    let mean = x.iter().zip(w).fold(Vec2::zeros(), |m, (x, w)| m + x * *w);
    let cov = x.iter().zip(w).fold(Matrix2::zeros(), |c, (x, w)| {
        let r = x - mean;
        c + r * r.transpose() * *w
    });
    (mean, cov)
}

impl Tracker {
    /// A tracker started from `init` (EPF step 3: particles drawn around each target's last
    /// init position; its dynamic model fitted to all its init positions).
    ///
    /// # Errors
    /// An invalid configuration.
    pub fn new<R: Rng + ?Sized>(init: &Init, cfg: &TrackerConfig, rng: &mut R) -> Result<Self> {
        cfg.validate()?;
        let gamma = gate_threshold(cfg.gate_probability)?;
        let fc = filter_config(cfg);
        let mut targets = Vec::with_capacity(init.targets().len());
        for t in init.targets() {
            let mut dynamics = SplineDynamics::new(cfg.spline);
            let mut shape = SplineDynamics::new(cfg.energy_spline);
            for &(f, p) in &t.points {
                dynamics.push(f as f64, p);
                shape.push(f as f64, p);
            }
            let n = t.points.len();
            let (last_frame, x0) = t.points[n - 1];
            let model = TargetModel {
                x0,
                q: cfg.q,
                r: cfg.r,
            };
            let mut pf = ParticleFilter::new(model, OptimalProposal, fc)?;
            pf.step(None, None, rng)?;
            let mut history = History::new();
            for &(f, p) in &t.points {
                history.push(f as f64, p);
            }
            targets.push(TargetState {
                pf,
                dynamics,
                shape,
                a_tm2: t.points[n - 2].1,
                a_tm1: x0,
                last_frame,
                misses: 0,
                history,
            });
        }
        let k = targets.len();
        Ok(Tracker {
            cfg: *cfg,
            gamma,
            ids: init.targets().iter().map(|t| t.id).collect(),
            targets,
            associator: Associator::new(),
            geometry: Vec::with_capacity(k),
            sigma: Vec::with_capacity(k),
            drift: Vec::with_capacity(k),
            extra_var: Vec::with_capacity(k),
            out: vec![None; k],
            status: vec![TrackStatus::Associated; k],
            associator_late: Associator::new(),
            round_targets: Vec::with_capacity(k),
            round_geometry: Vec::with_capacity(k),
            round_ys: Vec::new(),
            round_positions: Vec::new(),
            round_out: Vec::with_capacity(k),
            last_frame: init.last_frame(),
        })
    }

    /// Target ids, in init order.
    pub fn ids(&self) -> &[i64] {
        &self.ids
    }

    /// The association buffers of the last step's first round (energies, gates): every
    /// target when all of them, or none, took a detection at their previous step; else
    /// those that did.
    pub fn associator(&self) -> &Associator {
        &self.associator
    }

    /// Each target's status after the last step.
    pub fn status(&self) -> &[TrackStatus] {
        &self.status
    }

    /// The gate's squared Mahalanobis radius `γ`.
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// The configuration.
    pub fn config(&self) -> &TrackerConfig {
        &self.cfg
    }

    /// The geometry of each target at the last step (`Â(t−2)`, …, `Σ̂_k⁻¹`).
    pub fn geometry(&self) -> &[TargetGeometry] {
        &self.geometry
    }

    /// Each target's particles.
    pub fn particles(&self, k: usize) -> &[Vec2] {
        self.targets[k].pf.particles()
    }

    /// The validation gate of target `k` at the last step.
    ///
    /// # Errors
    /// A covariance that is not positive definite.
    pub fn gate(&self, k: usize) -> Result<ErrorEllipse> {
        let g = &self.geometry[k];
        let cov = self.sigma[k];
        Ok(error_ellipse(
            [g.a_t.x, g.a_t.y],
            [[cov[(0, 0)], cov[(0, 1)]], [cov[(1, 0)], cov[(1, 1)]]],
            self.cfg.gate_probability,
        )?)
    }

    /// Process frame `frame` with its detections `ys`; returns, per target, the index into
    /// `ys` of its detection.
    ///
    /// # Errors
    /// [`EpfError::FrameBackwards`] if `frame` is not after the last one; a filter error.
    pub fn step<R: Rng + ?Sized>(
        &mut self,
        frame: i64,
        ys: &[Vec2],
        rng: &mut R,
    ) -> Result<&[Option<usize>]> {
        if frame <= self.last_frame {
            return Err(EpfError::FrameBackwards {
                file: "detections",
                row: 0,
                frame,
                previous: self.last_frame,
            });
        }
        self.geometry.clear();
        self.sigma.clear();
        self.drift.clear();
        self.extra_var.clear();
        let (q2, r2) = (self.cfg.q * self.cfg.q, self.cfg.r * self.cfg.r);
        for s in &self.targets {
            let dt = (frame - s.last_frame) as f64;
            let t_prev = s.last_frame as f64;
            let (d, drift_var, extra) = if s.misses == 0 || !self.cfg.reacquire {
                // The paper's step: the dynamic model's displacement.
                let d = s.dynamics.displacement(t_prev, dt);
                (
                    d,
                    r2 * s.dynamics.displacement_noise_factor(t_prev, dt),
                    0.0,
                )
            } else {
                // Coasting: onto the least-squares line through the last detections.
                let (line, c) = s.history.predict(frame as f64);
                let v = r2 * c + q2 * s.history.velocity_walk(frame as f64);
                (line - s.a_tm1, v, v)
            };
            self.extra_var.push(extra);
            let a_t = s.a_tm1 + d;
            let a1_tp1 = a_t + s.shape.displacement(frame as f64, dt);
            let (_, p) = moments(s.pf.particles(), s.pf.weights());
            let sigma = p + Matrix2::identity() * (q2 * dt + r2 + drift_var);
            let cov_inv = sigma
                .try_inverse()
                .unwrap_or_else(|| Matrix2::identity() / (q2 * dt + r2));
            self.geometry.push(TargetGeometry {
                a_tm2: s.a_tm2,
                a_tm1: s.a_tm1,
                a_t,
                a1_tp1,
                cov_inv,
                dynamics: s.shape,
                t: frame as f64,
                dt_next: dt,
            });
            self.sigma.push(sigma);
            self.drift.push(Drift {
                d,
                dt,
                extra_var: 0.0,
            });
        }
        self.associate(ys);
        for (k, s) in self.targets.iter_mut().enumerate() {
            let y = self.out[k].map(|j| ys[j]);
            if y.is_some() {
                self.drift[k].extra_var = self.extra_var[k];
            }
            s.pf.step(Some(&self.drift[k]), y.as_ref(), rng)?;
            if let Some(y) = y {
                s.dynamics.push(frame as f64, y);
                s.shape.push(frame as f64, y);
                s.misses = 0;
                s.history.push(frame as f64, y);
                self.status[k] = TrackStatus::Associated;
            } else {
                s.misses += 1;
                self.status[k] = if s.misses > self.cfg.lost_after {
                    TrackStatus::Lost
                } else {
                    TrackStatus::Coasting
                };
            }
            let (mean, _) = moments(s.pf.particles(), s.pf.weights());
            s.a_tm2 = s.a_tm1;
            s.a_tm1 = mean;
            s.last_frame = frame;
        }
        self.last_frame = frame;
        Ok(&self.out)
    }

    /// Step 1 in two rounds: the targets that took a detection at their previous step
    /// associate first, then the others among the detections left (in one round when all
    /// targets are of one kind). Fills `self.out`.
    fn associate(&mut self, ys: &[Vec2]) {
        let fresh = |s: &TargetState| s.misses == 0;
        let n_fresh = self.targets.iter().filter(|s| fresh(s)).count();
        if !self.cfg.reacquire || n_fresh == 0 || n_fresh == self.targets.len() {
            self.associator.associate(
                &self.geometry,
                ys,
                self.gamma,
                self.cfg.association,
                &self.cfg.energy,
                &mut self.out,
            );
            return;
        }
        self.out.fill(None);
        self.round_ys.clear();
        self.round_ys.extend(0..ys.len());
        for first in [true, false] {
            self.round_targets.clear();
            self.round_targets.extend(
                self.targets
                    .iter()
                    .enumerate()
                    .filter(|(_, s)| fresh(s) == first)
                    .map(|(k, _)| k),
            );
            self.round_geometry.clear();
            self.round_geometry
                .extend(self.round_targets.iter().map(|&k| self.geometry[k]));
            self.round_positions.clear();
            self.round_positions
                .extend(self.round_ys.iter().map(|&j| ys[j]));
            self.round_out.clear();
            self.round_out.resize(self.round_targets.len(), None);
            let associator = if first {
                &mut self.associator
            } else {
                &mut self.associator_late
            };
            associator.associate(
                &self.round_geometry,
                &self.round_positions,
                self.gamma,
                self.cfg.association,
                &self.cfg.energy,
                &mut self.round_out,
            );
            for (&k, o) in self.round_targets.iter().zip(&self.round_out) {
                self.out[k] = o.map(|i| self.round_ys[i]);
            }
            // The detections left for the second round.
            let out = &self.out;
            self.round_ys.retain(|j| !out.contains(&Some(*j)));
        }
    }

    /// `X̂_{k,t}` of target `k` after the last step.
    pub fn estimate(&self, k: usize) -> Vec2 {
        self.targets[k].a_tm1
    }
}

/// Where a tracker's `q` or `r` came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NoiseSource {
    /// Given by the user.
    Given,
    /// Estimated from the init tracks ([`Init::estimate_noise`]).
    Estimated,
    /// [`TrackerConfig::default`]'s, the init tracks being too short to estimate it.
    Default,
}

impl NoiseSource {
    /// The name in messages and JSON.
    pub fn name(self) -> &'static str {
        match self {
            NoiseSource::Given => "given",
            NoiseSource::Estimated => "estimated from the init tracks",
            NoiseSource::Default => "default: no init track has 4 frames",
        }
    }
}

/// The `q` and `r` a tracker uses, and where each came from.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NoiseChoice {
    /// Process noise sd per √frame.
    pub q: f64,
    /// Detection noise sd.
    pub r: f64,
    /// Where `q` came from.
    pub q_source: NoiseSource,
    /// Where `r` came from.
    pub r_source: NoiseSource,
}

impl NoiseChoice {
    /// The given values where there are some; the others estimated from `init`'s tracks,
    /// or [`TrackerConfig::default`]'s when no track has the four frames the estimate needs.
    pub fn new(init: &Init, q: Option<f64>, r: Option<f64>) -> Self {
        let est = if q.is_none() || r.is_none() {
            init.estimate_noise()
        } else {
            None
        };
        let d = TrackerConfig::default();
        let pick =
            |given: Option<f64>, estimated: Option<f64>, default: f64| match (given, estimated) {
                (Some(v), _) => (v, NoiseSource::Given),
                (None, Some(v)) => (v, NoiseSource::Estimated),
                (None, None) => (default, NoiseSource::Default),
            };
        let (q, q_source) = pick(q, est.map(|e| e.q), d.q);
        let (r, r_source) = pick(r, est.map(|e| e.r), d.r);
        NoiseChoice {
            q,
            r,
            q_source,
            r_source,
        }
    }

    /// `cfg` with this `q` and `r`.
    pub fn apply(&self, cfg: &TrackerConfig) -> TrackerConfig {
        TrackerConfig {
            q: self.q,
            r: self.r,
            ..*cfg
        }
    }
}

/// The frames to track: every detection frame after the last init frame.
///
/// # Errors
/// [`EpfError::NothingToTrack`] when there is none.
pub fn tracked_frames(detections: &Detections, init: &Init) -> Result<Vec<i64>> {
    let last_init = init.last_frame();
    let frames: Vec<i64> = detections
        .frames()
        .into_iter()
        .filter(|&f| f > last_init)
        .collect();
    if frames.is_empty() {
        return Err(EpfError::NothingToTrack { last_init });
    }
    Ok(frames)
}

/// Track every target through `detections` (EPF or NNSF, as `cfg.association` says).
///
/// # Errors
/// An invalid configuration, nothing to track, or a filter error.
pub fn track<R: Rng + ?Sized>(
    detections: &Detections,
    init: &Init,
    cfg: &TrackerConfig,
    record: Record,
    rng: &mut R,
) -> Result<TrackResult> {
    let frames = tracked_frames(detections, init)?;
    let mut tracker = Tracker::new(init, cfg, rng)?;
    let k = tracker.ids().len();
    let mut tracks: Vec<Track> = tracker
        .ids()
        .iter()
        .map(|&target| Track {
            target,
            position: Vec::with_capacity(frames.len()),
            detection: Vec::with_capacity(frames.len()),
            status: Vec::with_capacity(frames.len()),
        })
        .collect();
    let mut records = Vec::new();
    let mut ys = Vec::new();
    for &frame in &frames {
        let rows = detections.positions_into(frame, &mut ys);
        let out = tracker.step(frame, &ys, rng)?.to_vec();
        for (i, tr) in tracks.iter_mut().enumerate() {
            let e = tracker.estimate(i);
            tr.position.push([e.x, e.y]);
            tr.detection.push(out[i].map(|j| rows.start + j));
            tr.status.push(tracker.status()[i]);
        }
        if record != Record::Tracks {
            let mut targets = Vec::with_capacity(k);
            for (i, tr) in tracks.iter().enumerate() {
                let g = &tracker.geometry()[i];
                targets.push(TargetFrame {
                    predicted: [g.a_t.x, g.a_t.y],
                    gate: tracker.gate(i)?,
                    estimate: *tr.position.last().expect("pushed above"),
                    detection: *tr.detection.last().expect("pushed above"),
                    status: tracker.status()[i],
                    particles: if record == Record::Particles {
                        tracker.particles(i).iter().map(|p| [p.x, p.y]).collect()
                    } else {
                        Vec::new()
                    },
                });
            }
            records.push(FrameRecord { frame, targets });
        }
    }
    Ok(TrackResult {
        frames,
        tracks,
        records,
    })
}

/// The energies of every target against every detection at one frame, in the style of the
/// paper's Tables 1–2.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EnergyTable {
    /// The frame `t`.
    pub frame: i64,
    /// Target ids (rows).
    pub targets: Vec<i64>,
    /// Detection row indices (columns).
    pub detections: Vec<usize>,
    /// Detection positions.
    pub positions: Vec<[f64; 2]>,
    /// Raw `E¹, E², E³` as K rows of M values each.
    pub raw: [Vec<Vec<f64>>; 3],
    /// Weighted `α_l E^l` as K rows of M values each (what the paper's Table 1 lists).
    pub weighted: [Vec<Vec<f64>>; 3],
    /// `E(k, y_j)`, eq. (1).
    pub e: Vec<Vec<f64>>,
    /// Whether `y_j` falls in target `k`'s gate.
    pub gated: Vec<Vec<bool>>,
    /// Each target's detection (row index) under `cfg.association`.
    pub assignment: Vec<Option<usize>>,
}

/// Track up to `frame` and return the energies computed there. The energies are computed
/// whatever `cfg.association` says; the frames before are associated as it says.
///
/// # Errors
/// [`EpfError::UnknownFrame`] if `frame` is not a tracked frame; as [`track`].
pub fn energies_at<R: Rng + ?Sized>(
    detections: &Detections,
    init: &Init,
    cfg: &TrackerConfig,
    frame: i64,
    rng: &mut R,
) -> Result<EnergyTable> {
    let frames = tracked_frames(detections, init)?;
    if !frames.contains(&frame) {
        return Err(EpfError::UnknownFrame {
            frame,
            tracked: frames,
        });
    }
    let mut tracker = Tracker::new(init, cfg, rng)?;
    let mut ys = Vec::new();
    for &f in frames.iter().take_while(|&&f| f < frame) {
        detections.positions_into(f, &mut ys);
        tracker.step(f, &ys, rng)?;
    }
    let rows = detections.frame_rows(frame);
    ys.clear();
    ys.extend(detections.rows()[rows.clone()].iter().map(|d| d.position));
    let mut energy_cfg = *cfg;
    if energy_cfg.association.cost() != Cost::Energy {
        energy_cfg.association = Association::Energy;
    }
    tracker.cfg = energy_cfg;
    let out = tracker.step(frame, &ys, rng)?.to_vec();
    // The table holds every target against every detection, whatever rounds the step
    // associated in.
    let mut a = Associator::new();
    let mut all = vec![None; tracker.ids().len()];
    a.associate(
        tracker.geometry(),
        &ys,
        tracker.gamma(),
        energy_cfg.association,
        &energy_cfg.energy,
        &mut all,
    );
    let e = a.energy();
    let (k, m) = (e.n_targets(), e.n_detections());
    Ok(EnergyTable {
        frame,
        targets: tracker.ids().to_vec(),
        detections: rows.clone().collect(),
        positions: ys.iter().map(|y| [y.x, y.y]).collect(),
        raw: [e.raw_rows(0), e.raw_rows(1), e.raw_rows(2)],
        weighted: [e.rows(0), e.rows(1), e.rows(2)],
        e: e.rows(3),
        gated: (0..k)
            .map(|i| (0..m).map(|j| a.is_gated(i, j, m)).collect())
            .collect(),
        assignment: out.iter().map(|o| o.map(|j| rows.start + j)).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::{Detection, InitRow};
    use pf_core::mc::stream_rng;

    fn init() -> Init {
        let r = |target, frame, x: f64, y: f64| InitRow {
            target,
            frame,
            position: Vec2::new(x, y),
        };
        Init::new(&[
            r(0, 0, 0.0, 0.0),
            r(0, 1, 1.0, 0.0),
            r(1, 0, 0.0, 10.0),
            r(1, 1, 1.0, 10.0),
        ])
        .unwrap()
    }

    /// Two well separated targets moving right: every association right; a frame where
    /// target 1 is missed leaves it without detection and with a finite prediction.
    #[test]
    fn tracks_separated_targets_and_survives_a_miss() {
        let d = |frame, x: f64, y: f64| Detection {
            frame,
            position: Vec2::new(x, y),
            target: None,
        };
        let dets = Detections::new(vec![
            d(2, 2.0, 0.0),
            d(2, 2.0, 10.0),
            d(3, 3.0, 0.0),
            d(4, 4.0, 10.0),
            d(4, 4.0, 0.0),
        ])
        .unwrap();
        for association in [Association::Energy, Association::Nearest] {
            let cfg = TrackerConfig {
                association,
                n_particles: 200,
                ..TrackerConfig::default()
            };
            let res = track(&dets, &init(), &cfg, Record::Gates, &mut stream_rng(1, 0)).unwrap();
            assert_eq!(res.frames, [2, 3, 4]);
            assert_eq!(res.tracks[0].detection, [Some(0), Some(2), Some(4)]);
            assert_eq!(res.tracks[1].detection, [Some(1), None, Some(3)]);
            // Target 1 at frame 3 is predicted by its constant velocity. The data lie
            // exactly on x = t, y = 10, so the posterior mean is (3, 10) up to Monte Carlo
            // error: the predictive sd is about √(r²/2 + q²) ≈ 0.6, over √200 particles
            // ≈ 0.04; 0.3 is 7 of those.
            let p = res.tracks[1].position[1];
            assert!(
                (p[0] - 3.0).abs() < 0.3 && (p[1] - 10.0).abs() < 0.3,
                "{p:?}"
            );
            assert_eq!(res.records.len(), 3);
        }
        let e = energies_at(
            &dets,
            &init(),
            &TrackerConfig::default(),
            1,
            &mut stream_rng(1, 0),
        );
        assert!(matches!(
            e,
            Err(EpfError::UnknownFrame { frame: 1, ref tracked }) if tracked == &[2, 3, 4]
        ));
        assert_eq!(
            e.unwrap_err().to_string(),
            "frame 1 is not a tracked frame (tracked frames: 2, 3, 4)"
        );
    }
}
