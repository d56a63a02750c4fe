//! The linear-Gaussian model on the batch filter: dense matrices flattened for loops over
//! particle columns, with the Kalman filter as its exact reference.

use nalgebra::DMatrix;
use nalgebra::DVector;

use super::LinearGaussian;
use crate::error::{CoreError, Result};
use crate::filter::{BatchModel, BatchTransitionDensity, Cols, ColsMut};
use crate::gaussian::LN_2PI;

/// [`LinearGaussian`] as a [`BatchModel`] (`D = d` columns, `d` normals a step), made by
/// [`LinearGaussian::batch`]. The Gaussian log-densities are computed through the inverse
/// Cholesky factors: `log N(e; 0, LLᵀ) = −½ m log 2π − Σ log L_ii − ½ |L⁻¹ e|²`.
#[derive(Debug, Clone)]
pub struct BatchLinearGaussian {
    d: usize,
    m: usize,
    /// A, `L_Q`, `L_{P₀}` row-major, `m₀`.
    a: Vec<f64>,
    lq: Vec<f64>,
    lp0: Vec<f64>,
    m0: Vec<f64>,
    /// `L_R⁻¹` (m×m) and `G = L_R⁻¹ C` (m×d), row-major, and `−½ m log 2π − Σ log (L_R)_ii`.
    lr_inv: Vec<f64>,
    g: Vec<f64>,
    log_norm_g: f64,
    /// `L_Q⁻¹` and `L_Q⁻¹ A` (d×d), and `−½ d log 2π − Σ log (L_Q)_ii`.
    lq_inv: Vec<f64>,
    lq_inv_a: Vec<f64>,
    log_norm_f: f64,
}

/// Particles handled together in the quadratic forms: a block of accumulators in
/// registers.
const BLOCK: usize = 8;

fn row_major(m: &DMatrix<f64>) -> Vec<f64> {
    m.transpose().as_slice().to_vec()
}

/// `L⁻¹` of a lower-triangular `L` with a positive diagonal.
fn lower_inverse(l: &DMatrix<f64>, what: &'static str) -> Result<DMatrix<f64>> {
    let n = l.nrows();
    l.solve_lower_triangular(&DMatrix::identity(n, n))
        .ok_or(CoreError::NotPositiveDefinite {
            what,
            pivot: 0,
            value: 0.0,
        })
}

impl LinearGaussian {
    /// The model for [`BatchFilter`](crate::filter::BatchFilter).
    ///
    /// # Errors
    /// A model with inputs (`B`): the batch form has none.
    pub fn batch(&self) -> Result<BatchLinearGaussian> {
        if self.b().is_some() {
            return Err(CoreError::Param(crate::params::ParamError::new(
                "B",
                self.input_dim() as f64,
                "the batch form of the linear-Gaussian model takes no inputs",
            )));
        }
        let (d, m) = (self.state_dim(), self.obs_dim());
        let lr_inv = lower_inverse(self.chol_r(), "R")?;
        let lq_inv = lower_inverse(self.chol_q(), "Q")?;
        let log_det = |l: &DMatrix<f64>| l.diagonal().iter().map(|v| v.ln()).sum::<f64>();
        Ok(BatchLinearGaussian {
            d,
            m,
            a: row_major(self.a()),
            lq: row_major(self.chol_q()),
            lp0: row_major(self.chol_p0()),
            m0: self.m0().as_slice().to_vec(),
            g: row_major(&(&lr_inv * self.c())),
            lr_inv: row_major(&lr_inv),
            log_norm_g: -0.5 * m as f64 * LN_2PI - log_det(self.chol_r()),
            lq_inv_a: row_major(&(&lq_inv * self.a())),
            lq_inv: row_major(&lq_inv),
            log_norm_f: -0.5 * d as f64 * LN_2PI - log_det(self.chol_q()),
        })
    }
}

/// `x_i = b_i + Σ_k M_ik z_k` for every row `i` of the row-major `M`, over columns.
#[inline(always)]
fn affine(b: Option<&[f64]>, m: &[f64], z: Cols<'_>, x: &mut ColsMut<'_>) {
    let cols = z.dim();
    for i in 0..x.dim() {
        let xi = x.col_mut(i);
        xi.fill(b.map_or(0.0, |b| b[i]));
        for (k, &mik) in m[i * cols..(i + 1) * cols].iter().enumerate() {
            if mik != 0.0 {
                for (x, &z) in xi.iter_mut().zip(z.col(k)) {
                    *x += mik * z;
                }
            }
        }
    }
}

/// `out[j] += c − ½ Σ_r (b(r) − Σ_k G_rk x_k[j] + Σ_k H_rk p_k[j])²` for the rows `r` of
/// the row-major `G` (`rows` of them, over `x`'s columns) and `H` (over `p`'s, if given):
/// a Gaussian log-density through an inverse Cholesky factor.
#[inline(always)]
fn add_quadratic(
    c: f64,
    rows: usize,
    b: impl Fn(usize) -> f64,
    g: &[f64],
    x: Cols<'_>,
    h: Option<(&[f64], Cols<'_>)>,
    out: &mut [f64],
) {
    let (dx, len) = (x.dim(), out.len());
    for o in out.iter_mut() {
        *o += c;
    }
    for r in 0..rows {
        let br = b(r);
        let mut j = 0;
        while j < len {
            let w = BLOCK.min(len - j);
            let mut v = [br; BLOCK];
            for (k, &grk) in g[r * dx..(r + 1) * dx].iter().enumerate() {
                for (v, &x) in v.iter_mut().zip(&x.col(k)[j..j + w]) {
                    *v -= grk * x;
                }
            }
            if let Some((h, p)) = h {
                let dp = p.dim();
                for (k, &hrk) in h[r * dp..(r + 1) * dp].iter().enumerate() {
                    for (v, &p) in v.iter_mut().zip(&p.col(k)[j..j + w]) {
                        *v += hrk * p;
                    }
                }
            }
            for (o, &v) in out[j..j + w].iter_mut().zip(&v) {
                *o -= 0.5 * v * v;
            }
            j += w;
        }
    }
}

impl BatchModel for BatchLinearGaussian {
    type Obs = DVector<f64>;
    type Input = ();

    fn dim(&self) -> usize {
        self.d
    }

    fn noise_dim(&self) -> usize {
        self.d
    }

    /// `X_0 = m₀ + L_{P₀} z`.
    fn initial(&self, z: Cols<'_>, mut x: ColsMut<'_>) {
        affine(Some(&self.m0), &self.lp0, z, &mut x);
    }

    /// `X_t = A X_{t−1} + L_Q z`.
    fn propagate(&self, _t: usize, _u: &(), parents: Cols<'_>, z: Cols<'_>, mut x: ColsMut<'_>) {
        affine(None, &self.a, parents, &mut x);
        let d = self.d;
        for i in 0..d {
            let xi = x.col_mut(i);
            for (k, &l) in self.lq[i * d..(i + 1) * d].iter().enumerate() {
                if l != 0.0 {
                    for (x, &z) in xi.iter_mut().zip(z.col(k)) {
                        *x += l * z;
                    }
                }
            }
        }
    }

    /// `log N(y; C x, R)`; an observation of the wrong length weighs nothing (`−∞`).
    fn add_log_likelihood(&self, _t: usize, y: &DVector<f64>, x: Cols<'_>, lw: &mut [f64]) {
        if y.len() != self.m {
            lw.fill(f64::NEG_INFINITY);
            return;
        }
        let m = self.m;
        // b_r = (L_R⁻¹ y)_r.
        let b = |r: usize| (0..m).map(|i| self.lr_inv[r * m + i] * y[i]).sum::<f64>();
        add_quadratic(self.log_norm_g, m, b, &self.g, x, None, lw);
    }
}

impl BatchTransitionDensity for BatchLinearGaussian {
    /// `log N(x; A x_{t−1}, Q)`.
    fn add_log_transition(
        &self,
        _t: usize,
        _u: &(),
        parents: Cols<'_>,
        x: Cols<'_>,
        out: &mut [f64],
    ) {
        add_quadratic(
            self.log_norm_f,
            self.d,
            |_| 0.0,
            &self.lq_inv,
            x,
            Some((&self.lq_inv_a, parents)),
            out,
        );
    }
}
