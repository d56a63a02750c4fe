//! Fig. 1's coalescence, measured over seeded runs of the N = 50 filter on Section 5's data.

use pf_core::resample::Resampler;
use pf_smooth::Theta;
use pf_smooth::experiments::{
    CoalescenceConfig, CoalescenceResult, CoalescenceSetting, Scale, coalescence,
};

fn run(runs: usize, particles: usize, theta: Theta) -> CoalescenceResult {
    let settings = [Resampler::Systematic, Resampler::Multinomial]
        .map(|resampler| CoalescenceSetting {
            label: "test".into(),
            theta,
            resampler,
        })
        .to_vec();
    coalescence(&CoalescenceConfig {
        particles,
        runs,
        settings,
        seed: 17,
        ..CoalescenceConfig::at_scale(Scale::Quick)
    })
    .unwrap()
}

/// Two binomial shares of `r` runs differ by more than 4 standard errors of their
/// difference (the share's variance `p (1 − p) / r`, with `p` floored at `1/r` so that a
/// share of 0 or 1 still counts as uncertain).
fn clearly_above(hi: f64, lo: f64, r: usize) -> bool {
    let r = r as f64;
    let var =
        |p: f64| p.clamp(1.0 / r, 1.0 - 1.0 / r) * (1.0 - p.clamp(1.0 / r, 1.0 - 1.0 / r)) / r;
    hi - lo > 4.0 * (var(hi) + var(lo)).sqrt()
}

/// Multinomial resampling coalesces much sooner than systematic: at both θ, the share of
/// runs whose 50 paths share an ancestor within 100 steps is larger under multinomial,
/// beyond 4 standard errors of 100 seeded runs each, and so is the median delay.
#[test]
fn multinomial_paths_coalesce_sooner_than_systematic_ones() {
    for theta in [Theta::paper_truth(), Theta::paper_start()] {
        let r = run(100, 50, theta);
        let (sys, mult) = (&r.rows[0], &r.rows[1]);
        assert!(
            clearly_above(mult.within_window, sys.within_window, 100),
            "within 100 steps: multinomial {} against systematic {}",
            mult.within_window,
            sys.within_window
        );
        let median = |q: &[Option<usize>; 5]| q[2].unwrap_or(usize::MAX);
        assert!(median(&mult.quantiles) < median(&sys.quantiles), "{r:?}");
    }
}

/// The mechanism: under multinomial resampling two lineages merge at step k with
/// probability exactly `E[Σ_i ν_i (ν_i − 1)] / (N (N − 1)) = Σ_i W_i²`, so the runs' mean
/// merge rate equals their mean `Σ W²` within 4 standard errors of the per-run differences;
/// systematic resampling merges at well under half that rate on the same weights.
#[test]
fn multinomial_merges_lineages_at_the_rate_sum_w2_and_systematic_far_below() {
    let r = run(60, 50, Theta::paper_truth());
    let (sys, mult) = (&r.rows[0], &r.rows[1]);
    let d: Vec<f64> = mult.runs.iter().map(|x| x.merge_rate - x.sum_w2).collect();
    let (mean, se) = pf_core::mc::mean_and_se(&d);
    assert!(mean.abs() < 4.0 * se, "merge rate − Σ W²: {mean} ± {se}");
    assert!(
        sys.merge_rate < 0.5 * sys.sum_w2,
        "{} against {}",
        sys.merge_rate,
        sys.sum_w2
    );
}

/// The known O(N) growth of the coalescence delay under multinomial resampling (Kingman:
/// `E[τ] ≈ 2 (1 − 1/N) / c̄` with `c̄ = E[1/ESS]`). ESS/N is about 0.88 at every N here, so
/// quadrupling N from 25 to 100 divides the merge rate by 4 (within 10 %: the per-run rates
/// vary by under 2 %), and the median delay should grow about 4-fold. Kingman's delay has
/// sd ≈ 0.54 of its mean, so the median of 60 runs is within about 9 % of its own: a ratio
/// above 2 is more than 4 of those errors below the expected 4.
#[test]
fn multinomial_delay_grows_with_n() {
    let small = run(60, 25, Theta::paper_truth());
    let big = run(60, 100, Theta::paper_truth());
    let ratio = small.rows[1].merge_rate / big.rows[1].merge_rate;
    assert!((ratio / 4.0 - 1.0).abs() < 0.1, "merge-rate ratio {ratio}");
    // N = 25 must coalesce within the window; a censored median at N = 100 (more than
    // half the runs not coalesced) is a delay longer than the window, so it counts as large.
    assert!(
        small.rows[1].quantiles[2].is_some(),
        "N = 25: no median delay"
    );
    let med = |r: &CoalescenceResult| r.rows[1].quantiles[2].unwrap_or(usize::MAX) as f64;
    assert!(
        med(&big) > 2.0 * med(&small),
        "{} against {}",
        med(&big),
        med(&small)
    );
}
