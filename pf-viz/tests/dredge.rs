//! `pf-viz dredge …` end to end: simulate → estimate, on-line against file mode, and the
//! one-line errors for bad data.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_pf-viz");

fn pf_viz(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().expect("run pf-viz")
}

struct Scratch(PathBuf);

impl Scratch {
    fn new(tag: &str) -> Self {
        let d = std::env::temp_dir().join(format!("pf-viz-dredge-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        Scratch(d)
    }
    fn file(&self, name: &str, text: &str) -> PathBuf {
        let p = self.0.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A simulated cycle cut to its first `rows` samples.
fn simulated(s: &Scratch, rows: usize) -> PathBuf {
    let full = s.0.join("full.csv");
    let o = pf_viz(&[
        "dredge",
        "simulate",
        "--out",
        full.to_str().unwrap(),
        "--seed",
        "4",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(o.stdout.is_empty(), "simulate prints nothing on stdout");
    let text = std::fs::read_to_string(&full).unwrap();
    let cut: Vec<&str> = text.lines().take(rows + 1).collect();
    s.file("cut.csv", &(cut.join("\n") + "\n"))
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn simulate_then_estimate_keeps_the_contract() {
    let s = Scratch::new("contract");
    let data = simulated(&s, 400);
    let header = std::fs::read_to_string(&data).unwrap();
    assert!(header.starts_with("t,V_t,m_t,Q_i,rho_i,Q_o,rho_o\n"));
    let o = pf_viz(&[
        "dredge",
        "estimate",
        "--data",
        path(&data),
        "--particles",
        "200",
        "--runs",
        "2",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let n = v["t"].as_array().unwrap().len();
    assert_eq!(n, 400);
    for key in ["Q_o", "rho_o"] {
        let xs = v[key].as_array().unwrap();
        assert_eq!(xs.len(), n);
        assert!(xs.iter().all(|x| x.as_f64().unwrap().is_finite()));
        assert_eq!(v["direct"][key].as_array().unwrap().len(), n);
        for stat in ["mean", "std", "max_abs"] {
            assert!(v["residuals"][key][stat].as_f64().unwrap().is_finite());
        }
    }
    // Without truth columns there are no residuals.
    let text = std::fs::read_to_string(&data).unwrap();
    let no_truth: String = text
        .lines()
        .map(|l| l.split(',').take(5).collect::<Vec<_>>().join(","))
        .collect::<Vec<_>>()
        .join("\n");
    let bare = s.file("bare.csv", &no_truth);
    let o = pf_viz(&[
        "dredge",
        "estimate",
        "--data",
        path(&bare),
        "--particles",
        "100",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v.get("residuals").is_none());
}

#[test]
fn online_mode_streams_the_file_modes_estimates() {
    let s = Scratch::new("online");
    let data = simulated(&s, 60);
    let o = pf_viz(&[
        "dredge",
        "estimate",
        "--data",
        path(&data),
        "--particles",
        "150",
        "--seed",
        "9",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let file: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let mut child = Command::new(BIN)
        .args([
            "dredge",
            "estimate",
            "--data",
            "-",
            "--online",
            "--particles",
            "150",
            "--seed",
            "9",
        ])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(std::fs::read(&data).unwrap().as_slice())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<serde_json::Value> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 60, "one line per sample");
    for (k, l) in lines.iter().enumerate() {
        assert_eq!(l["t"], file["t"][k]);
        assert_eq!(l["Q_o"], file["Q_o"][k], "Q_o at sample {k}");
        assert_eq!(l["rho_o"], file["rho_o"][k], "rho_o at sample {k}");
    }
}

#[test]
fn empty_cells_are_missing_observations() {
    let s = Scratch::new("missing");
    let data = s.file(
        "gap.csv",
        "t,V_t,m_t,Q_i,rho_i\n0,1000,1020000,8,1025\n5,,,8,1025\n10,1080,1102000,,\n15,1120,1143000,8,1030\n",
    );
    let o = pf_viz(&[
        "dredge",
        "estimate",
        "--data",
        path(&data),
        "--particles",
        "100",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["Q_o"].as_array().unwrap().len(), 4);
}

#[test]
fn bad_data_gets_one_line_naming_the_problem() {
    let s = Scratch::new("bad");
    let good = "t,V_t,m_t,Q_i,rho_i\n0,1000,1020000,8,1025\n5,1040,1061000,8,1025\n";
    let cases = [
        (
            "missing-column.csv",
            "t,V_t,m_t,Q_i\n0,1,2,3\n5,1,2,3\n",
            "rho_i",
        ),
        (
            "not-a-number.csv",
            "t,V_t,m_t,Q_i,rho_i\n0,1000,1020000,8,1025\n5,lots,1061000,8,1025\n",
            "line 3",
        ),
        (
            "backwards.csv",
            "t,V_t,m_t,Q_i,rho_i\n0,1000,1020000,8,1025\n5,1040,1061000,8,1025\n5,1041,1062000,8,1025\n",
            "line 4",
        ),
        (
            "negative.csv",
            "t,V_t,m_t,Q_i,rho_i\n0,1000,1020000,8,1025\n5,1040,1061000,-8,1025\n",
            "negative",
        ),
        ("empty.csv", "t,V_t,m_t,Q_i,rho_i\n", "no samples"),
    ];
    for (name, text, needle) in cases {
        let p = s.file(name, text);
        let o = pf_viz(&[
            "dredge",
            "estimate",
            "--data",
            path(&p),
            "--particles",
            "50",
            "--json",
        ]);
        assert_eq!(o.status.code(), Some(1), "{name} should fail");
        assert!(o.stdout.is_empty(), "{name}: nothing on stdout");
        let stderr = String::from_utf8(o.stderr).unwrap();
        assert_eq!(stderr.lines().count(), 1, "{name}: {stderr:?}");
        assert!(stderr.contains(name), "{name}: names the file: {stderr:?}");
        assert!(stderr.contains(needle), "{name}: {stderr:?}");
    }
    let good = s.file("good.csv", good);
    for args in [
        &[
            "dredge",
            "estimate",
            "--data",
            path(&good),
            "--particles",
            "0",
        ][..],
        &["dredge", "estimate", "--data", path(&good), "--runs", "0"][..],
        &["dredge", "estimate", "--data", "/nonexistent/x.csv"][..],
    ] {
        let o = pf_viz(args);
        assert!(!o.status.success(), "{args:?}");
        assert_eq!(String::from_utf8_lossy(&o.stderr).lines().count(), 1);
    }
}
