//! Cost of one correction, OHF against AOHF (the paper's cost comparison).
#![allow(missing_docs)] // criterion's macros generate undocumented items
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Matrix2, Vector2};
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

criterion_group!(benches, corrections);
criterion_main!(benches);
