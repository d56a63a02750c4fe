//! A structure-of-arrays bootstrap filter for scalar-state models: the fast path.
//!
//! The generic [`ParticleFilter`](super::ParticleFilter) calls the model once per particle
//! and stores states of any type. For a scalar state the same algorithm runs on plain `f64`
//! arrays in fixed chunks of [`BatchConfig::chunk`] particles:
//!
//! 1. resample (systematic: each output chunk finds its own ancestors by counting offspring
//!    against the global cumulative weights, so chunks run in parallel);
//! 2. gather, propagate and weigh in one pass, with standard normals from the chunk's own
//!    random stream;
//! 3. exponentiate and accumulate within each chunk;
//!    chunk totals are combined in chunk order.
//!
//! Chunks, streams and the order of every reduction are fixed by `N` and the chunk size,
//! not by the number of threads, so [`Par::Seq`] and [`Par::Rayon`] on any pool give
//! bit-identical results. The streams differ from the generic filter's single stream, so
//! the two filters agree in distribution, not draw by draw.

use super::{ResamplePolicy, RunSummary, StepReport};
use crate::error::{CoreError, Result};
use crate::mc::{Par, PfRng, stream_rng};
use crate::resample::{Resample, Resampler, ceil_to_usize};
use rand::RngExt;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;

/// A model with a scalar state, written in terms of standard normal noise so that the
/// fast path can feed it pre-drawn or chunk-local draws.
pub trait ScalarModel: Sync {
    /// `X_0` from a standard normal `z`.
    fn initial_from_normal(&self, z: f64) -> f64;
    /// `X_t` from `x_prev` and a standard normal `z`.
    fn transition_from_normal(&self, t: usize, x_prev: f64, z: f64) -> f64;
    /// `log g_t(y | x)`.
    fn log_likelihood_scalar(&self, t: usize, x: f64, y: f64) -> f64;
}

/// Configuration of [`BatchBootstrap`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BatchConfig {
    /// Number of particles `N`.
    pub n_particles: usize,
    /// Resampling scheme; systematic runs chunk-parallel, the others run on one thread.
    pub resampler: Resampler,
    /// When to resample.
    pub policy: ResamplePolicy,
    /// Particles per chunk: the unit of parallel work and of random streams.
    pub chunk: usize,
    /// Seed of the chunk streams and of the resampling uniforms.
    pub seed: u64,
    /// Where chunks run.
    pub par: Par,
}

impl BatchConfig {
    /// `n` particles, systematic resampling at every step, chunks of 8192, on rayon.
    pub fn new(n: usize, seed: u64) -> Self {
        BatchConfig {
            n_particles: n,
            resampler: Resampler::Systematic,
            policy: ResamplePolicy::Always,
            chunk: 8192,
            seed,
            par: Par::Rayon,
        }
    }
}

/// One chunk's share of a step: its states, log-weights, stream and (max, first NaN).
type ChunkWork<'a> = (
    usize,
    (
        (&'a mut [f64], &'a mut [f64]),
        (&'a mut ChunkRng, &'a mut (f64, Option<usize>)),
    ),
);

/// One chunk's cumulative weights, its log-weights and its (sum, sum of squares).
type AccumulateWork<'a> = ((&'a mut [f64], &'a [f64]), &'a mut (f64, f64));

/// A random stream on its own cache line, so that two threads never share one.
#[derive(Clone)]
#[repr(align(64))]
struct ChunkRng(PfRng);

/// The fast bootstrap filter for [`ScalarModel`]s.
pub struct BatchBootstrap<M> {
    model: M,
    cfg: BatchConfig,
    x: Vec<f64>,
    x_new: Vec<f64>,
    /// Normalised `log W` (only maintained when the policy may skip resampling).
    lw: Vec<f64>,
    lw_new: Vec<f64>,
    /// Cumulative unnormalised weights within each chunk.
    cw: Vec<f64>,
    ancestors: Vec<usize>,
    /// Normalised weights, for the resamplers that run on one thread.
    w_norm: Vec<f64>,
    rngs: Vec<ChunkRng>,
    master: PfRng,
    /// Per chunk: max log-weight, first NaN index, sum of weights, sum of squares.
    chunk_max: Vec<(f64, Option<usize>)>,
    chunk_sum: Vec<(f64, f64)>,
    /// Global offset of each chunk's cumulative weights.
    offset: Vec<f64>,
    total: f64,
    last: Option<StepReport>,
}

impl<M: ScalarModel> BatchBootstrap<M> {
    /// Allocate every buffer once.
    ///
    /// # Errors
    /// `N = 0` or a chunk size of 0.
    pub fn new(model: M, cfg: BatchConfig) -> Result<Self> {
        if cfg.n_particles == 0 {
            return Err(CoreError::InvalidParameter {
                name: "N",
                value: 0.0,
                reason: "the number of particles must be at least 1",
            });
        }
        if cfg.chunk == 0 {
            return Err(CoreError::InvalidParameter {
                name: "chunk",
                value: 0.0,
                reason: "the chunk size must be at least 1",
            });
        }
        cfg.policy.validate()?;
        let n = cfg.n_particles;
        let chunks = n.div_ceil(cfg.chunk);
        let mut f = BatchBootstrap {
            model,
            cfg,
            x: vec![0.0; n],
            x_new: vec![0.0; n],
            lw: vec![0.0; n],
            lw_new: vec![0.0; n],
            cw: vec![0.0; n],
            ancestors: (0..n).collect(),
            w_norm: vec![0.0; n],
            rngs: Vec::with_capacity(chunks),
            master: stream_rng(cfg.seed, u64::MAX),
            chunk_max: vec![(0.0, None); chunks],
            chunk_sum: vec![(0.0, 0.0); chunks],
            offset: vec![0.0; chunks],
            total: 0.0,
            last: None,
        };
        f.reset();
        Ok(f)
    }

    /// Back to `k = 0`, with the streams restarted from the seed.
    pub fn reset(&mut self) {
        let chunks = self.chunk_max.len();
        self.rngs = (0..chunks)
            .map(|c| ChunkRng(stream_rng(self.cfg.seed, c as u64)))
            .collect();
        self.master = stream_rng(self.cfg.seed, u64::MAX);
        self.last = None;
    }

    /// Current particles.
    pub fn particles(&self) -> &[f64] {
        &self.x
    }

    /// Running log-likelihood estimate.
    pub fn log_likelihood(&self) -> f64 {
        self.last.map_or(0.0, |r| r.log_lik)
    }

    /// Weighted mean of the current particles.
    pub fn mean(&self) -> f64 {
        let c = self.cfg.chunk;
        let mut acc = 0.0;
        for (xs, cws) in self.x.chunks(c).zip(self.cw.chunks(c)) {
            let mut prev = 0.0;
            for (x, &cw) in xs.iter().zip(cws) {
                acc += x * (cw - prev);
                prev = cw;
            }
        }
        acc / self.total
    }

    /// One step; `y = None` is a missing observation.
    ///
    /// # Errors
    /// All weights zero or a NaN weight at this step; the filter is then left unusable
    /// until [`reset`](Self::reset) (unlike the generic filter, it does not keep a copy of
    /// the previous step: that copy would cost a pass over memory every step).
    pub fn step(&mut self, y: Option<f64>) -> Result<StepReport> {
        let n = self.cfg.n_particles;
        let c = self.cfg.chunk;
        let log_n = (n as f64).ln();
        let (t, resample, prior_ll) = match self.last {
            None => (0, false, 0.0),
            Some(r) => (
                r.t + 1,
                self.cfg.policy.should_resample(r.ess, n),
                r.log_lik,
            ),
        };
        if resample {
            self.resample_step();
        }
        let model = &self.model;
        let (x_old, lw_old, ancestors) = (&self.x, &self.lw, &self.ancestors);
        let first = t == 0;
        let work = |(d, ((xs, lws), (rng, mx))): ChunkWork<'_>| {
            let base = d * c;
            let mut m = f64::NEG_INFINITY;
            let mut nan = None;
            for (j, (x, l)) in xs.iter_mut().zip(lws.iter_mut()).enumerate() {
                let i = base + j;
                let z: f64 = StandardNormal.sample(&mut rng.0);
                let prior = if first || resample { -log_n } else { lw_old[i] };
                *x = if first {
                    model.initial_from_normal(z)
                } else if resample {
                    model.transition_from_normal(t, x_old[ancestors[i]], z)
                } else {
                    model.transition_from_normal(t, x_old[i], z)
                };
                *l = match y {
                    Some(y) => prior + model.log_likelihood_scalar(t, *x, y),
                    None => prior,
                };
                if l.is_nan() || *l == f64::INFINITY {
                    nan = nan.or(Some(i));
                }
                m = m.max(*l);
            }
            *mx = (m, nan);
        };
        match self.cfg.par {
            Par::Seq => self
                .x_new
                .chunks_mut(c)
                .zip(self.lw_new.chunks_mut(c))
                .zip(self.rngs.iter_mut().zip(self.chunk_max.iter_mut()))
                .enumerate()
                .for_each(work),
            Par::Rayon => self
                .x_new
                .par_chunks_mut(c)
                .zip(self.lw_new.par_chunks_mut(c))
                .zip(self.rngs.par_iter_mut().zip(self.chunk_max.par_iter_mut()))
                .enumerate()
                .for_each(work),
        }
        if let Some(index) = self.chunk_max.iter().find_map(|&(_, nan)| nan) {
            return Err(CoreError::NonFiniteWeight {
                t,
                index,
                value: self.lw_new[index],
            });
        }
        let max = self
            .chunk_max
            .iter()
            .fold(f64::NEG_INFINITY, |a, &(m, _)| a.max(m));
        if max == f64::NEG_INFINITY {
            return Err(CoreError::AllWeightsZero { t });
        }
        let accumulate = |((cws, lws), s): AccumulateWork<'_>| {
            let mut acc = 0.0;
            let mut sq = 0.0;
            for (cw, &l) in cws.iter_mut().zip(lws) {
                let w = (l - max).exp();
                acc += w;
                sq += w * w;
                *cw = acc;
            }
            *s = (acc, sq);
        };
        match self.cfg.par {
            Par::Seq => self
                .cw
                .chunks_mut(c)
                .zip(self.lw_new.chunks(c))
                .zip(self.chunk_sum.iter_mut())
                .for_each(accumulate),
            Par::Rayon => self
                .cw
                .par_chunks_mut(c)
                .zip(self.lw_new.par_chunks(c))
                .zip(self.chunk_sum.par_iter_mut())
                .for_each(accumulate),
        }
        let mut total = 0.0;
        let mut sq = 0.0;
        for (off, &(s, q)) in self.offset.iter_mut().zip(&self.chunk_sum) {
            *off = total;
            total += s;
            sq += q;
        }
        self.total = total;
        let log_c = max + total.ln();
        if !matches!(self.cfg.policy, ResamplePolicy::Always) {
            let shift = log_c;
            match self.cfg.par {
                Par::Seq => self.lw_new.iter_mut().for_each(|l| *l -= shift),
                Par::Rayon => self.lw_new.par_iter_mut().for_each(|l| *l -= shift),
            }
        }
        std::mem::swap(&mut self.x, &mut self.x_new);
        std::mem::swap(&mut self.lw, &mut self.lw_new);
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

    fn resample_step(&mut self) {
        let n = self.cfg.n_particles;
        match self.cfg.resampler {
            Resampler::Systematic => {
                let u: f64 = self.master.random();
                let c = self.cfg.chunk;
                let scale = n as f64 / self.total;
                let (offset, cw) = (&self.offset, &self.cw);
                // Offspring boundary of particle j: #{i : (i + U)/N < G_j/T}, with
                // G_j = offset of j's chunk + cumulative weight within it.
                let k = |j: usize| -> usize {
                    if j + 1 == n {
                        n
                    } else {
                        let g = offset[j / c] + cw[j];
                        ceil_to_usize(g * scale - u).min(n)
                    }
                };
                // The scatter-and-prefix-sum of `Systematic`, restricted to one output chunk
                // [lo, hi): A_i = j0 + #{j ≥ j0 : k_j ≤ i}, where j0 is the first j with
                // k_j > lo (found by bisection, as k is non-decreasing).
                let fill = |(d, out): (usize, &mut [usize])| {
                    let lo = d * c;
                    let hi = lo + out.len();
                    let (mut a, mut b) = (0usize, n - 1);
                    while a < b {
                        let mid = (a + b) / 2;
                        if k(mid) > lo { b = mid } else { a = mid + 1 }
                    }
                    out.fill(0);
                    let mut j = a;
                    let mut chunk_end = (j / c + 1) * c;
                    let mut base = offset[j / c];
                    while j + 1 < n {
                        if j == chunk_end {
                            base = offset[j / c];
                            chunk_end += c;
                        }
                        let kj = ceil_to_usize((base + cw[j]) * scale - u);
                        if kj >= hi {
                            break;
                        }
                        out[kj - lo] += 1;
                        j += 1;
                    }
                    let mut acc = a;
                    for o in out.iter_mut() {
                        acc += *o;
                        *o = acc;
                    }
                };
                match self.cfg.par {
                    Par::Seq => self.ancestors.chunks_mut(c).enumerate().for_each(fill),
                    Par::Rayon => self.ancestors.par_chunks_mut(c).enumerate().for_each(fill),
                }
            }
            scheme => {
                for j in 0..n {
                    let prev = if j % self.cfg.chunk == 0 {
                        0.0
                    } else {
                        self.cw[j - 1]
                    };
                    self.w_norm[j] = (self.cw[j] - prev) / self.total;
                }
                scheme.resample(&self.w_norm, &mut self.master, &mut self.ancestors);
            }
        }
    }

    /// Filter `y_0, …, y_n` from the start.
    ///
    /// # Errors
    /// An empty sequence or any step error.
    pub fn run(&mut self, ys: &[Option<f64>]) -> Result<RunSummary> {
        if ys.is_empty() {
            return Err(CoreError::Empty {
                what: "observation sequence",
            });
        }
        self.reset();
        let mut reports = Vec::with_capacity(ys.len());
        for &y in ys {
            reports.push(self.step(y)?);
        }
        Ok(RunSummary {
            log_lik: self.log_likelihood(),
            reports,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::NoisyAr1;
    use crate::resample::InverseCdf;

    fn setup() -> (NoisyAr1, Vec<Option<f64>>) {
        let m = NoisyAr1::new(0.9, 0.5, 1.0).unwrap();
        let (_, ys) = m.simulate(30, &mut stream_rng(4, 0));
        (m, ys.into_iter().map(Some).collect())
    }

    #[test]
    fn identical_for_any_thread_count() {
        let (m, ys) = setup();
        let run = |par, threads| {
            let cfg = BatchConfig {
                chunk: 64,
                par,
                ..BatchConfig::new(1000, 7)
            };
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut f = BatchBootstrap::new(m, cfg).unwrap();
                let s = f.run(&ys).unwrap();
                (
                    s.log_lik.to_bits(),
                    f.mean().to_bits(),
                    f.particles().to_vec(),
                )
            })
        };
        let seq = run(Par::Seq, 1);
        assert_eq!(seq, run(Par::Rayon, 1));
        assert_eq!(seq, run(Par::Rayon, 2));
    }

    /// The chunk-parallel systematic resampler draws exactly the ancestors of the textbook
    /// inverse-CDF merge on the same weights and the same uniform.
    #[test]
    fn chunked_systematic_equals_the_merge() {
        let (m, ys) = setup();
        let cfg = BatchConfig {
            chunk: 37,
            ..BatchConfig::new(500, 3)
        };
        let mut f = BatchBootstrap::new(m, cfg).unwrap();
        f.step(ys[0]).unwrap();
        // Weights after step 0, normalised, as the merge sees them.
        let n = 500;
        let w: Vec<f64> = (0..n)
            .map(|j| {
                let prev = if j % 37 == 0 { 0.0 } else { f.cw[j - 1] };
                (f.cw[j] - prev) / f.total
            })
            .collect();
        let u: f64 = stream_rng(3, u64::MAX).random();
        f.step(ys[1]).unwrap();
        let mut cdf = InverseCdf::new(n, |j| w[j]);
        let merge: Vec<usize> = (0..n)
            .map(|i| cdf.locate((i as f64 + u) / n as f64))
            .collect();
        assert_eq!(f.ancestors, merge);
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
        let mut f = BatchBootstrap::new(m, BatchConfig::new(10, 0)).unwrap();
        assert!(f.run(&[]).is_err());
        assert!(matches!(
            f.run(&[Some(0.0), Some(f64::NAN)]),
            Err(CoreError::NonFiniteWeight { t: 1, .. })
        ));
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
