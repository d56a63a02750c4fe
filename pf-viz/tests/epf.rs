//! End-to-end checks of `pf-viz epf simulate|track|energies`: the CSV and JSON contracts and
//! the one-line errors for bad input.

mod common;

use std::fs;
use std::path::Path;
use std::process::Output;

use common::{Scratch, one_line_error, pf_viz, pf_viz_json, pf_viz_ok};

/// The command fails with exit code 1 and one `error: …` line that contains every `needle`.
fn fails_with(out: &Output, needles: &[&str]) {
    assert_eq!(out.status.code(), Some(1), "exit code");
    let err = one_line_error(out, "epf", needles);
    assert!(err.starts_with("error: "), "{err}");
    assert!(out.stdout.is_empty(), "nothing on stdout");
}

fn simulate(dir: &Path, scenario: &str, extra: &[&str]) {
    let out_dir = dir.display().to_string();
    let mut args = vec![
        "epf",
        "simulate",
        "--scenario",
        scenario,
        "--seed",
        "5",
        "--out",
        &out_dir,
    ];
    args.extend_from_slice(extra);
    pf_viz_ok(&args);
}

#[test]
fn simulate_then_track_follows_the_contract() {
    let s = Scratch::new("track");
    simulate(s.dir(), "walking-men", &["--clutter", "1", "--miss", "0.1"]);
    let det = fs::read_to_string(s.path("detections.csv")).unwrap();
    let header: Vec<&str> = det.lines().next().unwrap().split(',').collect();
    assert_eq!(header, ["frame", "x", "y", "target"]);
    let rows: Vec<Vec<&str>> = det
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert!(rows.iter().any(|r| r[3] == "-1"), "clutter is labelled −1");
    let init = fs::read_to_string(s.path("init.csv")).unwrap();
    assert_eq!(init.lines().next().unwrap(), "target,frame,x,y");
    assert_eq!(
        init.lines().count(),
        1 + 3 * 2,
        "three targets, two frames each"
    );

    for method in ["energy", "nn"] {
        let v = pf_viz_json(&[
            "epf",
            "track",
            "--data",
            &s.path("detections.csv"),
            "--init",
            &s.path("init.csv"),
            "--association",
            method,
            "--particles",
            "100",
            "--seed",
            "1",
            "--json",
        ]);
        let frames = v["frames"].as_array().unwrap();
        // Frames 0 and 1 are the init; 2..=12 are tracked (the miss rate may drop none
        // entirely, since clutter and the other targets keep frames present, but at most
        // 11 can be).
        assert!(!frames.is_empty() && frames.len() <= 11);
        assert!(frames[0].as_i64().unwrap() >= 2);
        let tracks = v["tracks"].as_array().unwrap();
        assert_eq!(tracks.len(), 3);
        for (k, t) in tracks.iter().enumerate() {
            assert_eq!(t["target"].as_i64(), Some(k as i64));
            let pos = t["position"].as_array().unwrap();
            let dets = t["detection"].as_array().unwrap();
            assert_eq!(pos.len(), frames.len());
            assert_eq!(dets.len(), frames.len());
            for (p, (d, f)) in pos.iter().zip(dets.iter().zip(frames)) {
                assert_eq!(p.as_array().unwrap().len(), 2);
                if let Some(j) = d.as_u64() {
                    // The row index points at a detection of that very frame.
                    let row = &rows[j as usize];
                    assert_eq!(row[0], f.to_string());
                } else {
                    assert!(d.is_null());
                }
            }
        }
    }
}

#[test]
fn energies_follow_the_contract() {
    let s = Scratch::new("energies");
    simulate(s.dir(), "van-plane", &[]);
    let v = pf_viz_json(&[
        "epf",
        "energies",
        "--data",
        &s.path("detections.csv"),
        "--init",
        &s.path("init.csv"),
        "--frame",
        "6",
        "--particles",
        "100",
        "--json",
    ]);
    assert_eq!(v["targets"].as_array().unwrap().len(), 2);
    let m = v["detections"].as_array().unwrap().len();
    assert_eq!(m, 2, "no clutter, no misses: two detections at frame 6");
    for key in ["E1", "E2", "E3", "E"] {
        let rows = v[key].as_array().unwrap();
        assert_eq!(rows.len(), 2, "{key}");
        for r in rows {
            let r = r.as_array().unwrap();
            assert_eq!(r.len(), m, "{key}");
            for x in r {
                let x = x.as_f64().unwrap();
                assert!((0.0..=1.0).contains(&x), "{key} = {x} outside [0, 1]");
            }
        }
    }
    // E is eq. (1) of the three weighted components.
    for k in 0..2 {
        for j in 0..m {
            let c = |key: &str| v[key][k][j].as_f64().unwrap();
            let e = ((c("E1").powi(2) + c("E2").powi(2) + c("E3").powi(2)) / 3.0).sqrt();
            assert!(
                (c("E") - e).abs() < 1e-12,
                "E = {} against eq. (1) {e}",
                c("E")
            );
        }
    }
    // α₁E¹ sums to 1 over the targets for each detection (E¹ > 0 here).
    for j in 0..m {
        let sum: f64 = (0..2).map(|k| v["E1"][k][j].as_f64().unwrap()).sum();
        assert!((sum - 1.0).abs() < 1e-12, "Σ_k α₁E¹ = {sum}");
    }
}

#[test]
fn bad_input_gets_a_one_line_error() {
    let s = Scratch::new("errors");
    let init = s.file(
        "init.csv",
        "target,frame,x,y\n0,0,0,0\n0,1,1,0\n1,0,0,5\n1,1,1,5\n",
    );
    let det = s.file("det.csv", "frame,x,y\n2,2,0\n2,2,5\n3,3,0\n3,3,5\n");
    let run = |data: &str, init: &str| {
        pf_viz(&["epf", "track", "--data", data, "--init", init, "--json"])
    };
    // The good files work.
    assert!(run(&det, &init).status.success());
    // Missing columns.
    let no_y = s.file("no_y.csv", "frame,x\n2,2\n");
    fails_with(&run(&no_y, &init), &["no_y.csv", "line 1", "no `y` column"]);
    let no_target = s.file("no_target.csv", "frame,x,y\n0,0,0\n1,1,0\n");
    fails_with(&run(&det, &no_target), &["no `target` column"]);
    // Non-numeric values, with the line (header = line 1).
    let text = s.file("text.csv", "frame,x,y\n2,2,0\n2,abc,5\n");
    fails_with(
        &run(&text, &init),
        &["text.csv", "line 3", "`x` = `abc` is not a number"],
    );
    let frame_text = s.file("frame_text.csv", "frame,x,y\n2.5,2,0\n");
    fails_with(&run(&frame_text, &init), &["line 2", "not an integer"]);
    // An init with fewer than two frames for a target.
    let short = s.file("short.csv", "target,frame,x,y\n0,0,0,0\n0,1,1,0\n1,1,1,5\n");
    fails_with(
        &run(&det, &short),
        &["short.csv", "target 1 has 1 init frame"],
    );
    // A frame that goes backwards.
    let back = s.file("back.csv", "frame,x,y\n2,2,0\n3,3,0\n2,2,5\n");
    fails_with(
        &run(&back, &init),
        &["back.csv", "line 4", "frame goes backwards"],
    );
    let init_back = s.file("init_back.csv", "target,frame,x,y\n0,1,0,0\n0,0,1,0\n");
    fails_with(
        &run(&det, &init_back),
        &["init_back.csv", "line 3", "frame goes backwards"],
    );
    // A frame `energies` cannot show.
    let out = pf_viz(&[
        "epf", "energies", "--data", &det, "--init", &init, "--frame", "1", "--json",
    ]);
    fails_with(&out, &["--frame", "not a tracked frame"]);
    // A missing file.
    fails_with(&run(&s.path("nope.csv"), &init), &["nope.csv"]);
    // An unknown dynamic model.
    let out = pf_viz(&[
        "epf", "track", "--data", &det, "--init", &init, "--spline", "cubic", "--json",
    ]);
    assert_ne!(out.status.code(), Some(0));
    let err = one_line_error(&out, "epf", &["--spline", "cubic"]);
    assert!(err.contains("cubic_b_spline_end"), "lists the names: {err}");
}

/// `--spline` and `--energy-spline` default to the library's `TrackerConfig` (the B-spline's
/// end derivatives move the particles, its curve shapes E²), and each named alternative runs.
#[test]
fn spline_flags_default_to_the_library_and_accept_every_order() {
    let s = Scratch::new("spline");
    simulate(s.dir(), "crossing", &[]);
    let track = |extra: &[&str]| {
        let (data, init) = (s.path("detections.csv"), s.path("init.csv"));
        let mut args = vec![
            "epf",
            "track",
            "--data",
            &data,
            "--init",
            &init,
            "--particles",
            "100",
            "--json",
        ];
        args.extend_from_slice(extra);
        pf_viz_json(&args)
    };
    let default = track(&[]);
    let d = pf_epf::tracker::TrackerConfig::default();
    assert_eq!(
        track(&[
            "--spline",
            d.spline.name(),
            "--energy-spline",
            d.energy_spline.name()
        ]),
        default
    );
    for order in ["cubic_b_spline", "linear", "quadratic"] {
        let v = track(&["--spline", order]);
        assert_eq!(v["tracks"].as_array().unwrap().len(), 2, "{order}");
        // The curve and the quadratic widen the gates by their 14r² (the chord's 2r²).
        if order != "linear" {
            assert_ne!(v, default, "{order} moves the particles differently");
        }
    }
}
