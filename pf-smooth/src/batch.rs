//! The path-space and fixed-lag estimators of the AR(1) statistics on pf-core's batch
//! filter: each particle's sums and the recent states of its ancestral line are columns of
//! its state, so resampling carries them along with the rest.
//!
//! [`SmoothedAr1`] is Section 5's model with `D = 1 + 4 + Δ` columns per particle:
//!
//! | column | holds |
//! |---|---|
//! | 0 | `ξ_t^i`, the state |
//! | 1 … 4 | `γ_t^i`, the running sums of `τ_{n,1…4}` along the particle's ancestral line (eq. (7)) |
//! | 5 … 4 + Δ | `ξ_{t−1}, …, ξ_{t−Δ}` of that line, a shift register |
//!
//! The filter gathers a particle's parent before it propagates it, so
//! `γ_t^i = γ_{t−1}^{A_t^i} + s_{t−1}(ξ_{t−1}^{A_t^i}, ξ_t^i)` (eq. (7)) is the model's
//! own transition, and the register shifts the parent's line by one. The path-space
//! estimate is then `τ̂_n^N = Σ_i W_n^i γ_n^i` (eq. (6)).
//!
//! The fixed-lag estimate `τ̂_n^{δ,N}` (eq. (9)) needs the weights of step `j + δ − 1` for
//! the term of step `j`: [`FixedLagTerms`], a [`BatchObserver`], freezes at each step `t`
//! the term `s_{j−1}(X_{j−1}, X_j)` of step `j = t + 1 − δ`, evaluated on the register's
//! lags `δ` and `δ − 1` under the weights `W_t` (the paper's recursion of Section 4, which
//! caches positions). After the last step the terms not yet frozen are read off the
//! register under `W_n`. Any resampling policy works: without resampling the ancestors are
//! the identity and the register is each particle's own past. Several lags share one
//! register of `Δ = max δ` columns.
//!
//! Indexing: the term of step `j ≥ 1` is `s_{j−1}(X_{j−1}, X_j)`, plus, for `j = 1`, the
//! term of `X_0` alone (see [`functional`](crate::functional)); it is frozen at step
//! `j + δ − 1` (the paper's `k + δ` with `k = j − 1`). So with resampling turned off both
//! estimators are exactly the importance-sampling formulas (tested). A lag `δ > n` freezes
//! nothing and gives the path-space estimate.

use crate::ar1::{Ar1Data, SuffStats, Theta};
use crate::error::{Result, SmoothError};
use pf_core::filter::{BatchModel, BatchObserver, BatchView, Cols, ColsMut, ScalarModel};
use pf_core::models::NoisyAr1;

/// Columns before the register: the state and the four sums.
const HEAD: usize = 5;

/// The column of `ξ_{t−ℓ}`: 0 for the state itself, then the register.
#[inline]
fn column(l: usize) -> usize {
    if l == 0 { 0 } else { HEAD + l - 1 }
}

/// The term `s_{j−1}(x_{j−1}, x_j)` of step `j ≥ 1` for `Y_j = y`:
/// `(x_{j−1}², x_{j−1} x_j, x_j², (y − x_j)²)`.
#[inline(always)]
fn term(y: f64, xp: f64, x: f64) -> [f64; 4] {
    let e = y - x;
    [xp * xp, xp * x, x * x, e * e]
}

/// Section 5's noisy AR(1) model at `θ` with the diffuse prior, carrying each particle's
/// sums `γ_t^i` (eq. (7)) and the last `Δ` states of its ancestral line as columns: a
/// [`BatchModel`] of dimension `5 + Δ` (see the [module](self) docs).
///
/// Filter it with `y_0` missing, as [`Ar1Data::filter_input`] gives: `Y_0` is in the
/// prior, and its term `(Y_0 − X_0)²` in `γ_0`. A step beyond the data has no `Y_t`, and
/// its sums are NaN, which the estimates report as an error.
#[derive(Debug, Clone, Copy)]
pub struct SmoothedAr1<'a> {
    model: NoisyAr1,
    y: &'a [f64],
    lags: usize,
}

impl<'a> SmoothedAr1<'a> {
    /// The model at `theta` for `data`, with a register of `lags` (Δ) past states: the
    /// fixed-lag estimator of lag `δ ≤ n` needs `Δ ≥ δ`; `Δ = 0` serves the path-space
    /// estimator alone.
    ///
    /// # Errors
    /// An invalid `θ`, or a `Δ` beyond [`MAX_COUNT`](pf_core::limits::MAX_COUNT).
    pub fn new(theta: &Theta, data: &'a Ar1Data, lags: usize) -> Result<Self> {
        pf_core::limits::check_count("fixed-lag register columns", lags)?;
        Ok(SmoothedAr1 {
            model: theta.model(data.y()[0])?,
            y: data.y(),
            lags,
        })
    }

    /// Δ, the number of past states each particle carries.
    pub fn lags(&self) -> usize {
        self.lags
    }

    /// The wrapped model.
    pub fn model(&self) -> &NoisyAr1 {
        &self.model
    }

    /// The column of `ξ_{t−ℓ}` for `ℓ ≤ Δ` (0 for the state itself).
    #[inline]
    pub fn lag_column(&self, l: usize) -> usize {
        column(l)
    }

    /// `Y_t`, NaN beyond the data.
    #[inline]
    fn y(&self, t: usize) -> f64 {
        self.y.get(t).copied().unwrap_or(f64::NAN)
    }

    /// The four sums and the state of each particle of the chunk from its parent (eq. (7)),
    /// weighed by `g_t(y | ·)` when `y` is given; then the register's shift.
    #[inline(always)]
    fn advance(
        &self,
        t: usize,
        y: Option<f64>,
        parents: Cols<'_>,
        z: Cols<'_>,
        mut x: ColsMut<'_>,
        lw: &mut [f64],
    ) {
        let yt = self.y(t);
        let m = &self.model;
        {
            let [p0, p1, p2, p3, p4] = parents.split::<HEAD>();
            let [x0, g1, g2, g3, g4] = x.split_mut::<HEAD>();
            let n = x0.len();
            let (p0, p1, p2, p3, p4, z) = (
                &p0[..n],
                &p1[..n],
                &p2[..n],
                &p3[..n],
                &p4[..n],
                &z.col(0)[..n],
            );
            let (g1, g2, g3, g4) = (&mut g1[..n], &mut g2[..n], &mut g3[..n], &mut g4[..n]);
            match y {
                Some(y) => {
                    let lw = &mut lw[..n];
                    for i in 0..n {
                        let xn = m.transition_from_normal(t, p0[i], z[i]);
                        let s = term(yt, p0[i], xn);
                        x0[i] = xn;
                        g1[i] = p1[i] + s[0];
                        g2[i] = p2[i] + s[1];
                        g3[i] = p3[i] + s[2];
                        g4[i] = p4[i] + s[3];
                        lw[i] += m.log_likelihood_scalar(t, xn, y);
                    }
                }
                None => {
                    for i in 0..n {
                        let xn = m.transition_from_normal(t, p0[i], z[i]);
                        let s = term(yt, p0[i], xn);
                        x0[i] = xn;
                        g1[i] = p1[i] + s[0];
                        g2[i] = p2[i] + s[1];
                        g3[i] = p3[i] + s[2];
                        g4[i] = p4[i] + s[3];
                    }
                }
            }
        }
        // ξ_{t−1} of the line is the parent's state; ξ_{t−ℓ} its ξ_{t−ℓ}, one column on.
        if self.lags > 0 {
            x.col_mut(HEAD).copy_from_slice(parents.col(0));
            for l in 2..=self.lags {
                x.col_mut(HEAD + l - 1)
                    .copy_from_slice(parents.col(HEAD + l - 2));
            }
        }
    }
}

impl BatchModel for SmoothedAr1<'_> {
    type Obs = f64;
    type Input = ();

    fn dim(&self) -> usize {
        HEAD + self.lags
    }

    fn noise_dim(&self) -> usize {
        1
    }

    /// `ξ_0 ~ N(Y_0, ρ²)`, `γ_0 = (0, 0, 0, (Y_0 − ξ_0)²)`; the register (steps before 0)
    /// holds zeros, which no term reads.
    fn initial(&self, z: Cols<'_>, mut x: ColsMut<'_>) {
        let y0 = self.y(0);
        {
            let [x0, g1, g2, g3, g4] = x.split_mut::<HEAD>();
            for (i, &z) in z.col(0).iter().enumerate().take(x0.len()) {
                let v = self.model.initial_from_normal(z);
                let e = y0 - v;
                x0[i] = v;
                g1[i] = 0.0;
                g2[i] = 0.0;
                g3[i] = 0.0;
                g4[i] = e * e;
            }
        }
        for l in 1..=self.lags {
            x.col_mut(HEAD + l - 1).fill(0.0);
        }
    }

    fn propagate(&self, t: usize, _u: &(), parents: Cols<'_>, z: Cols<'_>, x: ColsMut<'_>) {
        self.advance(t, None, parents, z, x, &mut []);
    }

    fn add_log_likelihood(&self, t: usize, &y: &f64, x: Cols<'_>, lw: &mut [f64]) {
        for (l, &x) in lw.iter_mut().zip(x.col(0)) {
            *l += self.model.log_likelihood_scalar(t, x, y);
        }
    }

    /// One loop moves, sums and weighs each particle; the register's shift follows.
    fn propagate_weighed(
        &self,
        t: usize,
        _u: &(),
        y: Option<&f64>,
        parents: Cols<'_>,
        z: Cols<'_>,
        x: ColsMut<'_>,
        lw: &mut [f64],
    ) {
        self.advance(t, y.copied(), parents, z, x, lw);
    }
}

/// The fixed-lag estimators `τ̂^{δ,N}` (eq. (9)) of several lags δ on one run of a
/// [`SmoothedAr1`] filter: a [`BatchObserver`] that freezes, at each step `t`, the term of
/// step `t + 1 − δ` under the weights `W_t`.
///
/// Buffers are sized in [`on_start`](BatchObserver::on_start) (or at the first step); a
/// step allocates nothing. A step with `t = 0` restarts it.
#[derive(Debug, Clone)]
pub struct FixedLagTerms<'a> {
    y: &'a [f64],
    /// Δ of the model the filter runs.
    register: usize,
    /// The lags δ.
    lags: Vec<usize>,
    /// The frozen part of each lag's estimate, `Σ_{j frozen} Σ_i W_{j+δ−1}^i s_j^i`.
    frozen: Vec<[f64; 4]>,
    /// `W_t^i` and two columns of the register.
    w: Vec<f64>,
    a: Vec<f64>,
    b: Vec<f64>,
    t: Option<usize>,
    /// The first error a step met, for [`on_finish`](BatchObserver::on_finish).
    error: Option<pf_core::CoreError>,
}

impl<'a> FixedLagTerms<'a> {
    /// The estimators of `lags` for filters of `model` on its data.
    ///
    /// # Errors
    /// A lag of 0, or a lag `δ ≤ n` beyond the model's register `Δ`.
    pub fn new(model: &SmoothedAr1<'a>, lags: &[usize]) -> Result<Self> {
        let n = model.y.len() - 1;
        for &d in lags {
            pf_core::params::at_least_one("lag", d)?;
            if d <= n && d > model.lags {
                return Err(SmoothError::Param(pf_core::params::ParamError {
                    name: "lag",
                    value: d as f64,
                    reason: "a lag within the data needs at least as many register columns (Δ) in the model",
                }));
            }
        }
        Ok(FixedLagTerms {
            y: model.y,
            register: model.lags,
            lags: lags.to_vec(),
            frozen: vec![[0.0; 4]; lags.len()],
            w: Vec::new(),
            a: Vec::new(),
            b: Vec::new(),
            t: None,
            error: None,
        })
    }

    /// The lags δ, as given.
    pub fn lags(&self) -> &[usize] {
        &self.lags
    }

    /// The frozen part of each lag's estimate.
    pub fn frozen(&self) -> &[[f64; 4]] {
        &self.frozen
    }

    fn y(&self, t: usize) -> f64 {
        self.y.get(t).copied().unwrap_or(f64::NAN)
    }

    fn resize(&mut self, n: usize) {
        self.w.resize(n, 0.0);
        self.a.resize(n, 0.0);
        self.b.resize(n, 0.0);
    }

    /// `out += Σ_i w_i s_{j−1}(a_i, b_i)` (plus the term of `X_0 = a_i` at `j = 1`).
    fn add_terms(&self, j: usize, out: &mut [f64; 4]) {
        let yj = self.y(j);
        let mut acc = [0.0; 4];
        for ((&w, &xp), &x) in self.w.iter().zip(&self.a).zip(&self.b) {
            let mut s = term(yj, xp, x);
            if j == 1 {
                let e = self.y(0) - xp;
                s[3] += e * e;
            }
            for (a, s) in acc.iter_mut().zip(s) {
                *a += w * s;
            }
        }
        for (o, a) in out.iter_mut().zip(acc) {
            *o += a;
        }
    }

    /// The path-space estimate (eq. (6)) and each lag's fixed-lag estimate (eq. (9)) at the
    /// step `view` shows, which must be the step this observer saw last.
    ///
    /// # Errors
    /// [`SmoothError::NoSteps`] before the first step or for a view of another step, a
    /// view of another model's columns, or a non-finite estimate.
    pub fn estimates(&mut self, view: &BatchView<'_>) -> Result<(SuffStats, Vec<SuffStats>)> {
        let t = match self.t {
            Some(t) if t == view.report().t => t,
            _ => {
                return Err(SmoothError::NoSteps {
                    what: "fixed-lag estimator (of the step shown)",
                });
            }
        };
        if view.dim() != HEAD + self.register {
            return Err(pf_core::CoreError::DimensionMismatch {
                what: "columns of the smoothed AR(1) filter",
                expected: HEAD + self.register,
                got: view.dim(),
            }
            .into());
        }
        self.resize(view.n());
        view.weights_into(&mut self.w)?;
        let mut joint = [0.0; 4];
        for (c, out) in joint.iter_mut().enumerate() {
            view.column_into(1 + c, &mut self.a)?;
            *out = self.w.iter().zip(&self.a).map(|(w, g)| w * g).sum();
        }
        let finite = |v: [f64; 4], what: &'static str| -> Result<SuffStats> {
            crate::estimate::check_finite(what, t, &v)?;
            Ok(SuffStats { n: t, tau: v })
        };
        let mut lagged = Vec::with_capacity(self.lags.len());
        for l in 0..self.lags.len() {
            let d = self.lags[l];
            if d > t {
                // Nothing frozen: the whole path is live, the path-space estimate.
                lagged.push(finite(joint, "fixed-lag estimate")?);
                continue;
            }
            // The live terms, steps j = t + 2 − δ … t, on the register's lags δ − 1 … 0.
            let mut est = self.frozen[l];
            view.column_into(column(d - 1), &mut self.a)?;
            for k in (0..d - 1).rev() {
                view.column_into(column(k), &mut self.b)?;
                self.add_terms(t - k, &mut est);
                std::mem::swap(&mut self.a, &mut self.b);
            }
            lagged.push(finite(est, "fixed-lag estimate")?);
        }
        Ok((finite(joint, "path-space estimate")?, lagged))
    }
}

impl FixedLagTerms<'_> {
    /// Freeze the term of step `j = t + 1 − δ ≥ 1` of each lag (the register's lags δ and
    /// δ − 1) under the weights of step `t`.
    fn freeze(&mut self, view: &BatchView<'_>) -> pf_core::Result<()> {
        let t = view.report().t;
        if t == 0 || self.t.is_none() {
            self.frozen.iter_mut().for_each(|f| *f = [0.0; 4]);
        }
        self.t = Some(t);
        if !self.lags.iter().any(|&d| d <= t && d <= self.register) {
            return Ok(());
        }
        self.resize(view.n());
        view.weights_into(&mut self.w)?;
        for l in 0..self.lags.len() {
            let d = self.lags[l];
            if d > t || d > self.register {
                continue;
            }
            view.column_into(column(d), &mut self.a)?;
            view.column_into(column(d - 1), &mut self.b)?;
            let mut f = self.frozen[l];
            self.add_terms(t + 1 - d, &mut f);
            self.frozen[l] = f;
        }
        Ok(())
    }
}

impl BatchObserver for FixedLagTerms<'_> {
    fn on_start(&mut self, n: usize, _dim: usize) {
        self.resize(n);
        self.error = None;
    }

    fn on_step(&mut self, view: &BatchView<'_>) {
        if let Err(e) = self.freeze(view) {
            self.error.get_or_insert(e);
        }
    }

    fn on_finish(&mut self) -> pf_core::Result<()> {
        self.error.take().map_or(Ok(()), Err)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One chunk of three particles moved by hand: the sums gain eq. (7)'s term, the
    /// register shifts the parent's line by one, and the likelihood is the model's.
    #[test]
    fn a_chunk_moves_its_sums_and_register_with_its_parents() {
        let data = Ar1Data::new(vec![0.5, 1.0, -2.0]).unwrap();
        let theta = Theta::paper_start();
        let m = SmoothedAr1::new(&theta, &data, 2).unwrap();
        assert_eq!(m.dim(), 7);
        // Parents: state, γ, then ξ_{t−1}, ξ_{t−2}.
        let parents = [
            [1.0, -1.0, 2.0],
            [10.0, 20.0, 30.0],
            [1.0, 2.0, 3.0],
            [0.5, 0.5, 0.5],
            [4.0, 5.0, 6.0],
            [0.3, 0.4, 0.5],
            [0.6, 0.7, 0.8],
        ]
        .concat();
        let z = [0.0, 1.0, -2.0];
        let mut x = vec![0.0; 21];
        let mut lw = vec![0.0; 3];
        m.propagate_weighed(
            2,
            &(),
            Some(&-2.0),
            Cols::new(&parents, 7, 3),
            Cols::new(&z, 1, 3),
            ColsMut::new(&mut x, 7, 3),
            &mut lw,
        );
        let col = |k: usize| &x[k * 3..(k + 1) * 3];
        for i in 0..3 {
            let (xp, zi) = (parents[i], z[i]);
            let xn = 0.8 * xp + 0.5 * zi;
            assert!((col(0)[i] - xn).abs() < 1e-15);
            let s = term(-2.0, xp, xn);
            for c in 0..4 {
                assert_eq!(col(1 + c)[i], parents[(1 + c) * 3 + i] + s[c]);
            }
            assert_eq!(col(5)[i], xp, "ξ_{{t−1}} is the parent's state");
            assert_eq!(
                col(6)[i],
                parents[5 * 3 + i],
                "ξ_{{t−2}} is the parent's ξ_{{t−1}}"
            );
            let e = (-2.0 - xn) / 2.0;
            let want = -(2.0f64.ln()) - 0.5 * (2.0 * std::f64::consts::PI).ln() - 0.5 * e * e;
            assert!((lw[i] - want).abs() < 1e-12, "{} vs {want}", lw[i]);
        }
        // Without an observation: the same states, no weight.
        let mut y = vec![0.0; 21];
        m.propagate(
            2,
            &(),
            Cols::new(&parents, 7, 3),
            Cols::new(&z, 1, 3),
            ColsMut::new(&mut y, 7, 3),
        );
        assert_eq!(x, y);
        // X_0 ~ N(Y_0, ρ²), γ_0 = (0, 0, 0, (Y_0 − X_0)²), an empty register.
        let mut x0 = vec![1.0; 21];
        m.initial(Cols::new(&z, 1, 3), ColsMut::new(&mut x0, 7, 3));
        for i in 0..3 {
            let v = 0.5 + 2.0 * z[i];
            assert_eq!(x0[i], v);
            assert_eq!([x0[3 + i], x0[6 + i], x0[9 + i]], [0.0; 3]);
            assert_eq!(x0[12 + i], (0.5 - v) * (0.5 - v));
            assert_eq!([x0[15 + i], x0[18 + i]], [0.0; 2]);
        }
    }
}
