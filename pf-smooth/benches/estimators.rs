//! One bootstrap run on Section 5's model (n = 500) with the joint and the fixed-lag
//! estimators attached, against the bare filter, at N = 100 and 1000; and the fixed-lag
//! estimator alone at the report's longest lag, δ = 200; and forward-only smoothing at
//! N = 100, whose N² backward weights per step dominate (10 000 per step × 500 steps).

#![allow(missing_docs)] // criterion's macros generate undocumented items
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use pf_core::filter::ParticleFilter;
use pf_core::mc::stream_rng;
use pf_core::models::NoisyAr1;
use pf_smooth::em::paper_filter_config;
use pf_smooth::{Ar1Data, Ar1Statistics, FixedLag, ForwardSmoothing, PathSpace, Theta};

fn bench(c: &mut Criterion) {
    let truth = NoisyAr1::new(0.98, 0.2, 1.0).unwrap();
    let data = Ar1Data::new(truth.simulate(500, &mut stream_rng(1, 0)).1).unwrap();
    let theta = Theta::paper_start();
    let ys = data.filter_input();
    let stats = Ar1Statistics::new(&data);
    let mut g = c.benchmark_group("smooth n=500");
    for n in [100usize, 1000] {
        let model = theta.model(data.y()[0]).unwrap();
        g.bench_with_input(BenchmarkId::new("filter only", n), &n, |b, &n| {
            let mut pf = ParticleFilter::bootstrap(model, paper_filter_config(n)).unwrap();
            let mut rng = stream_rng(2, 0);
            b.iter(|| pf.run(&ys, None, &mut rng, &mut ()).unwrap());
        });
        g.bench_with_input(BenchmarkId::new("joint + fixed-lag 20", n), &n, |b, &n| {
            let mut pf = ParticleFilter::bootstrap(model, paper_filter_config(n)).unwrap();
            let mut rng = stream_rng(2, 0);
            let mut joint = PathSpace::new(stats);
            let mut lag = FixedLag::new(stats, 20).unwrap();
            b.iter(|| {
                pf.run(&ys, None, &mut rng, &mut (&mut joint, &mut lag))
                    .unwrap();
                joint.estimate().unwrap()
            });
        });
        g.bench_with_input(BenchmarkId::new("fixed-lag 200", n), &n, |b, &n| {
            let mut pf = ParticleFilter::bootstrap(model, paper_filter_config(n)).unwrap();
            let mut rng = stream_rng(2, 0);
            let mut lag = FixedLag::new(stats, 200).unwrap();
            b.iter(|| {
                pf.run(&ys, None, &mut rng, &mut lag).unwrap();
                lag.estimate().unwrap()
            });
        });
    }
    let model = theta.model(data.y()[0]).unwrap();
    g.sample_size(10);
    g.bench_function(BenchmarkId::new("forward-only", 100), |b| {
        let mut pf = ParticleFilter::bootstrap(model, paper_filter_config(100)).unwrap();
        let mut rng = stream_rng(2, 0);
        let mut forward = ForwardSmoothing::new(model, stats);
        b.iter(|| {
            pf.run(&ys, None, &mut rng, &mut forward).unwrap();
            forward.estimate().unwrap()
        });
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
