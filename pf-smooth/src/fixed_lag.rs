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
//! without re-evaluation. The terms of a step are stored once, in a table of their own
//! (one of δ, reused in turn), and a particle's cache holds, per step, only the row of its
//! ancestor's term: resampling then copies δ indices per particle instead of δ·d values,
//! and the sums read the same values in the same order. Memory is O(N·δ·d), independent
//! of `n`.
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
    /// The terms, one table of N rows of `d` per slot: the term of step `j` is in slot
    /// `j mod δ`, row `i` computed for particle `i` of step `j`.
    terms: Vec<f64>,
    /// Whether a slot holds terms not yet frozen (else its terms are 0).
    live: Vec<bool>,
    /// Each particle's cache: for each slot, the row of its ancestor's term (N × δ,
    /// particle-major).
    rows: Vec<usize>,
    rows_next: Vec<usize>,
    /// The new terms of a step, before they go to their slot's table.
    fresh: Vec<f64>,
    /// `d` zeros: the terms of a slot that is not live.
    zeros: Vec<f64>,
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
    /// `δ = 0` ([`SmoothError::Param`]): the term `s_k(X_k, X_{k+1})` needs at
    /// least the step `k + 1`.
    pub fn new(f: F, delta: usize) -> Result<Self> {
        pf_core::params::at_least_one("delta", delta)?;
        let d = f.dim();
        Ok(FixedLag {
            f,
            d,
            delta,
            prev: Vec::new(),
            terms: Vec::new(),
            live: vec![false; delta],
            rows: Vec::new(),
            rows_next: Vec::new(),
            fresh: Vec::new(),
            zeros: vec![0.0; d],
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

    /// Number of particles N (0 before the first step).
    #[inline]
    fn n(&self) -> usize {
        self.rows.len() / self.delta
    }

    #[inline]
    fn slot(&self, j: usize) -> usize {
        j % self.delta
    }

    /// The cached term of particle `i` in slot `s` (zeros once frozen).
    #[inline]
    fn term(&self, i: usize, s: usize) -> &[f64] {
        if self.live[s] {
            let row = self.rows[i * self.delta + s];
            let at = (s * self.n() + row) * self.d;
            &self.terms[at..at + self.d]
        } else {
            &self.zeros
        }
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
        for (i, w) in self.weights.iter().enumerate() {
            for s in 0..self.delta {
                for (o, v) in out.iter_mut().zip(self.term(i, s)) {
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

    /// Put the terms in `fresh` into slot `s`, row `i` for particle `i`, and point every
    /// particle's cache there.
    fn store_fresh(&mut self, s: usize) {
        let (n, d, delta) = (self.n(), self.d, self.delta);
        self.terms[s * n * d..(s + 1) * n * d].copy_from_slice(&self.fresh);
        for (i, rows) in self.rows.chunks_exact_mut(delta).enumerate() {
            rows[s] = i;
        }
        self.live[s] = true;
    }
}

impl<S: Clone, F: AdditiveFunctional<S>> Observer<S> for FixedLag<S, F> {
    fn on_step(&mut self, view: &StepView<'_, S>) {
        let n = view.particles.len();
        let (d, delta) = (self.d, self.delta);
        let k = view.report.t;
        if k == 0 || self.t.is_none() {
            self.terms.clear();
            self.terms.resize(delta * n * d, 0.0);
            self.rows.resize(n * delta, 0);
            self.rows_next.resize(n * delta, 0);
            self.fresh.clear();
            self.fresh.resize(n * d, 0.0);
            self.live.fill(false);
            self.frozen.fill(0.0);
            // The term of X_0 belongs to s_0, frozen together with the term of step 1.
            for (x0, c) in view.particles.iter().zip(self.fresh.chunks_exact_mut(d)) {
                c.fill(0.0);
                self.f.initial(x0, c);
            }
            self.store_fresh(self.slot(1));
        } else {
            if view.report.resampled {
                // The cached terms follow their trajectories, like γ in eq. (7).
                for (i, c) in self.rows_next.chunks_exact_mut(delta).enumerate() {
                    let a = view.ancestors[i];
                    c.copy_from_slice(&self.rows[a * delta..(a + 1) * delta]);
                }
                std::mem::swap(&mut self.rows, &mut self.rows_next);
            }
            // The new term s_{k−1}(ξ_{k−1}^{A_k^i}, ξ_k^i) goes into slot k mod δ, added to
            // what the particle's cache holds there: nothing once its previous occupant (the
            // term of step k − δ) was frozen at step k − 1, the term of X_0 at step 1.
            let sk = self.slot(k);
            let mut fresh = std::mem::take(&mut self.fresh);
            for (i, c) in fresh.chunks_exact_mut(d).enumerate() {
                c.copy_from_slice(self.term(i, sk));
                let a = view.ancestors[i];
                self.f.increment(k, &self.prev[a], &view.particles[i], c);
            }
            self.fresh = fresh;
            self.store_fresh(sk);
            // Freeze the term of step j = k + 1 − δ under the weights of step k.
            if k + 1 >= delta {
                let j = k + 1 - delta;
                if j >= 1 {
                    let sj = self.slot(j);
                    let mut frozen = std::mem::take(&mut self.frozen);
                    for (i, w) in view.weights.iter().enumerate() {
                        for (fz, v) in frozen.iter_mut().zip(self.term(i, sj)) {
                            *fz += w * *v;
                        }
                    }
                    self.frozen = frozen;
                    self.live[sj] = false;
                }
            }
        }
        copy_states(&mut self.prev, view.particles);
        self.weights.clear();
        self.weights.extend_from_slice(view.weights);
        self.t = Some(k);
    }
}
