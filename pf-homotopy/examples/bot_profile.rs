//! Temporary: profile the batch PF.
use pf_homotopy::experiments::bench::BearingsBench;
fn main() {
    let mut b = BearingsBench::new(100_000, 40, 1).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| {
        for _ in 0..5 {
            let t0 = std::time::Instant::now();
            let l = b.run().unwrap();
            println!("{l} {:.3}", t0.elapsed().as_secs_f64());
        }
    });
}
