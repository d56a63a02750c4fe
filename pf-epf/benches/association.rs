//! Speed of one frame's association (energies + assignment) and of a whole track.
//! Ids: `associate/<association>/K=6,M=<m>`, `track/<scenario>/N=300`.
#![allow(missing_docs)] // criterion's macros generate undocumented items

use criterion::{Criterion, criterion_group, criterion_main};
use pf_core::mc::stream_rng;
use pf_epf::experiments::{Method, tracker_for};
use pf_epf::scenario::{Scenario, ScenarioConfig, simulate};
use pf_epf::tracker::{Record, Tracker, track, tracked_frames};
use std::hint::black_box;

fn associate(c: &mut Criterion) {
    // The ants' key frame with clutter: 6 targets, about 9 detections.
    let sc = ScenarioConfig {
        scenario: Scenario::Ants,
        clutter: 3.0,
        miss: 0.0,
    };
    let sim = simulate(&sc, &mut stream_rng(1, 0)).expect("valid scenario");
    let frames = tracked_frames(&sim.detections, &sim.init).expect("frames");
    let last = frames[frames.len() - 1];
    let rows = sim.detections.frame_rows(last);
    let ys: Vec<_> = sim.detections.rows()[rows]
        .iter()
        .map(|d| d.position)
        .collect();
    for m in [Method::Epf, Method::EpfArgmin, Method::Nnsf] {
        let cfg = m.configure(&tracker_for(Scenario::Ants));
        let mut rng = stream_rng(2, 0);
        let mut tracker = Tracker::new(&sim.init, &cfg, &mut rng).expect("valid config");
        for &f in &frames[..frames.len() - 1] {
            let r = sim.detections.frame_rows(f);
            let y: Vec<_> = sim.detections.rows()[r]
                .iter()
                .map(|d| d.position)
                .collect();
            tracker.step(f, &y, &mut rng).expect("step");
        }
        // The geometry of the last frame, associated again and again.
        let geometry = tracker.geometry().to_vec();
        let mut assoc = pf_epf::association::Associator::new();
        let gamma = pf_epf::association::gate_threshold(cfg.gate_probability).expect("P_G");
        let mut out = vec![None; geometry.len()];
        c.bench_function(
            &format!("associate/{}/K=6,M={}", cfg.association.name(), ys.len()),
            |b| {
                b.iter(|| {
                    assoc.associate(
                        black_box(&geometry),
                        black_box(&ys),
                        gamma,
                        cfg.association,
                        &cfg.energy,
                        &mut out,
                    );
                    black_box(&out);
                })
            },
        );
    }
}

fn whole_track(c: &mut Criterion) {
    for s in Scenario::ALL {
        let sim = simulate(&ScenarioConfig::new(s), &mut stream_rng(1, 0)).expect("valid");
        let mut cfg = tracker_for(s);
        cfg.n_particles = 300;
        c.bench_function(&format!("track/{}/N=300", s.name()), |b| {
            b.iter(|| {
                track(
                    &sim.detections,
                    &sim.init,
                    &cfg,
                    Record::Tracks,
                    &mut stream_rng(3, 0),
                )
                .expect("track")
            })
        });
    }
}

criterion_group!(benches, associate, whole_track);
criterion_main!(benches);
