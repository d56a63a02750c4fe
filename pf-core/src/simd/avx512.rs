//! The AVX-512 twins of the hottest kernels, written with `core::arch` intrinsics, and the
//! token that proves the CPU runs them.
//!
//! LLVM's own vectorisation of the portable kernels for AVX-512 gained little (a build with
//! `-C target-cpu=native` was a few per cent faster on the filter and 30 % slower on
//! residual resampling): it keeps many-lane arrays in memory,
//! looks tables up one lane at a time and lowers compares to mask-register shuffles. The
//! twins keep eight particles per register, look the 16-entry `exp` table up with one
//! permute, rotate with `vprolq`, count with masked adds, and load a ziggurat candidate's two
//! layer edges together.
//!
//! Each twin performs the same IEEE-754 operations, fused multiply-adds included, in the same
//! order as its portable kernel, so the results are the same bits (tested against the
//! portable and AVX2 copies). The one exception is the Poisson counts' twin in
//! `resample::poisson::avx512`. It inverts in `f32` and keeps a count only where a margin
//! certifies it equal to the `f64` one, and redoes the rest with these blocks, so its
//! counts are the same too. The intrinsics are safe to call inside functions compiled with
//! the features they need; calling such a function is `unsafe` only because of the CPU
//! requirement, which [`Avx512`] discharges once: it exists only after run-time detection.

use super::math::ChunkMap;
use super::{LaneRng, Simd};

/// `$kernel($args)`, a kernel compiled with the AVX-512 features, called behind the token
/// `$cpu`: the body of every safe wrapper of a kernel. Off x86-64 no token exists, and the
/// call is unreachable.
macro_rules! on_avx512 {
    ($cpu:expr, $kernel:path, ($($arg:expr),* $(,)?)) => {{
        let cpu: $crate::simd::avx512::Avx512 = $cpu;
        #[cfg(target_arch = "x86_64")]
        {
            let _ = cpu;
            // SAFETY: the token exists only where run-time detection found the features the
            // kernels are compiled with (see `Avx512::get`).
            #[allow(unsafe_code)]
            unsafe {
                $kernel($($arg),*)
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = ($($arg),*);
            cpu.unreachable()
        }
    }};
}
pub(crate) use on_avx512;

/// Proof that the CPU runs the AVX-512 kernels: made only by [`Avx512::get`], after run-time
/// detection, and taken by each safe wrapper of a kernel.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Avx512(Private);

#[cfg(target_arch = "x86_64")]
#[derive(Debug, Clone, Copy)]
struct Private;

/// No token can be made off x86-64.
#[cfg(not(target_arch = "x86_64"))]
type Private = std::convert::Infallible;

impl Avx512 {
    /// The token, when `simd` is [`Simd::Auto`] and the CPU has AVX-512 F, DQ, BW and VL (and
    /// the AVX2 and FMA they extend). The detection is cached by std: an atomic load each.
    #[inline]
    pub(crate) fn get(simd: Simd) -> Option<Self> {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            let cpu = has!("avx512f")
                && has!("avx512dq")
                && has!("avx512bw")
                && has!("avx512vl")
                && has!("avx2")
                && has!("fma");
            (simd == Simd::Auto && cpu).then_some(Avx512(Private))
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = simd;
            None
        }
    }

    /// The token for a test of a twin, or `None` on a CPU without AVX-512, where the test can
    /// only return early. `scripts/test.sh` says in its log whether the twins' tests ran.
    #[cfg(test)]
    pub(crate) fn for_test() -> Option<Self> {
        let cpu = Self::get(Simd::Auto);
        if cpu.is_none() {
            eprintln!("this CPU lacks AVX-512: the AVX-512 twin is not tested");
        }
        cpu
    }

    /// `l[k] ← exp(l[k] − shift)` for weights with `l[k] ≤ shift`: the batch filter's
    /// weights relative to its chunk maximum, by the twin of
    /// [`exp_fma_nonpositive`](super::math::exp_fma_nonpositive) (the same bits).
    /// `before(o)` runs before the weights from `o` on, for `o` a multiple of 64 (the batch
    /// filter's prefetches for its next chunk).
    pub(crate) fn exp_fma_nonpositive_shifted(
        self,
        l: &mut [f64],
        shift: f64,
        before: impl FnMut(usize),
    ) {
        on_avx512!(self, x86::exp_fma_nonpositive_shifted, (l, shift, before))
    }

    /// Standard normals into `out` from `rng`: the twin of
    /// [`LaneRng::fill_normal`](super::LaneRng::fill_normal) (the same draws, the same bits).
    pub(crate) fn fill_normal(self, rng: &mut LaneRng, out: &mut [f64]) {
        on_avx512!(self, x86::fill_normal, (rng, out))
    }

    /// Systematic resampling's offspring boundaries for a block of the batch filter's
    /// particles: `out[i] = ceil_index_in(map.x(cw[i]) − u, lo, hi)` with
    /// `(lo, hi) = range` (the same indices; see
    /// [`ceil_index_in`](super::math::ceil_index_in)). The ceiling is one conversion with
    /// upward rounding and the clamp two integer compares, where the portable form spends
    /// eight floating-point additions and compares (6 % of the filter at N = 10⁴).
    pub(crate) fn ceil_boundaries(
        self,
        cw: &[f64],
        (map, u): (ChunkMap, f64),
        range: (f64, f64),
        out: &mut [usize],
    ) {
        on_avx512!(self, x86::ceil_boundaries, (cw, map, u, range, out))
    }

    /// The largest of `l` (`−∞` if empty) and whether any is NaN or `+∞`: the batch
    /// filter's chunk maximum, over 32 running maxima in four registers. The portable loop's
    /// four form one chain of dependent `max`es, one per four weights, which bounds it (the
    /// twin makes the filter 3 % faster). Without NaN the result
    /// is the same value; when the largest is zero, either zero.
    pub(crate) fn max_and_flag(self, l: &[f64]) -> (f64, bool) {
        on_avx512!(self, x86::max_and_flag, (l))
    }

    /// `f` compiled with the AVX-512 features, for a generic kernel whose loops LLVM
    /// vectorises itself (the batch filter's chunk step).
    #[inline]
    pub(crate) fn run<R>(self, f: impl FnOnce() -> R) -> R {
        on_avx512!(self, x86::with_avx512, (f))
    }

    /// Off x86-64 no token exists, so nothing that takes one can run.
    #[cfg(not(target_arch = "x86_64"))]
    pub(crate) fn unreachable(self) -> ! {
        match self.0 {}
    }
}

/// The building blocks of the kernels, for eight lanes in one register each. Every function
/// is compiled with `avx2,fma,avx512f,avx512dq,avx512bw,avx512vl`, the features
/// [`Avx512::get`] detects (each `target_feature` attribute repeats them, since an attribute
/// takes a literal), and inlined into its callers.
#[cfg(target_arch = "x86_64")]
pub(crate) mod x86 {
    use super::super::LANES;
    use super::super::LaneRng;
    use super::super::lanes::State;
    use super::super::math::{
        ChunkMap, EXP_TAYLOR, EXP2_16THS, LN2_HI, LN2_LO, ROUND_MAGIC, ceil_index_in,
        exp_fma_nonpositive,
    };
    use super::super::tables::{LAYERS, NORMAL};
    use crate::buffer::Line;
    use std::arch::x86_64::*;

    /// Eight doubles from a slice of exactly eight.
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    pub(crate) fn load_pd(x: &[f64]) -> __m512d {
        let a: [f64; 8] = x.try_into().expect("eight lanes");
        bytemuck::cast(a)
    }

    /// The eight lanes of `v`.
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    pub(crate) fn lanes_pd(v: __m512d) -> [f64; 8] {
        bytemuck::cast(v)
    }

    /// One xoshiro256++ step of lanes `8g … 8g + 7` of a [`LaneRng`]'s
    /// state (the same step as `LaneRng::step`, with `vprolq` for the rotations): their eight
    /// outputs.
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    pub(crate) fn step8(s: &mut State, g: usize) -> __m512i {
        let mut w = load_lanes(s, g);
        let out = step_regs(&mut w);
        store_lanes(s, g, w);
        out
    }

    /// The state words of lanes `8g … 8g + 7`.
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    fn load_lanes(s: &State, g: usize) -> [__m512i; 4] {
        std::array::from_fn(|k| {
            let a: [u64; 8] = s[k][8 * g..8 * g + 8].try_into().expect("eight lanes");
            bytemuck::cast(a)
        })
    }

    /// Store the state words of lanes `8g … 8g + 7`.
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    fn store_lanes(s: &mut State, g: usize, w: [__m512i; 4]) {
        for (s, v) in s.iter_mut().zip(w) {
            let a: [u64; 8] = bytemuck::cast(v);
            s[8 * g..8 * g + 8].copy_from_slice(&a);
        }
    }

    /// One xoshiro256++ step of eight lanes held in registers: their outputs.
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    fn step_regs(w: &mut [__m512i; 4]) -> __m512i {
        let [s0, s1, s2, s3] = *w;
        let out = _mm512_add_epi64(_mm512_rol_epi64::<23>(_mm512_add_epi64(s0, s3)), s0);
        let t = _mm512_slli_epi64::<17>(s1);
        // The step's xors, three words to a `vpternlogq` (`0x96`: `a ^ b ^ c`).
        let s3x = _mm512_xor_si512(s3, s1);
        *w = [
            _mm512_ternarylogic_epi64::<0x96>(s0, s3, s1),
            _mm512_ternarylogic_epi64::<0x96>(s1, s2, s0),
            _mm512_ternarylogic_epi64::<0x96>(s2, s0, t),
            _mm512_rol_epi64::<45>(s3x),
        ];
        out
    }

    /// [`unit_from_bits`](super::super::math::unit_from_bits) of each lane: `⌊b/2¹²⌋·2⁻⁵²`.
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    pub(crate) fn unit8(b: __m512i) -> __m512d {
        let one = _mm512_set1_epi64(0x3ff0_0000_0000_0000);
        let x = _mm512_or_si512(_mm512_srli_epi64::<12>(b), one);
        _mm512_sub_pd(_mm512_castsi512_pd(x), _mm512_set1_pd(1.0))
    }

    /// The table of [`exp_fma8`], in two registers.
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    pub(crate) fn exp_table() -> [__m512d; 2] {
        let lo: [u64; 8] = EXP2_16THS[..8].try_into().expect("eight entries");
        let hi: [u64; 8] = EXP2_16THS[8..].try_into().expect("eight entries");
        [bytemuck::cast(lo), bytemuck::cast(hi)]
    }

    /// [`exp_fma`](super::super::math::exp_fma) of each lane, the same operations in the
    /// same order; `table` from [`exp_table`].
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    pub(crate) fn exp_fma8(x: __m512d, table: &[__m512d; 2]) -> __m512d {
        let magic = _mm512_set1_pd(ROUND_MAGIC);
        let t = _mm512_fmadd_pd(x, _mm512_set1_pd(16.0 / std::f64::consts::LN_2), magic);
        let nf = _mm512_sub_pd(t, magic);
        let r = _mm512_fnmadd_pd(nf, _mm512_set1_pd(LN2_HI / 16.0), x);
        let r = _mm512_fnmadd_pd(nf, _mm512_set1_pd(LN2_LO / 16.0), r);
        let [a6, a5, a4, a3, a2, a1, a0] = EXP_TAYLOR.map(|c| _mm512_set1_pd(c));
        let r2 = _mm512_mul_pd(r, r);
        let r4 = _mm512_mul_pd(r2, r2);
        let q0 = _mm512_fmadd_pd(r, a1, a0);
        let q1 = _mm512_fmadd_pd(r, a3, a2);
        let q2 = _mm512_fmadd_pd(r, a5, a4);
        let s0 = _mm512_fmadd_pd(r2, q1, q0);
        let s1 = _mm512_fmadd_pd(r2, a6, q2);
        let p = _mm512_mul_pd(_mm512_fmadd_pd(r4, s1, s0), r);
        let bits = _mm512_castpd_si512(t);
        let k = _mm512_srai_epi64::<4>(_mm512_sub_epi64(bits, _mm512_castpd_si512(magic)));
        // The permute reads the low four bits of each index: `bits & 15`.
        let entry = _mm512_permutex2var_pd(table[0], bits, table[1]);
        let s = _mm512_add_epi64(_mm512_castpd_si512(entry), _mm512_slli_epi64::<52>(k));
        let s = _mm512_castsi512_pd(s);
        _mm512_fmadd_pd(s, p, s)
    }

    /// [`exp_fma_nonpositive`] of `l[k] − shift` into `l[k]`, eight at a time: [`exp_fma8`]
    /// (the same operations in the same order) and the mask below −708.
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    pub(super) fn exp_fma_nonpositive_shifted(
        l: &mut [f64],
        shift: f64,
        mut before: impl FnMut(usize),
    ) {
        let table = exp_table();
        let sh = _mm512_set1_pd(shift);
        for (o, big) in l.chunks_mut(64).enumerate() {
            before(64 * o);
            let mut blocks = big.chunks_exact_mut(8);
            for b in &mut blocks {
                let x = _mm512_sub_pd(load_pd(b), sh);
                let y = exp_fma8(x, &table);
                let inside = _mm512_cmp_pd_mask::<_CMP_GE_OQ>(x, _mm512_set1_pd(-708.0));
                let y: [f64; 8] = bytemuck::cast(_mm512_maskz_mov_pd(inside, y));
                b.copy_from_slice(&y);
            }
            for v in blocks.into_remainder() {
                *v = exp_fma_nonpositive(*v - shift);
            }
        }
    }

    /// Lane steps and their standard normal candidates, one step per block of [`LANES`]
    /// slots of `c` (whose length is `LANES · rejected.len()`), with each block's mask of
    /// rejected candidates or-ed into `rejected`: the twin of `LaneRng::step` and the
    /// candidate loop of `LaneRng::fill_ziggurat` with `normal_candidate`, the same bits,
    /// except that a rejected candidate's slot holds its draw (see
    /// `LaneRng::fill_normal_blocks`).
    ///
    /// The blocks are filled eight lanes at a time, through all the blocks, so that those
    /// lanes' state stays in registers instead of a load and a store per word and step.
    /// Each candidate's layer edges `x[i]` and `x[i+1]` are adjacent, so they come in one
    /// 16-byte load, and two permutes sort eight such pairs into the two registers (hardware
    /// gathers are slower than the AVX2 copy's scalar loads).
    #[inline]
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    fn normal_blocks(s: &mut State, x: &[f64; LAYERS + 1], c: &mut [f64], rejected: &mut [u64]) {
        let even = _mm512_setr_epi64(0, 2, 4, 6, 8, 10, 12, 14);
        let odd = _mm512_setr_epi64(1, 3, 5, 7, 9, 11, 13, 15);
        for g in 0..LANES / 8 {
            let mut w = load_lanes(s, g);
            for (block, rej) in c.chunks_exact_mut(LANES).zip(rejected.iter_mut()) {
                let b = step_regs(&mut w);
                // The indices go through memory, one store and eight loads: without
                // `black_box`, LLVM moved each out of the register by `vmovd`/`vpextrd`
                // (eight vector-to-integer transfers per step), and the normals were 12 %
                // slower. The store fills a 64-byte aligned `Line`, so that store-to-load
                // forwarding does not depend on the stack's alignment: a 64-byte store 16
                // bytes past a 32-byte boundary is not forwarded on some CPUs, which made
                // the filter 1.6× slower in half of all processes.
                let bits: Line = std::hint::black_box(bytemuck::cast(b));
                let bits: &[u64; 8] = bytemuck::cast_ref(&bits);
                let edges = |l: usize| -> __m128d {
                    let i = bits[l] as usize & (LAYERS - 1);
                    let p: [f64; 2] = x[i..i + 2].try_into().expect("two edges");
                    bytemuck::cast(p)
                };
                let four = |l: usize| {
                    let v = _mm512_castpd128_pd512(edges(l));
                    let v = _mm512_insertf64x2::<1>(v, edges(l + 1));
                    let v = _mm512_insertf64x2::<2>(v, edges(l + 2));
                    _mm512_insertf64x2::<3>(v, edges(l + 3))
                };
                let (lo, hi) = (four(0), four(4));
                let (xi, xi1) = (
                    _mm512_permutex2var_pd(lo, even, hi),
                    _mm512_permutex2var_pd(lo, odd, hi),
                );
                // `u ∈ [−1, 1)` from the top 52 bits, as `normal_parts`.
                let two = _mm512_set1_epi64(0x4000_0000_0000_0000);
                let u = _mm512_castsi512_pd(_mm512_or_si512(_mm512_srli_epi64::<12>(b), two));
                let u = _mm512_sub_pd(u, _mm512_set1_pd(3.0));
                let v = _mm512_mul_pd(u, xi);
                let inside = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(_mm512_abs_pd(v), xi1);
                // A rejected candidate's place holds its draw, for the continuation.
                let v = _mm512_mask_blend_pd(inside, _mm512_castsi512_pd(b), v);
                block[8 * g..8 * g + 8].copy_from_slice(&lanes_pd(v));
                *rej |= u64::from(!inside) << (8 * g);
            }
            store_lanes(s, g, w);
        }
    }

    /// [`Avx512::ceil_boundaries`](super::Avx512::ceil_boundaries)'s body.
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    pub(super) fn ceil_boundaries(
        cw: &[f64],
        map: ChunkMap,
        u: f64,
        (lo, hi): (f64, f64),
        out: &mut [usize],
    ) {
        // `map.x(cw) − u`, the same operations in the same order.
        let (off, scale) = (_mm512_set1_pd(map.offset), _mm512_set1_pd(map.scale));
        let (s, u_v) = (_mm512_set1_pd(map.n_over_total), _mm512_set1_pd(u));
        // `lo ≤ hi < 2⁵¹` are integers.
        let (lo_i, hi_i) = (_mm512_set1_epi64(lo as i64), _mm512_set1_epi64(hi as i64));
        let mut blocks = out.chunks_exact_mut(8);
        for (o, c) in (&mut blocks).zip(cw.chunks_exact(8)) {
            let g = _mm512_add_pd(off, _mm512_mul_pd(scale, load_pd(c)));
            let x = _mm512_sub_pd(_mm512_mul_pd(g, s), u_v);
            // ⌈x⌉, exact for |x| < 2⁶³ (and x < 2⁵¹ here), then clamped to [lo, hi].
            let c = _mm512_cvt_roundpd_epi64::<{ _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC }>(x);
            let c = _mm512_min_epi64(_mm512_max_epi64(c, lo_i), hi_i);
            let k: [usize; 8] = bytemuck::cast(_mm512_sub_epi64(c, lo_i));
            o.copy_from_slice(&k);
        }
        let rest = blocks.into_remainder();
        let n = rest.len();
        for (o, &c) in rest.iter_mut().zip(&cw[cw.len() - n..]) {
            *o = ceil_index_in(map.x(c) - u, lo, hi);
        }
    }

    /// [`Avx512::run`](super::Avx512::run)'s body.
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    pub(super) fn with_avx512<R>(f: impl FnOnce() -> R) -> R {
        f()
    }

    /// [`Avx512::max_and_flag`](super::Avx512::max_and_flag)'s body.
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    pub(super) fn max_and_flag(l: &[f64]) -> (f64, bool) {
        let inf = _mm512_set1_pd(f64::INFINITY);
        let mut m = [_mm512_set1_pd(f64::NEG_INFINITY); 4];
        let mut bad: __mmask8 = 0;
        let mut blocks = l.chunks_exact(32);
        for b in &mut blocks {
            for (q, m) in m.iter_mut().enumerate() {
                let v = load_pd(&b[8 * q..8 * q + 8]);
                bad |= _mm512_cmp_pd_mask::<_CMP_NLT_UQ>(v, inf);
                *m = _mm512_max_pd(v, *m);
            }
        }
        let m = _mm512_max_pd(_mm512_max_pd(m[0], m[1]), _mm512_max_pd(m[2], m[3]));
        let mut best = f64::NEG_INFINITY;
        for v in lanes_pd(m) {
            best = if v > best { v } else { best };
        }
        let (rest, rest_bad) = super::super::math::max_and_flag(blocks.remainder());
        (if rest > best { rest } else { best }, bad != 0 || rest_bad)
    }

    /// [`Avx512::fill_normal`](super::Avx512::fill_normal)'s body.
    #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
    pub(super) fn fill_normal(rng: &mut LaneRng, out: &mut [f64]) {
        let x = &NORMAL.x;
        rng.fill_normal_blocks(out, |s, c, r| normal_blocks(s, x, c, r));
    }

    #[cfg(test)]
    mod tests {
        use super::super::Avx512;
        use super::*;
        use crate::mc::stream_rng;
        use crate::simd::LaneRng;
        use crate::simd::math::{exp_fma, unit_from_bits};

        /// The twins' `exp` of each value.
        #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
        fn exp_twin(xs: &[f64]) -> Vec<f64> {
            let table = exp_table();
            xs.chunks_exact(8)
                .flat_map(|x| lanes_pd(exp_fma8(load_pd(x), &table)))
                .collect()
        }

        /// Three lane steps, eight lanes at a time: each group's raw bits, then its uniforms'.
        #[target_feature(enable = "avx2,fma,avx512f,avx512dq,avx512bw,avx512vl")]
        fn lanes_twin(a: &mut LaneRng) -> Vec<u64> {
            let mut out = Vec::new();
            for _ in 0..3 {
                for g in 0..LANES / 8 {
                    let v = step8(a.state(), g);
                    out.extend(bytemuck::cast::<_, [u64; 8]>(v));
                    out.extend(lanes_pd(unit8(v)).map(f64::to_bits));
                }
            }
            out
        }

        /// The filter's `exp` twin gives `exp_fma_nonpositive`'s bits, over its whole range and
        /// beyond (0 below −708, also for −∞), on lengths that end inside a register.
        #[test]
        fn exp_fma_nonpositive_twin_matches() {
            let Some(cpu) = Avx512::for_test() else {
                return;
            };
            for len in [1usize, 8, 13, 64, 1000] {
                let shift = 3.5;
                let l: Vec<f64> = (0..len)
                    .map(|i| match i % 7 {
                        0 => f64::NEG_INFINITY,
                        1 => shift - 708.5,
                        2 => shift,
                        _ => shift - 709.0 * (i as f64 / len as f64).powi(3),
                    })
                    .collect();
                let mut got = l.clone();
                cpu.exp_fma_nonpositive_shifted(&mut got, shift, |_| ());
                for (x, y) in l.iter().zip(&got) {
                    let want = crate::simd::math::exp_fma_nonpositive(x - shift);
                    assert_eq!(y.to_bits(), want.to_bits(), "x = {x}");
                }
            }
        }

        /// The boundaries twin gives `ceil_index_in`'s indices: at, just above and just below
        /// integers, below `lo` and above `hi`, through a map that is the identity and
        /// through one that is not, on lengths that end inside a register.
        #[test]
        fn ceil_boundaries_match_the_portable_index() {
            let Some(cpu) = Avx512::for_test() else {
                return;
            };
            let cw: Vec<f64> = (-20..140)
                .flat_map(|i| {
                    let x = f64::from(i);
                    [x, x.next_up(), x.next_down(), x + 0.5, -0.0]
                })
                .collect();
            let maps = [
                (
                    ChunkMap {
                        offset: 0.0,
                        scale: 1.0,
                        n_over_total: 1.0,
                    },
                    0.0,
                ),
                (
                    ChunkMap {
                        offset: 0.3,
                        scale: 0.7,
                        n_over_total: 1.3,
                    },
                    0.731,
                ),
            ];
            for (map, u) in maps {
                for len in [cw.len(), cw.len() - 3, 5] {
                    let (lo, hi) = (3.0, 100.0);
                    let mut got = vec![usize::MAX; len];
                    cpu.ceil_boundaries(&cw[..len], (map, u), (lo, hi), &mut got);
                    for (&c, &k) in cw.iter().zip(&got) {
                        let want = ceil_index_in(map.x(c) - u, lo, hi);
                        assert_eq!(k, want, "cw = {c}, {map:?}, u = {u}");
                    }
                }
            }
        }

        /// The twins give the portable functions' bits: `exp` over the Poisson rates and
        /// beyond, the lane step, and the uniforms (on a CPU without AVX-512 there is
        /// nothing to compare).
        #[test]
        fn twins_match_the_portable_functions() {
            let xs: Vec<f64> = (0..4096)
                .map(|i| match i % 4 {
                    0 => 12.0 * i as f64 / 4096.0,
                    1 => -708.0 + 1417.0 * i as f64 / 4096.0,
                    2 => (i as f64 * 1e-3).powi(3),
                    _ => i as f64 * std::f64::consts::LN_2 / 16.0 % 700.0,
                })
                .collect();
            let Some(_) = Avx512::for_test() else {
                return;
            };
            // SAFETY: the token exists only where the CPU has the features.
            #[allow(unsafe_code)]
            let got = unsafe { exp_twin(&xs) };
            {
                for (x, y) in xs.iter().zip(got) {
                    assert_eq!(y.to_bits(), exp_fma(*x).to_bits(), "x = {x}");
                }
            }
            let mut a = LaneRng::from_rng(&mut stream_rng(9, 0));
            let mut b = a.clone();
            // SAFETY: as above.
            #[allow(unsafe_code)]
            let got = unsafe { lanes_twin(&mut a) };
            {
                let mut want = Vec::new();
                for _ in 0..3 {
                    let mut bits = [0u64; LANES];
                    b.step(&mut bits);
                    for g in bits.chunks_exact(8) {
                        want.extend(g);
                        want.extend(g.iter().map(|&x| unit_from_bits(x).to_bits()));
                    }
                }
                assert_eq!(got, want);
            }
        }
    }
}
