//! End-to-end checks of `pf-viz homotopy rmse|ellipses`: the JSON contract and bad arguments.

use std::process::{Command, Output};

use serde_json::Value;

const BIN: &str = env!("CARGO_BIN_EXE_pf-viz");

fn pf_viz(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().expect("run pf-viz")
}

/// Exactly one JSON object on stdout, exit 0.
fn json(args: &[&str]) -> Value {
    let out = pf_viz(args);
    assert!(
        out.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(stdout.trim_end().lines().count(), 1, "one line: {stdout}");
    serde_json::from_str(&stdout).expect("stdout is JSON")
}

/// Exit 1 with one `error: …` line on stderr mentioning `needle`, nothing on stdout.
fn fails(args: &[&str], needle: &str) {
    let out = pf_viz(args);
    assert_eq!(out.status.code(), Some(1), "{args:?} should fail");
    assert!(out.stdout.is_empty(), "nothing on stdout");
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    assert!(err.starts_with("error: "), "{err}");
    assert!(err.contains(needle), "{err} should mention {needle}");
}

fn numbers(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

#[test]
fn rmse_json_has_the_contract_shape() {
    let v = json(&[
        "homotopy",
        "rmse",
        "--realisations",
        "2",
        "--particles",
        "500",
        "--seed",
        "3",
        "--json",
    ]);
    let time = numbers(&v["time"]);
    assert_eq!(time[0], 0.0);
    assert!(time.windows(2).all(|w| w[1] > w[0]), "time increases");
    for alg in ["OHF", "AOHF", "UKF-LPC", "PF"] {
        let r = numbers(&v["rmse"][alg]);
        assert_eq!(r.len(), time.len(), "{alg}: one RMS per instant");
        assert!(r.iter().all(|x| x.is_finite() && *x >= 0.0), "{alg}: {r:?}");
        let s = v["seconds_per_run"][alg].as_f64().expect("seconds");
        assert!(s.is_finite() && s >= 0.0, "{alg}: {s}");
    }
    // Same seed, same numbers (times aside).
    let w = json(&[
        "homotopy",
        "rmse",
        "--realisations",
        "2",
        "--particles",
        "500",
        "--seed",
        "3",
        "--json",
    ]);
    assert_eq!(v["rmse"], w["rmse"]);
}

#[test]
fn ellipses_json_has_the_contract_shape() {
    let v = json(&[
        "homotopy", "ellipses", "--step", "17", "--seed", "1", "--json",
    ]);
    let truth = numbers(&v["truth"]);
    assert_eq!(truth.len(), 2);
    let lambda = numbers(&v["lambda"]);
    assert_eq!(lambda, vec![0.0, 0.25, 0.5, 0.75, 1.0]);
    let ells = v["ellipses"].as_array().expect("ellipses");
    assert_eq!(ells.len(), lambda.len());
    for e in ells {
        assert_eq!(numbers(&e["center"]).len(), 2, "key is `center`: {e}");
        let ax = numbers(&e["semi_axes"]);
        assert!(ax.len() == 2 && ax[0] >= ax[1] && ax[1] > 0.0, "{ax:?}");
        assert!(e["angle"].as_f64().expect("angle").is_finite());
    }
    // λ = 0 is the prediction, λ = 1 the posterior: the bearing shrinks the ellipse.
    let a0 = numbers(&ells[0]["semi_axes"]);
    let a1 = numbers(&ells[4]["semi_axes"]);
    assert!(a1[0] * a1[1] < a0[0] * a0[1], "{a0:?} -> {a1:?}");
}

#[test]
fn ellipses_rejects_steps_outside_the_scenario() {
    fails(
        &["homotopy", "ellipses", "--step", "99", "--json"],
        "--step",
    );
    fails(&["homotopy", "ellipses", "--step", "1", "--json"], "--step");
    fails(&["homotopy", "ellipses", "--step", "0"], "--step");
}

#[test]
fn rmse_rejects_zero_sizes() {
    fails(
        &["homotopy", "rmse", "--realisations", "0", "--json"],
        "--realisations",
    );
    fails(
        &[
            "homotopy",
            "rmse",
            "--realisations",
            "1",
            "--particles",
            "0",
            "--json",
        ],
        "--particles",
    );
}

#[test]
fn malformed_arguments_are_usage_errors() {
    let out = pf_viz(&["homotopy", "rmse", "--realisations", "-3"]);
    assert!(!out.status.success());
    assert!(out.stdout.is_empty());
    let out = pf_viz(&["homotopy", "ellipses", "--step", "x"]);
    assert!(!out.status.success());
}
