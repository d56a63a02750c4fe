//! The filter checked against its own model (13): on data drawn from that model, the
//! normalised estimation error squared (NEES) has mean 1 and the residuals' sd equals the
//! posterior sd. Two bounds, both from the seeded runs:
//! - replications: each run's mean NEES is one independent value; their mean lies within
//!   4 standard errors (estimated from the runs) of 1;
//! - chi-square: NEES values 40 samples apart (the filter's `Q_o` and `ρ_o` errors forget
//!   within about 20 samples) are nearly independent and, for a Gaussian posterior, each is
//!   `χ²₁`; the mean of `n` of them is `χ²_n / n`, whose two-sided 1 − 10⁻⁴ interval
//!   (z = 3.89) they must meet. The joint NEES of `(Q_o, ρ_o)` is `χ²₂`, halved: `χ²_2n / 2n`.

use pf_dredge::experiments::{ConsistencyConfig, ConsistencyResult, MeanSe, Scale, consistency};

const Z: f64 = 3.89;

/// The two-sided interval of `χ²_n / n` at `z` by the Wilson–Hilferty approximation
/// (`(χ²_n/n)^{1/3}` is nearly normal with mean `1 − 2/(9n)` and variance `2/(9n)`).
fn chi2_mean_interval(n: usize, z: f64) -> (f64, f64) {
    let v = 2.0 / (9.0 * n as f64);
    let at = |s: f64| (1.0 - v + s * z * v.sqrt()).powi(3);
    (at(-1.0), at(1.0))
}

/// 24 data sets of 300 phase-3 samples, NEES kept every 40 samples (7 per run).
fn run(n_particles: usize) -> ConsistencyResult {
    let mut cfg = ConsistencyConfig::at_scale(Scale::Default);
    cfg.filter = cfg.filter.with_particles(n_particles);
    cfg.runs = 24;
    cfg.max_samples = Some(300);
    cfg.spacing = 40;
    let r = consistency(&cfg).unwrap();
    assert_eq!(r.spaced_count, 24 * 7);
    r
}

fn near_one(name: &str, m: MeanSe) {
    assert!(
        (m.mean - 1.0).abs() < 4.0 * m.se,
        "{name}: mean NEES {} ± {} is not 1",
        m.mean,
        m.se
    );
}

fn in_chi2(name: &str, v: f64, n: usize) {
    let (lo, hi) = chi2_mean_interval(n, Z);
    assert!(lo < v && v < hi, "{name}: NEES {v} outside ({lo}, {hi})");
}

/// At the paper's N = 1000, `Q_o` is consistent: NEES about 1, and the residuals' sd is the
/// posterior sd within 4 standard errors of their difference over the runs.
#[test]
fn the_filter_is_consistent_in_q_o_at_the_papers_n() {
    let r = run(1000);
    near_one("Q_o", r.q_o.nees);
    in_chi2("Q_o", r.spaced_nees_mean[0], r.spaced_count);
    let (res, post) = (r.q_o.residual_std, r.q_o.posterior_sd);
    assert!(
        (res.mean - post.mean).abs() < 4.0 * (res.se + post.se),
        "Q_o residual sd {res:?} against posterior sd {post:?}"
    );
}

/// With N = 10 000 the weighted mean and variance are the posterior's, and `ρ_o` and the
/// joint `(Q_o, ρ_o)` are consistent too (at N = 1000 the `ρ_o` NEES is about 1.3: the
/// Monte Carlo error of 1000 particles, see the crate README).
#[test]
fn the_filter_is_consistent_in_rho_o_and_jointly_with_many_particles() {
    let r = run(10_000);
    near_one("Q_o", r.q_o.nees);
    near_one("rho_o", r.rho_o.nees);
    near_one("joint / 2", r.joint_nees);
    in_chi2("Q_o", r.spaced_nees_mean[0], r.spaced_count);
    in_chi2("rho_o", r.spaced_nees_mean[1], r.spaced_count);
    in_chi2("joint / 2", r.spaced_nees_mean[2], 2 * r.spaced_count);
    let (res, post) = (r.rho_o.residual_std, r.rho_o.posterior_sd);
    assert!(
        (res.mean - post.mean).abs() < 4.0 * (res.se + post.se),
        "rho_o residual sd {res:?} against posterior sd {post:?}"
    );
}
