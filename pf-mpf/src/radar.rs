//! The radar tracking example, eq. (13): a constant-acceleration target seen by range and
//! azimuth, and the partitions of its linear states between PF and KF.

use crate::error::{MpfError, Result};
use crate::model::{
    FactoredGaussian, Lanes, Measurement, MixedLinearGaussian, Model5Matrices, TILE,
};
use crate::mpf::{Mpf, MpfConfig};
use nalgebra::{SMatrix, SVector};
use pf_core::geometry::wrap_angle;
use pf_core::mc::Par;
use pf_core::params::ParamError;
use pf_core::simd::special;
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Full state `[p_x p_y v_x v_y a_x a_y]`.
pub type RadarState = SVector<f64, 6>;
/// Measurement `[range, azimuth]`.
pub type RadarObs = SVector<f64, 2>;

/// Eq. (13b): range `√(p_x² + p_y²)` and azimuth `atan2(p_y, p_x)`, read from the first two
/// components of `x^p` (positions are always PF states). The azimuth residual is wrapped.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RangeAzimuth;

impl<const P: usize> Measurement<P, 2> for RangeAzimuth {
    #[inline]
    fn h(&self, _t: usize, xp: &SVector<f64, P>) -> RadarObs {
        RadarObs::new(xp[0].hypot(xp[1]), xp[1].atan2(xp[0]))
    }

    #[inline]
    fn residual(&self, y: &RadarObs, y_hat: &RadarObs) -> RadarObs {
        RadarObs::new(y[0] - y_hat[0], wrap_angle(y[1] - y_hat[1]))
    }

    /// Column by column: `y_r − hypot(p_x, p_y)` and `y_a − atan2(p_y, p_x)` with pf-core's
    /// vectorising [`hypot`](special::hypot) and [`atan2`](special::atan2) (within 1 and
    /// 2 ulp of the C library's), the azimuth residual wrapped into `[−π, π]` by subtracting
    /// the nearest multiple of `2π` (the same value as [`wrap_angle`] for residuals already
    /// in range, which it returns unchanged).
    #[inline(always)]
    fn residuals(&self, _t: usize, y: &RadarObs, xp: &[&[f64]; P], m: usize, e: &mut [Lanes; 2]) {
        let m = m.min(TILE);
        let (px, py) = (&xp[0][..m], &xp[1][..m]);
        let [e_r, e_a] = e;
        for ((e, &x), &y_) in e_r[..m].iter_mut().zip(px).zip(py) {
            *e = y[0] - special::hypot(x, y_);
        }
        for ((e, &x), &y_) in e_a[..m].iter_mut().zip(px).zip(py) {
            *e = y[1] - special::atan2(y_, x);
        }
        // round(d/2π) by the 1.5·2⁵² trick: exact for |d/2π| < 2⁵¹, no libm call.
        const ROUND: f64 = 6_755_399_441_055_744.0;
        for e in &mut e_a[..m] {
            let k = (*e * (1.0 / TAU) + ROUND) - ROUND;
            *e -= TAU * k;
        }
    }
}

/// The radar scenario: the paper's model (13) plus the values it leaves unstated.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RadarConfig {
    /// Sampling period `T` (s). Unstated in the paper; 1 s.
    pub period: f64,
    /// Number of time samples `T_f`. Unstated; 100.
    pub n_steps: usize,
    /// `diag Q` (the paper: `[1 1 1 1 0.01 0.01]`).
    pub q_diag: [f64; 6],
    /// `diag R` (the paper: `[100, 1e-6]`).
    pub r_diag: [f64; 2],
    /// True initial state. Unstated; a target 2–3 km out moving at ~22 m/s.
    pub x0: [f64; 6],
    /// Prior mean offset is zero; prior `diag P_0`. Unstated; `[100 100 25 25 0.1 0.1]`.
    pub p0_diag: [f64; 6],
    /// Seed of the one true trajectory (the paper uses one trajectory and varies the noise).
    pub trajectory_seed: u64,
}

impl Default for RadarConfig {
    fn default() -> Self {
        Self {
            period: 1.0,
            n_steps: 100,
            q_diag: [1.0, 1.0, 1.0, 1.0, 0.01, 0.01],
            r_diag: [100.0, 1e-6],
            x0: [2000.0, 1500.0, -20.0, 10.0, 0.0, 0.0],
            p0_diag: [100.0, 100.0, 25.0, 25.0, 0.1, 0.1],
            trajectory_seed: 2005,
        }
    }
}

impl RadarConfig {
    /// Check every value.
    ///
    /// # Errors
    /// A non-positive period or variance, no steps, or a non-finite value.
    pub fn validate(&self) -> Result<()> {
        let bad = |name, value: f64, reason| {
            Err(MpfError::Param(ParamError {
                name,
                value,
                reason,
            }))
        };
        if !(self.period.is_finite() && self.period > 0.0) {
            return bad("T", self.period, "the sampling period must be positive");
        }
        if self.n_steps < 2 {
            return Err(MpfError::TooFewObservations {
                got: self.n_steps,
                need: 2,
            });
        }
        for &v in self.q_diag.iter().chain(&self.r_diag).chain(&self.p0_diag) {
            if !(v.is_finite() && v > 0.0) {
                return bad("diag(Q, R, P0)", v, "variances must be positive and finite");
            }
        }
        for &v in &self.x0 {
            if !v.is_finite() {
                return bad("x0", v, "initial state must be finite");
            }
        }
        Ok(())
    }

    /// The transition matrix of eq. (13a).
    pub fn a(&self) -> SMatrix<f64, 6, 6> {
        let t = self.period;
        let mut a = SMatrix::<f64, 6, 6>::identity();
        for i in 0..4 {
            a[(i, i + 2)] = t;
        }
        a[(0, 4)] = t * t / 2.0;
        a[(1, 5)] = t * t / 2.0;
        a
    }

    /// Simulate the true trajectory `x_1 … x_{T_f}` (with `x_0` given) from eq. (13a) with
    /// the trajectory seed's stream.
    pub fn truth(&self) -> Vec<RadarState> {
        let mut rng = pf_core::mc::stream_rng(self.trajectory_seed, u64::MAX);
        let a = self.a();
        let sq: [f64; 6] = self.q_diag.map(f64::sqrt);
        let mut x = RadarState::from_row_slice(&self.x0);
        let mut out = Vec::with_capacity(self.n_steps);
        for _ in 0..self.n_steps {
            out.push(x);
            let w = RadarState::from_fn(|i, _| {
                let z: f64 = StandardNormal.sample(&mut rng);
                sq[i] * z
            });
            x = a * x + w;
        }
        out
    }

    /// Noisy measurements of `truth` by eq. (13b).
    pub fn measure<R: Rng + ?Sized>(
        &self,
        truth: &[RadarState],
        rng: &mut R,
    ) -> Vec<Option<RadarObs>> {
        let sr = self.r_diag.map(f64::sqrt);
        truth
            .iter()
            .map(|x| {
                let e0: f64 = StandardNormal.sample(rng);
                let e1: f64 = StandardNormal.sample(rng);
                Some(RadarObs::new(
                    x[0].hypot(x[1]) + sr[0] * e0,
                    wrap_angle(x[1].atan2(x[0]) + sr[1] * e1),
                ))
            })
            .collect()
    }
}

/// Which of the six states the KF takes, written as in the paper (`PPKKPP`: velocities in
/// the KF). Positions must be `P`: the measurement is nonlinear in them.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub struct Partition {
    kalman: [bool; 6],
}

impl TryFrom<String> for Partition {
    type Error = MpfError;
    fn try_from(s: String) -> Result<Self> {
        s.parse()
    }
}

impl From<Partition> for String {
    fn from(p: Partition) -> String {
        p.name()
    }
}

impl std::str::FromStr for Partition {
    type Err = MpfError;
    fn from_str(s: &str) -> Result<Self> {
        let err = |reason| MpfError::Partition {
            partition: s.to_string(),
            reason,
        };
        let chars: Vec<char> = s.chars().collect();
        if chars.len() != 6 {
            return Err(err(
                "expected six letters P or K, one per state [px py vx vy ax ay]",
            ));
        }
        let mut kalman = [false; 6];
        for (i, c) in chars.iter().enumerate() {
            kalman[i] = match c {
                'P' | 'p' => false,
                'K' | 'k' => true,
                _ => {
                    return Err(err(
                        "letters must be P (particle filter) or K (Kalman filter)",
                    ));
                }
            };
        }
        if kalman[0] || kalman[1] {
            return Err(err(
                "positions enter the measurement nonlinearly and must be P",
            ));
        }
        Ok(Self { kalman })
    }
}

impl Partition {
    /// The four partitions of Tables II and III.
    pub fn paper() -> Vec<Partition> {
        ["PPPPPP", "PPKKPP", "PPPPKK", "PPKKKK"]
            .iter()
            .map(|s| s.parse().expect("valid"))
            .collect()
    }

    /// All 16 partitions of the four linear states (Fig. 3).
    pub fn all() -> Vec<Partition> {
        (0..16u32)
            .map(|bits| {
                let mut kalman = [false; 6];
                for j in 0..4 {
                    kalman[2 + j] = bits & (1 << (3 - j)) != 0;
                }
                Partition { kalman }
            })
            .collect()
    }

    /// `PPKKPP` and so on.
    pub fn name(&self) -> String {
        self.kalman
            .iter()
            .map(|&k| if k { 'K' } else { 'P' })
            .collect()
    }

    /// `k`, the number of KF states.
    pub fn k(&self) -> usize {
        self.kalman.iter().filter(|&&k| k).count()
    }

    /// `p = 6 − k`.
    pub fn p(&self) -> usize {
        6 - self.k()
    }

    /// Indices (into the full state) of `x^p`, in order.
    pub fn p_indices(&self) -> Vec<usize> {
        (0..6).filter(|&i| !self.kalman[i]).collect()
    }

    /// Indices of `x^k`, in order.
    pub fn k_indices(&self) -> Vec<usize> {
        (0..6).filter(|&i| self.kalman[i]).collect()
    }

    /// Model (5) for this partition of eq. (13): `A^p = A[P,P]`, `A^k = A[P,K]`,
    /// `F^p = A[K,P]`, `F^k = A[K,K]`, `Q^p`, `Q^k` the diagonal blocks (Q is diagonal, so
    /// the noises are independent), `C_t = 0`. The prior is centred on the true `x_0`.
    ///
    /// # Errors
    /// `P + K ≠ 6` or a `P`/`K` that does not match this partition; a bad config.
    pub fn model<const P: usize, const K: usize>(
        &self,
        cfg: &RadarConfig,
    ) -> Result<MixedLinearGaussian<P, K, 2, RangeAzimuth>> {
        cfg.validate()?;
        if P != self.p() || K != self.k() {
            return Err(MpfError::Partition {
                partition: self.name(),
                reason: "the filter's (p, k) does not match the partition",
            });
        }
        let a = cfg.a();
        let (pi, ki) = (self.p_indices(), self.k_indices());
        let q = SMatrix::<f64, 6, 6>::from_diagonal(&SVector::from_row_slice(&cfg.q_diag));
        let p0 = SMatrix::<f64, 6, 6>::from_diagonal(&SVector::from_row_slice(&cfg.p0_diag));
        let x0 = cfg.x0;
        let m = Model5Matrices::<P, K, 2> {
            a_p: SMatrix::from_fn(|r, c| a[(pi[r], pi[c])]),
            a_k: SMatrix::from_fn(|r, c| a[(pi[r], ki[c])]),
            f_p: SMatrix::from_fn(|r, c| a[(ki[r], pi[c])]),
            f_k: SMatrix::from_fn(|r, c| a[(ki[r], ki[c])]),
            q_p: SMatrix::from_fn(|r, c| q[(pi[r], pi[c])]),
            q_k: SMatrix::from_fn(|r, c| q[(ki[r], ki[c])]),
            c: SMatrix::zeros(),
            r: SMatrix::from_diagonal(&SVector::from_row_slice(&cfg.r_diag)),
            x0_p: SVector::from_fn(|r, _| x0[pi[r]]),
            p0_p: SMatrix::from_fn(|r, c| p0[(pi[r], pi[c])]),
            x0_k: SVector::from_fn(|r, _| x0[ki[r]]),
            p0_k: SMatrix::from_fn(|r, c| p0[(ki[r], ki[c])]),
        };
        let _ = FactoredGaussian::<2>::new("R", SVector::zeros(), m.r)?;
        MixedLinearGaussian::new(m, RangeAzimuth)
    }
}

/// Squared errors of one run, per time step, and its filter time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunErrors {
    /// `‖p − p̂‖²` per step.
    pub sq_pos: Vec<f64>,
    /// `‖v − v̂‖²` per step.
    pub sq_vel: Vec<f64>,
    /// `‖a − â‖²` per step.
    pub sq_acc: Vec<f64>,
    /// Wall-clock time of the filter loop (s).
    pub time_s: f64,
}

/// What one run looked like step by step, for recordings: the particles' positions and
/// the mean each particle's Kalman filter holds for the linear states.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct RunTrace {
    /// Names of the states in `kf_means` (e.g. `["vx", "vy"]` for `PPKKPP`).
    pub kf_states: Vec<String>,
    /// Per step, `[p_x, p_y]` of every particle.
    pub positions: Vec<Vec<[f64; 2]>>,
    /// Per step, every particle's KF mean `x̂^k` (empty for the standard PF).
    pub kf_means: Vec<Vec<Vec<f64>>>,
    /// Per step, normalised weights.
    pub weights: Vec<Vec<f64>>,
    /// Per step, the filter's estimate of the full state `[p v a]`.
    pub estimates: Vec<[f64; 6]>,
}

const STATE_NAMES: [&str; 6] = ["px", "py", "vx", "vy", "ax", "ay"];

fn run_pk<const P: usize, const K: usize, R: Rng + ?Sized>(
    part: &Partition,
    cfg: &RadarConfig,
    mpf_cfg: MpfConfig,
    truth: &[RadarState],
    ys: &[Option<RadarObs>],
    rng: &mut R,
    mut trace: Option<&mut RunTrace>,
) -> Result<RunErrors> {
    let model = part.model::<P, K>(cfg)?;
    // The chunk streams of the engine come from one draw of the caller's stream. Runs are
    // sequential: their callers replicate them in parallel, or time them.
    let mut filter = Mpf::new(model, mpf_cfg, rng.next_u64(), Par::Seq)?;
    let (pi, ki) = (part.p_indices(), part.k_indices());
    let n = truth.len();
    let mut est = vec![[0.0; 6]; n];
    let n_part = filter.n_particles();
    let mut col = vec![0.0; if trace.is_some() { n_part } else { 0 }];
    let start = std::time::Instant::now();
    if let Some(tr) = trace.as_deref_mut() {
        tr.kf_states = ki.iter().map(|&i| STATE_NAMES[i].to_string()).collect();
    }
    for (t, y) in ys.iter().enumerate() {
        filter.step(y.as_ref())?;
        let (mp, mk) = filter.estimate()?;
        for (r, &i) in pi.iter().enumerate() {
            est[t][i] = mp[r];
        }
        for (r, &i) in ki.iter().enumerate() {
            est[t][i] = mk[r];
        }
        if let Some(tr) = trace.as_deref_mut() {
            filter.column_into(0, &mut col)?;
            let mut pos: Vec<[f64; 2]> = col.iter().map(|&x| [x, 0.0]).collect();
            filter.column_into(1, &mut col)?;
            for (p, &y) in pos.iter_mut().zip(&col) {
                p[1] = y;
            }
            tr.positions.push(pos);
            let mut means = vec![Vec::with_capacity(K); n_part];
            for r in 0..K {
                filter.column_into(P + r, &mut col)?;
                for (m, &x) in means.iter_mut().zip(&col) {
                    m.push(x);
                }
            }
            tr.kf_means.push(means);
            filter.weights_into(&mut col)?;
            tr.weights.push(col.clone());
            tr.estimates.push(est[t]);
        }
    }
    let time_s = start.elapsed().as_secs_f64();
    let sq = |t: usize, a: usize| {
        (truth[t][a] - est[t][a]).powi(2) + (truth[t][a + 1] - est[t][a + 1]).powi(2)
    };
    Ok(RunErrors {
        sq_pos: (0..n).map(|t| sq(t, 0)).collect(),
        sq_vel: (0..n).map(|t| sq(t, 2)).collect(),
        sq_acc: (0..n).map(|t| sq(t, 4)).collect(),
        time_s,
    })
}

/// Run the MPF of `part` with `mpf_cfg` on measurements `ys` of `truth`, dispatching to the
/// fixed-size filter for its `(p, k)`.
///
/// # Errors
/// Length mismatch, a bad config, or a filter error.
pub fn run_partition<R: Rng + ?Sized>(
    part: &Partition,
    cfg: &RadarConfig,
    mpf_cfg: MpfConfig,
    truth: &[RadarState],
    ys: &[Option<RadarObs>],
    rng: &mut R,
) -> Result<RunErrors> {
    dispatch(part, cfg, mpf_cfg, truth, ys, rng, None)
}

/// [`run_partition`], also recording every step's particles and KF means (for
/// recordings; the copies make it slower, so time with [`run_partition`]).
///
/// # Errors
/// As [`run_partition`].
pub fn trace_partition<R: Rng + ?Sized>(
    part: &Partition,
    cfg: &RadarConfig,
    mpf_cfg: MpfConfig,
    truth: &[RadarState],
    ys: &[Option<RadarObs>],
    rng: &mut R,
) -> Result<(RunErrors, RunTrace)> {
    let mut trace = RunTrace::default();
    let errors = dispatch(part, cfg, mpf_cfg, truth, ys, rng, Some(&mut trace))?;
    Ok((errors, trace))
}

fn dispatch<R: Rng + ?Sized>(
    part: &Partition,
    cfg: &RadarConfig,
    mpf_cfg: MpfConfig,
    truth: &[RadarState],
    ys: &[Option<RadarObs>],
    rng: &mut R,
    trace: Option<&mut RunTrace>,
) -> Result<RunErrors> {
    if truth.len() != ys.len() {
        return Err(pf_core::CoreError::DimensionMismatch {
            what: "observations against true states",
            expected: truth.len(),
            got: ys.len(),
        }
        .into());
    }
    crate::model::check_observations(ys)?;
    match part.k() {
        0 => run_pk::<6, 0, R>(part, cfg, mpf_cfg, truth, ys, rng, trace),
        1 => run_pk::<5, 1, R>(part, cfg, mpf_cfg, truth, ys, rng, trace),
        2 => run_pk::<4, 2, R>(part, cfg, mpf_cfg, truth, ys, rng, trace),
        3 => run_pk::<3, 3, R>(part, cfg, mpf_cfg, truth, ys, rng, trace),
        _ => run_pk::<2, 4, R>(part, cfg, mpf_cfg, truth, ys, rng, trace),
    }
}
