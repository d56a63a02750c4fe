//! The Gaussian parameterisation `f(p; θ) = N(p; μ, Σ)` of Section 3 and its derivatives.
//!
//! `θ = (μ, vech Σ)` has `r = D + D(D+1)/2` entries: the means, then the variances
//! `Σ_ii`, then the covariances `Σ_ij`, `i < j`. For the BOT position (`D = 2`) this is the
//! paper's `r = 5`: two means, two variances and one covariance.
//!
//! The paper omits the derivatives ("for the sake of brevity"). With `Λ = Σ⁻¹`,
//! `e = p − μ`, `u = Λe` and `E_s = ∂Σ/∂θ_s = c_s(e_i e_jᵀ + e_j e_iᵀ)` for `s = (i, j)`
//! (`c_s = ½` if `i = j`, else 1):
//!
//! - score `∇_θ log f`: `∂/∂μ = u`, `∂/∂Σ_ii = ½(u_i² − Λ_ii)`, `∂/∂Σ_ij = u_i u_j − Λ_ij`;
//! - the integrand of (25), `∇log f ∇'log f − ∇∇'f / f = −∇∇' log f =: N(p; θ)`, with blocks
//!   `N_μμ = Λ`, `N_μs = Λ a_s`, `N_st = a_sᵀ Λ a_t − ½ tr(Λ E_s Λ E_t)`, where
//!   `a_s = E_s u` and `tr(Λ E_s Λ E_t) = 2 c_s c_t (Λ_ik Λ_jl + Λ_il Λ_jk)` for `t = (k, l)`;
//! - its mean under `f(·; θ)` itself, the Fisher information that makes (27) closed form:
//!   `H̃ = blockdiag(Λ, ½ tr(Λ E_s Λ E_t))` (the `μ–Σ` block vanishes since `E[u] = 0`,
//!   and `E[a_sᵀΛa_t] = tr(Λ E_s Λ E_t)` since `E[uuᵀ] = Λ`).
//!
//! Both are polynomials of degree at most 2 in `u`, so their weighted sums over the grid's
//! nodes (the quadratures of (25), (26) and (28)) are computed from the nodes' weighted
//! moments of `u` ([`Moments`]), the same sums in another order.

use nalgebra::{DMatrix, DVector, SMatrix, SVector};

use crate::error::{Result, check_data};
use pf_core::gaussian::LN_2PI;

/// A `D`-variate Gaussian `N(μ, Σ)`: the density family `f(·; θ)`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Gaussian<const D: usize> {
    /// μ.
    pub mean: SVector<f64, D>,
    /// Σ.
    pub cov: SMatrix<f64, D, D>,
}

impl<const D: usize> Gaussian<D> {
    /// `N(mean, cov)`; checked by [`Gaussian::validate`] where it matters.
    pub fn new(mean: SVector<f64, D>, cov: SMatrix<f64, D, D>) -> Self {
        Self { mean, cov }
    }

    /// Number of parameters `r = D + D(D+1)/2`.
    pub const R: usize = D + D * (D + 1) / 2;

    /// The pairs `(i, j)` indexing `vech Σ` in θ: diagonal first, then `i < j`.
    pub fn cov_pairs() -> Vec<(usize, usize)> {
        let mut v: Vec<(usize, usize)> = (0..D).map(|i| (i, i)).collect();
        for i in 0..D {
            for j in (i + 1)..D {
                v.push((i, j));
            }
        }
        v
    }

    /// θ as a vector of length `r`.
    pub fn theta(&self) -> DVector<f64> {
        let mut th = DVector::zeros(Self::R);
        self.write_theta(&mut th);
        th
    }

    /// Write θ into `th` (length `r`).
    pub fn write_theta(&self, th: &mut DVector<f64>) {
        for i in 0..D {
            th[i] = self.mean[i];
        }
        for (s, (i, j)) in Self::cov_pairs().into_iter().enumerate() {
            th[D + s] = self.cov[(i, j)];
        }
    }

    /// The Gaussian of parameter vector `th` (Σ symmetric by construction).
    pub fn from_theta(th: &DVector<f64>) -> Self {
        let mut g = Self::new(SVector::zeros(), SMatrix::zeros());
        for i in 0..D {
            g.mean[i] = th[i];
        }
        for (s, (i, j)) in Self::cov_pairs().into_iter().enumerate() {
            g.cov[(i, j)] = th[D + s];
            g.cov[(j, i)] = th[D + s];
        }
        g
    }

    /// Cholesky factor of Σ, or `None` if Σ is not (numerically) positive definite or has a
    /// non-finite entry.
    pub fn chol(&self) -> Option<SMatrix<f64, D, D>> {
        if self.cov.iter().any(|v| !v.is_finite()) || self.mean.iter().any(|v| !v.is_finite()) {
            return None;
        }
        self.cov.cholesky().map(|c| c.l())
    }

    /// Check that the mean is finite and Σ symmetric positive definite.
    pub fn validate(&self, what: &'static str) -> Result<()> {
        for (i, &v) in self.mean.iter().enumerate() {
            check_data(what, i, v)?;
        }
        let m = DMatrix::from_fn(D, D, |i, j| self.cov[(i, j)]);
        pf_core::gaussian::cholesky(what, &m)?;
        Ok(())
    }
}

/// Weighted moments `Σ w`, `Σ w·u` and `Σ w·u uᵀ` of the whitened points `u = Λ(p − μ)`.
///
/// The score and the integrand `N(p; θ)` of (25) are polynomials of degree at most 2 in
/// `u` (module docs), so their weighted sums over any set of points, the quadratures of
/// (25), (26) and (28), are functions of these moments alone: a point costs one update here
/// instead of an `r × r` integrand.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Moments<const D: usize> {
    m0: f64,
    m1: SVector<f64, D>,
    m2: SMatrix<f64, D, D>,
}

impl<const D: usize> Default for Moments<D> {
    fn default() -> Self {
        Self {
            m0: 0.0,
            m1: SVector::zeros(),
            m2: SMatrix::zeros(),
        }
    }
}

impl<const D: usize> Moments<D> {
    /// Add the whitened point `u` with weight `w`.
    #[inline]
    pub fn add(&mut self, u: &SVector<f64, D>, w: f64) {
        let wu = u * w;
        self.m0 += w;
        self.m1 += wu;
        self.m2 += wu * u.transpose();
    }
}

/// Interleaved partial sums of [`Derivatives::moments_pair`].
pub const MOMENT_LANES: usize = 4;

/// [`Moments`] as `L` interleaved partial sums, lane-minor so that a lane index is the
/// vector lane.
struct LaneMoments<const D: usize, const L: usize> {
    m0: [f64; L],
    m1: [[f64; L]; D],
    m2: [[[f64; L]; D]; D],
}

impl<const D: usize, const L: usize> LaneMoments<D, L> {
    #[inline(always)]
    fn new() -> Self {
        Self {
            m0: [0.0; L],
            m1: [[0.0; L]; D],
            m2: [[[0.0; L]; D]; D],
        }
    }

    /// [`Moments::add`] into lane `l`.
    #[inline(always)]
    fn add(&mut self, l: usize, u: &[f64; D], w: f64) {
        self.m0[l] += w;
        for (r, &ur) in u.iter().enumerate() {
            let wu = ur * w;
            self.m1[r][l] += wu;
            for (m2, &uc) in self.m2[r].iter_mut().zip(u) {
                m2[l] += wu * uc;
            }
        }
    }

    /// The lanes added in order.
    #[inline(always)]
    fn finish(&self) -> Moments<D> {
        let sum = |x: &[f64; L]| x.iter().sum::<f64>();
        Moments {
            m0: sum(&self.m0),
            m1: SVector::from_fn(|r, _| sum(&self.m1[r])),
            m2: SMatrix::from_fn(|r, c| sum(&self.m2[r][c])),
        }
    }
}

/// Derivative evaluator for a fixed θ: holds `Λ = Σ⁻¹` and the index pairs, so that scores
/// and Hessian integrands, at one point or summed over many, cost no allocation.
#[derive(Debug, Clone)]
pub struct Derivatives<const D: usize> {
    mu: SVector<f64, D>,
    lambda_mat: SMatrix<f64, D, D>,
    pairs: Vec<(usize, usize)>,
}

impl<const D: usize> Derivatives<D> {
    /// Prepare for θ = `g`; `None` if Σ is singular.
    pub fn new(g: &Gaussian<D>) -> Option<Self> {
        let lambda_mat = g.cov.try_inverse()?;
        Some(Self {
            mu: g.mean,
            lambda_mat,
            pairs: Gaussian::<D>::cov_pairs(),
        })
    }

    /// Re-point at θ = `g`, reusing the buffers; `false` (and unchanged) if Σ is singular.
    pub fn set(&mut self, g: &Gaussian<D>) -> bool {
        match g.cov.try_inverse() {
            Some(l) => {
                self.mu = g.mean;
                self.lambda_mat = l;
                true
            }
            None => false,
        }
    }

    /// Λ = Σ⁻¹.
    pub fn precision(&self) -> &SMatrix<f64, D, D> {
        &self.lambda_mat
    }

    /// The whitened point `u = Λ(p − μ)`.
    #[inline]
    pub fn whiten(&self, p: &SVector<f64, D>) -> SVector<f64, D> {
        self.lambda_mat * (p - self.mu)
    }

    /// The [`Moments`] of the whitened points `u_j = Λ(p_j − μ)` under two weightings at
    /// once, `(Σ_j a_j …, Σ_j b_j …)`: what [`Moments::add`] over every point gives, summed
    /// over [`MOMENT_LANES`] interleaved partial sums (point `j` into lane `j mod L`, the
    /// lanes added in order at the end), so that the loop vectorises instead of waiting on
    /// one running sum per moment. Lengths beyond the shortest slice are ignored.
    #[inline(always)]
    pub fn moments_pair(
        &self,
        points: &[SVector<f64, D>],
        a: &[f64],
        b: &[f64],
    ) -> (Moments<D>, Moments<D>) {
        const L: usize = MOMENT_LANES;
        let (mut ma, mut mb) = (LaneMoments::<D, L>::new(), LaneMoments::<D, L>::new());
        let n = points.len().min(a.len()).min(b.len());
        let full = n / L * L;
        let lm = &self.lambda_mat;
        let mu = &self.mu;
        let whiten = |p: &SVector<f64, D>| -> [f64; D] {
            std::array::from_fn(|r| {
                let mut x = 0.0;
                for c in 0..D {
                    x += lm[(r, c)] * (p[c] - mu[c]);
                }
                x
            })
        };
        for base in (0..full).step_by(L) {
            for l in 0..L {
                let j = base + l;
                let u = whiten(&points[j]);
                ma.add(l, &u, a[j]);
                mb.add(l, &u, b[j]);
            }
        }
        for j in full..n {
            let u = whiten(&points[j]);
            ma.add(j - full, &u, a[j]);
            mb.add(j - full, &u, b[j]);
        }
        (ma.finish(), mb.finish())
    }

    /// The score `∇_θ log f(p; θ)` into `s` (length `r`).
    pub fn score(&self, p: &SVector<f64, D>, s: &mut DVector<f64>) {
        let mut m = Moments::default();
        m.add(&self.whiten(p), 1.0);
        self.score_sum(&m, s);
    }

    /// `Σ_j w_j ∇_θ log f(p_j; θ)` into `s` (length `r`), from the points' [`Moments`].
    pub fn score_sum(&self, m: &Moments<D>, s: &mut DVector<f64>) {
        for i in 0..D {
            s[i] = m.m1[i];
        }
        for (t, &(i, j)) in self.pairs.iter().enumerate() {
            let centred = m.m2[(i, j)] - m.m0 * self.lambda_mat[(i, j)];
            s[D + t] = if i == j { 0.5 * centred } else { centred };
        }
    }

    /// `½ tr(Λ E_s Λ E_t)` for covariance parameters `s`, `t`.
    fn half_trace(&self, s: usize, t: usize) -> f64 {
        let (i, j) = self.pairs[s];
        let (k, l) = self.pairs[t];
        let cs = if i == j { 0.5 } else { 1.0 };
        let ct = if k == l { 0.5 } else { 1.0 };
        let lm = &self.lambda_mat;
        cs * ct * (lm[(i, k)] * lm[(j, l)] + lm[(i, l)] * lm[(j, k)])
    }

    /// The entries of `a_s = E_s u` as `(k, m)`: `a_s[k] = u[m]`, and 0 elsewhere.
    fn a_entries(&self, s: usize) -> ([(usize, usize); 2], usize) {
        let (i, j) = self.pairs[s];
        ([(i, j), (j, i)], if i == j { 1 } else { 2 })
    }

    /// Add `w · N(p; θ)` (the integrand of (25), `−∇∇' log f`) to `h` (r × r).
    pub fn accumulate_hessian(&self, p: &SVector<f64, D>, w: f64, h: &mut DMatrix<f64>) {
        let mut m = Moments::default();
        m.add(&self.whiten(p), w);
        self.add_hessian_sum(&m, h);
    }

    /// Add `Σ_j w_j N(p_j; θ)` to `h` (r × r), from the points' [`Moments`]: `N_μμ = Λ`
    /// sums to `Σw·Λ`, `N_μs = Λ a_s` to `Λ E_s Σw·u`, and `a_sᵀ Λ a_t` to the pairing of
    /// `Λ` with `Σw·u uᵀ` through the entries of `a_s` and `a_t`.
    pub fn add_hessian_sum(&self, m: &Moments<D>, h: &mut DMatrix<f64>) {
        let lm = &self.lambda_mat;
        for r in 0..D {
            for c in 0..D {
                h[(r, c)] += m.m0 * lm[(r, c)];
            }
        }
        let nc = self.pairs.len();
        for t in 0..nc {
            let (at, nt) = self.a_entries(t);
            // Λ · a_t(Σw·u)
            let mut la = SVector::<f64, D>::zeros();
            for &(k, src) in &at[..nt] {
                la += lm.column(k) * m.m1[src];
            }
            for r in 0..D {
                h[(r, D + t)] += la[r];
                h[(D + t, r)] += la[r];
            }
            for t2 in t..nc {
                let (at2, nt2) = self.a_entries(t2);
                let mut quad = 0.0;
                for &(k, src) in &at[..nt] {
                    for &(l, src2) in &at2[..nt2] {
                        quad += lm[(k, l)] * m.m2[(src, src2)];
                    }
                }
                let v = quad - m.m0 * self.half_trace(t, t2);
                h[(D + t, D + t2)] += v;
                if t2 != t {
                    h[(D + t2, D + t)] += v;
                }
            }
        }
    }

    /// The closed-form Fisher information `E_f[N(p; θ)]`, the H̃ of eq. (27), into `h`.
    pub fn fisher(&self, h: &mut DMatrix<f64>) {
        h.fill(0.0);
        for r in 0..D {
            for c in 0..D {
                h[(r, c)] = self.lambda_mat[(r, c)];
            }
        }
        let nc = self.pairs.len();
        for s in 0..nc {
            for t in 0..nc {
                h[(D + s, D + t)] = self.half_trace(s, t);
            }
        }
    }
}

/// `log N(p; μ, Σ)` without allocation, via the precomputed `Λ` and `ln det Σ`.
pub(crate) fn log_normal<const D: usize>(
    p: &SVector<f64, D>,
    mu: &SVector<f64, D>,
    lambda_mat: &SMatrix<f64, D, D>,
    ln_det: f64,
) -> f64 {
    let e = p - mu;
    -0.5 * (D as f64 * LN_2PI + ln_det + e.dot(&(lambda_mat * e)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Vector2};

    fn g() -> Gaussian<2> {
        Gaussian::new(Vector2::new(1.0, -2.0), Matrix2::new(2.0, 0.6, 0.6, 1.5))
    }

    /// The lane sums of `moments_pair` are `Moments::add` over every point, to rounding,
    /// for every remainder of the lane count.
    #[test]
    fn lane_moments_are_the_running_moments() {
        let d = Derivatives::new(&g()).unwrap();
        for n in [1usize, 3, 4, 5, 1151, 1152] {
            let pts: Vec<SVector<f64, 2>> = (0..n)
                .map(|j| {
                    let t = j as f64 * 0.37;
                    Vector2::new(1.0 + 3.0 * t.sin(), -2.0 + 2.0 * (1.3 * t).cos())
                })
                .collect();
            let a: Vec<f64> = (0..n).map(|j| ((j % 7) as f64 - 3.0) * 1e-3).collect();
            let b: Vec<f64> = (0..n).map(|j| 1.0 / (1.0 + j as f64)).collect();
            let (la, lb) = d.moments_pair(&pts, &a, &b);
            let (mut ra, mut rb) = (Moments::default(), Moments::default());
            for ((p, &wa), &wb) in pts.iter().zip(&a).zip(&b) {
                let u = d.whiten(p);
                ra.add(&u, wa);
                rb.add(&u, wb);
            }
            for (lane, run) in [(la, ra), (lb, rb)] {
                let scale = 1.0 + run.m0.abs() + run.m1.abs().sum() + run.m2.abs().sum();
                let err = (lane.m0 - run.m0).abs()
                    + (lane.m1 - run.m1).abs().sum()
                    + (lane.m2 - run.m2).abs().sum();
                assert!(err <= 1e-13 * scale, "n = {n}: {lane:?} against {run:?}");
            }
        }
    }

    fn log_f(th: &DVector<f64>, p: &Vector2<f64>) -> f64 {
        let g = Gaussian::<2>::from_theta(th);
        let l = g.cov.try_inverse().unwrap();
        log_normal(p, &g.mean, &l, g.cov.determinant().ln())
    }

    #[test]
    fn theta_round_trip_and_r() {
        assert_eq!(Gaussian::<2>::R, 5);
        let th = g().theta();
        assert_eq!(th.as_slice(), &[1.0, -2.0, 2.0, 1.5, 0.6]);
        assert_eq!(Gaussian::<2>::from_theta(&th), g());
    }

    /// Central differences of `Σ_p w_p log f(p; θ)` in θ: the weighted score and the
    /// weighted `−∇∇' log f`.
    fn finite_differences(points: &[(Vector2<f64>, f64)]) -> (DVector<f64>, DMatrix<f64>) {
        let th = g().theta();
        let sum = |th: &DVector<f64>| points.iter().map(|(p, w)| w * log_f(th, p)).sum::<f64>();
        let eps = 1e-4;
        let shifted = |a: usize, da: f64, b: usize, db: f64| {
            let mut t = th.clone();
            t[a] += da;
            t[b] += db;
            sum(&t)
        };
        let score = DVector::from_fn(5, |a, _| {
            (shifted(a, eps, a, 0.0) - shifted(a, -eps, a, 0.0)) / (2.0 * eps)
        });
        let hess = DMatrix::from_fn(5, 5, |a, b| {
            -(shifted(a, eps, b, eps) - shifted(a, eps, b, -eps) - shifted(a, -eps, b, eps)
                + shifted(a, -eps, b, -eps))
                / (4.0 * eps * eps)
        });
        (score, hess)
    }

    /// The score and `N` at one point, and their weighted sums over several points from the
    /// points' moments, against finite differences of `log f`.
    #[test]
    fn score_and_hessian_match_finite_differences() {
        let d = Derivatives::new(&g()).unwrap();
        let one = [(Vector2::new(2.3, -0.4), 1.0)];
        let several = [
            (Vector2::new(2.3, -0.4), 0.5),
            (Vector2::new(-0.7, -3.1), 0.3),
            (Vector2::new(1.4, 0.9), -0.2),
        ];
        for points in [&one[..], &several[..]] {
            let (mut s, mut h) = (DVector::zeros(5), DMatrix::zeros(5, 5));
            if let [(p, _)] = points {
                d.score(p, &mut s);
                d.accumulate_hessian(p, 1.0, &mut h);
            } else {
                let mut m = Moments::default();
                for (p, w) in points {
                    m.add(&d.whiten(p), *w);
                }
                d.score_sum(&m, &mut s);
                d.add_hessian_sum(&m, &mut h);
            }
            let (fs, fh) = finite_differences(points);
            // Central differences: truncation O(ε_h²·f''') ≈ 1e-8, round-off O(ε/ε_h) ≈
            // 1e-11 for the gradient; the second differences of log f have round-off
            // O(ε/ε_h²) ≈ 2e-8; 1e-6 and 1e-5 leave margin for both.
            for a in 0..5 {
                assert!(
                    (fs[a] - s[a]).abs() < 1e-6,
                    "score {a}: {} vs {}",
                    fs[a],
                    s[a]
                );
                for b in 0..5 {
                    let (want, got) = (fh[(a, b)], h[(a, b)]);
                    assert!((want - got).abs() < 1e-5, "N[{a},{b}]: {want} vs {got}");
                }
            }
        }
    }
}
