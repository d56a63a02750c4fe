//! `pf-viz smooth …` end to end: the JSON contracts, agreement with the exact answers, and
//! the one-line errors for bad input.

use std::path::PathBuf;
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_pf-viz");

fn pf_viz(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().expect("run pf-viz")
}

struct Scratch(PathBuf);

impl Scratch {
    fn new(tag: &str) -> Self {
        let d = std::env::temp_dir().join(format!("pf-viz-smooth-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        Scratch(d)
    }
    fn file(&self, name: &str, text: &str) -> String {
        let p = self.0.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_owned()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A deterministic AR(1)-like series of n + 1 values (a fixed pseudo-random sequence, so the
/// test needs no generator): `x_{k+1} = 0.9 x_k + e_k`, `y_k = x_k + f_k`.
fn series(n: usize) -> String {
    let mut s = String::from("y,other\n");
    let mut x = 0.0f64;
    for k in 0..=n {
        let e = ((k * 7919 % 101) as f64 / 101.0 - 0.5) * 0.6;
        let f = ((k * 104729 % 97) as f64 / 97.0 - 0.5) * 2.0;
        s.push_str(&format!("{},{k}\n", x + f));
        x = 0.9 * x + e;
    }
    s
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

const THETA: [&str; 6] = ["--phi", "0.8", "--sigma", "0.5", "--rho", "2"];

#[test]
fn em_keeps_the_contract_and_brackets_the_exact_update() {
    let s = Scratch::new("em");
    let data = s.file("y.csv", &series(100));
    let mut args = vec!["smooth", "em", "--data", &data];
    args.extend(THETA);
    args.extend([
        "--particles",
        "200",
        "--replications",
        "8",
        "--lag",
        "10",
        "--json",
    ]);
    let v = json(&args);
    assert_eq!(v["n"], 100);
    for p in ["phi", "sigma2", "rho2"] {
        let exact = v["exact"][p].as_f64().unwrap();
        for est in ["joint", "fixed_lag"] {
            let xs: Vec<f64> = v[est][p]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            assert_eq!(xs.len(), 8, "{est}.{p}");
            // The replications scatter around the exact update: it lies within the range
            // widened by the spread (a generous, assumption-light bound).
            let (lo, hi) = xs
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                    (a.min(x), b.max(x))
                });
            let w = (hi - lo).max(1e-3);
            assert!(
                exact > lo - w && exact < hi + w,
                "{est}.{p}: exact {exact} vs [{lo}, {hi}]"
            );
        }
    }
    // Without --lag there is no fixed_lag key.
    let mut args = vec!["smooth", "em", "--data", &data];
    args.extend(THETA);
    args.extend(["--particles", "50", "--replications", "2", "--json"]);
    assert!(json(&args).get("fixed_lag").is_none());
}

#[test]
fn sem_and_score_keep_the_contract() {
    let s = Scratch::new("sem");
    let data = s.file("y.csv", &series(60));
    let mut args = vec!["smooth", "sem", "--data", &data];
    args.extend(THETA);
    args.extend([
        "--particles",
        "25",
        "--iterations",
        "4",
        "--chains",
        "3",
        "--json",
    ]);
    let v = json(&args);
    let exact = v["exact"].as_array().unwrap();
    assert_eq!(exact.len(), 5, "starting point and four iterations");
    assert_eq!(exact[0]["phi"].as_f64().unwrap(), 0.8);
    assert!((exact[0]["rho2"].as_f64().unwrap() - 4.0).abs() < 1e-12);
    let chains = v["sem"].as_array().unwrap();
    assert_eq!(chains.len(), 3);
    assert!(chains.iter().all(|c| c.as_array().unwrap().len() == 5));

    let mut args = vec!["smooth", "score", "--data", &data];
    args.extend(THETA);
    args.extend(["--particles", "300", "--replications", "6", "--json"]);
    let v = json(&args);
    for p in ["phi", "sigma2", "rho2"] {
        assert!(v["exact"][p].as_f64().unwrap().is_finite());
        assert_eq!(v["particle"][p].as_array().unwrap().len(), 6);
    }
}

#[test]
fn bad_input_gets_one_line_naming_the_problem() {
    let s = Scratch::new("bad");
    let good = s.file("good.csv", &series(10));
    let no_y = s.file("no-y.csv", "x\n1\n2\n3\n");
    let nan = s.file("nan.csv", "y\n1.0\nNaN\n2.0\n");
    let text = s.file("text.csv", "y\n1.0\nabc\n");
    let short = s.file("short.csv", "y\n1.0\n");
    // `extra` replaces the defaults of the flags it names (clap rejects repeated flags).
    let run = |data: &str, extra: &[&str]| {
        let mut args = vec!["smooth", "em", "--data", data];
        let defaults = [
            ("--phi", "0.8"),
            ("--sigma", "0.5"),
            ("--rho", "2"),
            ("--particles", "10"),
            ("--replications", "2"),
        ];
        for (flag, value) in defaults {
            let v = extra
                .iter()
                .position(|e| *e == flag)
                .map_or(value, |i| extra[i + 1]);
            args.extend([flag, v]);
        }
        pf_viz(&args)
    };
    for (o, needle) in [
        (run("/nonexistent/y.csv", &[]), "/nonexistent/y.csv"),
        (run(&no_y, &[]), "no-y.csv"),
        (run(&nan, &[]), "line 3"),
        (run(&text, &[]), "line 3"),
        (run(&short, &[]), "short.csv"),
        (run(&good, &["--sigma", "0"]), "sigma"),
        (run(&good, &["--rho", "-1"]), "rho"),
        (run(&good, &["--particles", "0"]), "particles"),
        (run(&good, &["--replications", "0"]), "replications"),
    ] {
        assert!(!o.status.success());
        assert!(o.stdout.is_empty());
        let stderr = String::from_utf8(o.stderr).unwrap();
        assert_eq!(stderr.lines().count(), 1, "{stderr:?}");
        assert!(stderr.contains(needle), "{needle}: {stderr:?}");
        assert!(!stderr.contains("multiple times"), "{stderr:?}");
    }
}
