//! The OHF for bearings-only tracking (Section 3): closed-form prediction (18)–(20), the
//! homotopy over the position only (`r = 5`), then the full-state posterior by Gaussian
//! conditioning on the prior's position–velocity cross-covariance.
//!
//! Conditioning: the measurement depends on the position `p` only, so the posterior is
//! `π(v | p) π(p)` with `π(v | p)` the prior's Gaussian conditional. With the prior
//! `N([m_p; m_v], [[P_pp, P_pv], [P_vp, P_vv]])`, `K = P_vp P_pp⁻¹` and the position posterior
//! `N(μ⁺, Σ⁺)`: `m_v⁺ = m_v + K(μ⁺ − m_p)`, `P_vp⁺ = K Σ⁺`,
//! `P_vv⁺ = P_vv − K P_pv + K Σ⁺ Kᵀ`.

use nalgebra::{Matrix2, Matrix4, Vector2};

use crate::error::{Result, check_data};
use crate::model::{Realisation, ScenarioConfig};
use crate::ohf::{OhfConfig, OhfDiagnostics, OhfWorkspace, correct};
use crate::param::Gaussian;
use crate::prior::gaussian_prior;
use crate::quadrature::{PolarGrid, PolarGridConfig};

/// An OHF (or AOHF) tracker: a Gaussian belief over the full state.
#[derive(Debug, Clone)]
pub struct OhfTracker {
    config: OhfConfig,
    grid: PolarGridConfig,
    f: Matrix4<f64>,
    q: Matrix4<f64>,
    sigma: f64,
    lambdas: Vec<f64>,
    state: Gaussian<4>,
    ws: OhfWorkspace<2>,
    diagnostics: OhfDiagnostics,
}

impl OhfTracker {
    /// Initialise from the first bearing `y1` seen from `rho1` (Section 4).
    ///
    /// # Errors
    /// Invalid settings or a non-finite `y1`.
    pub fn new(
        scenario: &ScenarioConfig,
        config: OhfConfig,
        grid: PolarGridConfig,
        y1: f64,
        rho1: [f64; 2],
    ) -> Result<Self> {
        scenario.validate()?;
        config.validate()?;
        grid.validate()?;
        check_data("bearing", 1, y1)?;
        Ok(Self {
            config,
            grid,
            f: scenario.f(),
            q: scenario.q_matrix(),
            sigma: scenario.sigma(),
            lambdas: config.nodes_with(&[]),
            state: gaussian_prior(&scenario.prior, y1, scenario.sigma(), rho1),
            ws: OhfWorkspace::new(),
            diagnostics: OhfDiagnostics::default(),
        })
    }

    /// The current belief `N(m, P)` over `[x, y, ẋ, ẏ]`.
    pub fn state(&self) -> &Gaussian<4> {
        &self.state
    }

    /// Steps and halvings of every correction so far.
    pub fn diagnostics(&self) -> OhfDiagnostics {
        self.diagnostics
    }

    /// The position marginal of the current belief.
    pub fn position(&self) -> Gaussian<2> {
        Gaussian::new(
            self.state.mean.fixed_rows::<2>(0).into_owned(),
            self.state.cov.fixed_view::<2, 2>(0, 0).into_owned(),
        )
    }

    /// Prediction (4) in closed form: `m ← F m`, `P ← F P Fᵀ + Q`.
    pub fn predict(&mut self) {
        self.state.mean = self.f * self.state.mean;
        let p = self.f * self.state.cov * self.f.transpose() + self.q;
        self.state.cov = 0.5 * (p + p.transpose());
    }

    /// Correction with bearing `y` from `rho` at sampling instant `k`.
    ///
    /// # Errors
    /// A non-finite bearing or a failure of the homotopy (see [`correct`]).
    pub fn update(&mut self, k: usize, y: f64, rho: [f64; 2]) -> Result<()> {
        self.update_recording(k, y, rho, &[], |_, _| {})
    }

    /// [`update`](Self::update), calling `on_lambda(λ, position Gaussian)` at every λ node;
    /// the values `record_at` are merged into the λ grid so that they are among them.
    ///
    /// # Errors
    /// As [`update`](Self::update).
    pub fn update_recording(
        &mut self,
        k: usize,
        y: f64,
        rho: [f64; 2],
        record_at: &[f64],
        on_lambda: impl FnMut(f64, &Gaussian<2>),
    ) -> Result<()> {
        check_data("bearing", k, y)?;
        let prior_p = self.position();
        let quad = PolarGrid::new(self.grid, rho, y, self.sigma);
        let merged;
        let lambdas: &[f64] = if record_at.is_empty() {
            &self.lambdas
        } else {
            merged = self.config.nodes_with(record_at);
            &merged
        };
        let (post, diag) = correct(
            &prior_p,
            &quad,
            self.config.scheme,
            lambdas,
            self.config.max_halvings,
            k,
            &mut self.ws,
            on_lambda,
        )?;
        self.diagnostics.steps += diag.steps;
        self.diagnostics.halvings += diag.halvings;
        self.diagnostics.fisher_fallbacks += diag.fisher_fallbacks;
        self.condition(&prior_p, &post)
    }

    /// Full-state posterior from the position posterior (module docs).
    fn condition(&mut self, prior_p: &Gaussian<2>, post: &Gaussian<2>) -> Result<()> {
        let p = &self.state.cov;
        let ppp: Matrix2<f64> = prior_p.cov;
        let pvp: Matrix2<f64> = p.fixed_view::<2, 2>(2, 0).into_owned();
        let pvv: Matrix2<f64> = p.fixed_view::<2, 2>(2, 2).into_owned();
        let chol = ppp
            .cholesky()
            .ok_or(pf_core::CoreError::NotPositiveDefinite {
                what: "prior position covariance P_pp",
                pivot: 0,
                value: ppp[(0, 0)],
            })?;
        // K = P_vp P_pp⁻¹, i.e. Kᵀ = P_pp⁻¹ P_pv.
        let k = chol.solve(&pvp.transpose()).transpose();
        let mv: Vector2<f64> =
            self.state.mean.fixed_rows::<2>(2).into_owned() + k * (post.mean - prior_p.mean);
        let pvp_new = k * post.cov;
        let pvv_new = pvv - k * pvp.transpose() + k * post.cov * k.transpose();
        let mut cov = Matrix4::zeros();
        cov.fixed_view_mut::<2, 2>(0, 0).copy_from(&post.cov);
        cov.fixed_view_mut::<2, 2>(2, 0).copy_from(&pvp_new);
        cov.fixed_view_mut::<2, 2>(0, 2)
            .copy_from(&pvp_new.transpose());
        cov.fixed_view_mut::<2, 2>(2, 2)
            .copy_from(&(0.5 * (pvv_new + pvv_new.transpose())));
        self.state.mean.fixed_rows_mut::<2>(0).copy_from(&post.mean);
        self.state.mean.fixed_rows_mut::<2>(2).copy_from(&mv);
        self.state.cov = cov;
        Ok(())
    }
}

/// Filter a realisation; position means at `k = 1, …, K`.
///
/// # Errors
/// As [`OhfTracker::new`] and [`OhfTracker::update`].
pub fn run(
    scenario: &ScenarioConfig,
    config: &OhfConfig,
    grid: &PolarGridConfig,
    real: &Realisation,
) -> Result<Vec<[f64; 2]>> {
    let mut tr = OhfTracker::new(
        scenario,
        *config,
        *grid,
        real.bearings[0],
        real.observer[0].pos,
    )?;
    let mut out = Vec::with_capacity(real.bearings.len());
    out.push(mean_pos(&tr));
    for (i, (&y, o)) in real.bearings.iter().zip(&real.observer).enumerate().skip(1) {
        tr.predict();
        tr.update(i + 1, y, o.pos)?;
        out.push(mean_pos(&tr));
    }
    Ok(out)
}

fn mean_pos(tr: &OhfTracker) -> [f64; 2] {
    [tr.state.mean[0], tr.state.mean[1]]
}
