//! Branch-free elementary functions for the vectorised kernels.
//!
//! [`exp_nonpositive`] is a table-driven `exp` (Tang 1989, the method of glibc's and
//! musl's `exp`, here with a 64-entry table) for the range the filter needs, `x ≤ 0`: the
//! reduction `x = (64k + j)·ln 2/64 + r`, `|r| ≤ ln 2/128`, with `ln 2` split in fdlibm's
//! two parts so that `k` and `j` cost no accuracy; then `e^x = 2^k · 2^{j/64} · e^r`, with
//! `2^{j/64}` from a table of correctly rounded doubles, `e^r − 1` from its Taylor
//! polynomial of degree 5 (truncation below 4·10⁻¹⁷ relative at `|r| ≤ ln 2/128`), and
//! `2^k` applied to the exponent bits. Its relative error against the platform's `f64::exp`
//! is below 2·2⁻⁵² on `[−708, 0]` (tested; at most 1.0·2⁻⁵² over 4·10⁶ random points).
//! Below −708 it returns 0 (a weight `e^{−708}` times the largest one, which no sum or
//! resampling step can see), including at `−∞`.
//!
//! It replaced fdlibm's rational approximation (whose division and degree-5 polynomial
//! in `r²` sit on one long dependency chain), being 29 % faster on its own (1.00 against
//! 1.40 ns per weight, 2048 weights in L1) and making the batch filter 5–7 % faster; the
//! table lookups are nearly half of its time (see `docs/performance.md`).

// fdlibm's split of ln 2, digit for digit.
#![allow(clippy::excessive_precision)]

pub(crate) const LN2_HI: f64 = 6.931_471_803_691_238_164_90e-1;
pub(crate) const LN2_LO: f64 = 1.908_214_929_270_587_700_02e-10;

/// `1.5·2⁵²`: adding it rounds a double of magnitude below 2⁵¹ to the nearest integer,
/// which then sits in the low bits of the sum's significand.
pub(crate) const ROUND_MAGIC: f64 = 6_755_399_441_055_744.0;

/// `e^x` for `x ≤ 0` (`−∞` included), branch-free; 0 below −708. See the module docs.
///
/// A NaN argument gives an unspecified value (the filter rejects NaN weights before).
#[inline(always)]
pub fn exp_nonpositive(x: f64) -> f64 {
    let [y] = exp_nonpositive_lanes([x]);
    y
}

/// [`exp_nonpositive`] of each of `L` values, each operation applied to every lane before
/// the next.
///
/// The evaluation is a chain of dependent operations, and the CPU's scheduler holds only a
/// few loop iterations of it, so a plain vectorised loop waits on latency. Written a step
/// at a time over many lanes, the steps of different lanes are independent instructions
/// side by side: the filter, which calls this on 64 lanes, is about 7 % faster for it.
/// Every lane performs the same
/// operations as the one-lane case, so the results are the same bits.
#[inline(always)]
pub fn exp_nonpositive_lanes<const L: usize>(x: [f64; L]) -> [f64; L] {
    // n = round(64x / ln 2) by the magic-number trick (no `round`, which is a libm call on
    // baseline x86-64); nf is n as a double; t keeps n's two's complement in its low bits,
    // so that j = n mod 64 is its low six bits and k = ⌊n/64⌋ the rest.
    let t = each::<L>(|i| x[i] * (64.0 / std::f64::consts::LN_2) + ROUND_MAGIC);
    let nf = each::<L>(|i| t[i] - ROUND_MAGIC);
    // |n| < 2¹⁷ on [−708, 0] and LN2_HI has 32 significant bits, so n·LN2_HI/64 is exact.
    let r = each::<L>(|i| (x[i] - nf[i] * (LN2_HI / 64.0)) - nf[i] * (LN2_LO / 64.0));
    let r2 = each::<L>(|i| r[i] * r[i]);
    // e^r − 1 = r + r²(1/2 + r/6) + r⁴(1/24 + r/120), in Estrin's form (a shorter chain).
    let p = each::<L>(|i| {
        let a = 0.5 + r[i] * (1.0 / 6.0);
        let b = 1.0 / 24.0 + r[i] * (1.0 / 120.0);
        r[i] + r2[i] * (a + r2[i] * b)
    });
    // 2^k · 2^{j/64}: k ≥ −1022 on [−708, 0], so adding k to the exponent stays normal.
    let s = each::<L>(|i| {
        let bits = t[i].to_bits();
        let k = (bits.wrapping_sub(ROUND_MAGIC.to_bits()) as i64) >> 6;
        f64::from_bits(EXP2_64THS[(bits & 63) as usize].wrapping_add((k as u64) << 52))
    });
    each(|i| {
        let y = s[i] + s[i] * p[i];
        if x[i] >= -708.0 { y } else { 0.0 }
    })
}

/// `2^{j/64}` for `j = 0 … 63`, each the double nearest the exact value (computed with
/// 60-digit decimal arithmetic; a test checks them against `exp2`).
pub(crate) const EXP2_64THS: [u64; 64] = [
    0x3ff0000000000000,
    0x3ff02c9a3e778061,
    0x3ff059b0d3158574,
    0x3ff0874518759bc8,
    0x3ff0b5586cf9890f,
    0x3ff0e3ec32d3d1a2,
    0x3ff11301d0125b51,
    0x3ff1429aaea92de0,
    0x3ff172b83c7d517b,
    0x3ff1a35beb6fcb75,
    0x3ff1d4873168b9aa,
    0x3ff2063b88628cd6,
    0x3ff2387a6e756238,
    0x3ff26b4565e27cdd,
    0x3ff29e9df51fdee1,
    0x3ff2d285a6e4030b,
    0x3ff306fe0a31b715,
    0x3ff33c08b26416ff,
    0x3ff371a7373aa9cb,
    0x3ff3a7db34e59ff7,
    0x3ff3dea64c123422,
    0x3ff4160a21f72e2a,
    0x3ff44e086061892d,
    0x3ff486a2b5c13cd0,
    0x3ff4bfdad5362a27,
    0x3ff4f9b2769d2ca7,
    0x3ff5342b569d4f82,
    0x3ff56f4736b527da,
    0x3ff5ab07dd485429,
    0x3ff5e76f15ad2148,
    0x3ff6247eb03a5585,
    0x3ff6623882552225,
    0x3ff6a09e667f3bcd,
    0x3ff6dfb23c651a2f,
    0x3ff71f75e8ec5f74,
    0x3ff75feb564267c9,
    0x3ff7a11473eb0187,
    0x3ff7e2f336cf4e62,
    0x3ff82589994cce13,
    0x3ff868d99b4492ed,
    0x3ff8ace5422aa0db,
    0x3ff8f1ae99157736,
    0x3ff93737b0cdc5e5,
    0x3ff97d829fde4e50,
    0x3ff9c49182a3f090,
    0x3ffa0c667b5de565,
    0x3ffa5503b23e255d,
    0x3ffa9e6b5579fdbf,
    0x3ffae89f995ad3ad,
    0x3ffb33a2b84f15fb,
    0x3ffb7f76f2fb5e47,
    0x3ffbcc1e904bc1d2,
    0x3ffc199bdd85529c,
    0x3ffc67f12e57d14b,
    0x3ffcb720dcef9069,
    0x3ffd072d4a07897c,
    0x3ffd5818dcfba487,
    0x3ffda9e603db3285,
    0x3ffdfc97337b9b5f,
    0x3ffe502ee78b3ff6,
    0x3ffea4afa2a490da,
    0x3ffefa1bee615a27,
    0x3fff50765b6e4540,
    0x3fffa7c1819e90d8,
];

/// `e^x` for `−708 ≤ x ≤ 709`, in fused multiply-adds: the `e^λ` of the Poisson inversion
/// in multinomial and residual resampling (`0 ≤ λ ≤ 12` there).
///
/// The reduction of [`exp_nonpositive`] with a 16-entry table, `x = (16k + j)·ln 2/16 + r`,
/// `|r| ≤ ln 2/32`, and `e^r − 1` from its Taylor polynomial of degree 7 (truncation below
/// 10⁻¹⁸ relative) in Estrin's form; every step is one `mul_add`, so the result is the same
/// bits on every path (see the module docs of [`simd`](super)). Sixteen entries (every
/// fourth of the 64-entry table) fit one pair of AVX-512 registers, where one permute looks
/// them up; the 64 entries took four permutes and three blends, and with the fused steps
/// the Poisson counts are 1.25× as fast. Within 2 ulp of the platform's `exp` on its range
/// (tested).
#[inline(always)]
#[cfg_attr(not(test), allow(dead_code))] // the one-lane form: the docs' and the tests' reference
pub(crate) fn exp_fma(x: f64) -> f64 {
    let [y] = exp_fma_lanes([x]);
    y
}

/// [`exp_fma`] of each of `L` values, each operation applied to every lane before the next
/// (see [`exp_nonpositive_lanes`] for why).
#[inline(always)]
pub(crate) fn exp_fma_lanes<const L: usize>(x: [f64; L]) -> [f64; L] {
    let mut v = x;
    exp_fma_in_place(&mut v, |_, y| y);
    v
}

/// `v[i] ← finish(v[i], exp_fma(v[i]))` for each lane: [`exp_fma_lanes`]' steps, written
/// in place because LLVM built a returned 64-lane array on the stack and copied it out with
/// `memcpy` in the batch filter's AVX2 copy (8 % of its time).
#[inline(always)]
fn exp_fma_in_place<const L: usize>(v: &mut [f64; L], finish: impl Fn(f64, f64) -> f64) {
    let x = &*v;
    let t = each::<L>(|i| x[i].mul_add(16.0 / std::f64::consts::LN_2, ROUND_MAGIC));
    let nf = each::<L>(|i| t[i] - ROUND_MAGIC);
    let r = each::<L>(|i| (-nf[i]).mul_add(LN2_LO / 16.0, (-nf[i]).mul_add(LN2_HI / 16.0, x[i])));
    // (e^r − 1)/r = a₀ + a₁r + … + a₆r⁶ in Estrin's form: three levels of fused steps
    // instead of Horner's six, so the dependent chain is half as long.
    let [a6, a5, a4, a3, a2, a1, a0] = EXP_TAYLOR;
    let r2 = each::<L>(|i| r[i] * r[i]);
    let r4 = each::<L>(|i| r2[i] * r2[i]);
    let p = each::<L>(|i| {
        let q0 = r[i].mul_add(a1, a0);
        let q1 = r[i].mul_add(a3, a2);
        let q2 = r[i].mul_add(a5, a4);
        let s0 = r2[i].mul_add(q1, q0);
        let s1 = r2[i].mul_add(a6, q2);
        r4[i].mul_add(s1, s0) * r[i]
    });
    for (i, v) in v.iter_mut().enumerate() {
        let bits = t[i].to_bits();
        let k = (bits.wrapping_sub(ROUND_MAGIC.to_bits()) as i64) >> 4;
        let s = f64::from_bits(EXP2_16THS[(bits & 15) as usize].wrapping_add((k as u64) << 52));
        *v = finish(*v, s.mul_add(p[i], s));
    }
}

/// [`exp_fma`] for `x ≤ 0`, and 0 below −708 (also at `−∞`), as [`exp_nonpositive`]: the
/// batch filter's weights relative to their maximum.
///
/// Fused steps and a table that one permute reads take about 20 AVX-512 operations per
/// eight weights, where [`exp_nonpositive`] takes about 31, since without fusing it must
/// round as its portable copy does: the batch filter is 6 % faster at N = 10⁴ with
/// AVX-512. The price is paid elsewhere: the AVX2 copy is 2 % slower, since its table
/// lookups are scalar loads whatever the table's size, and the portable copy's `mul_add`s
/// are calls to the C library, about 4× slower.
#[inline(always)]
pub(crate) fn exp_fma_nonpositive(x: f64) -> f64 {
    let mut v = [x];
    exp_fma_nonpositive_lanes(&mut v);
    v[0]
}

/// [`exp_fma_nonpositive`] of each of `L` values in place, a step at a time over the lanes.
#[inline(always)]
pub(crate) fn exp_fma_nonpositive_lanes<const L: usize>(v: &mut [f64; L]) {
    exp_fma_in_place(v, |x, y| if x >= -708.0 { y } else { 0.0 });
}

/// `1/7!, 1/6!, …, 1/2!, 1`: the coefficients, highest first, of `(e^r − 1)/r` in [`exp_fma`].
pub(crate) const EXP_TAYLOR: [f64; 7] = [
    1.0 / 5040.0,
    1.0 / 720.0,
    1.0 / 120.0,
    1.0 / 24.0,
    1.0 / 6.0,
    0.5,
    1.0,
];

/// `2^{j/16}`, `j = 0 … 15`: every fourth entry of [`EXP2_64THS`].
pub(crate) const EXP2_16THS: [u64; 16] = {
    let mut t = [0; 16];
    let mut j = 0;
    while j < 16 {
        t[j] = EXP2_64THS[4 * j];
        j += 1;
    }
    t
};

/// `[f(0), …, f(L − 1)]`: one step of a computation over lanes.
#[inline(always)]
fn each<const L: usize>(f: impl FnMut(usize) -> f64) -> [f64; L] {
    std::array::from_fn(f)
}

/// `⌈x⌉` for `−1 < x < 2⁵¹`, as an index, in float and integer operations that vectorise
/// (no libm call, no float-to-integer conversion, which AVX2 lacks for 64-bit integers).
#[inline(always)]
pub(crate) fn ceil_index(x: f64) -> usize {
    // t = ROUND_MAGIC + round(x) exactly, and round(x) sits in t's low significand bits.
    let t = x + ROUND_MAGIC;
    let r = t - ROUND_MAGIC;
    ((t.to_bits().wrapping_sub(ROUND_MAGIC.to_bits()) as i64) + i64::from(r < x)) as usize
}

/// The largest of `l` (`−∞` if empty), and whether any is NaN or `+∞`: the batch filter's
/// chunk maximum over four running maxima (see [`max_and_flag_lanes`]).
#[inline(always)]
pub(crate) fn max_and_flag(l: &[f64]) -> (f64, bool) {
    max_and_flag_lanes::<4>(l)
}

/// [`max_and_flag`] over `L` running maxima and flags, compare-and-select, so that the loop
/// vectorises `L` lanes wide. Without NaN the maximum is the same value in any order, so
/// the lane count (and [`Avx512::max_and_flag`](super::avx512::Avx512::max_and_flag), which
/// keeps more and takes its remainder here) changes nothing but the speed.
#[inline(always)]
pub(crate) fn max_and_flag_lanes<const L: usize>(l: &[f64]) -> (f64, bool) {
    let mut m = [f64::NEG_INFINITY; L];
    let mut bad = [false; L];
    let mut blocks = l.chunks_exact(L);
    for b in &mut blocks {
        for k in 0..L {
            bad[k] |= b[k].is_nan() | (b[k] == f64::INFINITY);
            m[k] = if b[k] > m[k] { b[k] } else { m[k] };
        }
    }
    for (k, &v) in blocks.remainder().iter().enumerate() {
        bad[k] |= v.is_nan() | (v == f64::INFINITY);
        m[k] = if v > m[k] { v } else { m[k] };
    }
    let max = m
        .iter()
        .fold(f64::NEG_INFINITY, |a, &b| if b > a { b } else { a });
    (max, bad.iter().any(|&b| b))
}

/// The batch filter's map from a particle's cumulative weight `cw` within its chunk to its
/// global cumulative weight scaled by `N/T`, `x = (offset + scale·cw)·n_over_total`,
/// evaluated in that order: systematic resampling's point count below the particle is
/// `⌈x − U⌉`. One definition for the portable walk, its bisection and the AVX-512 twin, which
/// must agree to the bit.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ChunkMap {
    /// The chunk's global offset.
    pub offset: f64,
    /// The chunk's scale.
    pub scale: f64,
    /// `N/T`, the particle count over the total weight.
    pub n_over_total: f64,
}

impl ChunkMap {
    /// `x(cw)`.
    #[inline(always)]
    pub(crate) fn x(&self, cw: f64) -> f64 {
        (self.offset + self.scale * cw) * self.n_over_total
    }
}

/// `⌈x⌉` clamped to `[lo, hi]`, minus `lo`, as an index, for integers `0 ≤ lo ≤ hi < 2⁵¹`
/// and `x < 2⁵¹` (the same as `ceil_index(x).clamp(lo, hi) − lo` for `x > −1`): the clamp in
/// two float compare-and-selects rather than unsigned 64-bit ones, which AVX2 lacks. In the
/// batch filter's boundaries: 19 instead of 26 instructions per four particles, and the
/// filter 2 % faster.
#[inline(always)]
pub(crate) fn ceil_index_in(x: f64, lo: f64, hi: f64) -> usize {
    let t = x + ROUND_MAGIC;
    let r = t - ROUND_MAGIC;
    index_in(if r < x { r + 1.0 } else { r }, lo, hi)
}

/// The integer `c` (a double, `|c| < 2⁵¹`) clamped to `[lo, hi]`, minus `lo`, as an index
/// (see [`ceil_index_in`]).
#[inline(always)]
pub(crate) fn index_in(c: f64, lo: f64, hi: f64) -> usize {
    let c = if c < lo { lo } else { c };
    let c = if c > hi { hi } else { c };
    ((c - lo) + ROUND_MAGIC)
        .to_bits()
        .wrapping_sub(ROUND_MAGIC.to_bits()) as usize
}

/// `⌊x⌋` for `0 ≤ x < 2⁵¹`, as an index and as a double, vectorisable like [`ceil_index`].
#[inline(always)]
pub(crate) fn floor_index(x: f64) -> (usize, f64) {
    let t = x + ROUND_MAGIC;
    let r = t - ROUND_MAGIC;
    let above = r > x;
    let k = (t.to_bits().wrapping_sub(ROUND_MAGIC.to_bits()) as i64) - i64::from(above);
    (k as usize, if above { r - 1.0 } else { r })
}

/// A uniform on [0, 1) from the top 52 bits of `b`, exactly `⌊b/2¹²⌋·2⁻⁵²`, by the exponent
/// trick (AVX2 has no integer-to-float conversion for 64-bit lanes).
#[inline(always)]
pub(crate) fn unit_from_bits(b: u64) -> f64 {
    f64::from_bits((b >> 12) | 0x3ff0_0000_0000_0000) - 1.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The largest relative error of `f` against the platform's `exp` over `xs`; a NaN
    /// counts as infinitely wrong (`f64::max` would pass over it).
    fn worst_relative_error(f: impl Fn(f64) -> f64, xs: impl IntoIterator<Item = f64>) -> f64 {
        xs.into_iter()
            .map(|x| ((f(x) - x.exp()) / x.exp()).abs())
            .map(|e| if e.is_nan() { f64::INFINITY } else { e })
            .fold(0.0, f64::max)
    }

    /// Relative error against the platform's `exp` over the whole range, on a fine grid and
    /// at awkward points (exact multiples of ln 2, the ends).
    #[test]
    fn exp_is_accurate_to_two_ulp() {
        let grid = (0..=2_000_000).map(|i| -708.0 * f64::from(i) / 2e6);
        let steps = (0..1021).flat_map(|k| {
            let x = -f64::from(k) * std::f64::consts::LN_2;
            [-1e-12, 0.0, 1e-12].map(|d| (x + d).min(0.0))
        });
        let ends = [
            0.0,
            -0.0,
            -1e-300,
            -f64::MIN_POSITIVE,
            -708.0,
            -0.346,
            -0.347,
        ];
        let worst = worst_relative_error(exp_nonpositive, grid.chain(steps).chain(ends));
        assert!(worst <= 2.0 * f64::EPSILON, "max relative error {worst:e}");
    }

    #[test]
    fn ceil_and_floor_match_std() {
        for &x in &[
            -0.999,
            -0.5,
            -0.0,
            0.0,
            0.2,
            0.5,
            1.0,
            1.5,
            2.5,
            1.000_000_1,
            41.5,
            1e6,
            1e15,
        ] {
            assert_eq!(ceil_index(x), x.ceil().max(0.0) as usize, "ceil {x}");
            if x >= 0.0 {
                let (k, f) = floor_index(x);
                assert_eq!((k, f), (x.floor() as usize, x.floor()), "floor {x}");
            }
        }
        for i in 0..10_000 {
            let x = f64::from(i) * 0.37 - 0.9;
            assert_eq!(ceil_index(x), x.ceil().max(0.0) as usize, "ceil {x}");
        }
    }

    /// The clamped ceiling is `ceil_index(x).clamp(lo, hi) − lo`: at integers, a rounding
    /// step either side of them, below `lo`, above `hi` and near the range's ends.
    #[test]
    fn clamped_ceiling_matches_the_integer_clamp() {
        for (lo, hi) in [
            (0usize, 0usize),
            (0, 7),
            (5, 5),
            (3, 2051),
            (1 << 20, (1 << 20) + 64),
        ] {
            let (lof, hif) = (lo as f64, hi as f64);
            let mut xs = vec![-0.999, -0.0, 0.0, 1e-300, 2.0 * hif + 3.0, 1e15];
            let near_lo = lo.saturating_sub(3)..=(hi + 3).min(lo + 300);
            for i in (0..5).chain(near_lo).chain(hi.saturating_sub(3)..=hi + 3) {
                let k = i as f64;
                xs.extend([k, k.next_up(), k.next_down(), k + 0.5]);
            }
            for x in xs {
                let want = ceil_index(x).clamp(lo, hi) - lo;
                assert_eq!(ceil_index_in(x, lof, hif), want, "x = {x}, [{lo}, {hi}]");
            }
        }
    }

    /// The lane-wise form returns, lane by lane, the bits of the one-lane form (which is
    /// what the filter's AVX2 and portable kernels are each compared with).
    #[test]
    fn lanes_give_the_bits_of_one_lane() {
        let xs: [f64; 64] = std::array::from_fn(|i| match i {
            0 => f64::NEG_INFINITY,
            1 => -708.5,
            2 => -708.0,
            3 => -0.0,
            _ => -(i as f64).powf(1.7) * 0.37,
        });
        let lanes = exp_nonpositive_lanes(xs);
        for (x, y) in xs.iter().zip(lanes) {
            assert_eq!(y.to_bits(), exp_nonpositive(*x).to_bits(), "x = {x}");
        }
    }

    /// Each table entry is `2^{j/64}` to within the platform `exp2`'s own error (one ulp),
    /// and entry 32 is √2 exactly rounded.
    #[test]
    fn table_holds_powers_of_two() {
        for (j, &bits) in EXP2_64THS.iter().enumerate() {
            let (got, want) = (f64::from_bits(bits), (j as f64 / 64.0).exp2());
            assert!(
                (got - want).abs() <= want * f64::EPSILON,
                "entry {j}: {got} vs {want}"
            );
        }
        assert_eq!(f64::from_bits(EXP2_64THS[32]), std::f64::consts::SQRT_2);
    }

    /// The fused `exp` over its whole range: a fine grid, multiples of `ln 2/16` and their
    /// neighbours (where the table index and the exponent change), and the rates of the
    /// Poisson inversion densely.
    #[test]
    fn exp_fma_is_accurate_to_two_ulp() {
        let grid = (0..=2_000_000).flat_map(|i| {
            let t = f64::from(i) / 2e6;
            [-708.0 + 1417.0 * t, 12.0 * t]
        });
        let steps = (-16_350..16_380).flat_map(|k| {
            let x = f64::from(k) * std::f64::consts::LN_2 / 16.0;
            [-1e-12, 0.0, 1e-12].map(|d| (x + d).clamp(-708.0, 709.0))
        });
        let ends = [
            0.0,
            -0.0,
            1e-300,
            f64::MIN_POSITIVE,
            709.0,
            -708.0,
            0.0108,
            0.0109,
        ];
        let worst = worst_relative_error(exp_fma, grid.chain(steps).chain(ends));
        assert!(worst <= 2.0 * f64::EPSILON, "max relative error {worst:e}");
    }

    #[test]
    fn exp_underflows_to_zero() {
        assert_eq!(exp_nonpositive(-708.5), 0.0);
        assert_eq!(exp_nonpositive(-1e300), 0.0);
        assert_eq!(exp_nonpositive(f64::NEG_INFINITY), 0.0);
        assert_eq!(exp_nonpositive(0.0), 1.0);
        for x in [-708.5, -1e300, f64::NEG_INFINITY] {
            assert_eq!(exp_fma_nonpositive(x), 0.0, "x = {x}");
        }
    }

    /// The filter's weights are [`exp_fma`] on its range, so its accuracy test covers them,
    /// and 64 lanes at a time give the one-lane bits.
    #[test]
    fn exp_fma_nonpositive_is_exp_fma_on_its_range() {
        let mut lanes = [0.0; 64];
        for (i, x) in (0..=200_000)
            .map(|i| -708.0 * f64::from(i) / 2e5)
            .chain([-0.0, -1e-300, -708.0])
            .enumerate()
        {
            assert_eq!(
                exp_fma_nonpositive(x).to_bits(),
                exp_fma(x).to_bits(),
                "x = {x}"
            );
            lanes[i % 64] = x;
            if i % 64 == 63 {
                let mut got = lanes;
                exp_fma_nonpositive_lanes(&mut got);
                for (x, y) in lanes.iter().zip(got) {
                    assert_eq!(y.to_bits(), exp_fma(*x).to_bits(), "x = {x}");
                }
            }
        }
    }
}
