//! The `pf-viz` binary as a user runs it.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn pf_viz(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pf-viz"))
        .args(args)
        .output()
        .expect("pf-viz runs")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pf-viz-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// A PNG whose IHDR says it is at least `min_w` × `min_h` and whose file is not tiny.
fn assert_png(path: &Path, min_w: u32, min_h: u32) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{}", path.display());
    let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    assert!(w >= min_w && h >= min_h, "{}: {w}×{h}", path.display());
    // A blank 1200×800 PNG compresses to a few kB; a drawn figure is far larger.
    assert!(
        bytes.len() > 20_000,
        "{}: only {} bytes",
        path.display(),
        bytes.len()
    );
}

#[test]
fn report_writes_figures_recording_and_summary() {
    let out = temp_dir("report");
    let o = pf_viz(&["report", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_png(&out.join("genealogy.png"), 800, 600);
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let core = &summary["sections"]["core"];
    assert_eq!(core["config"]["filter"]["n_particles"], 50);
    assert_eq!(core["config"]["n"], 100);
    assert!(summary["seed"].is_u64());
    if cfg!(feature = "rrd") {
        let rrd = std::fs::read(out.join("genealogy.rrd")).unwrap();
        assert!(rrd.len() > 1000 && &rrd[..4] == b"RRF2", "not an rrd file");
    }
    // No temporary file is left behind.
    for entry in std::fs::read_dir(&out).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        assert!(!name.contains(".tmp"), "left behind: {name}");
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn an_unwritable_out_dir_is_one_line_and_nothing_is_written() {
    let dir = temp_dir("blocked");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("a-file");
    std::fs::write(&file, "x").unwrap();
    let target = file.join("report");
    let o = pf_viz(&["report", "--out", target.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.starts_with("error: "), "{err}");
    assert!(!target.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_arguments_exit_non_zero() {
    assert!(!pf_viz(&["report"]).status.success());
    assert!(
        !pf_viz(&["report", "--out", "/tmp/x", "--bogus"])
            .status
            .success()
    );
    assert!(
        !pf_viz(&["bench", "bootstrap", "--resampler", "bogus"])
            .status
            .success()
    );
    let o = pf_viz(&["bench", "bootstrap", "--particles", "0", "--json"]);
    assert!(!o.status.success());
    assert!(o.stdout.is_empty(), "nothing on stdout on error");
}

#[test]
fn bench_bootstrap_keeps_its_json_contract() {
    let dir = temp_dir("bench");
    std::fs::create_dir_all(&dir).unwrap();
    let data = dir.join("y.csv");
    let ys: Vec<String> = (0..51)
        .map(|k| format!("{}", (k as f64 * 0.1).sin()))
        .collect();
    std::fs::write(
        &data,
        format!(
            "t,y\n{}\n",
            ys.iter()
                .enumerate()
                .map(|(k, y)| format!("{k},{y}"))
                .collect::<Vec<_>>()
                .join("\n")
        ),
    )
    .unwrap();
    for threads in ["1", "2"] {
        let o = pf_viz(&[
            "bench",
            "bootstrap",
            "--data",
            data.to_str().unwrap(),
            "--particles",
            "2000",
            "--threads",
            threads,
            "--seed",
            "3",
            "--json",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        for key in [
            "particles",
            "steps",
            "threads",
            "seconds",
            "ns_per_particle_step",
            "loglik",
        ] {
            assert!(v.get(key).is_some(), "missing {key}");
        }
        assert_eq!(v["particles"], 2000);
        assert_eq!(v["steps"], 50);
        assert!(v["loglik"].as_f64().unwrap().is_finite());
    }
    // Same seed, different thread counts: the same estimate, bit for bit.
    let ll = |t: &str| {
        let o = pf_viz(&[
            "bench",
            "bootstrap",
            "--data",
            data.to_str().unwrap(),
            "--particles",
            "20000",
            "--threads",
            t,
            "--json",
        ]);
        serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()["loglik"]
            .as_f64()
            .unwrap()
    };
    assert_eq!(ll("1").to_bits(), ll("2").to_bits());
    // A malformed data file names the line.
    std::fs::write(&data, "y\n1.0\noops\n").unwrap();
    let o = pf_viz(&[
        "bench",
        "bootstrap",
        "--data",
        data.to_str().unwrap(),
        "--json",
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("line 3"));
    let _ = std::fs::remove_dir_all(&dir);
}
