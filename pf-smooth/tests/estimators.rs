//! The estimators against exact answers: the Kalman-smoother statistics against a
//! brute-force joint Gaussian posterior, and the particle estimates against the exact ones
//! with bounds derived from the replications (fixed seeds).

use nalgebra::DVector;
use pf_core::kalman::LinearGaussian;
use pf_core::mc::{mean_and_sd, mean_and_se, stream_rng};
use pf_core::models::NoisyAr1;
use pf_core::testing::joint_gaussian_posterior;
use pf_smooth::ar1::{Ar1Data, Theta};
use pf_smooth::exact::exact_statistics;
use pf_smooth::experiments::{EmConfig, Observations, ScoreConfig, em, score};

fn simulated(n: usize, seed: u64) -> Vec<f64> {
    NoisyAr1::new(0.98, 0.2, 1.0)
        .unwrap()
        .simulate(n, &mut stream_rng(seed, 0))
        .1
}

fn args(
    y: &[f64],
    particles: usize,
    replications: usize,
    lag: Option<usize>,
    seed: u64,
) -> EmConfig {
    EmConfig {
        data: Observations::Given(y.to_vec()),
        phi: 0.8,
        sigma: 0.5,
        rho: 2.0,
        particles,
        replications,
        lag,
        forward: false,
        seed,
    }
}

fn rmse_about(xs: &[f64], target: f64) -> f64 {
    (xs.iter().map(|x| (x - target).powi(2)).sum::<f64>() / xs.len() as f64).sqrt()
}

#[test]
fn exact_statistics_match_the_brute_force_joint_posterior() {
    let y = [0.3, -0.8, 1.9, 0.4, -1.2, 2.5, 0.7];
    let n = y.len() - 1;
    let theta = Theta::from_std(0.8, 0.5, 2.0).unwrap();
    let exact = exact_statistics(&Ar1Data::from_slice(&y).unwrap(), &theta).unwrap();
    // The diffuse prior of Section 5: the filter at time 0 is φ_0 = N(Y_0, ρ²), so Y_0 enters
    // through the prior and is not observed a second time.
    let model = LinearGaussian::scalar(0.8, 1.0, 0.25, 4.0, y[0], 4.0).unwrap();
    let ys: Vec<Option<DVector<f64>>> = y
        .iter()
        .enumerate()
        .map(|(k, &v)| (k > 0).then(|| DVector::from_element(1, v)))
        .collect();
    let post = joint_gaussian_posterior(&model, &ys).unwrap();
    let m = |k: usize| post.mean(k)[0];
    let c = |k: usize, j: usize| post.cov(k, j)[(0, 0)];
    let second = |k: usize| m(k) * m(k) + c(k, k);
    let tau = [
        (0..n).map(second).sum::<f64>(),
        (0..n).map(|k| m(k) * m(k + 1) + c(k, k + 1)).sum::<f64>(),
        (1..=n).map(second).sum::<f64>(),
        (0..=n)
            .map(|k| (y[k] - m(k)).powi(2) + c(k, k))
            .sum::<f64>(),
    ];
    for (i, (a, b)) in exact.tau.iter().zip(tau).enumerate() {
        assert!(
            (a - b).abs() <= 1e-9 * b.abs().max(1.0),
            "τ_{}: {a} vs {b}",
            i + 1
        );
    }
}

#[test]
fn particle_updates_converge_to_the_exact_update_as_n_grows() {
    let y = simulated(100, 3);
    let small = em(&args(&y, 50, 16, Some(10), 5)).unwrap();
    let large = em(&args(&y, 800, 16, Some(10), 5)).unwrap();
    let exact = small.exact;
    // 16× the particles: the Monte Carlo error should shrink about 4-fold (bias and
    // variance both fall with N); ask for at least 2-fold, for every parameter.
    for (name, pick) in [
        (
            "phi",
            (|s: &pf_smooth::ar1::ThetaSamples| s.phi.clone()) as fn(&_) -> Vec<f64>,
        ),
        ("sigma2", |s| s.sigma2.clone()),
        ("rho2", |s| s.rho2.clone()),
    ] {
        let target = match name {
            "phi" => exact.phi,
            "sigma2" => exact.sigma2,
            _ => exact.rho2,
        };
        for (est, a, b) in [
            ("joint", &small.joint, &large.joint),
            (
                "fixed lag",
                small.fixed_lag.as_ref().unwrap(),
                large.fixed_lag.as_ref().unwrap(),
            ),
        ] {
            let (ea, eb) = (rmse_about(&pick(a), target), rmse_about(&pick(b), target));
            assert!(
                eb < 0.5 * ea,
                "{est} {name}: RMSE {ea} at N = 50, {eb} at N = 800"
            );
        }
    }
}

#[test]
fn fixed_lag_has_a_clearly_smaller_spread_than_the_joint_estimator_at_n_500() {
    let y = simulated(500, 4);
    let out = em(&args(&y, 100, 20, Some(20), 6)).unwrap();
    let (j, f) = (
        mean_and_sd(&out.joint.phi).1,
        mean_and_sd(&out.fixed_lag.unwrap().phi).1,
    );
    // The paper: fixed lag at N = 100 is about the joint at N = 1000, a √10 ≈ 3.2 ratio in
    // spread; with 20 replications each std is known to about ±16 %, so 1.5 is safe.
    assert!(f * 1.5 < j, "std: fixed lag {f}, joint {j}");
}

#[test]
fn the_fisher_identity_score_agrees_with_the_exact_gradient() {
    let y = simulated(50, 7);
    let out = score(&ScoreConfig {
        data: Observations::Given(y),
        phi: 0.8,
        sigma: 0.5,
        rho: 2.0,
        particles: 2000,
        replications: 16,
        seed: 8,
    })
    .unwrap();
    for (name, xs, exact) in [
        ("phi", &out.particle.phi, out.exact.phi),
        ("sigma2", &out.particle.sigma2, out.exact.sigma2),
        ("rho2", &out.particle.rho2, out.exact.rho2),
    ] {
        let (mean, se) = mean_and_se(xs);
        // Within 4 standard errors of the replications, with no allowance for the path-space
        // estimator's O(n/N) bias: over 300 runs at N = 2000 the three means lie within 1.1
        // standard errors of the exact score. (An allowance of 1 % of the gradient's scale,
        // 0.045 on ρ², would have been ten of the standard errors of 16 runs.)
        assert!(
            (mean - exact).abs() <= 4.0 * se,
            "{name}: particle {mean} ± {se}, exact {exact}"
        );
    }
}

/// Simulated observations are the model's draw on the stream `(seed, stream)`: the same
/// numbers as given ones, and so the same experiment.
#[test]
fn simulated_observations_are_the_stream_s_draw() {
    let given = args(&simulated(40, 3), 20, 2, Some(5), 1);
    let drawn = EmConfig {
        data: Observations::Simulated {
            truth: Theta::paper_truth(),
            n: 40,
            seed: 3,
            stream: 0,
        },
        ..given.clone()
    };
    let (states, data) = drawn.data.draw().unwrap();
    assert_eq!(states.map(|x| x.len()), Some(41));
    assert_eq!(data.y(), simulated(40, 3).as_slice());
    assert_eq!(em(&drawn).unwrap(), em(&given).unwrap());
}

/// The lag sweep's exact fixed-lag updates: the lag's bias shrinks towards the exact EM
/// update as δ grows and vanishes once δ passes n (every term then smoothed given all the
/// data); and the particle updates of a short lag centre on that limit, not on the exact
/// update, within 4 standard errors of the replications.
#[test]
fn the_lag_sweep_separates_the_lags_bias_from_the_particles() {
    use pf_smooth::experiments::{LagSweepConfig, lag_sweep};
    let y = simulated(100, 5);
    let out = lag_sweep(&LagSweepConfig {
        data: Observations::Given(y),
        phi: 0.8,
        sigma: 0.5,
        rho: 2.0,
        particles: 500,
        replications: 40,
        lags: vec![1, 3, 10, 101],
        seed: 4,
    })
    .unwrap();
    let bias: Vec<f64> = out
        .exact_fixed_lag
        .iter()
        .map(|t| (t.phi - out.exact.phi).abs())
        .collect();
    assert!(bias[0] > bias[1] && bias[1] > bias[2], "{bias:?}");
    assert_eq!(
        out.exact_fixed_lag[3], out.exact,
        "δ > n is the joint smoother"
    );
    let (m, se) = mean_and_se(&out.fixed_lag[0].phi);
    let limit = out.exact_fixed_lag[0].phi;
    assert!(
        (m - limit).abs() < 4.0 * se,
        "δ = 1: {m} ± {se}, limit {limit}"
    );
    assert!(
        (m - out.exact.phi).abs() > 4.0 * se,
        "δ = 1 is biased: {m} ± {se}, exact {}",
        out.exact.phi
    );
}
