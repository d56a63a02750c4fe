//! The diagnosis behind the README's "Ordering" section: RMS position error over time of
//! the four filters plus two references, for a chosen turn direction and σ.
//!
//! - `UKF-LPC/cart`: the UKF-LPC started from the OHF's Cartesian Gaussian prior, which
//!   tells whether the OHF's initialisation explains a gap;
//! - `KL-opt`: the KL-optimal Gaussian correction computed directly (`Scheme::Direct`), the
//!   limit of the HΔE as its λ steps shrink.
//!
//! ```text
//! cargo run --release -p pf-homotopy --example ordering_diagnosis -- [R] [σ°] [turn °/s]
//! ```
//! (defaults: 40 realisations, the default σ and turn; seed 0, PF with N = 10 000).
use pf_core::mc::{Par, try_replicate};
use pf_homotopy::HomotopyError;
use pf_homotopy::filters::{FilterSettings, ohf_tracker, pf, ukf_lpc};
use pf_homotopy::model::ScenarioConfig;
use pf_homotopy::ohf::OhfConfig;
use pf_homotopy::prior::gaussian_prior;
use rand::RngExt;

fn main() -> Result<(), HomotopyError> {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("numeric arguments"))
        .collect();
    let base = ScenarioConfig::default();
    let reals = args.first().map_or(40, |&r| r as usize);
    let sc = ScenarioConfig {
        sigma_deg: *args.get(1).unwrap_or(&base.sigma_deg),
        turn_rate_deg: *args.get(2).unwrap_or(&base.turn_rate_deg),
        ..base
    };
    let set = FilterSettings::default();
    let names = ["UKF-LPC", "UKF-LPC/cart", "KL-opt", "OHF", "AOHF", "PF"];
    let runs = try_replicate(0, reals, Par::Rayon, |_, rng| {
        let real = sc.simulate(rng)?;
        let (obs, ys) = (&real.observer, &real.bearings);
        let g0 = gaussian_prior(&sc.prior, ys[0], sc.sigma(), obs[0].pos);
        let from_cart = ukf_lpc::run_from(
            ukf_lpc::UkfLpc::from_cartesian(&sc, set.ukf, g0.mean, g0.cov, &obs[0])?,
            &real,
        )?;
        let est = [
            ukf_lpc::run(&sc, set.ukf, &real)?,
            from_cart,
            ohf_tracker::run(&sc, &OhfConfig::direct(), &set.grid, &real)?,
            ohf_tracker::run(&sc, &set.ohf, &set.grid, &real)?,
            ohf_tracker::run(&sc, &set.aohf, &set.grid, &real)?,
            pf::run(&sc, 10_000, &real, rng.random())?,
        ];
        Ok::<_, HomotopyError>(
            est.iter()
                .map(|e| {
                    e.iter()
                        .zip(&real.target)
                        .map(|(e, x)| (e[0] - x[0]).powi(2) + (e[1] - x[1]).powi(2))
                        .collect::<Vec<f64>>()
                })
                .collect::<Vec<_>>(),
        )
    })?;
    println!(
        "σ = {}°, turn {} °/s, {reals} realisations: RMS position error (m)",
        sc.sigma_deg, sc.turn_rate_deg
    );
    print!("{:>4}", "k");
    names.iter().for_each(|n| print!(" {n:>13}"));
    println!();
    for k in (0..sc.n_samples).filter(|k| k % 5 == 0 || k + 1 == sc.n_samples || *k == 16) {
        print!("{:>4}", k + 1);
        for a in 0..names.len() {
            let ms = runs.iter().map(|r| r[a][k]).sum::<f64>() / reals as f64;
            print!(" {:>13.0}", ms.sqrt());
        }
        println!();
    }
    Ok(())
}
