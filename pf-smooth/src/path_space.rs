//! The path-space ("joint") estimator of a smoothed additive functional, eqs. (6)–(7).
//!
//! Each particle carries its running sum `γ_k^i`, the functional evaluated along its own
//! ancestral line. When the filter resamples, `γ` follows the ancestor indices (eq. (7)):
//! `γ_k^i = γ_{k−1}^{A_k^i} + s_{k−1}(ξ_{k−1}^{A_k^i}, ξ_k^i)`; when it does not, `A_k^i = i`
//! and the same formula is the first case of (7). So any resampling policy works. The
//! estimate is `τ̂_n^N = Σ_i W_n^i γ_n^i` (eq. (6)). Memory: positions, weights and `γ`
//! only, O(N·d), whatever `n`.

use crate::error::{Result, SmoothError};
use crate::functional::AdditiveFunctional;
use pf_core::observe::{Observer, StepView};

/// Path-space estimator of `τ_n = E[Σ_k s_k | Y_{0:n}]`, as a pf-core [`Observer`].
///
/// Attach it to [`ParticleFilter::run`](pf_core::filter::ParticleFilter::run), or call
/// [`on_step`](Observer::on_step) with [`ParticleFilter::view`](pf_core::filter::ParticleFilter::view)
/// after each online step. A step with `t = 0` restarts it. Nothing is allocated per step
/// once the buffers have their size.
#[derive(Debug, Clone)]
pub struct PathSpace<S, F> {
    f: F,
    d: usize,
    /// `ξ_{k−1}^i`, copied from the previous step.
    prev: Vec<S>,
    /// `γ_k^i`, N×d, particle-major.
    gamma: Vec<f64>,
    gamma_next: Vec<f64>,
    /// `W_k^i`.
    weights: Vec<f64>,
    t: Option<usize>,
}

impl<S: Clone, F: AdditiveFunctional<S>> PathSpace<S, F> {
    /// An estimator of the functional `f`.
    pub fn new(f: F) -> Self {
        let d = f.dim();
        PathSpace {
            f,
            d,
            prev: Vec::new(),
            gamma: Vec::new(),
            gamma_next: Vec::new(),
            weights: Vec::new(),
            t: None,
        }
    }

    /// The functional.
    pub fn functional(&self) -> &F {
        &self.f
    }

    /// Time index of the last step seen.
    pub fn t(&self) -> Option<usize> {
        self.t
    }

    /// `γ_k^i` of particle `i` (N×d, particle-major).
    pub fn gamma(&self) -> &[f64] {
        &self.gamma
    }

    /// Write `τ̂_k^N = Σ_i W_k^i γ_k^i` (eq. (6)) into `out` (length d).
    ///
    /// # Errors
    /// [`SmoothError::NoSteps`] before the first step, a length mismatch, or a non-finite
    /// component ([`SmoothError::NonFiniteEstimate`]).
    pub fn estimate_into(&self, out: &mut [f64]) -> Result<()> {
        let names = ("path-space estimator", "path-space estimate");
        weighted_estimate(names, self.t, (&self.weights, &self.gamma, self.d), out)
    }

    /// [`estimate_into`](Self::estimate_into) a new vector.
    ///
    /// # Errors
    /// As [`estimate_into`](Self::estimate_into).
    pub fn estimate(&self) -> Result<Vec<f64>> {
        let mut out = vec![0.0; self.d];
        self.estimate_into(&mut out)?;
        Ok(out)
    }
}

impl<S: Clone, F: AdditiveFunctional<S>> Observer<S> for PathSpace<S, F> {
    fn on_step(&mut self, view: &StepView<'_, S>) {
        let n = view.particles.len();
        let d = self.d;
        let k = view.report.t;
        if k == 0 || self.t.is_none() {
            self.gamma.clear();
            self.gamma.resize(n * d, 0.0);
            self.gamma_next.resize(n * d, 0.0);
            for (x0, g) in view.particles.iter().zip(self.gamma.chunks_exact_mut(d)) {
                self.f.initial(x0, g);
            }
        } else {
            // Eq. (7): γ_k^i = γ_{k−1}^{A_k^i} + s_{k−1}(ξ_{k−1}^{A_k^i}, ξ_k^i).
            for (i, g) in self.gamma_next.chunks_exact_mut(d).enumerate() {
                let a = view.ancestors[i];
                g.copy_from_slice(&self.gamma[a * d..(a + 1) * d]);
                self.f.increment(k, &self.prev[a], &view.particles[i], g);
            }
            std::mem::swap(&mut self.gamma, &mut self.gamma_next);
        }
        copy_states(&mut self.prev, view.particles);
        self.weights.clear();
        self.weights.extend_from_slice(view.weights);
        self.t = Some(k);
    }
}

/// `dst ← src`, reusing `dst`'s allocations.
pub(crate) fn copy_states<S: Clone>(dst: &mut Vec<S>, src: &[S]) {
    if dst.len() == src.len() {
        dst.clone_from_slice(src);
    } else {
        dst.clear();
        dst.extend_from_slice(src);
    }
}

/// `out ← Σ_i W_i v_i` for the per-particle sums `v` (N×d, particle-major) of an estimator
/// named `names.0` whose estimate is `names.1`, last at step `t`: the estimate of eq. (6),
/// and of forward-only smoothing.
pub(crate) fn weighted_estimate(
    names: (&'static str, &'static str),
    t: Option<usize>,
    (w, v, d): (&[f64], &[f64], usize),
    out: &mut [f64],
) -> Result<()> {
    let t = t.ok_or(SmoothError::NoSteps { what: names.0 })?;
    check_len(out.len(), d)?;
    weighted_sum(w, v, d, out);
    check_finite(names.1, t, out)
}

/// `out ← Σ_i w_i v_i` for particle-major `v` (N×d).
pub(crate) fn weighted_sum(w: &[f64], v: &[f64], d: usize, out: &mut [f64]) {
    out.fill(0.0);
    for (wi, vi) in w.iter().zip(v.chunks_exact(d)) {
        for (o, x) in out.iter_mut().zip(vi) {
            *o += wi * x;
        }
    }
}

pub(crate) fn check_len(got: usize, d: usize) -> Result<()> {
    if got == d {
        Ok(())
    } else {
        Err(pf_core::CoreError::DimensionMismatch {
            what: "estimate buffer (dimension of the statistic)",
            expected: d,
            got,
        }
        .into())
    }
}

pub(crate) fn check_finite(what: &'static str, t: usize, out: &[f64]) -> Result<()> {
    match out.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(component) => Err(SmoothError::NonFiniteEstimate { what, t, component }),
    }
}
