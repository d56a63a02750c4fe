//! Speed of the standard PF (`PPPPPP`) on the radar model (13): ns per particle-step at
//! N = 10³ … 10⁶, one thread (and two at 10⁶), through [`run_partition`] (with the
//! estimates every step) and through the benchmark [`RadarBench`] (the filter alone).
//! `cargo run --release -p pf-mpf --example radar_speed [steps [N]]`.
use pf_mpf::experiments::bench::RadarBench;
use pf_mpf::mpf::MpfConfig;
use pf_mpf::radar::{Partition, RadarConfig, run_partition};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let steps: usize = match std::env::args().nth(1) {
        Some(s) => s.parse()?,
        None => 20,
    };
    let cfg = RadarConfig {
        n_steps: steps,
        ..RadarConfig::default()
    };
    let truth = cfg.truth();
    let ys = cfg.measure(&truth, &mut pf_core::mc::stream_rng(0, 0));
    let part: Partition = "PPPPPP".parse()?;
    let pool = |k| rayon::ThreadPoolBuilder::new().num_threads(k).build();
    let (one, two) = (pool(1)?, pool(2)?);
    let only: Option<usize> = std::env::args().nth(2).map(|s| s.parse()).transpose()?;
    for n in [1_000usize, 10_000, 100_000, 1_000_000] {
        if only.is_some_and(|o| o != n) {
            continue;
        }
        let reps = (2_000_000 / n).clamp(3, 50);
        let per = |s: f64| s * 1e9 / (n * steps) as f64;
        let mut best = f64::INFINITY;
        for r in 0..reps {
            let mut rng = pf_core::mc::stream_rng(1, r as u64);
            let run = run_partition(&part, &cfg, MpfConfig::new(n), &truth, &ys, &mut rng)?;
            best = best.min(run.time_s);
        }
        let mut bench = RadarBench::with_observations(ys.clone(), n, 1)?;
        let mut time = |pool: &rayon::ThreadPool| -> Result<f64, pf_mpf::MpfError> {
            let mut best = f64::INFINITY;
            for _ in 0..reps {
                let s = Instant::now();
                pool.install(|| bench.run())?;
                best = best.min(s.elapsed().as_secs_f64());
            }
            Ok(best)
        };
        let b1 = time(&one)?;
        let b2 = if n == 1_000_000 {
            time(&two)?
        } else {
            f64::NAN
        };
        println!(
            "PPPPPP N = {n:>8}: run_partition {:7.1}, RadarBench 1 thread {:7.1}, 2 threads {:7.1} ns per particle-step",
            per(best),
            per(b1),
            per(b2)
        );
    }
    Ok(())
}
