//! `pf-viz smooth em|sem|score` as other tools call them: JSON contracts and bad inputs.

use std::path::PathBuf;
use std::process::{Command, Output};

fn pf_viz(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pf-viz"))
        .args(args)
        .output()
        .expect("pf-viz runs")
}

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("pf-viz-smooth-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn file(name: &str, text: &str) -> String {
    let p = dir().join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

/// A short AR(1)-like series with an extra column, n = 30.
fn data() -> String {
    let mut s = String::from("t,y\n");
    let mut x: f64 = 0.0;
    for k in 0..31 {
        x = 0.98 * x + 0.2 * ((k as f64) * 1.7).sin();
        s.push_str(&format!("{k},{}\n", x + ((k as f64) * 2.3).cos()));
    }
    file("ok.csv", &s)
}

fn json(o: &Output) -> serde_json::Value {
    assert!(
        o.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let out = String::from_utf8(o.stdout.clone()).unwrap();
    assert_eq!(out.trim().lines().count(), 1, "one JSON object: {out}");
    serde_json::from_str(&out).unwrap()
}

fn floats(v: &serde_json::Value, len: usize) {
    let a = v.as_array().expect("array");
    assert_eq!(a.len(), len);
    assert!(a.iter().all(|x| x.as_f64().is_some_and(f64::is_finite)));
}

const THETA: [&str; 6] = ["--phi", "0.8", "--sigma", "0.5", "--rho", "2"];

#[test]
fn em_keeps_its_json_contract() {
    let d = data();
    let mut args = vec!["smooth", "em", "--data", &d];
    args.extend(THETA);
    args.extend(["--particles", "20", "--replications", "3", "--seed", "1"]);
    let v = json(&pf_viz(&[args.as_slice(), &["--json"]].concat()));
    assert_eq!(v["n"], 30);
    for k in ["phi", "sigma2", "rho2"] {
        assert!(v["exact"][k].as_f64().is_some_and(f64::is_finite));
        floats(&v["joint"][k], 3);
    }
    assert!(v.get("fixed_lag").is_none(), "fixed_lag only with --lag");
    let v = json(&pf_viz(
        &[args.as_slice(), &["--lag", "5", "--json"]].concat(),
    ));
    for k in ["phi", "sigma2", "rho2"] {
        floats(&v["fixed_lag"][k], 3);
    }
    // Same seed, same numbers; and a readable summary without --json.
    let again = json(&pf_viz(
        &[args.as_slice(), &["--lag", "5", "--json"]].concat(),
    ));
    assert_eq!(v, again);
    let o = pf_viz(&[args.as_slice(), &["--lag", "5"]].concat());
    assert!(o.status.success());
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(
        text.contains("exact") && text.contains("fixed-lag"),
        "{text}"
    );
}

#[test]
fn sem_and_score_keep_their_json_contracts() {
    let d = data();
    let mut args = vec!["smooth", "sem", "--data", &d];
    args.extend(THETA);
    args.extend(["--particles", "10", "--iterations", "3", "--chains", "2"]);
    args.push("--json");
    let v = json(&pf_viz(&args));
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
    let v = json(&pf_viz(&args));
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
    assert!(!o.status.success(), "{args:?} should fail");
    assert!(o.stdout.is_empty(), "nothing on stdout on error");
    let err = String::from_utf8(o.stderr).unwrap();
    assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
    assert!(err.starts_with("error:"), "{err}");
    for n in needles {
        assert!(err.contains(n), "{err} should contain {n}");
    }
}

#[test]
fn bad_inputs_get_one_line_errors_naming_file_line_and_problem() {
    let ok = data();
    let missing = dir().join("does-not-exist.csv").display().to_string();
    fails(&missing, ("", ""), &["does-not-exist.csv"]);
    let noy = file("noy.csv", "t,x\n0,1\n1,2\n");
    fails(&noy, ("", ""), &["noy.csv", "line 1", "`y`"]);
    let text = file("text.csv", "t,y\n0,1\n1,abc\n2,3\n");
    fails(&text, ("", ""), &["text.csv", "line 3", "abc"]);
    let nan = file("nan.csv", "y\n1\n2\nNaN\n");
    fails(&nan, ("", ""), &["nan.csv", "line 4", "finite"]);
    let short = file("short.csv", "y\n1\n");
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
