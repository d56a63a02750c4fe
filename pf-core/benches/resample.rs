//! Each resampling scheme on skewed weights, at N = 10⁴ … 10⁷: the target is at
//! N = 10⁶, and a flat cost per particle across N shows the schemes are O(N). Throughput in
//! particles.
#![allow(missing_docs)] // criterion's macros generate undocumented items

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use pf_core::mc::stream_rng;
use pf_core::resample::{Resample, Resampler};
use rand::RngExt;
use std::hint::black_box;

fn resample(c: &mut Criterion) {
    let mut rng = stream_rng(3, 0);
    let mut group = c.benchmark_group("resample");
    for n in [10_000usize, 100_000, 1_000_000, 10_000_000] {
        // Fifty samples where a call takes a few milliseconds or less (N ≤ 10⁶), ten above:
        // as for the filter at N ≤ 10⁴, the median of fifty stays with the undisturbed
        // samples on a shared VM (docs/performance.md, "How it is measured").
        group.sample_size(if n <= 1_000_000 { 50 } else { 10 });
        let raw: Vec<f64> = (0..n).map(|_| rng.random::<f64>().powi(4)).collect();
        let total: f64 = raw.iter().sum();
        let w: Vec<f64> = raw.iter().map(|x| x / total).collect();
        let mut ancestors = vec![0usize; n];
        group.throughput(Throughput::Elements(n as u64));
        for scheme in Resampler::ALL {
            group.bench_with_input(
                BenchmarkId::new(scheme.name(), format!("N={n}")),
                &scheme,
                |b, s| {
                    b.iter(|| {
                        s.resample(&w, &mut rng, &mut ancestors);
                        black_box(ancestors[n / 2])
                    })
                },
            );
        }
    }
    group.finish();
}

criterion_group!(benches, resample);
criterion_main!(benches);
