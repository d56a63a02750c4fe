//! Additive functionals `S_n = Σ_k s_k(X_{k−1}, X_k)`: what the smoothers estimate.
//!
//! Cappé & Moulines write the target as `τ_n = E[Σ_{k=0}^{n−1} s_k(X_k, X_{k+1}) | Y_{0:n}]`
//! (eq. (5), where the product sign is a typo for a sum). Here the sum is split by the step
//! at which its term becomes computable: the term of step 0 depends on `X_0` only
//! ([`initial`](AdditiveFunctional::initial)), the term of step `k ≥ 1` on `(X_{k−1}, X_k)`
//! ([`increment`](AdditiveFunctional::increment)). This covers the paper's
//! `s_0(x_0) = log g_0(x_0)` and statistics such as `Σ_{k=0}^n (Y_k − X_k)²`.

/// A vector-valued additive functional of the hidden path.
///
/// Both methods *add* their term into `out` (length [`dim`](Self::dim)), so that running
/// sums `γ_k^i` are updated in place, without allocation.
pub trait AdditiveFunctional<S>: Sync {
    /// Dimension of the statistic.
    fn dim(&self) -> usize;

    /// `out += s(x_0)`, the term of step 0.
    fn initial(&self, x0: &S, out: &mut [f64]);

    /// `out += s_{k−1}(x_{k−1}, x_k)`, the term of step `k ≥ 1`.
    fn increment(&self, k: usize, x_prev: &S, x: &S, out: &mut [f64]);

    /// `out += Σ_j β_j s_{k−1}(x_prev[j], x)` over the `j` with `β_j ≠ 0`: the inner sum of
    /// forward-only smoothing ([`forward`](crate::forward)), for backward weights `β` that
    /// sum to 1. `scratch` holds `x_prev.len() · dim` values.
    ///
    /// By default each term is evaluated into `scratch`, then they are summed (reading
    /// each one back right after its scalar stores stalled on store forwarding, a third of
    /// the time). A functional with a closed form overrides it, as
    /// [`Ar1Statistics`](crate::Ar1Statistics) does.
    fn add_weighted_increments(
        &self,
        k: usize,
        x_prev: &[S],
        beta: &[f64],
        x: &S,
        scratch: &mut [f64],
        out: &mut [f64],
    ) {
        let d = out.len();
        scratch.fill(0.0);
        for ((&b, xj), sj) in beta.iter().zip(x_prev).zip(scratch.chunks_exact_mut(d)) {
            if b != 0.0 {
                self.increment(k, xj, x, sj);
            }
        }
        // Four components at a time in a local accumulator: summed in `out` itself, each
        // `j` waited on the previous store.
        for (c0, out) in (0..d).step_by(4).zip(out.chunks_mut(4)) {
            let w = out.len();
            let mut acc = [0.0f64; 4];
            for (&b, sj) in beta.iter().zip(scratch.chunks_exact(d)) {
                for (l, a) in acc[..w].iter_mut().enumerate() {
                    *a += b * sj[c0 + l];
                }
            }
            for (o, a) in out.iter_mut().zip(acc) {
                *o += a;
            }
        }
    }
}

impl<S, F: AdditiveFunctional<S> + ?Sized> AdditiveFunctional<S> for &F {
    fn dim(&self) -> usize {
        (**self).dim()
    }
    fn initial(&self, x0: &S, out: &mut [f64]) {
        (**self).initial(x0, out)
    }
    fn increment(&self, k: usize, x_prev: &S, x: &S, out: &mut [f64]) {
        (**self).increment(k, x_prev, x, out)
    }
    fn add_weighted_increments(
        &self,
        k: usize,
        x_prev: &[S],
        beta: &[f64],
        x: &S,
        scratch: &mut [f64],
        out: &mut [f64],
    ) {
        (**self).add_weighted_increments(k, x_prev, beta, x, scratch, out)
    }
}
