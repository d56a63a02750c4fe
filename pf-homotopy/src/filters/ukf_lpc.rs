//! The UKF in log-polar coordinates (UKF-LPC), the paper's first benchmark (its refs. \[2\],
//! \[8\]), and a Cartesian UKF for comparison.
//!
//! The belief is Gaussian in the log-polar coordinates of the target *relative to the
//! observer*, `z = [β, ln r, β̇, ṙ/r]` (Brehard & Le Cadre): the bearing is the first
//! coordinate, so the measurement is linear in `z`, and range (log r) stays separate from
//! the well-observed bearing. The observer's own motion enters the coordinate
//! transformation: with `s = x − o` the relative state and `o_k` the observer's
//! `[position, velocity]`, (18) gives `s_{k+1} = F(s_k + o_k) − o_{k+1} + w_k`; the
//! prediction is the unscented transform of `z_k ↦ lpc(F(cart(z_k) + o_k) − o_{k+1} + w_k)`
//! over the augmented `[z_k; w_k]`, since `w_k ~ N(0, Q)` is additive in Cartesian, not in
//! log-polar, coordinates.
//!
//! Bearings are kept continuous through the transform (`β' = β + wrap_angle(β' − β)`) and every
//! residual is wrapped (`pf_core::kalman::Ukf` takes the residual as a closure).
//!
//! ## References
//! - S. Julier, J. Uhlmann, H. F. Durrant-Whyte, *IEEE TAC* 45(3), 2000.
//! - T. Brehard, J.-P. Le Cadre, "Closed-form posterior Cramér–Rao bounds for bearings-only
//!   tracking", *IEEE TAES* 42(4), 2006 (log-polar coordinates).

use nalgebra::{DMatrix, DVector, Matrix4, Vector4};
use pf_core::kalman::{KalmanState, Ukf, UkfParams};

use crate::error::{Result, check_data};
use crate::model::bearing;
use crate::model::{ObserverState, Realisation, ScenarioConfig};
use pf_core::geometry::wrap_angle;

/// Log-polar coordinates `[β, ln r, β̇, ṙ/r]` of a relative Cartesian state `[x, y, ẋ, ẏ]`.
pub fn lpc_from_rel(s: &Vector4<f64>) -> Vector4<f64> {
    let r2 = s[0] * s[0] + s[1] * s[1];
    Vector4::new(
        s[1].atan2(s[0]),
        0.5 * r2.ln(),
        (s[0] * s[3] - s[1] * s[2]) / r2,
        (s[0] * s[2] + s[1] * s[3]) / r2,
    )
}

/// The relative Cartesian state of log-polar coordinates `z`.
pub fn rel_from_lpc(z: &Vector4<f64>) -> Vector4<f64> {
    let r = z[1].exp();
    let (sb, cb) = z[0].sin_cos();
    Vector4::new(
        r * cb,
        r * sb,
        r * (z[3] * cb - z[2] * sb),
        r * (z[3] * sb + z[2] * cb),
    )
}

fn obs_vec(o: &ObserverState) -> Vector4<f64> {
    Vector4::new(o.pos[0], o.pos[1], o.vel[0], o.vel[1])
}

fn v4(d: &DVector<f64>, off: usize) -> Vector4<f64> {
    Vector4::new(d[off], d[off + 1], d[off + 2], d[off + 3])
}

fn wrapped_residual(a: &DVector<f64>, b: &DVector<f64>) -> DVector<f64> {
    let mut d = a - b;
    d[0] = wrap_angle(d[0]);
    d
}

/// The UKF-LPC tracker.
#[derive(Debug, Clone)]
pub struct UkfLpc {
    aug_ukf: Ukf,
    ukf: Ukf,
    f: Matrix4<f64>,
    q: Matrix4<f64>,
    r: DMatrix<f64>,
    /// `N(z, P_z)`.
    state: KalmanState,
    aug: KalmanState,
    scratch: KalmanState,
    zero4: DMatrix<f64>,
    zero8: DMatrix<f64>,
}

impl UkfLpc {
    /// Initialise from the first bearing: the unscented transform of the independent polar
    /// prior `[β, r, speed, heading]` into log-polar coordinates relative to `o1`.
    ///
    /// # Errors
    /// Bad settings, or a transform that fails (non-finite sigma points).
    pub fn new(
        scenario: &ScenarioConfig,
        params: UkfParams,
        y1: f64,
        o1: &ObserverState,
    ) -> Result<Self> {
        scenario.validate()?;
        check_data("bearing", 1, y1)?;
        let pr = scenario.prior;
        let sigma = scenario.sigma();
        let mut ukf = Ukf::new(params)?;
        let mut st = KalmanState::new(
            DVector::from_vec(vec![y1, pr.range_mean, pr.speed_mean, pr.heading_mean]),
            DMatrix::from_diagonal(&DVector::from_vec(vec![
                sigma * sigma,
                pr.range_sd * pr.range_sd,
                pr.speed_sd * pr.speed_sd,
                pr.heading_sd * pr.heading_sd,
            ])),
        );
        let ov = o1.vel;
        // A sigma point with r ≤ 0 has no log-polar image: NaN, which the UKF reports.
        ukf.predict(
            &mut st,
            |x| {
                let (b, r, s, h) = (x[0], x[1], x[2], x[3]);
                let rel = Vector4::new(
                    r * b.cos(),
                    r * b.sin(),
                    s * h.cos() - ov[0],
                    s * h.sin() - ov[1],
                );
                let mut z = lpc_from_rel(&rel);
                z[0] = b + wrap_angle(z[0] - b);
                if r <= 0.0 {
                    z[1] = f64::NAN;
                }
                DVector::from_column_slice(z.as_slice())
            },
            &DMatrix::zeros(4, 4),
        )?;
        Self::from_state(params, scenario, ukf, st)
    }

    /// Initialise from a Cartesian Gaussian `N(m, P)` of the target state when the observer
    /// is at `o1`: the unscented transform into log-polar coordinates.
    ///
    /// # Errors
    /// Bad settings, or a non-positive-definite `P`.
    pub fn from_cartesian(
        scenario: &ScenarioConfig,
        params: UkfParams,
        m: Vector4<f64>,
        p: Matrix4<f64>,
        o1: &ObserverState,
    ) -> Result<Self> {
        scenario.validate()?;
        let mut ukf = Ukf::new(params)?;
        let mut st = KalmanState::new(
            DVector::from_column_slice(m.as_slice()),
            DMatrix::from_fn(4, 4, |i, j| p[(i, j)]),
        );
        let o = obs_vec(o1);
        let b0 = (m[1] - o[1]).atan2(m[0] - o[0]);
        ukf.predict(
            &mut st,
            |x| {
                let mut z = lpc_from_rel(&(v4(x, 0) - o));
                z[0] = b0 + wrap_angle(z[0] - b0);
                DVector::from_column_slice(z.as_slice())
            },
            &DMatrix::zeros(4, 4),
        )?;
        Self::from_state(params, scenario, ukf, st)
    }

    fn from_state(
        params: UkfParams,
        scenario: &ScenarioConfig,
        ukf: Ukf,
        st: KalmanState,
    ) -> Result<Self> {
        let sigma = scenario.sigma();
        Ok(Self {
            aug_ukf: Ukf::new(params)?,
            ukf,
            f: scenario.f(),
            q: scenario.q_matrix(),
            r: DMatrix::from_element(1, 1, sigma * sigma),
            state: st,
            aug: KalmanState::new(DVector::zeros(8), DMatrix::zeros(8, 8)),
            scratch: KalmanState::new(DVector::zeros(4), DMatrix::zeros(4, 4)),
            zero4: DMatrix::zeros(4, 4),
            zero8: DMatrix::zeros(8, 8),
        })
    }

    /// The log-polar belief `N(z, P_z)`.
    pub fn state(&self) -> &KalmanState {
        &self.state
    }

    /// Prediction from the observer state `o_prev` (at `k − 1`) to `o_next` (at `k`).
    ///
    /// # Errors
    /// A covariance that is no longer positive definite.
    pub fn predict(&mut self, o_prev: &ObserverState, o_next: &ObserverState) -> Result<()> {
        self.aug.m.fill(0.0);
        self.aug.p.fill(0.0);
        self.aug.m.rows_mut(0, 4).copy_from(&self.state.m);
        self.aug.p.view_mut((0, 0), (4, 4)).copy_from(&self.state.p);
        for i in 0..4 {
            for j in 0..4 {
                self.aug.p[(4 + i, 4 + j)] = self.q[(i, j)];
            }
        }
        let f = self.f;
        let (op, on) = (obs_vec(o_prev), obs_vec(o_next));
        self.aug_ukf.predict(
            &mut self.aug,
            |x| {
                let z = v4(x, 0);
                let w = v4(x, 4);
                let s_next = f * (rel_from_lpc(&z) + op) - on + w;
                let mut z2 = lpc_from_rel(&s_next);
                z2[0] = z[0] + wrap_angle(z2[0] - z[0]);
                let mut out = x.clone();
                out.rows_mut(0, 4).copy_from(&z2);
                out
            },
            &self.zero8,
        )?;
        self.state.m.copy_from(&self.aug.m.rows(0, 4));
        self.state.p.copy_from(&self.aug.p.view((0, 0), (4, 4)));
        Ok(())
    }

    /// Measurement update with bearing `y` (linear in log-polar coordinates, residual wrapped).
    ///
    /// # Errors
    /// A non-positive-definite innovation or state covariance.
    pub fn update(&mut self, y: f64) -> Result<()> {
        let yv = DVector::from_element(1, y);
        self.ukf.update(
            &mut self.state,
            |z| DVector::from_element(1, z[0]),
            &self.r,
            &yv,
            wrapped_residual,
        )?;
        self.state.m[0] = wrap_angle(self.state.m[0]);
        Ok(())
    }

    /// The Cartesian mean of the target `[x, y, ẋ, ẏ]` when the observer is at `o`: the
    /// unscented transform of `N(z, P_z)` through `z ↦ cart(z) + o`.
    ///
    /// # Errors
    /// A non-positive-definite covariance.
    pub fn cartesian_mean(&mut self, o: &ObserverState) -> Result<Vector4<f64>> {
        self.scratch.m.copy_from(&self.state.m);
        self.scratch.p.copy_from(&self.state.p);
        let ov = obs_vec(o);
        self.ukf.predict(
            &mut self.scratch,
            |z| {
                let c = rel_from_lpc(&v4(z, 0)) + ov;
                DVector::from_column_slice(c.as_slice())
            },
            &self.zero4,
        )?;
        Ok(v4(&self.scratch.m, 0))
    }
}

/// Filter a realisation with the UKF-LPC; position means at `k = 1, …, K`.
///
/// # Errors
/// As [`UkfLpc::new`], [`UkfLpc::predict`], [`UkfLpc::update`].
pub fn run(
    scenario: &ScenarioConfig,
    params: UkfParams,
    real: &Realisation,
) -> Result<Vec<[f64; 2]>> {
    let f = UkfLpc::new(scenario, params, real.bearings[0], &real.observer[0])?;
    run_from(f, real)
}

/// Filter a realisation from an initialised tracker `f` (its belief at `k = 1`, e.g. from
/// [`UkfLpc::from_cartesian`]); position means at `k = 1, …, K`.
///
/// # Errors
/// As [`UkfLpc::predict`], [`UkfLpc::update`].
pub fn run_from(mut f: UkfLpc, real: &Realisation) -> Result<Vec<[f64; 2]>> {
    let obs = &real.observer;
    let mut out = Vec::with_capacity(real.bearings.len());
    let m = f.cartesian_mean(&obs[0])?;
    out.push([m[0], m[1]]);
    for k in 1..real.bearings.len() {
        f.predict(&obs[k - 1], &obs[k])?;
        f.update(real.bearings[k])?;
        let m = f.cartesian_mean(&obs[k])?;
        out.push([m[0], m[1]]);
    }
    Ok(out)
}

/// A UKF in Cartesian coordinates `[x, y, ẋ, ẏ]` with the bearing measurement (21)–(22):
/// the reference for the UKF-LPC when the problem is nearly linear.
#[derive(Debug, Clone)]
pub struct CartesianUkf {
    ukf: Ukf,
    f: Matrix4<f64>,
    q: DMatrix<f64>,
    r: DMatrix<f64>,
    /// The belief.
    pub state: KalmanState,
}

impl CartesianUkf {
    /// Start from `N(m, P)`.
    ///
    /// # Errors
    /// Bad UKF parameters or scenario.
    pub fn new(
        scenario: &ScenarioConfig,
        params: UkfParams,
        m: Vector4<f64>,
        p: Matrix4<f64>,
    ) -> Result<Self> {
        scenario.validate()?;
        let q = scenario.q_matrix();
        let s = scenario.sigma();
        Ok(Self {
            ukf: Ukf::new(params)?,
            f: scenario.f(),
            q: DMatrix::from_fn(4, 4, |i, j| q[(i, j)]),
            r: DMatrix::from_element(1, 1, s * s),
            state: KalmanState::new(
                DVector::from_column_slice(m.as_slice()),
                DMatrix::from_fn(4, 4, |i, j| p[(i, j)]),
            ),
        })
    }

    /// Prediction by (18).
    ///
    /// # Errors
    /// A non-positive-definite covariance.
    pub fn predict(&mut self) -> Result<()> {
        let f = self.f;
        self.ukf.predict(
            &mut self.state,
            |x| DVector::from_column_slice((f * v4(x, 0)).as_slice()),
            &self.q,
        )?;
        Ok(())
    }

    /// Update with bearing `y` from `rho` (residual wrapped).
    ///
    /// # Errors
    /// A non-positive-definite covariance.
    pub fn update(&mut self, y: f64, rho: [f64; 2]) -> Result<()> {
        self.ukf.update(
            &mut self.state,
            |x| DVector::from_element(1, bearing([x[0], x[1]], rho)),
            &self.r,
            &DVector::from_element(1, y),
            wrapped_residual,
        )?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lpc_round_trip() {
        let s = Vector4::new(-3000.0, 4000.0, 50.0, -120.0);
        let z = lpc_from_rel(&s);
        assert!((z[1] - 5000f64.ln()).abs() < 1e-14);
        let back = rel_from_lpc(&z);
        // Round-off of exp/ln/sin/cos on O(5000) numbers: a few ε·5000.
        assert!((back - s).amax() < 1e-9, "{back} vs {s}");
    }
}
