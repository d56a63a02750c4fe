//! Stratified resampling: `u_i = (i + U_i)/M` with independent `U_i ~ U[0, 1)`.
//!
//! Instead of merging the `u_i` with the cumulative weights (a loop whose branch the CPU
//! mispredicts about half the time), each particle `j` computes how many `u_i` fall below
//! its cumulative weight `C_j` directly: with `x = M·C_j` and `f = ⌊x⌋`, every stratum
//! below `f` counts and stratum `f` counts when `U_f < x − f`. That needs random access to
//! `U_f`, so the `U_i` come from a counter-based stream: SplitMix64's output function applied
//! to `key + (i + 1)·γ`, with one fresh 64-bit `key` from the caller's generator per call.
//! This changes which uniforms are drawn, not the algorithm: the ancestors are exactly those
//! of the merge given the same `U_i` and the same cumulative weights (tested). The counts
//! are computed 64 particles at a time in a vectorised loop and written as runs of copies
//! (see [`offspring`](super::offspring)).

use super::Resample;
use super::offspring::walk_weights;
use crate::simd::Simd;
use crate::simd::math::floor_index;
use rand::Rng;

/// Stratified resampling (Kitagawa 1996).
#[derive(Debug, Clone, Copy, Default)]
pub struct Stratified;

/// SplitMix64's increment, the golden ratio in 64 bits.
const GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// `U_i` of the stream `key`: SplitMix64's output for counter `i`, as a double in [0, 1).
#[inline(always)]
fn stratum_uniform(key: u64, i: usize) -> f64 {
    let mut z = key.wrapping_add((i as u64).wrapping_add(1).wrapping_mul(GAMMA));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    // The top 53 bits as an exact multiple of 2⁻⁵³ (through the exponent trick, which
    // vectorises, rather than an integer-to-float conversion, which AVX2 lacks).
    f64::from_bits((z >> 11 >> 1) | 0x3ff0_0000_0000_0000) - 1.0
        + if z & (1 << 11) != 0 {
            1.0 / (1u64 << 53) as f64
        } else {
            0.0
        }
}

impl Resample for Stratified {
    fn resample<R: Rng + ?Sized>(&self, w: &[f64], rng: &mut R, ancestors: &mut [usize]) {
        let key = rng.next_u64();
        stratified_from_key(Simd::Auto, w, key, ancestors);
    }
}

/// Stratified resampling with the uniforms `U_i = stratum_uniform(key, i)`.
fn stratified_from_key(simd: Simd, w: &[f64], key: u64, ancestors: &mut [usize]) {
    let m = ancestors.len();
    let mf = m as f64;
    walk_weights(
        simd,
        w,
        |_, c, k| {
            for (k, &c) in k.iter_mut().zip(c) {
                let x = mf * c;
                let (f, ff) = floor_index(x);
                let below = stratum_uniform(key, f) < x - ff;
                *k = if f >= m { m } else { f + usize::from(below) };
            }
        },
        ancestors,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::resample::offspring::cumulative;

    #[test]
    fn counting_equals_the_merge_with_the_same_uniforms() {
        let w: Vec<f64> = {
            let raw: Vec<f64> = (1..=141).map(|i| ((i * 29) % 13) as f64 + 0.25).collect();
            let s: f64 = raw.iter().sum();
            raw.iter().map(|x| x / s).collect()
        };
        let c = cumulative(&w);
        for &m in &[1usize, 7, 41, 100, 141, 1000] {
            for key in [0u64, 1, 0xDEAD_BEEF, u64::MAX] {
                // Stratum i's point lies below C_j when i < ⌊M·C_j⌋, or i = ⌊M·C_j⌋ and
                // U_i < M·C_j − i: the merge over those comparisons.
                let mut j = 0;
                let merge: Vec<usize> = (0..m)
                    .map(|i| {
                        let below = |j: usize| {
                            let x = m as f64 * c[j];
                            let f = x.floor();
                            (i as f64) < f || ((i as f64) == f && stratum_uniform(key, i) < x - f)
                        };
                        while j + 1 < w.len() && !below(j) {
                            j += 1;
                        }
                        j
                    })
                    .collect();
                for simd in [Simd::Auto, Simd::Portable] {
                    let mut fast = vec![0; m];
                    stratified_from_key(simd, &w, key, &mut fast);
                    assert_eq!(fast, merge, "M = {m}, key = {key}, {simd:?}");
                }
            }
        }
    }

    #[test]
    fn stratum_uniforms_are_uniform() {
        // 10 equal bins over 10⁵ draws: chi-square with 9 degrees of freedom, P(> 27.9) = 0.001.
        let n = 100_000;
        let mut bins = [0usize; 10];
        for i in 0..n {
            let u = stratum_uniform(42, i);
            assert!((0.0..1.0).contains(&u));
            bins[(u * 10.0) as usize] += 1;
        }
        let e = n as f64 / 10.0;
        let chi2: f64 = bins.iter().map(|&b| (b as f64 - e).powi(2) / e).sum();
        assert!(chi2 < 27.9, "chi-square {chi2}");
    }

    /// The exponent-trick conversion is the plain `(z >> 11)·2⁻⁵³`.
    #[test]
    fn stratum_uniform_is_the_top_53_bits() {
        for i in 0..1000 {
            let mut z = 7u64.wrapping_add((i as u64 + 1).wrapping_mul(GAMMA));
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            let want = (z >> 11) as f64 / (1u64 << 53) as f64;
            assert_eq!(stratum_uniform(7, i), want);
        }
    }
}
