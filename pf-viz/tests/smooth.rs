//! `pf-viz smooth em|sem|score` as other tools call them: JSON contracts and bad inputs.

mod common;

use common::{Scratch, one_line_error, pf_viz, pf_viz_json};

/// Writes a short AR(1)-like series with an extra column, n = 30, into `dir`.
fn data(dir: &Scratch) -> String {
    let mut s = String::from("t,y\n");
    let mut x: f64 = 0.0;
    for k in 0..31 {
        x = 0.98 * x + 0.2 * ((k as f64) * 1.7).sin();
        s.push_str(&format!("{k},{}\n", x + ((k as f64) * 2.3).cos()));
    }
    dir.file("ok.csv", &s)
}

fn floats(v: &serde_json::Value, len: usize) {
    let a = v.as_array().expect("array");
    assert_eq!(a.len(), len);
    assert!(a.iter().all(|x| x.as_f64().is_some_and(f64::is_finite)));
}

const THETA: [&str; 6] = ["--phi", "0.8", "--sigma", "0.5", "--rho", "2"];

#[test]
fn em_keeps_its_json_contract() {
    let s = Scratch::new("em");
    let d = data(&s);
    let mut args = vec!["smooth", "em", "--data", &d];
    args.extend(THETA);
    args.extend(["--particles", "20", "--replications", "3", "--seed", "1"]);
    let v = pf_viz_json(&[args.as_slice(), &["--json"]].concat());
    assert_eq!(v["n"], 30);
    for k in ["phi", "sigma2", "rho2"] {
        assert!(v["exact"][k].as_f64().is_some_and(f64::is_finite));
        floats(&v["joint"][k], 3);
    }
    assert!(v.get("fixed_lag").is_none(), "fixed_lag only with --lag");
    let v = pf_viz_json(&[args.as_slice(), &["--lag", "5", "--json"]].concat());
    for k in ["phi", "sigma2", "rho2"] {
        floats(&v["fixed_lag"][k], 3);
    }
    // Same seed, same numbers; and a readable summary without --json.
    let again = pf_viz_json(&[args.as_slice(), &["--lag", "5", "--json"]].concat());
    assert_eq!(v, again);
    let o = pf_viz(&[args.as_slice(), &["--lag", "5"]].concat());
    assert!(o.status.success());
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(
        text.contains("exact") && text.contains("fixed-lag"),
        "{text}"
    );
}

/// `--forward` adds forward-only smoothing from the same particle runs: the joint updates
/// are those of the run without it, to the last bit (the smoother draws nothing).
#[test]
fn em_forward_adds_its_key_and_leaves_the_rest_alone() {
    let s = Scratch::new("em-forward");
    let d = data(&s);
    let mut args = vec!["smooth", "em", "--data", &d];
    args.extend(THETA);
    args.extend(["--particles", "20", "--replications", "3", "--lag", "5"]);
    let without = pf_viz_json(&[args.as_slice(), &["--json"]].concat());
    assert!(
        without.get("forward").is_none(),
        "forward only with --forward"
    );
    let with = pf_viz_json(&[args.as_slice(), &["--forward", "--json"]].concat());
    for k in ["phi", "sigma2", "rho2"] {
        floats(&with["forward"][k], 3);
    }
    for k in ["n", "exact", "joint", "fixed_lag"] {
        assert_eq!(with[k], without[k], "{k}");
    }
    let o = pf_viz(&[args.as_slice(), &["--forward"]].concat());
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(
        o.status.success() && text.contains("forward-only"),
        "{text}"
    );
}

#[test]
fn sem_and_score_keep_their_json_contracts() {
    let s = Scratch::new("sem-score");
    let d = data(&s);
    let mut args = vec!["smooth", "sem", "--data", &d];
    args.extend(THETA);
    args.extend(["--particles", "10", "--iterations", "3", "--chains", "2"]);
    args.push("--json");
    let v = pf_viz_json(&args);
    let exact = v["exact"].as_array().unwrap();
    assert_eq!(exact.len(), 4, "starting point first, then 3 iterations");
    assert_eq!(exact[0]["phi"], 0.8);
    assert_eq!(exact[0]["sigma2"], 0.25);
    assert_eq!(exact[0]["rho2"], 4.0);
    let sem = v["sem"].as_array().unwrap();
    assert_eq!(sem.len(), 2);
    for chain in sem {
        let c = chain.as_array().unwrap();
        assert_eq!(c.len(), 4);
        assert!(c[3]["sigma2"].as_f64().unwrap() > 0.0);
    }

    let mut args = vec!["smooth", "score", "--data", &d];
    args.extend(THETA);
    args.extend(["--particles", "20", "--replications", "4", "--json"]);
    let v = pf_viz_json(&args);
    for k in ["phi", "sigma2", "rho2"] {
        assert!(v["exact"][k].as_f64().is_some_and(f64::is_finite));
        floats(&v["particle"][k], 4);
    }
}

/// Runs `smooth em` with one argument replaced and checks a one-line error naming `needle`.
fn fails(data: &str, replace: (&str, &str), needles: &[&str]) {
    let mut args: Vec<String> = ["smooth", "em", "--data", data]
        .iter()
        .chain(THETA.iter())
        .chain(["--particles", "10", "--replications", "2", "--json"].iter())
        .map(|s| s.to_string())
        .collect();
    if let Some(i) = args.iter().position(|a| a == replace.0) {
        args[i + 1] = replace.1.to_string();
    }
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = pf_viz(&refs);
    assert!(o.stdout.is_empty(), "nothing on stdout on error");
    let err = one_line_error(&o, &format!("{args:?}"), needles);
    assert!(err.starts_with("error:"), "{err}");
}

#[test]
fn bad_inputs_get_one_line_errors_naming_file_line_and_problem() {
    let s = Scratch::new("errors");
    let ok = data(&s);
    let missing = s.path("does-not-exist.csv");
    fails(&missing, ("", ""), &["does-not-exist.csv"]);
    let noy = s.file("noy.csv", "t,x\n0,1\n1,2\n");
    fails(&noy, ("", ""), &["noy.csv", "line 1", "`y`"]);
    let text = s.file("text.csv", "t,y\n0,1\n1,abc\n2,3\n");
    fails(&text, ("", ""), &["text.csv", "line 3", "abc"]);
    let nan = s.file("nan.csv", "y\n1\n2\nNaN\n");
    fails(&nan, ("", ""), &["nan.csv", "line 4", "finite"]);
    let short = s.file("short.csv", "y\n1\n");
    fails(&short, ("", ""), &["short.csv", "at least 2"]);
    fails(&ok, ("--sigma", "0"), &["sigma"]);
    fails(&ok, ("--sigma", "-1"), &["sigma"]);
    fails(&ok, ("--rho", "0"), &["rho"]);
    fails(&ok, ("--rho", "-2"), &["rho"]);
    fails(&ok, ("--particles", "0"), &["particles"]);
    fails(&ok, ("--replications", "0"), &["replications"]);
    fails(&ok, ("--phi", "NaN"), &["phi"]);
    let mut args = vec!["smooth", "em", "--data", &ok];
    args.extend(THETA);
    args.extend(["--particles", "5", "--replications", "1", "--lag", "0"]);
    let o = pf_viz(&args);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("lag"));
}
