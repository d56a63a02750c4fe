//! The particle filter against exact Kalman answers on linear-Gaussian models.
//!
//! Bounds come from the replications themselves: with R independent runs, a Monte Carlo
//! average has standard error σ̂/√R, and a correct filter lands within z standard errors of
//! the exact value. z is chosen by a Bonferroni bound over every comparison a test makes, so
//! a correct implementation fails a test with probability below about 1e-4.

use nalgebra::{DMatrix, DVector};
use pf_core::filter::{
    BatchBootstrap, BatchConfig, EssThreshold, FilterConfig, ParticleFilter, ResamplePolicy,
};
use pf_core::kalman::{LinearGaussian, kalman_filter};
use pf_core::mc::{Par, mean_and_se, replicate, stream_rng};
use pf_core::models::NoisyAr1;
use pf_core::observe::EstimateRecorder;
use pf_core::resample::Resampler;

/// A 2-D constant-velocity-like state observed through its first coordinate.
fn tracking_model() -> LinearGaussian {
    LinearGaussian::new(
        DMatrix::from_row_slice(2, 2, &[1.0, 0.5, 0.0, 0.9]),
        None,
        DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
        DMatrix::from_row_slice(2, 2, &[0.1, 0.02, 0.02, 0.2]),
        DMatrix::from_row_slice(1, 1, &[0.5]),
        DVector::from_vec(vec![0.0, 1.0]),
        DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 1.0]),
    )
    .expect("a valid model")
}

/// Two-sided normal quantile for a family-wise error of 1e-4 over `m` comparisons,
/// from the Gaussian tail bound P(|Z| > z) ≤ 2φ(z)/z (solved by bisection).
fn bonferroni_z(m: usize) -> f64 {
    let target = 1e-4 / m as f64;
    let tail = |z: f64| 2.0 * (-0.5 * z * z).exp() / (z * (2.0 * std::f64::consts::PI).sqrt());
    let (mut lo, mut hi) = (1.0, 10.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if tail(mid) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// `Ẑ` is unbiased for `Z` (Del Moral 2004), so `Ẑ/Z = exp(log Ẑ − log Z)` averages to 1.
#[test]
fn likelihood_estimate_is_unbiased_and_filter_means_match_the_kalman_filter() {
    let model = tracking_model();
    let n = 25;
    let (_, ys) = model.simulate(n, None, &mut stream_rng(100, 0)).unwrap();
    let mut ys: Vec<Option<DVector<f64>>> = ys.into_iter().map(Some).collect();
    ys[7] = None; // a missing observation on the way
    let exact = kalman_filter(&model, &ys, None).unwrap();

    let reps = 200;
    let runs = replicate(1, reps, Par::Rayon, |_, rng| {
        let mut pf = ParticleFilter::bootstrap(model.clone(), FilterConfig::new(1000)).unwrap();
        let mut est = EstimateRecorder::new();
        let s = pf.run(&ys, None, rng, &mut est).unwrap();
        (s.log_lik, est.means)
    });

    let ratio: Vec<f64> = runs
        .iter()
        .map(|(l, _)| (l - exact.log_likelihood).exp())
        .collect();
    let z = bonferroni_z(1 + 2 * (n + 1));
    let (m, se) = mean_and_se(&ratio);
    assert!((m - 1.0).abs() < z * se, "E[Ẑ/Z] = {m} ± {se}");

    // Filter means, step by step and coordinate by coordinate. The PF mean carries an O(1/N)
    // bias; with N = 1000 it is far below the Monte Carlo standard error of one run, which is
    // what the bound uses (σ̂ of single runs, not of their average), so the bound is honest.
    for k in 0..=n {
        for d in 0..2 {
            let xs: Vec<f64> = runs.iter().map(|(_, means)| means[k][d]).collect();
            let (mean, se) = mean_and_se(&xs);
            let truth = exact.filtered_means[k][d];
            assert!(
                (mean - truth).abs() < z * se,
                "step {k}, coordinate {d}: PF {mean} ± {se}, KF {truth}"
            );
        }
    }
}

/// The noisy AR(1) model (φ = 0.9, σ = 0.5, ρ = 1), 41 observations simulated from stream
/// `(seed, 0)`, and their exact log-likelihood from the model's Kalman twin.
fn ar1_case(seed: u64) -> (NoisyAr1, Vec<Option<f64>>, f64) {
    let (phi, sigma, rho) = (0.9, 0.5, 1.0);
    let ar1 = NoisyAr1::new(phi, sigma, rho).unwrap();
    let twin = LinearGaussian::scalar(
        phi,
        1.0,
        sigma * sigma,
        rho * rho,
        ar1.m0(),
        ar1.s0() * ar1.s0(),
    )
    .unwrap();
    let (_, ys) = ar1.simulate(40, &mut stream_rng(seed, 0));
    let ys: Vec<Option<f64>> = ys.into_iter().map(Some).collect();
    let yv: Vec<Option<DVector<f64>>> = ys
        .iter()
        .map(|y| y.map(|y| DVector::from_element(1, y)))
        .collect();
    let exact = kalman_filter(&twin, &yv, None).unwrap().log_likelihood;
    (ar1, ys, exact)
}

/// Every resampling policy the unbiasedness tests cover.
const POLICIES: [ResamplePolicy; 2] = [
    ResamplePolicy::Always,
    ResamplePolicy::EssBelow(EssThreshold::Fraction(0.5)),
];

/// The same unbiasedness for every resampler and under adaptive (ESS-triggered) resampling,
/// on the scalar AR(1) model of Cappé & Moulines, whose Kalman twin is `LinearGaussian::scalar`.
#[test]
fn every_resampler_and_policy_gives_an_unbiased_likelihood() {
    let (ar1, ys, exact) = ar1_case(7);

    let z = bonferroni_z(Resampler::ALL.len() * POLICIES.len());
    for resampler in Resampler::ALL {
        for policy in POLICIES {
            let cfg = FilterConfig {
                n_particles: 200,
                resampler,
                policy,
            };
            let ratio = replicate(2, 400, Par::Rayon, |_, rng| {
                let mut pf = ParticleFilter::bootstrap(ar1, cfg).unwrap();
                (pf.run(&ys, None, rng, &mut ()).unwrap().log_lik - exact).exp()
            });
            let (m, se) = mean_and_se(&ratio);
            assert!(
                (m - 1.0).abs() < z * se,
                "{resampler} {policy:?}: E[Ẑ/Z] = {m} ± {se}"
            );
        }
    }
}

/// The fast structure-of-arrays filter draws from per-chunk streams, so it cannot match the
/// generic filter draw by draw; it must match it in distribution. Its `Ẑ` must be unbiased
/// for every scheme and policy, with several chunks in play (N = 200, chunks of 48).
#[test]
fn batch_filter_likelihood_is_unbiased() {
    let (ar1, ys, exact) = ar1_case(8);
    let z = bonferroni_z(Resampler::ALL.len() * POLICIES.len());
    for resampler in Resampler::ALL {
        for policy in POLICIES {
            let ratio = replicate(3, 400, Par::Rayon, |r, _| {
                let cfg = BatchConfig {
                    resampler,
                    policy,
                    chunk: 48,
                    par: Par::Seq,
                    ..BatchConfig::new(200, r as u64)
                };
                let mut f = BatchBootstrap::new(ar1, cfg).unwrap();
                (f.run(&ys).unwrap().log_lik - exact).exp()
            });
            let (m, se) = mean_and_se(&ratio);
            assert!(
                (m - 1.0).abs() < z * se,
                "batch {resampler} {policy:?}: E[Ẑ/Z] = {m} ± {se}"
            );
        }
    }
}

/// Bit-identical Monte Carlo results with one and two threads.
#[test]
fn monte_carlo_is_identical_for_any_thread_count() {
    let ar1 = NoisyAr1::new(0.98, 0.2, 1.0).unwrap();
    let (_, ys) = ar1.simulate(50, &mut stream_rng(3, 0));
    let ys: Vec<Option<f64>> = ys.into_iter().map(Some).collect();
    let work = || {
        replicate(11, 16, Par::Rayon, |_, rng| {
            let mut pf = ParticleFilter::bootstrap(ar1, FilterConfig::new(300)).unwrap();
            let s = pf.run(&ys, None, rng, &mut ()).unwrap();
            (s.log_lik.to_bits(), pf.mean().unwrap()[0].to_bits())
        })
    };
    let pool = |t| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
    };
    assert_eq!(pool(1).install(work), pool(2).install(work));
}
