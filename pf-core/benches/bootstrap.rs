//! Bootstrap filter on the noisy AR(1) model (φ = 0.98, σ = 0.2, ρ = 1), 500 steps,
//! systematic resampling every step (and each scheme in `batch_ar1_schemes`). Throughput is
//! in particle-steps, so criterion's "elem/s" inverts to nanoseconds per particle-step.
#![allow(missing_docs)] // criterion's macros generate undocumented items

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use pf_core::filter::{BatchBootstrap, BatchConfig, FilterConfig, ParticleFilter};
use pf_core::mc::Par;
use pf_core::mc::stream_rng;
use pf_core::models::NoisyAr1;
use pf_core::resample::Resampler;
use std::hint::black_box;

const STEPS: usize = 500;

fn bootstrap(c: &mut Criterion) {
    let model = NoisyAr1::new(0.98, 0.2, 1.0).expect("valid parameters");
    let (_, ys) = model.simulate(STEPS - 1, &mut stream_rng(1, 0));
    let ys: Vec<Option<f64>> = ys.into_iter().map(Some).collect();
    let mut group = c.benchmark_group("bootstrap_ar1");
    group.sample_size(10);
    for n in [1_000usize, 10_000, 100_000, 1_000_000] {
        group.throughput(Throughput::Elements((n * STEPS) as u64));
        let mut pf = ParticleFilter::bootstrap(model, FilterConfig::new(n)).expect("valid config");
        let mut rng = stream_rng(2, 0);
        group.bench_with_input(
            BenchmarkId::new("systematic", format!("N={n}")),
            &n,
            |b, _| {
                b.iter(|| {
                    black_box(
                        pf.run(&ys, None, &mut rng, &mut ())
                            .expect("filter runs")
                            .log_lik,
                    )
                })
            },
        );
    }
    group.finish();
}

/// The structure-of-arrays fast path, on one thread and on the current pool (both cores).
fn batch(c: &mut Criterion) {
    let model = NoisyAr1::new(0.98, 0.2, 1.0).expect("valid parameters");
    let (_, ys) = model.simulate(STEPS - 1, &mut stream_rng(1, 0));
    let ys: Vec<Option<f64>> = ys.into_iter().map(Some).collect();
    let mut group = c.benchmark_group("batch_ar1");
    group.sample_size(10);
    for n in [1_000usize, 10_000, 100_000, 1_000_000] {
        group.throughput(Throughput::Elements((n * STEPS) as u64));
        for (name, par) in [("1-thread", Par::Seq), ("rayon", Par::Rayon)] {
            let cfg = BatchConfig {
                par,
                ..BatchConfig::new(n, 2)
            };
            let mut f = BatchBootstrap::new(model, cfg).expect("valid config");
            group.bench_with_input(BenchmarkId::new(name, format!("N={n}")), &n, |b, _| {
                b.iter(|| black_box(f.run(&ys).expect("filter runs").log_lik))
            });
        }
    }
    group.finish();
}

/// N = 10⁷ (80 MB per state array, far beyond the caches), over 20 steps to keep a sample
/// short: is the cost per particle-step flat in N, and what do two threads buy?
fn batch_large(c: &mut Criterion) {
    const LARGE_STEPS: usize = 20;
    const N: usize = 10_000_000;
    let model = NoisyAr1::new(0.98, 0.2, 1.0).expect("valid parameters");
    let (_, ys) = model.simulate(LARGE_STEPS - 1, &mut stream_rng(1, 0));
    let ys: Vec<Option<f64>> = ys.into_iter().map(Some).collect();
    let mut group = c.benchmark_group("batch_ar1_large");
    group.sample_size(10);
    group.throughput(Throughput::Elements((N * LARGE_STEPS) as u64));
    for (name, par) in [("1-thread", Par::Seq), ("rayon", Par::Rayon)] {
        let cfg = BatchConfig {
            par,
            ..BatchConfig::new(N, 2)
        };
        let mut f = BatchBootstrap::new(model, cfg).expect("valid config");
        group.bench_with_input(BenchmarkId::new(name, format!("N={N}")), &N, |b, _| {
            b.iter(|| black_box(f.run(&ys).expect("filter runs").log_lik))
        });
    }
    group.finish();
}

/// Every resampling scheme in the fast path at N = 10⁶, on one thread and on the pool
/// (100 steps): what each scheme costs, and what the second core buys for it.
fn batch_schemes(c: &mut Criterion) {
    const SCHEME_STEPS: usize = 100;
    const N: usize = 1_000_000;
    let model = NoisyAr1::new(0.98, 0.2, 1.0).expect("valid parameters");
    let (_, ys) = model.simulate(SCHEME_STEPS - 1, &mut stream_rng(1, 0));
    let ys: Vec<Option<f64>> = ys.into_iter().map(Some).collect();
    let mut group = c.benchmark_group("batch_ar1_schemes");
    group.sample_size(10);
    group.throughput(Throughput::Elements((N * SCHEME_STEPS) as u64));
    for resampler in Resampler::ALL {
        for (name, par) in [("1-thread", Par::Seq), ("rayon", Par::Rayon)] {
            let cfg = BatchConfig {
                par,
                resampler,
                ..BatchConfig::new(N, 2)
            };
            let mut f = BatchBootstrap::new(model, cfg).expect("valid config");
            let id = BenchmarkId::new(format!("{resampler}/{name}"), format!("N={N}"));
            group.bench_with_input(id, &N, |b, _| {
                b.iter(|| black_box(f.run(&ys).expect("filter runs").log_lik))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bootstrap, batch, batch_large, batch_schemes);
criterion_main!(benches);
