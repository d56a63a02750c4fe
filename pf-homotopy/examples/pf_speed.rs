//! The PF of Section 4 at N = 10⁵: the generic filter's (`filters::pf_old`) against the
//! batch filter's, in one build: seconds per 40-step run on one thread and on two, and the
//! final RMS position error of each over the same realisations with its standard error.
//!
//! `cargo run --release -p pf-homotopy --example pf_speed [-- realisations]`
use std::time::Instant;

use pf_core::mc::{Par, rms_and_se, stream_rng, try_replicate};
use pf_homotopy::HomotopyError;
use pf_homotopy::filters::{pf, pf_old};
use pf_homotopy::model::ScenarioConfig;
use rand::RngExt;

/// CPU seconds of every thread of this process so far (`/proc/self/task/*/schedstat`), so
/// that a loaded machine's waiting does not count.
fn cpu_seconds() -> f64 {
    let mut ns = 0u64;
    if let Ok(dir) = std::fs::read_dir("/proc/self/task") {
        for t in dir.flatten() {
            if let Ok(s) = std::fs::read_to_string(t.path().join("schedstat")) {
                ns += s
                    .split_whitespace()
                    .next()
                    .and_then(|v| v.parse().ok())
                    .unwrap_or(0);
            }
        }
    }
    ns as f64 * 1e-9
}

fn main() -> Result<(), HomotopyError> {
    let realisations: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(40);
    let n = 100_000;
    let sc = ScenarioConfig::default();
    let real = sc.simulate(&mut stream_rng(1, 0))?;
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool");
        pool.install(|| -> Result<(), HomotopyError> {
            let reps = 7;
            let (mut old, mut new, mut old_cpu, mut new_cpu) = (vec![], vec![], vec![], vec![]);
            for r in 0..reps {
                let (t0, c0) = (Instant::now(), cpu_seconds());
                pf_old::run(&sc, n, &real, &mut stream_rng(2, r))?;
                old.push(t0.elapsed().as_secs_f64());
                old_cpu.push(cpu_seconds() - c0);
                let (t0, c0) = (Instant::now(), cpu_seconds());
                pf::run(&sc, n, &real, r)?;
                new.push(t0.elapsed().as_secs_f64());
                new_cpu.push(cpu_seconds() - c0);
            }
            let med = |v: &mut Vec<f64>| {
                v.sort_by(f64::total_cmp);
                v[v.len() / 2]
            };
            let (o, b) = (med(&mut old), med(&mut new));
            let (oc, bc) = (med(&mut old_cpu), med(&mut new_cpu));
            let (om, bm) = (old_cpu[0], new_cpu[0]);
            println!(
                "{threads} thread(s), N = {n}, median of {reps} runs: wall generic {o:.3} s, batch {b:.3} s, ratio {:.1}; CPU generic {oc:.3} s, batch {bc:.3} s, ratio {:.1}; least CPU generic {om:.3} s, batch {bm:.3} s, ratio {:.1}",
                o / b,
                oc / bc,
                om / bm
            );
            Ok(())
        })?;
    }
    // Final errors over the same realisations (both filters on each).
    let runs = try_replicate(0, realisations, Par::Rayon, |_, rng| {
        let real = sc.simulate(rng)?;
        let seed: u64 = rng.random();
        let old = pf_old::run(&sc, n, &real, rng)?;
        let new = pf::run(&sc, n, &real, seed)?;
        let x = real.target[real.target.len() - 1];
        let sq = |e: &Vec<[f64; 2]>| {
            let p = e[e.len() - 1];
            (p[0] - x[0]).powi(2) + (p[1] - x[1]).powi(2)
        };
        Ok::<_, HomotopyError>((sq(&old), sq(&new)))
    })?;
    let (o, b): (Vec<f64>, Vec<f64>) = runs.into_iter().unzip();
    let (ro, so) = rms_and_se(&o);
    let (rb, sb) = rms_and_se(&b);
    println!(
        "final RMS position error over {realisations} realisations: generic {ro:.1} ± {so:.1} m, batch {rb:.1} ± {sb:.1} m"
    );
    Ok(())
}
