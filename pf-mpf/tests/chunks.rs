//! The batch models' chunk functions against the per-particle algebra of the MPF (fixed-size
//! nalgebra products, one particle at a time, as eqs. (7)–(10) and ref. [15] write them), on
//! the same inputs: equal to 1e-12 relative.

use nalgebra::{Cholesky, SMatrix, SVector};
use pf_core::filter::{BatchModel, Cols, ColsMut};
use pf_core::mc::stream_rng;
use pf_mpf::model::{LinearMeasurement, Measurement, MixedLinearGaussian, Model5Matrices};
use pf_mpf::mpf::{PerParticleMpf, SharedMpf, riccati_time_update};
use pf_mpf::radar::{Partition, RadarConfig, RangeAzimuth};
use rand_distr::{Distribution, StandardNormal};

/// A chunk that spans more than one tile and ends in a partial one.
const N: usize = 77;

fn normals(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = stream_rng(seed, 0);
    (0..n).map(|_| StandardNormal.sample(&mut rng)).collect()
}

fn close(a: f64, b: f64, what: &str) {
    assert!(
        (a - b).abs() <= 1e-12 * b.abs().max(1.0),
        "{what}: batch {a} against per-particle {b}"
    );
}

/// `log N(e; 0, L Lᵀ)` with nalgebra.
fn log_normal<const D: usize>(s: &SMatrix<f64, D, D>, e: SVector<f64, D>) -> f64 {
    let l = Cholesky::new(*s).unwrap().l();
    let z = l.solve_lower_triangular(&e).unwrap();
    let log_det: f64 = (0..D).map(|i| l[(i, i)].ln()).sum();
    -0.5 * z.norm_squared() - log_det - 0.5 * D as f64 * (2.0 * std::f64::consts::PI).ln()
}

/// Alg. 1 on the radar partitions: propagate (eqs. (8)–(10) with the shared `P_{t|t}`) and
/// the weights `N(y; h(x^p), R)` (Alg. 1, step 2).
fn shared_case<const P: usize, const K: usize>(name: &str) {
    let cfg = RadarConfig::default();
    let part: Partition = name.parse().unwrap();
    let model = part.model::<P, K>(&cfg).unwrap();
    let batch = SharedMpf::new(model.clone()).unwrap();
    let t = 5;
    // P_{t−1|t−1} by the recursion, one step at a time.
    let mut p = *model.p0_k();
    for _ in 1..t {
        p = riccati_time_update(&model, &p).unwrap().2;
    }
    let (t1, l, _) = riccati_time_update(&model, &p).unwrap();
    assert!((batch.cov(t - 1) - p).amax() <= 1e-12 * p.amax().max(1e-300));
    // Parents around the true state, spread as a filter's particles are.
    let mut parents = normals((P + K) * N, 1);
    for (c, col) in parents.chunks_exact_mut(N).enumerate() {
        let i = if c < P {
            part.p_indices()[c]
        } else {
            part.k_indices()[c - P]
        };
        for v in col {
            *v = cfg.x0[i] + 10.0 * cfg.p0_diag[i].sqrt() * *v;
        }
    }
    let z = normals(P * N, 2);
    let mut out = vec![0.0; (P + K) * N];
    batch.propagate(
        t,
        &(),
        Cols::new(&parents, P + K, N),
        Cols::new(&z, P, N),
        ColsMut::new(&mut out, P + K, N),
    );
    let y = SVector::<f64, 2>::new(2400.0, 0.61);
    let mut lw = vec![0.5; N];
    batch.add_log_likelihood(t, &y, Cols::new(&out, P + K, N), &mut lw);
    let r = *model.r();
    for i in 0..N {
        let xp = SVector::<f64, P>::from_fn(|c, _| parents[c * N + i]);
        let xk = SVector::<f64, K>::from_fn(|c, _| parents[(P + c) * N + i]);
        let zi = SVector::<f64, P>::from_fn(|c, _| z[c * N + i]);
        // Table I: T3, T4, w, x̂^p, T7, T8, T9, x̂^k.
        let (t3, t4) = (model.a_p() * xp, model.a_k() * xk);
        let xp_new = t3 + t4 + t1 * zi;
        let t9 = xp_new - t3 - t4;
        let xk_new = model.f_k() * xk + model.f_p() * xp + l * t9;
        for c in 0..P {
            close(
                out[c * N + i],
                xp_new[c],
                &format!("{name} x^p[{c}] of {i}"),
            );
        }
        for c in 0..K {
            close(
                out[(P + c) * N + i],
                xk_new[c],
                &format!("{name} x^k[{c}] of {i}"),
            );
        }
        let h = Measurement::<P, 2>::h(model.h(), t, &xp_new);
        let e = Measurement::<P, 2>::residual(model.h(), &y, &h);
        close(
            lw[i],
            0.5 + log_normal(&r, e),
            &format!("{name} log q of {i}"),
        );
    }
}

#[test]
fn shared_riccati_chunks_agree_with_per_particle_algebra() {
    shared_case::<6, 0>("PPPPPP");
    shared_case::<4, 2>("PPKKPP");
    shared_case::<4, 2>("PPPPKK");
    shared_case::<2, 4>("PPKKKK");
}

/// The standard PF's initial draw: `x^p_0 = x̄ + chol(P_0) z`.
#[test]
fn initial_draw_agrees() {
    let cfg = RadarConfig::default();
    let model = "PPKKPP"
        .parse::<Partition>()
        .unwrap()
        .model::<4, 2>(&cfg)
        .unwrap();
    let batch = SharedMpf::new(model.clone()).unwrap();
    let z = normals(4 * N, 3);
    let mut out = vec![0.0; 6 * N];
    batch.initial(Cols::new(&z, 4, N), ColsMut::new(&mut out, 6, N));
    for i in 0..N {
        let zi = SVector::<f64, 4>::from_fn(|c, _| z[c * N + i]);
        let x = model.x0_p().mean() + model.x0_p().chol() * zi;
        for c in 0..4 {
            close(out[c * N + i], x[c], "x^p_0");
        }
        for c in 0..2 {
            close(out[(4 + c) * N + i], model.x0_k()[c], "x̂^k_0");
        }
    }
}

/// A model with `C_t ≠ 0`: p = 2, k = 2, the radar's range and azimuth plus `C x^k`.
fn c_model<H: Measurement<2, 2>>(h: H) -> MixedLinearGaussian<2, 2, 2, H> {
    let m = Model5Matrices::<2, 2, 2> {
        a_p: SMatrix::<f64, 2, 2>::new(1.0, 0.1, 0.0, 0.95),
        a_k: SMatrix::<f64, 2, 2>::new(1.0, 0.2, -0.3, 0.5),
        f_p: SMatrix::<f64, 2, 2>::new(0.05, 0.0, 0.1, -0.02),
        f_k: SMatrix::<f64, 2, 2>::new(0.9, 0.1, 0.0, 0.8),
        q_p: SMatrix::<f64, 2, 2>::new(1.0, 0.2, 0.2, 0.5),
        q_k: SMatrix::<f64, 2, 2>::new(0.3, 0.05, 0.05, 0.2),
        c: SMatrix::<f64, 2, 2>::new(0.7, 0.1, 0.0, 0.002),
        r: SMatrix::<f64, 2, 2>::new(4.0, 0.001, 0.001, 1e-4),
        x0_p: SVector::<f64, 2>::new(200.0, 150.0),
        p0_p: SMatrix::<f64, 2, 2>::new(10.0, 1.0, 1.0, 10.0),
        x0_k: SVector::<f64, 2>::new(1.0, -1.0),
        p0_k: SMatrix::<f64, 2, 2>::new(2.0, 0.3, 0.3, 1.0),
    };
    MixedLinearGaussian::new(m, h).unwrap()
}

/// Ref. [15]: the Kalman measurement update (Joseph form) with `y_{t−1}`, then the Riccati
/// time update, each particle with its own covariance; and the weights
/// `N(y; h(x^p) + C x̂^k, C P Cᵀ + R)`.
fn per_particle_case<H: Measurement<2, 2> + Clone>(h: H, what: &str) {
    let model = c_model(h);
    let batch = PerParticleMpf::new(model.clone());
    let d = batch.dim();
    assert_eq!(d, 2 + 2 + 3);
    // Parents: x^p, x̂^k, and a positive definite P per particle (entries 00, 01, 11).
    let g = normals(7 * N, 4);
    let mut parents = vec![0.0; d * N];
    for i in 0..N {
        parents[i] = 200.0 + 5.0 * g[i];
        parents[N + i] = 150.0 + 5.0 * g[N + i];
        parents[2 * N + i] = 1.0 + g[2 * N + i];
        parents[3 * N + i] = -1.0 + g[3 * N + i];
        let (a, b, c) = (1.0 + g[4 * N + i].abs(), 0.3 * g[5 * N + i], g[6 * N + i]);
        // P = B Bᵀ + 0.1 I with B = [[a, 0], [b, c]].
        parents[4 * N + i] = a * a + 0.1;
        parents[5 * N + i] = a * b;
        parents[6 * N + i] = b * b + c * c + 0.1;
    }
    let z = normals(2 * N, 5);
    let y_prev = SVector::<f64, 2>::new(250.0, 0.64);
    let y = SVector::<f64, 2>::new(251.0, 0.65);
    let t = 3;
    let mut out = vec![0.0; d * N];
    batch.propagate(
        t,
        &Some(y_prev),
        Cols::new(&parents, d, N),
        Cols::new(&z, 2, N),
        ColsMut::new(&mut out, d, N),
    );
    let mut lw = vec![0.0; N];
    batch.add_log_likelihood(t, &y, Cols::new(&out, d, N), &mut lw);
    let (c, r) = (*model.c(), *model.r());
    for i in 0..N {
        let xp = SVector::<f64, 2>::new(parents[i], parents[N + i]);
        let mut xk = SVector::<f64, 2>::new(parents[2 * N + i], parents[3 * N + i]);
        let mut p = SMatrix::<f64, 2, 2>::new(
            parents[4 * N + i],
            parents[5 * N + i],
            parents[5 * N + i],
            parents[6 * N + i],
        );
        // Measurement update with y_{t−1}.
        let e = model
            .h()
            .residual(&y_prev, &(model.h().h(t - 1, &xp) + c * xk));
        let pct = p * c.transpose();
        let s = c * pct + r;
        let chol = Cholesky::new(s).unwrap();
        let gain = chol.solve(&pct.transpose()).transpose();
        xk += gain * e;
        let ikc = SMatrix::<f64, 2, 2>::identity() - gain * c;
        p = ikc * p * ikc.transpose() + gain * r * gain.transpose();
        // Time update.
        let (t1, l, p_next) = riccati_time_update(&model, &p).unwrap();
        let zi = SVector::<f64, 2>::new(z[i], z[N + i]);
        let (t3, t4) = (model.a_p() * xp, model.a_k() * xk);
        let xp_new = t3 + t4 + t1 * zi;
        let xk_new = model.f_k() * xk + model.f_p() * xp + l * (xp_new - t3 - t4);
        let got = |c: usize| out[c * N + i];
        close(got(0), xp_new[0], &format!("{what} x^p[0] of {i}"));
        close(got(1), xp_new[1], &format!("{what} x^p[1] of {i}"));
        close(got(2), xk_new[0], &format!("{what} x^k[0] of {i}"));
        close(got(3), xk_new[1], &format!("{what} x^k[1] of {i}"));
        close(got(4), p_next[(0, 0)], &format!("{what} P00 of {i}"));
        close(got(5), p_next[(0, 1)], &format!("{what} P01 of {i}"));
        close(got(6), p_next[(1, 1)], &format!("{what} P11 of {i}"));
        // The weight with the predicted statistics.
        let e = model
            .h()
            .residual(&y, &(model.h().h(t, &xp_new) + c * xk_new));
        let s = c * p_next * c.transpose() + r;
        close(lw[i], log_normal(&s, e), &format!("{what} log q of {i}"));
    }
}

#[test]
fn per_particle_chunks_agree_with_per_particle_algebra() {
    per_particle_case(RangeAzimuth, "range-azimuth");
    per_particle_case(
        LinearMeasurement {
            h: SMatrix::<f64, 2, 2>::new(0.01, 0.0, 0.002, 0.001),
        },
        "linear",
    );
}
