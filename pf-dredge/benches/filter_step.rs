//! Time per on-line filter step against N, for the on-board time budget.
#![allow(missing_docs)] // criterion_group! generates an undocumented function

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use pf_core::mc::stream_rng;
use pf_dredge::estimator::{EstimatorConfig, OnlineEstimator};
use pf_dredge::simulator::{SimConfig, simulate};

fn bench(c: &mut Criterion) {
    let data = simulate(&SimConfig::default(), &mut stream_rng(1, 0))
        .expect("default cycle")
        .to_data();
    let mut g = c.benchmark_group("dredge_step");
    for n in [100usize, 1000, 10_000] {
        g.bench_with_input(
            BenchmarkId::from_parameter(format!("N={n}")),
            &n,
            |b, &n| {
                let cfg = EstimatorConfig::default().with_particles(n);
                let mut est = OnlineEstimator::new(&cfg).expect("valid config");
                let mut rng = stream_rng(0, 0);
                let mut k = 0;
                b.iter(|| {
                    if k == data.len() {
                        est = OnlineEstimator::new(&cfg).expect("valid config");
                        k = 0;
                    }
                    let e = est.push(&data.sample(k), &mut rng).expect("step");
                    k += 1;
                    e
                });
            },
        );
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
