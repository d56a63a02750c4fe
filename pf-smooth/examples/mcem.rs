//! Maximum likelihood for the noisy AR(1) of Section 5 by three EM algorithms side by side,
//! from the paper's starting point `θ_0 = (0.8, 0.5², 2²)` on 1000 simulated observations:
//!
//! - **exact EM**: the expectations of (10)–(12) from the Kalman smoother;
//! - **Monte Carlo EM**: the fixed-lag estimate (δ = 20, eqs. (8)–(9)) of a bootstrap filter
//!   whose particle count grows geometrically, so the iterates settle at the EM fixed point;
//! - **SEM**: the same with a fixed `N = 100`, whose iterates keep moving around it (Fig. 4).
//!
//! EM itself is slow on this model: after 40 iterations `σ²` is still well above the
//! maximum-likelihood value, shown for reference from 5000 exact EM iterations. The two
//! simulation-based runs follow the exact one closely all the way.
//!
//! `cargo run --release -p pf-smooth --example mcem`

use pf_core::mc::stream_rng;
use pf_core::models::NoisyAr1;
use pf_smooth::em::{Estimator, ParticleSchedule, StochasticEm};
use pf_smooth::exact::{exact_em, exact_log_likelihood};
use pf_smooth::{Ar1Data, SmoothError, Theta};

fn main() -> Result<(), SmoothError> {
    let truth = Theta::paper_truth();
    let (_, y) = NoisyAr1::new(truth.phi, truth.sigma2.sqrt(), truth.rho2.sqrt())?
        .simulate(1000, &mut stream_rng(1, 0));
    let data = Ar1Data::new(y)?;
    let start = Theta::paper_start();
    let iterations = 40;

    let exact = exact_em(&data, &start, iterations)?;
    let mcem = StochasticEm {
        particles: ParticleSchedule::Geometric {
            n0: 50,
            ratio: 1.15,
            max: 2000,
        },
        estimator: Estimator::FixedLag(20),
        iterations,
    }
    .run(&data, &start, 0, &mut stream_rng(2, 0))?;
    let sem = StochasticEm {
        particles: ParticleSchedule::Fixed(100),
        estimator: Estimator::FixedLag(20),
        iterations,
    }
    .run(&data, &start, 1, &mut stream_rng(2, 1))?;

    println!("  i  |       exact EM        |    MCEM (N → 2000)    |     SEM (N = 100)");
    println!("     |   φ      σ²     ρ²    |   φ      σ²     ρ²    |   φ      σ²     ρ²");
    for i in [0, 1, 2, 5, 10, 20, 30, 40] {
        let row = |t: &Theta| format!("{:.3}  {:.4}  {:.3}", t.phi, t.sigma2, t.rho2);
        println!(
            " {i:>3} | {} | {} | {}",
            row(&exact[i]),
            row(&mcem[i]),
            row(&sem[i])
        );
    }
    let mle = exact_em(&data, &start, 5000)?[5000];
    println!(
        "   ∞ | {:.3}  {:.4}  {:.3} | (5000 exact EM iterations: the maximum likelihood)",
        mle.phi, mle.sigma2, mle.rho2
    );
    let at = |t: &Theta| exact_log_likelihood(&data, t);
    println!(
        "\nexact log-likelihood at θ_40: EM {:.3}, MCEM {:.3}, SEM {:.3}; at θ_0 {:.3}, \
         at the maximum {:.3}",
        at(&exact[iterations])?,
        at(&mcem[iterations])?,
        at(&sem[iterations])?,
        at(&start)?,
        at(&mle)?
    );
    Ok(())
}
