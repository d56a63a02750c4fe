//! Cost of one correction, OHF against AOHF (the paper's cost comparison), and of the PF
//! with the linearised optimal proposal over one realisation.
#![allow(missing_docs)] // criterion's macros generate undocumented items
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Matrix2, Vector2};
use pf_core::mc::stream_rng;
use pf_homotopy::filters::pf;
use pf_homotopy::model::ScenarioConfig;
use pf_homotopy::ohf::{OhfConfig, OhfWorkspace, correct};
use pf_homotopy::param::Gaussian;
use pf_homotopy::quadrature::{PolarGrid, PolarGridConfig};

fn corrections(c: &mut Criterion) {
    let prior = Gaussian::new(
        Vector2::new(3500.0, 3500.0),
        Matrix2::new(1e6, 9e5, 9e5, 1e6),
    );
    let quad = PolarGrid::new(PolarGridConfig::default(), [0.0, 0.0], 0.87, 0.0175);
    for (name, cfg) in [("ohf", OhfConfig::ohf()), ("aohf", OhfConfig::aohf())] {
        let lambdas = cfg.lambda.nodes();
        let mut ws = OhfWorkspace::new();
        c.bench_function(&format!("correction/{name}"), |b| {
            b.iter(|| {
                correct(
                    &prior,
                    &quad,
                    cfg.scheme,
                    &lambdas,
                    cfg.max_halvings,
                    1,
                    &mut ws,
                    |_, _| {},
                )
            })
        });
    }
}

/// The PF of Section 4 over the default scenario's realisation from seed 1 (its 40
/// bearings, means included) on the batch filter, N = 10³, 10⁴, 10⁵ and 10⁶.
fn particle_filter(c: &mut Criterion) {
    let sc = ScenarioConfig::default();
    let real = sc.simulate(&mut stream_rng(1, 0)).expect("valid scenario");
    let mut group = c.benchmark_group("pf");
    group.sample_size(10);
    for n in [1000, 10_000, 100_000, 1_000_000] {
        group.bench_function(format!("N={n}"), |b| {
            b.iter(|| pf::run(&sc, n, &real, 2).expect("filter runs"))
        });
    }
    group.finish();
}

criterion_group!(benches, corrections, particle_filter);
criterion_main!(benches);
