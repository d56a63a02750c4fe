//! `pf-viz homotopy …` end to end: the JSON contracts and the one-line errors.

mod common;

use common::{one_line_error, pf_viz, pf_viz_ok};

/// Runs a `--json` command and parses its stdout as one JSON value (without the one-line
/// check of `common::pf_viz_json`).
fn json(args: &[&str]) -> serde_json::Value {
    serde_json::from_slice(&pf_viz_ok(args).stdout).expect("one JSON object on stdout")
}

#[test]
fn rmse_keeps_the_contract() {
    let rmse = [
        "homotopy",
        "rmse",
        "--realisations",
        "2",
        "--particles",
        "500",
        "--seed",
        "4",
        "--json",
    ];
    let v = json(&rmse);
    let n = v["time"].as_array().unwrap().len();
    assert!(n >= 17, "the scenario runs past the manoeuvre");
    for alg in ["OHF", "AOHF", "UKF-LPC", "PF"] {
        let e = v["rmse"][alg].as_array().unwrap();
        assert_eq!(e.len(), n, "{alg}");
        assert!(e.iter().all(|x| x.as_f64().unwrap() >= 0.0), "{alg}");
        let s = v["seconds_per_run"][alg].as_f64().unwrap();
        assert!(s.is_finite() && s > 0.0, "{alg}: {s}");
        // One final error per realisation, whose mean square is the last RMS error.
        let f: Vec<f64> = v["final_errors"][alg]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        assert_eq!(f.len(), 2, "{alg}");
        let ms = f.iter().map(|x| x * x).sum::<f64>() / 2.0;
        let last = e[n - 1].as_f64().unwrap();
        assert!(
            (ms.sqrt() - last).abs() <= 1e-9 * last,
            "{alg}: {f:?} against {last}"
        );
    }
    // Same seed, same errors.
    let w = json(&rmse);
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
        (
            &["homotopy", "ellipses", "--step", "99"][..],
            "K = 99 is outside 2..=40",
        ),
        (
            &["homotopy", "ellipses", "--step", "1"][..],
            "K = 1 is outside 2..=40",
        ),
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
        // A negative number is the option's value (and fails its range check), not a flag.
        (
            &["homotopy", "ellipses", "--sigma-deg", "-1"][..],
            "sigma_deg = -1",
        ),
    ] {
        let o = pf_viz(args);
        assert!(o.stdout.is_empty(), "{args:?}: nothing on stdout");
        one_line_error(&o, &format!("{args:?}"), &[needle]);
    }
}
