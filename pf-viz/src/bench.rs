//! `pf-viz bench bootstrap`: the speed of the AR(1)+noise bootstrap filter on this machine;
//! `pf-viz bench filter`: the same for the papers' filters on the batch engine;
//! `pf-viz bench genealogy`: the memory of pruned path storage.
//!
//! The filter is pf-core's structure-of-arrays fast path ([`BatchBootstrap`]): φ = 0.98,
//! σ = 0.2, ρ = 1, resampling at every step, Cappé & Moulines' diffuse prior N(Y_0, ρ²), so
//! `loglik` estimates log p(Y_1…Y_n | Y_0). Only filtering is timed: not simulation, not I/O.
//! With `--repeat R` the same computation runs R times and the fastest counts: on a shared
//! machine, the least disturbed run is the closest to what the code costs.

use std::time::Instant;

use pf_core::filter::{BatchBootstrap, BatchConfig, ResamplePolicy};
use pf_core::limits::check_count;
use pf_core::mc::{Par, stream_rng};
use pf_core::models::NoisyAr1;
use pf_core::simd::Simd;
use serde::{Deserialize, Serialize};

use pf_core::filter::{FilterConfig, ParticleFilter};
use pf_core::observe::AncestryRecorder;

use pf_homotopy::experiments::bench::BearingsBench;
use pf_mpf::experiments::bench::RadarBench;

use crate::cli::{BenchBootstrapArgs, BenchFilterArgs, BenchGenealogyArgs, BenchModel};
use crate::data::{read_radar, read_y};
use crate::error::{Result, VizError};

/// The JSON contract of `pf-viz bench bootstrap --json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BenchResult {
    /// N.
    pub particles: usize,
    /// n: observations filtered after Y_0.
    pub steps: usize,
    /// Worker threads.
    pub threads: usize,
    /// Wall-clock seconds of filtering (the fastest of the `repeat` runs).
    pub seconds: f64,
    /// `seconds / (N·n)` in nanoseconds.
    pub ns_per_particle_step: f64,
    /// Estimate of log p(Y_1…Y_n | Y_0).
    pub loglik: f64,
    /// Runs timed (`--repeat`).
    pub repeat: usize,
    /// The median of the runs' seconds (the upper of the middle two for an even `repeat`).
    pub seconds_median: f64,
    /// The copy of pf-core's kernels that ran (`--simd` on this CPU): `avx512`, `avx2` or
    /// `portable`.
    #[serde(default)]
    pub kernels: String,
}

/// Run the benchmark.
///
/// # Errors
/// Bad arguments (N = 0, n = 0, T = 0 or above [`MAX_THREADS`](crate::error::MAX_THREADS),
/// R = 0, more steps than data), unreadable data, or a filter failure.
pub fn bootstrap(args: &BenchBootstrapArgs) -> Result<BenchResult> {
    let invalid = |message: String| VizError::Argument { message };
    if args.particles == 0 {
        return Err(invalid("--particles must be at least 1".into()));
    }
    crate::error::check_threads("--threads", args.threads)?;
    if let Some(n) = args.steps {
        check_count("--steps", n).map_err(VizError::core("bench"))?;
    }
    if args.repeat == 0 {
        return Err(invalid("--repeat must be at least 1".into()));
    }
    let model = NoisyAr1::new(0.98, 0.2, 1.0).map_err(VizError::core("bench"))?;
    let ys: Vec<f64> = match &args.data {
        Some(path) => {
            let ys = read_y(path, 2)?;
            match args.steps {
                Some(n) if n + 1 > ys.len() => {
                    return Err(invalid(format!(
                        "--steps {n} needs {} observations, {} has {}",
                        n + 1,
                        path.display(),
                        ys.len()
                    )));
                }
                Some(n) => ys[..=n].to_vec(),
                None => ys,
            }
        }
        None => {
            let n = args.steps.unwrap_or(500);
            if n == 0 {
                return Err(invalid("--steps must be at least 1".into()));
            }
            model.simulate(n, &mut stream_rng(args.seed, u64::MAX)).1
        }
    };
    let model = model.diffuse(ys[0]).map_err(VizError::core("bench"))?;
    let obs: Vec<Option<f64>> = std::iter::once(None)
        .chain(ys[1..].iter().map(|&y| Some(y)))
        .collect();
    let cfg = BatchConfig {
        resampler: args.resampler,
        policy: ResamplePolicy::Always,
        simd: args.simd,
        par: if args.threads == 1 {
            Par::Seq
        } else {
            Par::Rayon
        },
        ..BatchConfig::new(args.particles, args.seed)
    };
    let mut filter = BatchBootstrap::new(model, cfg).map_err(VizError::core("bench"))?;
    let steps = ys.len() - 1;
    let runs = time_runs(args.threads, args.repeat, || {
        filter
            .run(&obs)
            .map(|s| s.log_lik)
            .map_err(VizError::core("bench"))
    })?;
    Ok(BenchResult::new(
        args.particles,
        steps,
        args.threads,
        args.repeat,
        args.simd,
        &runs,
    ))
}

impl BenchResult {
    /// The result of `repeat` timed runs of `particles` particles over `steps` steps on the
    /// kernels of `simd`.
    fn new(
        particles: usize,
        steps: usize,
        threads: usize,
        repeat: usize,
        simd: Simd,
        runs: &Runs,
    ) -> Self {
        BenchResult {
            particles,
            steps,
            threads,
            seconds: runs.seconds,
            ns_per_particle_step: runs.seconds * 1e9 / (particles as f64 * steps as f64),
            loglik: runs.loglik,
            repeat,
            seconds_median: runs.seconds_median,
            kernels: simd.kernels().into(),
        }
    }
}

/// The fastest and the median of `repeat` timed runs, and the last run's log-likelihood.
struct Runs {
    seconds: f64,
    seconds_median: f64,
    loglik: f64,
}

/// Time `repeat` runs of `run` (each a whole filter run from the start, so each computes
/// the same) on a pool of `threads` workers.
fn time_runs(
    threads: usize,
    repeat: usize,
    mut run: impl FnMut() -> Result<f64> + Send,
) -> Result<Runs> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| VizError::Argument {
            message: format!("cannot start {threads} threads: {e}"),
        })?;
    // Grown as the runs finish: a mistyped huge `--repeat` runs until stopped, but never
    // asks for its whole buffer up front.
    let mut times = Vec::new();
    let mut loglik = f64::NAN;
    for _ in 0..repeat {
        let (seconds, ll) = pool.install(|| {
            let start = Instant::now();
            let ll = run();
            (start.elapsed().as_secs_f64(), ll)
        });
        loglik = ll?;
        times.push(seconds);
    }
    times.sort_by(f64::total_cmp);
    Ok(Runs {
        seconds: times[0],
        seconds_median: times[times.len() / 2],
        loglik,
    })
}

/// The JSON contract of `pf-viz bench filter --json`: the model's name and
/// [`BenchResult`]'s keys.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FilterBenchResult {
    /// `ar1`, `radar` or `bearings`.
    pub model: String,
    /// The timing and the estimate.
    #[serde(flatten)]
    pub run: BenchResult,
}

/// Run `pf-viz bench filter`.
///
/// # Errors
/// Bad arguments, unreadable data, or a filter failure.
pub fn filter(args: &BenchFilterArgs) -> Result<FilterBenchResult> {
    let invalid = |message: String| VizError::Argument { message };
    if args.particles == 0 {
        return Err(invalid("--particles must be at least 1".into()));
    }
    crate::error::check_threads("--threads", args.threads)?;
    if args.repeat == 0 {
        return Err(invalid("--repeat must be at least 1".into()));
    }
    if args.steps == Some(0) {
        return Err(invalid("--steps must be at least 1".into()));
    }
    let result = |steps: usize, runs: &Runs| {
        BenchResult::new(
            args.particles,
            steps,
            args.threads,
            args.repeat,
            args.simd,
            runs,
        )
    };
    let (name, run) = match args.model {
        BenchModel::Ar1 => {
            let ar1 = BenchBootstrapArgs {
                data: args.data.clone(),
                particles: args.particles,
                steps: args.steps,
                threads: args.threads,
                resampler: pf_core::resample::Resampler::Systematic,
                seed: args.seed,
                repeat: args.repeat,
                simd: args.simd,
                json: args.json,
            };
            ("ar1", bootstrap(&ar1)?)
        }
        BenchModel::Radar => {
            let mpf = VizError::paper("bench filter radar");
            let mut bench = match &args.data {
                Some(path) => {
                    let mut ys = read_radar(path)?;
                    if let Some(n) = args.steps {
                        if n > ys.len() {
                            return Err(invalid(format!(
                                "--steps {n} needs {n} rows, {} has {}",
                                path.display(),
                                ys.len()
                            )));
                        }
                        ys.truncate(n);
                    }
                    RadarBench::with_observations(ys, args.particles, args.seed).map_err(mpf)?
                }
                None => RadarBench::new(args.particles, args.steps.unwrap_or(100), args.seed)
                    .map_err(mpf)?,
            };
            bench.set_simd(args.simd);
            let steps = bench.observations().len();
            let runs = time_runs(args.threads, args.repeat, || bench.run().map_err(mpf))?;
            ("radar", result(steps, &runs))
        }
        BenchModel::Bearings => {
            if args.data.is_some() {
                return Err(invalid(
                    "--data is for ar1 and radar; bearings simulates Morelande et al.'s scenario"
                        .into(),
                ));
            }
            let hom = VizError::paper("bench filter bearings");
            let steps = args.steps.unwrap_or(40);
            let mut bench = BearingsBench::new(args.particles, steps, args.seed).map_err(hom)?;
            bench.set_simd(args.simd);
            let runs = time_runs(args.threads, args.repeat, || bench.run().map_err(hom))?;
            ("bearings", result(steps, &runs))
        }
    };
    Ok(FilterBenchResult {
        model: name.into(),
        run,
    })
}

/// The JSON of `pf-viz bench genealogy --json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GenealogyBenchResult {
    /// N.
    pub particles: usize,
    /// n: steps after the first.
    pub steps: usize,
    /// Wall-clock seconds of filtering with the tree recorder.
    pub seconds: f64,
    /// Most tree nodes stored at once.
    pub peak_nodes: usize,
    /// Tree nodes stored at the end.
    pub live_nodes: usize,
    /// Bytes per node (parent id, child count, state).
    pub bytes_per_node: usize,
    /// `peak_nodes · bytes_per_node`.
    pub tree_peak_bytes: usize,
    /// What a full ancestor table (`N·(n+1)` indices and states) would take, in bytes.
    pub full_storage_bytes: usize,
    /// The process's peak resident memory (Linux `VmHWM`), when the system reports it.
    pub peak_rss_bytes: Option<u64>,
    /// Steps back from the end at which the living paths coalesce into one (`None`:
    /// not within the run).
    pub coalescence_depth: Option<usize>,
}

/// Run the bootstrap filter on the AR(1)+noise model while keeping every living particle's
/// trajectory in pruned path storage, and measure that storage.
///
/// # Errors
/// N = 0 or n = 0, or a filter failure.
pub fn genealogy(args: &BenchGenealogyArgs) -> Result<GenealogyBenchResult> {
    let invalid = |message: &str| VizError::Argument {
        message: message.into(),
    };
    if args.particles == 0 {
        return Err(invalid("--particles must be at least 1"));
    }
    if args.steps == 0 {
        return Err(invalid("--steps must be at least 1"));
    }
    let core = VizError::core("bench genealogy");
    check_count("--steps", args.steps).map_err(core)?;
    let model = NoisyAr1::new(0.98, 0.2, 1.0).map_err(core)?;
    let (_, ys) = model.simulate(args.steps, &mut stream_rng(args.seed, u64::MAX));
    let obs: Vec<Option<f64>> = ys.into_iter().map(Some).collect();
    let mut pf =
        ParticleFilter::bootstrap(model, FilterConfig::new(args.particles)).map_err(core)?;
    let mut recorder = AncestryRecorder::new();
    let start = Instant::now();
    pf.run(&obs, None, &mut stream_rng(args.seed, 0), &mut recorder)
        .map_err(core)?;
    let seconds = start.elapsed().as_secs_f64();
    let tree = recorder
        .tree()
        .ok_or_else(|| invalid("the filter recorded no step"))?;
    let bytes_per_node = pf_core::ancestry::AncestryTree::<f64>::bytes_per_node();
    let depth = tree.distinct_ancestors(tree.n_steps());
    Ok(GenealogyBenchResult {
        particles: args.particles,
        steps: args.steps,
        seconds,
        peak_nodes: tree.peak_nodes(),
        live_nodes: tree.live_nodes(),
        bytes_per_node,
        tree_peak_bytes: tree.peak_nodes() * bytes_per_node,
        full_storage_bytes: args.particles
            * (args.steps + 1)
            * (std::mem::size_of::<usize>() + std::mem::size_of::<f64>()),
        peak_rss_bytes: peak_rss_bytes(),
        coalescence_depth: depth
            .iter()
            .rposition(|&c| c == 1)
            .map(|k| depth.len() - 1 - k),
    })
}

/// Peak resident set size from `/proc/self/status` (`VmHWM`, in kB), where there is one.
fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}
