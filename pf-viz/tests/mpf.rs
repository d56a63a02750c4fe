//! `pf-viz mpf …` end to end: the JSON contracts and the one-line errors.

mod common;

use common::{one_line_error, pf_viz, pf_viz_json};

#[test]
fn calibrate_gives_positive_finite_coefficients() {
    let v = pf_viz_json(&["mpf", "calibrate", "--quick", "--json"]);
    for key in ["flop_ns", "c1", "c2", "c3"] {
        let x = v[key].as_f64().unwrap_or_else(|| panic!("{key} missing"));
        assert!(x.is_finite() && x > 0.0, "{key} = {x}");
    }
}

#[test]
fn ratio_reproduces_the_papers_worked_number() {
    let v = pf_viz_json(&["mpf", "ratio", "--json"]);
    let m: Vec<u64> = v["m"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect();
    assert_eq!(m, (3..=9).collect::<Vec<u64>>());
    let curves = v["curves"].as_array().unwrap();
    assert_eq!(curves.len(), 7, "k = 1 … m_max − n");
    for c in curves {
        let k = c["k"].as_u64().unwrap();
        for key in ["ct_zero", "ct_nonzero"] {
            let ys = c[key].as_array().unwrap();
            assert_eq!(ys.len(), 7);
            for (j, y) in ys.iter().enumerate() {
                // Defined only where k ≤ m − n.
                assert_eq!(y.is_null(), k > m[j] - 2, "k = {k}, m = {}", m[j]);
            }
        }
    }
    // Section IV: m = 6, k = 4 buys 1.44 times the particles (C_t = 0).
    let r = curves[3]["ct_zero"][3].as_f64().unwrap();
    assert!((r - 1.44).abs() < 0.005, "N(4)/N_PF = {r}");
}

#[test]
fn tables_keep_the_contract() {
    for cmd in ["table2", "table3"] {
        let v = pf_viz_json(&[
            "mpf", cmd, "--scale", "quick", "--mc", "2", "--seed", "3", "--json",
        ]);
        let rows = v["partitions"].as_array().unwrap();
        let names: Vec<&str> = rows.iter().map(|r| r["name"].as_str().unwrap()).collect();
        assert_eq!(names, ["PPPPPP", "PPKKPP", "PPPPKK", "PPKKKK"]);
        for r in rows {
            assert!(r["N"].as_u64().unwrap() >= 1);
            for key in ["rmse_pos", "rmse_vel", "rmse_acc", "time_s"] {
                let x = r[key].as_f64().unwrap();
                assert!(x.is_finite() && x > 0.0, "{cmd} {key} = {x}");
            }
        }
        assert_eq!(v["paper"].as_array().unwrap().len(), 4);
    }
}

#[test]
fn advise_ranks_partitions() {
    let v = pf_viz_json(&[
        "mpf",
        "advise",
        "--p",
        "2",
        "--k",
        "4",
        "--particles",
        "2000",
        "--json",
    ]);
    let opts = v["options"].as_array().unwrap();
    assert_eq!(opts.len(), 5, "k = 0 … 4");
    let times: Vec<f64> = opts.iter().map(|o| o["time_s"].as_f64().unwrap()).collect();
    assert!(
        times.windows(2).all(|w| w[0] <= w[1]),
        "fastest first: {times:?}"
    );
    let v = pf_viz_json(&[
        "mpf",
        "advise",
        "--p",
        "2",
        "--k",
        "4",
        "--budget-s",
        "0.01",
        "--json",
    ]);
    let n: Vec<u64> = v["options"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| o["n_particles"].as_u64().unwrap())
        .collect();
    assert!(
        n.windows(2).all(|w| w[0] >= w[1]),
        "most particles first: {n:?}"
    );
}

#[test]
fn bad_input_gets_one_line_and_a_failure() {
    for (args, needle) in [
        (
            &["mpf", "advise", "--p", "0", "--k", "4", "--particles", "10"][..],
            "p = 0",
        ),
        // Neither size: the one line names both ways of giving one.
        (
            &["mpf", "advise", "--p", "2", "--k", "4"][..],
            "<--budget-s <F>|--particles <N>>",
        ),
        (
            &[
                "mpf",
                "advise",
                "--p",
                "2",
                "--k",
                "4",
                "--budget-s",
                "1",
                "--particles",
                "5",
            ][..],
            "cannot be used",
        ),
        (
            &["mpf", "advise", "--p", "2", "--k", "4", "--budget-s=-1"][..],
            "budget",
        ),
        (
            &["mpf", "advise", "--p", "2", "--k", "4", "--budget-s", "0"][..],
            "budget",
        ),
        (&["mpf", "table2", "--mc", "0"][..], "--mc"),
        (&["mpf", "table3", "--mc", "many"][..], "many"),
    ] {
        let o = pf_viz(args);
        assert!(o.stdout.is_empty(), "{args:?}: nothing on stdout");
        one_line_error(&o, &format!("{args:?}"), &[needle]);
    }
}
