//! EPF against NNSF on the three scenarios: `cargo run --example compare -p pf-epf`.
use pf_core::mc::Par;
use pf_epf::dynamics::SplineOrder;
use pf_epf::energy::E1Reference;
use pf_epf::experiments::{ComparisonConfig, Method, compare};
use pf_epf::scenario::{Scenario, ScenarioConfig};

fn main() -> Result<(), pf_epf::error::EpfError> {
    let reps: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(50);
    for (order, e1) in [
        (SplineOrder::Linear, E1Reference::Previous),
        (SplineOrder::Linear, E1Reference::Predicted),
        (SplineOrder::Quadratic, E1Reference::Previous),
    ] {
        println!("{order:?} {e1:?}");
        for s in Scenario::ALL {
            for (clutter, miss) in [(0.0, 0.0), (1.0, 0.1)] {
                let sc = ScenarioConfig {
                    scenario: s,
                    clutter,
                    miss,
                };
                let mut cfg = ComparisonConfig::new(sc, reps);
                cfg.tracker.n_particles = 200;
                cfg.tracker.energy_spline = order;
                cfg.tracker.energy.e1_reference = e1;
                cfg.methods = vec![Method::Epf, Method::EpfArgmin, Method::Nnsf];
                let c = compare(&cfg, 1, Par::Rayon, &|| {})?;
                for m in &c.methods {
                    println!(
                        "{:12} clutter {clutter} miss {miss} {:14} error rate {:.3} ± {:.3}  rmse {:.2}  ospa {:.2}",
                        s.name(),
                        m.method.label(),
                        m.error_rate_mean.0,
                        m.error_rate_mean.1,
                        m.rmse_mean.0,
                        m.ospa_mean.0
                    );
                }
            }
        }
    }
    Ok(())
}
