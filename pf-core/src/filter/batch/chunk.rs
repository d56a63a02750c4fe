//! One output chunk of a step, on its own: ancestors, normals, the mutation, weights and
//! the chunk's cumulative weights (see the module docs of [`super`]).

use super::model::{BatchModel, Cols, ColsMut};
use super::mutation::BatchMutation;
use crate::buffer::Line;
use crate::resample::{SCAN, prefix4_each, stratified_index_in};
use crate::simd::avx2::Avx2;
use crate::simd::avx512::Avx512;
use crate::simd::math::{
    ChunkMap, ceil_index_in, exp_fma_nonpositive, exp_fma_nonpositive_lanes, max_and_flag,
};
use crate::simd::{LaneRng, prefetch};

/// Where a step's particles come from.
#[derive(Debug, Clone, Copy)]
pub(super) enum Source {
    /// `t = 0`: from the initial law.
    Initial,
    /// No resampling: particle `i` moves on from particle `i`, keeping its weight.
    Identity,
    /// Systematic resampling with the uniform `U`, done by each output chunk.
    Systematic(f64),
    /// Stratified resampling with the uniforms `stratum_uniform(key, ·)`, done by each output
    /// chunk: a stratum's uniform is drawn by its index, since any chunk may need it.
    Stratified(u64),
    /// Ancestors already drawn into the filter's `ancestors`.
    Given,
}

/// A chunk's summary after a step.
#[derive(Debug, Clone, Copy)]
pub(super) struct ChunkStat {
    /// Maximum log-weight `m_d` (−∞ if every weight is zero).
    pub(super) max: f64,
    /// The chunk's first NaN or +∞ log-weight: global index and value.
    pub(super) bad: Option<(usize, f64)>,
    /// `Σ exp(l_i − m_d)` and `Σ exp(l_i − m_d)²`.
    pub(super) sum: f64,
    pub(super) sum_sq: f64,
}

impl Default for ChunkStat {
    fn default() -> Self {
        ChunkStat {
            max: f64::NEG_INFINITY,
            bad: None,
            sum: 0.0,
            sum_sq: 0.0,
        }
    }
}

/// One worker's scratch, reused for every chunk it processes (it stays in L1/L2).
#[derive(Debug, Clone)]
pub(super) struct Scratch {
    /// Standard normals, column after column, as `f64`s on cache lines ([`Line`]: the
    /// normals' and `exp`'s twins load and store eight at a time).
    z: Vec<Line>,
    /// Log-weights, then weights relative to the chunk maximum, on cache lines as `z`.
    l: Vec<Line>,
    /// The parents' states, column after column (`PAD` longer: the walk's four-wide stores).
    p: Vec<Line>,
    /// For `D > 1`, the parents' positions in the previous state array, found by the walk
    /// (`PAD` longer).
    idx: Vec<usize>,
    /// The mutation's own scratch (a guided proposal's `log q`).
    q: Vec<Line>,
    /// Where this worker's walk stopped in this step (see [`WalkHint`]).
    pub(super) hint: WalkHint,
}

impl Scratch {
    /// For chunks of `c` particles with `dim` columns and `noise` normals each.
    pub(super) fn new(c: usize, dim: usize, noise: usize) -> Self {
        Scratch {
            z: Line::zeroed_for_f64s(noise * c),
            l: Line::zeroed_for_f64s(c + PAD),
            p: Line::zeroed_for_f64s(dim * c + PAD),
            idx: if dim > 1 {
                vec![0; c + PAD]
            } else {
                Vec::new()
            },
            q: Line::zeroed_for_f64s(c),
            hint: WalkHint::NONE,
        }
    }
}

/// Where a worker's walk stopped in this step: the output it would have written next, and
/// the first particle of its last block, whose predecessors all have boundaries below that
/// output. The worker's next chunk, which starts at that output, searches for its first
/// ancestor from there, among lines the walk has just read, instead of over all N
/// particles, whose lower levels of bisection miss the caches at N = 10⁷ (see
/// [`gather_counted`]). Reset at every step, since it speaks of one step's weights.
#[derive(Debug, Clone, Copy)]
pub(super) struct WalkHint {
    pub(super) next: usize,
    pub(super) from: usize,
}

impl WalkHint {
    pub(super) const NONE: WalkHint = WalkHint {
        next: usize::MAX,
        from: 0,
    };
}

/// What every chunk of one step reads.
pub(super) struct StepCtx<'a, M: BatchModel, Q> {
    pub(super) model: &'a M,
    pub(super) mutation: &'a Q,
    pub(super) t: usize,
    pub(super) u: &'a M::Input,
    pub(super) y: Option<&'a M::Obs>,
    pub(super) n: usize,
    pub(super) c: usize,
    /// `D`, the state's columns.
    pub(super) dim: usize,
    /// Normals per particle at this step.
    pub(super) noise: usize,
    /// `−log N`, the log-weight after resampling.
    pub(super) log_uniform: f64,
    pub(super) source: Source,
    /// States, chunk after chunk, each chunk `dim` columns `c` apart.
    pub(super) x_old: &'a [f64],
    pub(super) lw_old: &'a [f64],
    pub(super) cw_old: &'a [f64],
    pub(super) offset: &'a [f64],
    pub(super) scale: &'a [f64],
    /// `N / total` of the previous step.
    pub(super) n_over_total: f64,
    pub(super) ancestors: &'a [usize],
    pub(super) keep_lw: bool,
    /// Whether to prefetch (see [`PREFETCH_MIN`](super::PREFETCH_MIN)), and the chunks per
    /// worker: a chunk prefetches for the next one only within its own group.
    pub(super) prefetch: bool,
    pub(super) per_group: usize,
    /// The AVX-512 twins, where the configuration allows them and the CPU has AVX-512.
    pub(super) avx512: Option<Avx512>,
    /// The AVX2 twin of the normals, where the configuration allows it and the CPU has AVX2
    /// and FMA (used only without AVX-512).
    pub(super) avx2: Option<Avx2>,
}

impl<M: BatchModel, Q> StepCtx<'_, M, Q> {
    /// Chunk `d`'s map from its particles' cumulative weights to their scaled global ones.
    #[inline(always)]
    pub(super) fn chunk_map(&self, d: usize) -> ChunkMap {
        ChunkMap {
            offset: self.offset[d],
            scale: self.scale[d],
            n_over_total: self.n_over_total,
        }
    }

    /// Where particle `j`'s first column lies in the state arrays.
    #[inline(always)]
    fn position(&self, j: usize) -> usize {
        if self.dim == 1 {
            j
        } else {
            (j / self.c) * self.dim * self.c + j % self.c
        }
    }
}

/// One output chunk `d` of a step (see the module docs): ancestors, normals, the
/// mutation, weights, and the chunk's cumulative weights relative to its maximum. `xs` is
/// the chunk's slot in the new state array (`dim` columns `c` apart), `cws` and `lws` its
/// particles' cumulative and log-weights.
#[inline(always)]
pub(super) fn chunk_step<M: BatchModel, Q: BatchMutation<M>>(
    ctx: &StepCtx<'_, M, Q>,
    d: usize,
    xs: &mut [f64],
    cws: &mut [f64],
    lws: &mut [f64],
    rng: &mut LaneRng,
    s: &mut Scratch,
) -> ChunkStat {
    let len = cws.len();
    let lo = d * ctx.c;
    let (model, t, dim, c) = (ctx.model, ctx.t, ctx.dim, ctx.c);
    let z = &mut Line::f64s(&mut s.z)[..ctx.noise * len];
    rng.fill_normal_on((ctx.avx512, ctx.avx2), z);
    let z = Cols::strided(z, ctx.noise, len, len);
    let mut x = ColsMut::strided(xs, dim, len, c);
    // The prior log-weight: the previous one without resampling, uniform after it.
    let l = &mut Line::f64s(&mut s.l)[..len];
    match ctx.source {
        Source::Identity => l.copy_from_slice(&ctx.lw_old[lo..lo + len]),
        _ => l.fill(ctx.log_uniform),
    }
    let p = Line::f64s(&mut s.p);
    let parents = match ctx.source {
        Source::Initial => {
            model.initial(z, x.reborrow());
            if let Some(y) = ctx.y {
                model.add_log_likelihood(t, y, x.as_cols(), l);
            }
            None
        }
        Source::Identity => Some(Cols::strided(&ctx.x_old[d * dim * c..], dim, len, c)),
        Source::Systematic(u) => {
            let k = |x: f64, a, b| ceil_index_in(x - u, a, b);
            let twin = ctx.avx512.map(|cpu| (cpu, u));
            Some(walk(ctx, (k, twin), lo, len, p, &mut s.idx, &mut s.hint))
        }
        Source::Stratified(key) => {
            let k = |x, a, b| stratified_index_in(x, key, a, b);
            Some(walk(ctx, (k, None), lo, len, p, &mut s.idx, &mut s.hint))
        }
        Source::Given => {
            let anc = &ctx.ancestors[lo..lo + len];
            for k in 0..dim {
                let col = &mut p[k * len..(k + 1) * len];
                for (o, &a) in col.iter_mut().zip(anc) {
                    *o = ctx.x_old[ctx.position(a) + k * c];
                }
            }
            Some(Cols::strided(p, dim, len, len))
        }
    };
    if let Some(parents) = parents {
        let q = &mut Line::f64s(&mut s.q)[..len];
        ctx.mutation
            .mutate(model, t, ctx.u, ctx.y, parents, z, x.reborrow(), l, q);
    }
    // Maximum and a flag for NaN or +∞. Adding 0 makes a largest zero `+0` whichever zero
    // a path kept (`−0` and `+0` tie), so that every path gives the same bits.
    let (m, bad) = match ctx.avx512 {
        Some(cpu) => cpu.max_and_flag(l),
        None => max_and_flag(l),
    };
    let m = m + 0.0;
    if bad {
        let p = l
            .iter()
            .position(|v| v.is_nan() || *v == f64::INFINITY)
            .unwrap_or(0);
        return ChunkStat {
            bad: Some((lo + p, l[p])),
            ..ChunkStat::default()
        };
    }
    if ctx.keep_lw {
        lws.copy_from_slice(l);
    }
    // Weights relative to the chunk maximum (an all-zero chunk keeps zeros), EXP_LANES at a
    // time, then their cumulative sums (the resamplers' `prefix4`) with their squares
    // summed four lanes at a time on the way.
    let shift = if m == f64::NEG_INFINITY { 0.0 } else { m };
    // The next chunk of this worker writes its outputs just after these: prefetched now, a
    // block at a time, they arrive while this chunk computes instead of stalling its stores
    // (12 % at N = 10⁶ with the adaptive policy, whose log-weights add two arrays).
    let next_len = if ctx.prefetch && !(d + 1).is_multiple_of(ctx.per_group) {
        ctx.n.saturating_sub(lo + len).min(ctx.c)
    } else {
        0
    };
    // The next chunk's outputs (and, without resampling, its inputs), `k` values of each
    // column from offset `o` on. Its slot starts `dim·c` after this chunk's.
    let xs_next = x.as_cols().col(0).as_ptr().wrapping_add(dim * c);
    let ahead = |o: usize| {
        if o < next_len {
            let k = EXP_LANES.min(next_len - o);
            for col in 0..dim {
                prefetch(xs_next.wrapping_add(col * c + o), k);
            }
            prefetch(cws.as_ptr().wrapping_add(len + o), k);
            if ctx.keep_lw {
                prefetch(lws.as_ptr().wrapping_add(len + o), k);
            }
            if let Source::Identity = ctx.source {
                // Without resampling, the next chunk reads these at its own indices.
                let a = lo + len + o;
                let base = (d + 1) * dim * c + o;
                for col in 0..dim {
                    let at = base + col * c;
                    prefetch(ctx.x_old[at..at + k].as_ptr(), k);
                }
                prefetch(ctx.lw_old[a..a + k].as_ptr(), k);
            }
        }
    };
    match (ctx.avx512, next_len) {
        // On the AVX-512 twin, whose table lookups are permutes in registers.
        (Some(cpu), 0) => cpu.exp_fma_nonpositive_shifted(l, shift, |_| ()),
        (Some(cpu), _) => cpu.exp_fma_nonpositive_shifted(l, shift, ahead),
        (None, _) => {
            let mut blocks = l.chunks_exact_mut(EXP_LANES);
            if next_len == 0 {
                // A loop of its own, so that the prefetches leave the in-cache code as it was.
                for b in &mut blocks {
                    exp_block(b, shift);
                }
            } else {
                for (i, b) in (&mut blocks).enumerate() {
                    ahead(i * EXP_LANES);
                    exp_block(b, shift);
                }
            }
            for v in blocks.into_remainder() {
                *v = exp_fma_nonpositive(*v - shift);
            }
        }
    }
    let mut sq4 = [0.0; 4];
    let sum = prefix4_each(l, 0.0, cws, |w| {
        for (sq, &w) in sq4.iter_mut().zip(w) {
            *sq += w * w;
        }
    });
    ChunkStat {
        max: m,
        bad: None,
        sum,
        sum_sq: (sq4[0] + sq4[1]) + (sq4[2] + sq4[3]),
    }
}

/// The parents of the outputs `lo .. lo + len` into `p` by [`gather_counted`] (its `k` and
/// `twin`): for `D = 1` their states directly; for `D > 1` their positions into `idx`, then
/// each column gathered from them (in increasing order, so the reads stream).
#[inline(always)]
fn walk<'p, M: BatchModel, Q, K: Fn(f64, f64, f64) -> usize>(
    ctx: &StepCtx<'_, M, Q>,
    k_twin: (K, Option<(Avx512, f64)>),
    lo: usize,
    len: usize,
    p: &'p mut [f64],
    idx: &mut [usize],
    hint: &mut WalkHint,
) -> Cols<'p> {
    let (dim, c) = (ctx.dim, ctx.c);
    if dim == 1 {
        let x_old = ctx.x_old;
        gather_counted(ctx, k_twin, lo, len, &mut p[..len + PAD], hint, |j, m| {
            x_old[j..j + m].iter().copied()
        });
    } else {
        gather_counted(ctx, k_twin, lo, len, &mut idx[..len + PAD], hint, |j, m| {
            // Particles `j .. j + m` lie in one chunk, at consecutive positions.
            let base = ctx.position(j);
            base..base + m
        });
        // Two columns per pass over `idx`: half the index loads, and a loop body that does
        // not depend on where the linker places a five-instruction loop (radar PF, one
        // thread: 15.2 → 14.7 ns per particle-step at N = 10⁴, 19.0 → 17.7 at 10⁶).
        let idx = &idx[..len];
        let mut k = 0;
        while k + 2 <= dim {
            let (o0, o1) = p[k * len..(k + 2) * len].split_at_mut(len);
            let (s0, s1) = (&ctx.x_old[k * c..], &ctx.x_old[(k + 1) * c..]);
            for ((o0, o1), &a) in o0.iter_mut().zip(o1.iter_mut()).zip(idx) {
                *o0 = s0[a];
                *o1 = s1[a];
            }
            k += 2;
        }
        if k < dim {
            let src = &ctx.x_old[k * c..];
            for (o, &a) in p[k * len..(k + 1) * len].iter_mut().zip(idx) {
                *o = src[a];
            }
        }
    }
    Cols::strided(p, dim, len, len)
}

/// `b[k] ← exp(b[k] − shift)` over one block of [`EXP_LANES`] weights.
#[inline(always)]
fn exp_block(b: &mut [f64], shift: f64) {
    let b: &mut [f64; EXP_LANES] = b.try_into().expect("a block of EXP_LANES");
    for l in b.iter_mut() {
        *l -= shift;
    }
    exp_fma_nonpositive_lanes(b);
}

/// Offspring boundary of particle `j`: `k(x_j, 0, N)` at `x_j = G_j·N/T`, where
/// `G_j = offset_d + scale_d·cw_j` is its global cumulative weight (`k` gives the count of
/// points below `x_j/N`, clamped and less its second argument); the last particle's
/// boundary is `N` (the clamp).
#[inline(always)]
fn boundary<M: BatchModel, Q>(
    ctx: &StepCtx<'_, M, Q>,
    k: impl Fn(f64, f64, f64) -> usize,
    j: usize,
) -> usize {
    if j + 1 >= ctx.n {
        return ctx.n;
    }
    k(ctx.chunk_map(j / ctx.c).x(ctx.cw_old[j]), 0.0, ctx.n as f64)
}

/// Padding after a chunk's scratch, for the unconditional four-wide stores of
/// [`gather_counted`].
pub(super) const PAD: usize = 4;

/// Weights exponentiated together by [`exp_fma_nonpositive_lanes`]. With 16, LLVM vectorised
/// across blocks instead (strided loads, a transpose) and the time varied by 30 % from run
/// to run; with 64 it vectorises each block in place, steadily.
const EXP_LANES: usize = 64;

/// What `src(j, m)` gives for particles `j .. j + m` (their states, or their positions),
/// for the ancestors of the outputs `lo .. lo + len`, into `out[..len]` (`out` has
/// [`PAD`] more slots, overwritten freely), under the resampling whose boundaries `k` gives
/// (see [`boundary`]): `ceil_index_in(x − U, ·)` for systematic resampling,
/// [`stratified_index_in`] for stratified. `twin`, given only with systematic
/// resampling's `k`, is the token and `U` for the blocks' boundaries by
/// [`Avx512::ceil_boundaries`] (the same indices).
///
/// Output `i` descends from `A_i = #{j < N − 1 : k_j ≤ i}`, the first particle whose
/// boundary `k_j` exceeds `i`; so particle `j` fills outputs `k_{j−1} … k_j − 1`. The first
/// particle with a boundary above `lo` is found by bisection (`k` is non-decreasing),
/// bracketed by galloping up from `hint` when the worker's previous chunk ended at `lo`; then
/// the particles are walked in order, their boundaries computed 64 at a time (a vectorised
/// loop), and each particle's state is written four times at its first output with one
/// vector store, the next particle starting at its own first output and overwriting the
/// surplus (a loop only for the rare particle with more than four copies). The previous
/// states are read in order, never gathered. (This is the resamplers' `Runs` for states;
/// with [`PAD`] slots of slack the end is checked once per block instead of per particle,
/// which `Runs::push` would cost the filter about 4 %, measured.)
#[inline(always)]
pub(super) fn gather_counted<M, Q, K, V, S, I>(
    ctx: &StepCtx<'_, M, Q>,
    (k, twin): (K, Option<(Avx512, f64)>),
    lo: usize,
    len: usize,
    out: &mut [V],
    hint: &mut WalkHint,
    src: S,
) where
    M: BatchModel,
    K: Fn(f64, f64, f64) -> usize,
    V: Copy,
    S: Fn(usize, usize) -> I,
    I: Iterator<Item = V>,
{
    let n = ctx.n;
    let (mut a, mut b) = (0usize, n - 1);
    if hint.next == lo {
        // Gallop up from where the worker's last walk stopped, to bracket the bisection.
        a = hint.from;
        let mut step = 1;
        loop {
            let probe = a + step;
            if probe >= b {
                break;
            }
            if boundary(ctx, &k, probe) > lo {
                b = probe;
                break;
            }
            a = probe + 1;
            step *= 2;
        }
    }
    while a < b {
        let mid = (a + b) / 2;
        if boundary(ctx, &k, mid) > lo {
            b = mid;
        } else {
            a = mid + 1;
        }
    }
    let mut kb = [0usize; SCAN];
    let (lo_f, hi_f) = (lo as f64, (lo + len) as f64);
    let mut pos = 0usize;
    let mut j = a;
    'walk: while j < n {
        let d = j / ctx.c;
        let end = ((d + 1) * ctx.c).min(n);
        let map = ctx.chunk_map(d);
        while j < end {
            let m = (end - j).min(SCAN);
            if ctx.prefetch {
                // The previous states and weights of the block after next, while this one is
                // walked: a block's boundaries and walk take about 50 ns, less than a miss to
                // memory, and one block ahead was 3 % slower at N = 10⁶. (With `D > 1` the
                // states are gathered after the walk, from positions in increasing order.)
                let (a, b) = ((j + 2 * m).min(n), (j + 3 * m).min(n));
                if ctx.dim == 1 {
                    prefetch(ctx.x_old[a..b].as_ptr(), b - a);
                }
                prefetch(ctx.cw_old[a..b].as_ptr(), b - a);
            }
            // Boundaries relative to lo, capped at the chunk's end.
            let cw = &ctx.cw_old[j..j + m];
            match twin {
                Some((cpu, u)) => cpu.ceil_boundaries(cw, (map, u), (lo_f, hi_f), &mut kb[..m]),
                None => {
                    for (kj, &cw) in kb[..m].iter_mut().zip(cw) {
                        *kj = k(map.x(cw), lo_f, hi_f);
                    }
                }
            }
            if j + m == n {
                // The last particle's boundary is N (the clamp).
                kb[m - 1] = len;
            }
            // Past the chunk's end, boundaries are capped at `len`, so further particles
            // only write into the padding: the end is checked once per block. Boundaries
            // never decrease, so the next run starts at `k` (as in `Runs::push`).
            for (&k, x) in kb[..m].iter().zip(src(j, m)) {
                // `pos ≤ len < 2³²` (the chunk size is checked): read as 32 bits, it tells
                // the compiler that `pos + PAD` cannot overflow, which drops one of the two
                // bound checks per particle (3 % fewer instructions).
                pos = pos as u32 as usize;
                out[pos..pos + PAD].copy_from_slice(&[x; PAD]);
                if k > pos + PAD {
                    out[pos + PAD..k].fill(x);
                }
                debug_assert!(k >= pos, "boundaries never decrease");
                pos = k;
            }
            if pos >= len {
                *hint = WalkHint {
                    next: lo + len,
                    from: j,
                };
                break 'walk;
            }
            j += m;
        }
    }
}
