//! The structure-of-arrays filter: the fast path for every model whose state is a vector
//! of `f64`.
//!
//! The generic [`ParticleFilter`](super::ParticleFilter) calls the model once per particle
//! and stores states of any type. For a state of `D` reals the same algorithm runs on plain
//! `f64` arrays, `D` columns of them, in fixed chunks of [`BatchConfig::chunk`] particles,
//! and the model ([`BatchModel`]) is called once per chunk with columns to loop over. A
//! scalar model ([`ScalarModel`]) is the case `D = 1`. One step is **one pass over
//! memory**: each output chunk, on its own,
//!
//! 1. finds its ancestors (systematic and stratified resampling: it counts offspring
//!    against the previous step's cumulative weights, so chunks need nothing from each
//!    other; multinomial and residual resampling run before the pass, in blocks of chunks
//!    side by side, and the chunk reads their ancestors) and gathers their states;
//! 2. draws its standard normals from its own [`LaneRng`] (64 xoshiro256++ lanes and a
//!    vectorised ziggurat);
//! 3. propagates and weighs through its mutation ([`Bootstrap`], or [`Guided`] by a
//!    [`BatchProposal`]), and takes the chunk's maximum log-weight;
//! 4. exponentiates relative to that chunk maximum (a branch-free `exp`) and accumulates
//!    the chunk's cumulative weights.
//!
//! A chunk's states lie together: its `D` columns, `chunk` values apart, then the next
//! chunk's, so that chunks write disjoint memory and a column of a chunk is one slice.
//! Steps 2–4 work on L1-resident scratch, compiled for AVX-512 where the CPU has it and
//! for AVX2 otherwise when it has that ([`crate::simd`]; LLVM vectorises the model's
//! arithmetic itself; the normals, `exp` and the systematic boundaries call their
//! intrinsic twins). So a chunk
//! touches main memory in bursts (its walk reads, its outputs' stores); from `N = 2¹⁸`,
//! where the arrays outgrow the caches, it prefetches its walk two blocks ahead and,
//! during its `exp`, the next chunk's outputs, so that those bursts find their lines in
//! cache. Arrays of 2 MiB or more are mapped on 2 MiB pages
//! where Linux gives them (`buffer::ParticleBuf`): the 32 MiB of a step at N = 10⁶ then
//! take 16 TLB entries instead of 8192 (about 4 % faster there). Afterwards, a pass over
//! the chunk summaries (not the particles) reconciles the chunk maxima: chunk `d`'s
//! weights are scaled by `exp(m_d − max)` and offset by the chunks before it, which gives
//! the global cumulative weights, the likelihood increment and the ESS.
//!
//! Chunks, streams and the order of every reduction are fixed by `N` and the chunk size,
//! not by the number of threads or by the instruction set, so [`Par::Seq`] and
//! [`Par::Rayon`] on any pool, with any [`Simd`] setting, give
//! bit-identical results (tested). The streams differ from the generic filter's single
//! stream, so the two filters agree in distribution, not draw by draw (tested through the
//! unbiasedness of the likelihood estimate against the Kalman filter's exact value).

use super::{ResamplePolicy, RunSummary, StepReport};
use crate::buffer::ParticleBuf;
use crate::error::{CoreError, Result};
use crate::filter::{Bootstrap, Guided};
use crate::limits::{PARTICLE_BUFFERS, check_count, check_memory};
use crate::mc::{Par, PfRng, stream_rng};
use crate::params::ParamError;
use crate::resample::{
    BLOCK, BlockPlan, Blocked, ChunkSplit, ChunkedWeights, Resampler, chunks_per_block,
};
use crate::simd::avx2::Avx2;
use crate::simd::avx512::Avx512;
use crate::simd::{LaneRng, Simd, dispatch_widest};
use chunk::{ChunkStat, Scratch, Source, StepCtx, WalkHint, chunk_step};
use rand::RngExt;
use rayon::prelude::*;

mod chunk;
mod model;
mod mutation;
mod view;

pub use model::{BatchModel, BatchProposal, BatchTransitionDensity, Cols, ColsMut, ScalarModel};
pub use mutation::BatchMutation;
pub use view::{BatchObserver, BatchView, MomentRecorder};

/// Configuration of a [`BatchFilter`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BatchConfig {
    /// Number of particles `N`.
    pub n_particles: usize,
    /// Resampling scheme; systematic and stratified run chunk-parallel inside the step's
    /// single pass, multinomial and residual in parallel blocks before it.
    pub resampler: Resampler,
    /// When to resample.
    pub policy: ResamplePolicy,
    /// Particles per chunk: the unit of parallel work and of random streams (below 2³²).
    pub chunk: usize,
    /// Seed of the chunk streams and of the resampling uniforms.
    pub seed: u64,
    /// Where chunks run.
    pub par: Par,
    /// Which compiled kernels run (the results are the same).
    pub simd: Simd,
}

impl BatchConfig {
    /// `n` particles, systematic resampling at every step, chunks of [`default_chunk`]`(n)`,
    /// on rayon.
    pub fn new(n: usize, seed: u64) -> Self {
        BatchConfig {
            n_particles: n,
            resampler: Resampler::Systematic,
            policy: ResamplePolicy::Always,
            chunk: default_chunk(n),
            seed,
            par: Par::Rayon,
            simd: Simd::Auto,
        }
    }
}

/// The chunk size [`BatchConfig::new`] gives `n` particles: 2048 while the arrays stay in
/// the caches; 8192 from `N = 2¹⁸`, where they do not (and the prefetches start).
///
/// Out of the caches a chunk pays for its memory in bursts (the first ancestor's search,
/// the prefetches' first lines, its stream's state), and larger chunks pay less often: 8192
/// is 6–12 % faster than 2048 at N = 10⁶. In the caches the smaller chunk keeps its scratch
/// in L1 and L2 and balances better over two threads. The chunk fixes the streams, so the
/// two sizes give different (equally valid) draws.
pub fn default_chunk(n: usize) -> usize {
    if n >= PREFETCH_MIN { 8192 } else { 2048 }
}

/// A chunk's random stream, on its own cache lines ([`LaneRng`] is 64-byte aligned), so
/// that two threads never share one.
type ChunkRng = LaneRng;

/// From this many particles (the four state and weight arrays then span 8 MiB or more) each
/// chunk prefetches the memory the next chunk will use (see [`chunk_step`]). Below, the
/// arrays stay in the caches and the prefetches only cost instructions (3 % at N = 10⁵);
/// above, they save 5–15 %.
const PREFETCH_MIN: usize = 1 << 18;

/// The structure-of-arrays particle filter for [`BatchModel`]s, moving particles with the
/// mutation `Q`: [`Bootstrap`] ([`BatchFilter::new`]) or [`Guided`] ([`BatchFilter::guided`]).
pub struct BatchFilter<M, Q = Bootstrap> {
    model: M,
    mutation: Q,
    cfg: BatchConfig,
    /// `D`.
    dim: usize,
    /// Normals per particle: at `t = 0`, and at each later step.
    noise_initial: usize,
    noise_step: usize,
    /// States, chunk after chunk, each chunk `D` columns `chunk` values apart.
    x: ParticleBuf<f64>,
    x_new: ParticleBuf<f64>,
    /// Normalised `log W` (only maintained when the policy may skip resampling).
    lw: ParticleBuf<f64>,
    lw_new: ParticleBuf<f64>,
    /// Cumulative weights within each chunk, relative to the chunk's maximum.
    cw: ParticleBuf<f64>,
    cw_new: ParticleBuf<f64>,
    /// Ancestors from the schemes that resample before the pass (multinomial, residual).
    ancestors: ParticleBuf<usize>,
    /// The blocks' weights, normalised globally (residual) or within the block
    /// (multinomial).
    w_norm: ParticleBuf<f64>,
    /// The multinomial split's scratch.
    split: ChunkSplit,
    rngs: Vec<ChunkRng>,
    master: PfRng,
    stats: Vec<ChunkStat>,
    /// Per chunk: global offset of its cumulative weights, and its scale `exp(m_d − max)`.
    offset: Vec<f64>,
    scale: Vec<f64>,
    /// Sum of all weights relative to the global maximum.
    total: f64,
    scratch: Vec<Scratch>,
    last: Option<StepReport>,
    /// [`PREFETCH_MIN`]; the tests move it to run both paths.
    prefetch_min: usize,
    /// [`BLOCK`]; the tests make it small to split the multinomial draws into blocks.
    split_block: usize,
}

/// The bootstrap filter: the model's own transition as proposal.
pub type BatchBootstrap<M> = BatchFilter<M, Bootstrap>;

/// The configuration and the last step, not the particle arrays.
impl<M, Q> std::fmt::Debug for BatchFilter<M, Q> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BatchFilter")
            .field("cfg", &self.cfg)
            .field("dim", &self.dim)
            .field("last", &self.last)
            .finish_non_exhaustive()
    }
}

impl<M: BatchModel> BatchFilter<M, Bootstrap> {
    /// The bootstrap filter, every buffer allocated once.
    ///
    /// # Errors
    /// `N = 0`, a chunk size of 0 or of 2³² or more, a model of dimension 0, or arrays
    /// larger than the machine holds.
    pub fn new(model: M, cfg: BatchConfig) -> Result<Self> {
        Self::with_mutation(model, Bootstrap, cfg)
    }
}

impl<M: BatchTransitionDensity, P: BatchProposal<M>> BatchFilter<M, Guided<P>> {
    /// The filter with the importance density `proposal`: each new state is weighed by
    /// `g f / q`.
    ///
    /// # Errors
    /// As [`BatchFilter::new`].
    pub fn guided(model: M, proposal: P, cfg: BatchConfig) -> Result<Self> {
        Self::with_mutation(model, Guided(proposal), cfg)
    }
}

impl<M: BatchModel, Q: BatchMutation<M>> BatchFilter<M, Q> {
    fn with_mutation(model: M, mutation: Q, cfg: BatchConfig) -> Result<Self> {
        if cfg.n_particles == 0 {
            return Err(CoreError::Param(ParamError {
                name: "N",
                value: 0.0,
                reason: "the number of particles must be at least 1",
            }));
        }
        if cfg.chunk == 0 {
            return Err(CoreError::Param(ParamError {
                name: "chunk",
                value: 0.0,
                reason: "the chunk size must be at least 1",
            }));
        }
        if u32::try_from(cfg.chunk).is_err() {
            return Err(CoreError::Param(ParamError {
                name: "chunk",
                value: cfg.chunk as f64,
                reason: "the chunk size must be below 2³² (a chunk's scratch is meant to stay in cache)",
            }));
        }
        let dim = model.dim();
        if dim == 0 {
            return Err(CoreError::Param(ParamError {
                name: "dim",
                value: 0.0,
                reason: "a batch model's state needs at least one column",
            }));
        }
        cfg.policy.validate()?;
        let n = check_count("the number of particles N", cfg.n_particles)?;
        let chunks = n.div_ceil(cfg.chunk);
        // The states' arrays hold whole chunk slots (the last one padded).
        let slots = chunks.saturating_mul(cfg.chunk).saturating_mul(dim);
        // Two state arrays of D columns, five arrays of f64 and the ancestors, all of them
        // before any is mapped.
        let per_particle = (2 * dim + 5) * size_of::<f64>() + size_of::<usize>();
        check_memory(PARTICLE_BUFFERS, n, n.saturating_mul(per_particle))?;
        let noise_initial = model.initial_noise_dim();
        let noise_step = mutation.noise_dim(&model);
        let c = cfg.chunk.min(n);
        let mut f = BatchFilter {
            scratch: vec![Scratch::new(c, dim, noise_initial.max(noise_step))],
            model,
            mutation,
            cfg,
            dim,
            noise_initial,
            noise_step,
            x: ParticleBuf::zeroed(slots)?,
            x_new: ParticleBuf::zeroed(slots)?,
            lw: ParticleBuf::zeroed(n)?,
            lw_new: ParticleBuf::zeroed(n)?,
            cw: ParticleBuf::zeroed(n)?,
            cw_new: ParticleBuf::zeroed(n)?,
            ancestors: ParticleBuf::zeroed(n)?,
            w_norm: ParticleBuf::zeroed(n)?,
            split: ChunkSplit::default(),
            rngs: Vec::with_capacity(chunks),
            master: stream_rng(cfg.seed, u64::MAX),
            stats: vec![ChunkStat::default(); chunks],
            offset: vec![0.0; chunks],
            scale: vec![0.0; chunks],
            total: 0.0,
            last: None,
            prefetch_min: PREFETCH_MIN,
            split_block: BLOCK,
        };
        f.reset();
        Ok(f)
    }

    /// Back to `k = 0`, with the streams restarted from the seed.
    ///
    /// Chunk `d` draws from `LaneRng::from_rng(stream_rng(seed, d))`; the resampling
    /// uniforms come from `stream_rng(seed, u64::MAX)`.
    pub fn reset(&mut self) {
        let (chunks, seed) = (self.stats.len(), self.cfg.seed);
        // Refilled in place: a new vector per run (about 1 MiB at N = 10⁶) cost 260 page
        // faults every time `run` restarted the filter.
        self.rngs.clear();
        self.rngs
            .extend((0..chunks).map(|d| LaneRng::from_rng(&mut stream_rng(seed, d as u64))));
        self.master = stream_rng(self.cfg.seed, u64::MAX);
        self.last = None;
    }

    /// Run the kernels of `simd` from the next step on: the same bits, at that copy's speed
    /// (for benchmarks of a CPU without AVX-512 or AVX2 on one that has them).
    pub fn set_simd(&mut self, simd: Simd) {
        self.cfg.simd = simd;
    }

    /// The model.
    pub fn model(&self) -> &M {
        &self.model
    }

    /// The configuration.
    pub fn config(&self) -> &BatchConfig {
        &self.cfg
    }

    /// `D`, the state's dimension.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Time index of the current particles, `None` before the first step.
    pub fn t(&self) -> Option<usize> {
        self.last.map(|r| r.t)
    }

    /// The report of the last step: its log-likelihood increment, ESS and whether it
    /// resampled.
    pub fn last_report(&self) -> Option<&StepReport> {
        self.last.as_ref()
    }

    /// Running log-likelihood estimate.
    pub fn log_likelihood(&self) -> f64 {
        self.last.map_or(0.0, |r| r.log_lik)
    }

    /// The current particles and weights, `None` before the first step.
    pub fn view(&self) -> Option<BatchView<'_>> {
        self.last.map(|report| BatchView {
            report,
            x: &self.x,
            dim: self.dim,
            n: self.cfg.n_particles,
            c: self.cfg.chunk,
            cw: &self.cw,
            scale: &self.scale,
            total: self.total,
        })
    }

    /// The view, or the error that there are no particles yet.
    fn current(&self) -> Result<BatchView<'_>> {
        self.view().ok_or(CoreError::Empty {
            what: "particle set (no step made yet)",
        })
    }

    /// The weighted means of the current particles' `D` components into `out`.
    ///
    /// # Errors
    /// [`CoreError::Empty`] before the first step; `out` not of length `D`.
    pub fn mean_into(&self, out: &mut [f64]) -> Result<()> {
        self.current()?.mean_into(out)
    }

    /// One step with the input `u_t`; `y = None` is a missing observation.
    ///
    /// With [`Par::Rayon`], a loop of steps called from outside a rayon pool sends each
    /// step's parallel pass to the pool and waits for it; run such a loop inside the pool
    /// (`rayon::scope` or `ThreadPool::install`), as [`run`](Self::run) does: at N = 10⁴
    /// that takes two threads from 2.2 to 1.2 ns per particle-step.
    ///
    /// # Errors
    /// All weights zero or a NaN weight at this step. The filter then stays at step
    /// `k − 1`, as the generic one does (a step writes into the second set of buffers and
    /// swaps them only when it succeeds), but its random streams have moved on: stepping
    /// again draws other numbers than a fresh run would.
    pub fn step_with(&mut self, u: &M::Input, y: Option<&M::Obs>) -> Result<StepReport> {
        let n = self.cfg.n_particles;
        let c = self.cfg.chunk;
        let (t, resample, prior_ll) = match self.last {
            None => (0, false, 0.0),
            Some(r) => (
                r.t + 1,
                self.cfg.policy.should_resample(r.ess, n),
                r.log_lik,
            ),
        };
        let source = if t == 0 {
            Source::Initial
        } else if !resample {
            Source::Identity
        } else {
            match self.cfg.resampler {
                Resampler::Systematic => Source::Systematic(self.master.random()),
                Resampler::Stratified => Source::Stratified(self.master.random()),
                Resampler::Multinomial => {
                    self.resample_in_blocks(Blocked::Multinomial);
                    Source::Given
                }
                Resampler::Residual => {
                    self.resample_in_blocks(Blocked::Residual);
                    Source::Given
                }
            }
        };
        // Below two blocks the resampling before the pass runs on one thread, and waking the
        // other workers for the pass alone cost more than it saved (13–14 against 10–10.5 ns
        // per particle-step at N = 10⁴, multinomial and residual on two threads): the step
        // stays on this thread. Which thread runs a chunk never changes the result.
        let par = match source {
            Source::Given if n < 2 * self.split_block => Par::Seq,
            _ => self.cfg.par,
        };
        let chunks = self.stats.len();
        let threads = match par {
            Par::Seq => 1,
            Par::Rayon => rayon::current_num_threads().max(1),
        };
        // Contiguous groups of chunks, one per worker, each with its own scratch. Which
        // worker runs a chunk never changes what the chunk computes.
        let per_group = chunks.div_ceil(threads);
        let groups = chunks.div_ceil(per_group);
        if self.scratch.len() < groups {
            let (len, dim) = (c.min(n), self.dim);
            let noise = self.noise_initial.max(self.noise_step);
            self.scratch
                .resize_with(groups, || Scratch::new(len, dim, noise));
        }
        for s in &mut self.scratch {
            s.hint = WalkHint::NONE;
        }
        let dim = self.dim;
        let ctx = StepCtx {
            model: &self.model,
            mutation: &self.mutation,
            t,
            u,
            y,
            n,
            c,
            dim,
            noise: if t == 0 {
                self.noise_initial
            } else {
                self.noise_step
            },
            log_uniform: -(n as f64).ln(),
            source,
            x_old: &self.x,
            lw_old: &self.lw,
            cw_old: &self.cw,
            offset: &self.offset,
            scale: &self.scale,
            n_over_total: n as f64 / self.total,
            ancestors: &self.ancestors,
            keep_lw: !matches!(self.cfg.policy, ResamplePolicy::Always),
            prefetch: n >= self.prefetch_min,
            per_group,
            avx512: Avx512::get(self.cfg.simd),
            avx2: Avx2::get(self.cfg.simd),
        };
        let simd = self.cfg.simd;
        type GroupWork<'a> = (
            usize,
            (
                (
                    ((&'a mut [f64], &'a mut [f64]), &'a mut [f64]),
                    &'a mut [ChunkRng],
                ),
                (&'a mut [ChunkStat], &'a mut Scratch),
            ),
        );
        let slot = dim * c;
        let work = |(g, ((((xs, cws), lws), rngs), (stats, scratch))): GroupWork<'_>| {
            let chunks = xs
                .chunks_mut(slot)
                .zip(cws.chunks_mut(c))
                .zip(lws.chunks_mut(c))
                .zip(rngs.iter_mut().zip(stats.iter_mut()));
            for (k, (((x, cw), lw), (rng, stat))) in chunks.enumerate() {
                let d = g * per_group + k;
                *stat = dispatch_widest(
                    ctx.avx512,
                    simd,
                    #[inline(always)]
                    || chunk_step(&ctx, d, x, cw, lw, rng, scratch),
                );
            }
        };
        let gs = per_group * c;
        // The same zip of groups, over std's iterators on one thread or rayon's on the pool
        // (`Par::Seq` never touches rayon's global pool).
        macro_rules! run_groups {
            ($chunks:ident, $iter:ident) => {
                self.x_new
                    .$chunks(per_group * slot)
                    .zip(self.cw_new.$chunks(gs))
                    .zip(self.lw_new.$chunks(gs))
                    .zip(self.rngs.$chunks(per_group))
                    .zip(self.stats.$chunks(per_group).zip(self.scratch.$iter()))
                    .enumerate()
                    .for_each(work)
            };
        }
        match par {
            Par::Seq => run_groups!(chunks_mut, iter_mut),
            Par::Rayon => run_groups!(par_chunks_mut, par_iter_mut),
        }
        if let Some((index, value)) = self.stats.iter().find_map(|s| s.bad) {
            return Err(CoreError::NonFiniteWeight { t, index, value });
        }
        let max = self
            .stats
            .iter()
            .fold(f64::NEG_INFINITY, |a, s| if s.max > a { s.max } else { a });
        if max == f64::NEG_INFINITY {
            return Err(CoreError::AllWeightsZero { t });
        }
        // Reconcile the chunk maxima: chunk d's weights count exp(m_d − max) times.
        let mut total = 0.0;
        let mut sq = 0.0;
        for ((off, scale), s) in self
            .offset
            .iter_mut()
            .zip(self.scale.iter_mut())
            .zip(&self.stats)
        {
            let r = if s.max == f64::NEG_INFINITY {
                0.0
            } else {
                (s.max - max).exp()
            };
            *off = total;
            *scale = r;
            total += r * s.sum;
            sq += r * r * s.sum_sq;
        }
        self.total = total;
        let log_c = max + total.ln();
        if !matches!(self.cfg.policy, ResamplePolicy::Always) {
            let shift = log_c;
            match par {
                Par::Seq => self.lw_new.iter_mut().for_each(|l| *l -= shift),
                Par::Rayon => self.lw_new.par_iter_mut().for_each(|l| *l -= shift),
            }
        }
        std::mem::swap(&mut self.x, &mut self.x_new);
        std::mem::swap(&mut self.lw, &mut self.lw_new);
        std::mem::swap(&mut self.cw, &mut self.cw_new);
        let report = StepReport {
            t,
            log_lik_increment: if y.is_some() { log_c } else { 0.0 },
            log_lik: prior_ll + if y.is_some() { log_c } else { 0.0 },
            ess: total * total / sq,
            resampled: resample,
        };
        self.last = Some(report);
        Ok(report)
    }

    /// Multinomial or residual resampling into `self.ancestors`, blocks of [`BLOCK`]
    /// particles or more drawing side by side (see [`ChunkSplit`]).
    fn resample_in_blocks(&mut self, scheme: Blocked) {
        let w = ChunkedWeights {
            cum: &self.cw,
            chunk: self.cfg.chunk,
            scale: &self.scale,
        };
        let plan = BlockPlan {
            scheme,
            simd: self.cfg.simd,
            par: self.cfg.par,
            per_block: chunks_per_block(self.cfg.n_particles, self.cfg.chunk, self.split_block),
        };
        self.split.draw(
            plan,
            w,
            &mut self.master,
            &mut self.w_norm,
            &mut self.ancestors,
        );
    }

    /// Filter `y_0, …, y_n` from the start with the inputs `u_0, …, u_n` (`None`: the
    /// default input at every step), telling `observer` about each step.
    ///
    /// # Errors
    /// An empty sequence, inputs not one per observation, any step error, or the
    /// observer's error.
    pub fn run_observed<O: BatchObserver + Send + ?Sized>(
        &mut self,
        us: Option<&[M::Input]>,
        ys: &[Option<M::Obs>],
        observer: &mut O,
    ) -> Result<RunSummary>
    where
        M::Obs: Sized,
        M::Input: Default,
    {
        if ys.is_empty() {
            return Err(CoreError::Empty {
                what: "observation sequence",
            });
        }
        if let Some(us) = us
            && us.len() != ys.len()
        {
            return Err(CoreError::DimensionMismatch {
                what: "inputs u_t (one per observation)",
                expected: ys.len(),
                got: us.len(),
            });
        }
        self.reset();
        let none = M::Input::default();
        let steps = |f: &mut Self, observer: &mut O| -> Result<RunSummary> {
            observer.on_start(f.cfg.n_particles, f.dim);
            let mut reports = Vec::with_capacity(ys.len());
            for (t, y) in ys.iter().enumerate() {
                let u = us.map_or(&none, |us| &us[t]);
                reports.push(f.step_with(u, y.as_ref())?);
                if let Some(view) = f.view() {
                    observer.on_step(&view);
                }
            }
            observer.on_finish()?;
            Ok(RunSummary {
                log_lik: f.log_likelihood(),
                reports,
            })
        };
        match self.cfg.par {
            // Called from outside the pool, every step's parallel pass would be sent to the
            // pool while this thread sleeps, three threads taking turns on two cores: the
            // whole run goes to a worker instead (see `step_with`).
            Par::Rayon if rayon::current_thread_index().is_none() => {
                rayon::scope(|_| steps(self, observer))
            }
            _ => steps(self, observer),
        }
    }
}

impl<M: BatchModel<Input = ()>, Q: BatchMutation<M>> BatchFilter<M, Q> {
    /// One step of a model without inputs (see [`step_with`](Self::step_with)).
    ///
    /// # Errors
    /// As [`step_with`](Self::step_with).
    pub fn step(&mut self, y: Option<&M::Obs>) -> Result<StepReport> {
        self.step_with(&(), y)
    }

    /// Filter `y_0, …, y_n` from the start.
    ///
    /// # Errors
    /// An empty sequence or any step error.
    pub fn run(&mut self, ys: &[Option<M::Obs>]) -> Result<RunSummary>
    where
        M::Obs: Sized,
    {
        self.run_observed(None, ys, &mut ())
    }
}

impl<M: ScalarModel, Q: BatchMutation<M>> BatchFilter<M, Q> {
    /// Current particles (empty before the first step and after
    /// [`reset`](Self::reset)); a scalar state's column is one slice.
    pub fn particles(&self) -> &[f64] {
        if self.last.is_some() {
            &self.x[..self.cfg.n_particles]
        } else {
            &[]
        }
    }

    /// Weighted mean of the current particles.
    ///
    /// # Errors
    /// [`CoreError::Empty`] before the first step (there are no particles yet).
    pub fn mean(&self) -> Result<f64> {
        let mut m = [0.0];
        self.mean_into(&mut m)?;
        Ok(m[0])
    }
}

#[cfg(test)]
mod tests {
    use super::chunk::{PAD, gather_counted};
    use super::*;
    use crate::filter::EssThreshold;
    use crate::resample::stratified_index_in;
    use crate::simd::math::{ceil_index_in, max_and_flag};

    fn setup() -> (NoisyAr1, Vec<Option<f64>>) {
        let m = NoisyAr1::new(0.9, 0.5, 1.0).unwrap();
        let (_, ys) = m.simulate(30, &mut stream_rng(4, 0));
        (m, ys.into_iter().map(Some).collect())
    }

    use crate::models::NoisyAr1;

    /// Bit-identical results on one thread, on a pool of one and of two threads, with
    /// the portable kernels instead of AVX2, and with the prefetches forced on (on one
    /// worker and on two, where a chunk at its group's end prefetches nothing), for every
    /// scheme and for adaptive resampling; the last chunk is shorter than the others, and
    /// the multinomial and residual draws are split into blocks (and, with blocks of the
    /// default size, made in one, the step then kept on one thread).
    #[test]
    fn identical_for_any_thread_count_and_kernel() {
        let (m, mut ys) = setup();
        ys[7] = None;
        for resampler in Resampler::ALL {
            for policy in [
                ResamplePolicy::Always,
                ResamplePolicy::EssBelow(EssThreshold::Fraction(0.5)),
            ] {
                let run = |par, threads, simd, prefetch_min, split_block| {
                    let cfg = BatchConfig {
                        chunk: 64,
                        par,
                        simd,
                        resampler,
                        policy,
                        ..BatchConfig::new(1000, 7)
                    };
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .unwrap();
                    pool.install(|| {
                        let mut f = BatchBootstrap::new(m, cfg).unwrap();
                        f.prefetch_min = prefetch_min;
                        f.split_block = split_block;
                        let s = f.run(&ys).unwrap();
                        let ess: Vec<u64> = s.reports.iter().map(|r| r.ess.to_bits()).collect();
                        let x: Vec<u64> = f.particles().iter().map(|v| v.to_bits()).collect();
                        (s.log_lik.to_bits(), f.mean().unwrap().to_bits(), ess, x)
                    })
                };
                let off = PREFETCH_MIN;
                // Blocks of at least 200 particles: the multinomial and residual draws in four
                // blocks of four chunks.
                let seq = run(Par::Seq, 1, Simd::Auto, off, 200);
                assert_eq!(seq, run(Par::Rayon, 1, Simd::Auto, off, 200), "{resampler}");
                assert_eq!(seq, run(Par::Rayon, 2, Simd::Auto, off, 200), "{resampler}");
                assert_eq!(seq, run(Par::Rayon, 3, Simd::Auto, off, 200), "{resampler}");
                assert_eq!(seq, run(Par::Seq, 1, Simd::Avx2, off, 200), "{resampler}");
                assert_eq!(
                    seq,
                    run(Par::Seq, 1, Simd::Portable, off, 200),
                    "{resampler}"
                );
                assert_eq!(
                    seq,
                    run(Par::Rayon, 2, Simd::Portable, off, 200),
                    "{resampler}"
                );
                assert_eq!(
                    seq,
                    run(Par::Seq, 1, Simd::Auto, 0, 200),
                    "{resampler}, prefetching"
                );
                assert_eq!(
                    seq,
                    run(Par::Rayon, 2, Simd::Auto, 0, 200),
                    "{resampler}, prefetching"
                );
                // Blocks of the default size: one block, and the step on one thread.
                assert_eq!(
                    run(Par::Seq, 1, Simd::Auto, off, BLOCK),
                    run(Par::Rayon, 2, Simd::Auto, off, BLOCK),
                    "{resampler}, one block"
                );
            }
        }
    }

    /// `run` called from outside any pool (it then moves its steps to a worker of the
    /// global pool) gives the bits of the sequential run and of steps taken one by one.
    #[test]
    fn a_run_from_outside_the_pool_is_the_sequential_run() {
        assert!(
            rayon::current_thread_index().is_none(),
            "a test thread is outside"
        );
        let (m, ys) = setup();
        let cfg = |par| BatchConfig {
            chunk: 64,
            par,
            ..BatchConfig::new(1000, 7)
        };
        let bits = |f: &BatchBootstrap<NoisyAr1>, ll: f64| {
            let x: Vec<u64> = f.particles().iter().map(|v| v.to_bits()).collect();
            (ll.to_bits(), x)
        };
        let mut seq = BatchBootstrap::new(m, cfg(Par::Seq)).unwrap();
        let ll = seq.run(&ys).unwrap().log_lik;
        let want = bits(&seq, ll);
        let mut par = BatchBootstrap::new(m, cfg(Par::Rayon)).unwrap();
        let ll = par.run(&ys).unwrap().log_lik;
        assert_eq!(bits(&par, ll), want);
        let mut stepped = BatchBootstrap::new(m, cfg(Par::Rayon)).unwrap();
        for &y in &ys {
            stepped.step(y.as_ref()).unwrap();
        }
        assert_eq!(bits(&stepped, stepped.log_likelihood()), want);
    }

    /// A multivariate state (3 columns) gives the same bits on one thread and on pools of
    /// two and three, with the portable kernels, and with the prefetches forced on, for every
    /// scheme and both policies; its moments through the view agree with the columns read
    /// out particle by particle.
    #[test]
    fn a_multivariate_state_is_identical_for_any_thread_count() {
        use crate::kalman::LinearGaussian;
        use nalgebra::{DMatrix, DVector};
        let lg = LinearGaussian::new(
            DMatrix::from_row_slice(3, 3, &[0.9, 0.3, 0.0, 0.0, 0.8, 0.2, 0.1, 0.0, 0.7]),
            None,
            DMatrix::from_row_slice(1, 3, &[1.0, 0.0, 0.5]),
            DMatrix::from_row_slice(3, 3, &[0.2, 0.05, 0.0, 0.05, 0.3, 0.02, 0.0, 0.02, 0.1]),
            DMatrix::from_row_slice(1, 1, &[0.5]),
            DVector::from_vec(vec![0.0, 1.0, -1.0]),
            DMatrix::identity(3, 3),
        )
        .unwrap();
        let model = lg.batch().unwrap();
        let (_, ys) = lg.simulate(25, None, &mut stream_rng(8, 0)).unwrap();
        let mut ys: Vec<Option<DVector<f64>>> = ys.into_iter().map(Some).collect();
        ys[4] = None;
        for resampler in Resampler::ALL {
            for policy in [
                ResamplePolicy::Always,
                ResamplePolicy::EssBelow(EssThreshold::Fraction(0.5)),
            ] {
                let run = |par, threads, simd, prefetch_min| {
                    let cfg = BatchConfig {
                        chunk: 64,
                        par,
                        simd,
                        resampler,
                        policy,
                        ..BatchConfig::new(1000, 7)
                    };
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .unwrap();
                    pool.install(|| {
                        let mut f = BatchFilter::new(model.clone(), cfg).unwrap();
                        f.prefetch_min = prefetch_min;
                        f.split_block = 200;
                        let mut rec = MomentRecorder::default();
                        let s = f.run_observed(None, &ys, &mut rec).unwrap();
                        let v = f.view().unwrap();
                        let mut x = vec![0.0; 3 * 1000];
                        for (k, col) in x.chunks_mut(1000).enumerate() {
                            v.column_into(k, col).unwrap();
                        }
                        let mut w = vec![0.0; 1000];
                        v.weights_into(&mut w).unwrap();
                        // The view's mean is the columns' weighted sum.
                        let mut mean = [0.0; 3];
                        v.mean_into(&mut mean).unwrap();
                        for (k, m) in mean.iter().enumerate() {
                            let direct: f64 = x[k * 1000..(k + 1) * 1000]
                                .iter()
                                .zip(&w)
                                .map(|(x, w)| x * w)
                                .sum();
                            assert!(
                                (m - direct).abs() < 1e-12 * (1.0 + direct.abs()),
                                "{k}: {m} {direct}"
                            );
                        }
                        let mut state = [0.0; 3];
                        v.state_into(517, &mut state).unwrap();
                        assert_eq!(state, [x[517], x[1517], x[2517]]);
                        let bits = |v: &[f64]| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                        (
                            s.log_lik.to_bits(),
                            bits(&x),
                            bits(&rec.mean),
                            bits(&rec.cov),
                        )
                    })
                };
                let off = PREFETCH_MIN;
                let seq = run(Par::Seq, 1, Simd::Auto, off);
                assert_eq!(seq, run(Par::Rayon, 2, Simd::Auto, off), "{resampler}");
                assert_eq!(seq, run(Par::Rayon, 3, Simd::Auto, off), "{resampler}");
                assert_eq!(seq, run(Par::Seq, 1, Simd::Portable, off), "{resampler}");
                assert_eq!(
                    seq,
                    run(Par::Rayon, 2, Simd::Auto, 0),
                    "{resampler}, prefetching"
                );
            }
        }
    }

    /// The chunk-local resamplers (bisection, boundaries, four-wide copies) draw exactly
    /// the ancestors of the textbook merge of their points with the same global cumulative
    /// weights, whatever the chunk size: `(i + U)/N` for systematic resampling, and
    /// `(i + U_i)/N` with `U_i = stratum_uniform(key, i)` for stratified.
    #[test]
    fn chunked_resamplers_equal_the_merge() {
        use crate::resample::stratum_uniform;
        let (m, ys) = setup();
        for (n, chunk) in [(500usize, 37usize), (500, 500), (64, 8), (1, 1), (1000, 64)] {
            let cfg = BatchConfig {
                chunk,
                ..BatchConfig::new(n, 3)
            };
            let mut f = BatchBootstrap::new(m, cfg).unwrap();
            for y in &ys[..3] {
                f.step(y.as_ref()).unwrap();
            }
            // States equal to their indices, so the gathered states are the ancestors.
            let index: Vec<f64> = (0..n).map(|j| j as f64).collect();
            // The weights as the filter left them, and with runs of zero weights inside the
            // chunks (long plateaus of equal boundaries, where a search can stop early).
            for plateaus in [false, true] {
                let mut cw = f.cw.to_vec();
                if plateaus {
                    for j in 1..n {
                        if j % chunk != 0 && j % chunk != chunk - 1 && (j / 5) % 3 != 0 {
                            cw[j] = cw[j - 1];
                        }
                    }
                }
                let ctx = StepCtx {
                    model: &f.model,
                    mutation: &Bootstrap,
                    t: 3,
                    u: &(),
                    y: None,
                    n,
                    c: chunk,
                    dim: 1,
                    noise: 1,
                    log_uniform: 0.0,
                    source: Source::Identity,
                    x_old: &index,
                    lw_old: &f.lw,
                    cw_old: &cw,
                    offset: &f.offset,
                    scale: &f.scale,
                    n_over_total: n as f64 / f.total,
                    ancestors: &f.ancestors,
                    keep_lw: false,
                    prefetch: false,
                    per_group: 1,
                    avx512: None,
                    avx2: None,
                };
                // G_j N/T, from the global cumulative weights.
                let pos: Vec<f64> = (0..n).map(|j| ctx.chunk_map(j / chunk).x(cw[j])).collect();
                // Ancestors by the chunks, with boundaries `k`, the walk's hint carried from
                // chunk to chunk (as one worker runs them) or reset before each (a bisection
                // over all N, as a worker's first chunk).
                let chunked = |k: &dyn Fn(f64, f64, f64) -> usize,
                               twin: Option<(Avx512, f64)>,
                               carry: bool| {
                    let mut all = vec![0.0; n];
                    let mut out = vec![f64::NAN; chunk + PAD];
                    let mut hint = WalkHint::NONE;
                    for (d, dst) in all.chunks_mut(chunk).enumerate() {
                        if !carry {
                            hint = WalkHint::NONE;
                        }
                        let len = dst.len();
                        gather_counted(
                            &ctx,
                            (k, twin),
                            d * chunk,
                            len,
                            &mut out,
                            &mut hint,
                            |j, m| index[j..j + m].iter().copied(),
                        );
                        dst.copy_from_slice(&out[..len]);
                    }
                    all.iter().map(|&a| a as usize).collect::<Vec<_>>()
                };
                // The merge: A_i = first j whose `x_j = G_j N/T` lies above point `i`, clamped
                // to N − 1.
                let merge = |below: &dyn Fn(usize, f64) -> bool| {
                    let mut j = 0;
                    (0..n)
                        .map(|i| {
                            while j + 1 < n && !below(i, pos[j]) {
                                j += 1;
                            }
                            j
                        })
                        .collect::<Vec<_>>()
                };
                for u in [0.0, 0.25, 0.731, 0.999_999] {
                    let k = |x: f64, a, b| ceil_index_in(x - u, a, b);
                    let below = |i: usize, x: f64| (i as f64) < x - u;
                    // On the AVX-512 twin's boundaries too, where the CPU has them.
                    let twins = [None, Avx512::get(Simd::Auto).map(|cpu| (cpu, u))];
                    for (carry, twin) in [false, true]
                        .into_iter()
                        .flat_map(|c| twins.map(|t| (c, t)))
                    {
                        assert_eq!(
                            chunked(&k, twin, carry),
                            merge(&below),
                            "N = {n}, chunk {chunk}, U = {u}, plateaus {plateaus}, hint carried: {carry}, twin {}",
                            twin.is_some()
                        );
                    }
                }
                for key in [0u64, 7, u64::MAX] {
                    let k = |x, a, b| stratified_index_in(x, key, a, b);
                    // Point i lies below x when i < ⌊x⌋, or i = ⌊x⌋ and U_i < x − i.
                    let below = |i: usize, x: f64| {
                        let f = x.floor();
                        (i as f64) < f
                            || ((i as f64) == f && stratum_uniform(key, i as u64) < x - f)
                    };
                    for carry in [false, true] {
                        assert_eq!(
                            chunked(&k, None, carry),
                            merge(&below),
                            "N = {n}, chunk {chunk}, key {key}, plateaus {plateaus}, hint carried: {carry}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn degenerate_and_bad_inputs_are_errors() {
        let (m, _) = setup();
        assert!(BatchBootstrap::new(m, BatchConfig::new(0, 0)).is_err());
        assert!(
            BatchBootstrap::new(
                m,
                BatchConfig {
                    chunk: 0,
                    ..BatchConfig::new(10, 0)
                }
            )
            .is_err()
        );
        assert!(matches!(
            BatchBootstrap::new(
                m,
                BatchConfig {
                    chunk: 1 << 32,
                    ..BatchConfig::new(10, 0)
                }
            ),
            Err(CoreError::Param(ParamError { name: "chunk", .. }))
        ));
        // A count no machine can hold is refused, not a capacity overflow panic.
        assert!(matches!(
            BatchBootstrap::new(m, BatchConfig::new(usize::MAX, 0)),
            Err(CoreError::TooLarge { .. })
        ));
        // So is one within the count limit whose arrays (2³² particles, 256 GiB) exceed the
        // machine's memory: an error before anything is mapped, where Linux would grant the
        // mappings and kill the process at its first write.
        #[cfg(target_os = "linux")]
        assert!(matches!(
            BatchBootstrap::new(m, BatchConfig::new(crate::limits::MAX_COUNT, 0)),
            Err(CoreError::TooLarge {
                what: PARTICLE_BUFFERS,
                ..
            })
        ));
        let mut f = BatchBootstrap::new(m, BatchConfig::new(10, 0)).unwrap();
        assert!(f.run(&[]).is_err());
        assert!(matches!(
            f.run(&[Some(0.0), Some(f64::NAN)]),
            Err(CoreError::NonFiniteWeight { t: 1, .. })
        ));
        // Every weight exactly zero (log-weight −∞) is an error, not NaN.
        struct Impossible;
        impl ScalarModel for Impossible {
            fn initial_from_normal(&self, z: f64) -> f64 {
                z
            }
            fn transition_from_normal(&self, _t: usize, x: f64, z: f64) -> f64 {
                x + z
            }
            fn log_likelihood_scalar(&self, _t: usize, _x: f64, _y: f64) -> f64 {
                f64::NEG_INFINITY
            }
        }
        let mut f = BatchBootstrap::new(Impossible, BatchConfig::new(100, 0)).unwrap();
        assert!(matches!(
            f.run(&[None, Some(1.0)]),
            Err(CoreError::AllWeightsZero { t: 1 })
        ));
    }

    /// No mean before the first step; a failed step leaves the filter at the step before,
    /// with its particles and mean untouched, and the next step goes on from there.
    #[test]
    fn a_failed_step_leaves_the_filter_where_it_was() {
        let (m, ys) = setup();
        for resampler in [Resampler::Systematic, Resampler::Residual] {
            let cfg = BatchConfig {
                resampler,
                ..BatchConfig::new(500, 3)
            };
            let mut f = BatchBootstrap::new(m, cfg).unwrap();
            assert!(matches!(f.mean(), Err(CoreError::Empty { .. })));
            assert!(f.particles().is_empty() && f.t().is_none() && f.last_report().is_none());
            f.step(ys[0].as_ref()).unwrap();
            let ok = f.step(ys[1].as_ref()).unwrap();
            assert_eq!((f.t(), f.last_report()), (Some(1), Some(&ok)));
            let (x, mean) = (f.particles().to_vec(), f.mean().unwrap());
            assert!(matches!(
                f.step(Some(&f64::NAN)),
                Err(CoreError::NonFiniteWeight { t: 2, .. })
            ));
            assert_eq!(f.particles(), x);
            assert_eq!(f.mean().unwrap().to_bits(), mean.to_bits());
            assert_eq!(f.log_likelihood(), ok.log_lik);
            let next = f.step(ys[2].as_ref()).unwrap();
            assert_eq!(next.t, 2);
            assert!(next.log_lik.is_finite() && f.mean().unwrap().is_finite());
            f.reset();
            assert!(f.particles().is_empty() && f.t().is_none());
            assert!(format!("{f:?}").starts_with("BatchFilter { cfg: BatchConfig {"));
        }
    }

    /// The maximum's AVX-512 twin gives the portable loop's maximum (after the `+ 0`) and
    /// flag: on lengths around its 32-weight blocks, with the largest value in the blocks
    /// or in the remainder, with `−∞`, both zeros, and a NaN or `+∞` anywhere.
    #[test]
    fn the_maximum_twin_matches_the_portable_loop() {
        let Some(cpu) = Avx512::for_test() else {
            return;
        };
        let mut rng = stream_rng(5, 0);
        for len in [0usize, 1, 7, 31, 32, 33, 64, 100, 2048] {
            for case in 0..6 {
                let mut l: Vec<f64> = (0..len).map(|_| -rng.random::<f64>() * 50.0).collect();
                if len > 0 {
                    let i = rng.random_range(0..len);
                    match case {
                        0 => {}
                        1 => l[len - 1] = 1.0,
                        2 => l.iter_mut().for_each(|v| *v = f64::NEG_INFINITY),
                        3 => {
                            l[i] = 0.0;
                            l[len - 1 - i] = -0.0;
                        }
                        4 => l[i] = f64::NAN,
                        _ => l[i] = f64::INFINITY,
                    }
                }
                let (want, want_bad) = max_and_flag(&l);
                let (got, got_bad) = cpu.max_and_flag(&l);
                assert_eq!(got_bad, want_bad, "len {len}, case {case}");
                if !want_bad {
                    assert_eq!((got + 0.0).to_bits(), (want + 0.0).to_bits(), "len {len}");
                }
            }
        }
    }

    /// A NaN is reported at its own index, in whichever chunk it appears.
    #[test]
    fn a_nan_weight_names_its_particle() {
        struct NanAt(usize);
        impl ScalarModel for NanAt {
            fn initial_from_normal(&self, z: f64) -> f64 {
                z
            }
            fn transition_from_normal(&self, _t: usize, x: f64, z: f64) -> f64 {
                x + z
            }
            fn log_likelihood_scalar(&self, _t: usize, x: f64, _y: f64) -> f64 {
                // Particle states are distinct, so tag particle `self.0` by its state.
                if x.to_bits() == self.0 as u64 {
                    f64::NAN
                } else {
                    -x * x
                }
            }
        }
        let cfg = BatchConfig {
            chunk: 16,
            ..BatchConfig::new(100, 5)
        };
        let probe = BatchBootstrap::new(NanAt(u64::MAX as usize), cfg).map(|mut f| {
            f.step(None).unwrap();
            f.particles()[57].to_bits()
        });
        let tag = probe.unwrap() as usize;
        let mut f = BatchBootstrap::new(NanAt(tag), cfg).unwrap();
        match f.step(Some(&0.0)) {
            Err(CoreError::NonFiniteWeight { t: 0, index, value }) => {
                assert_eq!(index, 57);
                assert!(value.is_nan());
            }
            other => panic!("expected a NaN error, got {other:?}"),
        }
    }

    #[test]
    fn missing_observations_add_nothing() {
        let (m, mut ys) = setup();
        ys[5] = None;
        let mut f = BatchBootstrap::new(m, BatchConfig::new(100, 1)).unwrap();
        let s = f.run(&ys).unwrap();
        assert_eq!(s.reports[5].log_lik_increment, 0.0);
        assert!(s.log_lik.is_finite());
    }
}
