//! The AVX-512 twin of stratified resampling's boundaries
//! ([`stratified_index_in`](super::stratified::stratified_index_in) over a block): eight
//! particles to a register, with SplitMix64's two 64-bit multiplies in one instruction
//! each (`vpmullq`), where AVX2 takes three 32-bit steps. The floor, the hash, the uniform
//! and the clamp are the portable function's operations, so the boundaries are its own, bit
//! for bit, whatever the weights (tested in `stratified`).

use crate::simd::avx512::{Avx512, on_avx512};

/// `k[j] ←` the boundary of the particle whose cumulative weight is `c[j]`, for the whole
/// groups of eight: `stratified_index_in(mf·c[j], key, 0, mf)`. Returns how many it set.
pub(crate) fn boundaries(cpu: Avx512, c: &[f64], key: u64, mf: f64, k: &mut [usize]) -> usize {
    on_avx512!(cpu, x86::boundaries, (c, key, mf, k))
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use crate::mc::{GAMMA, SPLITMIX_MULTIPLIERS};
    use crate::simd::avx512::x86::load_pd;
    use crate::simd::math::ROUND_MAGIC;
    use std::arch::x86_64::*;

    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    pub(super) fn boundaries(c: &[f64], key: u64, mf: f64, k: &mut [usize]) -> usize {
        let magic = _mm512_set1_pd(ROUND_MAGIC);
        let magic_bits = _mm512_set1_epi64(ROUND_MAGIC.to_bits() as i64);
        let (zero, one, m) = (_mm512_setzero_pd(), _mm512_set1_pd(1.0), _mm512_set1_pd(mf));
        let ones = _mm512_set1_epi64(1);
        let mix = SPLITMIX_MULTIPLIERS.map(|c| _mm512_set1_epi64(c as i64));
        let (gamma, key) = (
            _mm512_set1_epi64(GAMMA as i64),
            _mm512_set1_epi64(key as i64),
        );
        let exponent = _mm512_set1_epi64(0x3ff0_0000_0000_0000);
        let mut groups = c.chunks_exact(8).zip(k.chunks_exact_mut(8));
        for (c, k) in &mut groups {
            let x = _mm512_mul_pd(m, load_pd(c));
            // `floor_index(x)`: the nearest integer by the magic number, less one where it
            // lies above `x`.
            let t = _mm512_add_pd(x, magic);
            let r = _mm512_sub_pd(t, magic);
            let above = _mm512_cmp_pd_mask::<_CMP_GT_OQ>(r, x);
            let f = _mm512_sub_epi64(_mm512_castpd_si512(t), magic_bits);
            let f = _mm512_mask_sub_epi64(f, above, f, ones);
            let ff = _mm512_mask_sub_pd(r, above, r, one);
            // `stratum_uniform(key, f)`: SplitMix64 at `key + (f + 1)·γ`, its top 52 bits
            // as a uniform on [0, 1).
            let z = _mm512_mullo_epi64(_mm512_add_epi64(f, ones), gamma);
            let z = _mm512_add_epi64(z, key);
            let z = _mm512_mullo_epi64(_mm512_xor_si512(z, _mm512_srli_epi64::<30>(z)), mix[0]);
            let z = _mm512_mullo_epi64(_mm512_xor_si512(z, _mm512_srli_epi64::<27>(z)), mix[1]);
            let z = _mm512_xor_si512(z, _mm512_srli_epi64::<31>(z));
            let u = _mm512_or_si512(_mm512_srli_epi64::<12>(z), exponent);
            let u = _mm512_sub_pd(_mm512_castsi512_pd(u), one);
            // `f + [U_f < x − f]`, clamped to [0, M] (a NaN passes both), as an index.
            let below = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(u, _mm512_sub_pd(x, ff));
            let kf = _mm512_mask_add_pd(ff, below, ff, one);
            let kf = _mm512_mask_mov_pd(kf, _mm512_cmp_pd_mask::<_CMP_LT_OQ>(kf, zero), zero);
            let kf = _mm512_mask_mov_pd(kf, _mm512_cmp_pd_mask::<_CMP_GT_OQ>(kf, m), m);
            let index = _mm512_sub_epi64(_mm512_castpd_si512(_mm512_add_pd(kf, magic)), magic_bits);
            let out: [u64; 8] = bytemuck::cast(index);
            for (k, o) in k.iter_mut().zip(out) {
                *k = o as usize;
            }
        }
        c.len() - c.len() % 8
    }
}
