//! `pf-viz homotopy …` end to end: the JSON contracts and the one-line errors.

use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_pf-viz");

fn pf_viz(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().expect("run pf-viz")
}

fn json(args: &[&str]) -> serde_json::Value {
    let o = pf_viz(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).expect("one JSON object on stdout")
}

#[test]
fn rmse_keeps_the_contract() {
    let v = json(&[
        "homotopy",
        "rmse",
        "--realisations",
        "2",
        "--particles",
        "500",
        "--seed",
        "4",
        "--json",
    ]);
    let n = v["time"].as_array().unwrap().len();
    assert!(n >= 17, "the scenario runs past the manoeuvre");
    for alg in ["OHF", "AOHF", "UKF-LPC", "PF"] {
        let e = v["rmse"][alg].as_array().unwrap();
        assert_eq!(e.len(), n, "{alg}");
        assert!(e.iter().all(|x| x.as_f64().unwrap() >= 0.0), "{alg}");
        let s = v["seconds_per_run"][alg].as_f64().unwrap();
        assert!(s.is_finite() && s > 0.0, "{alg}: {s}");
    }
    // Same seed, same errors.
    let w = json(&[
        "homotopy",
        "rmse",
        "--realisations",
        "2",
        "--particles",
        "500",
        "--seed",
        "4",
        "--json",
    ]);
    assert_eq!(v["rmse"], w["rmse"]);
}

#[test]
fn ellipses_keep_the_contract_and_shrink_across_the_line_of_sight() {
    let v = json(&["homotopy", "ellipses", "--step", "17", "--json"]);
    let truth = v["truth"].as_array().unwrap();
    assert_eq!(truth.len(), 2);
    let lambda: Vec<f64> = v["lambda"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(lambda, [0.0, 0.25, 0.5, 0.75, 1.0]);
    let ell = v["ellipses"].as_array().unwrap();
    assert_eq!(ell.len(), lambda.len());
    for e in ell {
        assert_eq!(e["center"].as_array().unwrap().len(), 2);
        let a = e["semi_axes"].as_array().unwrap();
        assert!(a[0].as_f64().unwrap() >= a[1].as_f64().unwrap());
        assert!(e["angle"].as_f64().unwrap().is_finite());
    }
    // The posterior (λ = 1) is no wider across the line of sight than the prior (λ = 0).
    let minor = |e: &serde_json::Value| e["semi_axes"][1].as_f64().unwrap();
    assert!(minor(&ell[4]) <= minor(&ell[0]) * 1.0001);
}

#[test]
fn bad_arguments_get_one_line() {
    for (args, needle) in [
        (&["homotopy", "ellipses", "--step", "99"][..], "step"),
        (&["homotopy", "ellipses", "--step", "1"][..], "step"),
        (
            &["homotopy", "rmse", "--realisations", "0"][..],
            "realisation",
        ),
        (
            &[
                "homotopy",
                "rmse",
                "--realisations",
                "1",
                "--particles",
                "0",
            ][..],
            "particle",
        ),
        (&["homotopy", "rmse", "--scale", "huge"][..], "huge"),
        (&["homotopy", "rmse", "--turn", "left"][..], "left"),
        (&["homotopy", "ellipses", "--sigma-deg", "0"][..], "sigma"),
        (&["homotopy", "ellipses", "--sigma-deg", "NaN"][..], "sigma"),
    ] {
        let o = pf_viz(args);
        assert!(!o.status.success(), "{args:?}");
        assert!(o.stdout.is_empty());
        let stderr = String::from_utf8(o.stderr).unwrap();
        assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr:?}");
        assert!(stderr.contains(needle), "{args:?}: {stderr:?}");
    }
}
