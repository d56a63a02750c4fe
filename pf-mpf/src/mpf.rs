//! The marginalized particle filter for model (5), on pf-core's batch engine.
//!
//! Each particle is a row of columns: `x^{p,(i)}` (p columns), then its Kalman filter's
//! mean `x̂^{k,(i)}` (k columns), then, when every particle has its own covariance, the
//! entries of `P^{(i)}` on and above the diagonal (k(k+1)/2 columns). pf-core's
//! [`BatchFilter`] resamples the rows (eq. (6)) and calls the model on chunks of them, so
//! the Kalman statistics travel with their particles.
//!
//! Two models, one per form of the Kalman part:
//! - [`SharedMpf`] is Alg. 1 (`C_t = 0`): every particle's Kalman filter has the same
//!   covariance, so one Riccati recursion, eq. (10), serves all particles. It does not depend
//!   on the particles or on `y`, so it is computed once, when the model is built, for every
//!   `t` (see [`SharedMpf::covers`]); a step is then a linear combination of the parents'
//!   columns and the normals with that step's coefficients, eqs. (8)–(10), and the weight
//!   `N(y_t; h_t(x^p_t), R)` of Alg. 1, step 2.
//! - [`PerParticleMpf`] is the general `C_t ≠ 0` MPF of Schön, Gustafsson & Nordlund (the
//!   paper's ref. \[15\]): each particle carries its own covariance, and a step runs, per
//!   particle, the Kalman measurement update with `y_{t−1}` (the step's input), then the
//!   Riccati time update, on tiles of [`TILE`] particles held as arrays of lanes.
//!
//! With `k = 0` either is the standard (bootstrap) PF on `x = x^p`.
//!
//! [`Mpf`] runs either on the engine and gives the filter estimates `x̂^p_{t|t}` and
//! `x̂^k_{t|t}`.

// The per-particle algebra indexes matrices by row and column, as the equations do, and
// each quantity's lanes by `q`: the indices are the notation, not a missed iterator.
#![allow(clippy::needless_range_loop)]

use crate::error::{MpfError, Result};
use crate::model::{Lanes, Measurement, MixedLinearGaussian, TILE, half_log_det_2pi};
use nalgebra::{Cholesky, SMatrix, SVector};
use pf_core::filter::{BatchConfig, BatchFilter, BatchModel, Bootstrap, Cols, ColsMut, StepReport};
use pf_core::gaussian::LN_2PI;
use pf_core::mc::Par;
use pf_core::params::ParamError;
use pf_core::resample::Resampler;
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

    /// The engine's configuration: resampling at every step (Alg. 1, step 3), streams from
    /// `seed`, chunks on `par`.
    pub fn batch(&self, seed: u64, par: Par) -> BatchConfig {
        BatchConfig {
            resampler: self.resampler,
            par,
            ..BatchConfig::new(self.n_particles, seed)
        }
    }
}

/// `out[i] = offset + Σ_j c_j · x_j[i]` over the terms whose coefficient is not zero, in
/// passes of up to four terms (a model's constant matrices are sparse: the radar's `A` has
/// 10 non-zero entries of 36).
#[inline(always)]
pub(crate) fn lincomb<'a>(
    out: &mut [f64],
    offset: f64,
    terms: impl IntoIterator<Item = (f64, &'a [f64])>,
) {
    let mut buf: [(f64, &[f64]); 4] = [(0.0, &[]); 4];
    let (mut m, mut first) = (0, true);
    for (c, x) in terms {
        if c == 0.0 {
            continue;
        }
        buf[m] = (c, x);
        m += 1;
        if m == 4 {
            lincomb_pass(out, offset, &buf, first);
            (m, first) = (0, false);
        }
    }
    if m > 0 || first {
        lincomb_pass(out, offset, &buf[..m], first);
    }
}

/// One pass of [`lincomb`]: `out = offset + Σ` on the first, `out += Σ` after.
#[inline(always)]
fn lincomb_pass(out: &mut [f64], offset: f64, t: &[(f64, &[f64])], first: bool) {
    let n = out.len();
    match *t {
        [] => out.fill(offset),
        [(a, x)] => {
            let x = &x[..n];
            if first {
                for (o, &x) in out.iter_mut().zip(x) {
                    *o = offset + a * x;
                }
            } else {
                for (o, &x) in out.iter_mut().zip(x) {
                    *o += a * x;
                }
            }
        }
        [(a, x), (b, y)] => {
            let (x, y) = (&x[..n], &y[..n]);
            if first {
                for i in 0..n {
                    out[i] = offset + a * x[i] + b * y[i];
                }
            } else {
                for i in 0..n {
                    out[i] += a * x[i] + b * y[i];
                }
            }
        }
        [(a, x), (b, y), (c, z)] => {
            let (x, y, z) = (&x[..n], &y[..n], &z[..n]);
            if first {
                for i in 0..n {
                    out[i] = offset + a * x[i] + b * y[i] + c * z[i];
                }
            } else {
                for i in 0..n {
                    out[i] += a * x[i] + b * y[i] + c * z[i];
                }
            }
        }
        [(a, x), (b, y), (c, z), (d, w), ..] => {
            let (x, y, z, w) = (&x[..n], &y[..n], &z[..n], &w[..n]);
            if first {
                for i in 0..n {
                    out[i] = offset + a * x[i] + b * y[i] + c * z[i] + d * w[i];
                }
            } else {
                for i in 0..n {
                    out[i] += a * x[i] + b * y[i] + c * z[i] + d * w[i];
                }
            }
        }
    }
}

/// A matrix as plain row-major arrays, for the loops.
fn rows<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> [[f64; C]; R] {
    std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]))
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

/// Eq. (10)'s Riccati part, given `P_{t|t}`: returns `T1 = chol(M_t)`, `L_t` and
/// `P_{t+1|t}`, with `M_t = A^k P (A^k)ᵀ + Q^p`, `L_t = F^k P (A^k)ᵀ M_t⁻¹`,
/// `P_{t+1|t} = F^k P (F^k)ᵀ + Q^k − L_t M_t L_tᵀ`. `None` if `M_t` is not positive definite.
#[allow(clippy::type_complexity)]
pub fn riccati_time_update<const P: usize, const K: usize, const NY: usize, H>(
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

/// The coefficients of one step of Alg. 1 that the Riccati recursion sets.
#[derive(Debug, Clone, Copy, PartialEq)]
struct SharedStep<const P: usize, const K: usize> {
    /// `T1 = chol(M_t)` (p×p, lower): `w = T1 z`, eq. (9).
    t1: [[f64; P]; P],
    /// `L_t T1` (k×p): `L_t (x^p_{t+1|t} − A^p x^p_t − A^k x̂^k_{t|t}) = L_t w`, eq. (10).
    lt1: [[f64; P]; K],
}

/// Steps beyond which [`SharedMpf::new`] stops tabulating a Riccati recursion that has not
/// converged.
pub const RICCATI_HORIZON: usize = 4096;

/// Alg. 1 (`C_t = 0`) as a [`BatchModel`]: state columns `[x^p, x̂^k]`, `p` normals per
/// particle and step.
///
/// `P_{t|t}` does not depend on the particles (eq. (7): with `C_t = 0` the measurement
/// leaves it as predicted), so the recursion of eq. (10) is run once, here, from
/// `P_{0|0} = P̄_0`, until it converges (the largest change of an entry at most `10⁻¹⁵`
/// of the largest entry; the steps after repeat the last) or for [`RICCATI_HORIZON`]
/// steps ([`covers`](Self::covers) says which steps the table holds).
#[derive(Debug, Clone)]
pub struct SharedMpf<const P: usize, const K: usize, const NY: usize, H> {
    model: MixedLinearGaussian<P, K, NY, H>,
    a_p: [[f64; P]; P],
    a_k: [[f64; K]; P],
    f_p: [[f64; P]; K],
    f_k: [[f64; K]; K],
    /// `x^p_0`'s mean and lower factor.
    x0_p: [f64; P],
    chol0: [[f64; P]; P],
    x0_k: [f64; K],
    /// `L⁻¹` of `R = L Lᵀ` (lower) and `½ log det(2πR)`.
    r_linv: [[f64; NY]; NY],
    half_log_det: f64,
    /// `steps[t − 1]` for the step to `t ≥ 1`.
    steps: Vec<SharedStep<P, K>>,
    /// `P_{t|t}` for `t = 0 …`.
    covs: Vec<SMatrix<f64, K, K>>,
    converged: bool,
}

impl<const P: usize, const K: usize, const NY: usize, H: Measurement<P, NY>>
    SharedMpf<P, K, NY, H>
{
    /// Alg. 1 for `model`, with its Riccati recursion tabulated.
    ///
    /// # Errors
    /// `C_t ≠ 0` ([`MpfError::SharedRiccatiNeedsZeroC`]), or `M_t` not positive definite at
    /// some step.
    pub fn new(model: MixedLinearGaussian<P, K, NY, H>) -> Result<Self> {
        if !model.c_is_zero() {
            return Err(MpfError::SharedRiccatiNeedsZeroC {
                max_abs: model.c().amax(),
            });
        }
        let mut p = *model.p0_k();
        let mut covs = vec![p];
        let mut steps = Vec::new();
        let mut converged = false;
        for t in 1..=RICCATI_HORIZON {
            let (t1, l, p_next) =
                riccati_time_update(&model, &p).ok_or(MpfError::NotPositiveDefinite {
                    what: "M_t",
                    t,
                    particle: 0,
                })?;
            steps.push(SharedStep {
                t1: rows(&t1),
                lt1: rows(&(l * t1)),
            });
            let change = (p_next - p).amax();
            p = p_next;
            covs.push(p);
            if change <= 1e-15 * p.amax() {
                converged = true;
                break;
            }
        }
        let l = model.e().chol();
        let linv = l
            .solve_lower_triangular(&SMatrix::<f64, NY, NY>::identity())
            .ok_or(MpfError::NotPositiveDefinite {
                what: "R",
                t: 0,
                particle: 0,
            })?;
        Ok(Self {
            a_p: rows(model.a_p()),
            a_k: rows(model.a_k()),
            f_p: rows(model.f_p()),
            f_k: rows(model.f_k()),
            x0_p: std::array::from_fn(|r| model.x0_p().mean()[r]),
            chol0: rows(model.x0_p().chol()),
            x0_k: std::array::from_fn(|r| model.x0_k()[r]),
            r_linv: rows(&linv),
            half_log_det: half_log_det_2pi(l),
            steps,
            covs,
            converged,
            model,
        })
    }

    /// The model.
    pub fn model(&self) -> &MixedLinearGaussian<P, K, NY, H> {
        &self.model
    }

    /// Whether the table holds the exact recursion at step `t` (it always does once the
    /// recursion has converged).
    pub fn covers(&self, t: usize) -> bool {
        self.converged || t <= self.steps.len()
    }

    /// `P_{t|t}`, shared by every particle.
    pub fn cov(&self, t: usize) -> &SMatrix<f64, K, K> {
        &self.covs[t.min(self.covs.len() - 1)]
    }

    fn step_at(&self, t: usize) -> &SharedStep<P, K> {
        &self.steps[t.clamp(1, self.steps.len()) - 1]
    }
}

impl<const P: usize, const K: usize, const NY: usize, H: Measurement<P, NY>> BatchModel
    for SharedMpf<P, K, NY, H>
{
    type Obs = SVector<f64, NY>;
    type Input = ();

    fn dim(&self) -> usize {
        P + K
    }

    fn noise_dim(&self) -> usize {
        P
    }

    /// Alg. 1, step 1: `x^{p,(i)}_0 ~ p(x^p_0)` (mean plus lower factor times `z`),
    /// `x̂^{k,(i)} = x̄^k_0`.
    #[inline(always)]
    fn initial(&self, z: Cols<'_>, mut x: ColsMut<'_>) {
        for r in 0..P {
            let terms = (0..P).map(|c| (self.chol0[r][c], z.col(c)));
            lincomb(x.col_mut(r), self.x0_p[r], terms);
        }
        for r in 0..K {
            x.col_mut(P + r).fill(self.x0_k[r]);
        }
    }

    /// Eqs. (8)–(10) from the resampled parents: `x^p_{t+1} = A^p x^p + A^k x̂^k + w` and
    /// `x̂^k_{t+1|t} = F^k x̂^k + F^p x^p + L_t w` with `w = T1 z` (`T9` of Table I is `w`).
    #[inline(always)]
    fn propagate(&self, t: usize, _u: &(), parents: Cols<'_>, z: Cols<'_>, mut x: ColsMut<'_>) {
        let s = self.step_at(t);
        for r in 0..P {
            let terms = (0..P)
                .map(|c| (self.a_p[r][c], parents.col(c)))
                .chain((0..K).map(|c| (self.a_k[r][c], parents.col(P + c))))
                .chain((0..=r).map(|c| (s.t1[r][c], z.col(c))));
            lincomb(x.col_mut(r), 0.0, terms);
        }
        for r in 0..K {
            let terms = (0..P)
                .map(|c| (self.f_p[r][c], parents.col(c)))
                .chain((0..K).map(|c| (self.f_k[r][c], parents.col(P + c))))
                .chain((0..P).map(|c| (s.lt1[r][c], z.col(c))));
            lincomb(x.col_mut(P + r), 0.0, terms);
        }
    }

    /// Alg. 1, step 2: `log q_t = log N(y_t; h_t(x^p_t), R)`.
    #[inline(always)]
    fn add_log_likelihood(&self, t: usize, y: &Self::Obs, x: Cols<'_>, lw: &mut [f64]) {
        let n = x.len();
        let mut e = [[0.0; TILE]; NY];
        let mut off = 0;
        while off < n {
            let m = (n - off).min(TILE);
            let xp: [&[f64]; P] = std::array::from_fn(|c| &x.col(c)[off..off + m]);
            self.model.h().residuals(t, y, &xp, m, &mut e);
            // `q = |R^{-1/2} e|²`, lane by lane over the whole tile (a loop over particles
            // inside each sum kept it scalar: about 3 % of the radar PF).
            let mut q = [0.0; TILE];
            for r in 0..NY {
                let mut s = [0.0; TILE];
                for (c, e) in e.iter().enumerate().take(r + 1) {
                    let a = self.r_linv[r][c];
                    for (s, &e) in s.iter_mut().zip(e) {
                        *s += a * e;
                    }
                }
                for (q, &s) in q.iter_mut().zip(&s) {
                    *q += s * s;
                }
            }
            for (l, &q) in lw[off..off + m].iter_mut().zip(&q) {
                *l += -0.5 * q - self.half_log_det;
            }
            off += m;
        }
    }
}

/// Index of `P[a][b]` (`a ≤ b`) among the k(k+1)/2 covariance columns, row by row.
#[inline(always)]
const fn packed(k: usize, a: usize, b: usize) -> usize {
    a * k - a * (a + 1) / 2 + b
}

/// The particles of a tile of [`PerParticleMpf`], one array of lanes per quantity.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Tile<const P: usize, const K: usize> {
    xp: [Lanes; P],
    xk: [Lanes; K],
    p: [[Lanes; K]; K],
}

/// Lower Cholesky factor of every lane's `a`, and the inverses of its diagonal; a lane whose
/// matrix is not positive definite gets NaN.
#[inline(always)]
fn chol_lanes<const D: usize>(a: &[[Lanes; D]; D]) -> ([[Lanes; D]; D], [Lanes; D]) {
    let mut l = [[[0.0; TILE]; D]; D];
    let mut inv = [[0.0; TILE]; D];
    for j in 0..D {
        for i in j..D {
            let mut s = a[i][j];
            for k in 0..j {
                for q in 0..TILE {
                    s[q] -= l[i][k][q] * l[j][k][q];
                }
            }
            if i == j {
                for q in 0..TILE {
                    let d = s[q].sqrt();
                    l[j][j][q] = d;
                    inv[j][q] = 1.0 / d;
                }
            } else {
                for q in 0..TILE {
                    l[i][j][q] = s[q] * inv[j][q];
                }
            }
        }
    }
    (l, inv)
}

/// `b := (L Lᵀ)⁻¹ b` lane by lane, `L` from [`chol_lanes`].
#[inline(always)]
fn chol_solve_lanes<const D: usize>(l: &[[Lanes; D]; D], inv: &[Lanes; D], b: &mut [Lanes; D]) {
    for i in 0..D {
        for k in 0..i {
            for q in 0..TILE {
                b[i][q] -= l[i][k][q] * b[k][q];
            }
        }
        for q in 0..TILE {
            b[i][q] *= inv[i][q];
        }
    }
    for i in (0..D).rev() {
        for k in (i + 1)..D {
            for q in 0..TILE {
                b[i][q] -= l[k][i][q] * b[k][q];
            }
        }
        for q in 0..TILE {
            b[i][q] *= inv[i][q];
        }
    }
}

/// `(M P Mᵀ + A, P Mᵀ)` of every lane for constant `M` (r×k) and `A` (r×r), the first
/// symmetrised: the innovation covariance `C P Cᵀ + R` and the time update's
/// `A^k P (A^k)ᵀ + Q^p`, with the cross term each needs next.
#[inline(always)]
#[allow(clippy::type_complexity)]
fn sandwich_lanes<const R: usize, const K: usize>(
    m: &[[f64; K]; R],
    p: &[[Lanes; K]; K],
    a: &[[f64; R]; R],
) -> ([[Lanes; R]; R], [[Lanes; R]; K]) {
    let mut pmt = [[[0.0; TILE]; R]; K];
    for b in 0..K {
        for r in 0..R {
            for c in 0..K {
                let coef = m[r][c];
                for q in 0..TILE {
                    pmt[b][r][q] += p[b][c][q] * coef;
                }
            }
        }
    }
    let mut s = [[[0.0; TILE]; R]; R];
    for i in 0..R {
        for j in 0..R {
            s[i][j] = [a[i][j]; TILE];
            for c in 0..K {
                let coef = m[i][c];
                for q in 0..TILE {
                    s[i][j][q] += coef * pmt[c][j][q];
                }
            }
        }
    }
    symmetrise_lanes(&mut s);
    (s, pmt)
}

/// Make each lane's matrix symmetric, `(P + Pᵀ)/2`.
#[inline(always)]
fn symmetrise_lanes<const D: usize>(p: &mut [[Lanes; D]; D]) {
    for j in 0..D {
        for i in (j + 1)..D {
            for q in 0..TILE {
                let s = 0.5 * (p[i][j][q] + p[j][i][q]);
                p[i][j][q] = s;
                p[j][i][q] = s;
            }
        }
    }
}

/// The general MPF (`C_t` any, ref. \[15\]) as a [`BatchModel`]: state columns
/// `[x^p, x̂^k_{t|t−1}, P_{t|t−1} (k(k+1)/2 entries, row by row on and above the diagonal)]`,
/// `p` normals per particle and step; the step's input is the previous observation
/// `y_{t−1}`, whose Kalman measurement update the step runs first.
#[derive(Debug, Clone)]
pub struct PerParticleMpf<const P: usize, const K: usize, const NY: usize, H> {
    model: MixedLinearGaussian<P, K, NY, H>,
    a_p: [[f64; P]; P],
    a_k: [[f64; K]; P],
    f_p: [[f64; P]; K],
    f_k: [[f64; K]; K],
    q_p: [[f64; P]; P],
    q_k: [[f64; K]; K],
    c: [[f64; K]; NY],
    r: [[f64; NY]; NY],
    x0_p: [f64; P],
    chol0: [[f64; P]; P],
    x0_k: [f64; K],
    p0_k: [[f64; K]; K],
}

impl<const P: usize, const K: usize, const NY: usize, H: Measurement<P, NY>>
    PerParticleMpf<P, K, NY, H>
{
    /// The general MPF for `model`.
    pub fn new(model: MixedLinearGaussian<P, K, NY, H>) -> Self {
        Self {
            a_p: rows(model.a_p()),
            a_k: rows(model.a_k()),
            f_p: rows(model.f_p()),
            f_k: rows(model.f_k()),
            q_p: rows(model.q_p()),
            q_k: rows(model.q_k()),
            c: rows(model.c()),
            r: rows(model.r()),
            x0_p: std::array::from_fn(|r| model.x0_p().mean()[r]),
            chol0: rows(model.x0_p().chol()),
            x0_k: std::array::from_fn(|r| model.x0_k()[r]),
            p0_k: rows(model.p0_k()),
            model,
        }
    }

    /// The model.
    pub fn model(&self) -> &MixedLinearGaussian<P, K, NY, H> {
        &self.model
    }

    /// Particles `off .. off + m` of `x` into a tile (lanes from `m` on are zero).
    #[inline(always)]
    pub(crate) fn load(&self, x: &Cols<'_>, off: usize, m: usize) -> Tile<P, K> {
        let mut tile = Tile {
            xp: [[0.0; TILE]; P],
            xk: [[0.0; TILE]; K],
            p: [[[0.0; TILE]; K]; K],
        };
        for c in 0..P {
            tile.xp[c][..m].copy_from_slice(&x.col(c)[off..off + m]);
        }
        for c in 0..K {
            tile.xk[c][..m].copy_from_slice(&x.col(P + c)[off..off + m]);
        }
        for a in 0..K {
            for b in a..K {
                let col = &x.col(P + K + packed(K, a, b))[off..off + m];
                tile.p[a][b][..m].copy_from_slice(col);
                tile.p[b][a][..m].copy_from_slice(col);
            }
        }
        tile
    }

    /// A tile's first `m` particles into `x`'s particles `off .. off + m`.
    #[inline(always)]
    pub(crate) fn store(&self, tile: &Tile<P, K>, x: &mut ColsMut<'_>, off: usize, m: usize) {
        for c in 0..P {
            x.col_mut(c)[off..off + m].copy_from_slice(&tile.xp[c][..m]);
        }
        for c in 0..K {
            x.col_mut(P + c)[off..off + m].copy_from_slice(&tile.xk[c][..m]);
        }
        for a in 0..K {
            for b in a..K {
                x.col_mut(P + K + packed(K, a, b))[off..off + m]
                    .copy_from_slice(&tile.p[a][b][..m]);
            }
        }
    }

    /// `e = y − h_t(x^p) − C x̂^k`, `S = C P Cᵀ + R` and `P Cᵀ` of every lane.
    #[inline(always)]
    #[allow(clippy::type_complexity)]
    fn innovation(
        &self,
        t: usize,
        y: &SVector<f64, NY>,
        tile: &Tile<P, K>,
    ) -> ([Lanes; NY], [[Lanes; NY]; NY], [[Lanes; NY]; K]) {
        let mut e = [[0.0; TILE]; NY];
        let xp: [&[f64]; P] = std::array::from_fn(|c| &tile.xp[c][..]);
        self.model.h().residuals(t, y, &xp, TILE, &mut e);
        for j in 0..NY {
            for a in 0..K {
                let c = self.c[j][a];
                for q in 0..TILE {
                    e[j][q] -= c * tile.xk[a][q];
                }
            }
        }
        let (s, pct) = sandwich_lanes(&self.c, &tile.p, &self.r);
        (e, s, pct)
    }

    /// `log N(y_t; h_t(x^p) + C x̂^k_{t|t−1}, C P_{t|t−1} Cᵀ + R)` of every lane (ref.
    /// \[15\]; Alg. 1, step 2, when `C_t = 0`).
    #[inline(always)]
    pub(crate) fn log_lik(&self, t: usize, y: &SVector<f64, NY>, tile: &Tile<P, K>) -> Lanes {
        let (mut e, s, _) = self.innovation(t, y, tile);
        let (l, inv) = chol_lanes(&s);
        // z = L⁻¹ e
        for i in 0..NY {
            for k in 0..i {
                for q in 0..TILE {
                    e[i][q] -= l[i][k][q] * e[k][q];
                }
            }
            for q in 0..TILE {
                e[i][q] *= inv[i][q];
            }
        }
        let mut out = [0.0; TILE];
        let mut det = [1.0; TILE];
        for i in 0..NY {
            for q in 0..TILE {
                out[q] += e[i][q] * e[i][q];
                det[q] *= l[i][i][q];
            }
        }
        let c = 0.5 * NY as f64 * LN_2PI;
        for q in 0..TILE {
            out[q] = -0.5 * out[q] - det[q].ln() - c;
        }
        out
    }

    /// The Kalman measurement update of ref. \[15\] with `y_t`: `K = P Cᵀ S⁻¹`,
    /// `x̂^k += K e`, `P := (I − K C) P (I − K C)ᵀ + K R Kᵀ` (Joseph form); eq. (7) when
    /// `C_t = 0`.
    #[inline(always)]
    pub(crate) fn measurement_update(&self, t: usize, y: &SVector<f64, NY>, tile: &mut Tile<P, K>) {
        let (e, s, pct) = self.innovation(t, y, tile);
        let (l, inv) = chol_lanes(&s);
        // Row a of the gain: S⁻¹ (P Cᵀ)[a] (S symmetric).
        let mut gain = pct;
        for g in &mut gain {
            chol_solve_lanes(&l, &inv, g);
        }
        for a in 0..K {
            for j in 0..NY {
                for q in 0..TILE {
                    tile.xk[a][q] += gain[a][j][q] * e[j][q];
                }
            }
        }
        // I − K C
        let mut ikc = [[[0.0; TILE]; K]; K];
        for a in 0..K {
            for b in 0..K {
                ikc[a][b] = [if a == b { 1.0 } else { 0.0 }; TILE];
                for j in 0..NY {
                    let c = self.c[j][b];
                    for q in 0..TILE {
                        ikc[a][b][q] -= gain[a][j][q] * c;
                    }
                }
            }
        }
        // T = (I − K C) P ; P' = T (I − K C)ᵀ + K R Kᵀ
        let mut tp = [[[0.0; TILE]; K]; K];
        for a in 0..K {
            for b in 0..K {
                for c in 0..K {
                    for q in 0..TILE {
                        tp[a][b][q] += ikc[a][c][q] * tile.p[c][b][q];
                    }
                }
            }
        }
        let mut kr = [[[0.0; TILE]; NY]; K];
        for a in 0..K {
            for j in 0..NY {
                for i in 0..NY {
                    let r = self.r[i][j];
                    for q in 0..TILE {
                        kr[a][j][q] += gain[a][i][q] * r;
                    }
                }
            }
        }
        for a in 0..K {
            for b in 0..K {
                let mut v = [0.0; TILE];
                for c in 0..K {
                    for q in 0..TILE {
                        v[q] += tp[a][c][q] * ikc[b][c][q];
                    }
                }
                for j in 0..NY {
                    for q in 0..TILE {
                        v[q] += kr[a][j][q] * gain[b][j][q];
                    }
                }
                tile.p[a][b] = v;
            }
        }
        symmetrise_lanes(&mut tile.p);
    }

    /// Eqs. (8)–(10) with each lane's own `P_{t|t}`: `M = A^k P (A^k)ᵀ + Q^p`,
    /// `L = F^k P (A^k)ᵀ M⁻¹`, `w = chol(M) z`, `x^p := A^p x^p + A^k x̂^k + w`,
    /// `x̂^k := F^k x̂^k + F^p x^p + L w`, `P := F^k P (F^k)ᵀ + Q^k − L M Lᵀ`.
    #[inline(always)]
    pub(crate) fn time_update(&self, z: &[Lanes; P], tile: &mut Tile<P, K>) {
        // M = A^k P (A^k)ᵀ + Q^p and P_A = P (A^k)ᵀ (k×p)
        let (mm, pa) = sandwich_lanes(&self.a_k, &tile.p, &self.q_p);
        let (lm, inv) = chol_lanes(&mm);
        // Row a of L: M⁻¹ (F^k P_A)[a]
        let mut lg = [[[0.0; TILE]; P]; K];
        for a in 0..K {
            for b in 0..K {
                let c = self.f_k[a][b];
                for r in 0..P {
                    for q in 0..TILE {
                        lg[a][r][q] += c * pa[b][r][q];
                    }
                }
            }
            chol_solve_lanes(&lm, &inv, &mut lg[a]);
        }
        // w = chol(M) z
        let mut w = [[0.0; TILE]; P];
        for r in 0..P {
            for c in 0..=r {
                for q in 0..TILE {
                    w[r][q] += lm[r][c][q] * z[c][q];
                }
            }
        }
        let mut xp = w;
        for r in 0..P {
            for c in 0..P {
                let a = self.a_p[r][c];
                for q in 0..TILE {
                    xp[r][q] += a * tile.xp[c][q];
                }
            }
            for c in 0..K {
                let a = self.a_k[r][c];
                for q in 0..TILE {
                    xp[r][q] += a * tile.xk[c][q];
                }
            }
        }
        let mut xk = [[0.0; TILE]; K];
        for a in 0..K {
            for b in 0..K {
                let f = self.f_k[a][b];
                for q in 0..TILE {
                    xk[a][q] += f * tile.xk[b][q];
                }
            }
            for c in 0..P {
                let f = self.f_p[a][c];
                for q in 0..TILE {
                    xk[a][q] += f * tile.xp[c][q] + lg[a][c][q] * w[c][q];
                }
            }
        }
        // P := F^k P (F^k)ᵀ + Q^k − L M Lᵀ
        let mut fp = [[[0.0; TILE]; K]; K];
        for a in 0..K {
            for b in 0..K {
                for c in 0..K {
                    let f = self.f_k[a][c];
                    for q in 0..TILE {
                        fp[a][b][q] += f * tile.p[c][b][q];
                    }
                }
            }
        }
        let mut lmm = [[[0.0; TILE]; P]; K];
        for a in 0..K {
            for s in 0..P {
                for r in 0..P {
                    for q in 0..TILE {
                        lmm[a][s][q] += lg[a][r][q] * mm[r][s][q];
                    }
                }
            }
        }
        for a in 0..K {
            for b in 0..K {
                let mut v = [self.q_k[a][b]; TILE];
                for c in 0..K {
                    let f = self.f_k[b][c];
                    for q in 0..TILE {
                        v[q] += fp[a][c][q] * f;
                    }
                }
                for s in 0..P {
                    for q in 0..TILE {
                        v[q] -= lmm[a][s][q] * lg[b][s][q];
                    }
                }
                tile.p[a][b] = v;
            }
        }
        symmetrise_lanes(&mut tile.p);
        tile.xp = xp;
        tile.xk = xk;
    }
}

impl<const P: usize, const K: usize, const NY: usize, H: Measurement<P, NY>> BatchModel
    for PerParticleMpf<P, K, NY, H>
{
    type Obs = SVector<f64, NY>;
    /// `y_{t−1}` (`None`: missing, or `t = 0`).
    type Input = Option<SVector<f64, NY>>;

    fn dim(&self) -> usize {
        P + K + K * (K + 1) / 2
    }

    fn noise_dim(&self) -> usize {
        P
    }

    /// `x^{p,(i)}_0 ~ p(x^p_0)`, `{x̂^k, P} = {x̄^k_0, P̄_0}`.
    #[inline(always)]
    fn initial(&self, z: Cols<'_>, mut x: ColsMut<'_>) {
        for r in 0..P {
            let terms = (0..P).map(|c| (self.chol0[r][c], z.col(c)));
            lincomb(x.col_mut(r), self.x0_p[r], terms);
        }
        for r in 0..K {
            x.col_mut(P + r).fill(self.x0_k[r]);
            for b in r..K {
                x.col_mut(P + K + packed(K, r, b)).fill(self.p0_k[r][b]);
            }
        }
    }

    /// The measurement update with `y_{t−1}` (when given), then the time update.
    #[inline(always)]
    fn propagate(
        &self,
        t: usize,
        u: &Self::Input,
        parents: Cols<'_>,
        z: Cols<'_>,
        mut x: ColsMut<'_>,
    ) {
        let n = parents.len();
        let mut off = 0;
        while off < n {
            let m = (n - off).min(TILE);
            let mut tile = self.load(&parents, off, m);
            if let Some(y) = u {
                self.measurement_update(t.saturating_sub(1), y, &mut tile);
            }
            let mut zt = [[0.0; TILE]; P];
            for (c, zt) in zt.iter_mut().enumerate() {
                zt[..m].copy_from_slice(&z.col(c)[off..off + m]);
            }
            self.time_update(&zt, &mut tile);
            self.store(&tile, &mut x, off, m);
            off += m;
        }
    }

    #[inline(always)]
    fn add_log_likelihood(&self, t: usize, y: &Self::Obs, x: Cols<'_>, lw: &mut [f64]) {
        let n = x.len();
        let mut off = 0;
        while off < n {
            let m = (n - off).min(TILE);
            let tile = self.load(&x, off, m);
            let ll = self.log_lik(t, y, &tile);
            for (l, v) in lw[off..off + m].iter_mut().zip(&ll) {
                *l += v;
            }
            off += m;
        }
    }
}

/// The engine and model behind an [`Mpf`].
enum Engine<const P: usize, const K: usize, const NY: usize, H> {
    Shared(BatchFilter<SharedMpf<P, K, NY, H>, Bootstrap>),
    PerParticle {
        filter: BatchFilter<PerParticleMpf<P, K, NY, H>, Bootstrap>,
        /// `y_t` of the last step: the next step's input.
        last_y: Option<SVector<f64, NY>>,
        /// The particles after the last step's measurement update, column by column
        /// (`dim × N`), and their weights.
        filtered: Vec<f64>,
        weights: Vec<f64>,
    },
}

/// The marginalized particle filter for model (5) on pf-core's batch engine; see the
/// [module docs](self).
pub struct Mpf<const P: usize, const K: usize, const NY: usize, H> {
    engine: Engine<P, K, NY, H>,
    n: usize,
    /// The next step's `t`.
    t_next: usize,
    /// Scratch for the estimates (`dim` values).
    mean: Vec<f64>,
}

/// The configuration and the last step, not the particle blocks.
impl<const P: usize, const K: usize, const NY: usize, H> std::fmt::Debug for Mpf<P, K, NY, H> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Mpf")
            .field("partition", &(P, K))
            .field("n_particles", &self.n)
            .field("shared_riccati", &matches!(self.engine, Engine::Shared(_)))
            .field("t_next", &self.t_next)
            .finish_non_exhaustive()
    }
}

impl<const P: usize, const K: usize, const NY: usize, H: Measurement<P, NY>> Mpf<P, K, NY, H> {
    /// A filter for `model` whose random streams come from `seed`, its chunks on `par`.
    ///
    /// # Errors
    /// A bad configuration, [`Riccati::Shared`] with `C_t ≠ 0`, or a shared Riccati
    /// recursion whose `M_t` is not positive definite.
    pub fn new(
        model: MixedLinearGaussian<P, K, NY, H>,
        config: MpfConfig,
        seed: u64,
        par: Par,
    ) -> Result<Self> {
        config.validate()?;
        let shared = match config.riccati {
            Riccati::Auto => model.c_is_zero(),
            Riccati::PerParticle => false,
            Riccati::Shared => true,
        };
        let n = config.n_particles;
        let batch = config.batch(seed, par);
        let engine = if shared {
            Engine::Shared(BatchFilter::new(SharedMpf::new(model)?, batch)?)
        } else {
            let model = PerParticleMpf::new(model);
            let dim = model.dim();
            const WHAT: &str = "the MPF's filtered particles";
            pf_core::limits::check_memory(WHAT, n, n.saturating_mul((dim + 1) * 8))?;
            Engine::PerParticle {
                filter: BatchFilter::new(model, batch)?,
                last_y: None,
                filtered: pf_core::limits::try_filled(WHAT, dim * n, 0.0)?,
                weights: pf_core::limits::try_filled(WHAT, n, 0.0)?,
            }
        };
        Ok(Self {
            engine,
            n,
            t_next: 0,
            mean: vec![0.0; P + K + K * (K + 1) / 2],
        })
    }

    /// Number of particles `N`.
    pub fn n_particles(&self) -> usize {
        self.n
    }

    /// Whether Alg. 1's shared Riccati recursion is in use.
    pub fn is_shared(&self) -> bool {
        matches!(self.engine, Engine::Shared(_))
    }

    /// Forget everything; the next step is `t = 0` (with the same random streams).
    pub fn reset(&mut self) {
        self.t_next = 0;
        match &mut self.engine {
            Engine::Shared(f) => f.reset(),
            Engine::PerParticle { filter, last_y, .. } => {
                filter.reset();
                *last_y = None;
            }
        }
    }

    /// The report of the last step.
    pub fn last_report(&self) -> Option<&StepReport> {
        match &self.engine {
            Engine::Shared(f) => f.last_report(),
            Engine::PerParticle { filter, .. } => filter.last_report(),
        }
    }

    /// Running log-likelihood estimate `Σ_t log p̂(y_t | Y_{t−1})`.
    pub fn log_likelihood(&self) -> f64 {
        match &self.engine {
            Engine::Shared(f) => f.log_likelihood(),
            Engine::PerParticle { filter, .. } => filter.log_likelihood(),
        }
    }

    /// Advance one step: `t = 0` on the first call, then `t + 1`. `y = None` is a missing
    /// observation: no reweighting, no KF measurement update.
    ///
    /// # Errors
    /// A non-finite observation; a step beyond a shared Riccati recursion's table that has
    /// not converged; a weight that is not a number (a covariance `M_t` or `S_t` that is not
    /// positive definite gives NaN) or all weights zero, from the engine.
    pub fn step(&mut self, y: Option<&SVector<f64, NY>>) -> Result<StepReport> {
        let t = self.t_next;
        if let Some(y) = y
            && let Some((index, &value)) = y.iter().enumerate().find(|(_, v)| !v.is_finite())
        {
            return Err(MpfError::NonFiniteObservation { t, index, value });
        }
        let report = match &mut self.engine {
            Engine::Shared(f) => {
                if !f.model().covers(t) {
                    return Err(MpfError::RiccatiHorizon {
                        t,
                        horizon: RICCATI_HORIZON,
                    });
                }
                f.step(y)?
            }
            Engine::PerParticle {
                filter,
                last_y,
                filtered,
                weights,
            } => {
                let report = filter.step_with(last_y, y)?;
                *last_y = y.copied();
                let view = filter.view().ok_or(pf_core::CoreError::Empty {
                    what: "MPF particle set after a step",
                })?;
                let (n, dim) = (view.n(), view.dim());
                for (c, col) in filtered.chunks_exact_mut(n).enumerate().take(dim) {
                    view.column_into(c, col)?;
                }
                view.weights_into(weights)?;
                if let Some(y) = y {
                    let model = filter.model();
                    let mut x = ColsMut::new(filtered, dim, n);
                    let mut off = 0;
                    while off < n {
                        let m = (n - off).min(TILE);
                        let mut tile = model.load(&x.as_cols(), off, m);
                        model.measurement_update(t, y, &mut tile);
                        model.store(&tile, &mut x, off, m);
                        off += m;
                    }
                }
                report
            }
        };
        self.t_next = t + 1;
        Ok(report)
    }

    /// Column `c` of the particles after the last step (`x^p` then `x̂^k_{t|t}`) into
    /// `out` (N values).
    ///
    /// # Errors
    /// Before the first step; `c` beyond `p + k` or `out` not `N` long.
    pub fn column_into(&self, c: usize, out: &mut [f64]) -> Result<()> {
        if c >= P + K || out.len() != self.n {
            return Err(pf_core::CoreError::DimensionMismatch {
                what: "MPF column (index below p + k, N values)",
                expected: if c >= P + K { P + K } else { self.n },
                got: if c >= P + K { c } else { out.len() },
            }
            .into());
        }
        match &self.engine {
            Engine::Shared(f) => f.view().ok_or(no_step())?.column_into(c, out)?,
            Engine::PerParticle { filtered, .. } => {
                self.check_stepped()?;
                out.copy_from_slice(&filtered[c * self.n..(c + 1) * self.n]);
            }
        }
        Ok(())
    }

    /// Normalised weights `q̃_t^{(i)}` into `out` (N values).
    ///
    /// # Errors
    /// Before the first step, or `out` not `N` long.
    pub fn weights_into(&self, out: &mut [f64]) -> Result<()> {
        if out.len() != self.n {
            return Err(pf_core::CoreError::DimensionMismatch {
                what: "MPF weights",
                expected: self.n,
                got: out.len(),
            }
            .into());
        }
        match &self.engine {
            Engine::Shared(f) => f.view().ok_or(no_step())?.weights_into(out)?,
            Engine::PerParticle { weights, .. } => {
                self.check_stepped()?;
                out.copy_from_slice(weights);
            }
        }
        Ok(())
    }

    fn check_stepped(&self) -> Result<()> {
        if self.t_next == 0 {
            return Err(no_step().into());
        }
        Ok(())
    }

    /// `P^{(i)}_{t|t}` of particle `i` (the shared one under Alg. 1).
    ///
    /// # Errors
    /// Before the first step, or `i ≥ N`.
    pub fn kf_cov(&self, i: usize) -> Result<SMatrix<f64, K, K>> {
        self.check_stepped()?;
        if i >= self.n {
            return Err(pf_core::CoreError::DimensionMismatch {
                what: "particle index below N",
                expected: self.n,
                got: i,
            }
            .into());
        }
        Ok(match &self.engine {
            Engine::Shared(f) => *f.model().cov(self.t_next - 1),
            Engine::PerParticle { filtered, .. } => SMatrix::from_fn(|a, b| {
                let (a, b) = (a.min(b), a.max(b));
                filtered[(P + K + packed(K, a, b)) * self.n + i]
            }),
        })
    }

    /// The filter estimates `x̂^p_{t|t} = Σ q̃_i x^{p,(i)}_t` and
    /// `x̂^k_{t|t} = Σ q̃_i x̂^{k,(i)}_{t|t}`.
    ///
    /// # Errors
    /// [`CoreError::Empty`](pf_core::CoreError::Empty) before the first step.
    pub fn estimate(&mut self) -> Result<(SVector<f64, P>, SVector<f64, K>)> {
        self.check_stepped()?;
        match &self.engine {
            Engine::Shared(f) => f
                .view()
                .ok_or(no_step())?
                .mean_into(&mut self.mean[..P + K])?,
            Engine::PerParticle {
                filtered, weights, ..
            } => {
                for (c, m) in self.mean[..P + K].iter_mut().enumerate() {
                    let col = &filtered[c * self.n..(c + 1) * self.n];
                    *m = col.iter().zip(weights.iter()).map(|(x, w)| x * w).sum();
                }
            }
        }
        Ok((
            SVector::from_fn(|r, _| self.mean[r]),
            SVector::from_fn(|r, _| self.mean[P + r]),
        ))
    }
}

fn no_step() -> pf_core::CoreError {
    pf_core::CoreError::Empty {
        what: "MPF particle set (no step made yet)",
    }
}
