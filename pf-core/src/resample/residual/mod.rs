//! Residual resampling: deterministic copies, then multinomial on what is left, drawn per
//! particle from Poisson counts.

mod floors_avx512;

use super::Resample;
use super::counts::Counts;
use super::offspring::SCAN;
use super::poisson::{
    DrawBuffers, Floors, OVERSHOOT, Rates, distinct_sorted, poisson_counts, round_mean, write_runs,
};
use crate::simd::avx512::Avx512;
use crate::simd::math::floor_index;
use crate::simd::{LaneRng, Simd, dispatch};
use rand::Rng;
use rand_distr::{Distribution, Poisson};
use std::cell::RefCell;

/// Residual resampling (Liu & Chen 1998): particle `j` gets `⌊M·W_j⌋` copies plus its share
/// of `R = M − Σ⌊M·W_j⌋` multinomial draws from the residual weights `r_j/R`, where
/// `r_j = M·W_j − ⌊M·W_j⌋`.
///
/// Every `r_j` is below 1, so the `R` draws can be made per particle in O(N), with no
/// points to place or search:
///
/// 1. **Poissonisation.** Particle `j` gets a Poisson(`Λ·r_j`) count, independent across
///    particles. `Λ·R = R + 3√R + 1`, so that the total `T`, Poisson(`Λ·R`), falls short of
///    `R` with probability about 10⁻³; then further rounds add counts (independent Poisson
///    counts add up to Poisson counts). The first round's `Λ` is planned from a sample of
///    the weights, so that its pass also sums the floors (see `first_rate`): any `Λ` gives
///    the same law.
/// 2. **Conditioning on `R`.** Given `T`, the counted draws are `T` independent draws from
///    `r/R`; a uniformly chosen subset of `T − R` of them (about `3√R`, from the caller's
///    generator) is removed, which leaves `R` independent draws.
/// 3. **Ancestors.** Each particle's copies and kept draws are written as one run, so the
///    ancestors come out in increasing order.
///
/// The counts are the inversion of multinomial resampling's (`poisson_counts`, one lane
/// uniform per particle and no search), with the rate `Λ·r_j ≤ 1` computed from each weight
/// as it is read. They replaced a Poisson(`Λ`) number of candidates thinned with
/// probability `r_j` (the same law, two lane draws per particle), which took half the
/// scheme's time. The joint law of the
/// offspring counts is tested by chi-square.
#[derive(Debug, Clone, Copy, Default)]
pub struct Residual;

impl Resample for Residual {
    fn resample<R: Rng + ?Sized>(&self, w: &[f64], rng: &mut R, ancestors: &mut [usize]) {
        residual(Simd::Auto, w, rng, ancestors);
    }
}

/// Largest rate `Λ` of a round (a block whose residual mass is far below its share of the
/// draws takes several rounds rather than rates far above 1).
const MAX_RATE: f64 = 4.0;

thread_local! {
    /// Scratch of [`residual`], per thread.
    static SCRATCH: RefCell<DrawBuffers> = const { RefCell::new(DrawBuffers::new()) };
}

/// What residual resampling needs to know of its weights before it draws.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ResidualSums {
    /// `Σ⌊M·W_j⌋`.
    pub(crate) floors: usize,
    /// `Σ r_j`.
    pub(crate) mass: f64,
    /// `max_j r_j`.
    pub(crate) peak: f64,
}

/// Running sums of [`floors_and_mass`], four lanes of each: weight `j` of a block of four
/// goes to lane `j mod 4` (the rest after the last whole block to lane 0).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct FloorLanes {
    /// Sums of the floors `⌊M·W_j⌋`.
    pub(crate) floors: [f64; 4],
    /// Sums of the residuals `r_j`.
    pub(crate) mass: [f64; 4],
    /// Largest residuals.
    pub(crate) peak: [f64; 4],
    /// Counts of the weights outside [0, 1] (or NaN).
    pub(crate) outside: [f64; 4],
}

impl FloorLanes {
    /// Weight `wj` into lane `l`.
    #[inline(always)]
    fn add(&mut self, l: usize, wj: f64, mf: f64) {
        self.outside[l] += if (0.0..=1.0).contains(&wj) { 0.0 } else { 1.0 };
        let x = mf * wj;
        let ff = floor_index(x).1;
        let r = x - ff;
        self.floors[l] += ff;
        self.mass[l] += r;
        self.peak[l] = if r > self.peak[l] { r } else { self.peak[l] };
    }
}

/// The [`ResidualSums`] of `w`, and whether every weight lies in [0, 1] (no NaN), four
/// partial sums at a time (a vectorisable loop). Everything is summed in floats, the floors
/// too (integers below 2⁵³, so exactly), and the weights outside [0, 1] are counted rather
/// than flagged: with an integer sum and a boolean beside the float ones, the pass took
/// 14 % of residual resampling's time at N = 10⁴, and 10.7 % this way.
/// LLVM still compiles the count to a mix of scalar and vector compares, 11 instructions per
/// weight; on a CPU with AVX-512 (and `simd` [`Simd::Auto`]) a twin does the whole blocks of
/// eight into the same lanes, with the same bits wherever they are used (the residual mass
/// in the same order; the integer sums and the largest residual are exact in any order).
#[inline(always)]
fn floors_and_mass(simd: Simd, w: &[f64], mf: f64) -> (ResidualSums, bool) {
    let (mut lanes, done) = match Avx512::get(simd) {
        Some(cpu) => floors_avx512::floor_lanes(cpu, w, mf),
        None => (FloorLanes::default(), 0),
    };
    let rest = &w[done..];
    dispatch(
        simd,
        #[inline(always)]
        || {
            let mut chunks = rest.chunks_exact(4);
            for c in &mut chunks {
                for (l, &wj) in c.iter().enumerate() {
                    lanes.add(l, wj, mf);
                }
            }
            for &wj in chunks.remainder() {
                lanes.add(0, wj, mf);
            }
        },
    );
    let sum4 = |x: [f64; 4]| (x[0] + x[1]) + (x[2] + x[3]);
    let ok = sum4(lanes.outside) == 0.0;
    let sums = ResidualSums {
        // Only read when `ok`; each floor is then at most `mf`, and the sum exact below 2⁵³
        // (a sum past `mf`, from weights summing past 1, leaves no draws either way).
        floors: sum4(lanes.floors) as usize,
        mass: sum4(lanes.mass),
        peak: lanes.peak.iter().fold(0.0, |a: f64, &p| a.max(p)),
    };
    (sums, ok)
}

/// A weight outside [0, 1] (or NaN) as residual resampling counts it: 0 below, 1 above.
fn clean(x: f64) -> f64 {
    if x >= 0.0 { x.min(1.0) } else { 0.0 }
}

/// The [`ResidualSums`] of the weights `w`, cleaned in place first if any lies outside
/// [0, 1]: what [`residual_draws`] then finds in them.
pub(crate) fn residual_sums(simd: Simd, w: &mut [f64], mf: f64) -> ResidualSums {
    let sums = |w: &[f64]| floors_and_mass(simd, w, mf);
    let (found, ok) = sums(w);
    if ok {
        return found;
    }
    w.iter_mut().for_each(|x| *x = clean(*x));
    sums(w).0
}

fn residual<R: Rng + ?Sized>(simd: Simd, w: &[f64], rng: &mut R, ancestors: &mut [usize]) {
    residual_draws(simd, w, ancestors.len() as f64, None, 0, rng, ancestors);
}

/// `out` ← the floors `⌊mf·W_j⌋` and `R = out.len() − Σ⌊mf·W_j⌋` multinomial draws from the
/// residuals `r_j = mf·W_j − ⌊mf·W_j⌋`, particle `j` written as `first + j`. The draws are
/// from `r_j/R`, any mass missing from `Σ r_j` going to the last particle (the contract of
/// [`Residual`]). For a `block` of a split (see `chunked`), whose weights are clean and
/// whose sums [`residual_sums`] gave, the draws are its share, from `r_j/Σ r_j`. `mf` is
/// `out.len()` for a whole call.
pub(crate) fn residual_draws<R: Rng + ?Sized>(
    simd: Simd,
    w: &[f64],
    mf: f64,
    block: Option<ResidualSums>,
    first: usize,
    rng: &mut R,
    out: &mut [usize],
) {
    let (n, m) = (w.len(), out.len());
    if n == 0 || m == 0 {
        return;
    }
    let drawn = SCRATCH.with(|cell| {
        let DrawBuffers {
            counts,
            extra,
            removed,
            seen,
        } = &mut *cell.borrow_mut();
        let mut lanes = None;
        // A whole call's first round, where a sample of the weights plans it, runs before
        // the floors are known and finds them (and checks the weights) as it goes.
        let planned = if block.is_none() {
            first_rate(w, mf)
        } else {
            None
        };
        let mut first_round = None;
        let (floors, mass) = match (block, planned) {
            (Some(sums), _) => (sums.floors, sums.mass),
            (None, Some(lam)) => {
                let lanes = lanes.insert(LaneRng::from_rng(rng));
                let rates = Rates::Residuals { a: mf, b: lam };
                let tally = poisson_counts(simd, counts, w, rates, lanes, rng);
                if !tally.clean {
                    return false;
                }
                first_round = Some((tally.total, lam));
                (tally.floors as usize, tally.rates / lam)
            }
            (None, None) => match floors_and_mass(simd, w, mf) {
                (sums, true) => (sums.floors, sums.mass),
                (_, false) => return false,
            },
        };
        let r = m.saturating_sub(floors);
        // The draws are from `r_j/R`. Weights summing short of 1 leave `Σ r_j < R`; the
        // missing mass goes to the last particle (where the cumulative-weight schemes put
        // it), as an extra rate `e`. Weights summing past 1 give the draws of `r_j/Σ r_j`.
        // Each round's candidate rate is set so that its counts have the mean it needs in
        // all (`Σ keep + e`).
        let rf = r as f64;
        let (scale, e, keep_total) = if let Some(sums) = block.filter(|_| mass > 0.0) {
            // Counts in proportion to `r_j` whatever their sum: keep probabilities
            // `r_j/max r_j` (rounded down, so at most 1), and the candidates' rate carries
            // the normalisation. With the largest keep probability 1, a round keeps at
            // least as many candidates as one particle has, so a block whose residual mass
            // is far below its share of the draws still needs few rounds.
            let scale = (1.0 - f64::EPSILON) / sums.peak;
            (scale, 0.0, mass * scale)
        } else {
            let scale = if mass > rf { rf / mass } else { 1.0 };
            (scale, (rf - mass * scale).max(0.0), rf)
        };
        let mut t = 0;
        // The missing mass's draws of a round at `rate` (its counts at `scale·rate·r_j`).
        let missing = |round: &mut Counts, rate: f64, rng: &mut R| {
            let more = Poisson::new(rate * e).map_or(0, |d| d.sample(rng) as usize);
            round.add_to(n - 1, more);
            more
        };
        match first_round {
            // Counts at `Λ·r_j` are those of a round at `Λ/scale`.
            Some((total, lam)) => t = total.saturating_add(missing(counts, lam / scale, rng)),
            None if r > 0 => lanes = Some(LaneRng::from_rng(rng)),
            None => {
                counts.reset(n);
                counts.small.fill(0);
            }
        }
        if let Some(lanes) = lanes.as_mut() {
            // Whether the next round's counts are the first (else they join the others).
            let mut fresh = first_round.is_none();
            while t < r {
                let rate = (round_mean(r.saturating_sub(t) as f64) / keep_total).min(MAX_RATE);
                let round = if fresh { &mut *counts } else { &mut *extra };
                let rates = Rates::Residuals {
                    a: mf,
                    b: scale * rate,
                };
                t += poisson_counts(simd, round, w, rates, lanes, rng).total;
                t += missing(round, rate, rng);
                if !fresh {
                    counts.add(extra);
                }
                fresh = false;
            }
        }
        distinct_sorted(t, t - r, rng, seen, removed);
        // Eight copies a store, as for multinomial: with four, the particles whose floor and
        // draws pass four (5 % on the bench's weights) took the run loop's slow branch, and
        // the scheme ran 5 % slower at N = 10⁶.
        let floor = |j: usize| floor_index(mf * w[j]).0;
        write_runs::<8>(simd, counts, removed, &Floors(floor), first, out);
        true
    });
    if !drawn {
        // Outside the contract (a NaN, negative or above-1 weight, where the floors would
        // mean nothing): such weights count as 0, or 1 above it, on a cleaned copy (an
        // allocation on this path only).
        let clean: Vec<f64> = w.iter().map(|&x| clean(x)).collect();
        residual_draws(simd, &clean, mf, None, first, rng, out);
    }
}

/// Blocks of [`SCAN`] weights that plan a whole call's first round ([`first_rate`]).
const PLAN_BLOCKS: usize = 32;

/// The rate `Λ` of a whole call's first round, from a sample of [`PLAN_BLOCKS`] blocks
/// spread evenly over the weights (all of them when there are fewer), or `None` when the
/// sample leaves the residual mass `R` too uncertain or too small: then a pass of its own
/// finds the floors first, as for a block of a split.
///
/// Any `Λ` gives the same law (the counts are conditioned on their total, and a short
/// total is topped up), so the sample only has to make the round efficient: `Λ` is that of
/// a round drawing the sample's lower bound on `R` (its estimate less [`OVERSHOOT`]
/// standard errors of cluster sampling), which overshoots a larger `R` by more and falls
/// short about as rarely as a round planned on the exact `R`. With the plan, the round's
/// pass over the weights also sums the floors and checks the weights (see
/// [`Tally`](super::poisson::Tally)), and the floors pass goes: it took 0.28 of the
/// scheme's 2.9 ns per particle at N = 10⁶.
fn first_rate(w: &[f64], mf: f64) -> Option<f64> {
    let blocks = w.len().div_ceil(SCAN);
    let k = blocks.min(PLAN_BLOCKS);
    let (mut sum, mut squares) = (0.0, 0.0);
    for i in 0..k {
        let b = i * blocks / k;
        let sample = &w[b * SCAN..((b + 1) * SCAN).min(w.len())];
        let s: f64 = sample
            .iter()
            .map(|&w| {
                let x = mf * w;
                x - floor_index(x).1
            })
            .sum();
        sum += s;
        squares += s * s;
    }
    let (k, blocks) = (k as f64, blocks as f64);
    let mean = sum / k;
    let spread = if k > 1.0 {
        (squares - k * mean * mean).max(0.0) / (k - 1.0)
    } else {
        0.0
    };
    let estimate = blocks * mean;
    let error = blocks * (spread * (1.0 - k / blocks) / k).sqrt();
    let low = estimate - OVERSHOOT * error;
    // A NaN (weights outside the contract) fails both tests.
    (low >= 1.0 && low >= estimate / 2.0).then(|| (round_mean(low) / low).min(MAX_RATE))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mc::stream_rng;
    use crate::resample::offspring_counts;
    use crate::testing::{binomial_pmf, chi2_quantile_999, multinomial_pmf, pearson_pooled};
    use rand::RngExt;

    /// The floors pass gives the same sums, bit for bit, on every kernel (the AVX-512 twin
    /// where the CPU has it): on lengths that end inside a block of four and of eight,
    /// weights whose `M·W_j` fall on integers and just beside them, −0, and weights outside
    /// [0, 1] (a NaN, a negative one, one above 1), which every kernel reports.
    #[test]
    fn floors_pass_is_the_same_on_every_kernel() {
        let mut rng = stream_rng(31, 0);
        for len in [1usize, 5, 8, 13, 64, 1003] {
            let mf = len as f64;
            let mut w: Vec<f64> = (0..len)
                .map(|j| match j % 5 {
                    0 => (j % 3) as f64 / mf,
                    1 => ((j % 4) as f64 / mf).next_up(),
                    2 => ((j % 4) as f64 / mf).next_down().max(0.0),
                    _ => rng.random::<f64>().powi(4) * 3.0 / mf,
                })
                .collect();
            // −0 lies inside; `⌊−0⌋` is −0 for the twin's rounding and +0 for `floor_index`.
            w[0] = -0.0;
            for bad in [None, Some(f64::NAN), Some(-1e-300), Some(1.5)] {
                if let Some(x) = bad {
                    w[len / 2] = x;
                }
                let want = floors_and_mass(Simd::Portable, &w, mf);
                for simd in [Simd::Auto, Simd::Avx2] {
                    let got = floors_and_mass(simd, &w, mf);
                    assert_eq!(got.1, want.1, "len {len}, {bad:?}, {simd:?}");
                    assert_eq!(got.1, bad.is_none(), "len {len}, {bad:?}, {simd:?}");
                    if want.1 {
                        assert_eq!(got.0.floors, want.0.floors, "len {len}, {simd:?}");
                        assert_eq!(got.0.mass.to_bits(), want.0.mass.to_bits(), "len {len}");
                        assert_eq!(got.0.peak.to_bits(), want.0.peak.to_bits(), "len {len}");
                    }
                }
            }
        }
    }

    /// Floors first: every particle gets at least `⌊M·W_j⌋`, exactly `M` ancestors come
    /// out, in increasing order, on every kernel alike.
    #[test]
    fn floors_total_and_order_on_every_kernel() {
        let w: Vec<f64> = {
            let raw: Vec<f64> = (1..=150).map(|i| ((i * 7) % 19) as f64 + 0.1).collect();
            let s: f64 = raw.iter().sum();
            raw.iter().map(|x| x / s).collect()
        };
        for &m in &[1usize, 10, 150, 1000, 5000] {
            let mut auto = vec![0; m];
            residual(Simd::Auto, &w, &mut stream_rng(1, m as u64), &mut auto);
            assert!(auto.windows(2).all(|p| p[0] <= p[1]), "M = {m}");
            for (j, c) in offspring_counts(&auto, w.len()).into_iter().enumerate() {
                assert!(
                    c >= (m as f64 * w[j]).floor() as usize,
                    "M = {m}, particle {j}"
                );
            }
            for simd in [Simd::Avx2, Simd::Portable] {
                let mut other = vec![0; m];
                residual(simd, &w, &mut stream_rng(1, m as u64), &mut other);
                assert_eq!(auto, other, "M = {m}, {simd:?}");
            }
        }
    }

    /// A block whose residual mass is tiny but which must make draws (its share of a
    /// split, see `chunked`) makes them from its residuals in few rounds: keep
    /// probabilities `r_j/max r_j` put the largest at 1, where `r_j` alone would keep one
    /// candidate in 10⁹ and take about 10⁹ rounds.
    #[test]
    fn a_block_with_tiny_residual_mass_draws_quickly() {
        let mut w = vec![0.0; 100];
        (w[3], w[70]) = (1e-9, 3e-9);
        let sums = residual_sums(Simd::Auto, &mut w, 1.0);
        assert_eq!((sums.floors, sums.peak), (0, 3e-9));
        // The draws follow r_j/Σ r_j: particle 70 (written as 75) takes about three in
        // four. 20 calls × 8 draws: Binomial(160, 3/4), mean 120, standard deviation 5.5.
        let mut heavy = 0;
        for seed in 0..20 {
            let mut out = vec![usize::MAX; 8];
            let rng = &mut stream_rng(5, seed);
            residual_draws(Simd::Auto, &w, 1.0, Some(sums), 5, rng, &mut out);
            assert!(out.iter().all(|&a| a == 8 || a == 75), "{out:?}");
            heavy += out.iter().filter(|&&a| a == 75).count();
        }
        assert!(
            (120 - 5 * 6..=120 + 5 * 6).contains(&heavy),
            "{heavy} of 160"
        );
    }

    /// Weights that are exact multiples of `1/M` leave no residual: the floors alone.
    #[test]
    fn exact_weights_are_copied_deterministically() {
        let w = [0.25, 0.5, 0.0, 0.25];
        let mut a = vec![9; 8];
        residual(Simd::Auto, &w, &mut stream_rng(2, 0), &mut a);
        assert_eq!(a, [0, 0, 1, 1, 1, 1, 3, 3]);
    }

    /// No residual mass but draws left (weights summing short of 1 in multiples of 1/M):
    /// the draws go to the last particle, and nothing hangs.
    #[test]
    fn draws_without_residual_mass_go_to_the_last_particle() {
        let w = [0.25, 0.25];
        let mut a = vec![9; 4];
        residual(Simd::Auto, &w, &mut stream_rng(3, 0), &mut a);
        assert_eq!(a, [0, 1, 1, 1]);
    }

    /// Weights far from summing to 1, or outside [0, 1], neither hang nor leave the range:
    /// missing mass goes to the last particle, a weight total above 1 is normalised, and a
    /// NaN or negative weight counts as 0.
    #[test]
    fn weights_far_from_normalised_stay_in_range() {
        let mut a = vec![0usize; 1000];
        let tiny = vec![1e-6; 10];
        residual(Simd::Auto, &tiny, &mut stream_rng(4, 0), &mut a);
        assert!(a.iter().all(|&i| i < 10));
        // Σ r_j = 0.01 of R = 1000 draws: nearly all go to the last particle.
        assert!(offspring_counts(&a, 10)[9] > 950);
        // Σ W = 1.0009 and M = 995: floors of 99, R = 5 and Σ r_j = 5.9: normalised.
        let big = vec![0.10009; 10];
        let mut b = vec![0usize; 995];
        residual(Simd::Auto, &big, &mut stream_rng(4, 1), &mut b);
        assert!(
            offspring_counts(&b, 10)
                .iter()
                .all(|&c| (99..=104).contains(&c))
        );
        let bad = [0.5, f64::NAN, f64::NAN, -1e-18, -0.5, f64::NAN, 0.5];
        residual(Simd::Auto, &bad, &mut stream_rng(4, 2), &mut a);
        let counts = offspring_counts(&a, bad.len());
        assert_eq!(counts, [500, 0, 0, 0, 0, 0, 500]);
    }

    /// The joint law: W = (0.45, 0.35, 0.2) and M = 4 give floors (1, 1, 0) and R = 2 draws
    /// from the residuals (0.4, 0.2, 0.4). Chi-square of the 6 outcomes over 60 000 seeded
    /// calls (Λ = 3.1 here, so most particles take the scalar path and every call removes
    /// draws); with 5 degrees of freedom, P(χ² > 20.5) = 0.001.
    #[test]
    fn residual_draws_are_jointly_multinomial() {
        let w = [0.45, 0.35, 0.2];
        let p = [0.4f64, 0.2, 0.4];
        let reps = 60_000;
        let mut seen = std::collections::HashMap::new();
        let mut rng = stream_rng(13, 0);
        let mut a = [0usize; 4];
        for _ in 0..reps {
            residual(Simd::Auto, &w, &mut rng, &mut a);
            let k = offspring_counts(&a, 3);
            *seen.entry([k[0] - 1, k[1] - 1, k[2]]).or_insert(0usize) += 1;
        }
        assert_eq!(seen.values().sum::<usize>(), reps);
        let mut chi2 = 0.0;
        for i in 0..=2usize {
            for j in 0..=2 - i {
                let l = 2 - i - j;
                let e = multinomial_pmf(&[i, j, l], &p) * reps as f64;
                let o = seen.get(&[i, j, l]).copied().unwrap_or(0) as f64;
                chi2 += (o - e).powi(2) / e;
            }
        }
        assert!(chi2 < 20.5, "χ² {chi2}");
    }

    /// The plan of a whole call's first round: exact where it samples every block, `Λ` of
    /// a round drawing about `R` on weights like the bench's, and no plan where the sample
    /// says little (weights outside the contract, too little residual mass).
    #[test]
    fn the_first_round_is_planned_from_a_sample() {
        let lam = |r: f64| (round_mean(r) / r).min(MAX_RATE);
        // 3 particles, M = 4: residuals (0.8, 0.4, 0.8), every block sampled.
        assert_eq!(first_rate(&[0.45, 0.35, 0.2], 4.0), Some(lam(2.0)));
        let mut rng = stream_rng(41, 0);
        for n in [5000usize, 100_000] {
            let raw: Vec<f64> = (0..n).map(|_| rng.random::<f64>().powi(4)).collect();
            let total: f64 = raw.iter().sum();
            let mut w: Vec<f64> = raw.iter().map(|x| x / total).collect();
            let mf = n as f64;
            let r: f64 = w.iter().map(|&w| mf * w - (mf * w).floor()).sum();
            // The sample's lower bound lies below `R` and within a fifth of it.
            let got = first_rate(&w, mf).expect("a plan");
            assert!(
                got >= lam(r) && got <= lam(0.8 * r),
                "N = {n}: {got} for R = {r}"
            );
            w[n / 2] = f64::NAN;
            assert_eq!(first_rate(&w, mf), None, "N = {n}");
        }
        // Residual mass 0.01 of a draw: no plan (the floors pass finds that there is none).
        assert_eq!(first_rate(&[1e-6; 10], 1000.0), None);
    }

    /// Residual draws stay multinomial where the plan misjudges `R` or gives up. With
    /// 320 blocks of 64 particles, the plan samples every tenth block. Residuals of 1/2
    /// only in those blocks make it think `R` ten times larger, so that its round falls
    /// short of `R` (by about 1 standard deviation: in about 1 call in 6) and a second
    /// round tops it up; the same residuals only in the other blocks leave it no sample
    /// of them, and the floors come first. Either way `R = 1024`, and the first block's
    /// draws beyond its floors are Binomial(1024, 1/32) if it holds residuals, none if not
    /// (chi-square over 1500 calls).
    #[test]
    fn draws_stay_multinomial_when_the_plan_misjudges() {
        let (blocks, m) = (320usize, 320 * 64);
        let mf = m as f64;
        for sampled in [true, false] {
            // `M·W_j`: 1.5 in the 32 blocks with residuals; elsewhere 1, and 0 for 1024
            // particles, so that the total is `M`.
            let mut zeros = 1024;
            let mw: Vec<f64> = (0..blocks)
                .flat_map(|b| {
                    let holds = b % 10 == if sampled { 0 } else { 5 };
                    (0..64).map(move |_| holds)
                })
                .map(|holds| match holds {
                    true => 1.5,
                    false if zeros > 0 => {
                        zeros -= 1;
                        0.0
                    }
                    false => 1.0,
                })
                .collect();
            let w: Vec<f64> = mw.iter().map(|x| x / mf).collect();
            assert_eq!(w.iter().filter(|&&x| x * mf == 1.5).count(), 2048);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            let plan = first_rate(&w, mf);
            match sampled {
                // The plan's round draws `Λ·R` on average, within one standard deviation.
                true => assert!(plan.expect("a plan") * 1024.0 < 1024.0 + 32.0, "{plan:?}"),
                false => assert_eq!(plan, None),
            }
            let first = mw.iter().position(|&x| x == 1.5).expect("residuals");
            let reps = 1500;
            let mut hist = vec![0usize; 1025];
            let mut rng = stream_rng(42, u64::from(sampled));
            let mut a = vec![0usize; m];
            for _ in 0..reps {
                residual(Simd::Auto, &w, &mut rng, &mut a);
                let counts = offspring_counts(&a, w.len());
                let draws: usize = (first..first + 64).map(|j| counts[j] - 1).sum();
                hist[draws] += 1;
            }
            let (chi2, df) = pearson_pooled(&hist, |k| binomial_pmf(1024, 1.0 / 32.0, k));
            assert!(df >= 4, "{df} df");
            assert!(
                chi2 < chi2_quantile_999(df),
                "sampled {sampled}: χ² {chi2} on {df} df"
            );
        }
    }

    /// 64 particles with residuals spread over [0, 1) (one vectorised block): particle 0's
    /// draws beyond its floor are Binomial(R, r_0/R). Chi-square over 20 000 calls.
    #[test]
    fn a_particles_draws_are_binomial() {
        let raw: Vec<f64> = (0..64)
            .map(|i| 1.0 + ((i * 37) % 10) as f64 / 9.0)
            .collect();
        let s: f64 = raw.iter().sum();
        let w: Vec<f64> = raw.iter().map(|x| x / s).collect();
        let m = 100usize;
        let floors: Vec<usize> = w.iter().map(|&x| (m as f64 * x).floor() as usize).collect();
        let r = m - floors.iter().sum::<usize>();
        let p0 = (m as f64 * w[0] - floors[0] as f64) / r as f64;
        let mut hist = vec![0usize; r + 1];
        let mut rng = stream_rng(14, 0);
        let mut a = vec![0usize; m];
        for _ in 0..20_000 {
            residual(Simd::Auto, &w, &mut rng, &mut a);
            hist[offspring_counts(&a, 64)[0] - floors[0]] += 1;
        }
        let (chi2, df) = pearson_pooled(&hist, |k| binomial_pmf(r, p0, k));
        assert!(df >= 2, "{df} df");
        assert!(chi2 < chi2_quantile_999(df), "χ² {chi2} on {df} df");
    }
}
