//! Multinomial resampling in O(N) through sorted uniforms generated in order.

use super::{InverseCdf, Resample};
use rand::Rng;
use rand_distr::{Distribution, Exp1};

/// Multinomial resampling: `M` independent draws from the weights.
///
/// The draws are produced already sorted, so the inverse CDF is one linear merge, not
/// O(N log N). The `i`-th smallest of `M` uniforms is `1 − s_i` with
/// `s_i = s_{i−1} · exp(−E_i / (M − i))`, `E_i ~ Exp(1)`: the minimum of the `M − i`
/// uniforms left above the last one.
#[derive(Debug, Clone, Copy, Default)]
pub struct Multinomial;

impl Resample for Multinomial {
    fn resample<R: Rng + ?Sized>(&self, w: &[f64], rng: &mut R, ancestors: &mut [usize]) {
        let m = ancestors.len();
        let mut cdf = InverseCdf::new(w.len(), |j| w[j]);
        sorted_uniforms(m, rng, |i, u| ancestors[i] = cdf.locate(u));
    }
}

/// Call `f(i, u_(i))` with the order statistics `u_(0) ≤ … ≤ u_(m−1)` of `m` uniforms.
pub(crate) fn sorted_uniforms<R: Rng + ?Sized>(
    m: usize,
    rng: &mut R,
    mut f: impl FnMut(usize, f64),
) {
    let mut s = 1.0_f64;
    for i in 0..m {
        let e: f64 = Exp1.sample(rng);
        s *= (-e / (m - i) as f64).exp();
        f(i, 1.0 - s);
    }
}
