//! The AVX-512 twin of [`poisson_counts`](super::poisson::poisson_counts): the same
//! inversion, eight particles to a register and four registers side by side.
//!
//! The portable kernel, compiled by LLVM for AVX-512, kept its 64-lane arrays in memory and
//! looked the `exp` table up lane by lane. Here a block of 64 particles is two halves of four
//! groups of eight; each group steps its eight lanes of the [`LaneRng`] (the same draws as
//! the portable lane step), and the four groups go through `exp`, the terms and the compares
//! a step at a time, so that their chains of dependent operations overlap (one group at a
//! time waited on latency: 2.6 against 2.3 ns per particle, scratch harness, 2026-11-27).
//! The counts equal the portable kernel's (tested in `poisson`).

use super::counts::Counts;
use super::poisson::Rates;
use crate::simd::LaneRng;
use crate::simd::avx512::{Avx512, on_avx512};
use rand::Rng;

/// [`poisson_counts`](super::poisson::poisson_counts) on AVX-512, into `counts` (already
/// reset for `w.len()` particles).
pub(crate) fn poisson_counts<R: Rng + ?Sized>(
    cpu: Avx512,
    counts: &mut Counts,
    w: &[f64],
    rates: Rates,
    lanes: &mut LaneRng,
    rng: &mut R,
) -> (usize, f64) {
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
    use super::super::counts::Counts;
    use super::super::poisson::{INV_FACTORIAL, RATE_INVERT, Rates, escape};
    use crate::simd::avx512::x86::{
        exp_fma8, exp_table, lanes_epi64, lanes_pd, load_pd, step8, unit8,
    };
    use crate::simd::{LANES, LaneRng};
    use rand::Rng;
    use std::arch::x86_64::*;

    /// Groups of eight particles taken side by side.
    const G: usize = 4;

    /// The rounding of `vrndscalepd` that gives `⌊x⌋`.
    const FLOOR: i32 = _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC;

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
    ) -> (usize, f64) {
        let rates = if RESIDUALS {
            Rates::Residuals { a, b }
        } else {
            Rates::Scaled(a)
        };
        let terms = rates.terms();
        let table = exp_table();
        let (zero, one) = (_mm512_setzero_pd(), _mm512_set1_pd(1.0));
        let ones = _mm512_set1_epi64(1);
        let mut sums = zero;
        let mut inverted = _mm512_setzero_si512();
        let mut total = 0usize;
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
            let mut cb = [0u8; LANES];
            let mut escaped = 0u64;
            for h in 0..LANES / (8 * G) {
                let g0 = h * G;
                let bits: [__m512i; G] = std::array::from_fn(|q| step8(lanes.state(), g0 + q));
                let lam: [__m512d; G] = std::array::from_fn(|q| {
                    let x = load_pd(&wb[8 * (g0 + q)..8 * (g0 + q + 1)]);
                    let x = _mm512_mul_pd(_mm512_set1_pd(a), x);
                    if RESIDUALS {
                        // `x − ⌊x⌋` (the rounding is exact, as `floor_index`'s), times `b`.
                        let f = _mm512_roundscale_pd::<FLOOR>(x);
                        _mm512_mul_pd(_mm512_sub_pd(x, f), _mm512_set1_pd(b))
                    } else {
                        // `max(x, 0)` returns its second operand unless `x > 0`: `rate_of`.
                        _mm512_max_pd(x, zero)
                    }
                });
                for l in lam {
                    sums = _mm512_add_pd(sums, l);
                }
                let esc: [__mmask8; G] = std::array::from_fn(|q| {
                    _mm512_cmp_pd_mask::<_CMP_GT_OQ>(lam[q], _mm512_set1_pd(RATE_INVERT))
                });
                let e: [__m512d; G] = std::array::from_fn(|q| exp_fma8(lam[q], &table));
                let u: [__m512d; G] = std::array::from_fn(|q| _mm512_mul_pd(unit8(bits[q]), e[q]));
                let mut pw = lam;
                let mut s: [__m512d; G] = std::array::from_fn(|q| _mm512_add_pd(one, lam[q]));
                let mut k: [__m512i; G] = std::array::from_fn(|q| {
                    _mm512_maskz_mov_epi64(_mm512_cmp_pd_mask::<_CMP_GE_OQ>(u[q], one), ones)
                });
                let mut ge: [__mmask8; G] =
                    std::array::from_fn(|q| _mm512_cmp_pd_mask::<_CMP_GE_OQ>(u[q], s[q]));
                for &c in &INV_FACTORIAL[2..terms] {
                    let c = _mm512_set1_pd(c);
                    for q in 0..G {
                        k[q] = _mm512_mask_add_epi64(k[q], ge[q], k[q], ones);
                        pw[q] = _mm512_mul_pd(pw[q], lam[q]);
                        s[q] = _mm512_fmadd_pd(pw[q], c, s[q]);
                        ge[q] = _mm512_cmp_pd_mask::<_CMP_GE_OQ>(u[q], s[q]);
                    }
                }
                for q in 0..G {
                    k[q] = _mm512_mask_add_epi64(k[q], ge[q], k[q], ones);
                    let more = ge[q] & !esc[q];
                    if more != 0 {
                        k[q] = continue_terms(terms, k[q], lam[q], u[q], pw[q], s[q], more);
                    }
                    k[q] = _mm512_maskz_mov_epi64(!esc[q], k[q]);
                    inverted = _mm512_add_epi64(inverted, k[q]);
                    escaped |= u64::from(esc[q]) << (8 * (g0 + q));
                }
                // The four groups' counts as 32 bytes: narrowed in registers and stored once
                // (narrowing straight to memory, `vpmovqb` with a memory operand, is slow).
                let b: [__m128i; G] = std::array::from_fn(|q| _mm512_cvtepi64_epi8(k[q]));
                let lo = _mm_unpacklo_epi64(b[0], b[1]);
                let hi = _mm_unpacklo_epi64(b[2], b[3]);
                let bytes: [u8; 32] = bytemuck::cast(_mm256_set_m128i(hi, lo));
                cb[8 * g0..8 * (g0 + G)].copy_from_slice(&bytes);
            }
            if len == LANES {
                // A copy of constant length: inline stores, not a call to `memmove`.
                let to: &mut [u8; LANES] = (&mut counts.small[j0..j0 + LANES])
                    .try_into()
                    .expect("a full block");
                *to = cb;
            } else {
                counts.small[j0..j0 + len].copy_from_slice(&cb[..len]);
            }
            if escaped != 0 {
                let lam: [f64; LANES] =
                    std::array::from_fn(|q| if q < len { rates.of(wb[q]) } else { 0.0 });
                total = total.saturating_add(escape(counts, escaped, j0, &lam, rng));
            }
        }
        let inverted: u64 = lanes_epi64(inverted).iter().sum();
        let sums: f64 = lanes_pd(sums).iter().sum();
        (total.saturating_add(inverted as usize), sums)
    }

    /// `poisson::continue_terms` for one group of eight.
    #[cold]
    #[inline(never)]
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
        // A slice's own iterator: in a cold function (optimised for size) `skip`'s `next`
        // stayed a call, with every register spilled around it.
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
}
