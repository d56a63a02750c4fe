//! EPF against NNSF on the three scenarios: `cargo run --release --example compare -p pf-epf -- R`.
use pf_epf::dynamics::SplineOrder;
use pf_epf::experiments::{ComparisonConfig, Method, compare};
use pf_epf::scenario::{Scenario, ScenarioConfig};

fn main() -> pf_epf::Result<()> {
    let reps: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(50);
    for (order, cap) in [
        (SplineOrder::Linear, 20.0),
        (SplineOrder::Quadratic, 20.0),
        (SplineOrder::Quadratic, 5.0),
        (SplineOrder::Quadratic, 2.0),
    ] {
        println!("E² model {order:?}, radius cap {cap}");
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
                cfg.tracker.energy.radius_cap = cap;
                cfg.methods = vec![Method::Epf, Method::Nnsf];
                let c = compare(&cfg)?;
                let (e, n) = (&c.methods[0], &c.methods[1]);
                println!(
                    "  {:12} clutter {clutter} miss {miss}: EPF {:.3} NNSF {:.3} (rmse {:.2} / {:.2})",
                    s.name(),
                    e.error_rate_mean.0,
                    n.error_rate_mean.0,
                    e.rmse_mean.0,
                    n.rmse_mean.0
                );
            }
        }
    }
    Ok(())
}
