//! What the batch filter shows after a step: its particles' columns and weights, and the
//! observers that record from them.

use super::model::Cols;
use crate::error::{CoreError, Result};
use crate::filter::StepReport;
use serde::{Deserialize, Serialize};

/// The particles and weights after one step of a [`BatchFilter`](super::BatchFilter),
/// borrowed from it.
///
/// The filter keeps each particle's weight as a cumulative sum within its chunk, relative
/// to the chunk's largest weight; the view turns them into normalised weights `W_t^i` and
/// weighted moments without copying the particles.
#[derive(Debug, Clone, Copy)]
pub struct BatchView<'a> {
    pub(super) report: StepReport,
    /// States, chunk after chunk, each chunk `dim` columns `c` apart.
    pub(super) x: &'a [f64],
    pub(super) dim: usize,
    pub(super) n: usize,
    pub(super) c: usize,
    pub(super) cw: &'a [f64],
    pub(super) scale: &'a [f64],
    pub(super) total: f64,
}

impl<'a> BatchView<'a> {
    /// The step's report (time, likelihood, ESS, whether it resampled).
    pub fn report(&self) -> &StepReport {
        &self.report
    }

    /// Particles `N`.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The state's dimension `D`.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Each chunk: its columns, its cumulative weights and its scale `exp(m_d − max)`.
    fn chunks(&self) -> impl Iterator<Item = (Cols<'a>, &'a [f64], f64)> + '_ {
        let (dim, c) = (self.dim, self.c);
        self.cw
            .chunks(c)
            .zip(self.scale)
            .enumerate()
            .map(move |(d, (cw, &scale))| {
                let x = Cols::strided(&self.x[d * dim * c..], dim, cw.len(), c);
                (x, cw, scale)
            })
    }

    fn check(&self, what: &'static str, expected: usize, got: usize) -> Result<()> {
        if expected == got {
            Ok(())
        } else {
            Err(CoreError::DimensionMismatch {
                what,
                expected,
                got,
            })
        }
    }

    /// The normalised weights `W_t^i` into `w` (`N` values).
    ///
    /// # Errors
    /// `w` not of length `N`.
    pub fn weights_into(&self, w: &mut [f64]) -> Result<()> {
        self.check("BatchView::weights_into output", self.n, w.len())?;
        let mut out = w.iter_mut();
        for (_, cw, scale) in self.chunks() {
            let r = scale / self.total;
            let mut prev = 0.0;
            for (&cw, w) in cw.iter().zip(&mut out) {
                *w = r * (cw - prev);
                prev = cw;
            }
        }
        Ok(())
    }

    /// The weighted means `Σ_i W_t^i X_t^i` of the `D` components into `out`.
    ///
    /// # Errors
    /// `out` not of length `D`.
    pub fn mean_into(&self, out: &mut [f64]) -> Result<()> {
        self.check("BatchView::mean_into output", self.dim, out.len())?;
        out.fill(0.0);
        for (x, cw, scale) in self.chunks() {
            for (k, acc) in out.iter_mut().enumerate() {
                let mut prev = 0.0;
                let mut chunk_acc = 0.0;
                for (x, &cw) in x.col(k).iter().zip(cw) {
                    chunk_acc += x * (cw - prev);
                    prev = cw;
                }
                *acc += scale * chunk_acc;
            }
        }
        for m in out.iter_mut() {
            *m /= self.total;
        }
        Ok(())
    }

    /// The weighted covariance `Σ_i W_t^i (X_t^i − m)(X_t^i − m)ᵀ` about the weighted
    /// means `mean` (from [`mean_into`](Self::mean_into)), row-major `D × D` into `out`.
    ///
    /// # Errors
    /// `mean` not of length `D`, or `out` not of length `D²`.
    pub fn covariance_into(&self, mean: &[f64], out: &mut [f64]) -> Result<()> {
        let d = self.dim;
        self.check("BatchView::covariance_into mean", d, mean.len())?;
        self.check("BatchView::covariance_into output", d * d, out.len())?;
        out.fill(0.0);
        for (x, cw, scale) in self.chunks() {
            for a in 0..d {
                for b in a..d {
                    let (xa, xb) = (x.col(a), x.col(b));
                    let (ma, mb) = (mean[a], mean[b]);
                    let mut prev = 0.0;
                    let mut acc = 0.0;
                    for ((&xa, &xb), &cw) in xa.iter().zip(xb).zip(cw) {
                        acc += (cw - prev) * (xa - ma) * (xb - mb);
                        prev = cw;
                    }
                    out[a * d + b] += scale * acc;
                }
            }
        }
        for a in 0..d {
            for b in a..d {
                let v = out[a * d + b] / self.total;
                out[a * d + b] = v;
                out[b * d + a] = v;
            }
        }
        Ok(())
    }

    /// Particle `i`'s state into `out` (`D` values).
    ///
    /// # Errors
    /// `i ≥ N`, or `out` not of length `D`.
    pub fn state_into(&self, i: usize, out: &mut [f64]) -> Result<()> {
        self.check("BatchView::state_into output", self.dim, out.len())?;
        if i >= self.n {
            return Err(CoreError::DimensionMismatch {
                what: "BatchView::state_into particle index (expected below N)",
                expected: self.n,
                got: i,
            });
        }
        let base = (i / self.c) * self.dim * self.c + i % self.c;
        for (k, o) in out.iter_mut().enumerate() {
            *o = self.x[base + k * self.c];
        }
        Ok(())
    }

    /// Column `k` of every particle (component `k` of `X_t^0 … X_t^{N−1}`) into `out`.
    ///
    /// # Errors
    /// `k ≥ D`, or `out` not of length `N`.
    pub fn column_into(&self, k: usize, out: &mut [f64]) -> Result<()> {
        self.check("BatchView::column_into output", self.n, out.len())?;
        if k >= self.dim {
            return Err(CoreError::DimensionMismatch {
                what: "BatchView::column_into column (expected below D)",
                expected: self.dim,
                got: k,
            });
        }
        let mut dst = out.iter_mut();
        for (x, _, _) in self.chunks() {
            // The chunk's values first: a zip that found them exhausted would already have
            // taken the next output slot.
            for (&v, o) in x.col(k).iter().zip(&mut dst) {
                *o = v;
            }
        }
        Ok(())
    }
}

/// Receives each step of a batch run. Every method defaults to doing nothing.
pub trait BatchObserver {
    /// Before the first step: `N` and `D`.
    fn on_start(&mut self, _n_particles: usize, _dim: usize) {}
    /// After every step.
    fn on_step(&mut self, _view: &BatchView<'_>) {}
    /// After the last step: the first error met while recording, if any.
    ///
    /// # Errors
    /// What the observer could not record.
    fn on_finish(&mut self) -> Result<()> {
        Ok(())
    }
}

impl BatchObserver for () {}

impl<O: BatchObserver + ?Sized> BatchObserver for &mut O {
    fn on_start(&mut self, n: usize, dim: usize) {
        (**self).on_start(n, dim)
    }
    fn on_step(&mut self, view: &BatchView<'_>) {
        (**self).on_step(view)
    }
    fn on_finish(&mut self) -> Result<()> {
        (**self).on_finish()
    }
}

/// `None` records nothing, so optional analyses can share one run.
impl<O: BatchObserver> BatchObserver for Option<O> {
    fn on_start(&mut self, n: usize, dim: usize) {
        if let Some(o) = self {
            o.on_start(n, dim)
        }
    }
    fn on_step(&mut self, view: &BatchView<'_>) {
        if let Some(o) = self {
            o.on_step(view)
        }
    }
    fn on_finish(&mut self) -> Result<()> {
        match self {
            Some(o) => o.on_finish(),
            None => Ok(()),
        }
    }
}

macro_rules! tuple_observer {
    ($($name:ident . $idx:tt),+) => {
        impl<$($name: BatchObserver),+> BatchObserver for ($($name,)+) {
            fn on_start(&mut self, n: usize, dim: usize) {
                $(self.$idx.on_start(n, dim);)+
            }
            fn on_step(&mut self, view: &BatchView<'_>) {
                $(self.$idx.on_step(view);)+
            }
            /// Finishes every member, then returns the first member's error.
            fn on_finish(&mut self) -> Result<()> {
                let mut first = Ok(());
                $(
                    let r = self.$idx.on_finish();
                    if first.is_ok() {
                        first = r;
                    }
                )+
                first
            }
        }
    };
}

tuple_observer!(A.0);
tuple_observer!(A.0, B.1);
tuple_observer!(A.0, B.1, C.2);
tuple_observer!(A.0, B.1, C.2, D.3);

/// Records, at every step, the ESS and the weighted mean and covariance of the state.
///
/// Made [`with_capacity`](Self::with_capacity) for the run's steps, it allocates nothing
/// while the filter runs.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MomentRecorder {
    /// The state's dimension `D`.
    pub dim: usize,
    /// Time index of each record.
    pub t: Vec<usize>,
    /// ESS of each step.
    pub ess: Vec<f64>,
    /// Weighted means, `D` per step.
    pub mean: Vec<f64>,
    /// Weighted covariances, `D × D` row-major per step.
    pub cov: Vec<f64>,
}

impl MomentRecorder {
    /// Room for `steps` steps of a `dim`-dimensional state.
    pub fn with_capacity(steps: usize, dim: usize) -> Self {
        MomentRecorder {
            dim,
            t: Vec::with_capacity(steps),
            ess: Vec::with_capacity(steps),
            mean: Vec::with_capacity(steps * dim),
            cov: Vec::with_capacity(steps * dim * dim),
        }
    }

    /// Step `s`'s mean (the `s`-th record).
    pub fn mean_at(&self, s: usize) -> &[f64] {
        &self.mean[s * self.dim..(s + 1) * self.dim]
    }

    /// Step `s`'s covariance, row-major.
    pub fn cov_at(&self, s: usize) -> &[f64] {
        let d2 = self.dim * self.dim;
        &self.cov[s * d2..(s + 1) * d2]
    }
}

impl BatchObserver for MomentRecorder {
    fn on_start(&mut self, _n: usize, dim: usize) {
        self.dim = dim;
        self.t.clear();
        self.ess.clear();
        self.mean.clear();
        self.cov.clear();
    }

    fn on_step(&mut self, view: &BatchView<'_>) {
        let d = view.dim;
        let m0 = self.mean.len();
        self.mean.resize(m0 + d, 0.0);
        let c0 = self.cov.len();
        self.cov.resize(c0 + d * d, 0.0);
        // Sizes match by construction, so these cannot fail.
        let mean = &mut self.mean[m0..];
        if view.mean_into(mean).is_ok() {
            let _ = view.covariance_into(&self.mean[m0..], &mut self.cov[c0..]);
        }
        self.t.push(view.report.t);
        self.ess.push(view.report.ess);
    }
}
