//! Stratified resampling: `u_i = (i + U_i)/M` with independent `U_i ~ U[0, 1)`.
//!
//! Instead of merging the `u_i` with the cumulative weights (a loop whose branch the CPU
//! mispredicts about half the time), each particle `j` computes how many `u_i` fall below
//! its cumulative weight `C_j` directly: with `x = M·C_j` and `f = ⌊x⌋`, every stratum
//! below `f` counts and stratum `f` counts when `U_f < x − f`. The counts are computed 64
//! particles at a time and written as runs of copies (see [`offspring`](super::offspring)).
//!
//! ## Where the uniforms come from
//!
//! `U_f` is the `f`-th output of a SplitMix64 stream keyed by one draw of the caller's
//! generator ([`stratum_uniform`]): a function of the stratum alone, so every particle whose
//! boundary falls in stratum `f` finds the same `U_f` with no look at its neighbours, and
//! the batch filter's chunks, each walking its own ancestors, find it too. The law is
//! exactly stratified resampling (tested by chi-square over every outcome of a small case),
//! and the ancestors are exactly those of the merge given the same `U_f` and the same
//! cumulative weights (tested).
//!
//! The hash costs two 64-bit multiplies per particle, which AVX2 emulates in three 32-bit
//! steps each; on a CPU with AVX-512 a twin ([`stratified_avx512`](super::stratified_avx512))
//! makes them one instruction. The hash on the twin is 1.33× as fast as the draw of each
//! stratum's first particle from a lane stream passed down the block by a chain of selects
//! (on AVX2 the hash is 6 % slower than that).

use super::Resample;
use super::offspring::walk_weights;
use crate::mc::{GAMMA, splitmix};
use crate::simd::Simd;
use crate::simd::avx512::Avx512;
use crate::simd::math::{floor_index, index_in, unit_from_bits};
use rand::Rng;

/// Stratified resampling (Kitagawa 1996).
#[derive(Debug, Clone, Copy, Default)]
pub struct Stratified;

impl Resample for Stratified {
    fn resample<R: Rng + ?Sized>(&self, w: &[f64], rng: &mut R, ancestors: &mut [usize]) {
        stratified_with_key(Simd::Auto, w, rng.next_u64(), ancestors);
    }
}

/// Stratified resampling with the uniforms [`stratum_uniform`]`(key, ·)`.
fn stratified_with_key(simd: Simd, w: &[f64], key: u64, ancestors: &mut [usize]) {
    let mf = ancestors.len() as f64;
    let cpu = Avx512::get(simd);
    walk_weights(
        simd,
        w,
        #[inline(always)]
        |c, k| {
            let done = cpu.map_or(0, |cpu| {
                super::stratified_avx512::boundaries(cpu, c, key, mf, k)
            });
            for (k, &c) in k[done..].iter_mut().zip(&c[done..]) {
                *k = stratified_index_in(mf * c, key, 0.0, mf);
            }
        },
        ancestors,
    );
}

/// `U_f = ⌊s_f/2¹²⌋·2⁻⁵²`, `s_f` the `f`-th output of the SplitMix64 stream seeded with `key`
/// (`splitmix(key + (f + 1)·γ)`): the uniform of stratum `f` where the strata must be drawn
/// in any order, by index (the batch filter's chunks, each walking its own ancestors).
#[inline(always)]
pub(crate) fn stratum_uniform(key: u64, f: u64) -> f64 {
    unit_from_bits(splitmix(
        key.wrapping_add(f.wrapping_add(1).wrapping_mul(GAMMA)),
    ))
}

/// The boundary of a particle whose scaled cumulative weight is `x = M·C_j` (`0 ≤ x < 2⁵¹`)
/// under stratified resampling with the uniforms [`stratum_uniform`]`(key, ·)`: with
/// `f = ⌊x⌋`, `f + [U_f < x − f]`, clamped to `[lo, hi]` and less `lo` (as
/// [`ceil_index_in`](crate::simd::math::ceil_index_in) does for systematic resampling).
/// Vectorisable: AVX2 multiplies 64-bit lanes in three 32-bit steps.
#[inline(always)]
pub(crate) fn stratified_index_in(x: f64, key: u64, lo: f64, hi: f64) -> usize {
    let (f, ff) = floor_index(x);
    let k = if stratum_uniform(key, f as u64) < x - ff {
        ff + 1.0
    } else {
        ff
    };
    index_in(k, lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mc::stream_rng;
    use crate::resample::offspring::cumulative;
    use crate::testing::chi2_quantile_999;
    use std::collections::HashMap;

    /// The strata's uniforms by index are uniform and uncorrelated from one stratum to the
    /// next: over 10⁵ strata, a chi-square over 64 equal bins and the lag-one correlation
    /// within five standard errors of 0, for two keys.
    #[test]
    fn stratum_uniforms_are_uniform_and_uncorrelated() {
        let n = 100_000;
        for key in [0u64, 0xdead_beef] {
            let u: Vec<f64> = (0..n as u64).map(|f| stratum_uniform(key, f)).collect();
            let mut bins = [0usize; 64];
            for &x in &u {
                assert!((0.0..1.0).contains(&x));
                bins[(x * 64.0) as usize] += 1;
            }
            let e = n as f64 / 64.0;
            let chi2: f64 = bins.iter().map(|&o| (o as f64 - e).powi(2) / e).sum();
            assert!(
                chi2 < chi2_quantile_999(63),
                "key {key}: χ² {chi2} on 63 df"
            );
            // Correlation of centred neighbours; its standard error is 1/√n.
            let r = u
                .windows(2)
                .map(|p| (p[0] - 0.5) * (p[1] - 0.5))
                .sum::<f64>()
                / ((n - 1) as f64 / 12.0);
            assert!(
                r.abs() < 5.0 / (n as f64).sqrt(),
                "key {key}: lag-one r = {r}"
            );
        }
    }

    /// The ancestors are those of the textbook merge of the points `(i + U_i)/M` with the
    /// same cumulative weights and `U_i = stratum_uniform(key, i)`, on every kernel (the
    /// AVX-512 twin's groups of eight and the rest after them).
    #[test]
    fn counting_equals_the_merge_with_the_same_uniforms() {
        for n in [141usize, 300] {
            let w: Vec<f64> = {
                let raw: Vec<f64> = (1..=n)
                    .map(|i| (((i * 29) % 13) as f64 + 0.25).powi(3))
                    .collect();
                let s: f64 = raw.iter().sum();
                raw.iter().map(|x| x / s).collect()
            };
            let c = cumulative(&w);
            for &m in &[1usize, 7, 41, 100, 141, 1000] {
                for key in [0u64, 7, u64::MAX] {
                    // Stratum i's point lies below C_j when i < ⌊M·C_j⌋, or i = ⌊M·C_j⌋
                    // and U_i < M·C_j − i.
                    let mut j = 0;
                    let merge: Vec<usize> = (0..m)
                        .map(|i| {
                            let below = |j: usize| {
                                let x = m as f64 * c[j];
                                let f = x.floor();
                                (i as f64) < f
                                    || ((i as f64) == f && stratum_uniform(key, i as u64) < x - f)
                            };
                            while j + 1 < n && !below(j) {
                                j += 1;
                            }
                            j
                        })
                        .collect();
                    for simd in [Simd::Auto, Simd::Avx2, Simd::Portable] {
                        let mut fast = vec![0; m];
                        stratified_with_key(simd, &w, key, &mut fast);
                        assert_eq!(fast, merge, "N = {n}, M = {m}, key {key}, {simd:?}");
                    }
                }
            }
        }
    }

    /// The AVX-512 twin's boundaries are the portable function's, bit for bit, on
    /// cumulative weights inside [0, 1] and far outside it: negative, NaN, infinite, and
    /// beyond `2⁵¹/M`, where the boundaries are garbage but the same garbage.
    #[test]
    fn the_twin_gives_the_portable_boundaries() {
        let Some(cpu) = Avx512::for_test() else {
            return;
        };
        let mut rng = crate::mc::stream_rng(43, 0);
        let specials = [
            -0.0,
            -1.0,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            1e300,
            3e15,
        ];
        for (case, mf) in [1.0, 7.0, 1000.0, 1e6].into_iter().enumerate() {
            let c: Vec<f64> = (0..203)
                .map(|j| match j % 9 {
                    0 => specials[(j / 9) % specials.len()],
                    1 => (j as f64 / mf).next_down(),
                    2 => j as f64 / mf,
                    _ => rand::RngExt::random::<f64>(&mut rng),
                })
                .collect();
            let key = case as u64 * 0x1234_5678_9abc_def1;
            let mut got = vec![usize::MAX; c.len()];
            let done = super::super::stratified_avx512::boundaries(cpu, &c, key, mf, &mut got);
            assert_eq!(done, 200);
            for (j, (&g, &c)) in got[..done].iter().zip(&c).enumerate() {
                let want = stratified_index_in(mf * c, key, 0.0, mf);
                assert_eq!(g, want, "M = {mf}, particle {j}, C = {c}");
            }
        }
    }

    /// The law of the ancestors is stratified resampling's: independent strata, stratum
    /// `i`'s ancestor `j` with probability `M·|[i/M, (i+1)/M) ∩ [C_{j−1}, C_j)|`. With
    /// `W = (0.05, 0.1, 0.05, 0.5, 0.3)` and `M = 4`, three boundaries share stratum 0 (so
    /// they must share its `U`) and the ancestors have eight outcomes: chi-square over
    /// 40 000 seeded calls.
    #[test]
    fn ancestors_follow_the_stratified_law() {
        let w = [0.05, 0.1, 0.05, 0.5, 0.3];
        let m = 4;
        let c: [f64; 5] = [0.05, 0.15, 0.2, 0.7, 1.0];
        // P(stratum i's ancestor is j).
        let p = |i: usize, j: usize| {
            let (lo, hi) = (i as f64 / m as f64, (i + 1) as f64 / m as f64);
            let (cl, ch) = (if j == 0 { 0.0 } else { c[j - 1] }, c[j]);
            m as f64 * (ch.min(hi) - cl.max(lo)).max(0.0)
        };
        let reps = 40_000;
        let mut seen: HashMap<Vec<usize>, usize> = HashMap::new();
        let mut rng = stream_rng(21, 0);
        let mut out = vec![0usize; m];
        for _ in 0..reps {
            Stratified.resample(&w, &mut rng, &mut out);
            *seen.entry(out.clone()).or_default() += 1;
        }
        let mut chi2 = 0.0;
        let mut outcomes = 0;
        for a0 in 0..5 {
            for a2 in 0..5 {
                let a = vec![a0, 3, a2, 4];
                let e = (0..m).map(|i| p(i, a[i])).product::<f64>() * reps as f64;
                let o = seen.get(&a).copied().unwrap_or(0) as f64;
                if e > 0.0 {
                    chi2 += (o - e).powi(2) / e;
                    outcomes += 1;
                } else {
                    assert_eq!(o, 0.0, "impossible outcome {a:?} drawn");
                }
            }
        }
        assert_eq!(outcomes, 8);
        assert_eq!(
            seen.values().sum::<usize>(),
            reps,
            "outcomes outside the support"
        );
        let stat_bound = chi2_quantile_999(outcomes - 1);
        assert!(chi2 < stat_bound, "chi-square {chi2} on 7 df");
    }
}
