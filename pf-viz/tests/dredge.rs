//! End-to-end checks of `pf-viz dredge simulate|estimate`: the JSON contract, the on-line
//! mode against the file mode, and one error per bad input of the issue.

mod common;

use std::fs;
use std::io::{BufRead, BufReader, Write};
use std::process::{Command, Output, Stdio};

use serde_json::Value;

use common::{BIN, Scratch, one_line_error, pf_viz, pf_viz_json, pf_viz_ok};

/// Runs `pf-viz` with `args`, feeding it `stdin` (the on-line mode reads from a pipe).
fn pf_viz_stdin(args: &[&str], stdin: &[u8]) -> Output {
    let mut child = Command::new(BIN)
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run pf-viz");
    child.stdin.take().unwrap().write_all(stdin).unwrap();
    child.wait_with_output().unwrap()
}

fn simulated(dir: &Scratch) -> String {
    let csv = dir.path("cycle.csv");
    pf_viz_ok(&["dredge", "simulate", "--out", &csv, "--seed", "3"]);
    csv
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn simulate_then_estimate_keeps_the_json_contract() {
    let dir = Scratch::new("roundtrip");
    let csv = simulated(&dir);
    let text = fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with("t,V_t,m_t,Q_i,rho_i,Q_o,rho_o\n"));
    let n = text.lines().count() - 1;
    let v = pf_viz_json(&[
        "dredge",
        "estimate",
        "--data",
        &csv,
        "--particles",
        "300",
        "--seed",
        "4",
        "--json",
    ]);
    for key in ["t", "Q_o", "rho_o"] {
        assert_eq!(v[key].as_array().unwrap().len(), n, "{key}");
    }
    assert_eq!(v["direct"]["Q_o"].as_array().unwrap().len(), n);
    assert_eq!(v["direct"]["rho_o"].as_array().unwrap().len(), n);
    let t = floats(&v["t"]);
    assert!(
        t.windows(2).all(|w| (w[1] - w[0] - 5.0).abs() < 1e-9),
        "T_s = 5 s from t"
    );
    // Residuals are there (truth columns) and sane: the Q_o residual std is well under the
    // Q_o range (0 to about 8 m³/s); the paper's is 0.345 m³/s.
    for key in ["Q_o", "rho_o"] {
        let r = &v["residuals"][key];
        for stat in ["mean", "std", "max_abs"] {
            assert!(r[stat].as_f64().unwrap().is_finite(), "{key}.{stat}");
        }
    }
    assert!(v["residuals"]["Q_o"]["std"].as_f64().unwrap() < 1.0);

    // Without the truth columns there is no `residuals` key.
    let no_truth: String = text
        .lines()
        .map(|l| l.split(',').take(5).collect::<Vec<_>>().join(",") + "\n")
        .collect();
    let p = dir.file("no_truth.csv", &no_truth);
    let v2 = pf_viz_json(&[
        "dredge",
        "estimate",
        "--data",
        &p,
        "--particles",
        "300",
        "--seed",
        "4",
        "--json",
    ]);
    assert!(v2.get("residuals").is_none());
    assert_eq!(
        v2["Q_o"], v["Q_o"],
        "truth columns do not change the estimate"
    );
}

/// The first `rows` data rows of the simulated cycle, with some cells emptied (missing
/// observations) to exercise that path in both modes.
fn with_gaps(csv: &str, rows: usize) -> String {
    let text = fs::read_to_string(csv).unwrap();
    let mut out = String::new();
    for (i, line) in text.lines().take(rows + 1).enumerate() {
        let mut f: Vec<&str> = line.split(',').collect();
        if i > 0 && i % 7 == 0 {
            f[1] = "";
        }
        if i > 0 && i % 11 == 0 {
            f[2] = "";
            f[3] = "";
        }
        out += &f.join(",");
        out.push('\n');
    }
    out
}

#[test]
fn online_gives_the_file_mode_estimates_for_the_same_seed() {
    let dir = Scratch::new("online");
    let csv = simulated(&dir);
    let text = with_gaps(&csv, 500);
    let p = dir.file("gaps.csv", &text);
    let args = ["--particles", "200", "--seed", "9", "--runs", "2"];
    let mut file_args = vec!["dredge", "estimate", "--data", &p, "--json"];
    file_args.extend(args);
    let file = pf_viz_json(&file_args);
    let mut online_args = vec!["dredge", "estimate", "--data", "-", "--online"];
    online_args.extend(args);
    let out = pf_viz_stdin(&online_args, text.as_bytes());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<Value> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 500, "one line per input sample");
    let (q, rho, t) = (
        floats(&file["Q_o"]),
        floats(&file["rho_o"]),
        floats(&file["t"]),
    );
    for (k, l) in lines.iter().enumerate() {
        assert_eq!(l["t"].as_f64().unwrap(), t[k]);
        assert_eq!(l["Q_o"].as_f64().unwrap(), q[k], "Q_o at sample {k}");
        assert_eq!(l["rho_o"].as_f64().unwrap(), rho[k], "rho_o at sample {k}");
    }
}

#[test]
fn online_answers_each_sample_before_the_next_arrives() {
    let mut child = Command::new(BIN)
        .args([
            "dredge",
            "estimate",
            "--data",
            "-",
            "--online",
            "--particles",
            "50",
        ])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    writeln!(stdin, "t,V_t,m_t,Q_i,rho_i").unwrap();
    let mut line = String::new();
    for k in 0..3 {
        // The pipe stays open: the answer can only come if it is flushed per sample.
        writeln!(stdin, "{},{},1.0e6,8,1200", 5 * k, 1000 + 40 * k).unwrap();
        stdin.flush().unwrap();
        line.clear();
        stdout.read_line(&mut line).unwrap();
        let v: Value = serde_json::from_str(&line).unwrap();
        assert_eq!(v["t"].as_f64().unwrap(), (5 * k) as f64);
    }
    drop(stdin);
    assert!(child.wait().unwrap().success());
}

/// Runs `estimate` on `text`, expects exit 1 and one stderr line with every `needles`.
fn rejects(dir: &Scratch, name: &str, text: &str, needles: &[&str]) {
    let p = dir.file(name, text);
    for online in [false, true] {
        let out = if online {
            pf_viz_stdin(
                &[
                    "dredge",
                    "estimate",
                    "--data",
                    "-",
                    "--online",
                    "--particles",
                    "50",
                ],
                text.as_bytes(),
            )
        } else {
            pf_viz(&[
                "dredge",
                "estimate",
                "--data",
                &p,
                "--particles",
                "50",
                "--json",
            ])
        };
        assert_eq!(out.status.code(), Some(1), "{name} (online {online})");
        let err = one_line_error(&out, &format!("{name} (online {online})"), needles);
        assert!(err.starts_with("error: "), "{err}");
        if !online {
            assert!(out.stdout.is_empty(), "{name}: nothing on stdout");
        }
    }
}

#[test]
fn each_bad_input_gets_a_one_line_error_naming_line_and_problem() {
    let dir = Scratch::new("errors");
    let h = "t,V_t,m_t,Q_i,rho_i\n";
    let ok = "0,1000,1.0e6,8,1200\n5,1040,1.05e6,8,1200\n";
    rejects(&dir, "empty.csv", "", &["line 1", "empty"]);
    rejects(&dir, "header_only.csv", h, &["line 2", "no data rows"]);
    rejects(
        &dir,
        "missing.csv",
        "t,V_t,Q_i,rho_i\n0,1000,8,1200\n",
        &["line 1", "missing column(s) m_t"],
    );
    rejects(
        &dir,
        "text.csv",
        &format!("{h}{ok}10,1080,heavy,8,1200\n"),
        &["line 4", "m_t = `heavy` is not a number"],
    );
    rejects(
        &dir,
        "time.csv",
        &format!("{h}{ok}5,1080,1.1e6,8,1200\n"),
        &["line 4", "time does not increase"],
    );
    rejects(
        &dir,
        "neg_flow.csv",
        &format!("{h}{ok}10,1080,1.1e6,-8,1200\n"),
        &["line 4", "Q_i = `-8` is negative"],
    );
    rejects(
        &dir,
        "neg_density.csv",
        &format!("{h}{ok}10,1080,1.1e6,8,-1200\n"),
        &["line 4", "rho_i = `-1200` is negative"],
    );
    rejects(
        &dir,
        "neg_truth.csv",
        "t,V_t,m_t,Q_i,rho_i,Q_o,rho_o\n0,1000,1.0e6,8,1200,1,-5\n",
        &["line 2", "rho_o = `-5` is negative"],
    );
    let missing = pf_viz(&["dredge", "estimate", "--data", "/nonexistent/x.csv"]);
    assert_eq!(missing.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("/nonexistent/x.csv"));
}

/// `--online` prints a line per sample and `--json` promises one object, so together they
/// are a one-line usage error, with nothing on stdout.
#[test]
fn online_and_json_conflict() {
    let s = Scratch::new("online-json");
    let csv = simulated(&s);
    for args in [
        ["dredge", "estimate", "--data", &csv, "--online", "--json"],
        ["dredge", "estimate", "--data", &csv, "--json", "--online"],
    ] {
        let o = pf_viz(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        one_line_error(&o, &format!("{args:?}"), &["--online", "--json"]);
        assert!(o.stdout.is_empty());
    }
}
