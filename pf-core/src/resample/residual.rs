//! Residual resampling: deterministic copies, then multinomial on what is left, drawn per
//! particle from Poisson counts.

use super::Resample;
use super::poisson::{
    DrawBuffers, Floors, Rates, distinct_sorted, poisson_counts, round_mean, write_runs,
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
///    counts add up to Poisson counts).
/// 2. **Conditioning on `R`.** Given `T`, the counted draws are `T` independent draws from
///    `r/R`; a uniformly chosen subset of `T − R` of them (about `3√R`, from the caller's
///    generator) is removed, which leaves `R` independent draws.
/// 3. **Ancestors.** Each particle's copies and kept draws are written as one run, so the
///    ancestors come out in increasing order.
///
/// The counts are the inversion of multinomial resampling's (`poisson_counts`, one lane
/// uniform per particle and no search), with the rate `Λ·r_j ≤ 1` computed from each weight
/// as it is read. They replaced a Poisson(`Λ`) number of candidates thinned with
/// probability `r_j` (the same law, two lane draws per particle), which took 3.1–3.4 of the
/// scheme's 6.0–6.3 ns per particle (performance log, 2026-11-27). The joint law of the
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
/// 14 % of residual resampling's time at N = 10⁴, and 10.7 % this way (performance log).
/// LLVM still compiles the count to a mix of scalar and vector compares, 11 instructions per
/// weight; on a CPU with AVX-512 (and `simd` [`Simd::Auto`]) a twin does the whole blocks of
/// eight into the same lanes, with the same bits wherever they are used (the residual mass
/// in the same order; the integer sums and the largest residual are exact in any order).
#[inline(always)]
fn floors_and_mass(simd: Simd, w: &[f64], mf: f64) -> (ResidualSums, bool) {
    let (mut lanes, done) = match Avx512::get(simd) {
        Some(cpu) => super::floors_avx512::floor_lanes(cpu, w, mf),
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
    let (sums, ok) = match block {
        Some(sums) => (sums, true),
        None => floors_and_mass(simd, w, mf),
    };
    let (floors, mass) = (sums.floors, sums.mass);
    if !ok {
        // Outside the contract (a NaN, negative or above-1 weight, where the floors would
        // mean nothing): such weights count as 0, or 1 above it, on a cleaned copy (an
        // allocation on this path only).
        let clean: Vec<f64> = w.iter().map(|&x| clean(x)).collect();
        return residual_draws(simd, &clean, mf, None, first, rng, out);
    }
    let r = m.saturating_sub(floors);
    // The draws are from `r_j/R`. Weights summing short of 1 leave `Σ r_j < R`; the missing
    // mass goes to the last particle (where the cumulative-weight schemes put it), as an
    // extra rate `e`. Weights summing past 1 give the draws of `r_j/Σ r_j`. Each round's
    // candidate rate is set so that its counts have the mean it needs in all (`Σ keep + e`).
    let rf = r as f64;
    let (scale, e, keep_total) = if block.is_some() && mass > 0.0 {
        // Counts in proportion to `r_j` whatever their sum: keep probabilities
        // `r_j/max r_j` (rounded down, so at most 1), and the candidates' rate carries the
        // normalisation. With the largest keep probability 1, a round keeps at least as
        // many candidates as one particle has, so a block whose residual mass is far below
        // its share of the draws still needs few rounds.
        let scale = (1.0 - f64::EPSILON) / sums.peak;
        (scale, 0.0, mass * scale)
    } else {
        let scale = if mass > rf { rf / mass } else { 1.0 };
        (scale, (rf - mass * scale).max(0.0), rf)
    };
    let floor = |j: usize| floor_index(mf * w[j]).0;
    let mut lanes = (r > 0).then(|| LaneRng::from_rng(rng));
    SCRATCH.with(|cell| {
        let DrawBuffers {
            counts,
            extra,
            removed,
            seen,
        } = &mut *cell.borrow_mut();
        // No clearing: the first round sets every count.
        counts.reset(n);
        let mut t = 0;
        match lanes.as_mut() {
            None => counts.small.fill(0),
            Some(lanes) => {
                let mut rate = (round_mean(r) / keep_total).min(MAX_RATE);
                let mut first_round = true;
                while t < r {
                    let round = if first_round {
                        &mut *counts
                    } else {
                        &mut *extra
                    };
                    let rates = Rates::Residuals {
                        a: mf,
                        b: scale * rate,
                    };
                    t += poisson_counts(simd, round, w, rates, lanes, rng).0;
                    if let Ok(more) = Poisson::new(rate * e) {
                        let more = more.sample(rng) as usize;
                        round.add_to(n - 1, more);
                        t += more;
                    }
                    if !first_round {
                        counts.add(extra);
                    }
                    first_round = false;
                    rate = (round_mean(r.saturating_sub(t)) / keep_total).min(MAX_RATE);
                }
            }
        }
        distinct_sorted(t, t - r, rng, seen, removed);
        // Eight copies a store, as for multinomial: with four, the particles whose floor and
        // draws pass four (5 % on the bench's weights) took the run loop's slow branch, and
        // the scheme ran 3.78 against 3.60 ns at N = 10⁶ (performance log, 2026-11-27).
        write_runs::<8>(simd, counts, removed, &Floors(floor), first, out);
    });
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
