//! Scratch: find realisations where the OHF/AOHF fail.
use pf_core::mc::stream_rng;
use pf_homotopy::filters::{FilterSettings, ohf_tracker};
use pf_homotopy::model::ScenarioConfig;

fn main() {
    let set = FilterSettings::default();
    for seed in [0u64, 1, 2] {
        for turn in [-30.0, 30.0] {
            for sigma in [0.5, 1.0, 2.0] {
                let sc = ScenarioConfig {
                    sigma_deg: sigma,
                    turn_rate_deg: turn,
                    ..ScenarioConfig::default()
                };
                for r in 0..40u64 {
                    let real = sc.simulate(&mut stream_rng(seed, r)).unwrap();
                    for (name, c) in [("OHF", set.ohf), ("AOHF", set.aohf)] {
                        if let Err(e) = ohf_tracker::run(&sc, &c, &set.grid, &real) {
                            println!("seed {seed} turn {turn} sigma {sigma} r {r} {name}: {e}");
                        }
                    }
                }
            }
        }
    }
}
