//! How often each method associates clutter on the ants with heavy clutter.
use pf_core::mc::stream_rng;
use pf_epf::experiments::{Method, tracker_for};
use pf_epf::scenario::{Scenario, ScenarioConfig, simulate};
use pf_epf::tracker::{Record, track};

fn main() {
    let sc = ScenarioConfig {
        scenario: Scenario::Ants,
        clutter: 3.0,
        miss: 0.2,
    };
    for m in [Method::Epf, Method::EpfArgmin, Method::Nnsf] {
        let (mut clutter, mut wrong_target, mut none_when_present, mut total) = (0, 0, 0, 0);
        for r in 0..300 {
            let sim = simulate(&sc, &mut stream_rng(9, r)).unwrap();
            let mut cfg = tracker_for(Scenario::Ants);
            cfg.n_particles = 200;
            let res = track(
                &sim.detections,
                &sim.init,
                &m.configure(&cfg),
                Record::Tracks,
                &mut stream_rng(10, r),
            )
            .unwrap();
            for t in &res.tracks {
                for (i, &f) in res.frames.iter().enumerate() {
                    total += 1;
                    let rows = sim.detections.frame_rows(f);
                    let truth = rows
                        .clone()
                        .find(|&j| sim.detections.rows()[j].target == Some(t.target));
                    match t.detection[i] {
                        Some(j) if sim.detections.rows()[j].target.is_none() => clutter += 1,
                        Some(j) if Some(j) != truth => wrong_target += 1,
                        None if truth.is_some() => none_when_present += 1,
                        _ => {}
                    }
                }
            }
        }
        let p = |x: usize| x as f64 / total as f64;
        println!(
            "{:14} clutter {:.3} other target {:.3} missed own {:.3}",
            m.label(),
            p(clutter),
            p(wrong_target),
            p(none_when_present)
        );
    }
}
