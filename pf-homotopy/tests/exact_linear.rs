//! Exact case: with a measurement linear-Gaussian in position, `y = C p + v`, the tempered
//! posterior `g^λ f₀` is Gaussian for every λ, so the KL-optimal Gaussian is exact and the
//! λ-flow (12) ends at the Kalman posterior. Euler schemes (13) and (17) converge to it at
//! first order in the step size.

use nalgebra::{DMatrix, DVector, Matrix2, SVector, Vector2};
use pf_core::kalman::{KalmanState, LinearGaussian};
use pf_homotopy::ohf::{LambdaGrid, OhfWorkspace, Scheme, Spacing, correct};
use pf_homotopy::param::Gaussian;
use pf_homotopy::quadrature::{WhitenedGrid, WhitenedGridConfig};

fn setup() -> (Gaussian<2>, Matrix2<f64>, Matrix2<f64>, Vector2<f64>) {
    let prior = Gaussian::new(Vector2::new(1.0, -0.5), Matrix2::new(2.0, 0.5, 0.5, 1.0));
    let c = Matrix2::new(1.0, 0.3, -0.2, 0.8);
    let r = Matrix2::new(0.8, 0.1, 0.1, 0.5);
    let y = Vector2::new(2.0, 0.4);
    (prior, c, r, y)
}

/// The exact posterior from pf-core's Kalman update (Joseph form).
fn kalman(
    prior: &Gaussian<2>,
    c: &Matrix2<f64>,
    r: &Matrix2<f64>,
    y: &Vector2<f64>,
) -> Gaussian<2> {
    let d = |m: &Matrix2<f64>| DMatrix::from_fn(2, 2, |i, j| m[(i, j)]);
    let model = LinearGaussian::new(
        d(&Matrix2::identity()),
        None,
        d(c),
        d(&Matrix2::identity()),
        d(r),
        DVector::from_column_slice(prior.mean.as_slice()),
        d(&prior.cov),
    )
    .unwrap();
    let mut st = KalmanState::prior(&model);
    st.update(&model, &DVector::from_column_slice(y.as_slice()))
        .unwrap();
    Gaussian::new(
        Vector2::new(st.m[0], st.m[1]),
        Matrix2::new(st.p[(0, 0)], st.p[(0, 1)], st.p[(1, 0)], st.p[(1, 1)]),
    )
}

fn error(a: &Gaussian<2>, b: &Gaussian<2>) -> f64 {
    (a.mean - b.mean).amax().max((a.cov - b.cov).amax())
}

fn run(scheme: Scheme, steps: usize) -> Gaussian<2> {
    let (prior, c, r, y) = setup();
    let r_inv = r.try_inverse().unwrap();
    let log_g = move |p: &SVector<f64, 2>| {
        let e = y - c * p;
        -0.5 * e.dot(&(r_inv * e))
    };
    let quad = WhitenedGrid {
        config: WhitenedGridConfig {
            n: 48,
            n_sigma: 7.0,
        },
        log_g,
    };
    let grid = LambdaGrid {
        steps,
        spacing: Spacing::Uniform,
    };
    let mut ws = OhfWorkspace::new();
    let (post, diag) = correct(
        &prior,
        &quad,
        scheme,
        &grid.nodes(),
        10,
        0,
        &mut ws,
        |_, _| {},
    )
    .unwrap();
    assert_eq!(diag.halvings, 0);
    post
}

#[test]
fn ohf_and_aohf_converge_to_the_kalman_posterior() {
    let (prior, c, r, y) = setup();
    let exact = kalman(&prior, &c, &r, &y);
    for scheme in [Scheme::Hde, Scheme::Ahde] {
        let errs: Vec<f64> = [8, 16, 32, 64]
            .iter()
            .map(|&m| error(&run(scheme, m), &exact))
            .collect();
        // Euler's global error is C/m + O(1/m²): each doubling of m must roughly halve it.
        // The quadrature (48² midpoint nodes over ±7σ of a Gaussian times a polynomial) is
        // accurate to far below the smallest Euler error here, so the ratio lies within
        // [0.4, 0.6] of pure first order (the O(1/m²) term moves it by ≲ 0.1 at m ≥ 8).
        for w in errs.windows(2) {
            let ratio = w[1] / w[0];
            assert!((0.4..0.6).contains(&ratio), "{scheme:?}: errors {errs:?}");
        }
        // Richardson extrapolation 2·e(64) − e(32) removes the first-order term: the limit
        // of the scheme is the Kalman posterior to within the O(1/m²) remainder, here below
        // a tenth of e(64).
        let fine = run(scheme, 64);
        let coarse = run(scheme, 32);
        let extrap = Gaussian::new(2.0 * fine.mean - coarse.mean, 2.0 * fine.cov - coarse.cov);
        assert!(
            error(&extrap, &exact) < 0.1 * errs[3],
            "{scheme:?}: {} vs {}",
            error(&extrap, &exact),
            errs[3]
        );
    }
}
