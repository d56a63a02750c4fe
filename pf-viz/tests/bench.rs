//! `pf-viz bench bootstrap` as other tools call it: its JSON contract and its errors.

mod common;

use common::{Scratch, one_line_error, pf_viz, pf_viz_json, pf_viz_ok};

#[test]
fn bad_bench_arguments_exit_non_zero_with_nothing_on_stdout() {
    assert!(
        !pf_viz(&["bench", "bootstrap", "--resampler", "bogus"])
            .status
            .success()
    );
    let o = pf_viz(&["bench", "bootstrap", "--particles", "0", "--json"]);
    assert!(!o.status.success());
    assert!(o.stdout.is_empty(), "nothing on stdout on error");
    let o = pf_viz(&["bench", "bootstrap", "--threads", "0", "--json"]);
    assert!(!o.status.success());
    let o = pf_viz(&["bench", "bootstrap", "--repeat", "0", "--json"]);
    assert!(!o.status.success());
    assert!(o.stdout.is_empty());
}

/// `--repeat R` times R runs of the same computation: the estimate is the single run's, bit
/// for bit, and `seconds` is the fastest run, so at most the median.
#[test]
fn bench_bootstrap_repeat_reports_the_fastest_of_identical_runs() {
    let run = |repeat: &str| {
        let o = pf_viz_ok(&[
            "bench",
            "bootstrap",
            "--particles",
            "3000",
            "--steps",
            "40",
            "--repeat",
            repeat,
            "--json",
        ]);
        serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()
    };
    let (one, three) = (run("1"), run("3"));
    assert_eq!(one["repeat"], 1);
    assert_eq!(three["repeat"], 3);
    assert_eq!(one["seconds"], one["seconds_median"]);
    let (fastest, median) = (
        three["seconds"].as_f64().unwrap(),
        three["seconds_median"].as_f64().unwrap(),
    );
    assert!(
        0.0 < fastest && fastest <= median,
        "{fastest} against {median}"
    );
    let ns = three["ns_per_particle_step"].as_f64().unwrap();
    assert!((ns - fastest * 1e9 / (3000.0 * 40.0)).abs() <= 1e-9 * ns);
    assert_eq!(
        one["loglik"].as_f64().unwrap().to_bits(),
        three["loglik"].as_f64().unwrap().to_bits()
    );
}

#[test]
fn bench_bootstrap_keeps_its_json_contract() {
    let dir = Scratch::new("bootstrap");
    let data = dir.path("y.csv");
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
        let o = pf_viz_ok(&[
            "bench",
            "bootstrap",
            "--data",
            &data,
            "--particles",
            "2000",
            "--threads",
            threads,
            "--seed",
            "3",
            "--json",
        ]);
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        for key in [
            "particles",
            "steps",
            "threads",
            "seconds",
            "ns_per_particle_step",
            "loglik",
            "kernels",
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
            &data,
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
    let o = pf_viz(&["bench", "bootstrap", "--data", &data, "--json"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("line 3"));
}

#[test]
fn bench_genealogy_prunes_dead_branches() {
    // Coalescence takes a few multiples of N steps here (weakly informative observations).
    let (n, steps) = (200usize, 2000usize);
    let o = pf_viz_ok(&[
        "bench",
        "genealogy",
        "--particles",
        &n.to_string(),
        "--steps",
        &steps.to_string(),
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let peak = v["peak_nodes"].as_u64().unwrap() as usize;
    let live = v["live_nodes"].as_u64().unwrap() as usize;
    // Every living path has n + 1 states and the N leaves are distinct: a lower bound.
    assert!(live >= n + steps, "live {live}");
    assert!(peak >= live);
    // Full storage would hold N·(n+1) nodes; pruning keeps a small fraction for this
    // mixing model, whose paths coalesce within the run.
    assert!(peak < n * (steps + 1) / 10, "peak {peak} nodes");
    let depth = v["coalescence_depth"]
        .as_u64()
        .expect("paths coalesce within the run");
    assert!((depth as usize) < steps);
    let o = pf_viz(&["bench", "genealogy", "--particles", "0", "--json"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(o.stdout.is_empty());
}

/// A thread count beyond the documented limit (1024) is refused at once, on one line,
/// instead of spending minutes starting the threads.
#[test]
fn absurd_thread_counts_are_refused_before_any_work() {
    // A usage error (exit 2) comes from parsing, before any pool is built.
    for threads in ["1025", "10000", "18446744073709551615"] {
        let args = [
            "bench",
            "bootstrap",
            "--particles",
            "10",
            "--steps",
            "1",
            "--threads",
            threads,
        ];
        let o = pf_viz(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        one_line_error(&o, &format!("{args:?}"), &["--threads", "1024"]);
        assert!(o.stdout.is_empty());
    }
}

/// Counts no machine can hold are one-line errors, not overflow panics or aborted
/// allocations.
#[test]
fn absurd_sizes_are_one_line_errors() {
    let max = "18446744073709551615";
    for (sub, particles, steps) in [
        ("bootstrap", "10", max),
        ("genealogy", "10", max),
        ("bootstrap", max, "5"),
        ("bootstrap", "1000000000000", "5"),
        ("genealogy", max, "5"),
    ] {
        let args = ["bench", sub, "--particles", particles, "--steps", steps];
        let o = pf_viz(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        one_line_error(
            &o,
            &format!("{args:?}"),
            &["more than this machine can hold"],
        );
    }
    let args = ["mpf", "calibrate", "--quick", "--rounds", max, "--json"];
    let o = pf_viz(&args);
    assert_eq!(o.status.code(), Some(1));
    one_line_error(
        &o,
        "calibrate --rounds",
        &["rounds", "more than this machine can hold"],
    );
}

/// Counts within the limit whose buffers or results exceed the machine's memory are one-line
/// errors too, before anything is allocated: Linux would grant the particle arrays and kill
/// the process at its first write, and abort on a billion replications' results.
#[test]
#[cfg(target_os = "linux")]
fn counts_beyond_the_machines_memory_are_one_line_errors() {
    let cases: [&[&str]; 4] = [
        &[
            "bench",
            "bootstrap",
            "--particles",
            "4000000000",
            "--steps",
            "5",
        ],
        &[
            "homotopy",
            "rmse",
            "--realisations",
            "4000000000",
            "--particles",
            "10",
        ],
        &["mpf", "table2", "--scale", "quick", "--mc", "4000000000"],
        &["mpf", "table3", "--scale", "quick", "--mc", "4000000000"],
    ];
    for args in cases {
        let o = pf_viz(args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        one_line_error(
            &o,
            &format!("{args:?}"),
            &["more than this machine can hold"],
        );
    }
}

/// `pf-viz bench filter --model M --json` prints the contract's keys for every model, and the
/// same estimate, bit for bit, on one thread and on two.
#[test]
fn bench_filter_keeps_its_json_contract_for_every_model() {
    for (model, steps) in [("ar1", "30"), ("radar", "20"), ("bearings", "20")] {
        let run = |threads: &str| {
            let o = pf_viz_ok(&[
                "bench",
                "filter",
                "--model",
                model,
                "--particles",
                "5000",
                "--steps",
                steps,
                "--threads",
                threads,
                "--json",
            ]);
            serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()
        };
        let (one, two) = (run("1"), run("2"));
        for key in [
            "model",
            "particles",
            "steps",
            "threads",
            "seconds",
            "ns_per_particle_step",
            "loglik",
            "kernels",
        ] {
            assert!(one.get(key).is_some(), "{model}: missing {key}");
        }
        assert_eq!(one["model"], model);
        assert_eq!(one["particles"], 5000);
        assert_eq!(one["steps"].to_string(), steps, "{model}");
        let ll = one["loglik"].as_f64().unwrap();
        assert!(ll.is_finite(), "{model}: {ll}");
        assert_eq!(
            ll.to_bits(),
            two["loglik"].as_f64().unwrap().to_bits(),
            "{model}: one thread against two"
        );
    }
    let o = pf_viz(&["bench", "filter", "--model", "bogus"]);
    assert!(!o.status.success() && o.stdout.is_empty());
    let o = pf_viz(&[
        "bench",
        "filter",
        "--model",
        "radar",
        "--particles",
        "0",
        "--json",
    ]);
    one_line_error(&o, "bench filter N = 0", &["--particles"]);
    assert!(o.stdout.is_empty());
}

/// `bench filter --model radar --data` reads its measurements by column name: the same rows
/// in another layout (Windows line ends, a byte-order mark, the columns swapped, an extra
/// column) give the same estimate, bit for bit; `,` is a missing measurement; a bad row is a
/// one-line error naming its line, and a blank line among the rows is refused rather than
/// skipped (which would shift every later measurement by a step).
#[test]
fn bench_filter_reads_radar_measurements_by_column() {
    let dir = Scratch::new("radar-data");
    let rows = [
        (2503.46, 0.6443),
        (2493.20, 0.6513),
        (2481.53, 0.6589),
        (2443.94, 0.6657),
        (2431.08, 0.6721),
    ];
    let plain: String = std::iter::once("range,azimuth\n".to_owned())
        .chain(rows.iter().map(|(r, a)| format!("{r},{a}\n")))
        .collect();
    let other: String = std::iter::once("\u{feff}note,azimuth,range\r\n".to_owned())
        .chain(rows.iter().map(|(r, a)| format!("x,{a},{r}\r\n")))
        .collect();
    let loglik = |path: &str| {
        let v = pf_viz_json(&[
            "bench",
            "filter",
            "--model",
            "radar",
            "--data",
            path,
            "--particles",
            "2000",
            "--json",
        ]);
        assert_eq!(v["steps"], 5, "{path}");
        v["loglik"].as_f64().unwrap()
    };
    let a = loglik(&dir.file("plain.csv", &plain));
    let b = loglik(&dir.file("other.csv", &other));
    assert!(a.is_finite());
    assert_eq!(a.to_bits(), b.to_bits(), "{a} against {b}");
    let gap = plain.replacen("2481.53,0.6589", ",", 1);
    let c = loglik(&dir.file("gap.csv", &gap));
    assert!(
        c.is_finite() && c != a,
        "a missing measurement: {c} against {a}"
    );

    for (name, text, needles) in [
        (
            "nan.csv",
            plain.replacen("0.6589", "NaN", 1),
            &[
                "nan.csv, line 4",
                "`azimuth` = `NaN` is not a finite number",
            ][..],
        ),
        (
            "half.csv",
            plain.replacen("2481.53,", ",", 1),
            &["half.csv, line 4", "both be given"][..],
        ),
        (
            "blank.csv",
            plain.replacen("2481.53", "\n2481.53", 1),
            &["blank.csv, line 4", "blank line", "`,`"][..],
        ),
        (
            "header.csv",
            plain.replacen("range,azimuth", "r,azimuth", 1),
            &["header.csv, line 1", "no `range` column"][..],
        ),
    ] {
        let path = dir.file(name, &text);
        let o = pf_viz(&[
            "bench", "filter", "--model", "radar", "--data", &path, "--json",
        ]);
        assert_eq!(o.status.code(), Some(1), "{name}");
        assert!(o.stdout.is_empty(), "{name}");
        one_line_error(&o, name, needles);
    }
}

/// `--simd` chooses which compiled copy of pf-core's kernels runs, never the estimate: every
/// model gives the same log-likelihood, bit for bit, on the portable, AVX2 and widest
/// copies, and the JSON's `kernels` names the copy that ran (`portable` when asked for).
#[test]
fn bench_kernel_copies_give_the_same_estimate() {
    for (model, steps) in [("ar1", "20"), ("radar", "10"), ("bearings", "6")] {
        let run = |simd: &str| {
            pf_viz_json(&[
                "bench",
                "filter",
                "--model",
                model,
                "--particles",
                "3000",
                "--steps",
                steps,
                "--simd",
                simd,
                "--json",
            ])
        };
        let (auto, avx2, portable) = (run("auto"), run("avx2"), run("portable"));
        assert_eq!(portable["kernels"], "portable", "{model}");
        assert!(
            ["avx512", "avx2", "portable"].contains(&auto["kernels"].as_str().unwrap()),
            "{model}: {}",
            auto["kernels"]
        );
        assert_ne!(
            avx2["kernels"], "avx512",
            "{model}: --simd avx2 caps the copy"
        );
        // On a CPU that has them the three copies really are three (else two of the
        // comparisons below would compare the portable copy with itself).
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
            assert_eq!(avx2["kernels"], "avx2", "{model}");
            let widest = if is_x86_feature_detected!("avx512f")
                && is_x86_feature_detected!("avx512dq")
                && is_x86_feature_detected!("avx512bw")
                && is_x86_feature_detected!("avx512vl")
            {
                "avx512"
            } else {
                "avx2"
            };
            assert_eq!(auto["kernels"], widest, "{model}");
        }
        let bits = |v: &serde_json::Value| v["loglik"].as_f64().unwrap().to_bits();
        assert_eq!(
            bits(&auto),
            bits(&portable),
            "{model}: widest against portable"
        );
        assert_eq!(
            bits(&avx2),
            bits(&portable),
            "{model}: AVX2 against portable"
        );
    }
    let o = pf_viz(&["bench", "bootstrap", "--simd", "sse9", "--json"]);
    assert!(o.stdout.is_empty());
    one_line_error(&o, "--simd sse9", &["sse9", "auto, avx2 or portable"]);
}
