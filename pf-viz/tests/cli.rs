//! End-to-end checks of the `pf-viz` binary.

mod common;

use std::fs;
use std::path::Path;

use common::{Scratch, one_line_error, pf_viz, pf_viz_ok};

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Width and height from a PNG's IHDR chunk, after checking the signature.
fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert!(bytes.len() > 33, "PNG too short");
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&bytes[12..16], b"IHDR", "first chunk is IHDR");
    let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
    (be(16), be(20))
}

fn check_png(path: &Path) {
    let bytes = fs::read(path).unwrap();
    assert_eq!(png_size(&bytes), (1200, 800), "{}", path.display());
    // A drawn figure with text and thousands of marks compresses to tens of KB; a blank
    // 1200×800 canvas to well under 10 KB.
    assert!(
        bytes.len() > 20_000,
        "{} is only {} bytes",
        path.display(),
        bytes.len()
    );
    assert_eq!(
        &bytes[bytes.len() - 8..bytes.len() - 4],
        b"IEND",
        "PNG ends with IEND"
    );
}

#[test]
fn report_writes_figures_recording_and_summary() {
    let s = Scratch::new("report");
    let out = s.dir().join("nested/out");
    pf_viz_ok(&[
        "report",
        "--out",
        out.to_str().unwrap(),
        "--seed",
        "7",
        "--only",
        "core",
        "--scale",
        "quick",
    ]);

    let mut expected = vec![
        "REPORT.md",
        "ess.png",
        "genealogy.png",
        "index.html",
        "summary.json",
    ];
    if cfg!(feature = "rrd") {
        expected.push("genealogy.rrd");
        expected.sort_unstable();
    }
    assert_eq!(names(&out), expected, "exactly these files, no temporaries");

    check_png(&out.join("genealogy.png"));
    check_png(&out.join("ess.png"));

    let summary: serde_json::Value =
        serde_json::from_slice(&fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["seed"], 7);
    let core = &summary["sections"]["core"];
    for key in [
        "config",
        "log_lik",
        "coalescence_time",
        "surviving_per_step",
        "ess",
        "genealogy",
        "files",
    ] {
        assert!(!core[key].is_null(), "summary lacks sections.core.{key}");
    }
    assert_eq!(core["config"]["filter"]["n_particles"], 50);
    assert_eq!(core["config"]["filter"]["resampler"], "multinomial");
    let steps = core["config"]["n"].as_u64().unwrap() as usize + 1;
    assert_eq!(core["ess"].as_array().unwrap().len(), steps);
    let surviving = core["surviving_per_step"].as_array().unwrap();
    assert_eq!(surviving.len(), steps);
    // Every final particle survives trivially; the count never grows backwards in time.
    assert_eq!(surviving[steps - 1], 50);
    assert!(core["log_lik"].as_f64().unwrap().is_finite());

    if cfg!(feature = "rrd") {
        let rrd = fs::read(out.join("genealogy.rrd")).unwrap();
        assert_eq!(&rrd[..4], b"RRF2", "rrd magic bytes");
        assert!(rrd.len() > 10_000);
    }
}

#[test]
fn same_seed_same_numbers_whatever_the_jobs() {
    let s = Scratch::new("determinism");
    let (a, b) = (s.dir().join("a"), s.dir().join("b"));
    for (d, jobs) in [(&a, "1"), (&b, "2")] {
        pf_viz_ok(&[
            "report",
            "--out",
            d.to_str().unwrap(),
            "--no-rrd",
            "--scale",
            "quick",
            "--jobs",
            jobs,
        ]);
    }
    // Everything but the parts the summary itself declares timing-dependent is identical.
    let load = |d: &Path| -> serde_json::Value {
        let mut v: serde_json::Value =
            serde_json::from_slice(&fs::read(d.join("summary.json")).unwrap()).unwrap();
        let timing = v["timing_dependent"].clone();
        for (section, pointers) in timing.as_object().unwrap() {
            for p in pointers.as_array().unwrap() {
                let p = p.as_str().unwrap();
                let (parent, key) = p.rsplit_once('/').unwrap();
                let removed = v["sections"][section]
                    .pointer_mut(parent)
                    .and_then(|x| x.as_object_mut())
                    .and_then(|o| o.remove(key));
                assert!(removed.is_some(), "{section}{p} is declared but absent");
            }
        }
        v
    };
    let (va, vb) = (load(&a), load(&b));
    assert_eq!(
        va["timing_dependent"]["mpf"].as_array().map(Vec::len),
        Some(3)
    );
    for (name, section) in va["sections"].as_object().unwrap() {
        assert_eq!(
            section, &vb["sections"][name],
            "section {name} differs between --jobs"
        );
    }
    assert_eq!(va, vb);
    assert!(
        !a.join("genealogy.rrd").exists(),
        "--no-rrd writes no recording"
    );
}

#[test]
fn unwritable_out_fails_with_one_line_and_leaves_nothing() {
    let s = Scratch::new("unwritable");
    let file = s.dir().join("plain-file");
    fs::write(&file, b"not a directory").unwrap();
    let out = file.join("out");
    let o = pf_viz(&["report", "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    // The one line names the path.
    let stderr = one_line_error(&o, "unwritable --out", &["plain-file"]);
    assert!(stderr.starts_with("error: "), "{stderr:?}");
    assert_eq!(names(s.dir()), vec!["plain-file"], "nothing created");
    assert_eq!(fs::read(&file).unwrap(), b"not a directory");
    // A file as the output directory itself is named as such, not "File exists".
    let o = pf_viz(&["report", "--out", file.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    one_line_error(&o, "file as --out", &["plain-file", "not a directory"]);
    assert_eq!(fs::read(&file).unwrap(), b"not a directory");
}

#[test]
fn bad_arguments_are_rejected() {
    for args in [
        &["report", "--out", "x", "--bogus"][..],
        &["report"][..],
        &["report", "--out", "x", "--seed", "minus-one"][..],
        &["frobnicate"][..],
    ] {
        let o = pf_viz(args);
        assert_eq!(o.status.code(), Some(2), "{args:?} should fail");
        let stderr = one_line_error(&o, &format!("{args:?}"), &[]);
        assert!(stderr.starts_with("error: "), "{args:?}: {stderr:?}");
    }
    // A missing required argument is named on that one line.
    let o = pf_viz(&["report"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("--out"));
    // Report-specific meaning checks: an unknown section, zero jobs.
    for (args, needle) in [
        (
            &["report", "--out", "x", "--only", "smooth,bogus"][..],
            "bogus",
        ),
        (&["report", "--out", "x", "--jobs", "0"][..], "--jobs"),
        (&["report", "--out", "x", "--scale", "huge"][..], "huge"),
    ] {
        one_line_error(&pf_viz(args), &format!("{args:?}"), &[needle]);
    }
    assert!(!Path::new("x").exists(), "no output for rejected arguments");
}

/// `report --help` names every section that `--only` accepts.
#[test]
fn report_help_names_every_section() {
    let help = String::from_utf8(pf_viz_ok(&["report", "--help"]).stdout).unwrap();
    for s in pf_viz::report::SECTIONS {
        assert!(
            help.contains(&format!("`{}`", s.name)),
            "{}: {help}",
            s.name
        );
    }
}

/// `--jobs` beyond the documented limit (1024) is a one-line usage error before the output
/// directory is even created (4294967295 used to hang building the pool).
#[test]
fn absurd_job_counts_are_refused_before_any_work() {
    let s = Scratch::new("jobs-limit");
    let out = s.dir().join("r");
    let out = out.to_str().unwrap();
    for jobs in ["1025", "4294967295"] {
        let args = ["report", "--out", out, "--only", "core", "--jobs", jobs];
        let o = pf_viz(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        one_line_error(&o, &format!("{args:?}"), &["--jobs", "1024"]);
        assert!(!Path::new(out).exists(), "nothing created");
    }
}
