//! The components of one particle-step, each in ns per element at N = 10⁶: a standard
//! normal (rand_distr, and the vectorised lanes), a unit exponential (lanes), a shifted
//! exp with its sum (libm, and the branch-free vectorisable one), and normalisation.
//! Criterion's "elem/s" inverts to ns per element.
#![allow(missing_docs)] // criterion's macros generate undocumented items

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use pf_core::mc::stream_rng;
use pf_core::simd::math::exp_nonpositive;
use pf_core::simd::{LaneRng, Simd};
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
    let mut lanes = LaneRng::from_rng(&mut stream_rng(1, 1));
    for (name, simd) in [
        ("lanes_normal", Simd::Auto),
        ("lanes_normal_avx2", Simd::Avx2),
        ("lanes_normal_portable", Simd::Portable),
    ] {
        group.bench_function(name, |b| {
            b.iter(|| {
                lanes.fill_normal_with(simd, &mut out);
                black_box(out[N - 1])
            })
        });
    }
    group.bench_function("lanes_exp1", |b| {
        b.iter(|| {
            lanes.fill_exp1(&mut out);
            black_box(out[N - 1])
        })
    });
    // The loop auto-vectorises only where the build enables AVX2; this bench is built for
    // baseline x86-64, so it shows the portable (SSE2) speed of the same function.
    group.bench_function("exp_branch_free", |b| {
        b.iter(|| {
            let mut s = 0.0;
            for (o, &l) in out.iter_mut().zip(&lw) {
                *o = exp_nonpositive(l - 0.1);
                s += *o;
            }
            black_box(s)
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
