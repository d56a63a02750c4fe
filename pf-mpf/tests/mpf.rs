//! The marginalized particle filter against exact references, pf-core's standard PF, its own
//! two Riccati forms, and the RMSE claim.

use nalgebra::{SMatrix, SVector};
use pf_core::filter::{FilterConfig, ParticleFilter};
use pf_core::kalman::{LinearGaussian, kalman_filter};
use pf_core::mc::{Par, mean_and_se, replicate, stream_rng};
use pf_mpf::error::MpfError;
use pf_mpf::model::{LinearMeasurement, MixedLinearGaussian, Model5Matrices};
use pf_mpf::mpf::{Mpf, MpfConfig, Riccati};
use pf_mpf::radar::{Partition, RadarConfig, run_partition};

fn radar(steps: usize) -> RadarConfig {
    RadarConfig {
        n_steps: steps,
        ..RadarConfig::default()
    }
}

#[test]
fn k_zero_is_pf_cores_standard_pf() {
    let cfg = radar(15);
    let truth = cfg.truth();
    let ys = cfg.measure(&truth, &mut stream_rng(9, 0));
    let part: Partition = "PPPPPP".parse().unwrap();
    let model = part.model::<6, 0>(&cfg).unwrap();
    let mut mpf = Mpf::new(model.clone(), MpfConfig::new(300)).unwrap();
    let mut pf = ParticleFilter::bootstrap(model, FilterConfig::new(300)).unwrap();
    let (mut r1, mut r2) = (stream_rng(4, 0), stream_rng(4, 0));
    for y in &ys {
        let a = mpf.step(y.as_ref(), &mut r1).unwrap();
        let b = pf.step(None, y.as_ref(), &mut r2).unwrap();
        // Same random numbers in the same order; only the order of floating-point sums
        // differs (faer block products against per-particle products): ~1e-15 relative.
        assert!((a.log_lik - b.log_lik).abs() < 1e-9 * b.log_lik.abs().max(1.0));
        let (mp, _) = mpf.estimate().unwrap();
        let m = pf.mean().unwrap();
        for d in 0..6 {
            assert!(
                (mp[d] - m[d]).abs() < 1e-9 * m[d].abs().max(1.0),
                "state {d}"
            );
        }
    }
}

#[test]
fn per_particle_riccati_equals_alg1_when_c_is_zero() {
    let cfg = radar(15);
    let truth = cfg.truth();
    let ys = cfg.measure(&truth, &mut stream_rng(9, 1));
    let part: Partition = "PPKKKK".parse().unwrap();
    let model = part.model::<2, 4>(&cfg).unwrap();
    let shared = MpfConfig {
        riccati: Riccati::Shared,
        ..MpfConfig::new(200)
    };
    let each = MpfConfig {
        riccati: Riccati::PerParticle,
        ..MpfConfig::new(200)
    };
    let mut a = Mpf::new(model.clone(), shared).unwrap();
    let mut b = Mpf::new(model, each).unwrap();
    assert!(a.is_shared() && !b.is_shared());
    let (mut r1, mut r2) = (stream_rng(5, 0), stream_rng(5, 0));
    for y in &ys {
        a.step(y.as_ref(), &mut r1).unwrap();
        b.step(y.as_ref(), &mut r2).unwrap();
        let ((pa, ka), (pb, kb)) = (a.estimate().unwrap(), b.estimate().unwrap());
        // Identical arithmetic up to summation order: relative 1e-9 is ~10⁶ ulps of slack.
        for d in 0..2 {
            assert!((pa[d] - pb[d]).abs() < 1e-9 * pa[d].abs().max(1.0));
        }
        for d in 0..4 {
            assert!((ka[d] - kb[d]).abs() < 1e-9 * ka[d].abs().max(1.0));
        }
        assert!((a.kf_cov(0) - b.kf_cov(7)).amax() < 1e-9 * a.kf_cov(0).amax());
    }
}

/// x^k ∈ ℝ², observed through C; x^p empty: every particle carries the exact Kalman filter.
#[test]
fn marginalising_every_state_reproduces_the_kalman_filter() {
    let f_k = SMatrix::<f64, 2, 2>::new(0.9, 0.3, -0.2, 0.8);
    let q_k = SMatrix::<f64, 2, 2>::new(0.5, 0.1, 0.1, 0.4);
    let c = SMatrix::<f64, 1, 2>::new(1.0, 0.5);
    let r = SMatrix::<f64, 1, 1>::new(0.7);
    let x0 = SVector::<f64, 2>::new(1.0, -1.0);
    let p0 = SMatrix::<f64, 2, 2>::new(2.0, 0.3, 0.3, 1.0);
    let m = Model5Matrices::<0, 2, 1> {
        a_p: SMatrix::zeros(),
        a_k: SMatrix::zeros(),
        f_p: SMatrix::zeros(),
        f_k,
        q_p: SMatrix::zeros(),
        q_k,
        c,
        r,
        x0_p: SVector::zeros(),
        p0_p: SMatrix::zeros(),
        x0_k: x0,
        p0_k: p0,
    };
    let model = MixedLinearGaussian::new(
        m,
        LinearMeasurement {
            h: SMatrix::zeros(),
        },
    )
    .unwrap();
    let dm = |s: &[f64], r, c| nalgebra::DMatrix::from_column_slice(r, c, s);
    let lg = LinearGaussian::new(
        dm(f_k.as_slice(), 2, 2),
        None,
        dm(c.as_slice(), 1, 2),
        dm(q_k.as_slice(), 2, 2),
        dm(r.as_slice(), 1, 1),
        nalgebra::DVector::from_column_slice(x0.as_slice()),
        dm(p0.as_slice(), 2, 2),
    )
    .unwrap();
    let (_, ys) = lg.simulate(30, None, &mut stream_rng(1, 0)).unwrap();
    let ys: Vec<Option<nalgebra::DVector<f64>>> = ys
        .into_iter()
        .enumerate()
        .map(|(t, y)| (t % 7 != 3).then_some(y))
        .collect();
    let kf = kalman_filter(&lg, &ys, None).unwrap();
    let mut mpf = Mpf::new(model, MpfConfig::new(5)).unwrap();
    assert!(!mpf.is_shared());
    let mut rng = stream_rng(2, 0);
    for (t, y) in ys.iter().enumerate() {
        let y = y.as_ref().map(|y| SVector::<f64, 1>::new(y[0]));
        mpf.step(y.as_ref(), &mut rng).unwrap();
        let (_, mk) = mpf.estimate().unwrap();
        for d in 0..2 {
            // Exact algebra in a different order (Joseph form in both): 1e-9 relative.
            assert!(
                (mk[d] - kf.filtered_means[t][d]).abs() < 1e-9 * (1.0 + mk[d].abs()),
                "t={t}"
            );
            for e in 0..2 {
                assert!((mpf.kf_cov(0)[(d, e)] - kf.filtered_covs[t][(d, e)]).abs() < 1e-9);
            }
        }
    }
    assert!((mpf.log_likelihood() - kf.log_likelihood).abs() < 1e-9 * kf.log_likelihood.abs());
}

#[test]
fn marginalisation_does_not_raise_the_rmse_at_equal_n() {
    // R paired replications (same measurement noise for both filters): d_r is the PF's
    // mean squared position+velocity error minus the full MPF's. Rao-Blackwellisation says
    // E[d] ≥ 0; the test fails if the mean difference is below −2σ̂/√R (a one-sided 2.3 %
    // false-alarm level if E[d] = 0 exactly).
    let cfg = radar(25);
    let truth = cfg.truth();
    let n = 150;
    let r = 24;
    let pf: Partition = "PPPPPP".parse().unwrap();
    let mpf: Partition = "PPKKKK".parse().unwrap();
    let d = replicate(11, r, Par::Rayon, |_, rng| {
        let ys = cfg.measure(&truth, rng);
        let mut r1 = rng.clone();
        let a = run_partition(&pf, &cfg, MpfConfig::new(n), &truth, &ys, &mut r1).unwrap();
        let b = run_partition(&mpf, &cfg, MpfConfig::new(n), &truth, &ys, rng).unwrap();
        let mse = |e: &pf_mpf::radar::RunErrors| {
            e.sq_pos
                .iter()
                .zip(&e.sq_vel)
                .map(|(p, v)| p + v)
                .sum::<f64>()
                / e.sq_pos.len() as f64
        };
        mse(&a) - mse(&b)
    });
    let (mean, se) = mean_and_se(&d);
    assert!(mean > -2.0 * se, "mean difference {mean} (se {se})");
}

#[test]
fn bad_inputs_are_errors() {
    for bad in ["KKPPPP", "PPXPPP", "PPKK", ""] {
        assert!(
            matches!(bad.parse::<Partition>(), Err(MpfError::Partition { .. })),
            "{bad}"
        );
    }
    let cfg = radar(5);
    let part: Partition = "PPKKPP".parse().unwrap();
    assert!(part.model::<2, 4>(&cfg).is_err());
    let model = part.model::<4, 2>(&cfg).unwrap();
    assert!(Mpf::new(model.clone(), MpfConfig::new(0)).is_err());
    // Counts no machine holds are errors before anything is allocated: above the count
    // limit, and (2³¹ particles, about 670 GB of buffers) above this machine's memory.
    for n in [usize::MAX, 1 << 31] {
        assert!(
            matches!(
                Mpf::new(model.clone(), MpfConfig::new(n)),
                Err(MpfError::Core(pf_core::CoreError::TooLarge { .. }))
            ),
            "N = {n}"
        );
    }
    let mut f = Mpf::new(model, MpfConfig::new(10)).unwrap();
    // Nothing to estimate before the first step: an error, not the buffers' zeros.
    assert!(matches!(
        f.estimate(),
        Err(MpfError::Core(pf_core::CoreError::Empty { .. }))
    ));
    let y = SVector::<f64, 2>::new(f64::NAN, 0.1);
    assert!(matches!(
        f.step(Some(&y), &mut stream_rng(0, 0)),
        Err(MpfError::NonFiniteObservation { t: 0, index: 0, .. })
    ));
    assert!(
        RadarConfig {
            period: -1.0,
            ..RadarConfig::default()
        }
        .validate()
        .is_err()
    );
    assert!(
        RadarConfig {
            n_steps: 1,
            ..RadarConfig::default()
        }
        .validate()
        .is_err()
    );
    let json = r#"{"n_particles": 10, "resampler": "systematic", "riccati": "auto", "extra": 1}"#;
    assert!(serde_json::from_str::<MpfConfig>(json).is_err());
    // Alg. 1 with C ≠ 0 is refused.
    let m = Model5Matrices::<1, 1, 1> {
        a_p: SMatrix::identity(),
        a_k: SMatrix::zeros(),
        f_p: SMatrix::zeros(),
        f_k: SMatrix::identity(),
        q_p: SMatrix::identity(),
        q_k: SMatrix::identity(),
        c: SMatrix::identity(),
        r: SMatrix::identity(),
        x0_p: SVector::zeros(),
        p0_p: SMatrix::identity(),
        x0_k: SVector::zeros(),
        p0_k: SMatrix::identity(),
    };
    let lin = MixedLinearGaussian::new(
        m,
        LinearMeasurement {
            h: SMatrix::identity(),
        },
    )
    .unwrap();
    let shared = MpfConfig {
        riccati: Riccati::Shared,
        ..MpfConfig::new(10)
    };
    assert!(matches!(
        Mpf::new(lin, shared),
        Err(MpfError::SharedRiccatiNeedsZeroC { .. })
    ));
}
