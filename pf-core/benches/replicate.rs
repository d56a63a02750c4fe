//! Monte Carlo replications on one and on two threads, beside the machine's own two-thread
//! scaling for independent CPU-bound work (the ceiling: on a VM the two vCPUs may share a
//! physical core).
//!
//! - `baseline`: 64 independent tasks, each drawing 2·10⁵ random numbers and summing them.
//! - `replicate`: 64 replications of a bootstrap filter (noisy AR(1), N = 1000, 200 steps)
//!   through [`pf_core::mc::replicate`].
//!
//! Scaling = time on 1 thread / time on 2 threads; the target is replication scaling ≥ 90 %
//! of the baseline's. Each group's "1-thread" and "2-threads" entries give both.
#![allow(missing_docs)] // criterion's macros generate undocumented items

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use pf_core::filter::{FilterConfig, ParticleFilter};
use pf_core::mc::{Par, replicate, stream_rng};
use pf_core::models::NoisyAr1;
use rand::Rng;
use std::hint::black_box;

const TASKS: usize = 64;

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
}

fn scaling(c: &mut Criterion) {
    let model = NoisyAr1::new(0.98, 0.2, 1.0).expect("valid parameters");
    let (_, ys) = model.simulate(199, &mut stream_rng(1, 0));
    let ys: Vec<Option<f64>> = ys.into_iter().map(Some).collect();
    let mut group = c.benchmark_group("mc_scaling");
    group.sample_size(10);
    for threads in [1usize, 2] {
        let p = pool(threads);
        group.bench_function(
            BenchmarkId::new("baseline", format!("{threads}-threads")),
            |b| {
                b.iter(|| {
                    p.install(|| {
                        black_box(replicate(3, TASKS, Par::Rayon, |_, rng| {
                            (0..200_000).fold(0u64, |a, _| a.wrapping_add(rng.next_u64()))
                        }))
                    })
                })
            },
        );
        group.bench_function(
            BenchmarkId::new("replicate", format!("{threads}-threads")),
            |b| {
                b.iter(|| {
                    p.install(|| {
                        black_box(replicate(3, TASKS, Par::Rayon, |_, rng| {
                            let mut pf = ParticleFilter::bootstrap(model, FilterConfig::new(1000))
                                .expect("valid config");
                            pf.run(&ys, None, rng, &mut ())
                                .expect("filter runs")
                                .log_lik
                        }))
                    })
                })
            },
        );
    }
    group.finish();
}

criterion_group!(benches, scaling);
criterion_main!(benches);
