//! The AVX-512 twin of [`poisson_counts`](super::poisson_counts): the same
//! counts as the portable kernel, found in single precision and certified lane by lane.
//!
//! A block of 64 particles is four pairs of lane groups of eight. Each group steps its
//! eight lanes of the [`LaneRng`] (the same draws as the portable lane step) and forms its
//! rates in `f64`, so the rates' sums and the escapes above
//! [`RATE_INVERT`](super::RATE_INVERT) are the portable kernel's. Each pair's
//! inversion then runs in one register of sixteen `f32` lanes: the rate rounded, the
//! uniform's top 24 bits, a single-precision `e^λ` ([`exp16`](x86::exp16), its table scaled
//! by `2⁻²⁴·(1 + δ)` so that `hi` below is one fused step), and the partial sums
//! `S_i = Σ_{k ≤ i} λ^k/k!`.
//!
//! **The certification.** Each lane counts its sums at or below
//! `hi = (u₂₄ + 2⁻²⁴)·e^λ·(1 + δ)`, and its count stands only where the last of them is
//! also at or below `lo = u₂₄·e^λ·(1 − δ)`, so that no sum lies between the two. Here `δ` is
//! [`DELTA`](x86::DELTA) (2⁻¹⁶ ≈ 1.5·10⁻⁵).
//!
//! The errors against the `f64` kernel's `U = u·e^λ` and sums, relative, at most:
//! - `(3i + 1)·2⁻²⁴` for sum `i`: the rate's rounding carried through `λ^i`, one rounding
//!   per multiply and per fused step, and `1/i!` rounded. That is 5.4·10⁻⁶ at the last term,
//!   [`LAST_TERM`](x86::LAST_TERM) = 30.
//! - about 10⁻⁶ for `e^λ`: `λ·2⁻²⁴` ≤ 7.2·10⁻⁷ from the rate's rounding at `λ ≤ 12`, and
//!   1.5·10⁻⁷ from [`exp16`](x86::exp16) (tested).
//! - 1.8·10⁻⁷ for the products forming `hi` and `lo`: one rounding for `hi`, three for
//!   `lo` (its factor `(1 − δ)/(1 + δ)` rounded, and two products).
//!
//! A rate or a term below `f32`'s normal range (small rates, from about the seventh term)
//! loses only an absolute error below 2⁻¹⁴⁹, against sums that are at least 1.
//!
//! The `f64` values are within about 10⁻¹⁴ of exact. The truncated uniform is at most
//! 2⁻²⁴ below `u`, which `hi` covers. So a certified lane has every sum at or below `lo`
//! at or below `U` in `f64`, and every sum above `hi` above it: its count is the `f64`
//! kernel's, bit for bit, with twice the margin needed. The budget's terms are tested one by
//! one against the `f64` kernel's values, on rates across `[0, 12]`.
//!
//! **Lanes that are not certified.** Three kinds of lane are not certified:
//! - a lane near a sum;
//! - a lane whose `f32` sum stops moving;
//! - a lane still going at [`LAST_TERM`](x86::LAST_TERM).
//!
//! On the bench's weights at N = 10⁶ that is 1.7 lanes in 10⁴ for multinomial rates and 1.2
//! for residual ones. Such a lane's pair of groups is redone by the `f64` inversion
//! ([`counts64`](x86::counts64)), with the portable kernel's operations in its order. A pair
//! with a lane whose count reaches the compared terms continues in `f32` a term at a time,
//! inline.
//!
//! Sixteen lanes to a register halve the inversion's chains: at N = 10⁶ multinomial
//! resampling is 13 % faster than with the `f64` inversion, residual 15 %.
//! The counts equal the portable kernel's. That is tested in `poisson` and in `multinomial`,
//! and here on lanes built to sit on the sums.

use super::{Rates, Tally};
use crate::resample::counts::Counts;
use crate::simd::LaneRng;
use crate::simd::avx512::{Avx512, on_avx512};
use rand::Rng;

/// [`poisson_counts`](super::poisson_counts) on AVX-512, into `counts` (already
/// reset for `w.len()` particles).
pub(crate) fn poisson_counts<R: Rng + ?Sized>(
    cpu: Avx512,
    counts: &mut Counts,
    w: &[f64],
    rates: Rates,
    lanes: &mut LaneRng,
    rng: &mut R,
) -> Tally {
    match rates {
        Rates::Scaled(a) => on_avx512!(
            cpu,
            x86::poisson_counts::<false, R>,
            (counts, w, a, 0.0, lanes, rng)
        ),
        Rates::Residuals { a, b } => on_avx512!(
            cpu,
            x86::poisson_counts::<true, R>,
            (counts, w, a, b, lanes, rng)
        ),
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use crate::resample::counts::Counts;
    use crate::resample::poisson::{INV_FACTORIAL, RATE_INVERT, Rates, Tally, escape};
    use crate::simd::avx512::x86::{exp_fma8, exp_table, load_pd, step8, unit8};
    use crate::simd::math::EXP2_16THS;
    use crate::simd::{LANES, LaneRng};
    use rand::Rng;
    use std::arch::x86_64::*;

    /// The rounding of `vrndscalepd` that gives `⌊x⌋`.
    const FLOOR: i32 = _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC;

    /// The relative margin `δ = 2⁻¹⁶` of the single-precision counts (see the module docs):
    /// above twice their worst error against the `f64` inversion's sums and `u·e^λ`.
    pub(super) const DELTA: f32 = 1.0 / 65_536.0;

    /// The last term of the single-precision inversion: `λ³⁰` stays finite in `f32` for
    /// `λ ≤ 12`, and the error bound `(3i + 1)·2⁻²⁴` of the sums holds the margin there.
    pub(super) const LAST_TERM: usize = 30;

    /// `1/i!` rounded to `f32`, `i = 0 … LAST_TERM`.
    static INV_FACTORIAL_F32: [f32; LAST_TERM + 1] = {
        let mut t = [0.0f32; LAST_TERM + 1];
        let mut i = 0;
        while i <= LAST_TERM {
            t[i] = INV_FACTORIAL[i] as f32;
            i += 1;
        }
        t
    };

    /// The scale of [`exp16`]'s table: `(1 + δ)·2⁻²⁴`, the factor of `hi` per unit of the
    /// uniform's top 24 bits.
    pub(super) const EXP_SCALE: f64 = (1.0 + DELTA as f64) / 16_777_216.0;

    /// `lo/hi` per unit of the uniform: `(1 − δ)/(1 + δ)`, rounded to `f32`.
    const LO_PER_HI: f32 = ((1.0 - DELTA as f64) / (1.0 + DELTA as f64)) as f32;

    /// `2^{j/16}·`[`EXP_SCALE`], `j = 0 … 15`, rounded once to `f32`: one register, looked
    /// up by `vpermps`. The scale, folded in here, saves three products per pair of groups.
    static EXP2_16THS_SCALED: [f32; 16] = {
        let mut t = [0.0f32; 16];
        let mut j = 0;
        while j < 16 {
            t[j] = (f64::from_bits(EXP2_16THS[j]) * EXP_SCALE) as f32;
            j += 1;
        }
        t
    };

    /// `ln 2/16` in two parts for the reduction of [`exp16`].
    const LN2_16_HI: f32 = (std::f64::consts::LN_2 / 16.0) as f32;
    const LN2_16_LO: f32 = (std::f64::consts::LN_2 / 16.0 - LN2_16_HI as f64) as f32;

    /// `2⁻²⁴`: the spacing of the single-precision uniforms (folded into
    /// [`EXP_SCALE`] in the kernel).
    #[cfg(test)]
    const ULP_U: f32 = 1.0 / 16_777_216.0;

    /// The kernel for [`Rates::Scaled`]`(a)`, or with `RESIDUALS` for
    /// [`Rates::Residuals`]` { a, b }`.
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    pub(super) fn poisson_counts<const RESIDUALS: bool, R: Rng + ?Sized>(
        counts: &mut Counts,
        w: &[f64],
        a: f64,
        b: f64,
        lanes: &mut LaneRng,
        rng: &mut R,
    ) -> Tally {
        let rates = if RESIDUALS {
            Rates::Residuals { a, b }
        } else {
            Rates::Scaled(a)
        };
        let terms = rates.terms();
        if RESIDUALS {
            // Every byte is written below.
            counts.runs.resize(w.len(), 0);
        }
        let table = exp_table16();
        let zero = _mm512_setzero_pd();
        let mut sums = zero;
        let mut inverted = _mm_setzero_si128();
        let mut total = 0usize;
        // The floors' sum: a block's bytes summed eight to a lane, or, where one saturates,
        // its floors in `f64` (rare: only weights of `255/M` or more).
        let mut floor_bytes = _mm512_setzero_si512();
        let mut floor_sum = 0.0;
        let mut outside: __mmask8 = 0;
        let mut wpad = [0.0f64; LANES];
        for (blk, wb) in w.chunks(LANES).enumerate() {
            let (j0, len) = (blk * LANES, wb.len());
            // A partial last block: the lanes past the weights get rate 0 (count 0), and
            // every lane steps, as in the portable kernel.
            let wb = if len == LANES {
                wb
            } else {
                wpad[..len].copy_from_slice(wb);
                wpad[len..].fill(0.0);
                &wpad[..]
            };
            // The block's count bytes and floor bytes, sixteen moved in per pair at the top of
            // a register: staged in arrays instead, each block's 64-byte reload of its four
            // 16-byte stores waited for them to reach the cache (no store forwarding).
            let mut cb = _mm512_setzero_si512();
            let mut fb = _mm512_setzero_si512();
            let mut escaped = 0u64;
            // Sixteen particles at a time (a pair of lane groups): with two or four such
            // registers side by side, as the `f64` inversion has, residual resampling is
            // 6 % slower at N = 10⁶ and multinomial no faster.
            for h in 0..LANES / 16 {
                let bits: [__m512i; 2] = std::array::from_fn(|q| step8(lanes.state(), 2 * h + q));
                let mut floors = [zero; 2];
                let lam: [__m512d; 2] = std::array::from_fn(|q| {
                    let w = load_pd(&wb[16 * h + 8 * q..16 * h + 8 * (q + 1)]);
                    let x = _mm512_mul_pd(_mm512_set1_pd(a), w);
                    if RESIDUALS {
                        // Ordered comparisons: a NaN weight is outside.
                        let inside = _mm512_cmp_pd_mask::<_CMP_GE_OQ>(w, zero)
                            & _mm512_cmp_pd_mask::<_CMP_LE_OQ>(w, _mm512_set1_pd(1.0));
                        outside |= !inside;
                        // `x − ⌊x⌋` (the rounding is exact, as `floor_index`'s), times `b`.
                        let f = _mm512_roundscale_pd::<FLOOR>(x);
                        floors[q] = f;
                        _mm512_mul_pd(_mm512_sub_pd(x, f), _mm512_set1_pd(b))
                    } else {
                        // `max(x, 0)` returns its second operand unless `x > 0`: `rate_of`.
                        _mm512_max_pd(x, zero)
                    }
                });
                for l in lam {
                    sums = _mm512_add_pd(sums, l);
                }
                if RESIDUALS {
                    fb = shift_in(fb, bytes16(floors));
                }
                let esc = escapes(lam);
                // The sixteen counts as bytes (each at most `MAX_TERM`), narrowed in a
                // register (narrowing straight to memory, `vpmovdb` with a memory operand, is
                // slow), and summed eight bytes to a lane.
                let k = _mm512_cvtepi32_epi8(counts16(lam, bits, esc, terms, table));
                inverted = _mm_add_epi64(inverted, _mm_sad_epu8(k, _mm_setzero_si128()));
                cb = shift_in(cb, k);
                escaped |= u64::from(esc) << (16 * h);
            }
            // The runs: floors plus counts, saturated, and 255 for the escaped lanes (whose
            // counts come later), a block at a time: with the floors kept in registers
            // through the inversion, the rates' sums went to the stack, a chain through
            // memory.
            // (Dead in the multinomial copy, where `rb` is never stored.)
            let rb = _mm512_mask_mov_epi8(_mm512_adds_epu8(fb, cb), escaped, _mm512_set1_epi8(-1));
            if RESIDUALS {
                if _mm512_cmpeq_epi8_mask(fb, _mm512_set1_epi8(-1)) == 0 {
                    let sums = _mm512_sad_epu8(fb, _mm512_setzero_si512());
                    floor_bytes = _mm512_add_epi64(floor_bytes, sums);
                } else {
                    floor_sum += wb.iter().map(|&w| (a * w).floor()).sum::<f64>();
                }
            }
            let (cb, rb): ([u8; LANES], [u8; LANES]) = (bytemuck::cast(cb), bytemuck::cast(rb));
            if len == LANES {
                // A copy of constant length: inline stores, not a call to `memmove`.
                let to: &mut [u8; LANES] = (&mut counts.small[j0..j0 + LANES])
                    .try_into()
                    .expect("a full block");
                *to = cb;
                if RESIDUALS {
                    let to: &mut [u8; LANES] = (&mut counts.runs[j0..j0 + LANES])
                        .try_into()
                        .expect("a full block");
                    *to = rb;
                }
            } else {
                counts.small[j0..j0 + len].copy_from_slice(&cb[..len]);
                if RESIDUALS {
                    counts.runs[j0..j0 + len].copy_from_slice(&rb[..len]);
                }
            }
            if escaped != 0 {
                let lam: [f64; LANES] =
                    std::array::from_fn(|q| if q < len { rates.of(wb[q]) } else { 0.0 });
                total = total.saturating_add(escape(counts, escaped, j0, &lam, rng));
            }
        }
        counts.runs_set = RESIDUALS;
        let inverted: [u64; 2] = bytemuck::cast(inverted);
        let sums: [f64; 8] = bytemuck::cast(sums);
        let inverted: u64 = inverted.iter().sum();
        let floor_bytes: [u64; 8] = bytemuck::cast(floor_bytes);
        Tally {
            total: total.saturating_add(inverted as usize),
            rates: sums.iter().sum(),
            floors: floor_sum + floor_bytes.iter().sum::<u64>() as f64,
            clean: outside == 0,
        }
    }

    /// The table of [`exp16`].
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    fn exp_table16() -> __m512 {
        bytemuck::cast(EXP2_16THS_SCALED)
    }

    /// `e^x·`[`EXP_SCALE`] in single precision for `0 ≤ x ≤ 12`, within about 1.5·10⁻⁷
    /// relative (tested): `x = (16n + j)·ln 2/16 + r`, `|r| ≤ ln 2/32`,
    /// `2^{j/16}·`[`EXP_SCALE`] from the table, and `e^r − 1`
    /// from its Taylor polynomial of degree 3 (truncation below 10⁻⁸). Other lanes give
    /// values of no use and no fault.
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    pub(super) fn exp16(x: __m512, table: __m512) -> __m512 {
        let magic = _mm512_set1_ps(12_582_912.0); // 1.5·2²³: adding it rounds to an integer
        let t = _mm512_fmadd_ps(
            x,
            _mm512_set1_ps((16.0 / std::f64::consts::LN_2) as f32),
            magic,
        );
        let nf = _mm512_sub_ps(t, magic);
        let r = _mm512_fnmadd_ps(nf, _mm512_set1_ps(LN2_16_HI), x);
        let r = _mm512_fnmadd_ps(nf, _mm512_set1_ps(LN2_16_LO), r);
        let q = _mm512_fmadd_ps(r, _mm512_set1_ps(1.0 / 6.0), _mm512_set1_ps(0.5));
        let q = _mm512_fmadd_ps(q, r, _mm512_set1_ps(1.0));
        let p = _mm512_mul_ps(q, r);
        let bits = _mm512_castps_si512(t);
        let n = _mm512_srai_epi32::<4>(_mm512_sub_epi32(bits, _mm512_castps_si512(magic)));
        // The permute reads the low four bits of each index: `j`.
        let entry = _mm512_permutexvar_ps(bits, table);
        let s = _mm512_add_epi32(_mm512_castps_si512(entry), _mm512_slli_epi32::<23>(n));
        let s = _mm512_castsi512_ps(s);
        _mm512_fmadd_ps(s, p, s)
    }

    /// The rates of two groups of eight as sixteen `f32` lanes, the first group's first.
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    fn pack16(a: __m512d, b: __m512d) -> __m512 {
        let lo = _mm512_castps256_ps512(_mm512_cvtpd_ps(a));
        _mm512_insertf32x8::<1>(lo, _mm512_cvtpd_ps(b))
    }

    /// The top 24 bits of two groups' draws, `⌊b/2⁴⁰⌋`, as `f32` (exactly): times `2⁻²⁴`,
    /// each at most `2⁻²⁴` below its `f64` uniform [`unit8`], which has the next 28 bits too.
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    fn top16(a: __m512i, b: __m512i) -> __m512 {
        // The high half of each 64-bit lane, `a`'s eight then `b`'s.
        let high = _mm512_set_epi32(31, 29, 27, 25, 23, 21, 19, 17, 15, 13, 11, 9, 7, 5, 3, 1);
        let top = _mm512_srli_epi32::<8>(_mm512_permutex2var_epi32(a, high, b));
        _mm512_cvtepi32_ps(top)
    }

    /// `v` moved down sixteen bytes, and `x` in at the top.
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    fn shift_in(v: __m512i, x: __m128i) -> __m512i {
        _mm512_alignr_epi64::<2>(_mm512_castsi128_si512(x), v)
    }

    /// The floors `f` of two groups of eight as bytes, saturated at 255, the first group's
    /// first (from 255 up they saturate the same, and the conversion stays in range
    /// whatever `M`).
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    fn bytes16(f: [__m512d; 2]) -> __m128i {
        let [lo, hi] = f.map(|f| _mm512_cvttpd_epi32(_mm512_min_pd(f, _mm512_set1_pd(255.0))));
        _mm512_cvtusepi32_epi8(_mm512_inserti64x4::<1>(_mm512_castsi256_si512(lo), hi))
    }

    /// The lanes of two groups of eight whose rate is above [`RATE_INVERT`] (drawn by
    /// [`escape`] instead), the first group's in the low byte.
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    fn escapes(lam: [__m512d; 2]) -> __mmask16 {
        let [a, b] = lam.map(|l| _mm512_cmp_pd_mask::<_CMP_GT_OQ>(l, _mm512_set1_pd(RATE_INVERT)));
        u16::from(a) | u16::from(b) << 8
    }

    /// The counts of two groups of eight (rates `lam`, draws `bits`, escaped lanes `esc`)
    /// as sixteen `i32`, the first group's first: the inversion in single precision,
    /// certified against the `f64` one lane by lane, or the `f64` one ([`counts64`]) when a
    /// lane is not. Escaped lanes count 0.
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    pub(super) fn counts16(
        lam: [__m512d; 2],
        bits: [__m512i; 2],
        esc: __mmask16,
        terms: usize,
        table: __m512,
    ) -> __m512i {
        let one = _mm512_set1_ps(1.0);
        let l = pack16(lam[0], lam[1]);
        let top = top16(bits[0], bits[1]);
        let e = exp16(l, table);
        // `u·e^λ` from above, `(top + 1)·2⁻²⁴·e^λ·(1 + δ)` (the uniform's truncation and the
        // margin), and from below, `top·2⁻²⁴·e^λ·(1 − δ)`.
        let hi = _mm512_fmadd_ps(top, e, e);
        let lo = _mm512_mul_ps(top, _mm512_mul_ps(e, _mm512_set1_ps(LO_PER_HI)));
        // `k`: the sums `S_0 = 1, S_1, …` at or below `hi`; `below`: the last of them (0
        // when none), which must be at or below `lo` too.
        let mut pw = l;
        let mut s = _mm512_add_ps(one, l);
        let ge0 = _mm512_cmp_ps_mask::<_CMP_GE_OQ>(hi, one);
        let mut k = _mm512_maskz_mov_epi32(ge0, _mm512_set1_epi32(1));
        let mut below = _mm512_maskz_mov_ps(ge0, one);
        let mut ge = _mm512_cmp_ps_mask::<_CMP_GE_OQ>(hi, s);
        for (i, &c) in INV_FACTORIAL_F32[..terms].iter().enumerate().skip(2) {
            k = _mm512_mask_mov_epi32(k, ge, _mm512_set1_epi32(i as i32));
            below = _mm512_mask_mov_ps(below, ge, s);
            pw = _mm512_mul_ps(pw, l);
            s = _mm512_fmadd_ps(pw, _mm512_set1_ps(c), s);
            ge = _mm512_cmp_ps_mask::<_CMP_GE_OQ>(hi, s);
        }
        k = _mm512_mask_mov_epi32(k, ge, _mm512_set1_epi32(terms as i32));
        below = _mm512_mask_mov_ps(below, ge, s);
        let more = ge & !esc;
        let unresolved = if more != 0 {
            continue16(terms, &mut k, &mut below, l, hi, pw, s, more)
        } else {
            0
        };
        let near = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(below, lo);
        if (near | unresolved) & !esc != 0 {
            k = counts64(lam, bits, esc, terms);
        }
        _mm512_maskz_mov_epi32(!esc, k)
    }

    /// Terms of [`continue16`] taken before it first tests for the end: a lane that has
    /// stopped is masked out of them, so they change nothing but the branches. With a test
    /// per term, the loop's exit (data-dependent, so mispredicted about once per
    /// continuing pair) came sooner after its entry; with 3, multinomial and residual
    /// resampling are 3–4 % faster. 2, 4 and 6 do about as well; 8 no better than none.
    const BATCH: usize = 3;

    /// The single-precision inversion continued from term `from` for the lanes in `more`
    /// (at or below `hi` at the last sum `s`, `pw` the last power), until none is (the
    /// first [`BATCH`] terms untested); returns the lanes it cannot settle: those whose
    /// sum stops moving in `f32`, or still going at [`LAST_TERM`].
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    #[allow(clippy::too_many_arguments)]
    fn continue16(
        from: usize,
        k: &mut __m512i,
        below: &mut __m512,
        lam: __m512,
        hi: __m512,
        mut pw: __m512,
        mut s: __m512,
        mut more: __mmask16,
    ) -> __mmask16 {
        let mut unresolved = 0;
        for (i, &c) in INV_FACTORIAL_F32.iter().enumerate().skip(from) {
            if i >= from + BATCH && more == 0 {
                return unresolved;
            }
            pw = _mm512_mul_ps(pw, lam);
            let next = _mm512_fmadd_ps(pw, _mm512_set1_ps(c), s);
            let stuck = more & _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(next, s);
            unresolved |= stuck;
            more = _mm512_mask_cmp_ps_mask::<_CMP_GE_OQ>(more & !stuck, hi, next);
            *k = _mm512_mask_mov_epi32(*k, more, _mm512_set1_epi32(i as i32 + 1));
            *below = _mm512_mask_mov_ps(*below, more, next);
            s = next;
        }
        unresolved | more
    }

    /// The `f64` inversion of two groups of eight, the portable kernel's operations in its
    /// order (so its counts), as sixteen `i32`: for the rare pair the single-precision
    /// counts cannot settle.
    #[cold]
    #[inline(never)]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    pub(super) fn counts64(
        lam: [__m512d; 2],
        bits: [__m512i; 2],
        esc: __mmask16,
        terms: usize,
    ) -> __m512i {
        let table = exp_table();
        let (one, ones) = (_mm512_set1_pd(1.0), _mm512_set1_epi64(1));
        let k: [__m256i; 2] = std::array::from_fn(|q| {
            let lam = lam[q];
            let u = _mm512_mul_pd(unit8(bits[q]), exp_fma8(lam, &table));
            let mut pw = lam;
            let mut s = _mm512_add_pd(one, lam);
            let mut k = _mm512_maskz_mov_epi64(_mm512_cmp_pd_mask::<_CMP_GE_OQ>(u, one), ones);
            let mut ge = _mm512_cmp_pd_mask::<_CMP_GE_OQ>(u, s);
            for &c in &INV_FACTORIAL[2..terms] {
                k = _mm512_mask_add_epi64(k, ge, k, ones);
                pw = _mm512_mul_pd(pw, lam);
                s = _mm512_fmadd_pd(pw, _mm512_set1_pd(c), s);
                ge = _mm512_cmp_pd_mask::<_CMP_GE_OQ>(u, s);
            }
            k = _mm512_mask_add_epi64(k, ge, k, ones);
            let more = ge & !((esc >> (8 * q)) as u8);
            if more != 0 {
                k = continue_terms(terms, k, lam, u, pw, s, more);
            }
            _mm512_cvtepi64_epi32(k)
        });
        _mm512_inserti64x4::<1>(_mm512_castsi256_si512(k[0]), k[1])
    }

    /// `poisson::continue_terms` for one group of eight.
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    fn continue_terms(
        from: usize,
        mut k: __m512i,
        lam: __m512d,
        u: __m512d,
        mut pw: __m512d,
        mut s: __m512d,
        mut more: __mmask8,
    ) -> __m512i {
        let ones = _mm512_set1_epi64(1);
        for (&c, i) in INV_FACTORIAL[from..].iter().zip(from..) {
            if more == 0 {
                break;
            }
            pw = _mm512_mul_pd(pw, lam);
            let next = _mm512_fmadd_pd(pw, _mm512_set1_pd(c), s);
            let past = _mm512_cmp_pd_mask::<_CMP_GT_OQ>(_mm512_set1_pd(i as f64), lam)
                & _mm512_cmp_pd_mask::<_CMP_EQ_OQ>(next, s);
            more &= _mm512_cmp_pd_mask::<_CMP_GE_OQ>(u, next) & !past;
            s = next;
            k = _mm512_mask_add_epi64(k, more, k, ones);
        }
        k
    }

    #[cfg(test)]
    mod tests {
        use super::*;
        use crate::mc::stream_rng;
        use crate::resample::poisson::poisson_block;
        use crate::simd::avx512::Avx512;
        use crate::simd::math::exp_fma;
        use rand::RngExt;

        /// [`exp16`] of each value (a multiple of sixteen of them).
        #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
        fn exp16_of(xs: &[f32]) -> Vec<f32> {
            let table = exp_table16();
            xs.chunks_exact(16)
                .flat_map(|x| {
                    let x: [f32; 16] = x.try_into().expect("sixteen lanes");
                    let y: [f32; 16] = bytemuck::cast(exp16(bytemuck::cast(x), table));
                    y
                })
                .collect()
        }

        /// [`counts16`] of 32 lanes, sixteen at a time, with `terms` compared up front.
        #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
        fn counts_of(lam: &[f64; 32], bits: &[u64; 32], terms: usize) -> [i32; 32] {
            let l: [__m512d; 4] = std::array::from_fn(|q| load_pd(&lam[8 * q..8 * q + 8]));
            let b: [__m512i; 4] = std::array::from_fn(|q| {
                let x: [u64; 8] = bits[8 * q..8 * q + 8].try_into().expect("eight lanes");
                bytemuck::cast(x)
            });
            let table = exp_table16();
            let k = [0, 1].map(|h| {
                let lam = [l[2 * h], l[2 * h + 1]];
                let k: [i32; 16] = bytemuck::cast(counts16(
                    lam,
                    [b[2 * h], b[2 * h + 1]],
                    escapes(lam),
                    terms,
                    table,
                ));
                k
            });
            bytemuck::cast(k)
        }

        /// The partial sums `S_0 … S_LAST_TERM` of rate `l` as the `f64` kernels form them.
        fn sums64(l: f64) -> [f64; LAST_TERM + 1] {
            let (mut pw, mut s) = (l, 1.0 + l);
            let mut out = [1.0; LAST_TERM + 1];
            out[1] = s;
            for i in 2..=LAST_TERM {
                pw *= l;
                s = pw.mul_add(INV_FACTORIAL[i], s);
                out[i] = s;
            }
            out
        }

        /// The same in single precision, as [`counts16`] forms them (scalar `f32` arithmetic
        /// repeats its operations bit for bit).
        fn sums32(l: f32) -> [f32; LAST_TERM + 1] {
            let (mut pw, mut s) = (l, 1.0 + l);
            let mut out = [1.0; LAST_TERM + 1];
            out[1] = s;
            for i in 2..=LAST_TERM {
                pw *= l;
                s = pw.mul_add(INV_FACTORIAL_F32[i], s);
                out[i] = s;
            }
            out
        }

        /// The single-precision `exp` is within 1.5·10⁻⁷ of `e^x·`[`EXP_SCALE`] (taken in
        /// `f64`) over `[0, 12]`: every 97th `f32` there, and the ends. The certification's
        /// margin assumes 10⁻⁶ with the rounding of the rate.
        #[test]
        fn exp16_is_accurate_on_the_rates() {
            let Some(_) = Avx512::for_test() else {
                return;
            };
            let mut xs: Vec<f32> = (0..12.0f32.to_bits())
                .step_by(97)
                .map(f32::from_bits)
                .collect();
            xs.extend([0.0, 12.0, 12.0f32.next_down(), f32::MIN_POSITIVE]);
            xs.resize(xs.len().next_multiple_of(16), 1.0);
            // SAFETY: the token exists only where the CPU has the features.
            #[allow(unsafe_code)]
            let got = unsafe { exp16_of(&xs) };
            let worst = xs
                .iter()
                .zip(&got)
                .map(|(&x, &y)| {
                    let e = f64::from(x).exp() * EXP_SCALE;
                    (f64::from(y) - e).abs() / e
                })
                .fold(0.0, f64::max);
            assert!(worst < 1.5e-7, "relative error {worst:e}");
        }

        /// The error budget of the module docs, term by term: on rates across `[0, 12]`, each
        /// `f32` partial sum (the kernel's operations, which scalar `f32` arithmetic repeats
        /// bit for bit) is within `(3i + 1)·2⁻²⁴` of the `f64` kernel's, `exp16` of the
        /// rounded rate within 10⁻⁶ of the `f64` kernel's `e^λ` (scaled), and the whole
        /// budget with the products' 1.8·10⁻⁷ within half the margin.
        #[test]
        fn the_error_budget_holds() {
            let Some(_) = Avx512::for_test() else {
                return;
            };
            let ulp = f64::from(ULP_U);
            let worst = (3 * LAST_TERM + 1) as f64 * ulp + 1e-6 + 1.8e-7;
            assert!(worst <= f64::from(DELTA) / 2.0, "budget {worst:e}");
            let mut rng = stream_rng(17, 0);
            let lams: Vec<f64> = (0..4096)
                .map(|i| match i % 4 {
                    0 => 12.0 * rng.random::<f64>(),
                    1 => rng.random::<f64>(),
                    2 => 1e-3 * rng.random::<f64>(),
                    _ => 12.0 - 1e-6 * rng.random::<f64>(),
                })
                .collect();
            let l32: Vec<f32> = lams.iter().map(|&l| l as f32).collect();
            // SAFETY: the token exists only where the CPU has the features.
            #[allow(unsafe_code)]
            let e32 = unsafe { exp16_of(&l32) };
            for ((&l, &m), &e) in lams.iter().zip(&l32).zip(&e32) {
                let e64 = exp_fma(l) * EXP_SCALE;
                let err = (f64::from(e) - e64).abs() / e64;
                assert!(err <= 1e-6, "λ = {l}: e^λ off by {err:e}");
                let (s64, s32) = (sums64(l), sums32(m));
                for (i, (&s, &s32)) in s64.iter().zip(&s32).enumerate().skip(1) {
                    let err = (f64::from(s32) - s).abs() / s;
                    let bound = (3 * i + 1) as f64 * ulp;
                    assert!(err <= bound, "λ = {l}, sum {i}: off by {err:e} > {bound:e}");
                }
            }
        }

        /// `f64` draws whose `u·e^λ` falls within a few ulp of the inversion's partial sums
        /// `S_i` (as the kernels compute them), and others at the ends of the uniforms, for
        /// rates from 0 (and below `f32`'s normal range) to past [`RATE_INVERT`].
        fn hard_lanes(seed: u64, n: usize) -> (Vec<f64>, Vec<u64>) {
            let mut rng = stream_rng(seed, 0);
            let (mut lam, mut bits) = (Vec::new(), Vec::new());
            for i in 0..n {
                let l = match i % 11 {
                    0 => 0.0,
                    1 => 1e-40,
                    2 => rng.random::<f64>() * 1e-6,
                    3 => 12.0,
                    4 => 12.0f64.next_up(),
                    5 => 5.0 + 7.0 * rng.random::<f64>(),
                    6 => 1.0 + 4.0 * rng.random::<f64>(),
                    _ => rng.random::<f64>(),
                };
                let low: u64 = rng.random::<u64>() & 0xfff;
                let b = match i % 5 {
                    0 => rng.random(),
                    1 => u64::MAX - (low << 20),
                    2 => low,
                    _ => {
                        // A partial sum S_t as the kernels form it, and u = S_t/e^λ give or
                        // take two steps of 2⁻⁵².
                        let t = rng.random_range(0..=(l as usize + 10).min(28));
                        let u = sums64(l)[t] / exp_fma(l);
                        let m = (u * 2f64.powi(52)).min(2f64.powi(52) - 3.0) as i64;
                        let m = (m + rng.random_range(-2..=2i64)).max(0) as u64;
                        m << 12 | low
                    }
                };
                lam.push(l);
                bits.push(b);
            }
            (lam, bits)
        }

        /// The inversion in single precision with neither margin nor redo.
        fn plain_f32(l: f64, b: u64) -> u64 {
            let l = l as f32;
            let u = (b >> 40) as f32 * ULP_U * l.exp();
            sums32(l).iter().take_while(|&&s| u >= s).count() as u64
        }

        /// The single-precision counts, certified or redone in `f64`, equal the portable
        /// kernel's on lanes chosen to sit on the edges of the inversion, with eight terms
        /// compared up front and with four.
        #[test]
        fn certified_counts_equal_the_portable_inversion() {
            let Some(_) = Avx512::for_test() else {
                return;
            };
            let (lam, bits) = hard_lanes(5, 64 * 400);
            // Lanes where a plain single-precision inversion (no margin, no redo) would
            // miscount: the lanes must be hard enough that the certification matters.
            let mut plain_wrong = 0;
            for (l, b) in lam.chunks_exact(64).zip(bits.chunks_exact(64)) {
                let l: &[f64; 64] = l.try_into().expect("a block");
                let b: &[u64; 64] = b.try_into().expect("a block");
                for terms in [4, 8] {
                    let mut want = [0u64; 64];
                    if terms == 4 {
                        poisson_block::<4>(l, b, &mut want);
                    } else {
                        poisson_block::<8>(l, b, &mut want);
                    }
                    for (q, &w) in want.iter().enumerate() {
                        plain_wrong +=
                            usize::from(l[q] <= RATE_INVERT && plain_f32(l[q], b[q]) != w);
                    }
                    for h in 0..2 {
                        let r = 32 * h..32 * (h + 1);
                        let lh: &[f64; 32] = l[r.clone()].try_into().expect("half");
                        let bh: &[u64; 32] = b[r.clone()].try_into().expect("half");
                        // SAFETY: the token exists only where the CPU has the features.
                        #[allow(unsafe_code)]
                        let got = unsafe { counts_of(lh, bh, terms) };
                        for (q, (&g, &w)) in got.iter().zip(&want[r]).enumerate() {
                            let q = 32 * h + q;
                            assert_eq!(
                                g as u64, w,
                                "λ = {:e}, bits {:#x}, {terms} terms",
                                l[q], b[q]
                            );
                        }
                    }
                }
            }
            assert!(plain_wrong > 100, "only {plain_wrong} lanes are hard");
        }
    }
}
