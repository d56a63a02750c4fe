//! Time of a radar MPF run per partition (Table II's partitions), N = 2000, 20 steps.
#![allow(missing_docs)] // criterion's macros generate undocumented items

use criterion::{Criterion, criterion_group, criterion_main};
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

criterion_group!(benches, partitions);
criterion_main!(benches);
