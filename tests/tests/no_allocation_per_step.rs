//! The filters' steps and the resamplers keep allocation out of their loops: every
//! allocation on this test's thread is counted, through a counting global allocator.
//!
//! - Systematic and stratified resampling need no buffer that depends on the draws: once a
//!   filter has stepped, no later step allocates.
//! - Multinomial and residual resampling keep per-thread buffers sized by random totals
//!   (the Poisson total `T` and the surplus `T − M` removed from it), which can grow when a
//!   total sets a new high. Each growth at least doubles a buffer's capacity, and while
//!   `T < 2M` (it exceeds `M` by about `3√M`) neither asks for more than `4M + 64` slots,
//!   so over any number of steps each grows at most `1 + log₂(4M + 64)` times: far fewer
//!   than one allocation per step, which is what the test rules out (it runs 200 steps).
//!
//! - A state that owns heap memory (a `DVector`) is written into the particles' own
//!   storage, from the second move on.
//! - pf-smooth's joint and fixed-lag estimators on the batch filter keep their sums and
//!   register in the particles' columns and size their buffers at the start; forward-only
//!   smoothing sizes its buffers at the first step.
//!
//! Everything runs on the test's own thread (`Par::Seq`), and only that thread's
//! allocations are counted, so the other tests of this binary cannot disturb the count.

// A global allocator can only be written with `unsafe` (the trait is unsafe to implement);
// this one forwards every call to `System` unchanged.
#![allow(unsafe_code)]

use nalgebra::{DMatrix, DVector};
use pf_core::StateSpaceModel;
use pf_core::filter::{
    BatchBootstrap, BatchConfig, BatchFilter, BatchObserver, FilterConfig, MomentRecorder,
    ParticleFilter,
};
use pf_core::kalman::LinearGaussian;
use pf_core::mc::{Par, stream_rng};
use pf_core::models::NoisyAr1;
use pf_core::observe::Observer;
use pf_core::resample::{Resample, Resampler};
use pf_smooth::{Ar1Data, Ar1Statistics, FixedLagTerms, ForwardSmoothing, SmoothedAr1, Theta};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

/// The system allocator, counting the calls made on threads that asked to be counted.
struct Counting;

thread_local! {
    /// `Some(n)`: this thread is counting, and has allocated `n` times so far.
    static COUNT: Cell<Option<usize>> = const { Cell::new(None) };
}

fn note() {
    // `try_with`: allocations during a thread's teardown find no thread-local.
    let _ = COUNT.try_with(|c| c.set(c.get().map(|n| n + 1)));
}

// SAFETY: every method forwards its arguments unchanged to `System`, which upholds the
// `GlobalAlloc` contract; counting touches only a thread-local `Cell`, never the heap.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note();
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note();
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note();
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// How many times `f` allocates on this thread.
fn allocations(f: impl FnOnce()) -> usize {
    COUNT.with(|c| c.set(Some(0)));
    f();
    COUNT.with(|c| c.replace(None)).expect("counting was on")
}

fn observations(n: usize) -> Vec<Option<f64>> {
    let model = NoisyAr1::new(0.98, 0.2, 1.0).expect("valid parameters");
    let (_, ys) = model.simulate(n - 1, &mut stream_rng(1, 0));
    ys.into_iter().map(Some).collect()
}

/// Steps counted after the warm-up.
const STEPS: usize = 200;

/// The most allocations `STEPS` steps may make with `m` draws per step (see the module
/// docs): none for systematic and stratified resampling, and for multinomial and residual
/// at most `1 + log₂(4m + 64)` growths of each of their two buffers.
fn allowed(resampler: Resampler, m: usize) -> usize {
    match resampler {
        Resampler::Systematic | Resampler::Stratified => 0,
        Resampler::Multinomial | Resampler::Residual => 2 * (1 + (4 * m + 64).ilog2() as usize),
    }
}

/// The batch filter, with every scheme, in one block and split into several (N ≥ 2¹⁵, the
/// multinomial and residual draws in blocks).
#[test]
fn batch_filter_steps_keep_allocation_out() {
    let ys = observations(STEPS + 2);
    let model = NoisyAr1::new(0.98, 0.2, 1.0).expect("valid parameters");
    for n in [3_000usize, 40_000] {
        for resampler in Resampler::ALL {
            let cfg = BatchConfig {
                resampler,
                par: Par::Seq,
                ..BatchConfig::new(n, 3)
            };
            let mut f = BatchBootstrap::new(model, cfg).expect("valid config");
            for y in &ys[..2] {
                f.step(y.as_ref()).expect("step runs");
            }
            let count = allocations(|| {
                for y in &ys[2..] {
                    f.step(y.as_ref()).expect("step runs");
                }
            });
            assert!(
                count <= allowed(resampler, n),
                "N = {n}, {resampler}: {count}"
            );
        }
    }
}

/// The batch filter on a multivariate state (the 2-D linear-Gaussian model: the walk's
/// positions and the column gathers), bootstrap and guided by the model's own transition,
/// with every scheme, recording moments into a recorder made with room for the run.
#[test]
fn multivariate_batch_filter_steps_keep_allocation_out() {
    let lg = pf_core::kalman::LinearGaussian::new(
        nalgebra::DMatrix::from_row_slice(2, 2, &[1.0, 0.5, 0.0, 0.9]),
        None,
        nalgebra::DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
        nalgebra::DMatrix::from_row_slice(2, 2, &[0.1, 0.02, 0.02, 0.2]),
        nalgebra::DMatrix::from_row_slice(1, 1, &[0.5]),
        nalgebra::DVector::from_vec(vec![0.0, 1.0]),
        nalgebra::DMatrix::identity(2, 2),
    )
    .expect("a valid model");
    let model = lg.batch().expect("no inputs");
    let ys: Vec<Option<nalgebra::DVector<f64>>> = observations(STEPS + 2)
        .into_iter()
        .map(|y| y.map(|y| nalgebra::DVector::from_element(1, y)))
        .collect();
    for n in [3_000usize, 40_000] {
        for resampler in Resampler::ALL {
            let cfg = BatchConfig {
                resampler,
                par: Par::Seq,
                ..BatchConfig::new(n, 3)
            };
            let mut f = BatchFilter::new(model.clone(), cfg).expect("valid config");
            let mut rec = MomentRecorder::with_capacity(STEPS + 2, 2);
            rec.on_start(n, 2);
            for y in &ys[..2] {
                f.step(y.as_ref()).expect("step runs");
            }
            let count = allocations(|| {
                for y in &ys[2..] {
                    f.step(y.as_ref()).expect("step runs");
                    rec.on_step(&f.view().expect("a step was made"));
                }
            });
            assert!(
                count <= allowed(resampler, n),
                "N = {n}, {resampler}, 2-D: {count}"
            );
            assert_eq!(rec.t.len(), STEPS);
        }
    }
}

/// The allocations of the generic filter's steps over `ys[2..]`, after two steps (the first
/// draws the particles, the second makes room for the moves) that are not counted.
fn allocations_after_two_steps<M: StateSpaceModel>(
    mut pf: ParticleFilter<M>,
    ys: &[Option<M::Obs>],
) -> usize {
    let mut rng = stream_rng(4, 0);
    for y in &ys[..2] {
        pf.step(None, y.as_ref(), &mut rng).expect("step runs");
    }
    allocations(|| {
        for y in &ys[2..] {
            pf.step(None, y.as_ref(), &mut rng).expect("step runs");
        }
    })
}

/// The generic filter with a scalar state, every scheme.
#[test]
fn generic_filter_steps_keep_allocation_out() {
    let ys = observations(STEPS + 2);
    let model = NoisyAr1::new(0.98, 0.2, 1.0).expect("valid parameters");
    for resampler in Resampler::ALL {
        let cfg = FilterConfig {
            resampler,
            ..FilterConfig::new(2_000)
        };
        let pf = ParticleFilter::bootstrap(model, cfg).expect("valid config");
        let count = allocations_after_two_steps(pf, &ys);
        assert!(count <= allowed(resampler, 2_000), "{resampler}: {count}");
    }
}

/// The generic filter with a state that owns heap memory (`DVector`, a constant-velocity
/// model): each step writes into the particles' own storage and the densities use
/// per-thread scratch vectors, so a step allocates no more than with a scalar state.
#[test]
fn generic_filter_with_vector_states_keeps_allocation_out() {
    let model = LinearGaussian::new(
        DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 0.0, 1.0]),
        None,
        DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
        DMatrix::from_row_slice(2, 2, &[0.02, 0.01, 0.01, 0.02]),
        DMatrix::from_element(1, 1, 1.0),
        DVector::zeros(2),
        DMatrix::identity(2, 2),
    )
    .expect("valid model");
    let ys: Vec<Option<DVector<f64>>> = (0..STEPS + 2)
        .map(|k| Some(DVector::from_element(1, 0.3 * k as f64)))
        .collect();
    for resampler in Resampler::ALL {
        let cfg = FilterConfig {
            resampler,
            ..FilterConfig::new(500)
        };
        let pf = ParticleFilter::bootstrap(model.clone(), cfg).expect("valid config");
        let count = allocations_after_two_steps(pf, &ys);
        assert!(count <= allowed(resampler, 500), "{resampler}: {count}");
    }
}

/// The smoothers of pf-smooth: the joint (path-space) and fixed-lag estimators on the batch
/// filter (their sums and register are the model's columns, the frozen terms' buffers are
/// sized in `on_start`), and forward-only smoothing on the generic filter (its buffers
/// sized at the first step).
#[test]
fn smoothers_keep_allocation_out() {
    let ys = observations(STEPS + 2);
    let y: Vec<f64> = ys.iter().map(|y| y.expect("observed")).collect();
    let data = Ar1Data::from_slice(&y).expect("valid data");
    let stats = Ar1Statistics::new(&data);
    let theta = Theta::paper_start();
    let model = theta.model(y[0]).expect("valid model");
    let mut pf = ParticleFilter::bootstrap(model, FilterConfig::new(300)).expect("valid config");
    // Forward-only smoothing on one thread (on the pool it takes scratch rows per task).
    let mut forward = ForwardSmoothing::new(model, stats);
    let smoothed = SmoothedAr1::new(&theta, &data, 50).expect("valid model");
    let mut lags = FixedLagTerms::new(&smoothed, &[1, 7, 50]).expect("valid lags");
    let cfg = BatchConfig {
        par: Par::Seq,
        ..BatchConfig::new(300, 7)
    };
    let mut bf = BatchFilter::new(smoothed, cfg).expect("valid config");
    lags.on_start(300, bf.dim());
    let mut rng = stream_rng(7, 0);
    let mut step =
        |pf: &mut ParticleFilter<_>, bf: &mut BatchFilter<SmoothedAr1<'_>>, y: &Option<f64>| {
            pf.step(None, y.as_ref(), &mut rng).expect("step runs");
            Observer::on_step(&mut forward, &pf.view().expect("a step was made"));
            bf.step(y.as_ref()).expect("step runs");
            lags.on_step(&bf.view().expect("a step was made"));
        };
    for y in &ys[..2] {
        step(&mut pf, &mut bf, y);
    }
    let count = allocations(|| {
        for y in &ys[2..] {
            step(&mut pf, &mut bf, y);
        }
    });
    assert_eq!(count, 0);
}

/// Each resampler, called again and again on the same weights.
#[test]
fn resamplers_keep_allocation_out() {
    let raw: Vec<f64> = (0..5_000)
        .map(|i| ((i * 7919) % 101) as f64 + 0.5)
        .collect();
    let total: f64 = raw.iter().sum();
    let w: Vec<f64> = raw.iter().map(|x| x / total).collect();
    let mut out = vec![0usize; w.len()];
    let mut rng = stream_rng(5, 0);
    for resampler in Resampler::ALL {
        resampler.resample(&w, &mut rng, &mut out);
        let count = allocations(|| {
            for _ in 0..STEPS {
                resampler.resample(&w, &mut rng, &mut out);
            }
        });
        assert!(count <= allowed(resampler, w.len()), "{resampler}: {count}");
    }
}
