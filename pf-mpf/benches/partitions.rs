//! Time of a radar MPF run per partition (Table II's partitions), N = 2000, 20 steps; and
//! the standard PF on the radar model (13) at N = 10³ … 10⁶, one thread (`radar_pf`, the
//! filter of `pf-viz bench filter --model radar`), in elements = particle-steps.
#![allow(missing_docs)] // criterion's macros generate undocumented items

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use pf_mpf::experiments::bench::RadarBench;
use pf_mpf::mpf::MpfConfig;
use pf_mpf::radar::{Partition, RadarConfig, run_partition};

fn partitions(c: &mut Criterion) {
    let cfg = RadarConfig {
        n_steps: 20,
        ..RadarConfig::default()
    };
    let truth = cfg.truth();
    let ys = cfg.measure(&truth, &mut pf_core::mc::stream_rng(0, 0));
    let mut g = c.benchmark_group("mpf_radar");
    g.sample_size(10);
    for part in Partition::paper() {
        g.bench_function(format!("{}/N=2000", part.name()), |b| {
            b.iter(|| {
                let mut rng = pf_core::mc::stream_rng(1, 0);
                run_partition(&part, &cfg, MpfConfig::new(2000), &truth, &ys, &mut rng).unwrap()
            })
        });
    }
    g.finish();
}

fn radar_pf(c: &mut Criterion) {
    let steps = 20;
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut g = c.benchmark_group("radar_pf");
    g.sample_size(10);
    for n in [1_000usize, 10_000, 100_000, 1_000_000] {
        let mut bench = RadarBench::new(n, steps, 0).unwrap();
        g.throughput(Throughput::Elements((n * steps) as u64));
        g.bench_function(format!("N={n}"), |b| {
            b.iter(|| one.install(|| bench.run().unwrap()))
        });
    }
    g.finish();
}

criterion_group!(benches, partitions, radar_pf);
criterion_main!(benches);
