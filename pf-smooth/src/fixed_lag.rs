//! The fixed-lag estimator `τ̂_n^{δ,N}` of a smoothed additive functional, eqs. (8)–(9).
//!
//! Instead of letting resampling rewrite the whole past (eq. (7)), the term
//! `s_k(X_k, X_{k+1})` is evaluated on the trajectories of step `(k + δ) ∧ n` and then
//! frozen: it estimates `E[s_k | Y_{0:(k+δ)∧n}]`, the δ-lag smoothing expectation of eq. (8).
//! Forgetting makes that close to `E[s_k | Y_{0:n}]`, and the frozen terms no longer suffer
//! from path degeneracy, so the variance drops at the price of a small bias.
//!
//! Recursive form (Section 4): each particle keeps a cache of its last δ terms, which
//! follows the ancestor indices like `γ` in eq. (7), plus one shared vector holds the
//! frozen, already-final contribution. The paper caches the last δ *positions* and
//! re-evaluates `s_k` from them; caching the terms themselves gives the same numbers
//! without re-evaluation. Memory is O(N·δ·d), independent of `n`.
//!
//! Indexing: the term of step `j ≥ 1` is `s_{j−1}(X_{j−1}, X_j)`; it is frozen at step
//! `j + δ − 1` (the paper's `k + δ` with `k = j − 1`), weighted by the weights of that step.
//! The term of step 0 (a function of `X_0` only) is part of `s_0` and frozen with it. For
//! `δ > n` nothing is frozen and the estimate is the path-space one (eq. (6)).

use crate::error::{Result, SmoothError};
use crate::functional::AdditiveFunctional;
use crate::path_space::{check_finite, check_len, copy_states};
use pf_core::observe::{Observer, StepView};

/// Fixed-lag estimator `τ̂_n^{δ,N}` (eq. (9)) as a pf-core [`Observer`].
///
/// Works with any resampling policy: between resamplings the ancestors are the identity and
/// the cache is left in place. Nothing is allocated per step once the buffers have their
/// size.
#[derive(Debug, Clone)]
pub struct FixedLag<S, F> {
    f: F,
    d: usize,
    /// δ.
    delta: usize,
    /// `ξ_{k−1}^i`.
    prev: Vec<S>,
    /// The last δ terms of each particle: N × δ × d, particle-major; the term of step j
    /// sits in slot `j mod δ`.
    cache: Vec<f64>,
    cache_next: Vec<f64>,
    /// Frozen contribution `Σ_{j frozen} Σ_i W_{j+δ−1}^i s^i_j` (length d).
    frozen: Vec<f64>,
    /// `W_k^i`.
    weights: Vec<f64>,
    t: Option<usize>,
}

impl<S: Clone, F: AdditiveFunctional<S>> FixedLag<S, F> {
    /// The estimator of `f` with lag `δ = delta`.
    ///
    /// # Errors
    /// `δ = 0` ([`SmoothError::InvalidParameter`]): the term `s_k(X_k, X_{k+1})` needs at
    /// least the step `k + 1`.
    pub fn new(f: F, delta: usize) -> Result<Self> {
        if delta == 0 {
            return Err(SmoothError::InvalidParameter {
                name: "delta",
                value: 0.0,
                reason: "the lag must be at least 1",
            });
        }
        let d = f.dim();
        Ok(FixedLag {
            f,
            d,
            delta,
            prev: Vec::new(),
            cache: Vec::new(),
            cache_next: Vec::new(),
            frozen: vec![0.0; d],
            weights: Vec::new(),
            t: None,
        })
    }

    /// The lag δ.
    pub fn delta(&self) -> usize {
        self.delta
    }

    /// Time index of the last step seen.
    pub fn t(&self) -> Option<usize> {
        self.t
    }

    /// The frozen part of the estimate (terms older than the lag).
    pub fn frozen(&self) -> &[f64] {
        &self.frozen
    }

    #[inline]
    fn slot(&self, j: usize) -> usize {
        j % self.delta
    }

    /// Write `τ̂_k^{δ,N}` (eq. (9)): the frozen part plus `Σ_i W_k^i` times the particle's
    /// cached terms.
    ///
    /// # Errors
    /// [`SmoothError::NoSteps`] before the first step, a length mismatch, or a non-finite
    /// component.
    pub fn estimate_into(&self, out: &mut [f64]) -> Result<()> {
        let t = self.t.ok_or(SmoothError::NoSteps {
            what: "fixed-lag estimator",
        })?;
        check_len(out.len(), self.d)?;
        out.copy_from_slice(&self.frozen);
        let block = self.delta * self.d;
        for (w, c) in self.weights.iter().zip(self.cache.chunks_exact(block)) {
            for term in c.chunks_exact(self.d) {
                for (o, v) in out.iter_mut().zip(term) {
                    *o += w * v;
                }
            }
        }
        check_finite("fixed-lag estimate", t, out)
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

impl<S: Clone, F: AdditiveFunctional<S>> Observer<S> for FixedLag<S, F> {
    fn on_step(&mut self, view: &StepView<'_, S>) {
        let n = view.particles.len();
        let d = self.d;
        let block = self.delta * d;
        let k = view.report.t;
        if k == 0 || self.t.is_none() {
            self.cache.clear();
            self.cache.resize(n * block, 0.0);
            self.cache_next.resize(n * block, 0.0);
            self.frozen.fill(0.0);
            // The term of X_0 belongs to s_0, frozen together with the term of step 1.
            let off = self.slot(1) * d;
            for (x0, c) in view
                .particles
                .iter()
                .zip(self.cache.chunks_exact_mut(block))
            {
                self.f.initial(x0, &mut c[off..off + d]);
            }
        } else {
            if view.report.resampled {
                // The cached terms follow their trajectories, like γ in eq. (7).
                for (i, c) in self.cache_next.chunks_exact_mut(block).enumerate() {
                    let a = view.ancestors[i];
                    c.copy_from_slice(&self.cache[a * block..(a + 1) * block]);
                }
                std::mem::swap(&mut self.cache, &mut self.cache_next);
            }
            // The new term s_{k−1}(ξ_{k−1}^{A_k^i}, ξ_k^i) goes into slot k mod δ, emptied when
            // its previous occupant (the term of step k − δ) was frozen at step k − 1.
            let off = self.slot(k) * d;
            for (i, c) in self.cache.chunks_exact_mut(block).enumerate() {
                let a = view.ancestors[i];
                self.f
                    .increment(k, &self.prev[a], &view.particles[i], &mut c[off..off + d]);
            }
            // Freeze the term of step j = k + 1 − δ under the weights of step k.
            if k + 1 >= self.delta {
                let j = k + 1 - self.delta;
                if j >= 1 {
                    let off = self.slot(j) * d;
                    for (w, c) in view.weights.iter().zip(self.cache.chunks_exact_mut(block)) {
                        let term = &mut c[off..off + d];
                        for (fz, v) in self.frozen.iter_mut().zip(term.iter_mut()) {
                            *fz += w * *v;
                            *v = 0.0;
                        }
                    }
                }
            }
        }
        copy_states(&mut self.prev, view.particles);
        self.weights.clear();
        self.weights.extend_from_slice(view.weights);
        self.t = Some(k);
    }
}
