//! The Poisson machinery of the O(N) multinomial draws: counts with a rate per particle
//! (multinomial and residual resampling), the uniformly chosen draws removed when
//! conditioning a Poisson total, and the runs of ancestors they leave.
//! The counts have an AVX-512 twin in [`avx512`].

mod avx512;

use super::counts::Counts;
use super::offspring::{Runs, SCAN};
use crate::simd::avx512::Avx512;
use crate::simd::math::{exp_fma_lanes, floor_index, unit_from_bits};
use crate::simd::{LANES, LaneRng, Simd, dispatch, set_bits};
use rand::{Rng, RngExt};
use rand_distr::{Distribution, Poisson};

/// The per-thread buffers of the Poisson draws, reused from call to call: every call
/// overwrites what it reads, and a buffer grows only when a call's random totals need more
/// than any call before (rarely, and by doubling; see [`distinct_sorted`]).
#[derive(Debug)]
pub(crate) struct DrawBuffers {
    /// Each particle's count.
    pub(crate) counts: Counts,
    /// The counts of a round that tops a short total up, before they join `counts`.
    pub(crate) extra: Counts,
    /// The draws removed when conditioning on the total, then `usize::MAX`.
    pub(crate) removed: Vec<usize>,
    /// One bit per draw: which have been chosen for removal.
    pub(crate) seen: Vec<u64>,
}

impl DrawBuffers {
    pub(crate) const fn new() -> Self {
        DrawBuffers {
            counts: Counts::new(),
            extra: Counts::new(),
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

/// Standard deviations of a Poisson total by which a round overshoots its target.
pub(crate) const OVERSHOOT: f64 = 3.0;

/// The mean total of a round of Poisson counts that must bring `d` more draws: `d` plus
/// [`OVERSHOOT`] standard deviations, so that it falls short about once in a thousand
/// rounds, and the surplus to remove (about `3√d`) costs little.
pub(crate) fn round_mean(d: f64) -> f64 {
    d + OVERSHOOT * d.sqrt() + 1.0
}

/// Rates above this are drawn by `rand_distr`'s exact sampler (its PTRS rejection, O(1)
/// whatever the rate) instead of by inversion, whose length grows with the rate.
pub(crate) const RATE_INVERT: f64 = 12.0;

/// A cap on one count, far above any that resampling into memory can ask for.
const MAX_COUNT: usize = 1 << 40;

/// The last term of an inversion: for `λ ≤ 12` the sum stops moving long before (its terms
/// fall below 2⁻⁵³ of it from about the 50th), and `P(N > 127) < 10⁻⁶⁰`.
pub(crate) const MAX_TERM: usize = 127;

/// `1/i!`, `i = 0 … MAX_TERM`, by repeated division (each within `i` roundings).
pub(crate) static INV_FACTORIAL: [f64; MAX_TERM + 1] = {
    let mut t = [1.0; MAX_TERM + 1];
    let mut i = 1;
    while i <= MAX_TERM {
        t[i] = t[i - 1] / i as f64;
        i += 1;
    }
    t
};

/// How a particle's Poisson rate comes from its weight `w`.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Rates {
    /// `λ = a·w`, or 0 where that is negative, zero or NaN: multinomial resampling's
    /// `μ·W_j`.
    Scaled(f64),
    /// `λ = (x − ⌊x⌋)·b` with `x = a·w`: residual resampling's residual `M·W_j − ⌊M·W_j⌋`,
    /// times the round's rate and normalisation `b`. For weights in [0, 1] and `a < 2⁵¹`.
    Residuals { a: f64, b: f64 },
}

impl Rates {
    /// The rate of weight `w`.
    #[inline(always)]
    pub(crate) fn of(self, w: f64) -> f64 {
        match self {
            Rates::Scaled(a) => rate_of(a * w),
            Rates::Residuals { a, b } => {
                let x = a * w;
                (x - floor_index(x).1) * b
            }
        }
    }

    /// The terms of the inversion compared on every particle for these rates; the particles
    /// of a group of eight still above the last continue term by term (see
    /// [`poisson_counts`]). Eight suit multinomial rates around 1 with a tail to 5, the
    /// benchmark's weights: with six, a quarter of the groups continued, and the
    /// mispredicted exits cost more than two terms more for everyone (eight terms count
    /// 1.3× faster than six; nine gain nothing). Residual rates are at most about 1, where
    /// four leave `P(N ≥ 4) < 1.9 %` per particle; three or five terms are 3–8 % slower.
    /// The single-precision AVX-512 counts measure the same optimum.
    pub(crate) const fn terms(self) -> usize {
        match self {
            Rates::Scaled(_) => 8,
            Rates::Residuals { .. } => 4,
        }
    }
}

/// What a pass of [`poisson_counts`] found besides the counts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Tally {
    /// The sum of the counts (saturating).
    pub(crate) total: usize,
    /// The sum of the rates, in eight partial sums (lane `j mod 8` of each block of 64 into
    /// sum `j mod 8`, in order).
    pub(crate) rates: f64,
    /// For [`Rates::Residuals`]: the sum of the floors `⌊a·w_j⌋`, exact for weights in
    /// [0, 1] (integers below 2⁵³ in any order); 0 otherwise.
    pub(crate) floors: f64,
    /// For [`Rates::Residuals`]: whether every weight lies in [0, 1] (no NaN), which the
    /// floors and rates assume; `true` otherwise.
    pub(crate) clean: bool,
}

/// `counts[j] ←` a Poisson(`λ_j`) count, `λ_j` from `w_j` by `rates` (see [`Rates`]),
/// independent across particles; with residual rates, also the runs' bytes
/// ([`Counts::runs`]). Returns the sums and the check of the weights (see [`Tally`]): for
/// residual resampling, a first round that can start before the floors are known reads
/// the weights once.
///
/// Inversion of one lane uniform `u` per particle (a lane step per 64 particles): the count
/// is the number of `i ≥ 0` with `U ≥ S_i`, where `U = u·e^λ` and `S_i = Σ_{k ≤ i} λ^k/k!`,
/// which is `u ≥ P(N ≤ i)` multiplied through by `e^λ`. The partial sums take one multiply
/// (`λ^i = λ^{i−1}·λ`) and one fused multiply-add (`S_i = λ^i·(1/i!) + S_{i−1}`) per term,
/// and no division: `e^λ` comes once per particle from [`exp_fma`](crate::simd::math::exp_fma).
/// The first [`Rates::terms`] are compared on every particle; a group of eight particles some of
/// which are still at or above the last sum continues a term at a time until none is, a
/// particle stopping where `U < S_i`, or where the sum no longer moves past the mode
/// (`i > λ`, `S_i = S_{i−1}`: the tail left is below 2⁻⁵² and `U` sits in it only through
/// rounding). Rates above [`RATE_INVERT`] are drawn by `rand_distr` on `rng`, particle by
/// particle in order. Exact up to the rounding of the sums (a few ulp of each probability).
///
/// On a CPU with AVX-512 (and `simd` [`Simd::Auto`]) the twin in `avx512` runs: the
/// inversion in single precision, sixteen particles to a register, each count certified
/// against this one's sums or redone with its operations. Otherwise the code below runs,
/// compiled by [`dispatch`]. Both give the same counts (tested).
pub(crate) fn poisson_counts<R: Rng + ?Sized>(
    simd: Simd,
    counts: &mut Counts,
    w: &[f64],
    rates: Rates,
    lanes: &mut LaneRng,
    rng: &mut R,
) -> Tally {
    counts.reset(w.len());
    if let Some(cpu) = Avx512::get(simd) {
        return avx512::poisson_counts(cpu, counts, w, rates, lanes, rng);
    }
    match rates.terms() {
        8 => dispatch(
            simd,
            #[inline(always)]
            || poisson_counts_portable::<8, R>(counts, w, rates, lanes, rng),
        ),
        _ => dispatch(
            simd,
            #[inline(always)]
            || poisson_counts_portable::<4, R>(counts, w, rates, lanes, rng),
        ),
    }
}

/// The portable body of [`poisson_counts`].
#[inline(always)]
fn poisson_counts_portable<const T: usize, R: Rng + ?Sized>(
    counts: &mut Counts,
    w: &[f64],
    rates: Rates,
    lanes: &mut LaneRng,
    rng: &mut R,
) -> Tally {
    let mut total = 0usize;
    let mut sums = [0.0f64; 8];
    let (mut floor_sum, mut outside) = (0.0, false);
    let mut bits = [0u64; LANES];
    let mut lam = [0.0f64; LANES];
    let mut k = [0u64; LANES];
    let floors = match rates {
        Rates::Residuals { a, .. } => {
            // Every byte is written below.
            counts.runs.resize(w.len(), 0);
            Some(a)
        }
        Rates::Scaled(_) => None,
    };
    for (b, wb) in w.chunks(LANES).enumerate() {
        let (j0, len) = (b * LANES, wb.len());
        lanes.step(&mut bits);
        if len < LANES {
            lam.fill(0.0);
        }
        for (l, &w) in lam.iter_mut().zip(wb) {
            *l = rates.of(w);
        }
        for l8 in lam.chunks_exact(8) {
            for (r, l) in sums.iter_mut().zip(l8) {
                *r += l;
            }
        }
        let escaped = poisson_block::<T>(&lam, &bits, &mut k);
        for (c, &k) in counts.small[j0..j0 + len].iter_mut().zip(&k) {
            *c = k as u8;
        }
        total += k[..len].iter().sum::<u64>() as usize;
        let escaped = escaped & (u64::MAX >> (LANES - len));
        if let Some(a) = floors {
            // The floors and counts as the AVX-512 twin forms them, saturated at 255.
            let runs = counts.runs[j0..j0 + len].iter_mut();
            for (q, (r, (&w, &k))) in runs.zip(wb.iter().zip(&k)).enumerate() {
                let (f, ff) = floor_index(a * w);
                floor_sum += ff;
                outside |= !(0.0..=1.0).contains(&w);
                let run = (f.min(255) as u64 + k).min(255);
                *r = if escaped >> q & 1 == 0 {
                    run as u8
                } else {
                    255
                };
            }
        }
        total = total.saturating_add(escape(counts, escaped, j0, &lam, rng));
    }
    counts.runs_set = floors.is_some();
    Tally {
        total,
        rates: sums.iter().sum(),
        floors: floor_sum,
        clean: !outside,
    }
}

/// The rate of a scaled weight `x`: `x`, or 0 where `x` is negative, zero or NaN (so that no
/// NaN reaches the inversion).
#[inline(always)]
pub(crate) fn rate_of(x: f64) -> f64 {
    if x > 0.0 { x } else { 0.0 }
}

/// The inversion counts of one block, `k[q]` for rate `lam[q]` and draw `bits[q]`, and the
/// mask of the lanes whose rate is above [`RATE_INVERT`] (their `k` is 0, for [`escape`]).
#[inline(always)]
pub(super) fn poisson_block<const T: usize>(
    lam: &[f64; LANES],
    bits: &[u64; LANES],
    k: &mut [u64; LANES],
) -> u64 {
    let e = exp_fma_lanes(*lam);
    let u: [f64; LANES] = std::array::from_fn(|q| unit_from_bits(bits[q]) * e[q]);
    let mut escaped = 0u64;
    for (q, &l) in lam.iter().enumerate() {
        escaped |= u64::from(l > RATE_INVERT) << q;
    }
    // Eight lanes at a time through all the terms, so that they stay in registers.
    for (g, ((k, lam), u)) in k
        .chunks_exact_mut(8)
        .zip(lam.chunks_exact(8))
        .zip(u.chunks_exact(8))
        .enumerate()
    {
        let k: &mut [u64; 8] = k.try_into().expect("eight lanes");
        let lam: &[f64; 8] = lam.try_into().expect("eight lanes");
        let u: &[f64; 8] = u.try_into().expect("eight lanes");
        let mut pw = *lam;
        let mut s: [f64; 8] = std::array::from_fn(|l| 1.0 + lam[l]);
        let mut ge: [bool; 8] = std::array::from_fn(|l| u[l] >= s[l]);
        *k = std::array::from_fn(|l| u64::from(u[l] >= 1.0));
        for &c in &INV_FACTORIAL[2..T] {
            for l in 0..8 {
                k[l] += u64::from(ge[l]);
                pw[l] *= lam[l];
                s[l] = pw[l].mul_add(c, s[l]);
                ge[l] = u[l] >= s[l];
            }
        }
        let mut more = 0u8;
        for l in 0..8 {
            k[l] += u64::from(ge[l]);
            more |= u8::from(ge[l]) << l;
        }
        more &= !((escaped >> (8 * g)) as u8);
        if more != 0 {
            continue_terms(T, k, lam, u, pw, s, more);
        }
    }
    for q in set_bits(escaped) {
        k[q] = 0;
    }
    escaped
}

/// The inversion continued from term `from` for the lanes in `more`, which are at or above
/// the sum `s` (`pw` the last power), until none is (see [`poisson_counts`]).
#[cold]
#[inline(never)]
fn continue_terms(
    from: usize,
    k: &mut [u64; 8],
    lam: &[f64; 8],
    u: &[f64; 8],
    mut pw: [f64; 8],
    mut s: [f64; 8],
    mut more: u8,
) {
    // A slice's own iterator: in a cold function (optimised for size) `skip`'s `next`
    // stayed a call.
    for (&c, i) in INV_FACTORIAL[from..].iter().zip(from..) {
        if more == 0 {
            break;
        }
        for l in 0..8 {
            pw[l] *= lam[l];
            let next = pw[l].mul_add(c, s[l]);
            let go = u[l] >= next && !(i as f64 > lam[l] && next == s[l]);
            let go = go && more & (1 << l) != 0;
            s[l] = next;
            k[l] += u64::from(go);
            more = (more & !(1 << l)) | (u8::from(go) << l);
        }
    }
}

/// The counts of the lanes in `escaped` (rates above [`RATE_INVERT`]), drawn by
/// `rand_distr` on `rng` in lane order into `counts` at `j0 + q`; returns their sum.
#[inline(always)]
pub(crate) fn escape<R: Rng + ?Sized>(
    counts: &mut Counts,
    escaped: u64,
    j0: usize,
    lam: &[f64],
    rng: &mut R,
) -> usize {
    let mut total = 0usize;
    for q in set_bits(escaped) {
        let c = large_rate(lam[q], rng);
        counts.set(j0 + q, c);
        total = total.saturating_add(c);
    }
    total
}

/// A Poisson(`lam`) count for a rate above [`RATE_INVERT`]. Weights far outside the
/// contract can make rates of any size (the caller then normalises and draws again): the
/// count is capped so that no sum of counts overflows.
#[cold]
fn large_rate<R: Rng + ?Sized>(lam: f64, rng: &mut R) -> usize {
    Poisson::new(lam).map_or(0, |d| (d.sample(rng) as usize).min(MAX_COUNT))
}

/// The copies each particle gets before its kept draws in [`write_runs`]: residual
/// resampling's floors `⌊M·W_j⌋` ([`Floors`]), or none (multinomial, [`NoBases`]).
pub(crate) trait Bases {
    /// Whether every base is 0, known when the writer is compiled: the runs are then the
    /// counts, and a block sums one array of bytes, not two.
    const NONE: bool;
    /// Particle `j`'s base.
    fn of(&self, j: usize) -> usize;
    /// Each particle's base plus its count as a byte, 255 for 255 up (see [`Counts::runs`]),
    /// if `counts` has them.
    fn runs<'c>(&self, counts: &'c Counts) -> Option<&'c [u8]>;
}

/// No base copies: every particle's copies are its kept draws.
pub(crate) struct NoBases;

impl Bases for NoBases {
    const NONE: bool = true;
    #[inline(always)]
    fn of(&self, _: usize) -> usize {
        0
    }
    #[inline(always)]
    fn runs<'c>(&self, counts: &'c Counts) -> Option<&'c [u8]> {
        Some(&counts.small)
    }
}

/// Base copies given per particle by a function.
pub(crate) struct Floors<F>(pub(crate) F);

impl<F: Fn(usize) -> usize> Bases for Floors<F> {
    const NONE: bool = false;
    #[inline(always)]
    fn of(&self, j: usize) -> usize {
        (self.0)(j)
    }
    #[inline(always)]
    fn runs<'c>(&self, counts: &'c Counts) -> Option<&'c [u8]> {
        counts.runs()
    }
}

/// Particle `j`'s base copies (`base.of(j)`) and kept draws (its count less the draws
/// `removed`, an ascending list of indices among all the counted draws in particle order,
/// then `usize::MAX`) as one run of copies of `first + j` in `out`, written `W` at a time
/// (see [`Runs`]). Boundaries are computed a block at a time; a block that holds a removal (one
/// in about every `√M/3` particles) also finds the particle of each removal.
///
/// A full block whose runs end at least `W` outputs before the end of `out` writes them with
/// no clamp and no end test per run (as `offspring::walk` does). The writer stays on the AVX2
/// copy on a CPU with AVX-512: compiled for AVX-512 (one store of eight copies), it ran
/// multinomial resampling no faster and residual resampling 15–30 % slower, and once it
/// visited only the particles with copies, multinomial 19 % slower.
pub(crate) fn write_runs<const W: usize>(
    simd: Simd,
    counts: &Counts,
    removed: &[usize],
    base: &impl Bases,
    first: usize,
    out: &mut [usize],
) {
    dispatch(
        simd,
        #[inline(always)]
        || {
            if u32::try_from(out.len()).is_ok() {
                let mut writer = RunWriter::<W, true>::new(counts, removed, first);
                while writer.clean_block(base, out) || writer.block(base, out) {}
            } else {
                let mut writer = RunWriter::<W, false>::new(counts, removed, first);
                while writer.block(base, out) {}
            }
        },
    );
}

/// The state of [`write_runs`] between blocks of [`SCAN`] particles, with `SMALL` when
/// `M < 2³²` (see [`Runs`]).
struct RunWriter<'a, const W: usize, const SMALL: bool> {
    counts: &'a Counts,
    removed: &'a [usize],
    first: usize,
    runs: Runs<W>,
    /// The next block's first particle.
    j0: usize,
    /// Draws counted before the block.
    drawn: usize,
    /// Outputs written before the block.
    kept: usize,
    /// The next removal.
    x: usize,
    /// The next entry of `counts.big`.
    big: usize,
}

impl<'a, const W: usize, const SMALL: bool> RunWriter<'a, W, SMALL> {
    fn new(counts: &'a Counts, removed: &'a [usize], first: usize) -> Self {
        RunWriter {
            counts,
            removed,
            first,
            runs: Runs::new(),
            j0: 0,
            drawn: 0,
            kept: 0,
            x: 0,
            big: 0,
        }
    }

    /// Write the next block's runs if it is a full one with no big count or run, whose runs
    /// end at least `W` outputs before the end of `out`, and the counting pass left the runs
    /// ([`Bases::runs`]); whether it did. Nothing changes otherwise. The checks are
    /// vectorised, and each run is written with no clamp and no end test, its boundary
    /// summed as it goes (no prefix pass). At N = 10⁴ most blocks hold a removal (about
    /// `3√M` of them among `M/64` blocks), so removals are taken here too.
    ///
    /// The runs come from their bytes, not from the bases: for residual resampling the
    /// writer then makes no pass over the weights for the floors (nor copies out a block
    /// of `usize` copies): 4 % faster at N = 10⁶, 10 % at 10⁴.
    #[inline(always)]
    fn clean_block<B: Bases>(&mut self, base: &B, out: &mut [usize]) -> bool {
        let j0 = self.j0;
        let Some(bytes) = self.counts.small.get(j0..j0 + SCAN) else {
            return false;
        };
        let bytes: &[u8; SCAN] = bytes.try_into().expect("a full block");
        if !SMALL {
            return false;
        }
        // Each particle's run before removals, from its byte: no pass over the weights for
        // residual resampling's floors.
        let Some(runs) = base.runs(self.counts) else {
            return false;
        };
        let runs: &[u8; SCAN] = runs[j0..j0 + SCAN].try_into().expect("a full block");
        // `some`: the particles with copies, before removals (a removal can leave one with
        // none: its `W` stores are then overwritten by the next run).
        let (draws, big, nonzero) = byte_summary(bytes);
        let (mut total, long, some) = if B::NONE {
            (draws, big, nonzero)
        } else {
            byte_summary(runs)
        };
        if big || long {
            return false;
        }
        let mut kb: [usize; SCAN] = std::array::from_fn(|q| usize::from(runs[q]));
        let end = self.drawn + draws;
        let mut x = self.x;
        if self.removed[x] < end {
            // Each removal comes off the particle whose draws hold it: the first whose draws
            // end above it, found by counting the ends at or below it.
            let mut ends = [0usize; SCAN];
            let mut drawn = self.drawn;
            for (e, &c) in ends.iter_mut().zip(bytes) {
                drawn += usize::from(c);
                *e = drawn;
            }
            while self.removed[x] < end {
                let r = self.removed[x];
                kb[ends.iter().filter(|&&e| e <= r).count()] -= 1;
                total -= 1;
                x += 1;
            }
        }
        if self.kept.saturating_add(total).saturating_add(W) > out.len() {
            return false;
        }
        // `kept < M < 2³²` here, so 32 bits hold every position (see `Runs`). Only the
        // particles with copies are visited: most have none (on the bench's weights about
        // 60 % for multinomial), and each visit stores `W` copies.
        let mut pos = self.kept as u32 as usize;
        for q in set_bits(some) {
            let k = kb[q];
            let a = self.first + j0 + q;
            out[pos..pos + W].copy_from_slice(&[a; W]);
            if k > W {
                out[pos + W..pos + k].fill(a);
            }
            pos += k;
        }
        self.x = x;
        self.drawn = end;
        self.kept += total;
        self.runs.skip_to(self.kept);
        self.j0 += SCAN;
        true
    }

    /// Write the next block's runs; whether there is more to write.
    #[inline(always)]
    fn block(&mut self, base: &impl Bases, out: &mut [usize]) -> bool {
        let j0 = self.j0;
        let len = SCAN.min(self.counts.small.len() - j0);
        if len == 0 {
            return false;
        }
        // Before a block, fewer than `M` outputs are written (else the writer has stopped),
        // so a block without big counts adds at most `64·(M + 254)` to the sums: below
        // `usize::MAX` for any `M` that fits in memory, and plain additions (which vectorise)
        // do. With a big count, saturating ones (a serial chain of compare-and-branch).
        let plain = !self.counts.small[j0..j0 + len].contains(&Counts::BIG) && out.len() < 1 << 48;
        if plain {
            self.block_with::<true>(len, base, out)
        } else {
            self.block_with::<false>(len, base, out)
        }
    }

    /// [`block`](Self::block), with plain additions when `PLAIN`, saturating ones otherwise.
    #[inline(always)]
    fn block_with<const PLAIN: bool>(
        &mut self,
        len: usize,
        base: &impl Bases,
        out: &mut [usize],
    ) -> bool {
        let add = |a: usize, b: usize| if PLAIN { a + b } else { a.saturating_add(b) };
        let j0 = self.j0;
        let block = &self.counts.small[j0..j0 + len];
        let mut cb = [0usize; SCAN];
        let cb = &mut cb[..len];
        for (c, &s) in cb.iter_mut().zip(block) {
            *c = usize::from(s);
        }
        if !PLAIN {
            for c in cb.iter_mut().filter(|c| **c == usize::from(Counts::BIG)) {
                self.big += 1;
                *c = self.counts.big[self.big - 1].1;
            }
        }
        let mut kb = [0usize; SCAN];
        let kb = &mut kb[..len];
        for (q, (k, &c)) in kb.iter_mut().zip(cb.iter()).enumerate() {
            *k = add(base.of(j0 + q), c);
        }
        let drawn = if PLAIN {
            cb.iter().sum()
        } else {
            cb.iter().fold(0, |a: usize, &c| a.saturating_add(c))
        };
        let end = self.drawn.saturating_add(drawn);
        let clean = self.removed[self.x] >= end;
        if !clean {
            // Each removal comes off the particle whose draws hold it: the first whose draws
            // end above it, found by counting the ends at or below it (a vectorised count
            // per removal, not a loop with a branch per particle).
            let mut ends = [0usize; SCAN];
            let ends = &mut ends[..len];
            let mut drawn = self.drawn;
            for (e, &c) in ends.iter_mut().zip(cb.iter()) {
                drawn = add(drawn, c);
                *e = drawn;
            }
            while self.removed[self.x] < end {
                let r = self.removed[self.x];
                kb[ends.iter().filter(|&&e| e <= r).count()] -= 1;
                self.x += 1;
            }
        }
        self.drawn = end;
        for k in kb.iter_mut() {
            self.kept = add(self.kept, *k);
            *k = self.kept;
        }
        if clean && len == SCAN && self.runs.fits(kb, out.len()) {
            self.runs.push_each::<true, true>(out, self.first + j0, kb);
        } else {
            self.runs
                .push_each::<SMALL, false>(out, self.first + j0, kb);
        }
        self.j0 += len;
        !self.runs.is_full(out.len())
    }
}

/// The sum of a block's counts, whether one of them is [`Counts::BIG`], and which are not
/// zero (bit `q` for count `q`), sixteen bytes to an SSE2 register (x86-64's baseline): a
/// sum of absolute differences, two byte compares and a byte mask each. LLVM had compiled
/// the mask, written per byte, from the bytes widened to 64 bits: sixteen compares, sixteen
/// masks and an OR-reduction per block.
#[inline(always)]
fn byte_summary(bytes: &[u8; SCAN]) -> (usize, bool, u64) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: the intrinsics need SSE2 only, which every x86-64 CPU has (it is part of the
    // baseline); they read and write nothing but their operands.
    #[allow(unsafe_code)]
    unsafe {
        use std::arch::x86_64::*;
        let zero = _mm_setzero_si128();
        let (mut sums, mut big, mut nonzero) = (zero, zero, 0u64);
        let v: [__m128i; SCAN / 16] = bytemuck::cast(*bytes);
        for (i, x) in v.into_iter().enumerate() {
            sums = _mm_add_epi64(sums, _mm_sad_epu8(x, zero));
            big = _mm_or_si128(big, _mm_cmpeq_epi8(x, _mm_set1_epi8(-1)));
            let zeros = _mm_movemask_epi8(_mm_cmpeq_epi8(x, zero)) as u64;
            nonzero |= (!zeros & 0xffff) << (16 * i);
        }
        let sums: [u64; 2] = bytemuck::cast(sums);
        (
            (sums[0] + sums[1]) as usize,
            _mm_movemask_epi8(big) != 0,
            nonzero,
        )
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let (sum, big) = byte_sum(bytes);
        let mut nonzero = 0u64;
        for (q, &c) in bytes.iter().enumerate() {
            nonzero |= u64::from(c != 0) << q;
        }
        (sum, big, nonzero)
    }
}

/// The sum of a block's counts, and whether one of them is [`Counts::BIG`], eight bytes to
/// a word: LLVM compiled the same over the bytes themselves as a chain of 64 byte compares
/// and conditional moves.
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
#[inline(always)]
fn byte_sum(bytes: &[u8; SCAN]) -> (usize, bool) {
    const ONES: u64 = u64::from_le_bytes([1; 8]);
    const LOW: u64 = u64::from_le_bytes([0xff, 0, 0xff, 0, 0xff, 0, 0xff, 0]);
    let words: [u64; SCAN / 8] = bytemuck::cast(*bytes);
    let (mut pairs, mut big) = (0u64, 0u64);
    for x in words {
        // Four 16-bit sums of byte pairs (each at most 510), accumulated over the eight
        // words (at most 4080 each).
        pairs += (x & LOW) + ((x >> 8) & LOW);
        // A byte of `x` is 0xff exactly where the same byte of `!x` is zero.
        let y = !x;
        big |= y.wrapping_sub(ONES) & !y & (ONES << 7);
    }
    let sum =
        (pairs & 0xffff) + ((pairs >> 16) & 0xffff) + ((pairs >> 32) & 0xffff) + (pairs >> 48);
    (sum as usize, big != 0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mc::{PfRng, stream_rng};
    use crate::simd::Simd;
    use crate::testing::{chi2_quantile_999, pearson_pooled, poisson_pmf};

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

    /// first gives Poisson(2λ), and the returned sum of rates is theirs.
    #[test]
    fn poisson_counts_follow_each_rate() {
        let rates = [0.7, 4.5, 11.0, 30.0];
        let n = 80_000;
        let w: Vec<f64> = (0..n).map(|j| rates[j % 4]).collect();
        for simd in [Simd::Auto, Simd::Avx2, Simd::Portable] {
            let mut rng = stream_rng(16, 0);
            let mut lanes = LaneRng::from_rng(&mut rng);
            let (mut counts, mut extra) = (Counts::new(), Counts::new());
            for round in [1.0, 2.0] {
                let into = if round == 1.0 {
                    &mut counts
                } else {
                    &mut extra
                };
                let Tally {
                    total,
                    rates: rate_sum,
                    ..
                } = poisson_counts(simd, into, &w, Rates::Scaled(1.0), &mut lanes, &mut rng);
                assert_eq!(total, into.to_vec().iter().sum::<usize>());
                let want: f64 = w.iter().sum();
                assert!(
                    (rate_sum - want).abs() < 1e-9 * want,
                    "{rate_sum} against {want}"
                );
                if round == 2.0 {
                    counts.add(&extra);
                }
                let all = counts.to_vec();
                for (i, &rate) in rates.iter().enumerate() {
                    let mut hist = vec![0usize; 200];
                    for &c in all.iter().skip(i).step_by(4) {
                        hist[c] += 1;
                    }
                    let (chi2, df) = pearson_pooled(&hist, |k| poisson_pmf(round * rate, k));
                    assert!(
                        chi2 < chi2_quantile_999(df),
                        "{simd:?}, λ = {}: χ² {chi2} on {df} df",
                        round * rate
                    );
                }
            }
        }
    }

    /// Every kernel gives the same counts, totals and sums of rates, draw for draw: rates
    /// around the escape threshold and far beyond it (counts of `Counts::BIG` and more),
    /// zero, negative, NaN and infinite weights, groups that continue, and lengths that end
    /// inside a block or a group; and residual rates, from weights whose `M·W_j` fall on,
    /// just below and just above integers. Then the same lanes and generator go on alike.
    #[test]
    fn every_kernel_counts_the_same() {
        let specials = [
            0.0,
            -1.0,
            f64::NAN,
            f64::INFINITY,
            12.0,
            12.000_000_1,
            11.999_999,
            400.0,
            1e-300,
            6.5,
        ];
        for (case, n) in [1usize, 7, 63, 64, 65, 200, 1000, 4099]
            .into_iter()
            .enumerate()
        {
            let w: Vec<f64> = (0..n)
                .map(|j| match j % 13 {
                    0 => specials[(j / 13) % specials.len()],
                    r => (r as f64 / 2.6).powi(2),
                })
                .collect();
            let mf = n as f64;
            let residual: Vec<f64> = (0..n)
                .map(|j| match j % 5 {
                    0 => 3.0 / mf,
                    1 => (3.0 - 1e-12) / mf,
                    2 => (3.0 + 1e-12) / mf,
                    _ => ((j * 37 % 101) as f64 / 101.0).powi(3),
                })
                .collect();
            let run = |simd, w: &[f64], rates| {
                let mut rng = stream_rng(21, case as u64);
                let mut lanes = LaneRng::from_rng(&mut rng);
                let mut counts = Counts::new();
                let tally = poisson_counts(simd, &mut counts, w, rates, &mut lanes, &mut rng);
                let mut after = [0u64; LANES];
                lanes.step(&mut after);
                let runs = counts.runs().map(<[u8]>::to_vec);
                // The floors' sum means nothing once a weight lies outside [0, 1].
                let floors = tally.clean.then_some(tally.floors);
                let tally = (tally.total, tally.rates.to_bits(), floors, tally.clean);
                (counts.to_vec(), runs, tally, after, rng.next_u64())
            };
            // Residual weights with one outside [0, 1], which every kernel reports.
            let mut outside = residual.clone();
            outside[n / 2] = [f64::NAN, -1e-300, 1.5][case % 3];
            for (w, rates) in [
                (&w, Rates::Scaled(1.3)),
                (&residual, Rates::Residuals { a: mf, b: 1.7 }),
                (&outside, Rates::Residuals { a: mf, b: 1.7 }),
            ] {
                let auto = run(Simd::Auto, w, rates);
                assert_eq!(auto, run(Simd::Avx2, w, rates), "N = {n}, {rates:?}");
                assert_eq!(auto, run(Simd::Portable, w, rates), "N = {n}, {rates:?}");
                let residuals = matches!(rates, Rates::Residuals { .. });
                let inside = w.iter().all(|w| (0.0..=1.0).contains(w));
                assert_eq!(auto.2.3, !residuals || inside, "N = {n}, {rates:?}");
                if inside {
                    let floors: f64 = w.iter().map(|&w| (mf * w).floor()).sum();
                    let want = if residuals { floors } else { 0.0 };
                    assert_eq!(auto.2.2, Some(want), "N = {n}");
                }
                // Residual rates leave each particle's floor plus count, saturated at 255
                // (floors past 255 among these weights once N passes 255).
                let want = (residuals && inside).then(|| {
                    let floors = w.iter().map(|&w| floor_index(mf * w).0);
                    let runs = floors.zip(&auto.0).map(|(f, &c)| (f + c).min(255) as u8);
                    runs.collect::<Vec<u8>>()
                });
                if inside {
                    assert_eq!(auto.1, want, "N = {n}, {rates:?}");
                }
            }
            let big = run(Simd::Auto, &w, Rates::Scaled(1.3)).0;
            assert!(big.iter().any(|&c| c >= usize::from(Counts::BIG)) || n < 13 * 8);
        }
    }

    /// The block sums by words and by registers equal the plain ones, find a big count
    /// wherever it is, and the registers' mask marks exactly the counts that are not zero
    /// (counts mostly zero, as multinomial's are, and a count at each end of a block).
    #[test]
    fn byte_sums_and_big_counts() {
        let mut rng = stream_rng(22, 0);
        for case in 0..3000 {
            let mut bytes: [u8; SCAN] = std::array::from_fn(|_| match case % 3 {
                0 => (rng.next_u64() % 255) as u8,
                _ => (rng.next_u64() % 4).saturating_sub(2) as u8,
            });
            if case % 5 == 0 {
                bytes[case % SCAN] = Counts::BIG;
            }
            if case % 7 == 0 {
                bytes = [254; SCAN];
            }
            if case % 11 == 0 {
                bytes = [0; SCAN];
                bytes[(case / 11) % 2 * (SCAN - 1)] = 1;
            }
            let want: usize = bytes.iter().map(|&c| usize::from(c)).sum();
            let big = bytes.contains(&Counts::BIG);
            let nonzero = (0..SCAN)
                .filter(|&q| bytes[q] != 0)
                .fold(0u64, |m, q| m | 1 << q);
            assert_eq!(byte_sum(&bytes), (want, big), "{bytes:?}");
            assert_eq!(byte_summary(&bytes), (want, big, nonzero), "{bytes:?}");
        }
    }

    /// The inversion ends, near the tail's end, for a uniform the rounded sums never pass.
    #[test]
    fn inversion_stops_at_the_top_of_the_unit_interval() {
        for lam in [0.5f64, 6.0, 12.0] {
            let lanes = [lam; 8];
            let u = [(1.0 - f64::EPSILON / 2.0) * crate::simd::math::exp_fma(lam); 8];
            let mut pw = lanes;
            let mut s = [1.0 + lam; 8];
            let mut k = [0u64; 8];
            for &c in &INV_FACTORIAL[2..8] {
                for l in 0..8 {
                    pw[l] *= lam;
                    s[l] = pw[l].mul_add(c, s[l]);
                }
            }
            continue_terms(8, &mut k, &lanes, &u, pw, s, 0xff);
            assert!(
                k.iter().all(|&k| (k as f64) < lam + 40.0),
                "λ = {lam}: {k:?}"
            );
        }
    }

    /// The runs equal the draws written out one by one, the removed ones left out, after
    /// each particle's base copies (or with none, where blocks visit only the particles
    /// whose count is not zero), on every kernel: with removals in most blocks, in few and
    /// in none (where full blocks take the unchecked runs), long runs, a big count, and
    /// counts of zero (one particle in five, and more after removals).
    #[test]
    fn runs_leave_out_exactly_the_removed_draws() {
        let mut rng = stream_rng(17, 0);
        for (n, per_draw) in [
            (300usize, 0.3),
            (1000, 0.01),
            (5, 0.5),
            (1000, 0.0),
            (130, 0.0),
        ] {
            // Counts beyond one store of copies (11) and a big one (300).
            let counts: Vec<usize> = (0..n)
                .map(|j| match j {
                    100 => 300,
                    j if j % 17 == 0 => 11,
                    j => (j * 7 + 3) % 5,
                })
                .collect();
            for with_bases in [true, false] {
                let base = |j: usize| if with_bases { j % 3 } else { 0 };
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
                let mut packed = Counts::new();
                packed.reset(n);
                for (j, &c) in counts.iter().enumerate() {
                    packed.set(j, c);
                }
                // The runs before removals, as the counting passes leave them.
                let mut with_runs = packed.clone();
                with_runs.runs = (0..n)
                    .map(|j| (base(j) + counts[j]).min(255) as u8)
                    .collect();
                with_runs.runs_set = true;
                // Runs of four and of eight copies a store.
                fn write<B: Bases>(
                    simd: Simd,
                    counts: &Counts,
                    removed: &[usize],
                    bases: &B,
                    len: usize,
                ) -> [Vec<usize>; 2] {
                    let mut out = [vec![usize::MAX; len], vec![usize::MAX; len]];
                    write_runs::<4>(simd, counts, removed, bases, 0, &mut out[0]);
                    write_runs::<8>(simd, counts, removed, bases, 0, &mut out[1]);
                    out
                }
                for simd in [Simd::Auto, Simd::Avx2, Simd::Portable] {
                    // Bases from the runs' bytes where they are set, else from `base`.
                    for counts in [&packed, &with_runs] {
                        let runs = counts.runs().is_some();
                        let outs = if with_bases {
                            write(simd, counts, &removed, &Floors(base), want.len())
                        } else {
                            write(simd, counts, &removed, &NoBases, want.len())
                        };
                        for (out, w) in outs.iter().zip([4, 8]) {
                            assert_eq!(
                                *out, want,
                                "N = {n}, bases {with_bases}, runs {runs}, W = {w}, {simd:?}"
                            );
                        }
                    }
                }
            }
        }
    }
}
