//! [`LaneRng`]: 64 xoshiro256++ generators in lock-step, and vectorised ziggurat samplers
//! on top of them.

use super::avx2::Avx2;
use super::avx512::Avx512;
use super::math::exp_nonpositive;
use super::tables::{EXPONENTIAL, LAYERS, NORMAL, Ziggurat};
use super::{Simd, dispatch, set_bits};
use crate::mc::PfRng;
use rand::{Rng, RngExt, SeedableRng};
use rand_distr::Open01;

/// Number of xoshiro256++ lanes stepped together (sixteen AVX2 registers per state word).
pub const LANES: usize = 64;

/// A vectorisable random stream: [`LANES`] independent xoshiro256++ generators stepped in
/// lock-step, plus one scalar xoshiro256++ stream for the rare ziggurat rejections.
///
/// - **Raw bits.** Draw `p` of the stream is output `⌊p / 64⌋` of lane `p mod 64`: each lane
///   is exactly `rand`'s `Xoshiro256PlusPlus` (tested), whose step is adds, xors and shifts
///   only, so 64 of them step as 16 AVX2 registers' worth of integer instructions. (64
///   rather than 4 or 8: with fewer lanes LLVM fully unrolls the step and then keeps one of
///   its rotations in scalar registers.)
/// - **Seeding.** [`LaneRng::from_rng`] takes 256 outputs of a generator as the lanes' 256-bit
///   states (lane `l` gets outputs `4l … 4l+3`) and 4 more as the fix-up stream's state.
///   The engine seeds it from [`stream_rng`](crate::mc::stream_rng)`(seed, r)`, so all
///   seeding stays explicit.
/// - **Normals and exponentials** come from the ziggurat of Marsaglia & Tsang (2000) in
///   `rand_distr`'s layout with 1024 layers instead of 256 (tables built at first use in
///   `tables`, which says why): one 64-bit draw per candidate (the low 10 bits for the
///   layer, the top 52 for the uniform), accepted inside the layer's rectangle (99.6 % of
///   the time for the normal) by a branch-free vectorised pass. A rejected
///   candidate continues as `rand_distr`'s ziggurat does (wedge test, or tail for layer 0,
///   then fresh candidates), with its extra uniforms from the fix-up stream, so every value
///   is an exact draw from the target law and values in distinct slots are independent. The
///   wedge test's density comes from [`exp_nonpositive`] (within 2 ulp of libm's), which is
///   cheaper than a libm call on a path taken for about one candidate in a hundred.
///   Where the CPU has AVX-512, [`fill_normal`](Self::fill_normal) makes the candidates on
///   an intrinsic twin (eight lanes to a register, kept there through 32 lane steps,
///   `vprolq` for the rotations, a candidate's two layer edges in one load, its layer
///   index read back from memory), and where it has only AVX2 and FMA on a four-lane twin
///   of it: 0.80 and 1.05 against 1.22 ns per normal for the AVX2 copy LLVM vectorises, the
///   same bits.
///
/// A call that fills `m` values consumes `⌈m / 64⌉` lane steps (a partial last step is
/// discarded), so the values depend on how a stream is cut into calls, never on the thread
/// that runs them or on the instruction set.
#[derive(Debug, Clone)]
#[repr(align(64))]
pub struct LaneRng {
    /// `s[k][l]`: word `k` of lane `l`'s state.
    s: State,
    /// The scalar stream that continues rejected ziggurat candidates.
    fix: PfRng,
}

impl LaneRng {
    /// Seed the lanes and the fix-up stream from `4·LANES + 4` outputs of `rng`.
    pub fn from_rng<R: Rng + ?Sized>(rng: &mut R) -> Self {
        let mut s = [[0u64; LANES]; 4];
        for l in 0..LANES {
            for word in &mut s {
                word[l] = rng.next_u64();
            }
            if (0..4).all(|k| s[k][l] == 0) {
                // xoshiro's one forbidden state (probability 2⁻²⁵⁶).
                s[0][l] = 1;
            }
        }
        let mut seed = [0u8; 32];
        for b in seed.chunks_exact_mut(8) {
            b.copy_from_slice(&rng.next_u64().to_le_bytes());
        }
        LaneRng {
            s,
            fix: PfRng::from_seed(seed),
        }
    }

    /// One lock-step xoshiro256++ step: one output per lane into `out` (the raw bits, for
    /// samplers built on the lanes inside a dispatched kernel). The caller's buffer is reused
    /// from step to step: returning a fresh array zero-filled it first, a quarter to half an
    /// instruction per draw.
    #[inline(always)]
    #[allow(clippy::manual_rotate)] // `rotate_left` was lowered to scalar `rol`s here
    pub(crate) fn step(&mut self, out: &mut [u64; LANES]) {
        let [s0, s1, s2, s3] = &mut self.s;
        for l in 0..LANES {
            // Rotations as shift pairs: LLVM keeps those in vector registers.
            let sum = s0[l].wrapping_add(s3[l]);
            out[l] = ((sum << 23) | (sum >> 41)).wrapping_add(s0[l]);
            let t = s1[l] << 17;
            s2[l] ^= s0[l];
            s3[l] ^= s1[l];
            s1[l] ^= s2[l];
            s0[l] ^= s3[l];
            s2[l] ^= t;
            s3[l] = (s3[l] << 45) ^ (s3[l] >> 19);
        }
    }

    /// The lanes' state, `s[k][l]` word `k` of lane `l`: for the AVX-512 kernels, which step
    /// eight lanes at a time (`simd::avx512::x86::step8`).
    #[inline(always)]
    pub(crate) fn state(&mut self) -> &mut State {
        &mut self.s
    }

    /// Fill `out` (length a multiple of [`LANES`]) with raw 64-bit draws.
    #[cfg(test)]
    fn fill_bits(&mut self, out: &mut [u64]) {
        debug_assert_eq!(out.len() % LANES, 0);
        for block in out.chunks_exact_mut(LANES) {
            let block: &mut [u64; LANES] = block.try_into().expect("a whole lane step");
            self.step(block);
        }
    }

    /// Fill `out` with independent standard normals (vectorised ziggurat).
    pub fn fill_normal(&mut self, out: &mut [f64]) {
        self.fill_normal_with(Simd::Auto, out);
    }

    /// [`fill_normal`](Self::fill_normal) on the chosen kernel (the numbers are the same).
    pub fn fill_normal_with(&mut self, simd: Simd, out: &mut [f64]) {
        match (Avx512::get(simd), Avx2::get(simd)) {
            (None, None) => dispatch(
                simd,
                #[inline(always)]
                || self.fill_normal_inline(out),
            ),
            twins => self.fill_normal_on(twins, out),
        }
    }

    /// The normals on the widest twin the tokens allow (AVX-512, else AVX2), or without
    /// either on the copy the caller is compiled in: for callers already inside a
    /// dispatched kernel, which hold the tokens.
    #[inline(always)]
    pub(crate) fn fill_normal_on(
        &mut self,
        twins: (Option<Avx512>, Option<Avx2>),
        out: &mut [f64],
    ) {
        match twins {
            (Some(cpu), _) => cpu.fill_normal(self, out),
            (None, Some(cpu)) => cpu.fill_normal(self, out),
            (None, None) => self.fill_normal_inline(out),
        }
    }

    /// Fill `out` with independent unit exponentials (vectorised ziggurat).
    pub fn fill_exp1(&mut self, out: &mut [f64]) {
        self.fill_exp1_with(Simd::Auto, out);
    }

    /// [`fill_exp1`](Self::fill_exp1) on the chosen kernel (the numbers are the same).
    pub fn fill_exp1_with(&mut self, simd: Simd, out: &mut [f64]) {
        dispatch(
            simd,
            #[inline(always)]
            || self.fill_exp1_inline(out),
        );
    }

    /// The normal sampler's body, for callers already inside a dispatched kernel.
    #[inline(always)]
    pub(crate) fn fill_normal_inline(&mut self, out: &mut [f64]) {
        let z: &Ziggurat = &NORMAL;
        self.fill_ziggurat(
            out,
            #[inline(always)]
            |b| normal_candidate(z, b),
            |b, rng| normal_continue(z, b, rng),
        );
    }

    /// The normal sampler with `blocks` stepping the lanes once per block of [`LANES`]
    /// slots of its output and making their candidates in place, a rejected one as its
    /// draw's bits (`f64::from_bits`, read back by the continuation: one store fewer per
    /// eight candidates than a separate array of draws), and or-ing each block's mask of
    /// those rejected into its mask slice: for the AVX-512 twin, with the same bits as
    /// [`fill_normal_inline`](Self::fill_normal_inline). Up to [`COLUMN_BLOCKS`] blocks go
    /// to one call, then their rejected candidates are continued in order. The loop repeats
    /// [`fill_ziggurat`](Self::fill_ziggurat)'s rather than sharing it: passed through a
    /// closure, the AVX2 copy's candidate loop stopped vectorising (1.5 against 1.2 ns per
    /// normal).
    #[inline(always)]
    pub(crate) fn fill_normal_blocks(
        &mut self,
        out: &mut [f64],
        mut blocks: impl FnMut(&mut State, &mut [f64], &mut [u64]),
    ) {
        let z: &Ziggurat = &NORMAL;
        let mut rejected = [0u64; COLUMN_BLOCKS];
        let whole = out.len() / LANES * LANES;
        let (full, rest) = out.split_at_mut(whole);
        for group in full.chunks_mut(LANES * COLUMN_BLOCKS) {
            let rejected = &mut rejected[..group.len() / LANES];
            rejected.fill(0);
            blocks(&mut self.s, group, rejected);
            for (chunk, &r) in group.chunks_exact_mut(LANES).zip(rejected.iter()) {
                for p in set_bits(r) {
                    chunk[p] = normal_continue(z, chunk[p].to_bits(), &mut self.fix);
                }
            }
        }
        if !rest.is_empty() {
            let len = rest.len();
            let mut tail = [0.0f64; LANES];
            let mut r = [0u64];
            blocks(&mut self.s, &mut tail, &mut r);
            rest.copy_from_slice(&tail[..len]);
            for p in set_bits(r[0] & ((1u64 << len) - 1)) {
                rest[p] = normal_continue(z, tail[p].to_bits(), &mut self.fix);
            }
        }
    }

    /// The exponential sampler's body, for callers already inside a dispatched kernel.
    #[inline(always)]
    pub(crate) fn fill_exp1_inline(&mut self, out: &mut [f64]) {
        let z: &Ziggurat = &EXPONENTIAL;
        self.fill_ziggurat(
            out,
            #[inline(always)]
            |b| exp1_candidate(z, b),
            |b, rng| exp1_continue(z, b, rng),
        );
    }

    /// One lane step per [`LANES`] values: its draws become candidates in place (NaN where a
    /// candidate falls outside its rectangle), a bit mask marks those, and only the marked
    /// ones are continued on the scalar stream, in order.
    #[inline(always)]
    fn fill_ziggurat(
        &mut self,
        out: &mut [f64],
        candidate: impl Fn(u64) -> f64,
        continue_from: impl Fn(u64, &mut PfRng) -> f64,
    ) {
        let mut tail = [0.0f64; LANES];
        let mut draws = [0u64; LANES];
        for chunk in out.chunks_mut(LANES) {
            self.step(&mut draws);
            let fill = |c: &mut [f64]| {
                let mut rejected = 0u64;
                for (l, (c, &b)) in c.iter_mut().zip(draws.iter()).enumerate() {
                    *c = candidate(b);
                    rejected |= u64::from(c.is_nan()) << l;
                }
                rejected
            };
            // A whole step runs on the output itself, a partial last one on `tail`: with the
            // length unknown to the compiler the candidate loop stops vectorising (76.7
            // against 65.2 instructions per particle-step in the filter).
            let len = chunk.len();
            let rejected = if len == LANES {
                fill(chunk)
            } else {
                let r = fill(&mut tail);
                chunk.copy_from_slice(&tail[..len]);
                r & ((1u64 << len) - 1)
            };
            for p in set_bits(rejected) {
                chunk[p] = continue_from(draws[p], &mut self.fix);
            }
        }
    }
}

/// Blocks of [`LANES`] normals whose candidates the AVX-512 twin makes in one call (see
/// [`LaneRng::fill_normal_blocks`]): the batch filter's chunk of 2048.
const COLUMN_BLOCKS: usize = 32;

/// The lanes' state: `s[k][l]` is word `k` of lane `l`.
pub(crate) type State = [[u64; LANES]; 4];

/// Layer index (low 10 bits) and uniform in [−1, 1) (top 52 bits) of a normal candidate.
#[inline(always)]
fn normal_parts(b: u64) -> (usize, f64) {
    let u = f64::from_bits((b >> 12) | 0x4000_0000_0000_0000) - 3.0;
    ((b as usize) & (LAYERS - 1), u)
}

/// Layer index (low 10 bits) and uniform in (0, 1) (top 52 bits) of an exponential
/// candidate.
#[inline(always)]
fn exp1_parts(b: u64) -> (usize, f64) {
    let u = f64::from_bits((b >> 12) | 0x3ff0_0000_0000_0000) - (1.0 - f64::EPSILON / 2.0);
    ((b as usize) & (LAYERS - 1), u)
}

/// The candidate `u·X[i]` if it lies inside layer `i`'s rectangle, NaN (a marker) otherwise.
#[inline(always)]
fn normal_candidate(z: &Ziggurat, b: u64) -> f64 {
    let (i, u) = normal_parts(b);
    let x = u * z.x[i];
    if x.abs() < z.x[i + 1] { x } else { f64::NAN }
}

#[inline(always)]
fn exp1_candidate(z: &Ziggurat, b: u64) -> f64 {
    let (i, u) = exp1_parts(b);
    let x = u * z.x[i];
    if x < z.x[i + 1] { x } else { f64::NAN }
}

/// The ziggurat for the standard normal (as in `rand_distr`), started from the 64-bit draw
/// `b`, with further uniforms from `rng`.
#[cold]
fn normal_continue(z: &Ziggurat, mut b: u64, rng: &mut PfRng) -> f64 {
    loop {
        let (i, u) = normal_parts(b);
        let x = u * z.x[i];
        if x.abs() < z.x[i + 1] {
            return x;
        }
        if i == 0 {
            // The tail beyond R (Marsaglia 1964).
            let (mut x, mut y) = (1.0f64, 0.0f64);
            while -2.0 * y < x * x {
                let (a, c): (f64, f64) = (rng.sample(Open01), rng.sample(Open01));
                x = a.ln() / z.r;
                y = c.ln();
            }
            return if u < 0.0 { x - z.r } else { z.r - x };
        }
        if z.f[i + 1] + (z.f[i] - z.f[i + 1]) * rng.random::<f64>() < exp_nonpositive(-x * x / 2.0)
        {
            return x;
        }
        b = rng.next_u64();
    }
}

/// The ziggurat for the unit exponential (as in `rand_distr`), started from the 64-bit draw `b`.
#[cold]
fn exp1_continue(z: &Ziggurat, mut b: u64, rng: &mut PfRng) -> f64 {
    loop {
        let (i, u) = exp1_parts(b);
        let x = u * z.x[i];
        if x < z.x[i + 1] {
            return x;
        }
        if i == 0 {
            // Memoryless tail: R + Exp(1).
            let a: f64 = rng.sample(Open01);
            return z.r - a.ln();
        }
        if z.f[i + 1] + (z.f[i] - z.f[i + 1]) * rng.random::<f64>() < exp_nonpositive(-x) {
            return x;
        }
        b = rng.next_u64();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mc::stream_rng;

    /// Each lane is `rand`'s xoshiro256++ seeded with the same 32 bytes, draw for draw.
    #[test]
    fn lanes_are_interleaved_xoshiro256plusplus() {
        let mut seeder = stream_rng(5, 1);
        let mut lanes = LaneRng::from_rng(&mut seeder.clone());
        let mut refs: Vec<PfRng> = (0..LANES)
            .map(|_| {
                let mut seed = [0u8; 32];
                for b in seed.chunks_exact_mut(8) {
                    b.copy_from_slice(&seeder.next_u64().to_le_bytes());
                }
                PfRng::from_seed(seed)
            })
            .collect();
        let mut bits = vec![0u64; 10 * LANES];
        lanes.fill_bits(&mut bits);
        for (p, &b) in bits.iter().enumerate() {
            assert_eq!(b, refs[p % LANES].next_u64(), "draw {p}");
        }
    }

    /// Every kernel produces the same bits: the AVX-512 twin of the normals (where the CPU
    /// has AVX-512), the AVX2 twin of the normals and the AVX2 copy of the exponentials
    /// (where it has AVX2 and FMA) and the portable copy; on a CPU without them the calls
    /// run the same copy and the test is trivially true. Ten
    /// thousand normals hold about forty rejected candidates, continued on the scalar
    /// stream.
    #[test]
    fn every_kernel_gives_the_same_samples() {
        for len in [1usize, 7, 8, 63, 255, 256, 257, 2048, 2048 + 69, 10_000] {
            let mut a = LaneRng::from_rng(&mut stream_rng(1, len as u64));
            let (mut b, mut c) = (a.clone(), a.clone());
            let (mut za, mut zb, mut zc) = (vec![0.0; len], vec![0.0; len], vec![0.0; len]);
            for _ in 0..3 {
                a.fill_normal_with(Simd::Auto, &mut za);
                b.fill_normal_with(Simd::Avx2, &mut zb);
                c.fill_normal_with(Simd::Portable, &mut zc);
                assert_eq!(bits_of(&za), bits_of(&zc), "normal, len {len}");
                assert_eq!(bits_of(&zb), bits_of(&zc), "normal, len {len}");
                a.fill_exp1_with(Simd::Auto, &mut za);
                b.fill_exp1_with(Simd::Avx2, &mut zb);
                c.fill_exp1_with(Simd::Portable, &mut zc);
                assert_eq!(bits_of(&za), bits_of(&zc), "exp1, len {len}");
                assert_eq!(bits_of(&zb), bits_of(&zc), "exp1, len {len}");
            }
            // The streams are left in the same state.
            let (mut ra, mut rb, mut rc) = ([0u64; LANES], [0u64; LANES], [0u64; LANES]);
            a.step(&mut ra);
            b.step(&mut rb);
            c.step(&mut rc);
            assert_eq!(ra, rc, "lanes after len {len}");
            assert_eq!(rb, rc, "AVX2 lanes after len {len}");
            let fix = c.fix.next_u64();
            assert_eq!(a.fix.next_u64(), fix, "fix-up stream after len {len}");
            assert_eq!(b.fix.next_u64(), fix, "AVX2 fix-up stream after len {len}");
        }
    }

    fn bits_of(x: &[f64]) -> Vec<u64> {
        x.iter().map(|v| v.to_bits()).collect()
    }

    /// Moments and tail frequencies of 4·10⁶ normals. Standard errors, for m draws: mean
    /// 1/√m, variance √(2/m), fourth moment √(96/m) (Var Z⁴ = 105 − 9); the count beyond
    /// |z| > c is binomial(m, p_c). All bounds are 5 standard errors (a correct generator
    /// fails one with probability below 10⁻⁵), and the tail counts exercise the slow path.
    #[test]
    fn normals_have_the_normal_law() {
        let m = 4_000_000;
        let mut z = vec![0.0; m];
        LaneRng::from_rng(&mut stream_rng(2, 0)).fill_normal(&mut z);
        assert!(z.iter().all(|v| v.is_finite()));
        let mf = m as f64;
        let mean = z.iter().sum::<f64>() / mf;
        let var = z.iter().map(|v| v * v).sum::<f64>() / mf;
        let m4 = z.iter().map(|v| v.powi(4)).sum::<f64>() / mf;
        assert!(mean.abs() < 5.0 / mf.sqrt(), "mean {mean}");
        assert!(
            (var - 1.0).abs() < 5.0 * (2.0 / mf).sqrt(),
            "variance {var}"
        );
        assert!(
            (m4 - 3.0).abs() < 5.0 * (96.0 / mf).sqrt(),
            "fourth moment {m4}"
        );
        // P(|Z| > c) for c = 1, 2, 3, R (the ziggurat's tail start), 4.
        for (c, p) in [
            (1.0, 0.317_310_507_862_914_15),
            (2.0, 0.045_500_263_896_358_4),
            (3.0, 0.002_699_796_063_260_2),
            (NORMAL.r, 5.371_393_460_685_516e-5),
            (4.0, 6.334_248_366_623_996e-5),
        ] {
            let k = z.iter().filter(|v| v.abs() > c).count() as f64;
            let se = (mf * p * (1.0 - p)).sqrt();
            assert!(
                (k - mf * p).abs() < 5.0 * se,
                "P(|Z| > {c}): {k} vs {}",
                mf * p
            );
        }
        // Symmetry: as many positive as negative values.
        let pos = z.iter().filter(|v| **v > 0.0).count() as f64;
        assert!(
            (pos - mf / 2.0).abs() < 5.0 * (mf / 4.0).sqrt(),
            "positives {pos}"
        );
    }

    /// Exponentials: mean 1 (se 1/√m), variance 1 (se √(8/m): Var (E−1)² = 8), and
    /// P(E > c) = e^{−c}, binomial counts; 5 standard errors each.
    #[test]
    fn exponentials_have_the_exponential_law() {
        let m = 4_000_000;
        let mut e = vec![0.0; m];
        LaneRng::from_rng(&mut stream_rng(3, 0)).fill_exp1(&mut e);
        assert!(e.iter().all(|v| v.is_finite() && *v >= 0.0));
        let mf = m as f64;
        let mean = e.iter().sum::<f64>() / mf;
        let var = e.iter().map(|v| (v - 1.0).powi(2)).sum::<f64>() / mf;
        assert!((mean - 1.0).abs() < 5.0 / mf.sqrt(), "mean {mean}");
        assert!(
            (var - 1.0).abs() < 5.0 * (8.0 / mf).sqrt(),
            "variance {var}"
        );
        for c in [0.1, 1.0, 3.0, EXPONENTIAL.r, 9.0] {
            let p = (-c).exp();
            let k = e.iter().filter(|v| **v > c).count() as f64;
            let se = (mf * p * (1.0 - p)).sqrt();
            assert!(
                (k - mf * p).abs() < 5.0 * se,
                "P(E > {c}): {k} vs {}",
                mf * p
            );
        }
    }
}
