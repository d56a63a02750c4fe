//! The components of one particle-step, each in ns per element at N = 10⁶: a standard
//! normal, a shifted exp with its sum, and normalisation. Criterion's "elem/s" inverts to
//! ns per element.
#![allow(missing_docs)] // criterion's macros generate undocumented items

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use pf_core::mc::stream_rng;
use pf_core::weights::normalise;
use rand_distr::{Distribution, StandardNormal};
use std::hint::black_box;

const N: usize = 1_000_000;

fn components(c: &mut Criterion) {
    let mut rng = stream_rng(1, 0);
    let lw: Vec<f64> = (0..N)
        .map(|_| {
            let z: f64 = StandardNormal.sample(&mut rng);
            -0.5 * z * z
        })
        .collect();
    let mut out = vec![0.0; N];
    let mut group = c.benchmark_group("components");
    group.sample_size(20);
    group.throughput(Throughput::Elements(N as u64));
    group.bench_function("standard_normal", |b| {
        b.iter(|| {
            for o in out.iter_mut() {
                *o = StandardNormal.sample(&mut rng);
            }
            black_box(out[N - 1])
        })
    });
    group.bench_function("exp_scalar", |b| {
        b.iter(|| {
            let mut s = 0.0;
            for (o, &l) in out.iter_mut().zip(&lw) {
                *o = (l - 0.1).exp();
                s += *o;
            }
            black_box(s)
        })
    });
    let mut l = lw.clone();
    group.bench_function("normalise", |b| {
        b.iter(|| {
            l.copy_from_slice(&lw);
            black_box(normalise(0, &mut l, &mut out).expect("finite weights"))
        })
    });
    group.finish();
}

criterion_group!(benches, components);
criterion_main!(benches);
