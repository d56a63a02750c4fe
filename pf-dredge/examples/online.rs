//! Simulate a loading cycle and estimate the overflow on line, printing one JSON line per
//! sample as it arrives (what `pf-viz dredge estimate --online` does with a CSV stream).

use pf_core::mc::stream_rng;
use pf_dredge::estimator::{EstimatorConfig, OnlineEstimator};
use pf_dredge::simulator::{SimConfig, simulate};

fn main() -> Result<(), pf_dredge::DredgeError> {
    let data = simulate(&SimConfig::default(), &mut stream_rng(1, 0))?.to_data();
    let mut online = OnlineEstimator::new(&EstimatorConfig::default())?;
    let mut rng = stream_rng(0, 0);
    for k in (0..data.len()).take(2000) {
        let est = online.push(&data.sample(k), &mut rng)?;
        if k % 60 == 0 {
            println!(
                "{{\"t\": {}, \"Q_o\": {:.3}, \"rho_o\": {:.1}}}",
                est.t, est.q_o, est.rho_o
            );
        }
    }
    Ok(())
}
