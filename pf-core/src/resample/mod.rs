//! Resampling schemes. Each is O(N) and fills an ancestor buffer the caller owns.
//!
//! None of them merges its points with the cumulative weights in a branchy loop: each
//! counts every particle's offspring directly (its *boundary*, the number of points below
//! its cumulative weight, clamped to `M` for the last particle) and writes its ancestors as
//! runs of copies, with the arithmetic vectorised and compiled for AVX2 where the CPU has
//! it (`crate::simd`; the numbers are the same either way). For systematic and stratified
//! resampling the ancestors are exactly those of the inverse-CDF merge ([`InverseCdf`],
//! kept as the reference and for callers who need one query at a time) on the same points
//! and the same cumulative weights (tested); multinomial and residual resampling draw each
//! particle's count without placing points, and their laws are tested by chi-square.
//! The cumulative weights are summed four at a time, so they may differ from a
//! left-to-right sum by a few ulp.
//!
//! All schemes are unbiased: the expected number of offspring of particle `j` is `M·W_j`.
//! Systematic and residual resampling also keep every count within `⌊M·W_j⌋ … ⌈M·W_j⌉`
//! (residual: at least the floor), which is why they add less noise (Douc, Cappé &
//! Moulines 2005).
//!
//! ## References
//! R. Douc, O. Cappé, E. Moulines, "Comparison of resampling schemes for particle
//! filtering", ISPA 2005.

mod chunked;
mod counts;
mod multinomial;
mod offspring;
mod poisson;
mod residual;
mod stratified;
mod stratified_avx512;
mod systematic;

pub use multinomial::Multinomial;
pub use residual::Residual;
pub use stratified::Stratified;
pub use systematic::Systematic;

pub(crate) use chunked::{BLOCK, BlockPlan, Blocked, ChunkSplit, ChunkedWeights, chunks_per_block};
pub(crate) use offspring::{SCAN, prefix4_each};
pub(crate) use stratified::stratified_index_in;
#[cfg(test)]
pub(crate) use stratified::stratum_uniform;

use rand::Rng;
use serde::{Deserialize, Serialize};

/// A resampling scheme: draws ancestor indices from normalised weights.
pub trait Resample: Sync {
    /// Fill `ancestors` (length `M`, any `M ≥ 1`) with indices into `w` (normalised, length
    /// `N ≥ 1`), drawn so that particle `j` gets `M·W_j` offspring on average.
    fn resample<R: Rng + ?Sized>(&self, w: &[f64], rng: &mut R, ancestors: &mut [usize]);
}

/// The four schemes as one serialisable choice, for configs and the CLI.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Resampler {
    /// Independent draws (Poisson counts per particle, conditioned on their total, O(N)).
    Multinomial,
    /// One uniform shared by all strata.
    #[default]
    Systematic,
    /// One uniform per stratum.
    Stratified,
    /// Deterministic `⌊M·W⌋` copies, multinomial on the residuals.
    Residual,
}

impl Resampler {
    /// Every scheme, for sweeps and tests.
    pub const ALL: [Resampler; 4] = [
        Resampler::Multinomial,
        Resampler::Systematic,
        Resampler::Stratified,
        Resampler::Residual,
    ];

    /// The lower-case name used in configs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Resampler::Multinomial => "multinomial",
            Resampler::Systematic => "systematic",
            Resampler::Stratified => "stratified",
            Resampler::Residual => "residual",
        }
    }
}

impl std::str::FromStr for Resampler {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        crate::names::parse_name("resampler", &Resampler::ALL, Resampler::name, s)
    }
}

impl std::fmt::Display for Resampler {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Resample for Resampler {
    fn resample<R: Rng + ?Sized>(&self, w: &[f64], rng: &mut R, ancestors: &mut [usize]) {
        match self {
            Resampler::Multinomial => Multinomial.resample(w, rng, ancestors),
            Resampler::Systematic => Systematic.resample(w, rng, ancestors),
            Resampler::Stratified => Stratified.resample(w, rng, ancestors),
            Resampler::Residual => Residual.resample(w, rng, ancestors),
        }
    }
}

/// The inverse of the empirical CDF of weights, queried with non-decreasing `u`.
///
/// A monotone merge: O(N + M) over a whole pass. The index is clamped to `N − 1`, so a
/// cumulative sum that falls short of 1 by rounding can never run past the end.
pub struct InverseCdf<W> {
    w: W,
    n: usize,
    j: usize,
    c: f64,
}

impl<W: Fn(usize) -> f64> InverseCdf<W> {
    /// Over `n` weights given by `w(j)` (not necessarily a slice, so residual weights need
    /// no buffer).
    pub fn new(n: usize, w: W) -> Self {
        let c = w(0);
        InverseCdf { w, n, j: 0, c }
    }

    /// The smallest `j` with `u < C_j`, clamped to `N − 1`. `u` must not decrease between calls.
    #[inline]
    pub fn locate(&mut self, u: f64) -> usize {
        while u >= self.c && self.j + 1 < self.n {
            self.j += 1;
            self.c += (self.w)(self.j);
        }
        self.j
    }
}

/// Offspring counts of each particle from an ancestor vector (for tests and diagnostics).
pub fn offspring_counts(ancestors: &[usize], n: usize) -> Vec<usize> {
    let mut counts = vec![0; n];
    for &a in ancestors {
        counts[a] += 1;
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    fn skewed_weights(n: usize) -> Vec<f64> {
        let raw: Vec<f64> = (0..n).map(|i| ((i * 7919) % 13) as f64 + 0.1).collect();
        let s: f64 = raw.iter().sum();
        raw.iter().map(|x| x / s).collect()
    }

    /// Mean offspring counts over many draws match M·W_j. Each count is a sum of bounded
    /// draws; its standard error is at most sqrt(M·W_j / reps) (the multinomial variance
    /// M·W(1−W) bounds every scheme here), so 5 standard errors is a bound that a correct
    /// scheme crosses with probability < 1e-5 per particle.
    #[test]
    fn every_scheme_is_unbiased() {
        let n = 20;
        let m = 30; // M ≠ N exercises the general case.
        let w = skewed_weights(n);
        let reps = 20_000;
        for scheme in Resampler::ALL {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
            let mut sum = vec![0.0; n];
            let mut a = vec![0; m];
            for _ in 0..reps {
                scheme.resample(&w, &mut rng, &mut a);
                for (s, c) in sum.iter_mut().zip(offspring_counts(&a, n)) {
                    *s += c as f64;
                }
            }
            for j in 0..n {
                let mean = sum[j] / reps as f64;
                let expected = m as f64 * w[j];
                let se = (expected * (1.0 - w[j]) / reps as f64).sqrt();
                assert!(
                    (mean - expected).abs() < 5.0 * se + 1e-12,
                    "{scheme}: particle {j}: mean {mean}, expected {expected}, se {se}"
                );
            }
        }
    }

    #[test]
    fn systematic_and_residual_counts_stay_within_floor_and_ceil() {
        let n = 50;
        let w = skewed_weights(n);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        let mut a = vec![0; n];
        for _ in 0..2000 {
            for scheme in [Resampler::Systematic, Resampler::Residual] {
                scheme.resample(&w, &mut rng, &mut a);
                for (j, c) in offspring_counts(&a, n).into_iter().enumerate() {
                    let nw = n as f64 * w[j];
                    // One ulp of slack on the product, nothing more.
                    assert!(c as f64 >= (nw * (1.0 - 1e-12)).floor(), "{scheme} {j}");
                    if scheme == Resampler::Systematic {
                        assert!(c as f64 <= (nw * (1.0 + 1e-12)).ceil(), "{scheme} {j}");
                    }
                }
            }
        }
    }

    #[test]
    fn ancestors_are_in_range_even_when_weights_sum_short_of_one() {
        // Weights summing to 1 − 1e-9: the clamp must keep every index < N.
        let n = 10;
        let w = vec![(1.0 - 1e-9) / n as f64; n];
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
        let mut a = vec![0; 1000];
        for scheme in Resampler::ALL {
            for _ in 0..100 {
                scheme.resample(&w, &mut rng, &mut a);
                assert!(a.iter().all(|&i| i < n), "{scheme}");
            }
        }
    }

    /// Weights outside the contract (NaN, infinite, huge, negative, all zero) give ancestors in
    /// range from every scheme, with no panic (the filters reject such weights before they
    /// get here; a direct caller gets indices, not a crash).
    #[test]
    fn bad_weights_never_panic_and_stay_in_range() {
        let cases: [&[f64]; 7] = [
            &[0.2, f64::NAN, 0.3, f64::NAN, 0.5],
            &[0.2, f64::INFINITY, 0.3],
            &[0.6, -0.5, 0.9, -1e300],
            &[0.0, 0.0, 0.0],
            &[1e300, 1e300, 1.0],
            &[f64::MAX, 0.5, f64::MAX],
            &[1e17, 1e17, 1e17],
        ];
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(8);
        for w in cases {
            for m in [1usize, 7, 100] {
                for scheme in Resampler::ALL {
                    // Every output written (none left at the marker), each in range.
                    let mut a = vec![usize::MAX; m];
                    scheme.resample(w, &mut rng, &mut a);
                    assert!(a.iter().all(|&i| i < w.len()), "{scheme} {w:?}");
                }
            }
        }
    }

    #[test]
    fn a_point_mass_is_copied_everywhere() {
        let w = [0.0, 0.0, 1.0, 0.0];
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(9);
        let mut a = vec![0; 7];
        for scheme in Resampler::ALL {
            scheme.resample(&w, &mut rng, &mut a);
            assert!(a.iter().all(|&i| i == 2), "{scheme}: {a:?}");
        }
    }

    #[test]
    fn names_round_trip() {
        for scheme in Resampler::ALL {
            assert_eq!(scheme.name().parse::<Resampler>(), Ok(scheme));
        }
        assert!("bogus".parse::<Resampler>().is_err());
    }
}
