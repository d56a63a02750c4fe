//! The optimal homotopy filter's correction step (Section 2): the λ-flow (12) of the
//! KL-optimal Gaussian parameterisation, integrated by the HΔE (13) or the AHΔE (17).
//!
//! With the KL criterion (23), `∇_θ J(λ, θ) = −∫ ∇_θ log f(p; θ) π̃(p; λ) dp`, so the
//! optimality condition (9) is moment matching and
//!
//! - `H(λ, θ) = ∫ [∇log f ∇'log f − ∇∇'f/f] π̃(p; λ) dp` (25), the integrand being
//!   [`N(p; θ)`](crate::param) = `−∇∇' log f`;
//! - `d(λ, θ) = ∂/∂λ ∇_θ J = −∫ ∇_θ log f · log g(y|p) · π̃(p; λ) dp`, since
//!   `∂π̃(p; λ)/∂λ = log g(y|p) π̃(p; λ)` for the homotopy (7). The paper prints (26)
//!   without the minus sign; with it, `dθ/dλ = −H⁻¹d` (12) moves the flow towards the
//!   posterior (without it the flow runs away from the data).
//!
//! Two implementation choices the paper leaves open, both exact for the ODE (12):
//!
//! - `log g` is centred by its weighted mean over the nodes before (26)/(28) are formed.
//!   The added term is `c·∇_θ J`, which vanishes on the solution path (9); off the path
//!   (Euler and quadrature error) centring makes the steps independent of the likelihood's
//!   normalising constant.
//! - A step that leaves `Σ` non-positive-definite is halved (up to `max_halvings` times)
//!   and the flow continues from the accepted half step: an adaptive refinement of the λ
//!   grid, reported in [`OhfDiagnostics::halvings`].
//! - On the solution path H (25) *is* the Fisher information of `f(·; θ)`, the closed form
//!   (27): its integrand `−∇∇' log f(p; θ)` is quadratic in `p`, so its expectation depends
//!   only on the first two moments of `π̃(·; λ)`, which (9) makes equal to those of
//!   `f(·; θ)`. Off the path (Euler error) the quadrature of (25) can lose positive
//!   definiteness when Σ has shrunk faster than the tempered posterior; such a step uses the
//!   on-path value, the Fisher information, and is counted in
//!   [`OhfDiagnostics::fisher_fallbacks`].
//!
//! Both `H` and `d` scale with `∫ π̃(p; λ) dp`, which cancels in `H⁻¹d`; the nodes are
//! therefore normalised.
//!
//! ## References
//! - M. R. Morelande, L. Svensson, J. Hagmar, M. Jirstrand, "Optimal posterior density
//!   approximation for bearings-only tracking", eqs. (7)–(17), (23)–(28).
//! - J. Hagmar, M. Jirstrand, L. Svensson, M. Morelande, "Optimal parameterization of
//!   posterior densities using homotopy", *Fusion* 2011 (the HΔE).

use nalgebra::{DMatrix, DVector, SMatrix, SVector};
use serde::{Deserialize, Serialize};

use crate::error::{HomotopyError, Result};
use crate::param::{Derivatives, Gaussian};
use crate::quadrature::{Nodes, TemperedQuadrature};
use pf_core::params::ParamError;

/// How the λ-ODE (12) is integrated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Scheme {
    /// The homotopy difference equation (13), with `H` (25) and `d` (26) under the
    /// tempered posterior `g^λ f(·; θ_{k|k−1})`: the OHF.
    Hde,
    /// The approximate HΔE (17), with `H̃` (27) in closed form and `d̃` (28) under the
    /// current Gaussian `f(·; θ_k(λ_i))`: the AOHF.
    Ahde,
    /// No flow: θ(λ) evaluated directly at each node as the KL-optimal Gaussian (8), i.e. the
    /// mean and covariance of `g^λ f(·; θ_{k|k−1})` by quadrature. Not in the paper: it is
    /// the limit the HΔE converges to as its steps shrink (the exact solution of (12)), made
    /// computable here because the polar grid adapts to the tempered posterior itself. The
    /// reference of the λ-step ablation; the tracker evaluates it at λ = 1 only.
    Direct,
}

/// Spacing of the λ grid `0 = λ_0 < … < λ_m = 1`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Spacing {
    /// `s_i = 1/m`.
    Uniform,
    /// `s_{i+1} = ratio · s_i`, normalised to sum to one: small first steps, where the
    /// flow is fastest (the tempered posterior shrinks like `1/(1 + λ·I)`), i.e. roughly
    /// uniform in `log λ`.
    Geometric {
        /// Ratio of consecutive step sizes, > 1.
        ratio: f64,
    },
}

/// The λ grid: number of steps and spacing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LambdaGrid {
    /// Number of steps `m`.
    pub steps: usize,
    /// Spacing.
    pub spacing: Spacing,
}

impl Default for LambdaGrid {
    /// 60 geometric steps of ratio 1.1: first step ≈ 3·10⁻⁴, last ≈ 0.09 (not stated in the
    /// paper; see the README and the λ-step ablation).
    fn default() -> Self {
        Self {
            steps: 60,
            spacing: Spacing::Geometric { ratio: 1.1 },
        }
    }
}

impl LambdaGrid {
    /// Check the grid.
    pub fn validate(&self) -> Result<()> {
        const WHAT: &str = "m (λ steps)";
        if self.steps == 0 {
            return Err(HomotopyError::Param(ParamError {
                name: WHAT,
                value: 0.0,
                reason: "at least one λ step is needed",
            }));
        }
        // The m + 1 nodes are a vector: a count past the limit or the machine's memory is an
        // error here, not an aborted allocation in `nodes`.
        pf_core::limits::check_count(WHAT, self.steps)?;
        pf_core::limits::check_memory(WHAT, self.steps, self.steps.saturating_mul(8))?;
        if let Spacing::Geometric { ratio } = self.spacing
            && !(ratio.is_finite() && ratio > 1.0)
        {
            return Err(HomotopyError::Param(ParamError {
                name: "geometric λ ratio",
                value: ratio,
                reason: "must be finite and > 1",
            }));
        }
        Ok(())
    }

    /// The nodes `λ_0 = 0, …, λ_m = 1`.
    pub fn nodes(&self) -> Vec<f64> {
        let m = self.steps;
        let mut out = Vec::with_capacity(m + 1);
        out.push(0.0);
        match self.spacing {
            Spacing::Uniform => out.extend((1..=m).map(|i| i as f64 / m as f64)),
            Spacing::Geometric { ratio } => {
                let total: f64 = (0..m).map(|i| ratio.powi(i as i32)).sum();
                let mut acc = 0.0;
                for i in 0..m {
                    acc += ratio.powi(i as i32) / total;
                    out.push(acc);
                }
            }
        }
        out[m] = 1.0;
        out
    }

    /// [`nodes`](Self::nodes) with extra values in (0, 1) merged in (used to record the
    /// parameterisation at given λ, as in Fig. 2).
    pub fn nodes_with(&self, extra: &[f64]) -> Vec<f64> {
        let mut v = self.nodes();
        v.extend(extra.iter().copied().filter(|l| *l > 0.0 && *l < 1.0));
        v.sort_by(f64::total_cmp);
        v.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
        v
    }
}

/// Settings of one OHF correction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OhfConfig {
    /// HΔE (OHF) or AHΔE (AOHF).
    pub scheme: Scheme,
    /// The λ grid.
    pub lambda: LambdaGrid,
    /// How many times a step may be halved to keep Σ positive definite.
    pub max_halvings: u32,
}

impl OhfConfig {
    /// The λ nodes a correction visits, with `extra` values in (0, 1) merged in: the grid
    /// of the flow, or only `0`, the extras and `1` for [`Scheme::Direct`].
    pub fn nodes_with(&self, extra: &[f64]) -> Vec<f64> {
        match self.scheme {
            Scheme::Direct => LambdaGrid {
                steps: 1,
                spacing: Spacing::Uniform,
            }
            .nodes_with(extra),
            Scheme::Hde | Scheme::Ahde => self.lambda.nodes_with(extra),
        }
    }

    /// The OHF (HΔE) with the default λ grid.
    pub fn ohf() -> Self {
        Self {
            scheme: Scheme::Hde,
            lambda: LambdaGrid::default(),
            max_halvings: 20,
        }
    }

    /// The AOHF (AHΔE) with the default λ grid.
    pub fn aohf() -> Self {
        Self {
            scheme: Scheme::Ahde,
            ..Self::ohf()
        }
    }

    /// The direct KL-optimal Gaussian ([`Scheme::Direct`]), the HΔE's limit.
    pub fn direct() -> Self {
        Self {
            scheme: Scheme::Direct,
            ..Self::ohf()
        }
    }

    /// Check the settings.
    pub fn validate(&self) -> Result<()> {
        self.lambda.validate()
    }
}

impl Default for OhfConfig {
    fn default() -> Self {
        Self::ohf()
    }
}

/// What one correction did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct OhfDiagnostics {
    /// Euler steps taken (grid steps plus the extra ones from halving).
    pub steps: usize,
    /// Step halvings needed to keep Σ positive definite.
    pub halvings: usize,
    /// HΔE steps whose quadrature of H (25) was not positive definite and that used H's
    /// value on the solution path, the Fisher information (27), instead (module docs).
    pub fisher_fallbacks: usize,
}

/// Buffers of the correction, reused from call to call.
#[derive(Debug, Clone)]
pub struct OhfWorkspace<const D: usize> {
    nodes: Nodes<D>,
    deriv: Option<Derivatives<D>>,
    h: DMatrix<f64>,
    l: DMatrix<f64>,
    d: DVector<f64>,
    th: DVector<f64>,
    /// The centred weights `w_j (log g_j − mean log g)` of (26) / (28).
    centred_w: Vec<f64>,
}

impl<const D: usize> Default for OhfWorkspace<D> {
    fn default() -> Self {
        let r = Gaussian::<D>::R;
        Self {
            nodes: Nodes::new(),
            deriv: None,
            h: DMatrix::zeros(r, r),
            l: DMatrix::zeros(r, r),
            d: DVector::zeros(r),
            th: DVector::zeros(r),
            centred_w: Vec::new(),
        }
    }
}

impl<const D: usize> OhfWorkspace<D> {
    /// Fresh buffers.
    pub fn new() -> Self {
        Self::default()
    }

    /// The quadrature nodes of the last direction computed (for inspection).
    pub fn nodes(&self) -> &Nodes<D> {
        &self.nodes
    }

    /// `−H⁻¹d` at `(λ, θ)` into `self.d`; `true` when H fell back to the Fisher information.
    fn direction<Q: TemperedQuadrature<D>>(
        &mut self,
        prior: &Gaussian<D>,
        theta: &Gaussian<D>,
        lambda: f64,
        scheme: Scheme,
        quad: &Q,
        k: usize,
    ) -> Result<bool> {
        let not_pd = HomotopyError::FlowNotPositiveDefinite {
            k,
            lambda,
            halvings: 0,
        };
        match &mut self.deriv {
            Some(d) => {
                if !d.set(theta) {
                    return Err(not_pd);
                }
            }
            None => self.deriv = Some(Derivatives::new(theta).ok_or(not_pd)?),
        }
        let deriv = self.deriv.as_ref().expect("set above");
        match scheme {
            Scheme::Hde | Scheme::Direct => quad.fill(prior, lambda, &mut self.nodes)?,
            Scheme::Ahde => quad.fill(theta, 0.0, &mut self.nodes)?,
        }
        self.nodes.normalise(k, lambda)?;
        let nodes = &self.nodes;
        // −d = Σ_j w_j ∇log f(p_j) (log g_j − mean log g): eq. (26) / (28), centred; and
        // H = Σ_j w_j N(p_j), eq. (25). Both from the nodes' moments (see `param`), in
        // loops of plain arithmetic that LLVM vectorises.
        let (centred, all) = pf_core::simd::vectorised(
            #[inline(always)]
            || {
                let lg_bar = lane_dot(&nodes.log_g, &nodes.w);
                let cw = &mut self.centred_w;
                cw.clear();
                cw.extend(
                    nodes
                        .w
                        .iter()
                        .zip(&nodes.log_g)
                        .map(|(&w, &lg)| w * (lg - lg_bar)),
                );
                deriv.moments_pair(&nodes.points, cw, &nodes.w)
            },
        );
        deriv.score_sum(&centred, &mut self.d);
        if scheme == Scheme::Hde {
            self.h.fill(0.0);
            deriv.add_hessian_sum(&all, &mut self.h);
        } else {
            deriv.fisher(&mut self.h);
        }
        let mut fallback = false;
        if pf_core::gaussian::cholesky_into("H", &self.h, &mut self.l).is_err() {
            if scheme != Scheme::Hde {
                return Err(HomotopyError::HessianNotPositiveDefinite { k, lambda });
            }
            deriv.fisher(&mut self.h);
            pf_core::gaussian::cholesky_into("H", &self.h, &mut self.l)
                .map_err(|_| HomotopyError::HessianNotPositiveDefinite { k, lambda })?;
            fallback = true;
        }
        // Direction −H⁻¹d = H⁻¹(−d).
        self.l.solve_lower_triangular_unchecked_mut(&mut self.d);
        self.l.tr_solve_lower_triangular_unchecked_mut(&mut self.d);
        Ok(fallback)
    }

    /// The KL-optimal Gaussian (8) at `λ`: the moments of `g^λ f(·; prior)` on the nodes.
    fn moments<Q: TemperedQuadrature<D>>(
        &mut self,
        prior: &Gaussian<D>,
        lambda: f64,
        quad: &Q,
        k: usize,
    ) -> Result<Gaussian<D>> {
        quad.fill(prior, lambda, &mut self.nodes)?;
        self.nodes.normalise(k, lambda)?;
        let nodes = &self.nodes;
        let mean = nodes
            .points
            .iter()
            .zip(&nodes.w)
            .fold(SVector::<f64, D>::zeros(), |a, (p, &w)| a + p * w);
        let cov =
            nodes
                .points
                .iter()
                .zip(&nodes.w)
                .fold(SMatrix::<f64, D, D>::zeros(), |a, (p, &w)| {
                    let e = p - mean;
                    a + e * e.transpose() * w
                });
        let g = Gaussian::new(mean, 0.5 * (cov + cov.transpose()));
        if g.chol().is_none() {
            return Err(HomotopyError::FlowNotPositiveDefinite {
                k,
                lambda,
                halvings: 0,
            });
        }
        Ok(g)
    }
}

/// `Σ_j x_j y_j` over eight interleaved partial sums (index `j` into lane `j mod 8`), the
/// lanes added in order at the end.
#[inline(always)]
fn lane_dot(x: &[f64], y: &[f64]) -> f64 {
    const L: usize = 8;
    let mut acc = [0.0f64; L];
    let (mut xb, mut yb) = (x.chunks_exact(L), y.chunks_exact(L));
    for (xc, yc) in (&mut xb).zip(&mut yb) {
        for l in 0..L {
            acc[l] += xc[l] * yc[l];
        }
    }
    for (l, (a, b)) in xb.remainder().iter().zip(yb.remainder()).enumerate() {
        acc[l] += a * b;
    }
    acc.iter().sum()
}

/// One OHF correction: integrate (12) from `θ(0) = prior` to `θ(1)` over the λ nodes
/// `lambdas` (from [`LambdaGrid::nodes`]) with the scheme `scheme`, calling
/// `on_lambda(λ_i, f(·; θ(λ_i)))` at every node. `k` labels errors.
///
/// # Errors
/// A bad prior, a degenerate quadrature, a non-PD Hessian (HΔE), or a flow that keeps
/// losing positive definiteness after `max_halvings` halvings.
#[allow(clippy::too_many_arguments)]
pub fn correct<const D: usize, Q: TemperedQuadrature<D>>(
    prior: &Gaussian<D>,
    quad: &Q,
    scheme: Scheme,
    lambdas: &[f64],
    max_halvings: u32,
    k: usize,
    ws: &mut OhfWorkspace<D>,
    mut on_lambda: impl FnMut(f64, &Gaussian<D>),
) -> Result<(Gaussian<D>, OhfDiagnostics)> {
    prior.validate("OHF prior")?;
    let mut theta = *prior;
    let mut diag = OhfDiagnostics::default();
    if let Some(&l0) = lambdas.first() {
        on_lambda(l0, &theta);
    }
    if scheme == Scheme::Direct {
        for &lam in lambdas.iter().skip(1) {
            theta = ws.moments(prior, lam, quad, k)?;
            diag.steps += 1;
            on_lambda(lam, &theta);
        }
        return Ok((theta, diag));
    }
    for win in lambdas.windows(2) {
        let (mut lam, target) = (win[0], win[1]);
        while lam < target {
            if ws.direction(prior, &theta, lam, scheme, quad, k)? {
                diag.fisher_fallbacks += 1;
            }
            let mut h = target - lam;
            let mut halvings = 0;
            let cand = loop {
                theta.write_theta(&mut ws.th);
                ws.th.axpy(h, &ws.d, 1.0);
                let cand = Gaussian::<D>::from_theta(&ws.th);
                if cand.chol().is_some() {
                    break cand;
                }
                halvings += 1;
                if halvings > max_halvings {
                    return Err(HomotopyError::FlowNotPositiveDefinite {
                        k,
                        lambda: lam,
                        halvings: max_halvings,
                    });
                }
                h *= 0.5;
            };
            diag.halvings += halvings as usize;
            diag.steps += 1;
            theta = cand;
            lam = if halvings == 0 { target } else { lam + h };
        }
        on_lambda(target, &theta);
    }
    Ok((theta, diag))
}
