//! Profiling driver (not committed).
#![allow(missing_docs)]
use pf_core::mc::stream_rng;
use pf_core::resample::{Resample, Resampler};
use rand::RngExt;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scheme: Resampler = args[1].parse().unwrap();
    let n: usize = args.get(2).map_or(1_000_000, |s| s.parse().unwrap());
    let reps: usize = args.get(3).map_or(20, |s| s.parse().unwrap());
    let mut rng = stream_rng(3, 0);
    let raw: Vec<f64> = (0..n).map(|_| rng.random::<f64>().powi(4)).collect();
    let total: f64 = raw.iter().sum();
    let w: Vec<f64> = raw.iter().map(|x| x / total).collect();
    let mut a = vec![0usize; n];
    let mut best = f64::INFINITY;
    for _ in 0..reps {
        let t = std::time::Instant::now();
        scheme.resample(&w, &mut rng, &mut a);
        best = best.min(t.elapsed().as_secs_f64());
        std::hint::black_box(&a);
    }
    println!("{scheme} N={n}: {:.3} ns/particle", best * 1e9 / n as f64);
}
