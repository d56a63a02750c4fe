//! Multinomial resampling in O(N) through sorted uniforms generated in order.

use super::Resample;
use super::offspring::{SCAN, prefix4, walk};
use crate::simd::math::floor_index;
use crate::simd::{LaneRng, Simd, dispatch};
use rand::Rng;
use std::cell::RefCell;

/// Multinomial resampling: `M` independent draws from the weights.
///
/// The draws are produced already sorted, so matching them to particles is linear, not
/// O(N log N): the `M` sorted uniforms are `U_(i) = S_i / S_M` with `S_i = E_0 + … + E_i`
/// and `E_0, …, E_M` independent unit exponentials (the spacings of uniform order statistics
/// are exchangeable exponentials over their sum; Devroye 1986, §V.2). The exponentials come
/// from a [`LaneRng`] seeded from the caller's generator (vectorised ziggurat).
///
/// Each particle's offspring count is then found without a branchy merge, through a grid of
/// `M` buckets: a table gives, for each bucket, how many points lie below it, and a
/// particle only compares its cumulative weight with the points of its own bucket (one on
/// average; four at a time). The ancestors are exactly those of the textbook merge of the
/// same sorted points with the same cumulative weights (tested).
#[derive(Debug, Clone, Copy, Default)]
pub struct Multinomial;

impl Resample for Multinomial {
    fn resample<R: Rng + ?Sized>(&self, w: &[f64], rng: &mut R, ancestors: &mut [usize]) {
        sorted_draws(Simd::Auto, w.len(), |j| w[j], rng, ancestors);
    }
}

/// Points below which the bucket search stops comparing: `+∞` past the last point.
const PAD: usize = 4;

thread_local! {
    /// Scratch of [`sorted_draws`]: the partial sums `S_i` and the bucket table, reused
    /// from call to call on each thread (no allocation once grown; contents never carry
    /// over: every call overwrites what it reads).
    static SCRATCH: RefCell<(Vec<f64>, Vec<usize>)> = const { RefCell::new((Vec::new(), Vec::new())) };
}

/// `out` ← `M = out.len()` independent draws from the weights `w(0), …, w(n − 1)` (summing
/// to 1 up to rounding), in increasing order, in O(M + n).
///
/// 1. `S_0 … S_M`: unit exponentials from a [`LaneRng`] seeded by `rng`, summed ([`prefix4`]).
/// 2. The bucket of a value `v ∈ [0, S_M]` is `b(v) = ⌊v·M/S_M⌋` (capped at `M`);
///    `first[b] = #{i < M : b(S_i) < b}` for `b = 0 … M`, from a histogram of the points'
///    buckets and its prefix sums.
/// 3. Particle `j`'s boundary, the number of points below `key_j = C_j·S_M`, is
///    `first[b(key_j)]` plus the points of that bucket below `key_j` (since `b` is
///    monotone, points in lower buckets are below and points in higher buckets are not).
///    Its ancestors are then written as runs (see [`offspring`](super::offspring)).
pub(crate) fn sorted_draws<R: Rng + ?Sized>(
    simd: Simd,
    n: usize,
    w: impl Fn(usize) -> f64,
    rng: &mut R,
    out: &mut [usize],
) {
    let m = out.len();
    if m == 0 || n == 0 {
        return;
    }
    let mut lanes = LaneRng::from_rng(rng);
    SCRATCH.with(|cell| {
        let mut guard = cell.borrow_mut();
        let (s, first) = &mut *guard;
        s.resize(m + 1 + PAD, 0.0);
        first.resize(m + 2, 0);
        dispatch(
            simd,
            #[inline(always)]
            || {
                let total = spacings(&mut lanes, &mut s[..m + 1]);
                s[m + 1..].fill(f64::INFINITY);
                let g = m as f64 / total;
                let bucket = |v: f64| floor_index(v * g).0.min(m);
                // first[b]: a histogram of the points' buckets (shifted by one), then its
                // prefix sums. The buckets are computed SCAN at a time (vectorised).
                first.fill(0);
                let mut kb = [0usize; SCAN];
                for block in s[..m].chunks(SCAN) {
                    for (k, &v) in kb.iter_mut().zip(block) {
                        *k = bucket(v) + 1;
                    }
                    for &k in &kb[..block.len()] {
                        first[k] += 1;
                    }
                }
                let mut acc = 0;
                for f in first.iter_mut() {
                    acc += *f;
                    *f = acc;
                }
                let (s, first) = (&s[..], &first[..]);
                walk(
                    n,
                    w,
                    |_, c, k| {
                        for (k, &c) in k.iter_mut().zip(c) {
                            let key = c * total;
                            let mut i = first[bucket(key)];
                            loop {
                                let p: &[f64; PAD] = s[i..i + PAD].try_into().expect("PAD points");
                                let below = usize::from(p[0] < key)
                                    + usize::from(p[1] < key)
                                    + usize::from(p[2] < key)
                                    + usize::from(p[3] < key);
                                i += below;
                                if below < PAD {
                                    break;
                                }
                            }
                            *k = i;
                        }
                    },
                    out,
                );
            },
        );
    });
}

/// `s[i] ← E_0 + … + E_i` for unit exponentials `E_i`; returns the last sum.
#[inline(always)]
fn spacings(lanes: &mut LaneRng, s: &mut [f64]) -> f64 {
    lanes.fill_exp1_inline(s);
    let mut carry = 0.0;
    let mut e = [0.0f64; SCAN];
    for block in s.chunks_mut(SCAN) {
        let e = &mut e[..block.len()];
        e.copy_from_slice(block);
        carry = prefix4(e, carry, block);
    }
    carry
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mc::stream_rng;
    use crate::resample::offspring::cumulative;

    /// The bucket search gives the ancestors of the plain merge of the same sorted points
    /// with the same cumulative weights, on both kernels, for M below, at and above N.
    #[test]
    fn bucket_search_equals_the_plain_merge_of_the_same_draws() {
        for (n, skew) in [(23usize, 1), (300, 4), (1, 1)] {
            let w: Vec<f64> = {
                let raw: Vec<f64> = (1..=n)
                    .map(|i| (((i * 17) % 11) as f64 + 0.3).powi(skew))
                    .collect();
                let s: f64 = raw.iter().sum();
                raw.iter().map(|x| x / s).collect()
            };
            let c = cumulative(&w);
            for &m in &[1usize, 5, 23, 200, 301, 1000] {
                // The same exponentials, summed the same way, merged plainly.
                let mut lanes = LaneRng::from_rng(&mut stream_rng(9, m as u64));
                let mut s = vec![0.0; m + 1];
                let total = spacings(&mut lanes, &mut s);
                let mut j = 0;
                let plain: Vec<usize> = s[..m]
                    .iter()
                    .map(|&si| {
                        // First j whose key C_j·S_M exceeds the point.
                        while j + 1 < n && si >= c[j] * total {
                            j += 1;
                        }
                        j
                    })
                    .collect();
                for simd in [Simd::Auto, Simd::Portable] {
                    let mut fast = vec![0; m];
                    sorted_draws(simd, n, |j| w[j], &mut stream_rng(9, m as u64), &mut fast);
                    assert_eq!(fast, plain, "N = {n}, M = {m}, {simd:?}");
                }
            }
        }
    }
}
