//! The paper's claims on the simulated scenarios, over seeded replications, and the REC
//! curves' properties.

use pf_core::mc::mean_and_se;
use pf_epf::experiments::{ComparisonConfig, Method, compare};
use pf_epf::metrics::rec_of;
use pf_epf::scenario::{Scenario, ScenarioConfig};

/// Paired differences `a − b` of the association error rate over `reps` runs; returns the
/// two means, the mean difference and its standard error.
fn paired(s: ScenarioConfig, reps: usize, seed: u64, a: Method, b: Method) -> (f64, f64, f64, f64) {
    let mut cfg = ComparisonConfig {
        seed,
        ..ComparisonConfig::new(s, reps)
    };
    cfg.tracker.n_particles = 100;
    cfg.methods = vec![a, b];
    let c = compare(&cfg).unwrap();
    let (ra, rb) = (&c.methods[0], &c.methods[1]);
    let d: Vec<f64> = ra
        .error_rate
        .iter()
        .zip(&rb.error_rate)
        .map(|(x, y)| x - y)
        .collect();
    let (mean_d, se_d) = mean_and_se(&d);
    (ra.error_rate_mean.0, rb.error_rate_mean.0, mean_d, se_d)
}

/// Against the paper's NNSF (nearest neighbour to the prediction Â(t)), the paper's EPF
/// (eq. (1) per measurement) is no better on any scenario, clean or with clutter and missed
/// detections: the mean paired difference d = NNSF − EPF is below 2 standard errors of d
/// (a one-sided test at about 2.5 %; a seeded run where NNSF were really worse would fail
/// it). The margins are printed (`cargo test -- --nocapture`).
#[test]
fn nnsf_to_the_prediction_is_no_worse_than_epf() {
    for s in Scenario::ALL {
        for (clutter, miss) in [(0.0, 0.0), (1.0, 0.1)] {
            let sc = ScenarioConfig {
                scenario: s,
                clutter,
                miss,
            };
            let (nnsf, epf, d, se) = paired(sc, 200, 2024, Method::Nnsf, Method::Epf);
            println!(
                "{} clutter {clutter} miss {miss}: NNSF {nnsf:.3}, EPF {epf:.3}, NNSF − EPF = {d:+.3} ± {se:.3}",
                s.name()
            );
            assert!(
                d <= 2.0 * se,
                "{}: NNSF worse than EPF by {d:.3} (se {se:.3})",
                s.name()
            );
        }
    }
}

/// On van–plane and walking men, built so that nearest neighbour to the last positions
/// Â(t−1) fails at frame 6 (Section 4's "NNSF would associate M₂ to T₁"), EPF is strictly
/// better than it: the paired difference is more than 2 standard errors below 0.
#[test]
fn epf_beats_nearest_to_the_last_position_where_section4_builds_it() {
    for s in [Scenario::VanPlane, Scenario::WalkingMen] {
        let (epf, nn, d, se) = paired(
            ScenarioConfig::new(s),
            200,
            7,
            Method::Epf,
            Method::NnPrevious,
        );
        assert!(
            d < -2.0 * se,
            "{}: EPF {epf:.3}, NN to Â(t−1) {nn:.3}, EPF − NN = {d:.3} ± {se:.3}",
            s.name()
        );
    }
}

/// Section 3: each target's filter resamples multinomially, in the adaptive way, when
/// N_eff falls below half the particles.
#[test]
fn resampling_is_adaptive_multinomial() {
    use pf_core::filter::{EssThreshold, ResamplePolicy};
    use pf_core::resample::Resampler;
    let fc = pf_epf::tracker::filter_config(&pf_epf::tracker::TrackerConfig::default());
    assert_eq!(fc.resampler, Resampler::Multinomial);
    assert_eq!(
        fc.policy,
        ResamplePolicy::EssBelow(EssThreshold::Fraction(0.5))
    );
}

/// REC curves from tracking errors are monotone, start at 0 for zero tolerance (errors are
/// continuous, so none is exactly 0 almost surely) and reach 1 at the largest error.
#[test]
fn rec_curves_are_monotone_from_zero_to_one() {
    let mut cfg = ComparisonConfig {
        seed: 3,
        ..ComparisonConfig::new(ScenarioConfig::new(Scenario::Ants), 10)
    };
    cfg.tracker.n_particles = 100;
    cfg.methods = vec![Method::Epf, Method::Nnsf];
    let c = compare(&cfg).unwrap();
    for m in &c.methods {
        for errs in &m.errors_per_target {
            let max = errs.iter().copied().fold(0.0, f64::max);
            let mut grid = pf_core::metrics::tolerance_grid(max, 101);
            // `max·100/100` can round one ulp below `max`; end the grid exactly on it.
            *grid.last_mut().unwrap() = max;
            let rec = rec_of(errs, &grid).unwrap();
            assert_eq!(rec.accuracy[0], 0.0, "accuracy at zero tolerance");
            assert_eq!(
                *rec.accuracy.last().unwrap(),
                1.0,
                "accuracy at the largest error"
            );
            assert!(rec.accuracy.windows(2).all(|w| w[0] <= w[1]), "monotone");
        }
    }
}

/// The report's experiment gives the same numbers on one thread as on the rayon pool (their
/// serialised forms, which leave out where the replications ran, are equal), calls
/// `tick` as often as `ticks` says, and its REC curves, pooled on one grid, reach 1.
#[test]
fn section4_is_the_same_on_any_thread_count() {
    use pf_core::mc::{Par, Scale};
    use pf_epf::experiments::{Section4Config, section4, section4_with_progress};
    use std::sync::atomic::{AtomicU64, Ordering};

    let cfg = Section4Config {
        seed: 11,
        ..Section4Config::at_scale(Scale::Quick)
    };
    let ticks = AtomicU64::new(0);
    let pooled = section4_with_progress(&cfg, &|| {
        ticks.fetch_add(1, Ordering::Relaxed);
    })
    .unwrap();
    assert_eq!(ticks.into_inner(), cfg.ticks());
    let alone = section4(&Section4Config {
        par: Par::Seq,
        ..cfg.clone()
    })
    .unwrap();
    let json = |r| serde_json::to_value(r).unwrap();
    assert!(json(&pooled) == json(&alone), "the results differ");
    assert_eq!(pooled.scenarios.len(), Scenario::ALL.len());
    for s in &pooled.scenarios {
        assert_eq!(s.comparisons.len(), cfg.variants.len());
        assert_eq!(s.rec.len(), 2 * s.truth.len(), "EPF and NNSF per target");
        for r in &s.rec {
            assert_eq!(r.curve.accuracy.last(), Some(&1.0), "{:?}", s.scenario);
        }
    }
}

/// Eq. (1) term by term at a frame where EPF goes wrong: the table holds a target given
/// another target's detection, that detection's E is the least among the targets gating it
/// (the per-measurement rule), and every row's terms recompose E.
#[test]
fn the_wrong_frame_table_recomposes_eq_1() {
    use pf_epf::experiments::{first_wrong_frame, tracker_for};
    let s = Scenario::WalkingMen;
    let mut tracker = tracker_for(s);
    tracker.n_particles = 100;
    // The paper's one-round association (re-acquisition lets targets without a detection
    // at their previous step choose second, among the detections left).
    tracker.reacquire = false;
    let w = first_wrong_frame(ScenarioConfig::new(s), &tracker, 50, 3, s.key_frame())
        .unwrap()
        .expect("EPF goes wrong in one of 50 walking-men runs");
    assert!(w.frame >= s.key_frame());
    let wrong = w
        .rows
        .iter()
        .find(|r| r.assigned && r.source >= 0 && r.source != r.target)
        .expect("a target given another target's detection");
    let rivals: Vec<_> = w
        .rows
        .iter()
        .filter(|r| r.source == wrong.source && r.gated && r.target != wrong.target)
        .collect();
    assert!(
        !rivals.is_empty(),
        "another target gates the detection: {wrong:?}"
    );
    for r in rivals {
        assert!(
            wrong.terms.e <= r.terms.e,
            "eq. (1): {wrong:?} against {r:?}"
        );
    }
    for r in &w.rows {
        let t = &r.terms;
        for l in 0..3 {
            assert!((t.weighted[l] - (t.alpha[l] * t.raw[l]).min(1.0)).abs() < 1e-12);
        }
        let e = (t.weighted.iter().map(|x| x * x).sum::<f64>() / 3.0).sqrt();
        assert!((t.e - e).abs() < 1e-12);
    }
}
