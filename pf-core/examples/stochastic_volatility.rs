//! Your own model on pf-core: the stochastic volatility model of financial returns,
//!
//! `X_0 ~ N(μ, σ²/(1 − φ²))`, `X_t = μ + φ·(X_{t−1} − μ) + σ·V_t`, `Y_t = exp(X_t/2)·W_t`,
//!
//! with `V_t`, `W_t` independent standard normals. It implements [`StateSpaceModel`] (three
//! methods), runs the bootstrap filter with resampling when the ESS falls below N/2, reads
//! the filter's estimates and ESS through observers, and profiles the log-likelihood in `σ`
//! over seeded Monte Carlo replications, as a particle-marginal Metropolis–Hastings or a
//! grid search would use it:
//!
//! `cargo run --release -p pf-core --example stochastic_volatility`

use pf_core::filter::{EssThreshold, FilterConfig, ParticleFilter, ResamplePolicy};
use pf_core::gaussian::log_normal_pdf_1d;
use pf_core::mc::{Par, mean_and_se, replicate, stream_rng};
use pf_core::observe::{EssRecorder, EstimateRecorder};
use pf_core::{CoreError, StateSpaceModel};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

/// The model's parameters. It holds no random generator: every draw takes the caller's.
#[derive(Debug, Clone, Copy)]
struct StochasticVolatility {
    /// `μ`, the mean log-variance.
    mu: f64,
    /// `φ`, the persistence, `|φ| < 1`.
    phi: f64,
    /// `σ`, the volatility of the log-variance.
    sigma: f64,
}

impl StateSpaceModel for StochasticVolatility {
    type State = f64;
    type Obs = f64;
    type Input = ();

    fn sample_initial<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        // The stationary law, so that the filter starts where the simulation does.
        let z: f64 = StandardNormal.sample(rng);
        self.mu + self.sigma / (1.0 - self.phi * self.phi).sqrt() * z
    }

    fn sample_transition<R: Rng + ?Sized>(
        &self,
        _t: usize,
        x_prev: &f64,
        _u: Option<&()>,
        rng: &mut R,
    ) -> f64 {
        let z: f64 = StandardNormal.sample(rng);
        self.mu + self.phi * (x_prev - self.mu) + self.sigma * z
    }

    fn log_likelihood(&self, _t: usize, x: &f64, y: &f64) -> f64 {
        log_normal_pdf_1d(*y, 0.0, x.exp())
    }
}

impl StochasticVolatility {
    /// `y_0 … y_n` simulated from the model.
    fn simulate<R: Rng + ?Sized>(&self, n: usize, rng: &mut R) -> Vec<f64> {
        let mut x = self.sample_initial(rng);
        (0..=n)
            .map(|t| {
                if t > 0 {
                    x = self.sample_transition(t, &x, None, rng);
                }
                let w: f64 = StandardNormal.sample(rng);
                (x / 2.0).exp() * w
            })
            .collect()
    }
}

fn main() -> Result<(), CoreError> {
    let truth = StochasticVolatility {
        mu: -1.0,
        phi: 0.95,
        sigma: 0.3,
    };
    let ys: Vec<Option<f64>> = truth
        .simulate(500, &mut stream_rng(1, 0))
        .into_iter()
        .map(Some)
        .collect();

    // One filter, resampling (systematic, the default scheme) only when ESS < N/2.
    let config = FilterConfig {
        policy: ResamplePolicy::EssBelow(EssThreshold::Fraction(0.5)),
        ..FilterConfig::new(1000)
    };
    let mut pf = ParticleFilter::bootstrap(truth, config)?;
    let (mut ess, mut estimates) = (EssRecorder::new(), EstimateRecorder::new());
    let run = pf.run(
        &ys,
        None,
        &mut stream_rng(2, 0),
        &mut (&mut ess, &mut estimates),
    )?;
    let resampled = ess.resampled().iter().filter(|&&r| r).count();
    let least_ess = ess.ess().iter().copied().fold(f64::INFINITY, f64::min);
    println!(
        "{} steps, N = {}: log-likelihood {:.2}, resampled at {resampled} steps, \
         smallest ESS {least_ess:.0}",
        ys.len(),
        pf.n_particles(),
        run.log_lik,
    );
    let last = estimates.means.last().map_or(f64::NAN, |m| m[0]);
    println!(
        "E[X_n | y_0:n] ≈ {last:.3}: a volatility exp(X_n/2) of about {:.3}",
        (last / 2.0).exp()
    );

    // The log-likelihood as a function of σ: 20 independent filters per value, each on its
    // own stream of seed 3 (the same streams for every σ, so that the differences between
    // values are less noisy than the values), on every core.
    println!("\n   σ    log-likelihood (mean ± s.e. of 20 filters)");
    for sigma in [0.1, 0.2, 0.3, 0.4, 0.6] {
        let model = StochasticVolatility { sigma, ..truth };
        let logliks = replicate(3, 20, Par::Rayon, |_, rng| {
            let mut pf = ParticleFilter::bootstrap(model, config)?;
            Ok::<_, CoreError>(pf.run(&ys, None, rng, &mut ())?.log_lik)
        })
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?;
        let (mean, se) = mean_and_se(&logliks);
        println!("  {sigma:.1}  {mean:9.2} ± {se:.2}");
    }
    Ok(())
}
