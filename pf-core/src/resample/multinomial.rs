//! Multinomial resampling in O(N): Poisson offspring counts, conditioned on their total.

use super::Resample;
use super::poisson::{
    DrawBuffers, NoBases, Rates, distinct_sorted, poisson_counts, round_mean, write_runs,
};
use crate::simd::{LaneRng, Simd};
use rand::Rng;
use std::cell::RefCell;

/// Multinomial resampling: `M` independent draws from the weights.
///
/// Drawing `M` independent uniforms and matching each with the cumulative weights needs
/// the uniforms in order; sorting them costs O(M log M). Instead each particle's number of
/// draws is drawn directly:
///
/// 1. **Poissonisation.** Particle `j` gets a Poisson(`μ·W_j`) count, independent across
///    particles (see `poisson_counts`). These are the counts, per particle, of a Poisson
///    process of rate `μ` on [0, 1) cut at the cumulative weights: given their total `T`,
///    they are the counts of `T` independent draws from the weights. `μ = M + 3√M + 1`, so
///    that `T` falls short of `M` with probability about 10⁻³; then further rounds add
///    counts (independent Poisson counts add up to Poisson counts).
/// 2. **Conditioning on `M`.** A uniformly chosen subset of `T − M` of the draws (about
///    `3√M`, from the caller's generator) is removed, which leaves `M` independent draws.
/// 3. **Ancestors.** Each particle's draws are written as one run of copies, so the
///    ancestors come out in increasing order.
///
/// The weights are normalised by their sum (so a sum off 1 by rounding changes nothing);
/// weights with no finite positive mass give every draw to the last particle, as the
/// cumulative-weight schemes do. The joint law of the offspring counts is tested by
/// chi-square over every outcome of a small case, and the Poisson counts on each of their
/// paths.
#[derive(Debug, Clone, Copy, Default)]
pub struct Multinomial;

impl Resample for Multinomial {
    fn resample<R: Rng + ?Sized>(&self, w: &[f64], rng: &mut R, ancestors: &mut [usize]) {
        multinomial_draws(Simd::Auto, w, 0, rng, ancestors);
    }
}

thread_local! {
    /// Scratch of [`multinomial_draws`], per thread.
    static SCRATCH: RefCell<DrawBuffers> = const { RefCell::new(DrawBuffers::new()) };
}

/// `out` ← `M = out.len()` independent draws from the weights `w` (normalised here), in
/// increasing order, in O(M + N): see [`Multinomial`]. Particle `j` is written as
/// `first + j`.
pub(crate) fn multinomial_draws<R: Rng + ?Sized>(
    simd: Simd,
    w: &[f64],
    first: usize,
    rng: &mut R,
    out: &mut [usize],
) {
    let (n, m) = (w.len(), out.len());
    if m == 0 || n == 0 {
        return;
    }
    let mut lanes = LaneRng::from_rng(rng);
    SCRATCH.with(|cell| {
        let DrawBuffers {
            counts,
            extra,
            removed,
            seen,
        } = &mut *cell.borrow_mut();
        // The first round assumes weights summing to 1 and measures their mass; it is redone,
        // normalised, when the mass is off by more than rounding.
        let mean = round_mean(m as f64);
        let first_round = poisson_counts(simd, counts, w, Rates::Scaled(mean), &mut lanes, rng);
        let (mut t, rates) = (first_round.total, first_round.rates);
        let mass = rates / mean;
        if !(mass > 0.0 && mass.is_finite()) {
            out.fill(first + n - 1);
            return;
        }
        if (mass - 1.0).abs() > 1e-6 {
            let s = mean / mass;
            t = poisson_counts(simd, counts, w, Rates::Scaled(s), &mut lanes, rng).total;
        }
        while t < m {
            let s = round_mean((m - t) as f64) / mass;
            t = t.saturating_add(
                poisson_counts(simd, extra, w, Rates::Scaled(s), &mut lanes, rng).total,
            );
            counts.add(extra);
        }
        distinct_sorted(t, t - m, rng, seen, removed);
        write_runs::<8>(simd, counts, removed, &NoBases, first, out);
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mc::stream_rng;
    use crate::testing::{binomial_pmf, chi2_quantile_999, multinomial_pmf, pearson_pooled};

    /// The joint law of the offspring counts of 3 particles from M = 4 draws is
    /// Multinomial(4; W): chi-square over all 15 outcomes from 60 000 seeded draws (the
    /// conditioning step acts in almost every one, since T ~ Poisson(11)). With 14 degrees
    /// of freedom, P(χ² > 36.1) = 0.001. The same weights scaled by 7 (a sum far from 1)
    /// give the same law: they are normalised.
    #[test]
    fn offspring_counts_are_jointly_multinomial() {
        let w = [0.5, 0.3, 0.2];
        let m = 4usize;
        let reps = 60_000;
        for (seed, scale) in [(11, 1.0), (13, 7.0)] {
            let scaled = w.map(|x| x * scale);
            let mut seen = std::collections::HashMap::new();
            let mut rng = stream_rng(seed, 0);
            let mut out = [0usize; 4];
            for _ in 0..reps {
                multinomial_draws(Simd::Auto, &scaled, 0, &mut rng, &mut out);
                assert!(out.windows(2).all(|p| p[0] <= p[1]), "in order: {out:?}");
                let mut k = [0usize; 3];
                for &a in &out {
                    k[a] += 1;
                }
                *seen.entry(k).or_insert(0usize) += 1;
            }
            let mut chi2 = 0.0;
            let mut outcomes = 0;
            for a in 0..=m {
                for b in 0..=m - a {
                    let c = m - a - b;
                    let e = multinomial_pmf(&[a, b, c], &w) * reps as f64;
                    let o = seen.get(&[a, b, c]).copied().unwrap_or(0) as f64;
                    chi2 += (o - e).powi(2) / e;
                    outcomes += 1;
                }
            }
            assert_eq!(outcomes, 15);
            assert_eq!(seen.values().sum::<usize>(), reps);
            assert!(chi2 < 36.1, "scale {scale}: chi-square {chi2}");
        }
    }

    /// Every kernel (AVX-512 where the CPU has it, AVX2, portable) gives the same
    /// ancestors, in order, on every path of the counts: skewed weights over several lane
    /// steps (groups that continue their terms), a dominant weight (a rate above 12), weights
    /// far from normalised, and `M` below and above `N`.
    #[test]
    fn every_kernel_draws_the_same_ancestors() {
        let skewed: Vec<f64> = (1..=300)
            .map(|i| (((i * 37) % 11) as f64 + 0.3).powi(4))
            .collect();
        let dominant = [0.01, 0.97, 0.02];
        let cases: [&[f64]; 3] = [&skewed, &dominant, &[3.0, 1.0, 2.0, 0.5]];
        for w in cases {
            for m in [1usize, 50, 300, 1000] {
                for seed in 0..3 {
                    let draw = |simd| {
                        let mut out = vec![0; m];
                        multinomial_draws(simd, w, 0, &mut stream_rng(seed, 1), &mut out);
                        out
                    };
                    let auto = draw(Simd::Auto);
                    assert_eq!(
                        auto,
                        draw(Simd::Avx2),
                        "N = {}, M = {m}, seed {seed}",
                        w.len()
                    );
                    assert_eq!(
                        auto,
                        draw(Simd::Portable),
                        "N = {}, M = {m}, seed {seed}",
                        w.len()
                    );
                    assert!(auto.windows(2).all(|p| p[0] <= p[1]));
                    assert!(auto.iter().all(|&a| a < w.len()));
                }
            }
        }
    }

    /// With one heavy particle (a rate above 12, drawn by `rand_distr`) and two light ones,
    /// each particle's count is Binomial(M, W_j): chi-square per particle over 20 000 draws.
    #[test]
    fn marginals_are_binomial_when_one_weight_dominates() {
        let w = [0.05, 0.9, 0.05];
        let m = 40usize;
        let mut hist = [[0usize; 41]; 3];
        let mut rng = stream_rng(12, 0);
        let mut out = vec![0usize; m];
        for _ in 0..20_000 {
            multinomial_draws(Simd::Auto, &w, 0, &mut rng, &mut out);
            let mut k = [0usize; 3];
            for &a in &out {
                k[a] += 1;
            }
            for (h, &kj) in hist.iter_mut().zip(&k) {
                h[kj] += 1;
            }
        }
        for (j, h) in hist.iter().enumerate() {
            let (stat, df) = pearson_pooled(h, |k| binomial_pmf(m, w[j], k));
            assert!(
                stat < chi2_quantile_999(df),
                "particle {j}: χ² {stat} on {df} df"
            );
        }
    }

    /// Weights with no mass give every draw to the last particle, as the cumulative-weight
    /// schemes do, and never hang.
    #[test]
    fn zero_weights_go_to_the_last_particle() {
        let mut out = vec![7usize; 10];
        multinomial_draws(Simd::Auto, &[0.0; 3], 0, &mut stream_rng(1, 0), &mut out);
        assert!(out.iter().all(|&a| a == 2));
    }
}
