//! Multinomial and residual resampling split over blocks of particles, so that the blocks
//! draw in parallel: the batch filter's two schemes that resample before its pass.
//!
//! `M` independent draws from weights `W` fall into the blocks as a Multinomial(`M`; block
//! masses) split, and given that split the draws of each block are independent draws from
//! the block's own normalised weights. So the split is drawn first, as a chain of binomials
//! (block `b` takes Binomial(`M − M_0 − … − M_{b−1}`, `mass_b / Σ_{e ≥ b} mass_e`) draws),
//! and then each block makes its `M_b` draws with [`multinomial_draws`] on a stream of its
//! own. The ancestors come out in increasing order, block after block; the law is exactly
//! multinomial (tested by chi-square), and the result depends on the blocks, not on the
//! threads that run them.
//!
//! Residual resampling splits the same way: its floors `⌊M·W_j⌋` are fixed, and its
//! `R = M − Σ⌊M·W_j⌋` multinomial draws from the residuals `r_j/R` split over the blocks by
//! their residual masses `Σ_{j∈b} r_j`; each block writes its floors and draws its share from
//! `r_j/Σ_{j∈b} r_j` ([`residual_draws`]). The blocks' floors and residual masses take a
//! first parallel pass.
//!
//! Blocks are whole chunks of the batch filter, as few and as large as parallel work allows
//! (see [`chunks_per_block`]): each block's Poisson counts overshoot its `M_b` by about
//! `3√M_b` draws, which it then draws uniformly and removes, so small blocks cost more on
//! one thread: at N = 10⁶ blocks of one 2048-particle chunk made the filter with
//! multinomial resampling about 25 % slower on one thread than no split, blocks of 2¹⁴
//! particles about 12 %.

use super::multinomial::multinomial_draws;
use super::residual::{ResidualSums, residual_draws, residual_sums};
use crate::mc::{Par, stream_rng};
use crate::simd::Simd;
use rand::{Rng, RngExt};
use rand_distr::{Binomial, Distribution};
use rayon::prelude::*;

/// The schemes that draw in blocks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Blocked {
    /// Independent draws from `W`.
    Multinomial,
    /// `⌊M·W_j⌋` copies plus independent draws from the residuals.
    Residual,
}

/// How a call's draws are split and run: which scheme, which kernels, on which threads,
/// and how many chunks make a block (the split, and so the draws, depend on the sizes
/// alone, never on the threads).
#[derive(Debug, Clone, Copy)]
pub(crate) struct BlockPlan {
    pub(crate) scheme: Blocked,
    pub(crate) simd: Simd,
    pub(crate) par: Par,
    /// Chunks per block (see [`chunks_per_block`]).
    pub(crate) per_block: usize,
}

/// Particles per block, at least: from `N = 2·BLOCK` the draws run on two threads or more.
pub(crate) const BLOCK: usize = 1 << 14;

/// Blocks at most: enough for eight threads, and at N = 10⁶ blocks of 125 000 particles.
const MAX_BLOCKS: usize = 8;

/// Chunks per block for `n` particles in chunks of `chunk`: `n/min_block` blocks (at least
/// one, at most [`MAX_BLOCKS`]), fixed by the sizes alone so that the draws do not depend on
/// the number of threads.
pub(crate) fn chunks_per_block(n: usize, chunk: usize, min_block: usize) -> usize {
    let blocks = (n / min_block.max(1)).clamp(1, MAX_BLOCKS);
    n.div_ceil(chunk).div_ceil(blocks).max(1)
}

/// The particles of one call: weights as cumulative sums within chunks, each chunk on a
/// scale of its own.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ChunkedWeights<'a> {
    /// Cumulative weights within each chunk, chunk after chunk.
    pub(crate) cum: &'a [f64],
    /// Particles per chunk (the last chunk may be shorter).
    pub(crate) chunk: usize,
    /// Chunk `d`'s weights count `scale[d]` times.
    pub(crate) scale: &'a [f64],
}

impl ChunkedWeights<'_> {
    /// Chunk `d`'s mass.
    fn mass(&self, d: usize) -> f64 {
        let end = ((d + 1) * self.chunk).min(self.cum.len());
        self.scale[d] * self.cum[end - 1]
    }

    /// The weights of chunks `d0 .. d1` times `factor`, from their cumulative sums, into
    /// `out` (at least as long as those chunks).
    pub(crate) fn write(&self, d0: usize, d1: usize, factor: f64, out: &mut [f64]) {
        let c = self.chunk;
        let (lo, hi) = (d0 * c, (d1 * c).min(self.cum.len()));
        let chunks = out[..hi - lo].chunks_mut(c).zip(self.cum[lo..hi].chunks(c));
        for (d, (w, cum)) in (d0..).zip(chunks) {
            let s = self.scale[d] * factor;
            let mut prev = 0.0;
            for (w, &x) in w.iter_mut().zip(cum) {
                *w = (x - prev) * s;
                prev = x;
            }
        }
    }
}

/// What every block reads.
struct Blocks<'a> {
    plan: BlockPlan,
    w: ChunkedWeights<'a>,
    /// `starts[b]`: where block `b`'s draws begin in the output.
    starts: &'a [usize],
    /// Block `b`'s mass (and no floors) for multinomial, its residual sums for residual.
    sums: &'a [ResidualSums],
    /// The key of the blocks' streams: block `b` draws from `stream_rng(key, b)`.
    key: u64,
    /// `M`.
    m: usize,
}

/// The split's scratch, kept by the caller so that a step allocates nothing.
#[derive(Debug, Clone, Default)]
pub(crate) struct ChunkSplit {
    starts: Vec<usize>,
    /// Per block: the outputs fixed before the split (residual's floors), the mass the
    /// draws split by, and the largest residual.
    sums: Vec<ResidualSums>,
    /// The mass of blocks `b, b + 1, …`.
    rest: Vec<f64>,
}

impl ChunkSplit {
    /// `out` ← `M = out.len()` ancestors from the weights `w` as `plan` says. `scratch` is
    /// as long as `w.cum`; `rng` draws the split and the blocks' key.
    pub(crate) fn draw<R: Rng + ?Sized>(
        &mut self,
        plan: BlockPlan,
        w: ChunkedWeights<'_>,
        rng: &mut R,
        scratch: &mut [f64],
        out: &mut [usize],
    ) {
        let BlockPlan {
            scheme,
            simd,
            par,
            per_block,
        } = plan;
        let chunks = w.cum.len().div_ceil(w.chunk);
        let blocks = chunks.div_ceil(per_block);
        let m = out.len();
        if blocks == 0 || m == 0 {
            return;
        }
        self.sums.clear();
        self.sums.extend((0..blocks).map(|b| {
            let end = ((b + 1) * per_block).min(chunks);
            ResidualSums {
                floors: 0,
                mass: (b * per_block..end).map(|d| w.mass(d)).sum::<f64>(),
                peak: 0.0,
            }
        }));
        if scheme == Blocked::Residual {
            // The weights normalised into `scratch` (where the blocks draw from them), and
            // each block's residual sums, block by block side by side.
            let total: f64 = self.sums.iter().map(|s| s.mass).sum();
            let (inv, mf, len) = (1.0 / total, m as f64, per_block * w.chunk);
            let block = |(b, (ws, sums)): (usize, (&mut [f64], &mut ResidualSums))| {
                let d0 = b * per_block;
                w.write(d0, (d0 + per_block).min(chunks), inv, ws);
                *sums = residual_sums(simd, ws, mf);
            };
            let scratch = &mut scratch[..w.cum.len()];
            match par {
                Par::Seq => scratch
                    .chunks_mut(len)
                    .zip(self.sums.iter_mut())
                    .enumerate()
                    .for_each(block),
                Par::Rayon => scratch
                    .par_chunks_mut(len)
                    .zip(self.sums.par_iter_mut())
                    .enumerate()
                    .for_each(block),
            }
        }
        // The draws beyond the fixed outputs (all of them for multinomial).
        let fixed: usize = self.sums.iter().map(|s| s.floors).sum();
        // Summed from the end, `rest[b] ≥ mass[b]` exactly, and the last block with mass
        // has `rest[b] = mass[b]`: it takes every draw left, and no draw reaches a block
        // without mass.
        self.rest.clear();
        self.rest.resize(blocks + 1, 0.0);
        for b in (0..blocks).rev() {
            self.rest[b] = self.sums[b].mass + self.rest[b + 1];
        }
        self.starts.clear();
        self.starts.resize(blocks + 1, 0);
        let key = rng.random();
        let mut left = m.saturating_sub(fixed);
        for b in 0..blocks {
            let p = if self.rest[b] > 0.0 {
                (self.sums[b].mass / self.rest[b]).min(1.0)
            } else {
                0.0
            };
            let k = if p >= 1.0 {
                left
            } else {
                Binomial::new(left as u64, p).map_or(0, |d| d.sample(rng) as usize)
            };
            // Capped at M: floors summing past it (weights past 1 beyond rounding) only
            // shorten the last blocks, whose runs then stop at the end of `out`.
            self.starts[b + 1] = (self.starts[b] + self.sums[b].floors + k).min(m);
            left -= k;
        }
        // Weights with no mass at all (outside the contract) leave draws over: the last
        // block takes them, as the cumulative-weight schemes give them the last particle.
        self.starts[blocks] = m;
        let ctx = Blocks {
            plan,
            w,
            starts: &self.starts,
            sums: &self.sums,
            key,
            m,
        };
        split(&ctx, 0, blocks, scratch, out);
    }
}

/// The blocks `b0 .. b1`, with their weights' scratch `w` and their outputs `out`: halves
/// side by side on rayon's pool (or one after the other with [`Par::Seq`]) down to single
/// blocks.
fn split(ctx: &Blocks<'_>, b0: usize, b1: usize, w: &mut [f64], out: &mut [usize]) {
    if b1 - b0 == 1 {
        return draw_block(ctx, b0, w, out);
    }
    let mid = (b0 + b1) / 2;
    let (w0, w1) = w.split_at_mut((mid - b0) * ctx.plan.per_block * ctx.w.chunk);
    let (o0, o1) = out.split_at_mut(ctx.starts[mid] - ctx.starts[b0]);
    match ctx.plan.par {
        Par::Seq => {
            split(ctx, b0, mid, w0, o0);
            split(ctx, mid, b1, w1, o1);
        }
        Par::Rayon => {
            rayon::join(
                || split(ctx, b0, mid, w0, o0),
                || split(ctx, mid, b1, w1, o1),
            );
        }
    }
}

/// Block `b`'s draws on its own stream, written as global indices: for multinomial, its
/// weights normalised from the chunks' cumulative sums, then [`multinomial_draws`]; for
/// residual, [`residual_draws`] on the weights the first pass left in `w`.
fn draw_block(ctx: &Blocks<'_>, b: usize, w: &mut [f64], out: &mut [usize]) {
    if out.is_empty() {
        return;
    }
    let (c, d0) = (ctx.w.chunk, b * ctx.plan.per_block);
    let d1 = (d0 + ctx.plan.per_block).min(ctx.w.cum.len().div_ceil(c));
    let (lo, hi) = (d0 * c, (d1 * c).min(ctx.w.cum.len()));
    let w = &mut w[..hi - lo];
    let rng = &mut stream_rng(ctx.key, b as u64);
    match ctx.plan.scheme {
        Blocked::Multinomial => {
            ctx.w.write(d0, d1, 1.0 / ctx.sums[b].mass, w);
            multinomial_draws(ctx.plan.simd, w, lo, rng, out);
        }
        Blocked::Residual => {
            residual_draws(
                ctx.plan.simd,
                w,
                ctx.m as f64,
                Some(ctx.sums[b]),
                lo,
                rng,
                out,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::resample::offspring_counts;
    use crate::testing::{chi2_quantile_999, multinomial_pmf};
    use std::collections::HashMap;

    /// Cumulative sums within chunks of `w`, chunk `d`'s divided by `scale[d]`.
    fn chunked(w: &[f64], chunk: usize, scale: &[f64]) -> Vec<f64> {
        let mut cum = Vec::new();
        for (d, c) in w.chunks(chunk).enumerate() {
            let mut s = 0.0;
            for &x in c {
                s += x / scale[d];
                cum.push(s);
            }
        }
        cum
    }

    /// Chi-square of the offspring counts of `reps` seeded calls under `scheme` over five
    /// particles with weights `w` in chunks of two (so three chunks, the last a single
    /// particle), each chunk's sums on a scale of its own, in blocks of one chunk and of
    /// two, against the probabilities `p` of every composition of `m` into five counts (all
    /// of them listed by `p`'s keys). The pool's draws equal one thread's.
    fn chi_square_in_blocks(
        scheme: Blocked,
        w: &[f64; 5],
        m: usize,
        p: &HashMap<Vec<usize>, f64>,
        reps: usize,
    ) {
        let scale = [1.0, 1e-3, 7.0];
        let cum = chunked(w, 2, &scale);
        let weights = ChunkedWeights {
            cum: &cum,
            chunk: 2,
            scale: &scale,
        };
        for per_block in [1, 2] {
            let mut seen: HashMap<Vec<usize>, usize> = HashMap::new();
            let mut split = ChunkSplit::default();
            let mut scratch = vec![0.0; 5];
            let mut rng = stream_rng(31, per_block as u64);
            let (mut out, mut pooled) = (vec![0usize; m], vec![0usize; m]);
            for _ in 0..reps {
                let mut again = rng.clone();
                let plan = |par| BlockPlan {
                    scheme,
                    simd: Simd::Auto,
                    par,
                    per_block,
                };
                let (pooled_plan, seq_plan) = (plan(Par::Rayon), plan(Par::Seq));
                split.draw(pooled_plan, weights, &mut again, &mut scratch, &mut pooled);
                split.draw(seq_plan, weights, &mut rng, &mut scratch, &mut out);
                assert_eq!(out, pooled);
                assert!(out.windows(2).all(|p| p[0] <= p[1]), "in order: {out:?}");
                *seen.entry(offspring_counts(&out, 5)).or_default() += 1;
            }
            let mut chi2 = 0.0;
            for (k, &pk) in p {
                let e = pk * reps as f64;
                let o = seen.get(k).copied().unwrap_or(0) as f64;
                chi2 += (o - e).powi(2) / e;
            }
            assert_eq!(seen.keys().filter(|k| !p.contains_key(*k)).count(), 0);
            let df = p.len() - 1;
            let bound = chi2_quantile_999(df);
            assert!(
                chi2 < bound,
                "{scheme:?}, blocks of {per_block}: χ² {chi2} on {df} df"
            );
        }
    }

    /// Every way of splitting `m` draws over five particles.
    fn compositions(m: usize) -> Vec<Vec<usize>> {
        let mut all = Vec::new();
        for a in 0..=m {
            for b in 0..=m - a {
                for c in 0..=m - a - b {
                    for d in 0..=m - a - b - c {
                        all.push(vec![a, b, c, d, m - a - b - c - d]);
                    }
                }
            }
        }
        all
    }

    /// Multinomial in blocks: the offspring counts are jointly Multinomial(4; W) over all
    /// 70 outcomes, chi-square over 40 000 calls per block size.
    #[test]
    fn multinomial_counts_are_jointly_multinomial() {
        let w = [0.1, 0.25, 0.3, 0.05, 0.3];
        let p = compositions(4)
            .into_iter()
            .map(|k| {
                let pk = multinomial_pmf(&k, &w);
                (k, pk)
            })
            .collect();
        chi_square_in_blocks(Blocked::Multinomial, &w, 4, &p, 40_000);
    }

    /// Residual in blocks: with `W = (0.1, 0.3, 0.35, 0.05, 0.2)` and `M = 4` the floors are
    /// `(0, 1, 1, 0, 0)` and the `R = 2` residual draws come from `(0.2, 0.1, 0.2, 0.1,
    /// 0.4)`; the counts beyond the floors are jointly Multinomial(2; those) over all 15
    /// outcomes, chi-square over 40 000 calls per block size.
    #[test]
    fn residual_counts_are_floors_plus_multinomial_draws() {
        let w = [0.1, 0.3, 0.35, 0.05, 0.2];
        let floors = [0, 1, 1, 0, 0];
        let r = [0.2, 0.1, 0.2, 0.1, 0.4];
        let p = compositions(2)
            .into_iter()
            .map(|k| {
                let pk = multinomial_pmf(&k, &r);
                (k.iter().zip(&floors).map(|(k, f)| k + f).collect(), pk)
            })
            .collect();
        chi_square_in_blocks(Blocked::Residual, &w, 4, &p, 40_000);
    }

    /// Blocks without mass get no draws, and every output lands in a block with mass, for
    /// both schemes.
    #[test]
    fn blocks_without_mass_get_nothing() {
        let scale = [1.0; 3];
        let cum = chunked(&[0.0, 0.0, 0.5, 0.5, 0.0, 0.0], 2, &scale);
        let weights = ChunkedWeights {
            cum: &cum,
            chunk: 2,
            scale: &scale,
        };
        for scheme in [Blocked::Multinomial, Blocked::Residual] {
            let mut split = ChunkSplit::default();
            let mut scratch = vec![0.0; 6];
            let mut out = vec![usize::MAX; 100];
            let mut rng = stream_rng(2, 0);
            let plan = BlockPlan {
                scheme,
                simd: Simd::Auto,
                par: Par::Seq,
                per_block: 1,
            };
            split.draw(plan, weights, &mut rng, &mut scratch, &mut out);
            assert!(out.iter().all(|&a| a == 2 || a == 3), "{scheme:?}: {out:?}");
            assert_eq!(split.starts, [0, 0, 100, 100], "{scheme:?}");
        }
    }
}
