//! The whole report at the `quick` scale, the way a researcher runs it: every section runs,
//! every figure decodes and shows something, every recording loads in the official Rerun
//! tools, and the pages carry every figure and table without reaching for the network.
//!
//! The tests that run the Rerun CLI are `#[ignore]`d by a plain `cargo test`: they need
//! `PF_RERUN` to name it, fail when it does not, and `scripts/test.sh` runs them with
//! `--include-ignored`.

mod common;

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use common::BIN;

/// The paper sections `--only` accepts, as the issue names them.
const PAPERS: [&str; 5] = ["smooth", "mpf", "homotopy", "dredge", "epf"];

/// One quick report for every test in this file (it is the expensive part).
fn report() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        // Cargo's scratch directory for integration tests: a static is never dropped, so
        // the report stays after the run, under the target directory rather than in /tmp.
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("pf-viz-report");
        let _ = fs::remove_dir_all(&dir);
        let o = Command::new(BIN)
            .args(["report", "--scale", "quick", "--seed", "3", "--out"])
            .arg(&dir)
            .output()
            .expect("run pf-viz");
        assert!(
            o.status.success(),
            "quick report failed: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(
            String::from_utf8_lossy(&o.stdout).lines().count() <= 1,
            "progress never goes to stdout"
        );
        dir
    })
}

fn files(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == ext))
        .collect();
    v.sort();
    v
}

#[test]
fn every_section_reports_and_no_temporaries_remain() {
    let dir = report();
    let summary: serde_json::Value =
        serde_json::from_slice(&fs::read(dir.join("summary.json")).unwrap()).unwrap();
    let sections = summary["sections"].as_object().unwrap();
    for p in PAPERS {
        assert!(sections.contains_key(p), "summary.json lacks section {p}");
    }
    assert_eq!(summary["scale"], "quick");
    assert_eq!(summary["seed"], 3);
    for e in fs::read_dir(dir).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.starts_with('.'), "temporary left behind: {name}");
    }
}

#[test]
fn every_png_decodes_and_is_not_blank() {
    let pngs = files(report(), "png");
    assert!(pngs.len() >= 2, "figures: {pngs:?}");
    for p in &pngs {
        let img = image::open(p)
            .unwrap_or_else(|e| panic!("{} does not decode: {e}", p.display()))
            .to_rgb8();
        let (w, h) = img.dimensions();
        assert!(
            (300..=4000).contains(&w) && (150..=4000).contains(&h),
            "{}: {w}×{h}",
            p.display()
        );
        let ink = img.pixels().filter(|px| px.0 != [255, 255, 255]).count();
        let frac = ink as f64 / (w as f64 * h as f64);
        assert!(
            frac > 0.01,
            "{} is nearly blank ({:.2}% ink)",
            p.display(),
            100.0 * frac
        );
        let shades: BTreeSet<[u8; 3]> = img.pixels().map(|px| px.0).collect();
        assert!(
            shades.len() > 4,
            "{} has {} colours",
            p.display(),
            shades.len()
        );
    }
}

/// Why the tests that run the official Rerun tools are ignored by a plain `cargo test`.
const NEEDS_RERUN: &str = "needs the Rerun CLI: run scripts/test.sh or set PF_RERUN";

/// The Rerun CLI named by `PF_RERUN`; a test that needs it fails without it (or without
/// the `rrd` feature), never passes.
fn rerun_cli() -> PathBuf {
    if !cfg!(feature = "rrd") {
        panic!("pf-viz was built without the rrd feature: there are no recordings to check");
    }
    match std::env::var_os("PF_RERUN") {
        Some(p) => PathBuf::from(p),
        None => panic!("PF_RERUN is not set: {NEEDS_RERUN}"),
    }
}

#[test]
#[cfg_attr(not(feature = "rrd"), ignore = "needs the rrd feature")]
fn every_paper_has_a_recording() {
    let rrds = files(report(), "rrd");
    for p in PAPERS {
        assert!(
            rrds.iter()
                .any(|r| r.file_name().unwrap() == format!("{p}.rrd").as_str()),
            "no {p}.rrd among {rrds:?}"
        );
    }
    for r in &rrds {
        let bytes = fs::read(r).unwrap();
        assert_eq!(&bytes[..4], b"RRF2", "{} magic bytes", r.display());
    }
}

/// Every recording passes `rerun rrd verify` of the rerun crate's version.
// Ignored by a plain `cargo test` only because the official Rerun CLI is a Python package
// outside cargo's reach; `scripts/test.sh` (the README's test command, which CI runs)
// installs it, sets `PF_RERUN` and runs this test with `--include-ignored`.
#[test]
#[ignore = "needs the Rerun CLI: run scripts/test.sh or set PF_RERUN"]
fn every_recording_loads_in_the_official_rerun_tools() {
    let rerun = rerun_cli();
    let rrds = files(report(), "rrd");
    assert!(rrds.len() >= PAPERS.len(), "recordings: {rrds:?}");
    let o = Command::new(&rerun)
        .args(["rrd", "verify"])
        .args(&rrds)
        .output()
        .expect("run the rerun CLI named by PF_RERUN");
    assert!(
        o.status.success(),
        "rerun rrd verify failed: {}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// The layouts carry the view properties the SDK's builder cannot set: the dredger's four
/// time series open on the whole cycle, and the views of moving scenes on fixed frames.
// Ignored by a plain `cargo test` for the same reason as the test above; `scripts/test.sh`
// runs it.
#[test]
#[ignore = "needs the Rerun CLI: run scripts/test.sh or set PF_RERUN"]
fn recordings_open_on_whole_runs_and_fixed_frames() {
    let rerun = rerun_cli();
    let dir = report();
    // (recording, blueprint property, views that carry it)
    for (paper, property, views) in [
        ("dredge", "TimeAxis", 4),
        ("dredge", "VisualBounds2D", 1),
        ("homotopy", "VisualBounds2D", 2),
        ("mpf", "VisualBounds2D", 1),
        ("smooth", "VisualBounds2D", 2),
        ("smooth", "PlotLegend", 3),
        ("genealogy", "VisualBounds2D", 1),
    ] {
        let o = Command::new(&rerun)
            .args(["rrd", "print"])
            .arg(dir.join(format!("{paper}.rrd")))
            .output()
            .expect("run the rerun CLI named by PF_RERUN");
        assert!(o.status.success(), "rerun rrd print {paper}.rrd failed");
        let listing = String::from_utf8_lossy(&o.stdout);
        let found = listing
            .lines()
            .filter(|l| l.contains(&format!("/{property} - data columns")))
            .count();
        assert_eq!(found, views, "{paper}.rrd: views with {property}");
    }
}

#[test]
fn pages_carry_every_figure_and_need_no_network() {
    let dir = report();
    let html = fs::read_to_string(dir.join("index.html")).unwrap();
    let md = fs::read_to_string(dir.join("REPORT.md")).unwrap();
    for p in files(dir, "png") {
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if html.contains(&format!("alt=\"{name}\"")) {
            assert!(md.contains(&format!("]({name})")), "REPORT.md lacks {name}");
        } else {
            // Table images: the pages carry the table as text and list the image.
            assert!(
                html.contains(&format!("<code>{name}</code>")),
                "index.html neither shows nor lists {name}"
            );
        }
    }
    assert!(
        html.contains("data:image/png;base64,"),
        "figures are embedded"
    );
    // The header speaks of recordings only when there are some.
    let said = if files(dir, "rrd").is_empty() {
        "no recordings were written"
    } else {
        "open in the Rerun viewer"
    };
    assert!(
        md.contains(said) && html.contains(said),
        "the pages should say {said:?}"
    );
    for banned in ["<script", "http://", "https://", "<link"] {
        assert!(!html.contains(banned), "index.html contains {banned}");
    }
    for p in PAPERS {
        assert!(
            html.contains(&format!("id=\"{p}\"")),
            "index.html lacks {p}"
        );
    }
}
