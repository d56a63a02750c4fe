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
        sorted_draws(w.len(), |j| w[j], rng, ancestors);
    }
}

/// `out` ← `M = out.len()` independent draws from the weights `w(0), …, w(n − 1)` (summing
/// to 1 up to rounding), in increasing order, in O(M + n).
///
/// The sorted uniforms are `U_(i) = S_i / S_{M+1}` with `S_i = E_1 + … + E_i`,
/// `E_i ~ Exp(1)` (the spacings of uniform order statistics are exchangeable exponentials
/// over their sum), so no `exp` is needed per draw. `S_i` is kept in `out[i]` as its bit
/// pattern until the merge overwrites it with the draw: no scratch buffer. The merge with
/// the cumulative weights selects instead of branching, so a random interleaving costs no
/// mispredictions. Draws beyond the last cumulative weight go to the last index (the clamp).
pub(crate) fn sorted_draws<R: Rng + ?Sized>(
    n: usize,
    w: impl Fn(usize) -> f64,
    rng: &mut R,
    out: &mut [usize],
) {
    let m = out.len();
    if m == 0 || n == 0 {
        return;
    }
    if usize::BITS < 64 {
        // No room for an f64 in a usize: the exp-product generator and the plain merge.
        let mut cdf = InverseCdf::new(n, w);
        sorted_uniforms(m, rng, |i, u| out[i] = cdf.locate(u));
        return;
    }
    let mut s = 0.0_f64;
    for o in out.iter_mut() {
        let e: f64 = Exp1.sample(rng);
        s += e;
        *o = s.to_bits() as usize;
    }
    let e: f64 = Exp1.sample(rng);
    let total = s + e;
    let last = n - 1;
    let (mut i, mut j) = (0usize, 0usize);
    let mut c = w(0) * total;
    while i < m {
        let bits = out[i];
        let take = f64::from_bits(bits as u64) < c || j == last;
        out[i] = if take { j } else { bits };
        i += usize::from(take);
        let next = j + usize::from(!take);
        c += if take { 0.0 } else { w(next) * total };
        j = next;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mc::stream_rng;

    #[test]
    fn in_place_merge_equals_the_plain_merge_of_the_same_draws() {
        let w: Vec<f64> = {
            let raw: Vec<f64> = (1..=23).map(|i| ((i * 17) % 11) as f64 + 0.3).collect();
            let s: f64 = raw.iter().sum();
            raw.iter().map(|x| x / s).collect()
        };
        for &m in &[1usize, 5, 23, 200] {
            let mut fast = vec![0; m];
            sorted_draws(w.len(), |j| w[j], &mut stream_rng(9, m as u64), &mut fast);
            // The same exponentials, normalised, merged by the reference inverse CDF.
            let mut rng = stream_rng(9, m as u64);
            let e: Vec<f64> = (0..=m).map(|_| Exp1.sample(&mut rng)).collect();
            let total: f64 = e.iter().sum();
            let mut cdf = InverseCdf::new(w.len(), |j| w[j]);
            let mut s = 0.0;
            let plain: Vec<usize> = e[..m]
                .iter()
                .map(|x| {
                    s += x;
                    cdf.locate(s / total)
                })
                .collect();
            assert_eq!(fast, plain, "M = {m}");
            assert!(fast.windows(2).all(|p| p[0] <= p[1]), "sorted");
        }
    }
}
