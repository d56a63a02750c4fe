//! The Poisson machinery of the O(N) multinomial draws: counts with a rate per particle
//! (multinomial), counts of one rate thinned per particle (residual), the uniformly chosen
//! draws removed when conditioning a Poisson total, and the runs of ancestors they leave.

use super::offspring::{Runs, SCAN};
use crate::simd::math::{exp_nonpositive_lanes, unit_from_bits};
use crate::simd::{LANES, LaneRng, set_bits};
use rand::{Rng, RngExt};
use rand_distr::{Distribution, Poisson};

/// Outcomes with a threshold; for the rates this module is used with (at most 4:
/// `P(N ≥ 48) < 10⁻³⁴` there) the count stops well before the last.
const LEN: usize = 48;

/// `2⁵³`, above every 53-bit draw.
const TWO53: u64 = 1 << 53;

/// Inversion thresholds of a Poisson(`rate`) law: with `v` a uniform 53-bit integer,
/// `#{k : v ≥ T_k}` is a Poisson(`rate`) count (`T_k = ⌊2⁵³·P(N ≤ k)⌋`, exact to 2⁻⁵³ per
/// outcome; the last threshold is 2⁵³, above every draw, where the tail is below 2⁻⁵³).
#[derive(Debug, Clone)]
pub(crate) struct Thresholds {
    t: [u64; LEN],
}

impl Thresholds {
    /// The thresholds of Poisson(`rate`), `0 < rate ≤ 4`.
    pub(crate) fn new(rate: f64) -> Self {
        debug_assert!(rate > 0.0 && rate <= 4.0, "rate {rate}");
        let mut t = [TWO53; LEN];
        let (mut term, mut cdf) = ((-rate).exp(), 0.0f64);
        for (k, tk) in t.iter_mut().enumerate() {
            cdf += term;
            // Stop where the distribution function rounds to 1, or stalls just below it
            // with a tail `P(N > k) < 2·term < 2⁻⁵³` (past `2·rate` the terms more than
            // halve): the count then never passes `k`.
            if cdf >= 1.0 || (k as f64 >= 2.0 * rate && term < 1.0 / (2 * TWO53) as f64) {
                break;
            }
            *tk = (cdf * TWO53 as f64) as u64;
            term *= rate / (k + 1) as f64;
        }
        Thresholds { t }
    }

    /// The count of `v` against the first `Q` thresholds (branch-free; `Q` means "`Q` or
    /// more", finished by [`Thresholds::count_from`]).
    #[inline(always)]
    pub(crate) fn count_quick<const Q: usize>(&self, v: u64) -> usize {
        let mut k = 0;
        for &th in &self.t[..Q] {
            k += usize::from(v >= th);
        }
        k
    }

    /// The whole count of `v`, known to be at least `q`.
    pub(crate) fn count_from(&self, v: u64, q: usize) -> usize {
        q + self.t[q..].iter().take_while(|&&th| v >= th).count()
    }
}

/// The per-thread buffers of the Poisson draws, reused from call to call: every call
/// overwrites what it reads, and a buffer grows only when a call's random totals need more
/// than any call before (rarely, and by doubling; see [`distinct_sorted`]).
#[derive(Debug)]
pub(crate) struct DrawBuffers {
    /// Each particle's count.
    pub(crate) counts: Vec<usize>,
    /// The draws removed when conditioning on the total, then `usize::MAX`.
    pub(crate) removed: Vec<usize>,
    /// One bit per draw: which have been chosen for removal.
    pub(crate) seen: Vec<u64>,
}

impl DrawBuffers {
    pub(crate) const fn new() -> Self {
        DrawBuffers {
            counts: Vec::new(),
            removed: Vec::new(),
            seen: Vec::new(),
        }
    }
}

/// `out` ← `d ≤ t` distinct indices among `0 … t − 1`, uniformly, sorted, then
/// `usize::MAX` (a sentinel for merges). Uniform draws are taken until `d` distinct ones
/// have come; the procedure is invariant under relabelling, so every subset is equally
/// likely. They are marked in the bitmap `seen` and read back in order, in O(d + t/64)
/// work; sorting them, O(d log d), took 8 % of multinomial resampling's time at N = 10⁴.
pub(crate) fn distinct_sorted<R: Rng + ?Sized>(
    t: usize,
    d: usize,
    rng: &mut R,
    seen: &mut Vec<u64>,
    out: &mut Vec<usize>,
) {
    debug_assert!(d <= t);
    // With room to spare: the next calls' random totals differ a little, and without it
    // every new high reallocated (growth stays rare: tests/no_allocation_per_step.rs).
    let words = t.div_ceil(64);
    seen.clear();
    seen.reserve(words + words / 8 + 1);
    seen.resize(words, 0);
    let mut found = 0;
    while found < d {
        let i = rng.random_range(0..t);
        let bit = 1u64 << (i % 64);
        found += usize::from(seen[i / 64] & bit == 0);
        seen[i / 64] |= bit;
    }
    out.clear();
    out.reserve(2 * d + 64);
    for (w, &word) in seen.iter().enumerate() {
        out.extend(set_bits(word).map(|b| w * 64 + b));
    }
    out.push(usize::MAX);
}

/// Candidate counts compared in the vectorised pass, where up to `QUICK − 1` candidates are
/// thinned at once; `QUICK` means "`QUICK` or more", finished one by one.
const QUICK: usize = 4;

/// `counts[j] ←` (with `add`, `+=`) the number of kept candidates of particle `j`: a
/// Poisson(`rate`) number of candidates (`th` its thresholds), each kept with probability
/// `keep(j) ∈ [0, 1]`. Returns the sum of the new counts.
#[inline(always)]
pub(crate) fn thin<R: Rng + ?Sized>(
    counts: &mut [usize],
    th: &Thresholds,
    add: bool,
    keep: &impl Fn(usize) -> f64,
    lanes: &mut LaneRng,
    rng: &mut R,
) -> usize {
    let mut total = 0;
    let (mut v, mut u) = ([0u64; LANES], [0u64; LANES]);
    for (b, block) in counts.chunks_mut(LANES).enumerate() {
        let j0 = b * LANES;
        let mut p = [0.0f64; LANES];
        for (q, p) in p[..block.len()].iter_mut().enumerate() {
            *p = keep(j0 + q);
        }
        lanes.step(&mut v);
        lanes.step(&mut u);
        let mut k = [0usize; LANES];
        let mut c = [0usize; LANES];
        for q in 0..LANES {
            let cq = th.count_quick::<QUICK>(v[q] >> 11);
            // Binomial(cq, p) kept candidates by inversion of one uniform, for cq ≤ 3: the
            // distribution function at 0, 1 and 2 (2 where it is 1 already, above every
            // uniform).
            let (pq, qq) = (p[q], 1.0 - p[q]);
            let q2 = qq * qq;
            let q3 = q2 * qq;
            let f0 = match cq {
                1 => qq,
                2 => q2,
                3 => q3,
                _ => 2.0,
            };
            let f1 = match cq {
                2 => 1.0 - pq * pq,
                3 => q3 + 3.0 * pq * q2,
                _ => 2.0,
            };
            let f2 = if cq == 3 { 1.0 - pq * pq * pq } else { 2.0 };
            let uq = unit_from_bits(u[q]);
            k[q] = usize::from(uq >= f0) + usize::from(uq >= f1) + usize::from(uq >= f2);
            c[q] = cq;
        }
        // Particles with QUICK candidates or more: a bit mask, so that the scalar work is
        // per such particle.
        let mut rest = 0u64;
        for (q, &cq) in c.iter().enumerate() {
            rest |= u64::from(cq == QUICK) << q;
        }
        rest &= u64::MAX >> (LANES - block.len());
        for q in set_bits(rest) {
            let cq = th.count_from(v[q] >> 11, QUICK);
            k[q] = (0..cq).filter(|_| rng.random::<f64>() < p[q]).count();
        }
        for (n, &kq) in block.iter_mut().zip(&k) {
            *n = if add { *n + kq } else { kq };
            total += kq;
        }
    }
    total
}

/// Standard deviations of a Poisson total by which a round overshoots its target.
const OVERSHOOT: f64 = 3.0;

/// The mean total of a round of Poisson counts that must bring `d` more draws: `d` plus
/// [`OVERSHOOT`] standard deviations, so that it falls short about once in a thousand
/// rounds, and the surplus to remove (about `3√d`) costs little.
pub(crate) fn round_mean(d: usize) -> f64 {
    let d = d as f64;
    d + OVERSHOOT * d.sqrt() + 1.0
}

/// Rates above this are drawn by `rand_distr`'s exact sampler (its PTRS rejection, O(1)
/// whatever the rate) instead of by inversion, whose length grows with the rate.
const RATE_INVERT: f64 = 12.0;

/// A cap on one count, far above any that resampling into memory can ask for.
const MAX_COUNT: usize = 1 << 40;

/// Terms of the distribution function compared in the vectorised pass; a count of `TERMS`
/// means "`TERMS` or more" and is finished one term at a time.
const TERMS: usize = 6;

/// `counts[j] ←` (with `add`, `+=`) a Poisson(`λ_j`) count, `λ_j = scale·w_j` (0 where
/// that is negative or NaN), independent across particles. Returns the sum of the new
/// counts (saturating) and the sum of the rates.
///
/// Inversion: with one uniform `u` per particle (a lane step per 64 particles), the count
/// is the first `i` with `u < F_i`, the distribution function summed term by term from
/// `p_0 = e^{−λ}` by `p_i = p_{i−1}·λ/i`. The first [`TERMS`] terms are compared on all 64
/// particles at once; the few particles past them, and those with `λ > 12`, are finished
/// one by one (see [`poisson_rest`]). Exact up to the rounding of the terms (a few ulp of
/// each probability).
#[inline(always)]
pub(crate) fn poisson_counts<R: Rng + ?Sized>(
    counts: &mut [usize],
    w: &[f64],
    scale: f64,
    add: bool,
    lanes: &mut LaneRng,
    rng: &mut R,
) -> (usize, f64) {
    debug_assert_eq!(counts.len(), w.len());
    let mut total = 0usize;
    // Eight partial sums of the rates (a vectorisable reduction).
    let mut rates = [0.0f64; 8];
    let mut bits = [0u64; LANES];
    let mut lam = [0.0f64; LANES];
    let mut k = [0usize; LANES];
    for (block, wb) in counts.chunks_mut(LANES).zip(w.chunks(LANES)) {
        let len = block.len();
        lanes.step(&mut bits);
        if len < LANES {
            lam.fill(0.0);
        }
        for (l, &w) in lam.iter_mut().zip(wb) {
            let x = scale * w;
            *l = if x > 0.0 { x } else { 0.0 };
        }
        for l8 in lam.chunks_exact(8) {
            for (r, l) in rates.iter_mut().zip(l8) {
                *r += l;
            }
        }
        poisson_block(&lam, &bits, &mut k, rng);
        for (c, &k) in block.iter_mut().zip(&k) {
            *c = if add { *c + k } else { k };
        }
        total = total.saturating_add(k[..len].iter().sum::<usize>());
    }
    (total, rates.iter().sum())
}

/// Poisson(`lam[q]`) counts by inversion of the uniforms in `bits`, into `k`.
#[inline(always)]
fn poisson_block<R: Rng + ?Sized>(
    lam: &[f64; LANES],
    bits: &[u64; LANES],
    k: &mut [usize; LANES],
    rng: &mut R,
) {
    let mut p = exp_nonpositive_lanes(std::array::from_fn::<f64, LANES, _>(|q| -lam[q]));
    let u: [f64; LANES] = std::array::from_fn(|q| unit_from_bits(bits[q]));
    let mut f = [0.0f64; LANES];
    // Four lanes at a time through all the terms, so that they stay in registers (over all
    // 64 lanes per term, they went through the stack, and the loads of misaligned vectors
    // waited on the stores before them).
    let groups = k
        .chunks_exact_mut(4)
        .zip(p.chunks_exact_mut(4).zip(f.chunks_exact_mut(4)))
        .zip(u.chunks_exact(4).zip(lam.chunks_exact(4)));
    for ((k, (p, f)), (u, lam)) in groups {
        let mut k4 = [0usize; 4];
        let mut p4: [f64; 4] = std::array::from_fn(|l| p[l]);
        let mut f4 = p4;
        for i in 1..TERMS {
            let inv = 1.0 / i as f64;
            for l in 0..4 {
                k4[l] += usize::from(u[l] >= f4[l]);
                p4[l] *= lam[l] * inv;
                f4[l] += p4[l];
            }
        }
        for l in 0..4 {
            k[l] = k4[l] + usize::from(u[l] >= f4[l]);
        }
        p.copy_from_slice(&p4);
        f.copy_from_slice(&f4);
    }
    let mut rest = 0u64;
    for q in 0..LANES {
        rest |= u64::from((k[q] == TERMS) | (lam[q] > RATE_INVERT)) << q;
    }
    for q in set_bits(rest) {
        k[q] = poisson_rest(lam[q], u[q], p[q], f[q], rng);
    }
}

/// The count of a particle the vectorised pass left: for `λ ≤ 12`, the inversion continued
/// from term [`TERMS`] (`p`, `f`: the last term and the sum so far); above, `rand_distr`'s
/// sampler on `rng`.
#[cold]
fn poisson_rest<R: Rng + ?Sized>(lam: f64, u: f64, mut p: f64, mut f: f64, rng: &mut R) -> usize {
    if lam > RATE_INVERT {
        // Weights far outside the contract can make rates of any size (the caller then
        // normalises and draws again): the count is capped so that no sum of counts
        // overflows.
        return Poisson::new(lam).map_or(0, |d| (d.sample(rng) as usize).min(MAX_COUNT));
    }
    let mut i = TERMS;
    loop {
        p *= lam / i as f64;
        f += p;
        // Past the mode, once the terms no longer move the sum, the tail left is below
        // 2⁻⁵²: stop rather than loop on a sum that rounds short of `u`.
        if u < f || (i as f64 > lam && p < f * f64::EPSILON) {
            return i;
        }
        i += 1;
    }
}

/// Particle `j`'s `base(j)` copies and kept draws (its count less the draws `removed`, an
/// ascending list of indices among all the counted draws in particle order, then
/// `usize::MAX`) as one run of copies of `first + j` in `out`, written `W` at a time (see
/// [`Runs`]). Boundaries are computed a block at a time; a block that holds a removal (one
/// in about every `√M/3` particles) also finds the particle of each removal.
#[inline(always)]
pub(crate) fn write_runs<const W: usize>(
    counts: &[usize],
    removed: &[usize],
    base: &impl Fn(usize) -> usize,
    first: usize,
    out: &mut [usize],
) {
    if u32::try_from(out.len()).is_ok() {
        write_runs_with::<W, true>(counts, removed, base, first, out);
    } else {
        write_runs_with::<W, false>(counts, removed, base, first, out);
    }
}

/// [`write_runs`], with `SMALL` when `M < 2³²` (see [`Runs`]).
#[inline(always)]
fn write_runs_with<const W: usize, const SMALL: bool>(
    counts: &[usize],
    removed: &[usize],
    base: &impl Fn(usize) -> usize,
    first: usize,
    out: &mut [usize],
) {
    let mut runs = Runs::<W>::new();
    let (mut drawn, mut kept, mut x) = (0usize, 0usize, 0usize);
    let (mut kb, mut ends) = ([0usize; SCAN], [0usize; SCAN]);
    for (b, block) in counts.chunks(SCAN).enumerate() {
        let j0 = b * SCAN;
        let kb = &mut kb[..block.len()];
        for (q, (k, &c)) in kb.iter_mut().zip(block).enumerate() {
            *k = base(j0 + q) + c;
        }
        let end = drawn + block.iter().sum::<usize>();
        if removed[x] < end {
            // Each removal comes off the particle whose draws hold it: the first whose draws
            // end above it, found by counting the ends at or below it (a vectorised count
            // per removal, not a loop with a branch per particle).
            let ends = &mut ends[..block.len()];
            for (e, &c) in ends.iter_mut().zip(block) {
                drawn += c;
                *e = drawn;
            }
            while removed[x] < end {
                let r = removed[x];
                kb[ends.iter().filter(|&&e| e <= r).count()] -= 1;
                x += 1;
            }
        }
        drawn = end;
        for k in kb.iter_mut() {
            kept += *k;
            *k = kept;
        }
        runs.push_each::<SMALL, false>(out, first + j0, kb);
        if runs.is_full(out.len()) {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mc::{PfRng, stream_rng};
    use crate::simd::{Simd, dispatch};
    use crate::testing::{chi2_quantile_999, pearson_pooled, poisson_pmf};

    /// The thresholds are the distribution function, to the 53-bit grid, and stop where it
    /// rounds to 1.
    #[test]
    fn thresholds_are_the_poisson_cdf() {
        for rate in [0.3, 1.0, 1.003, 2.5, 4.0] {
            let th = Thresholds::new(rate);
            let mut cdf = 0.0;
            for (k, &t) in th.t.iter().enumerate() {
                cdf += poisson_pmf(rate, k);
                let want = cdf.min(1.0) * TWO53 as f64;
                assert!(
                    (t as f64 - want).abs() <= 64.0,
                    "rate {rate}, k = {k}: {t} against {want}"
                );
            }
            let last =
                th.t.iter()
                    .position(|&x| x == TWO53)
                    .expect("a last threshold");
            assert!(last < 40, "rate {rate}: {last}");
        }
    }

    /// The quick count and its continuation give the full count.
    #[test]
    fn quick_count_and_continuation_agree() {
        let th = Thresholds::new(2.5);
        let mut rng = stream_rng(4, 0);
        for _ in 0..10_000 {
            let v = rng.next_u64() >> 11;
            let full = th.t.iter().filter(|&&x| v >= x).count();
            let quick = th.count_quick::<3>(v);
            let got = if quick == 3 {
                th.count_from(v, 3)
            } else {
                quick
            };
            assert_eq!(got, full);
        }
    }

    /// Exactly `d` distinct sorted indices below `t`, then the sentinel; and every index is
    /// equally likely to be chosen (chi-square over 8 cells, 7 df, P(χ² > 24.3) = 0.001).
    #[test]
    fn distinct_sorted_is_a_uniform_subset() {
        let mut rng = stream_rng(8, 0);
        let (mut seen, mut out) = (Vec::new(), Vec::new());
        let mut hits = [0usize; 8];
        for _ in 0..20_000 {
            distinct_sorted(8, 3, &mut rng, &mut seen, &mut out);
            assert_eq!(out.len(), 4);
            assert_eq!(out[3], usize::MAX);
            assert!(out[..3].windows(2).all(|p| p[0] < p[1]));
            for &i in &out[..3] {
                hits[i] += 1;
            }
        }
        let e = 20_000.0 * 3.0 / 8.0;
        let chi2: f64 = hits.iter().map(|&h| (h as f64 - e).powi(2) / e).sum();
        assert!(chi2 < 24.3, "χ² {chi2}");
        distinct_sorted(5, 5, &mut rng, &mut seen, &mut out);
        assert_eq!(out, [0, 1, 2, 3, 4, usize::MAX]);
        distinct_sorted(0, 0, &mut rng, &mut seen, &mut out);
        assert_eq!(out, [usize::MAX]);
    }

    /// The bitmap draws the same subset from the same stream as the textbook procedure
    /// (draw `d − |S|` more, sort, deduplicate, repeat): until `d` distinct indices have
    /// come, both consume the same draws. Over sizes that cross word boundaries, subsets
    /// from none to all, and a bitmap left dirty by a larger call.
    #[test]
    fn distinct_sorted_equals_sort_and_deduplicate() {
        fn reference(t: usize, d: usize, rng: &mut PfRng) -> Vec<usize> {
            let mut out = Vec::new();
            while out.len() < d {
                for _ in out.len()..d {
                    out.push(rng.random_range(0..t));
                }
                out.sort_unstable();
                out.dedup();
            }
            out.push(usize::MAX);
            out
        }
        let (mut seen, mut out) = (Vec::new(), Vec::new());
        for (t, d) in [
            (1, 1),
            (63, 20),
            (64, 64),
            (65, 30),
            (1000, 97),
            (10_300, 301),
            (130, 0),
        ] {
            for seed in 0..20 {
                let (mut theirs, mut ours) = (stream_rng(seed, 2), stream_rng(seed, 2));
                let want = reference(t, d, &mut theirs);
                distinct_sorted(t, d, &mut ours, &mut seen, &mut out);
                assert_eq!(out, want, "t = {t}, d = {d}, seed {seed}");
                // Both left the stream at the same place.
                assert_eq!(ours.next_u64(), theirs.next_u64(), "t = {t}, d = {d}");
            }
        }
    }

    /// Thinning a Poisson(Λ) number of candidates with probability `p` gives Poisson(Λ·p)
    /// counts, on the vectorised binomial path (Λ = 1.5: most particles have at most three
    /// candidates) and on the scalar one (Λ = 3.9: a third have four or more).
    #[test]
    fn thinned_counts_are_poisson() {
        let n = 40_000;
        for (i, (rate, p)) in [(1.5, 0.8), (1.5, 0.3), (1.0, 0.05), (3.9, 0.9), (3.9, 0.5)]
            .into_iter()
            .enumerate()
        {
            let mut rng = stream_rng(15, i as u64);
            let mut lanes = LaneRng::from_rng(&mut rng);
            let mut counts = vec![0usize; n];
            let th = Thresholds::new(rate);
            dispatch(Simd::Auto, || {
                thin(&mut counts, &th, false, &|_| p, &mut lanes, &mut rng)
            });
            let mut hist = vec![0usize; 40];
            for &c in &counts {
                hist[c] += 1;
            }
            let (chi2, df) = pearson_pooled(&hist, |k| poisson_pmf(rate * p, k));
            assert!(
                chi2 < chi2_quantile_999(df),
                "Λ = {rate}, p = {p}: χ² {chi2} on {df} df"
            );
        }
    }

    /// Poisson counts with per-particle rates follow Poisson(λ) on each path: the
    /// vectorised terms alone (λ = 0.7), the inversion continued one by one (λ = 4.5 and
    /// 11: P(N ≥ 6) = 0.30 and 0.96), and `rand_distr`'s sampler (λ = 30); the rates
    /// interleaved in one call, so that every block mixes the paths. Chi-square per rate
    /// over 20 000 particles. A second round with `add` adds independent counts (λ doubles),
    /// and the returned sum of rates is theirs.
    #[test]
    fn poisson_counts_follow_each_rate() {
        let rates = [0.7, 4.5, 11.0, 30.0];
        let n = 80_000;
        let w: Vec<f64> = (0..n).map(|j| rates[j % 4]).collect();
        let mut rng = stream_rng(16, 0);
        let mut lanes = LaneRng::from_rng(&mut rng);
        let mut counts = vec![0usize; n];
        for (round, add) in [(1.0, false), (2.0, true)] {
            let (total, rate_sum) = dispatch(Simd::Auto, || {
                poisson_counts(&mut counts, &w, 1.0, add, &mut lanes, &mut rng)
            });
            let want: f64 = w.iter().sum();
            assert!(
                (rate_sum - want).abs() < 1e-9 * want,
                "{rate_sum} against {want}"
            );
            if !add {
                assert_eq!(total, counts.iter().sum::<usize>());
            }
            for (i, &rate) in rates.iter().enumerate() {
                let mut hist = vec![0usize; 200];
                for &c in counts.iter().skip(i).step_by(4) {
                    hist[c] += 1;
                }
                let (chi2, df) = pearson_pooled(&hist, |k| poisson_pmf(round * rate, k));
                assert!(
                    chi2 < chi2_quantile_999(df),
                    "λ = {}: χ² {chi2} on {df} df",
                    round * rate
                );
            }
        }
    }

    /// The inversion ends even for a uniform the rounded distribution function never
    /// passes, near the tail's end rather than running on.
    #[test]
    fn inversion_stops_at_the_top_of_the_unit_interval() {
        for lam in [0.5f64, 6.0, 12.0] {
            // The state after the vectorised terms: p_5 and F_5.
            let mut p = (-lam).exp();
            let mut f = p;
            for i in 1..TERMS {
                p *= lam / i as f64;
                f += p;
            }
            let k = poisson_rest(lam, 1.0 - f64::EPSILON / 2.0, p, f, &mut stream_rng(1, 0));
            assert!(k >= TERMS && (k as f64) < lam + 40.0, "λ = {lam}: {k}");
        }
    }

    /// The runs equal the draws written out one by one, the removed ones left out, after
    /// each particle's base copies; with removals in most blocks and in none.
    #[test]
    fn runs_leave_out_exactly_the_removed_draws() {
        let mut rng = stream_rng(17, 0);
        for (n, per_draw) in [(300usize, 0.3), (1000, 0.01), (5, 0.5)] {
            let counts: Vec<usize> = (0..n).map(|j| (j * 7 + 3) % 5).collect();
            let base = |j: usize| j % 3;
            let t: usize = counts.iter().sum();
            let mut removed: Vec<usize> =
                (0..t).filter(|_| rng.random::<f64>() < per_draw).collect();
            let mut want = Vec::new();
            let mut draw = 0;
            for (j, &c) in counts.iter().enumerate() {
                want.extend(std::iter::repeat_n(j, base(j)));
                for _ in 0..c {
                    if removed.binary_search(&draw).is_err() {
                        want.push(j);
                    }
                    draw += 1;
                }
            }
            removed.push(usize::MAX);
            let mut out = vec![usize::MAX; want.len()];
            write_runs::<4>(&counts, &removed, &base, 0, &mut out);
            let mut out8 = vec![usize::MAX; want.len()];
            write_runs::<8>(&counts, &removed, &base, 0, &mut out8);
            assert_eq!(out8, want, "N = {n}");
            assert_eq!(out, want, "N = {n}");
        }
    }
}
