//! The components of one particle-step, each in ns per element at N = 10⁶: a standard
//! normal (rand_distr, and the vectorised lanes), a unit exponential (lanes), a shifted
//! exp with its sum (libm, and the branch-free vectorisable one), and normalisation; and
//! `pf_core::simd::special`'s functions against std's, in loops compiled for AVX2.
//! Criterion's "elem/s" inverts to ns per element.
#![allow(missing_docs)] // criterion's macros generate undocumented items

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use pf_core::mc::stream_rng;
use pf_core::simd::math::exp_nonpositive;
use pf_core::simd::special;
use pf_core::simd::{LaneRng, Simd};
use pf_core::weights::normalise;
use rand::RngExt;
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

/// A loop of `f` over `N_SPECIAL` arguments (one or two slices), compiled for AVX2 and FMA
/// as the batch filter's model calls are, or for baseline x86-64.
macro_rules! special_loops {
    ($($name:ident: |$a:ident, $b:ident| $body:expr;)*) => {
        $(
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2,fma")]
            fn $name(xs: &[f64], ys: &[f64], out: &mut [f64]) {
                for ((o, &$a), &$b) in out.iter_mut().zip(xs).zip(ys) {
                    *o = $body;
                }
            }
        )*
    };
}

special_loops! {
    loop_exp: |x, _y| special::exp(x);
    loop_std_exp: |x, _y| x.exp();
    loop_ln: |x, _y| special::ln(x);
    loop_std_ln: |x, _y| x.ln();
    loop_atan2: |x, y| special::atan2(y, x);
    loop_std_atan2: |x, y| y.atan2(x);
    loop_hypot: |x, y| special::hypot(x, y);
    loop_std_hypot: |x, y| x.hypot(y);
}

type SpecialLoop = unsafe fn(&[f64], &[f64], &mut [f64]);

/// `pf_core::simd::special` against std (glibc's libm) on 4096 arguments in L1, each loop
/// compiled for AVX2 and FMA (the bench skips itself on a CPU without them): `x` in
/// [−20, 20] for exp, (0, 10⁴] for ln, `(x, y)` in a ±10⁴ m square for atan2 and hypot (the
/// bearings-only model's range). The ratio of each pair's times is the speed-up the
/// functions' docs state.
#[cfg(target_arch = "x86_64")]
fn special_functions(c: &mut Criterion) {
    if !(std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma"))
    {
        return;
    }
    const N_SPECIAL: usize = 4096;
    let mut rng = stream_rng(1, 2);
    let mut uniform = |lo: f64, hi: f64| -> Vec<f64> {
        (0..N_SPECIAL)
            .map(|_| lo + (hi - lo) * rng.random::<f64>())
            .collect()
    };
    let (e, l, px, py) = (
        uniform(-20.0, 20.0),
        uniform(1e-9, 1e4),
        uniform(-1e4, 1e4),
        uniform(-1e4, 1e4),
    );
    let mut out = vec![0.0; N_SPECIAL];
    let mut group = c.benchmark_group("special");
    group.throughput(Throughput::Elements(N_SPECIAL as u64));
    let cases: [(&str, SpecialLoop, &[f64], &[f64]); 8] = [
        ("exp", loop_exp, &e, &e),
        ("exp_std", loop_std_exp, &e, &e),
        ("ln", loop_ln, &l, &l),
        ("ln_std", loop_std_ln, &l, &l),
        ("atan2", loop_atan2, &px, &py),
        ("atan2_std", loop_std_atan2, &px, &py),
        ("hypot", loop_hypot, &px, &py),
        ("hypot_std", loop_std_hypot, &px, &py),
    ];
    for (name, f, xs, ys) in cases {
        group.bench_function(name, |b| {
            b.iter(|| {
                // SAFETY: the loops are compiled for AVX2 and FMA, which this CPU has
                // (checked at the top).
                #[allow(unsafe_code)]
                unsafe {
                    f(black_box(xs), ys, &mut out)
                };
                black_box(out[N_SPECIAL - 1])
            })
        });
    }
    group.finish();
}

#[cfg(not(target_arch = "x86_64"))]
fn special_functions(_: &mut Criterion) {}

criterion_group!(benches, components, special_functions);
criterion_main!(benches);
