//! The AVX2 copy: the dispatch that compiles a kernel with AVX2 and FMA, and the intrinsic
//! twin of the normals' candidates for CPUs without AVX-512.
//!
//! LLVM's vectorisation of the portable candidate loop looks the layer edges up one lane
//! at a time and keeps the 64 lanes' state in memory, storing and reloading it every step.
//! The twin keeps four lanes' state in registers through up to 32 lane steps and loads a
//! candidate's two edges, adjacent in the table, in one 16-byte load, as the AVX-512 twin
//! does eight lanes at a time: 1.05 against 1.22 ns per normal. It performs the same
//! IEEE-754 operations in the same order as `normal_candidate`, so the normals are the same
//! bits (tested).

use super::{LaneRng, Simd};

/// `f` compiled with AVX2 and FMA enabled.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn with_avx2<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// Call the AVX2 copy only on a CPU that has AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
#[inline]
pub(super) fn run<R>(f: impl FnOnce() -> R) -> R {
    if has_avx2_fma() {
        // SAFETY: `with_avx2` is safe to call on any CPU that supports AVX2 and FMA, and
        // the run-time check just above established that this one does. The detection
        // result is cached by std, so each check costs one atomic load.
        unsafe { with_avx2(f) }
    } else {
        f()
    }
}

#[cfg(target_arch = "x86_64")]
#[inline]
fn has_avx2_fma() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

/// Proof that the CPU runs the AVX2 twin: made only by [`Avx2::get`], after run-time
/// detection.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Avx2(Private);

#[cfg(target_arch = "x86_64")]
#[derive(Debug, Clone, Copy)]
struct Private;

/// No token can be made off x86-64.
#[cfg(not(target_arch = "x86_64"))]
type Private = std::convert::Infallible;

impl Avx2 {
    /// The token, when `simd` allows the AVX2 copy and the CPU has AVX2 and FMA.
    #[inline]
    pub(crate) fn get(simd: Simd) -> Option<Self> {
        #[cfg(target_arch = "x86_64")]
        {
            (simd != Simd::Portable && has_avx2_fma()).then_some(Avx2(Private))
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = simd;
            None
        }
    }

    /// Standard normals into `out` from `rng`: the twin of
    /// [`LaneRng::fill_normal`](super::LaneRng::fill_normal) (the same draws, the same bits).
    pub(crate) fn fill_normal(self, rng: &mut LaneRng, out: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        {
            let _ = self;
            // SAFETY: the token exists only where run-time detection found AVX2 and FMA,
            // the features `x86::fill_normal` is compiled with.
            #[allow(unsafe_code)]
            unsafe {
                x86::fill_normal(rng, out)
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = (rng, out);
            match self.0 {}
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::super::LANES;
    use super::super::LaneRng;
    use super::super::lanes::State;
    use super::super::tables::{LAYERS, NORMAL};
    use bytemuck::{Pod, Zeroable};
    use std::arch::x86_64::*;

    /// Four lanes' draws, stored 32-byte aligned so that reading them back is forwarded from
    /// the store whatever the stack's alignment.
    #[derive(Clone, Copy, Zeroable, Pod)]
    #[repr(C, align(32))]
    struct Quad([u64; 4]);

    /// The state words of lanes `4g … 4g + 3`.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn load_lanes(s: &State, g: usize) -> [__m256i; 4] {
        std::array::from_fn(|k| {
            let a: [u64; 4] = s[k][4 * g..4 * g + 4].try_into().expect("four lanes");
            bytemuck::cast(a)
        })
    }

    /// Store the state words of lanes `4g … 4g + 3`.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn store_lanes(s: &mut State, g: usize, w: [__m256i; 4]) {
        for (s, v) in s.iter_mut().zip(w) {
            let a: [u64; 4] = bytemuck::cast(v);
            s[4 * g..4 * g + 4].copy_from_slice(&a);
        }
    }

    /// `x` rotated left by `K` bits (`R = 64 − K`), as two shifts.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn rotl<const K: i32, const R: i32>(x: __m256i) -> __m256i {
        _mm256_or_si256(_mm256_slli_epi64::<K>(x), _mm256_srli_epi64::<R>(x))
    }

    /// One xoshiro256++ step of four lanes held in registers (`LaneRng::step`): their
    /// outputs.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn step_regs(w: &mut [__m256i; 4]) -> __m256i {
        let [s0, s1, s2, s3] = *w;
        let out = _mm256_add_epi64(rotl::<23, 41>(_mm256_add_epi64(s0, s3)), s0);
        let t = _mm256_slli_epi64::<17>(s1);
        let s2 = _mm256_xor_si256(s2, s0);
        let s3 = _mm256_xor_si256(s3, s1);
        let s1 = _mm256_xor_si256(s1, s2);
        let s0 = _mm256_xor_si256(s0, s3);
        *w = [s0, s1, _mm256_xor_si256(s2, t), rotl::<45, 19>(s3)];
        out
    }

    /// The candidates of one block of [`LANES`] per lane step, for as many steps as
    /// `rejected` has masks (up to 32), four lanes at a time; a rejected candidate's place
    /// holds its draw and its bit in `rejected` is set (see `LaneRng::fill_normal_blocks`).
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn normal_blocks(s: &mut State, x: &[f64; LAYERS + 1], c: &mut [f64], rejected: &mut [u64]) {
        let two = _mm256_set1_epi64x(0x4000_0000_0000_0000);
        let three = _mm256_set1_pd(3.0);
        let sign = _mm256_set1_pd(-0.0);
        for g in 0..LANES / 4 {
            let mut w = load_lanes(s, g);
            for (block, rej) in c.chunks_exact_mut(LANES).zip(rejected.iter_mut()) {
                let b = step_regs(&mut w);
                let bits: Quad = std::hint::black_box(bytemuck::cast(b));
                let edges = |l: usize| -> __m128d {
                    let i = bits.0[l] as usize & (LAYERS - 1);
                    let p: [f64; 2] = x[i..i + 2].try_into().expect("two edges");
                    bytemuck::cast(p)
                };
                // Lanes 0 and 2, 1 and 3 side by side: unpacking their halves gives the
                // four `x[i]` and the four `x[i+1]` in lane order.
                let v02 = _mm256_set_m128d(edges(2), edges(0));
                let v13 = _mm256_set_m128d(edges(3), edges(1));
                let (xi, xi1) = (_mm256_unpacklo_pd(v02, v13), _mm256_unpackhi_pd(v02, v13));
                // `u ∈ [−1, 1)` from the top 52 bits, as `normal_parts`.
                let u = _mm256_castsi256_pd(_mm256_or_si256(_mm256_srli_epi64::<12>(b), two));
                let v = _mm256_mul_pd(_mm256_sub_pd(u, three), xi);
                let inside = _mm256_cmp_pd::<_CMP_LT_OQ>(_mm256_andnot_pd(sign, v), xi1);
                // A rejected candidate's place holds its draw, for the continuation.
                let v = _mm256_blendv_pd(_mm256_castsi256_pd(b), v, inside);
                let v: [f64; 4] = bytemuck::cast(v);
                block[4 * g..4 * g + 4].copy_from_slice(&v);
                let kept = _mm256_movemask_pd(inside) as u64;
                *rej |= (!kept & 0xf) << (4 * g);
            }
            store_lanes(s, g, w);
        }
    }

    /// [`Avx2::fill_normal`](super::Avx2::fill_normal)'s body.
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn fill_normal(rng: &mut LaneRng, out: &mut [f64]) {
        let x = &NORMAL.x;
        rng.fill_normal_blocks(out, |s, c, r| normal_blocks(s, x, c, r));
    }
}
