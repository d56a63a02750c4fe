//! The AVX-512 twin of residual resampling's floors pass (`residual::floors_and_mass`):
//! eight weights to a register, their two blocks of four going to the same four lanes, so
//! the sums are the portable pass's, bit for bit, wherever they are used (tested in
//! `residual`).

use super::FloorLanes;
use crate::simd::avx512::{Avx512, on_avx512};

/// The [`FloorLanes`] of the whole blocks of eight of `w`, and how many weights that is.
pub(crate) fn floor_lanes(cpu: Avx512, w: &[f64], mf: f64) -> (FloorLanes, usize) {
    on_avx512!(cpu, x86::floor_lanes, (w, mf))
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::FloorLanes;
    use crate::simd::avx512::x86::load_pd;
    use std::arch::x86_64::*;

    /// The rounding of `vrndscalepd` that gives `⌊x⌋`: `floor_index`'s value for the
    /// weights in [0, 1] whose sums are used, up to the sign of a zero (`⌊−0⌋`), which no
    /// sum shows.
    const FLOOR: i32 = _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC;

    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    pub(super) fn floor_lanes(w: &[f64], mf: f64) -> (FloorLanes, usize) {
        let m = _mm512_set1_pd(mf);
        let (zero, one) = (_mm256_setzero_pd(), _mm512_set1_pd(1.0));
        let (mut floors, mut mass, mut peak, mut outside) = (zero, zero, zero, zero);
        let mut blocks = w.chunks_exact(8);
        for b in &mut blocks {
            let x = load_pd(b);
            // Outside [0, 1] (or NaN): both compares fail for NaN.
            let inside = _mm512_cmp_pd_mask::<_CMP_GE_OQ>(x, _mm512_setzero_pd())
                & _mm512_cmp_pd_mask::<_CMP_LE_OQ>(x, one);
            let out = _mm512_maskz_mov_pd(!inside, one);
            let x = _mm512_mul_pd(m, x);
            let ff = _mm512_roundscale_pd::<FLOOR>(x);
            let r = _mm512_sub_pd(x, ff);
            let halves = |v: __m512d| (_mm512_castpd512_pd256(v), _mm512_extractf64x4_pd::<1>(v));
            let ((o0, o1), (f0, f1), (r0, r1)) = (halves(out), halves(ff), halves(r));
            // Only the residuals' sum keeps the portable order, block after block, on its
            // carried chain. The counts and the floors are integers below 2⁵³, whose sums
            // are exact in any order, and the largest residual is the same whichever way
            // it is found (no NaN and no −0 where it is used: see `floors_and_mass`), so
            // each of those adds its two blocks first, one step on its chain per eight.
            outside = _mm256_add_pd(outside, _mm256_add_pd(o0, o1));
            floors = _mm256_add_pd(floors, _mm256_add_pd(f0, f1));
            mass = _mm256_add_pd(_mm256_add_pd(mass, r0), r1);
            peak = _mm256_max_pd(peak, _mm256_max_pd(r0, r1));
        }
        let done = w.len() - blocks.remainder().len();
        let lanes = FloorLanes {
            floors: bytemuck::cast(floors),
            mass: bytemuck::cast(mass),
            peak: bytemuck::cast(peak),
            outside: bytemuck::cast(outside),
        };
        (lanes, done)
    }
}
