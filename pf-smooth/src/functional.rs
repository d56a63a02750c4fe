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
}
