//! The marginalized particle filter for model (5).
//!
//! Two forms of the Kalman part:
//! - [`Riccati::Shared`] is Alg. 1 (`C_t = 0`): every particle's Kalman filter has the same
//!   covariance, so one Riccati recursion serves all particles, and the time update works on
//!   all `N` particles at once, as Table I writes it (`T2 := randn(p,N)`, `w := T1·T2`, …).
//!   The p×N and k×N products go through faer.
//! - [`Riccati::PerParticle`] is the general `C_t ≠ 0` MPF of Schön, Gustafsson & Nordlund
//!   (the paper's ref. \[15\]): each particle carries its own covariance, updated by a Kalman
//!   measurement update and a Riccati time update, all with fixed-size nalgebra matrices.
//!
//! With `k = 0` both are the standard (bootstrap) PF on `x = x^p`, drawing random numbers in
//! the same order as pf-core's [`ParticleFilter`](pf_core::filter::ParticleFilter), so the
//! two agree on the same seed.
//!
//! One step at time `t` (the first call is `t = 0`):
//! 1. `t > 0`: resample with the weights of `t − 1` (eq. (6)); the Kalman statistics travel
//!    with their particles;
//! 2. `t > 0`: PF time update, eqs. (8)–(9), and KF time update, eq. (10);
//! 3. importance weights `q_t^{(i)} = N(y_t; h_t(x^{p,(i)}_t) + C_t x̂^{k,(i)}_{t|t−1}, S_t^{(i)})`
//!    (Alg. 1, step 2, with `S = R` when `C_t = 0`) and the KF measurement update (eq. (7)
//!    when `C_t = 0`).

use crate::error::{MpfError, Result};
use crate::model::{Measurement, MixedLinearGaussian, half_log_det_2pi, log_normal_chol};
use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef};
use nalgebra::{Cholesky, SMatrix, SVector, SVectorView};
use pf_core::filter::StepReport;
use pf_core::params::ParamError;
use pf_core::resample::{Resample, Resampler};
use pf_core::weights;
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

/// Which form of the Kalman part runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Riccati {
    /// Alg. 1 when `C_t = 0`, else the per-particle form.
    #[default]
    Auto,
    /// Alg. 1: one Riccati recursion shared by all particles (needs `C_t = 0`).
    Shared,
    /// One covariance per particle (ref. \[15\]); valid for any `C_t`.
    PerParticle,
}

/// Configuration of the MPF.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MpfConfig {
    /// Number of particles `N`.
    pub n_particles: usize,
    /// Resampling scheme (eq. (6) is multinomial; systematic is the lower-variance default).
    pub resampler: Resampler,
    /// Shared or per-particle Riccati recursion.
    pub riccati: Riccati,
}

impl Default for MpfConfig {
    /// `N = 2000` as in Section IV-B, systematic resampling, automatic Riccati form.
    fn default() -> Self {
        Self {
            n_particles: 2000,
            resampler: Resampler::Systematic,
            riccati: Riccati::Auto,
        }
    }
}

impl MpfConfig {
    /// `N` particles, otherwise the defaults.
    pub fn new(n_particles: usize) -> Self {
        Self {
            n_particles,
            ..Self::default()
        }
    }

    /// Check that the configuration can run.
    ///
    /// # Errors
    /// `N = 0`, or `N` above [`MAX_COUNT`](pf_core::limits::MAX_COUNT).
    pub fn validate(&self) -> Result<()> {
        if self.n_particles == 0 {
            return Err(MpfError::Param(ParamError {
                name: "N",
                value: 0.0,
                reason: "the number of particles must be at least 1",
            }));
        }
        pf_core::limits::check_count("the number of particles N", self.n_particles)?;
        Ok(())
    }
}

fn view<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(m.as_slice(), R, C)
}

fn block(v: &[f64], rows: usize, n: usize) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(v, rows, n)
}

fn block_mut(v: &mut [f64], rows: usize, n: usize) -> MatMut<'_, f64> {
    MatMut::from_column_major_slice_mut(v, rows, n)
}

fn col<const D: usize>(v: &[f64], i: usize) -> SVector<f64, D> {
    SVectorView::<f64, D>::from_slice(&v[i * D..(i + 1) * D]).into_owned()
}

fn set_col<const D: usize>(v: &mut [f64], i: usize, x: &SVector<f64, D>) {
    v[i * D..(i + 1) * D].copy_from_slice(x.as_slice());
}

fn symmetrise<const D: usize>(p: &mut SMatrix<f64, D, D>) {
    for j in 0..D {
        for i in (j + 1)..D {
            let s = 0.5 * (p[(i, j)] + p[(j, i)]);
            p[(i, j)] = s;
            p[(j, i)] = s;
        }
    }
}

/// The marginalized particle filter for model (5); see the [module docs](self).
///
/// Particle blocks are stored column-major: `x^p` as a p×N block, `x̂^k` as a k×N block.
/// Every buffer is allocated once, in [`Mpf::new`].
pub struct Mpf<const P: usize, const K: usize, const NY: usize, H> {
    model: MixedLinearGaussian<P, K, NY, H>,
    resampler: Resampler,
    shared: bool,
    n: usize,
    /// `x^{p,(i)}_t`, p×N.
    xp: Vec<f64>,
    /// `x̂^{k,(i)}_{t|t}` (after the step's measurement update), k×N.
    xk: Vec<f64>,
    /// `P^{(i)}_{t|t}`: one entry (Alg. 1) or N.
    pk: Vec<SMatrix<f64, K, K>>,
    /// Resampled copies.
    xp_r: Vec<f64>,
    xk_r: Vec<f64>,
    pk_r: Vec<SMatrix<f64, K, K>>,
    /// Table I temporaries: `T2`, `w`, `T3`, `T4` (p×N); `T7`, `T8` (k×N); `T9` (p×N).
    t2: Vec<f64>,
    w_noise: Vec<f64>,
    t3: Vec<f64>,
    t4: Vec<f64>,
    t7: Vec<f64>,
    t8: Vec<f64>,
    t9: Vec<f64>,
    log_w: Vec<f64>,
    w: Vec<f64>,
    ancestors: Vec<usize>,
    last: Option<StepReport>,
}

/// The configuration and the last step, not the particle blocks.
impl<const P: usize, const K: usize, const NY: usize, H> std::fmt::Debug for Mpf<P, K, NY, H> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Mpf")
            .field("partition", &(P, K))
            .field("n_particles", &self.n)
            .field("resampler", &self.resampler)
            .field("shared_riccati", &self.shared)
            .field("last", &self.last)
            .finish_non_exhaustive()
    }
}

impl<const P: usize, const K: usize, const NY: usize, H: Measurement<P, NY>> Mpf<P, K, NY, H> {
    /// A filter for `model`.
    ///
    /// # Errors
    /// A bad configuration, or [`Riccati::Shared`] with `C_t ≠ 0`.
    pub fn new(model: MixedLinearGaussian<P, K, NY, H>, config: MpfConfig) -> Result<Self> {
        config.validate()?;
        let shared = match config.riccati {
            Riccati::Auto => model.c_is_zero(),
            Riccati::PerParticle => false,
            Riccati::Shared => {
                if !model.c_is_zero() {
                    return Err(MpfError::SharedRiccatiNeedsZeroC {
                        max_abs: model.c().amax(),
                    });
                }
                true
            }
        };
        let n = config.n_particles;
        let n_cov = if shared { 1 } else { n };
        // Every buffer's size, checked against the machine's memory before any is taken, so
        // that a count it cannot hold is an error rather than an aborted allocation.
        const WHAT: &str = "the MPF's particle buffers";
        let per_particle = (7 * P + 4 * K + 2) * size_of::<f64>() + size_of::<usize>();
        let covariances = 2 * size_of::<SMatrix<f64, K, K>>();
        let bytes = n
            .saturating_mul(per_particle)
            .saturating_add(n_cov.saturating_mul(covariances));
        pf_core::limits::check_memory(WHAT, n, bytes)?;
        let zeros = |len: usize| pf_core::limits::try_filled(WHAT, len, 0.0);
        let covs = || pf_core::limits::try_filled(WHAT, n_cov, SMatrix::zeros());
        let mut ancestors = pf_core::limits::try_with_capacity(WHAT, n)?;
        ancestors.extend(0..n);
        Ok(Self {
            model,
            resampler: config.resampler,
            shared,
            n,
            xp: zeros(P * n)?,
            xk: zeros(K * n)?,
            pk: covs()?,
            xp_r: zeros(P * n)?,
            xk_r: zeros(K * n)?,
            pk_r: covs()?,
            t2: zeros(P * n)?,
            w_noise: zeros(P * n)?,
            t3: zeros(P * n)?,
            t4: zeros(P * n)?,
            t7: zeros(K * n)?,
            t8: zeros(K * n)?,
            t9: zeros(P * n)?,
            log_w: zeros(n)?,
            w: pf_core::limits::try_filled(WHAT, n, 1.0 / n as f64)?,
            ancestors,
            last: None,
        })
    }

    /// The model.
    pub fn model(&self) -> &MixedLinearGaussian<P, K, NY, H> {
        &self.model
    }

    /// Number of particles `N`.
    pub fn n_particles(&self) -> usize {
        self.n
    }

    /// Whether Alg. 1's shared Riccati recursion is in use.
    pub fn is_shared(&self) -> bool {
        self.shared
    }

    /// Forget everything; the next step is `t = 0`.
    pub fn reset(&mut self) {
        self.last = None;
    }

    /// The report of the last step.
    pub fn last_report(&self) -> Option<&StepReport> {
        self.last.as_ref()
    }

    /// Running log-likelihood estimate `Σ_t log p̂(y_t | Y_{t−1})`.
    pub fn log_likelihood(&self) -> f64 {
        self.last.map_or(0.0, |r| r.log_lik)
    }

    /// Normalised weights `q̃_t^{(i)}`.
    pub fn weights(&self) -> &[f64] {
        &self.w
    }

    /// Ancestors `A_t^i` of the last step (identity at `t = 0`).
    pub fn ancestors(&self) -> &[usize] {
        &self.ancestors
    }

    /// The PF particles `x^{p,(i)}_t` as a column-major p×N block.
    pub fn xp_block(&self) -> &[f64] {
        &self.xp
    }

    /// The KF means `x̂^{k,(i)}_{t|t}` as a column-major k×N block.
    pub fn xk_block(&self) -> &[f64] {
        &self.xk
    }

    /// `x^{p,(i)}_t`.
    pub fn particle_p(&self, i: usize) -> SVector<f64, P> {
        col(&self.xp, i)
    }

    /// `x̂^{k,(i)}_{t|t}`.
    pub fn kf_mean(&self, i: usize) -> SVector<f64, K> {
        col(&self.xk, i)
    }

    /// `P^{(i)}_{t|t}` (the shared one under Alg. 1).
    pub fn kf_cov(&self, i: usize) -> &SMatrix<f64, K, K> {
        if self.shared {
            &self.pk[0]
        } else {
            &self.pk[i]
        }
    }

    /// The filter estimates `x̂^p_{t|t} = Σ q̃_i x^{p,(i)}_t` and
    /// `x̂^k_{t|t} = Σ q̃_i x̂^{k,(i)}_{t|t}`.
    ///
    /// # Errors
    /// [`CoreError::Empty`](pf_core::CoreError::Empty) before the first step, when there is
    /// nothing to estimate from (the buffers hold zeros, not particles).
    pub fn estimate(&self) -> Result<(SVector<f64, P>, SVector<f64, K>)> {
        if self.last.is_none() {
            return Err(pf_core::CoreError::Empty {
                what: "MPF particle set (no step made yet)",
            }
            .into());
        }
        let mut mp = SVector::<f64, P>::zeros();
        let mut mk = SVector::<f64, K>::zeros();
        for (i, &wi) in self.w.iter().enumerate() {
            for d in 0..P {
                mp[d] += wi * self.xp[i * P + d];
            }
            for d in 0..K {
                mk[d] += wi * self.xk[i * K + d];
            }
        }
        Ok((mp, mk))
    }

    /// Advance one step: `t = 0` on the first call, then `t + 1`. `y = None` is a missing
    /// observation: no reweighting, no KF measurement update.
    ///
    /// # Errors
    /// A non-finite observation, a covariance that is not positive definite (`M_t`, `S_t`),
    /// or all weights zero; the step's `t` and particle are named.
    pub fn step<R: Rng + ?Sized>(
        &mut self,
        y: Option<&SVector<f64, NY>>,
        rng: &mut R,
    ) -> Result<StepReport> {
        let t = self.last.map_or(0, |r| r.t + 1);
        if let Some(y) = y
            && let Some((index, &value)) = y.iter().enumerate().find(|(_, v)| !v.is_finite())
        {
            return Err(MpfError::NonFiniteObservation { t, index, value });
        }
        let n = self.n;
        match self.last {
            None => self.initialise(rng),
            Some(_) => {
                self.resampler.resample(&self.w, rng, &mut self.ancestors);
                self.gather();
                self.time_update(t, rng)?;
            }
        }
        let log_n = (n as f64).ln();
        let log_c = match y {
            Some(y) => {
                self.measurement_update(t, y)?;
                for lw in &mut self.log_w {
                    *lw -= log_n;
                }
                weights::normalise(t, &mut self.log_w, &mut self.w)?
            }
            None => {
                self.w.fill(1.0 / n as f64);
                self.log_w.fill(-log_n);
                0.0
            }
        };
        let report = StepReport {
            t,
            log_lik_increment: log_c,
            log_lik: self.log_likelihood() + log_c,
            ess: weights::ess(&self.w),
            resampled: t > 0,
        };
        self.last = Some(report);
        Ok(report)
    }

    /// Alg. 1, step 1: `x^{p,(i)}_0 ~ p(x^p_0)`, `{x̂^k, P} = {x̄^k_0, P̄_0}`.
    fn initialise<R: Rng + ?Sized>(&mut self, rng: &mut R) {
        for i in 0..self.n {
            let x = self.model.x0_p().sample(rng);
            set_col(&mut self.xp, i, &x);
            set_col(&mut self.xk, i, self.model.x0_k());
            self.ancestors[i] = i;
        }
        self.pk.fill(*self.model.p0_k());
    }

    /// Copy the resampled particles, KF means and covariances into the `_r` buffers.
    fn gather(&mut self) {
        for (i, &a) in self.ancestors.iter().enumerate() {
            self.xp_r[i * P..(i + 1) * P].copy_from_slice(&self.xp[a * P..(a + 1) * P]);
            self.xk_r[i * K..(i + 1) * K].copy_from_slice(&self.xk[a * K..(a + 1) * K]);
            if !self.shared {
                self.pk_r[i] = self.pk[a];
            }
        }
        if self.shared {
            self.pk_r[0] = self.pk[0];
        }
    }

    /// PF time update (eqs. (8)–(9)) and KF time update (eq. (10)), from the resampled
    /// buffers into `xp`, `xk`, `pk`, following Table I.
    fn time_update<R: Rng + ?Sized>(&mut self, t: usize, rng: &mut R) -> Result<()> {
        let n = self.n;
        let par = faer::Par::Seq;
        let m = &self.model;
        // T2 := randn(p, N)
        for z in &mut self.t2 {
            *z = StandardNormal.sample(rng);
        }
        // T3 := A^p x^p, T4 := A^k x^k, T7 := F^k x^k, T8 := F^p x^p (all particles at once).
        let xp_r = block(&self.xp_r, P, n);
        let xk_r = block(&self.xk_r, K, n);
        matmul(
            block_mut(&mut self.t3, P, n),
            Accum::Replace,
            view(m.a_p()),
            xp_r,
            1.0,
            par,
        );
        matmul(
            block_mut(&mut self.t4, P, n),
            Accum::Replace,
            view(m.a_k()),
            xk_r,
            1.0,
            par,
        );
        matmul(
            block_mut(&mut self.t7, K, n),
            Accum::Replace,
            view(m.f_k()),
            xk_r,
            1.0,
            par,
        );
        matmul(
            block_mut(&mut self.t8, K, n),
            Accum::Replace,
            view(m.f_p()),
            xp_r,
            1.0,
            par,
        );
        if self.shared {
            let p_tt = self.pk_r[0];
            let (t1, l_gain, p_next) =
                riccati_time_update(m, &p_tt).ok_or(MpfError::NotPositiveDefinite {
                    what: "M_t",
                    t,
                    particle: 0,
                })?;
            // w := T1·T2
            matmul(
                block_mut(&mut self.w_noise, P, n),
                Accum::Replace,
                view(&t1),
                block(&self.t2, P, n),
                1.0,
                par,
            );
            // x̂^p_{t+1|t} := T3 + T4 + w
            for (((x, a), b), c) in self
                .xp
                .iter_mut()
                .zip(&self.t3)
                .zip(&self.t4)
                .zip(&self.w_noise)
            {
                *x = a + b + c;
            }
            // T9 := x̂^p_{t+1|t} − T3 − T4
            for (((d, x), a), b) in self.t9.iter_mut().zip(&self.xp).zip(&self.t3).zip(&self.t4) {
                *d = x - a - b;
            }
            // x̂^k_{t+1|t} := T7 + T8 + L·T9
            for ((x, a), b) in self.xk.iter_mut().zip(&self.t7).zip(&self.t8) {
                *x = a + b;
            }
            matmul(
                block_mut(&mut self.xk, K, n),
                Accum::Add,
                view(&l_gain),
                block(&self.t9, P, n),
                1.0,
                par,
            );
            self.pk[0] = p_next;
        } else {
            for i in 0..n {
                let (t1, l_gain, p_next) =
                    riccati_time_update(m, &self.pk_r[i]).ok_or(MpfError::NotPositiveDefinite {
                        what: "M_t",
                        t,
                        particle: i,
                    })?;
                let z: SVector<f64, P> = col(&self.t2, i);
                let t3: SVector<f64, P> = col(&self.t3, i);
                let t4: SVector<f64, P> = col(&self.t4, i);
                let xp = t3 + t4 + t1 * z;
                let t9 = xp - t3 - t4;
                let xk = col::<K>(&self.t7, i) + col::<K>(&self.t8, i) + l_gain * t9;
                set_col(&mut self.xp, i, &xp);
                set_col(&mut self.xk, i, &xk);
                self.pk[i] = p_next;
            }
        }
        Ok(())
    }

    /// Alg. 1, step 2 (importance weights, unnormalised, into `log_w`) and the KF
    /// measurement update: eq. (7) when shared (`C_t = 0`), the Kalman update of ref. \[15\]
    /// otherwise.
    fn measurement_update(&mut self, t: usize, y: &SVector<f64, NY>) -> Result<()> {
        let m = &self.model;
        if self.shared {
            for i in 0..self.n {
                let xp: SVector<f64, P> = col(&self.xp, i);
                self.log_w[i] = m.log_likelihood_p(t, &xp, y);
            }
            return Ok(());
        }
        let r = m.r();
        for i in 0..self.n {
            let xp: SVector<f64, P> = col(&self.xp, i);
            let xk: SVector<f64, K> = col(&self.xk, i);
            let p = self.pk[i];
            let y_hat = m.h().h(t, &xp) + m.c() * xk;
            let e = m.h().residual(y, &y_hat);
            let pct = p * m.c().transpose();
            let mut s = m.c() * pct + r;
            symmetrise(&mut s);
            let chol = Cholesky::new(s).ok_or(MpfError::NotPositiveDefinite {
                what: "S_t = C P Cᵀ + R",
                t,
                particle: i,
            })?;
            let l = chol.l();
            self.log_w[i] = log_normal_chol(&l, e, half_log_det_2pi(&l));
            // K = P Cᵀ S⁻¹ (S symmetric: solve S Kᵀ = C P).
            let gain = chol.solve(&pct.transpose()).transpose();
            set_col(&mut self.xk, i, &(xk + gain * e));
            // Joseph form: (I − K C) P (I − K C)ᵀ + K R Kᵀ.
            let ikc = SMatrix::<f64, K, K>::identity() - gain * m.c();
            let mut p_new = ikc * p * ikc.transpose() + gain * r * gain.transpose();
            symmetrise(&mut p_new);
            self.pk[i] = p_new;
        }
        Ok(())
    }
}

/// Eq. (10)'s Riccati part, given `P_{t|t}`: returns `T1 = chol(M_t)`, `L_t` and
/// `P_{t+1|t}`, with `M_t = A^k P (A^k)ᵀ + Q^p`, `L_t = F^k P (A^k)ᵀ M_t⁻¹`,
/// `P_{t+1|t} = F^k P (F^k)ᵀ + Q^k − L_t M_t L_tᵀ`. `None` if `M_t` is not positive definite.
#[allow(clippy::type_complexity)]
fn riccati_time_update<const P: usize, const K: usize, const NY: usize, H>(
    m: &MixedLinearGaussian<P, K, NY, H>,
    p_tt: &SMatrix<f64, K, K>,
) -> Option<(SMatrix<f64, P, P>, SMatrix<f64, K, P>, SMatrix<f64, K, K>)> {
    // P_A := P (A^k)ᵀ ; M := A^k P_A + Q^p ; T1 := chol(M)
    let p_a = p_tt * m.a_k().transpose();
    let mut mm = m.a_k() * p_a + m.q_p();
    symmetrise(&mut mm);
    let chol = Cholesky::new(mm)?;
    let t1 = chol.l();
    // L := F^k P_A M⁻¹ (M symmetric: solve M Lᵀ = P_Aᵀ (F^k)ᵀ).
    let l_gain = chol.solve(&(m.f_k() * p_a).transpose()).transpose();
    // P := F^k P (F^k)ᵀ + Q^k − L M Lᵀ
    let mut p_next =
        m.f_k() * p_tt * m.f_k().transpose() + m.q_k() - l_gain * mm * l_gain.transpose();
    symmetrise(&mut p_next);
    Some((t1, l_gain, p_next))
}
