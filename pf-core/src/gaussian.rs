//! Gaussian tools: a Cholesky factor that names its failing pivot, multivariate normals
//! factored once, and 2-D error ellipses.
//!
//! Every covariance is factored once, `Σ = L·Lᵀ` with `L` lower triangular, and all later
//! work (sampling `μ + L·z`, densities via `L⁻¹(x − μ)`) uses the factor. No inverse is
//! ever formed.
//!
//! ## References
//! - G. H. Golub, C. F. Van Loan, *Matrix Computations*, 4th ed., §4.2 (Cholesky).
//! - A. Papoulis, *Probability, Random Variables and Stochastic Processes*: the χ² law of the
//!   Mahalanobis distance used by [`error_ellipse`].

use nalgebra::{DMatrix, DVector};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::error::{CoreError, Result};
use crate::params::ParamError;

/// `ln(2π)`, correctly rounded: the normalising constant of every Gaussian density in the
/// workspace (`−½ d ln 2π` in `d` dimensions).
pub const LN_2PI: f64 = 1.837_877_066_409_345_5;

/// Lower Cholesky factor `L` of a symmetric positive-definite `m = L·Lᵀ`.
///
/// Only the lower triangle of `m` is read. Errors: [`CoreError::DimensionMismatch`] if `m`
/// is not square, [`CoreError::NonFiniteData`] for a NaN/∞ entry (`index` = row·n + column),
/// [`CoreError::NotPositiveDefinite`] naming the first pivot `j` whose value
/// `m_jj − Σ_{k<j} L_jk²` is not strictly positive. `what` names the matrix in the error.
pub fn cholesky(what: &'static str, m: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    let mut l = DMatrix::zeros(m.nrows(), m.ncols());
    cholesky_into(what, m, &mut l)?;
    Ok(l)
}

/// [`cholesky`] writing into `l`, which is resized only if its shape differs from `m`'s, so
/// a caller that keeps `l` between steps never allocates. On error `l` holds garbage.
pub fn cholesky_into(what: &'static str, m: &DMatrix<f64>, l: &mut DMatrix<f64>) -> Result<()> {
    let n = m.nrows();
    if m.ncols() != n {
        return Err(CoreError::DimensionMismatch {
            what,
            expected: n,
            got: m.ncols(),
        });
    }
    for i in 0..n {
        for j in 0..n {
            let v = m[(i, j)];
            if !v.is_finite() {
                return Err(CoreError::NonFiniteData {
                    what,
                    index: i * n + j,
                    value: v,
                });
            }
        }
    }
    if l.shape() != (n, n) {
        *l = DMatrix::zeros(n, n);
    }
    // Cholesky–Crout, column by column (Golub & Van Loan, Alg. 4.2.1).
    for j in 0..n {
        let mut d = m[(j, j)];
        for k in 0..j {
            d -= l[(j, k)] * l[(j, k)];
        }
        // `!(d > 0)` also catches a NaN produced by overflow.
        if !(d > 0.0 && d.is_finite()) {
            return Err(CoreError::NotPositiveDefinite {
                what,
                pivot: j,
                value: d,
            });
        }
        let ljj = d.sqrt();
        l[(j, j)] = ljj;
        for i in 0..j {
            l[(i, j)] = 0.0;
        }
        for i in (j + 1)..n {
            let mut s = m[(i, j)];
            for k in 0..j {
                s -= l[(i, k)] * l[(j, k)];
            }
            l[(i, j)] = s / ljj;
        }
    }
    Ok(())
}

/// Replace `p` by `(p + pᵀ)/2` in place: removes the round-off asymmetry that products such
/// as `A·P·Aᵀ` leave, so that covariances stay exactly symmetric from step to step.
pub fn symmetrise(p: &mut DMatrix<f64>) {
    let n = p.nrows().min(p.ncols());
    for j in 0..n {
        for i in (j + 1)..n {
            let v = 0.5 * (p[(i, j)] + p[(j, i)]);
            p[(i, j)] = v;
            p[(j, i)] = v;
        }
    }
}

/// `Σ_i ln L_ii`, i.e. `½ ln det Σ` for `Σ = L·Lᵀ`.
pub(crate) fn half_log_det(l: &DMatrix<f64>) -> f64 {
    l.diagonal().iter().map(|v| v.ln()).sum()
}

/// `log N(r; 0, L·Lᵀ)` for a residual `r`, overwriting `r` with `L⁻¹r` (no allocation).
pub(crate) fn log_normal_chol_in_place(l: &DMatrix<f64>, r: &mut DVector<f64>) -> f64 {
    l.solve_lower_triangular_unchecked_mut(r);
    -0.5 * (r.len() as f64 * LN_2PI) - half_log_det(l) - 0.5 * r.norm_squared()
}

/// Scalar normal log-density `log N(x; mean, var)`; `var` must be positive (else NaN or −∞).
pub fn log_normal_pdf_1d(x: f64, mean: f64, var: f64) -> f64 {
    let d = x - mean;
    -0.5 * (LN_2PI + var.ln() + d * d / var)
}

/// A multivariate normal `N(μ, Σ)` stored by its mean and lower Cholesky factor `L`
/// (`Σ = L·Lᵀ`), computed once at construction.
#[derive(Debug, Clone, PartialEq)]
pub struct MvNormal {
    /// μ.
    mean: DVector<f64>,
    /// L, lower triangular with positive diagonal.
    chol: DMatrix<f64>,
    /// `−½ d ln 2π − Σ ln L_ii`, the log normalising constant.
    log_norm: f64,
}

impl MvNormal {
    /// `N(mean, cov)`. Errors if the shapes disagree, an entry is not finite, or `cov` is not
    /// positive definite (see [`cholesky`]; only its lower triangle is read).
    pub fn new(mean: DVector<f64>, cov: &DMatrix<f64>) -> Result<Self> {
        if cov.nrows() != mean.len() {
            return Err(CoreError::DimensionMismatch {
                what: "MvNormal covariance rows vs mean length",
                expected: mean.len(),
                got: cov.nrows(),
            });
        }
        if let Some((index, &value)) = mean.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(CoreError::NonFiniteData {
                what: "MvNormal mean",
                index,
                value,
            });
        }
        let chol = cholesky("MvNormal covariance", cov)?;
        Ok(Self::from_parts(mean, chol))
    }

    /// Build from an already-checked mean and factor (dimensions and positivity assumed).
    pub(crate) fn from_parts(mean: DVector<f64>, chol: DMatrix<f64>) -> Self {
        let log_norm = -0.5 * (mean.len() as f64) * LN_2PI - half_log_det(&chol);
        Self {
            mean,
            chol,
            log_norm,
        }
    }

    /// Dimension `d`.
    pub fn dim(&self) -> usize {
        self.mean.len()
    }

    /// μ.
    pub fn mean(&self) -> &DVector<f64> {
        &self.mean
    }

    /// The lower Cholesky factor `L` of Σ.
    pub fn chol(&self) -> &DMatrix<f64> {
        &self.chol
    }

    /// Σ = L·Lᵀ (computed, so it is exactly symmetric positive semi-definite).
    pub fn covariance(&self) -> DMatrix<f64> {
        &self.chol * self.chol.transpose()
    }

    /// Draw `μ + L·z`, `z ~ N(0, I)`.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> DVector<f64> {
        let mut out = DVector::zeros(self.dim());
        self.sample_into(rng, &mut out);
        out
    }

    /// Draw `μ + L·z` into `out` without allocating (`out` is resized only if its length is
    /// not `d`). The product `L·z` is formed in place, bottom row first, since row `i` of a
    /// lower-triangular product reads only `z_0..z_i`.
    pub fn sample_into<R: Rng + ?Sized>(&self, rng: &mut R, out: &mut DVector<f64>) {
        let d = self.dim();
        if out.len() != d {
            *out = DVector::zeros(d);
        }
        for v in out.iter_mut() {
            *v = StandardNormal.sample(rng);
        }
        lower_mul_in_place(&self.chol, out);
        *out += &self.mean;
    }

    /// `log N(x; μ, Σ) = −½ d ln 2π − Σ ln L_ii − ½‖L⁻¹(x − μ)‖²`, by one triangular solve.
    ///
    /// Returns NaN if `x.len() ≠ d`, so that a filter reports a bad observation as a
    /// non-finite weight instead of panicking.
    pub fn log_density(&self, x: &DVector<f64>) -> f64 {
        if x.len() != self.dim() {
            return f64::NAN;
        }
        let mut r = x - &self.mean;
        self.log_density_residual_in_place(&mut r)
    }

    /// `log N(μ + r; μ, Σ)` for a residual `r = x − μ`, overwriting `r` with `L⁻¹r`.
    /// Allocation-free; returns NaN if `r.len() ≠ d`.
    pub fn log_density_residual_in_place(&self, r: &mut DVector<f64>) -> f64 {
        if r.len() != self.dim() {
            return f64::NAN;
        }
        self.chol.solve_lower_triangular_unchecked_mut(r);
        self.log_norm - 0.5 * r.norm_squared()
    }
}

/// `v ← L·v` for lower-triangular `L`, in place (rows from the bottom up).
pub(crate) fn lower_mul_in_place(l: &DMatrix<f64>, v: &mut DVector<f64>) {
    let d = v.len();
    for i in (0..d).rev() {
        let mut s = 0.0;
        for j in 0..=i {
            s += l[(i, j)] * v[j];
        }
        v[i] = s;
    }
}

/// The region `{x : (x − μ)ᵀ Σ⁻¹ (x − μ) ≤ k²}` of a 2-D Gaussian: an ellipse.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ErrorEllipse {
    /// Centre μ.
    pub centre: [f64; 2],
    /// Semi-axes `k·√λ₁ ≥ k·√λ₂`, major first.
    pub semi_axes: [f64; 2],
    /// Angle of the major axis from the x-axis, radians, in (−π/2, π/2].
    pub angle: f64,
}

impl ErrorEllipse {
    /// `n` points on the outline, evenly spaced in the parametric angle `t = 2πi/n`,
    /// starting on the major axis; join the last point to the first to close the curve.
    pub fn points(&self, n: usize) -> Vec<[f64; 2]> {
        let (s, c) = self.angle.sin_cos();
        (0..n)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / n as f64;
                let u = self.semi_axes[0] * t.cos();
                let v = self.semi_axes[1] * t.sin();
                [
                    self.centre[0] + c * u - s * v,
                    self.centre[1] + s * u + c * v,
                ]
            })
            .collect()
    }

    /// Whether `p` lies in the closed ellipse.
    pub fn contains(&self, p: [f64; 2]) -> bool {
        let (s, c) = self.angle.sin_cos();
        let dx = p[0] - self.centre[0];
        let dy = p[1] - self.centre[1];
        // Rotate by −angle into the ellipse's own axes.
        let u = (c * dx + s * dy) / self.semi_axes[0];
        let v = (-s * dx + c * dy) / self.semi_axes[1];
        u * u + v * v <= 1.0
    }
}

/// The error ellipse holding probability `mass` (0 < mass < 1) of `N(mean, cov)` in 2-D.
///
/// The Mahalanobis distance² of a 2-D Gaussian is χ²₂, whose CDF is `1 − e^{−k²/2}`, so
/// `k² = −2 ln(1 − mass)`. The axes come from the closed-form eigen decomposition of the
/// 2×2 `cov = [[a, b], [b, c]]`: `λ₁,₂ = (a+c)/2 ± √(((a−c)/2)² + b²)`, major-axis angle
/// `½·atan2(2b, a − c)`. `cov` must be symmetric (relative tolerance 1e-12) and positive
/// definite.
pub fn error_ellipse(mean: [f64; 2], cov: [[f64; 2]; 2], mass: f64) -> Result<ErrorEllipse> {
    if !(mass > 0.0 && mass < 1.0) {
        return Err(CoreError::Param(ParamError {
            name: "mass",
            value: mass,
            reason: "the ellipse's probability mass must lie in (0, 1)",
        }));
    }
    for (index, &value) in mean.iter().enumerate() {
        if !value.is_finite() {
            return Err(CoreError::NonFiniteData {
                what: "ellipse mean",
                index,
                value,
            });
        }
    }
    let (a, b01, b10, c) = (cov[0][0], cov[0][1], cov[1][0], cov[1][1]);
    let scale = a.abs().max(c.abs()).max(b01.abs());
    if (b01 - b10).abs() > 1e-12 * scale {
        return Err(CoreError::Param(ParamError {
            name: "cov[0][1] − cov[1][0]",
            value: b01 - b10,
            reason: "the ellipse covariance must be symmetric",
        }));
    }
    let m = DMatrix::from_row_slice(2, 2, &[a, b01, b10, c]);
    cholesky("ellipse covariance", &m)?;
    let b = 0.5 * (b01 + b10);
    let half_tr = 0.5 * (a + c);
    let rad = (0.25 * (a - c) * (a - c) + b * b).sqrt();
    let l1 = half_tr + rad;
    // λ₂ = det/λ₁ avoids the cancellation in half_tr − rad for elongated ellipses.
    let l2 = (a * c - b * b) / l1;
    let mut angle = 0.5 * b.atan2(0.5 * (a - c));
    // atan2 ∈ (−π, π] gives angle ∈ (−π/2, π/2]; keep the closed upper end.
    if angle <= -std::f64::consts::FRAC_PI_2 {
        angle += std::f64::consts::PI;
    }
    let k2 = -2.0 * (-mass).ln_1p();
    Ok(ErrorEllipse {
        centre: mean,
        semi_axes: [(k2 * l1).sqrt(), (k2 * l2.max(0.0)).sqrt()],
        angle,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `LN_2PI` is the f64 nearest to ln 2π: fifty digits of ln 2π parse (correctly
    /// rounded) to it. `(2π).ln()` is one ulp below, since `2.0 * PI` is already rounded.
    #[test]
    fn ln_2pi_is_correctly_rounded() {
        let digits = "1.8378770664093454835606594728112352797227949472756";
        assert_eq!(LN_2PI, digits.parse::<f64>().unwrap());
        assert_eq!(0.5 * LN_2PI, 0.918_938_533_204_672_8);
    }
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    #[test]
    fn cholesky_reconstructs() {
        let m = DMatrix::from_row_slice(3, 3, &[4.0, 2.0, 0.6, 2.0, 5.0, 1.0, 0.6, 1.0, 3.0]);
        let l = cholesky("m", &m).unwrap();
        for i in 0..3 {
            for j in (i + 1)..3 {
                assert_eq!(l[(i, j)], 0.0, "upper triangle must be zero");
            }
        }
        // Backward stability of Cholesky: ‖L·Lᵀ − M‖ ≤ c·n·ε·‖M‖ (Golub & Van Loan §4.2.6);
        // c = 4 leaves room for the summation order.
        let err = (&l * l.transpose() - &m).amax();
        assert!(err <= 4.0 * 3.0 * f64::EPSILON * m.amax(), "err = {err}");
    }

    #[test]
    fn cholesky_names_failing_pivot() {
        // Pivot 1 is 1 − (2/2)² = 0 exactly: singular.
        let m = DMatrix::from_row_slice(3, 3, &[4.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
        assert_eq!(
            cholesky("m", &m),
            Err(CoreError::NotPositiveDefinite {
                what: "m",
                pivot: 1,
                value: 0.0
            })
        );
        let m = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 2.0, -3.0]));
        assert_eq!(
            cholesky("q", &m),
            Err(CoreError::NotPositiveDefinite {
                what: "q",
                pivot: 2,
                value: -3.0
            })
        );
        let m = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, f64::NAN, 1.0]);
        assert!(matches!(
            cholesky("m", &m),
            Err(CoreError::NonFiniteData { index: 2, .. })
        ));
        assert!(matches!(
            cholesky("m", &DMatrix::zeros(2, 3)),
            Err(CoreError::DimensionMismatch { .. })
        ));
    }

    #[test]
    fn log_density_matches_closed_form_2d() {
        let (s1, s2, rho) = (1.5_f64, 0.7_f64, -0.4_f64);
        let cov = DMatrix::from_row_slice(2, 2, &[s1 * s1, rho * s1 * s2, rho * s1 * s2, s2 * s2]);
        let mu = DVector::from_vec(vec![0.3, -1.0]);
        let g = MvNormal::new(mu.clone(), &cov).unwrap();
        let x = DVector::from_vec(vec![1.1, -0.2]);
        // Bivariate normal density, textbook form.
        let (z1, z2) = ((x[0] - mu[0]) / s1, (x[1] - mu[1]) / s2);
        let q = (z1 * z1 - 2.0 * rho * z1 * z2 + z2 * z2) / (1.0 - rho * rho);
        let want = -(std::f64::consts::TAU * s1 * s2 * (1.0 - rho * rho).sqrt()).ln() - 0.5 * q;
        // A handful of flops on O(1) numbers: a few ε of relative error.
        assert!((g.log_density(&x) - want).abs() <= 16.0 * f64::EPSILON * want.abs().max(1.0));
        assert!(g.log_density(&DVector::zeros(3)).is_nan());
        let var = 2.3;
        let want1 = -0.5 * (std::f64::consts::TAU * var).ln() - 0.5 * 0.49 / var;
        assert!((log_normal_pdf_1d(1.0, 0.3, var) - want1).abs() <= 8.0 * f64::EPSILON);
    }

    #[test]
    fn sample_moments_within_standard_errors() {
        let cov = DMatrix::from_row_slice(2, 2, &[2.0, -0.6, -0.6, 0.5]);
        let mu = DVector::from_vec(vec![1.0, -2.0]);
        let g = MvNormal::new(mu.clone(), &cov).unwrap();
        assert!((g.covariance() - &cov).amax() <= 4.0 * f64::EPSILON * 2.0);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        let n = 20_000;
        let mut x = DVector::zeros(2);
        let mut sum = DVector::zeros(2);
        let mut sum2 = DMatrix::zeros(2, 2);
        for _ in 0..n {
            g.sample_into(&mut rng, &mut x);
            sum += &x;
            let d = &x - &mu;
            sum2 += &d * d.transpose();
        }
        let nf = n as f64;
        let mean = sum / nf;
        let emp = sum2 / nf;
        // z = 4: a 4σ deviation has probability ≈ 6e-5 per entry for a correct sampler.
        // SE of a mean entry is σ_i/√n; of a covariance entry (known mean), for Gaussians,
        // √((Σ_ii Σ_jj + Σ_ij²)/n).
        for i in 0..2 {
            let se = (cov[(i, i)] / nf).sqrt();
            assert!((mean[i] - mu[i]).abs() < 4.0 * se, "mean[{i}]");
            for j in 0..2 {
                let se = ((cov[(i, i)] * cov[(j, j)] + cov[(i, j)].powi(2)) / nf).sqrt();
                assert!((emp[(i, j)] - cov[(i, j)]).abs() < 4.0 * se, "cov[{i}{j}]");
            }
        }
    }

    #[test]
    fn ellipse_of_diagonal_covariance_is_axis_aligned() {
        let mass = 0.95;
        let k2 = -2.0 * (1.0_f64 - mass).ln();
        let e = error_ellipse([1.0, 2.0], [[4.0, 0.0], [0.0, 1.0]], mass).unwrap();
        // Closed-form on exact inputs: a few ε.
        let tol = 8.0 * f64::EPSILON * 4.0 * k2;
        assert!((e.semi_axes[0] - (k2 * 4.0).sqrt()).abs() < tol);
        assert!((e.semi_axes[1] - k2.sqrt()).abs() < tol);
        assert_eq!(e.angle, 0.0);
        // Major axis along y.
        let e = error_ellipse([0.0, 0.0], [[1.0, 0.0], [0.0, 9.0]], mass).unwrap();
        assert!((e.angle - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!((e.semi_axes[0] - 3.0 * k2.sqrt()).abs() < tol);
        // Outline points lie on the ellipse.
        for p in e.points(16) {
            let q = p[0] * p[0] / (k2 * 1.0) + p[1] * p[1] / (k2 * 9.0);
            assert!((q - 1.0).abs() < 1e-14, "q = {q}");
        }
    }

    #[test]
    fn ellipse_recovers_rotation() {
        let (l1, l2) = (5.0_f64, 0.5_f64);
        // 2.0 rad is outside (−π/2, π/2]: the same axis is reported as 2.0 − π.
        for (theta, expect) in [(0.6, 0.6), (-1.2, -1.2), (2.0, 2.0 - std::f64::consts::PI)] {
            let (s, c) = f64::sin_cos(theta);
            let cov = [
                [l1 * c * c + l2 * s * s, (l1 - l2) * s * c],
                [(l1 - l2) * s * c, l1 * s * s + l2 * c * c],
            ];
            let e = error_ellipse([0.0, 0.0], cov, 0.5).unwrap();
            // Eigenvector perturbation ~ ε·‖Σ‖/(λ₁ − λ₂) ≈ 1.1 ε; allow 64 ε.
            assert!(
                (e.angle - expect).abs() < 64.0 * f64::EPSILON,
                "θ = {theta}"
            );
            let k2 = -2.0 * 0.5_f64.ln();
            assert!((e.semi_axes[0] - (k2 * l1).sqrt()).abs() < 64.0 * f64::EPSILON);
            assert!((e.semi_axes[1] - (k2 * l2).sqrt()).abs() < 64.0 * f64::EPSILON);
        }
        assert!(matches!(
            error_ellipse([0.0, 0.0], [[1.0, 2.0], [2.0, 1.0]], 0.5),
            Err(CoreError::NotPositiveDefinite { pivot: 1, .. })
        ));
        assert!(matches!(
            error_ellipse([0.0, 0.0], [[1.0, 0.0], [0.0, 1.0]], 1.0),
            Err(CoreError::Param(ParamError { name: "mass", .. }))
        ));
    }

    #[test]
    fn ellipse_holds_its_mass() {
        let cov = [[2.0, 0.9], [0.9, 1.0]];
        let mu = [0.5, -0.5];
        let mass = 0.9;
        let e = error_ellipse(mu, cov, mass).unwrap();
        let g = MvNormal::new(
            DVector::from_row_slice(&mu),
            &DMatrix::from_row_slice(2, 2, &[2.0, 0.9, 0.9, 1.0]),
        )
        .unwrap();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
        let n = 20_000;
        let inside = (0..n)
            .filter(|_| {
                let x = g.sample(&mut rng);
                e.contains([x[0], x[1]])
            })
            .count();
        let frac = inside as f64 / n as f64;
        // Binomial SE √(p(1−p)/n) ≈ 0.0021; z = 4.
        let se = (mass * (1.0 - mass) / n as f64).sqrt();
        assert!((frac - mass).abs() < 4.0 * se, "frac = {frac}");
    }
}
