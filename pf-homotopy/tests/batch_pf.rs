//! The PF with the linearised optimal proposal on the batch filter: its chunk functions
//! against per-particle formulas (the generic filter's, which they replaced), its weights
//! against the Kalman filter on a linear measurement, and its runs for any thread count.

use nalgebra::{Matrix4, RowVector4, Vector4};
use pf_core::filter::{BatchModel, BatchProposal, BatchTransitionDensity, Cols, ColsMut};
use pf_core::gaussian::LN_2PI;
use pf_core::geometry::wrap_angle;
use pf_core::mc::{PfRng, stream_rng};
use pf_homotopy::filters::pf::{BotModel, LinearisedOptimal};
use pf_homotopy::model::{ScenarioConfig, State, bearing};
use pf_homotopy::prior::sample_prior;
use rand_distr::{Distribution, StandardNormal};

/// The per-particle formulas of the generic filter's PF, in nalgebra, as references.
struct Reference {
    f: Matrix4<f64>,
    lq: Matrix4<f64>,
    q: Matrix4<f64>,
    q_inv: Matrix4<f64>,
    ln_det_q: f64,
    sigma: f64,
}

impl Reference {
    fn new(sc: &ScenarioConfig) -> Self {
        let q = sc.q_matrix();
        let chol = q.cholesky().unwrap();
        let lq = chol.l();
        Reference {
            f: sc.f(),
            lq,
            q,
            q_inv: chol.inverse(),
            ln_det_q: 2.0 * (0..4).map(|i| lq[(i, i)].ln()).sum::<f64>(),
            sigma: sc.sigma(),
        }
    }

    /// `log N(wrap_angle(y − h(x, ρ)); 0, σ²)`.
    fn log_likelihood(&self, rho: [f64; 2], x: &State, y: f64) -> f64 {
        let e = wrap_angle(y - bearing([x[0], x[1]], rho)) / self.sigma;
        -0.5 * (LN_2PI + e * e) - self.sigma.ln()
    }

    /// `log N(x; F x_prev, Q)`.
    fn log_transition(&self, x_prev: &State, x: &State) -> f64 {
        let d = x - self.f * x_prev;
        -0.5 * (4.0 * LN_2PI + self.ln_det_q + d.dot(&(self.q_inv * d)))
    }

    /// The Matheron draw from `z`, `ε` and its log-density.
    fn propose(&self, rho: [f64; 2], x_prev: &State, y: f64, z: &State, eps: f64) -> (State, f64) {
        let xb = self.f * x_prev;
        let (dx, dy) = (xb[0] - rho[0], xb[1] - rho[1]);
        let r2 = dx * dx + dy * dy;
        let h = RowVector4::new(-dy / r2, dx / r2, 0.0, 0.0);
        let e = wrap_angle(y - dy.atan2(dx));
        let s = (h * self.q * h.transpose())[(0, 0)] + self.sigma * self.sigma;
        let k = self.q * h.transpose() / s;
        let x0 = xb + self.lq * z;
        let innov = e - (h * (x0 - xb))[(0, 0)] - self.sigma * eps;
        let x = x0 + k * innov;
        let d = x - (xb + k * e);
        let s2 = self.sigma * self.sigma;
        let hd = (h * d)[(0, 0)];
        let quad = d.dot(&(self.q_inv * d)) + hd * hd / s2;
        let ln_det = self.ln_det_q - (s / s2).ln();
        (x, -0.5 * (4.0 * LN_2PI + ln_det + quad))
    }
}

fn normals(rng: &mut PfRng, n: usize) -> Vec<f64> {
    (0..n).map(|_| StandardNormal.sample(rng)).collect()
}

/// `|a − b| ≤ 1e-12·max(|a|, |b|)`, with a message.
fn close(a: f64, b: f64, what: &str) {
    assert!(
        (a - b).abs() <= 1e-12 * a.abs().max(b.abs()),
        "{what}: {a} vs {b}"
    );
}

/// Column-major `[col][i]` from row vectors.
fn columns(xs: &[State]) -> Vec<f64> {
    (0..4).flat_map(|k| xs.iter().map(move |x| x[k])).collect()
}

/// Every chunk function of the model and the proposal gives, particle by particle, what
/// the per-particle formulas give on the same parents and the same normals, to 1e-12
/// relative: the initial draw, the transition, its density, the likelihood, and the
/// proposal's draw and log-density (with a bearing, and without one, where it is the
/// transition). Parents spread over the prior (ranges 0–20 km, all bearings), so that
/// residuals wrap and the reduction branches of `atan2` are all taken.
#[test]
fn chunk_functions_agree_with_the_per_particle_formulas() {
    let sc = ScenarioConfig::default();
    let rho = [[0.0, 0.0], [150.0, -40.0], [290.0, -110.0]];
    let y1 = 1.39;
    let model = BotModel::new(&sc, rho.to_vec(), y1).unwrap();
    let r = Reference::new(&sc);
    let n = 1000;
    let mut rng = stream_rng(7, 0);

    // X_0 from the polar prior, normals in the order `sample_prior` draws them.
    let z0 = normals(&mut stream_rng(7, 1), 4 * n);
    let mut zc = vec![0.0; 4 * n];
    for i in 0..n {
        for k in 0..4 {
            zc[k * n + i] = z0[4 * i + k];
        }
    }
    let mut x0 = vec![0.0; 4 * n];
    model.initial(Cols::new(&zc, 4, n), ColsMut::new(&mut x0, 4, n));
    let mut replay = stream_rng(7, 1);
    for i in 0..n {
        let want = sample_prior(&sc.prior, y1, sc.sigma(), rho[0], &mut replay);
        for k in 0..4 {
            close(x0[k * n + i], want[k], "initial");
        }
    }

    // Parents anywhere around the observer (every quadrant, so that bearings wrap).
    let parents: Vec<State> = (0..n)
        .map(|_| {
            let z = normals(&mut rng, 4);
            Vector4::new(8000.0 * z[0], 8000.0 * z[1], 100.0 * z[2], 100.0 * z[3])
        })
        .collect();
    let pc = columns(&parents);
    let t = 2;
    let y = 3.1; // near the cut at ±π: residuals wrap for a share of the particles
    let zs = normals(&mut rng, 5 * n);

    // The proposal with a bearing.
    let mut x = vec![0.0; 4 * n];
    let mut log_q = vec![0.0; n];
    LinearisedOptimal.propose(
        &model,
        t,
        &(),
        Some(&y),
        Cols::new(&pc, 4, n),
        Cols::new(&zs, 5, n),
        ColsMut::new(&mut x, 4, n),
        &mut log_q,
    );
    let mut lt = vec![0.0; n];
    model.add_log_transition(t, &(), Cols::new(&pc, 4, n), Cols::new(&x, 4, n), &mut lt);
    let mut ll = vec![0.0; n];
    model.add_log_likelihood(t, &y, Cols::new(&x, 4, n), &mut ll);
    let mut wrapped = 0;
    for i in 0..n {
        let z = Vector4::from_fn(|k, _| zs[k * n + i]);
        let (want, want_q) = r.propose(rho[t], &parents[i], y, &z, zs[4 * n + i]);
        for k in 0..4 {
            close(x[k * n + i], want[k], "proposal draw");
        }
        close(log_q[i], want_q, "proposal log-density");
        let xi = Vector4::from_fn(|k, _| x[k * n + i]);
        close(
            lt[i],
            r.log_transition(&parents[i], &xi),
            "transition density",
        );
        close(ll[i], r.log_likelihood(rho[t], &xi, y), "likelihood");
        wrapped += usize::from((y - bearing([xi[0], xi[1]], rho[t])).abs() > std::f64::consts::PI);
    }
    assert!(wrapped > n / 10, "only {wrapped} residuals wrapped");

    // Without a bearing the proposal is the transition, and log q its density.
    let mut xf = vec![0.0; 4 * n];
    LinearisedOptimal.propose(
        &model,
        t,
        &(),
        None,
        Cols::new(&pc, 4, n),
        Cols::new(&zs, 5, n),
        ColsMut::new(&mut xf, 4, n),
        &mut log_q,
    );
    let mut xp = vec![0.0; 4 * n];
    model.propagate(
        t,
        &(),
        Cols::new(&pc, 4, n),
        Cols::new(&zs[..4 * n], 4, n),
        ColsMut::new(&mut xp, 4, n),
    );
    assert_eq!(xf, xp);
    for i in 0..n {
        let z = Vector4::from_fn(|k, _| zs[k * n + i]);
        let want = r.f * parents[i] + r.lq * z;
        for k in 0..4 {
            close(xp[k * n + i], want[k], "transition draw");
        }
        close(
            log_q[i],
            r.log_transition(&parents[i], &want),
            "log q = log f",
        );
    }
}

/// When `h` is linear over the proposal's spread, the linearised optimal density is the
/// optimal one and `g·f/q = p(y_k | x_{k−1}) = N(y; h(F x_{k−1}), H Q Hᵀ + σ²)` for every
/// draw. Here the spread is √Q ≈ 0.06 m at 5 km: the curvature term of h is
/// ~(0.3 m / 5 km)² ≈ 4e-9 rad, which moves log w by ≲ |e|·4e-9/σ² ≈ 1e-5; 1e-4 bounds it.
/// The target sits on the ±π cut, so the weights are right only if residuals wrap.
#[test]
fn linearised_optimal_weights_equal_the_predictive_density() {
    let sc = ScenarioConfig::default();
    let model = BotModel::new(&sc, vec![[0.0, 0.0]; 3], 0.0).unwrap();
    let x_prev = Vector4::new(-5000.0, 0.5, -10.0, 3.0);
    let xb = sc.f() * x_prev;
    let y = wrap_angle(bearing([xb[0], xb[1]], [0.0, 0.0]) + 0.015);
    let r2 = xb[0] * xb[0] + xb[1] * xb[1];
    let h = RowVector4::new(-xb[1] / r2, xb[0] / r2, 0.0, 0.0);
    let s = (h * sc.q_matrix() * h.transpose())[(0, 0)] + sc.sigma().powi(2);
    let e = wrap_angle(y - bearing([xb[0], xb[1]], [0.0, 0.0]));
    let want = -0.5 * ((2.0 * std::f64::consts::PI * s).ln() + e * e / s);
    let n = 200;
    let pc: Vec<f64> = (0..4).flat_map(|k| vec![x_prev[k]; n]).collect();
    let zs = normals(&mut stream_rng(3, 0), 5 * n);
    let mut x = vec![0.0; 4 * n];
    let mut lw = vec![0.0; n];
    LinearisedOptimal.propose(
        &model,
        1,
        &(),
        Some(&y),
        Cols::new(&pc, 4, n),
        Cols::new(&zs, 5, n),
        ColsMut::new(&mut x, 4, n),
        &mut lw,
    );
    for l in &mut lw {
        *l = -*l;
    }
    model.add_log_likelihood(1, &y, Cols::new(&x, 4, n), &mut lw);
    model.add_log_transition(1, &(), Cols::new(&pc, 4, n), Cols::new(&x, 4, n), &mut lw);
    for l in lw {
        assert!((l - want).abs() < 1e-4, "{l} vs {want}");
    }
}

/// With a linear measurement of the position the linearised optimal proposal is the
/// optimal one, and the model linear-Gaussian: the guided batch filter's likelihood
/// estimate `Ẑ` is unbiased for the Kalman filter's exact `Z`, so `Ẑ/Z` averages to 1 over
/// seeded replications (within 3 standard errors), with a missing observation on the way.
#[test]
fn guided_batch_likelihood_is_unbiased_against_the_kalman_filter() {
    use nalgebra::{DMatrix, DVector};
    use pf_core::kalman::{LinearGaussian, kalman_filter};
    use pf_core::mc::{Par, mean_and_se};
    use pf_homotopy::filters::pf::particle_filter;
    let sc = ScenarioConfig {
        q: 1.0,
        sigma_deg: 2f64.to_degrees(), // σ = 2 (of the measurement's unit, m)
        ..ScenarioConfig::default()
    };
    let c = [1.0, -0.5];
    let m0 = [100.0, 50.0, -3.0, 2.0];
    let p0 = Matrix4::from_diagonal(&Vector4::new(9.0, 4.0, 1.0, 1.0));
    let model = BotModel::linear(&sc, c, m0, &p0).unwrap();
    let twin = LinearGaussian::new(
        DMatrix::from_iterator(4, 4, sc.f().iter().copied()),
        None,
        DMatrix::from_row_slice(1, 4, &[c[0], c[1], 0.0, 0.0]),
        DMatrix::from_iterator(4, 4, sc.q_matrix().iter().copied()),
        DMatrix::from_element(1, 1, 4.0),
        DVector::from_row_slice(&m0),
        DMatrix::from_iterator(4, 4, p0.iter().copied()),
    )
    .unwrap();
    let n = 20;
    let (_, ys) = twin.simulate(n, None, &mut stream_rng(11, 0)).unwrap();
    let mut yv: Vec<Option<DVector<f64>>> = ys.into_iter().map(Some).collect();
    yv[6] = None;
    let exact = kalman_filter(&twin, &yv, None).unwrap().log_likelihood;
    let ys: Vec<Option<f64>> = yv.iter().map(|y| y.as_ref().map(|y| y[0])).collect();
    let ratios: Vec<f64> = (0..400)
        .map(|r| {
            let mut pf = particle_filter(model.clone(), 1000, r, Par::Seq).unwrap();
            (pf.run(&ys).unwrap().log_lik - exact).exp()
        })
        .collect();
    let (m, se) = mean_and_se(&ratios);
    eprintln!("E[Ẑ/Z] = {m} ± {se}");
    assert!((m - 1.0).abs() < 3.0 * se, "E[Ẑ/Z] = {m} ± {se}");
    // The bound is informative: the estimates vary, but not wildly.
    assert!(se > 1e-4 && se < 0.08, "standard error {se}");
}

/// A run on one thread and on two gives the same bits: the log-likelihood and every
/// step's position mean, at a size with many chunks.
#[test]
fn one_and_two_threads_give_the_same_bits() {
    use pf_core::mc::Par;
    use pf_homotopy::filters::pf::particle_filter;
    let sc = ScenarioConfig {
        n_samples: 12,
        ..ScenarioConfig::default()
    };
    let real = sc.simulate(&mut stream_rng(5, 0)).unwrap();
    let observer: Vec<[f64; 2]> = real.observer.iter().map(|o| o.pos).collect();
    let model = BotModel::new(&sc, observer, real.bearings[0]).unwrap();
    let run_on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut pf = particle_filter(model.clone(), 20_000, 9, Par::Rayon).unwrap();
            let mut bits = Vec::new();
            let mut m = [0.0; 4];
            for (k, y) in real.bearings.iter().enumerate() {
                pf.step((k > 0).then_some(y)).unwrap();
                pf.view().unwrap().mean_into(&mut m).unwrap();
                bits.extend(m.map(f64::to_bits));
            }
            bits.push(pf.log_likelihood().to_bits());
            bits
        })
    };
    assert_eq!(run_on(1), run_on(2));
}

/// `pf::run`'s position means, summed from the copied-out weights and columns, are the
/// filter's own `mean_into` to rounding (the same particles and weights, summed in another
/// order), at a size whose last group of eight is partial.
#[test]
fn run_means_are_the_filters_means() {
    use pf_core::mc::Par;
    use pf_homotopy::filters::pf::{particle_filter, run};
    let sc = ScenarioConfig {
        n_samples: 12,
        ..ScenarioConfig::default()
    };
    let real = sc.simulate(&mut stream_rng(5, 0)).unwrap();
    let n = 20_003;
    let observer: Vec<[f64; 2]> = real.observer.iter().map(|o| o.pos).collect();
    let model = BotModel::new(&sc, observer, real.bearings[0]).unwrap();
    let mut pf = particle_filter(model, n, 9, Par::Rayon).unwrap();
    let means = run(&sc, n, &real, 9).unwrap();
    assert_eq!(means.len(), real.bearings.len());
    let mut m = [0.0; 4];
    for (k, (y, got)) in real.bearings.iter().zip(&means).enumerate() {
        pf.step((k > 0).then_some(y)).unwrap();
        pf.mean_into(&mut m).unwrap();
        for c in 0..2 {
            let scale = m[c].abs().max(1.0);
            assert!(
                (got[c] - m[c]).abs() <= 1e-11 * scale,
                "step {k}, component {c}: {} against {}",
                got[c],
                m[c]
            );
        }
    }
}
