//! One bootstrap run on Section 5's model (n = 500) on the batch filter: the bare filter,
//! the filter carrying the joint and fixed-lag (δ = 20) estimators, at N = 100 and 1000;
//! the fixed-lag estimator alone at the report's longest lag, δ = 200 (a register of 200
//! columns); and forward-only smoothing at N = 100, whose N² backward weights per step
//! dominate (10 000 per step × 500 steps). Each filter on one thread, as the experiments'
//! replications run them.

#![allow(missing_docs)] // criterion's macros generate undocumented items
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use pf_core::filter::{BatchFilter, FilterConfig};
use pf_core::mc::stream_rng;
use pf_core::models::NoisyAr1;
use pf_smooth::em::{batch_config, paper_filter_config};
use pf_smooth::{Ar1Data, Ar1Statistics, FixedLagTerms, ForwardSmoothing, SmoothedAr1, Theta};

fn bench(c: &mut Criterion) {
    let truth = NoisyAr1::new(0.98, 0.2, 1.0).unwrap();
    let data = Ar1Data::new(truth.simulate(500, &mut stream_rng(1, 0)).1).unwrap();
    let theta = Theta::paper_start();
    let ys = data.filter_input();
    let cfg = |n: usize| -> FilterConfig { paper_filter_config(n) };
    let mut g = c.benchmark_group("smooth n=500");
    for n in [100usize, 1000] {
        g.bench_with_input(BenchmarkId::new("filter only", n), &n, |b, &n| {
            let model = theta.model(data.y()[0]).unwrap();
            let mut pf = BatchFilter::new(model, batch_config(cfg(n), 2)).unwrap();
            b.iter(|| pf.run(&ys).unwrap());
        });
        for delta in [20usize, 200] {
            let name = if delta == 20 {
                "joint + fixed-lag 20"
            } else {
                "fixed-lag 200"
            };
            g.bench_with_input(BenchmarkId::new(name, n), &n, |b, &n| {
                let model = SmoothedAr1::new(&theta, &data, delta).unwrap();
                let mut terms = FixedLagTerms::new(&model, &[delta]).unwrap();
                let mut pf = BatchFilter::new(model, batch_config(cfg(n), 2)).unwrap();
                b.iter(|| {
                    pf.run_observed(None, &ys, &mut terms).unwrap();
                    terms.estimates(&pf.view().unwrap()).unwrap()
                });
            });
        }
    }
    g.sample_size(10);
    g.bench_function(BenchmarkId::new("forward-only", 100), |b| {
        let model = SmoothedAr1::new(&theta, &data, 0).unwrap();
        let mut forward = ForwardSmoothing::new(*model.model(), Ar1Statistics::new(&data));
        let mut pf = BatchFilter::new(model, batch_config(cfg(100), 2)).unwrap();
        b.iter(|| {
            pf.run_observed(None, &ys, &mut forward).unwrap();
            forward.estimate().unwrap()
        });
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
