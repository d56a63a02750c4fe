//! Profiling driver (not committed).
#![allow(missing_docs)]
use pf_core::filter::{BatchBootstrap, BatchConfig};
use pf_core::mc::{Par, stream_rng};
use pf_core::models::NoisyAr1;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map_or(10_000, |s| s.parse().unwrap());
    let steps: usize = args.get(2).map_or(100, |s| s.parse().unwrap());
    let chunk: usize = args.get(3).map_or(2048, |s| s.parse().unwrap());
    let model = NoisyAr1::new(0.98, 0.2, 1.0).unwrap();
    let (_, ys) = model.simulate(steps - 1, &mut stream_rng(1, 0));
    let ys: Vec<Option<f64>> = ys.into_iter().map(Some).collect();
    let cfg = BatchConfig {
        par: Par::Seq,
        chunk,
        ..BatchConfig::new(n, 2)
    };
    let mut f = BatchBootstrap::new(model, cfg).unwrap();
    let mut best = f64::INFINITY;
    let reps: usize = args.get(4).map_or(5, |s| s.parse().unwrap());
    for _ in 0..reps {
        let t = std::time::Instant::now();
        let ll = f.run(&ys).unwrap().log_lik;
        let dt = t.elapsed().as_secs_f64();
        best = best.min(dt);
        std::hint::black_box(ll);
    }
    println!(
        "N={n} steps={steps} chunk={chunk}: {:.3} ns/particle-step (best of {reps})",
        best * 1e9 / (n * steps) as f64
    );
}
