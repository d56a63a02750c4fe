//! Speed of the standard PF (`PPPPPP`) on the radar model (13), one thread: ns per
//! particle-step at N = 10³ … 10⁶. `cargo run --release -p pf-mpf --example radar_speed`.
use pf_mpf::mpf::MpfConfig;
use pf_mpf::radar::{Partition, RadarConfig, run_partition};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let steps = 20;
    let cfg = RadarConfig {
        n_steps: steps,
        ..RadarConfig::default()
    };
    let truth = cfg.truth();
    let ys = cfg.measure(&truth, &mut pf_core::mc::stream_rng(0, 0));
    let part: Partition = "PPPPPP".parse()?;
    for n in [1_000usize, 10_000, 100_000, 1_000_000] {
        let reps = (2_000_000 / n).clamp(2, 50);
        let mut best = f64::INFINITY;
        for r in 0..reps {
            let mut rng = pf_core::mc::stream_rng(1, r as u64);
            let run = run_partition(&part, &cfg, MpfConfig::new(n), &truth, &ys, &mut rng)?;
            best = best.min(run.time_s);
        }
        println!(
            "PPPPPP N = {n:>8}: {:8.1} ns per particle-step",
            best * 1e9 / (n * steps) as f64
        );
    }
    Ok(())
}
