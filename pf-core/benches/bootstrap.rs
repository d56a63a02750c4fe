//! Bootstrap filter on the noisy AR(1) model (φ = 0.98, σ = 0.2, ρ = 1), 500 steps,
//! systematic resampling every step (and each scheme in `batch_ar1_schemes`). Throughput is
//! in particle-steps, so criterion's "elem/s" inverts to nanoseconds per particle-step.
#![allow(missing_docs)] // criterion's macros generate undocumented items

use criterion::measurement::WallTime;
use criterion::{
    BenchmarkGroup, BenchmarkId, Criterion, Throughput, criterion_group, criterion_main,
};
use nalgebra::{DMatrix, DVector};
use pf_core::StateSpaceModel;
use pf_core::filter::{BatchBootstrap, BatchConfig, BatchFilter, FilterConfig, ParticleFilter};
use pf_core::kalman::LinearGaussian;
use pf_core::mc::Par;
use pf_core::mc::stream_rng;
use pf_core::models::NoisyAr1;
use pf_core::resample::Resampler;
use pf_core::simd::Simd;
use std::hint::black_box;

const STEPS: usize = 500;

/// The model and `steps` observations simulated from seed 1, as every group uses them.
fn ar1_case(steps: usize) -> (NoisyAr1, Vec<Option<f64>>) {
    let model = NoisyAr1::new(0.98, 0.2, 1.0).expect("valid parameters");
    let (_, ys) = model.simulate(steps - 1, &mut stream_rng(1, 0));
    (model, ys.into_iter().map(Some).collect())
}

/// The fast path with `cfg` over `ys`, on one thread (`1-thread`) and on the current pool
/// (`rayon`, both cores), under the ids `id(name)`.
fn bench_batch(
    group: &mut BenchmarkGroup<'_, WallTime>,
    id: impl Fn(&str) -> BenchmarkId,
    model: NoisyAr1,
    cfg: BatchConfig,
    ys: &[Option<f64>],
) {
    for (name, par) in [("1-thread", Par::Seq), ("rayon", Par::Rayon)] {
        let mut f = BatchBootstrap::new(model, BatchConfig { par, ..cfg }).expect("valid config");
        group.bench_function(id(name), |b| {
            b.iter(|| black_box(f.run(ys).expect("filter runs").log_lik))
        });
    }
}

/// The generic filter with `n` particles and systematic resampling over `ys`, under the id
/// `systematic/N=n`.
fn bench_generic<M: StateSpaceModel>(
    group: &mut BenchmarkGroup<'_, WallTime>,
    model: M,
    n: usize,
    ys: &[Option<M::Obs>],
) {
    group.throughput(Throughput::Elements((n * ys.len()) as u64));
    let mut pf = ParticleFilter::bootstrap(model, FilterConfig::new(n)).expect("valid config");
    let mut rng = stream_rng(2, 0);
    group.bench_function(BenchmarkId::new("systematic", format!("N={n}")), |b| {
        b.iter(|| {
            black_box(
                pf.run(ys, None, &mut rng, &mut ())
                    .expect("filter runs")
                    .log_lik,
            )
        })
    });
}

fn bootstrap(c: &mut Criterion) {
    let (model, ys) = ar1_case(STEPS);
    let mut group = c.benchmark_group("bootstrap_ar1");
    group.sample_size(10);
    for n in [1_000usize, 10_000, 100_000, 1_000_000] {
        bench_generic(&mut group, model, n, &ys);
    }
    group.finish();
}

/// The structure-of-arrays fast path, on one thread and on the current pool (both cores).
///
/// Fifty samples where a run of the filter takes 15 ms or less (N ≤ 10⁴), ten above: on a
/// shared VM about one sample in five is slowed by other work, and the median of fifty
/// stays with the rest (docs/performance.md, "How it is measured").
fn batch(c: &mut Criterion) {
    let (model, ys) = ar1_case(STEPS);
    let mut group = c.benchmark_group("batch_ar1");
    for n in [1_000usize, 10_000, 100_000, 1_000_000] {
        group.sample_size(if n <= 10_000 { 50 } else { 10 });
        group.throughput(Throughput::Elements((n * STEPS) as u64));
        let id = |name: &str| BenchmarkId::new(name, format!("N={n}"));
        bench_batch(&mut group, id, model, BatchConfig::new(n, 2), &ys);
    }
    group.finish();
}

/// The fast path at N = 10⁴ on one thread, capped at the AVX2 copy and at the portable
/// copy of its kernels: what a CPU without AVX-512 (or without AVX2 and FMA) pays, with
/// systematic resampling and, on the AVX2 copy, with multinomial resampling (its Poisson
/// counts). All copies give the same bits.
fn batch_kernels(c: &mut Criterion) {
    const N: usize = 10_000;
    let (model, ys) = ar1_case(STEPS);
    let mut group = c.benchmark_group("batch_ar1_kernels");
    group.sample_size(10);
    group.throughput(Throughput::Elements((N * STEPS) as u64));
    for (name, simd, resampler) in [
        ("avx2", Simd::Avx2, Resampler::Systematic),
        ("portable", Simd::Portable, Resampler::Systematic),
        ("multinomial/avx2", Simd::Avx2, Resampler::Multinomial),
    ] {
        let cfg = BatchConfig {
            par: Par::Seq,
            simd,
            resampler,
            ..BatchConfig::new(N, 2)
        };
        let mut f = BatchBootstrap::new(model, cfg).expect("valid config");
        group.bench_function(BenchmarkId::new(name, format!("N={N}")), |b| {
            b.iter(|| black_box(f.run(&ys).expect("filter runs").log_lik))
        });
    }
    group.finish();
}

/// N = 10⁷ (80 MB per state array, far beyond the caches), over 20 steps to keep a sample
/// short: is the cost per particle-step flat in N, and what do two threads buy?
fn batch_large(c: &mut Criterion) {
    const LARGE_STEPS: usize = 20;
    const N: usize = 10_000_000;
    let (model, ys) = ar1_case(LARGE_STEPS);
    let mut group = c.benchmark_group("batch_ar1_large");
    group.sample_size(10);
    group.throughput(Throughput::Elements((N * LARGE_STEPS) as u64));
    let id = |name: &str| BenchmarkId::new(name, format!("N={N}"));
    bench_batch(&mut group, id, model, BatchConfig::new(N, 2), &ys);
    group.finish();
}

/// Every resampling scheme in the fast path at N = 10⁶, on one thread and on the pool
/// (100 steps): what each scheme costs, and what the second core buys for it.
fn batch_schemes(c: &mut Criterion) {
    const SCHEME_STEPS: usize = 100;
    const N: usize = 1_000_000;
    let (model, ys) = ar1_case(SCHEME_STEPS);
    let mut group = c.benchmark_group("batch_ar1_schemes");
    group.sample_size(10);
    group.throughput(Throughput::Elements((N * SCHEME_STEPS) as u64));
    for resampler in Resampler::ALL {
        let id = |name: &str| BenchmarkId::new(format!("{resampler}/{name}"), format!("N={N}"));
        let cfg = BatchConfig {
            resampler,
            ..BatchConfig::new(N, 2)
        };
        bench_batch(&mut group, id, model, cfg, &ys);
    }
    group.finish();
}

/// The generic filter with a heap-allocated state: a constant-velocity model (position and
/// velocity, `nalgebra::DVector`) observed in position, 100 steps. What a model written
/// with dynamic vectors pays per particle-step.
fn linear_gaussian(c: &mut Criterion) {
    const LG_STEPS: usize = 100;
    let model = LinearGaussian::new(
        DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 0.0, 1.0]),
        None,
        DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
        DMatrix::from_row_slice(2, 2, &[0.25, 0.5, 0.5, 1.0]) * 0.01
            + DMatrix::identity(2, 2) * 1e-4,
        DMatrix::from_element(1, 1, 1.0),
        DVector::zeros(2),
        DMatrix::identity(2, 2),
    )
    .expect("valid model");
    let ys: Vec<Option<DVector<f64>>> = (0..LG_STEPS)
        .map(|k| Some(DVector::from_element(1, 0.3 * k as f64)))
        .collect();
    let mut group = c.benchmark_group("bootstrap_linear_gaussian");
    group.sample_size(10);
    for n in [1_000usize, 10_000] {
        bench_generic(&mut group, model.clone(), n, &ys);
    }
    group.finish();
    // The same model on the batch engine (`LinearGaussian::batch`), one thread and the pool.
    let batch = model.batch().expect("no inputs");
    let mut group = c.benchmark_group("batch_linear_gaussian");
    group.sample_size(10);
    for n in [1_000usize, 10_000, 100_000, 1_000_000] {
        group.throughput(Throughput::Elements((n * ys.len()) as u64));
        for par in [Par::Seq, Par::Rayon] {
            let cfg = BatchConfig {
                par,
                ..BatchConfig::new(n, 2)
            };
            let mut f = BatchFilter::new(batch.clone(), cfg).expect("valid config");
            let name = if par == Par::Seq {
                "one_thread"
            } else {
                "pool"
            };
            group.bench_function(BenchmarkId::new(name, format!("N={n}")), |b| {
                b.iter(|| black_box(f.run(&ys).expect("filter runs").log_lik))
            });
        }
    }
    group.finish();
}

criterion_group!(
    benches,
    bootstrap,
    batch,
    batch_kernels,
    batch_large,
    batch_schemes,
    linear_gaussian
);
criterion_main!(benches);
