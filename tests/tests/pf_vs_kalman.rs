//! The particle filter against exact Kalman answers on linear-Gaussian models.
//!
//! Bounds come from the replications themselves: with R independent runs, a Monte Carlo
//! average has standard error σ̂/√R, and a correct filter lands within z standard errors of
//! the exact value. z is chosen by a Bonferroni bound over every comparison a test makes, so
//! a correct implementation fails a test with probability below about 1e-4.

use nalgebra::{DMatrix, DVector};
use pf_core::filter::{
    BatchBootstrap, BatchConfig, BatchFilter, BatchProposal, Cols, ColsMut, EssThreshold,
    FilterConfig, MomentRecorder, ParticleFilter, ResamplePolicy,
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
    // bias b/N; the bound is z standard errors of the average of R = 200 runs, about
    // z·σ/√(N·R) for a posterior sd σ, so a bias coefficient |b| of the order of σ is a tenth
    // of the bound (√(R/N)/z ≈ 0.11 with N = 1000).
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

/// A 3-D state observed in two coordinates, with correlated noise: the batch filter's
/// multivariate case.
fn three_state_model() -> LinearGaussian {
    LinearGaussian::new(
        DMatrix::from_row_slice(3, 3, &[0.9, 0.3, 0.0, 0.0, 0.8, 0.2, 0.1, 0.0, 0.7]),
        None,
        DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 0.5, 0.0, 1.0, -0.5]),
        DMatrix::from_row_slice(3, 3, &[0.2, 0.05, 0.0, 0.05, 0.3, 0.02, 0.0, 0.02, 0.1]),
        DMatrix::from_row_slice(2, 2, &[0.5, 0.1, 0.1, 0.4]),
        DVector::from_vec(vec![0.0, 1.0, -1.0]),
        DMatrix::from_row_slice(3, 3, &[1.0, 0.2, 0.0, 0.2, 1.0, 0.0, 0.0, 0.0, 0.5]),
    )
    .expect("a valid model")
}

/// The batch filter on a multivariate model: `Ẑ` unbiased for every scheme and policy, with
/// several chunks and a missing observation; and with N = 1000 its weighted means and
/// variances (through `MomentRecorder`) match the Kalman filter's at every step.
#[test]
fn batch_filter_on_a_multivariate_model_matches_the_kalman_filter() {
    let model = three_state_model();
    let batch = model.batch().unwrap();
    let n = 20;
    let (_, ys) = model.simulate(n, None, &mut stream_rng(101, 0)).unwrap();
    let mut ys: Vec<Option<DVector<f64>>> = ys.into_iter().map(Some).collect();
    ys[5] = None;
    let exact = kalman_filter(&model, &ys, None).unwrap();
    let z = bonferroni_z(Resampler::ALL.len() * POLICIES.len() + 2 * 3 * (n + 1));
    for resampler in Resampler::ALL {
        for policy in POLICIES {
            let ratio = replicate(4, 400, Par::Rayon, |r, _| {
                let cfg = BatchConfig {
                    resampler,
                    policy,
                    chunk: 48,
                    par: Par::Seq,
                    ..BatchConfig::new(200, r as u64)
                };
                let mut f = BatchFilter::new(batch.clone(), cfg).unwrap();
                (f.run(&ys).unwrap().log_lik - exact.log_likelihood).exp()
            });
            let (m, se) = mean_and_se(&ratio);
            assert!(
                (m - 1.0).abs() < z * se,
                "batch 3-D {resampler} {policy:?}: E[Ẑ/Z] = {m} ± {se}"
            );
        }
    }
    let runs = replicate(5, 200, Par::Rayon, |r, _| {
        let cfg = BatchConfig {
            chunk: 256,
            par: Par::Seq,
            ..BatchConfig::new(1000, r as u64)
        };
        let mut f = BatchFilter::new(batch.clone(), cfg).unwrap();
        let mut rec = MomentRecorder::with_capacity(ys.len(), 3);
        f.run_observed(None, &ys, &mut rec).unwrap();
        rec
    });
    for k in 0..=n {
        for d in 0..3 {
            let means: Vec<f64> = runs.iter().map(|rec| rec.mean_at(k)[d]).collect();
            let (mean, se) = mean_and_se(&means);
            let truth = exact.filtered_means[k][d];
            assert!(
                (mean - truth).abs() < z * se,
                "step {k}, coordinate {d}: batch PF mean {mean} ± {se}, KF {truth}"
            );
            let vars: Vec<f64> = runs.iter().map(|rec| rec.cov_at(k)[d * 3 + d]).collect();
            let (var, se) = mean_and_se(&vars);
            let truth = exact.filtered_covs[k][(d, d)];
            // The weighted variance is biased by O(1/N) (about truth/N); the bound allows it.
            assert!(
                (var - truth).abs() < z * se + 2.0 * truth / 1000.0,
                "step {k}, coordinate {d}: batch PF variance {var} ± {se}, KF {truth}"
            );
        }
    }
}

/// The optimal importance density of the noisy AR(1) model,
/// `q(x | x', y) = N((ρ² φ x' + σ² y)/(σ² + ρ²), σ²ρ²/(σ² + ρ²))`, and the prior without `y`.
struct Ar1Optimal;

impl BatchProposal<NoisyAr1> for Ar1Optimal {
    fn noise_dim(&self, _m: &NoisyAr1) -> usize {
        1
    }
    fn propose(
        &self,
        m: &NoisyAr1,
        _t: usize,
        _u: &(),
        y: Option<&f64>,
        parents: Cols<'_>,
        z: Cols<'_>,
        mut x: ColsMut<'_>,
        log_q: &mut [f64],
    ) {
        let (s2, r2) = (m.sigma() * m.sigma(), m.rho() * m.rho());
        let (gain, sd) = match y {
            Some(_) => (s2 / (s2 + r2), (s2 * r2 / (s2 + r2)).sqrt()),
            None => (0.0, m.sigma()),
        };
        let y = y.copied().unwrap_or(0.0);
        let c = -sd.ln() - 0.5 * pf_core::gaussian::LN_2PI;
        for (((x, &z), &xp), lq) in x
            .col_mut(0)
            .iter_mut()
            .zip(z.col(0))
            .zip(parents.col(0))
            .zip(log_q)
        {
            let prior = m.phi() * xp;
            *x = prior + gain * (y - prior) + sd * z;
            *lq = c - 0.5 * z * z;
        }
    }
}

/// The guided batch filter's `Ẑ` (weights `g f / q`) is unbiased too, with every scheme.
#[test]
fn guided_batch_filter_likelihood_is_unbiased() {
    let (ar1, mut ys, _) = ar1_case(9);
    ys[0] = None;
    let ys_v: Vec<Option<DVector<f64>>> = ys
        .iter()
        .map(|y| y.map(|y| DVector::from_element(1, y)))
        .collect();
    let twin = LinearGaussian::scalar(0.9, 1.0, 0.25, 1.0, ar1.m0(), ar1.s0() * ar1.s0()).unwrap();
    let exact_missing = kalman_filter(&twin, &ys_v, None).unwrap().log_likelihood;
    let z = bonferroni_z(Resampler::ALL.len());
    for resampler in Resampler::ALL {
        let ratio = replicate(6, 400, Par::Rayon, |r, _| {
            let cfg = BatchConfig {
                resampler,
                chunk: 48,
                par: Par::Seq,
                ..BatchConfig::new(100, r as u64)
            };
            let mut f = BatchFilter::guided(ar1, Ar1Optimal, cfg).unwrap();
            (f.run(&ys).unwrap().log_lik - exact_missing).exp()
        });
        let (m, se) = mean_and_se(&ratio);
        assert!(
            (m - 1.0).abs() < z * se,
            "guided {resampler}: E[Ẑ/Z] = {m} ± {se}"
        );
    }
}
