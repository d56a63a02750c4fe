//! The EF formulas against the paper's worked numbers, the figures' qualitative claims, the
//! advisor and the JSON contracts.

use pf_mpf::advisor::{AdviseConfig, advise};
use pf_mpf::calibrate::{CalibrateConfig, Calibration, calibrate};
use pf_mpf::complexity::*;
use pf_mpf::experiments::{RatioConfig, ratio};

#[test]
fn eq14_reproduces_the_papers_numbers() {
    let c = EfCoefficients::default();
    // Eq. (14) with c1 = 445, c2 = 487, c3 = 125: 1 − 556/1832.
    assert!((eq14_factor(&c) - (1.0 - 556.0 / 1832.0)).abs() < 1e-15);
    // Section IV-B: N(k)/N_PF = 1.44 for m = 6, k = 4 (two decimals as printed).
    let r = particle_ratio(CtCase::Zero, 2, 4, 2000.0, &c);
    assert!((r - 1.44).abs() < 0.005, "ratio {r}");
    // Eq. (14) is eq. (11) with the N-independent terms dropped: as N_PF → ∞ the ratio
    // tends to 1/factor.
    let r_inf = particle_ratio(CtCase::Zero, 2, 4, 1e12, &c);
    assert!((r_inf - 1.0 / eq14_factor(&c)).abs() < 1e-9);
}

#[test]
fn table_one_sums_to_eq11_but_for_likelihood_resampling_and_one_k_cubed() {
    let c = EfCoefficients::default();
    for p in 1..7 {
        for k in 0..6 {
            let n = 1000;
            let table = table_one_total(p, k, n, &c) + (c.c1 + c.c2) * n as f64;
            let eq11 = ef_ct_zero(p, k, &c).at(n as f64);
            // The rows give 4k³; eq. (11) prints 5k³ (documented in the README).
            assert!(
                (eq11 - table - (k as f64).powi(3)).abs() < 1e-6 * eq11,
                "p={p} k={k}"
            );
        }
    }
}

#[test]
fn figures_show_the_papers_claims() {
    let res = ratio(&RatioConfig::default()).unwrap();
    assert_eq!(res.m, (3..=9).collect::<Vec<_>>());
    for curve in &res.curves {
        for (j, v) in curve.ct_zero.iter().enumerate() {
            let m = res.m[j];
            assert_eq!(v.is_some(), curve.k <= m - 2);
            // Fig. 1: with C_t = 0 the MPF can always afford more particles.
            if let Some(v) = v {
                assert!(*v > 1.0, "m={m} k={}", curve.k);
            }
        }
    }
    let at = |k: usize, m: usize| res.curves[k - 1].ct_nonzero[m - 3].unwrap();
    // Fig. 2: few states, MPF more efficient; m = 9 with 7 marginalized, N(k) < N_PF.
    assert!(at(1, 3) > 1.0);
    assert!(at(7, 9) < 1.0);
    let json = serde_json::to_value(&res).unwrap();
    assert!(json["curves"][0]["ct_zero"].is_array() && json["curves"][0]["k"] == 1);
    assert!(json["curves"][6]["ct_nonzero"][0].is_null());
}

#[test]
fn calibration_is_positive_and_finite() {
    let cal = calibrate(&CalibrateConfig::quick()).unwrap();
    for v in [cal.flop_ns, cal.c1, cal.c2, cal.c3] {
        assert!(v.is_finite() && v > 0.0, "{cal:?}");
    }
    let json = serde_json::to_value(cal).unwrap();
    let mut keys: Vec<_> = json.as_object().unwrap().keys().cloned().collect();
    keys.sort();
    assert_eq!(keys, ["c1", "c2", "c3", "flop_ns"]);
    assert!(
        calibrate(&CalibrateConfig {
            n_values: vec![100],
            ..CalibrateConfig::quick()
        })
        .is_err()
    );
}

#[test]
fn advisor_ranks_full_marginalization_first_for_the_radar() {
    let cal = Calibration {
        flop_ns: 1.0,
        c1: 445.0,
        c2: 487.0,
        c3: 125.0,
    };
    let a = advise(&AdviseConfig::default(), &cal).unwrap();
    assert_eq!(a.options.len(), 5);
    assert_eq!((a.options[0].p, a.options[0].k), (2, 4));
    // A budget equal to the PF's cost at N = 2000 buys 2000 × 1.44 particles with k = 4.
    let budget = ef_ct_zero(6, 0, &cal.coefficients()).at(2000.0) * 1e-9;
    let b = advise(
        &AdviseConfig {
            budget_s: Some(budget),
            particles: None,
            ..AdviseConfig::default()
        },
        &cal,
    )
    .unwrap();
    assert_eq!(b.options[0].k, 4);
    assert!((b.options[0].n_particles as f64 / 2000.0 - 1.44).abs() < 0.01);
    assert!(
        advise(
            &AdviseConfig {
                budget_s: Some(1.0),
                ..AdviseConfig::default()
            },
            &cal
        )
        .is_err()
    );
    assert!(
        advise(
            &AdviseConfig {
                budget_s: Some(1e-15),
                particles: None,
                ..AdviseConfig::default()
            },
            &cal
        )
        .is_err()
    );
}
