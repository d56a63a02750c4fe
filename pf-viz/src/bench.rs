//! `pf-viz bench bootstrap`: the speed of the AR(1)+noise bootstrap filter on this machine.
//!
//! The filter is pf-core's structure-of-arrays fast path ([`BatchBootstrap`]): φ = 0.98,
//! σ = 0.2, ρ = 1, resampling at every step, Cappé & Moulines' diffuse prior N(Y_0, ρ²), so
//! `loglik` estimates log p(Y_1…Y_n | Y_0). Only filtering is timed: not simulation, not I/O.

use std::time::Instant;

use pf_core::filter::{BatchBootstrap, BatchConfig, ResamplePolicy};
use pf_core::mc::{Par, stream_rng};
use pf_core::models::NoisyAr1;
use serde::{Deserialize, Serialize};

use crate::cli::BenchBootstrapArgs;
use crate::data::read_y;
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
    /// Wall-clock seconds of filtering.
    pub seconds: f64,
    /// `seconds / (N·n)` in nanoseconds.
    pub ns_per_particle_step: f64,
    /// Estimate of log p(Y_1…Y_n | Y_0).
    pub loglik: f64,
}

/// Run the benchmark.
///
/// # Errors
/// Bad arguments (N = 0, n = 0, T = 0, more steps than data), unreadable data, or a filter
/// failure.
pub fn bootstrap(args: &BenchBootstrapArgs) -> Result<BenchResult> {
    let invalid = |message: String| VizError::Argument { message };
    if args.particles == 0 {
        return Err(invalid("--particles must be at least 1".into()));
    }
    if args.threads == 0 {
        return Err(invalid("--threads must be at least 1".into()));
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
        par: if args.threads == 1 {
            Par::Seq
        } else {
            Par::Rayon
        },
        ..BatchConfig::new(args.particles, args.seed)
    };
    let mut filter = BatchBootstrap::new(model, cfg).map_err(VizError::core("bench"))?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads)
        .build()
        .map_err(|e| invalid(format!("cannot start {} threads: {e}", args.threads)))?;
    let (seconds, run) = pool.install(|| {
        let start = Instant::now();
        let run = filter.run(&obs);
        (start.elapsed().as_secs_f64(), run)
    });
    let run = run.map_err(VizError::core("bench"))?;
    let steps = ys.len() - 1;
    Ok(BenchResult {
        particles: args.particles,
        steps,
        threads: args.threads,
        seconds,
        ns_per_particle_step: seconds * 1e9 / (args.particles as f64 * steps as f64),
        loglik: run.log_lik,
    })
}
