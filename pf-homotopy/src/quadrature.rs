//! Grid approximations of the intractable integrals (25), (26) and (28).
//!
//! Every integral the homotopy needs has the form `∫ φ(p) g(y|p)^λ N(p; m, P) dp`: for the
//! HΔE with `N(m, P)` the prior `f(·; θ_{k|k−1})` and λ the current homotopy value (eq. (7)),
//! for the AHΔE with `N(m, P) = f(·; θ_k(λ_i))` and `λ = 0` (eqs. (27)–(28)). A
//! [`TemperedQuadrature`] returns nodes `p_j` with log-weights
//! `log w_j ≈ log(cell volume) + log N(p_j; m, P) + λ log g(y|p_j)` and the values
//! `log g(y|p_j)` that (26) and (28) multiply by.
//!
//! - [`PolarGrid`] is the paper's choice for bearings-only tracking: a change of variables
//!   to polar coordinates `p = ρ + r (cos β, sin β)` centred on the observer, `dp = r dr dβ`,
//!   then a grid. In these coordinates the bearing likelihood depends on β alone, so the
//!   β-grid can follow the likelihood's width `σ/√λ`, and along each ray the Gaussian is a
//!   one-dimensional Gaussian in `r` whose own mean and width place that ray's `r`-grid.
//! - [`WhitenedGrid`] is a tensor midpoint grid in the whitened coordinates of `N(m, P)`,
//!   for any likelihood no sharper than the Gaussian (used for the linear-Gaussian checks).

use nalgebra::{SMatrix, SVector, Vector2};
use serde::{Deserialize, Serialize};

use crate::error::{HomotopyError, Result};
use crate::param::{Gaussian, log_normal};
use pf_core::gaussian::LN_2PI;
use pf_core::geometry::wrap_angle;
use pf_core::params::{ParamError, positive};
use pf_core::simd::math::exp_nonpositive;
use pf_core::simd::special::{exp, ln};

/// Quadrature nodes, reused from one call to the next (no allocation once grown).
#[derive(Debug, Clone, Default)]
pub struct Nodes<const D: usize> {
    /// `p_j`.
    pub points: Vec<SVector<f64, D>>,
    /// `log w_j`, including the `g^λ` factor; unnormalised.
    pub log_w: Vec<f64>,
    /// `log g(y | p_j)`.
    pub log_g: Vec<f64>,
    /// Normalised weights `w_j / Σ w`, filled by [`Nodes::normalise`].
    pub w: Vec<f64>,
}

impl<const D: usize> Nodes<D> {
    /// Empty node set.
    pub fn new() -> Self {
        Self {
            points: Vec::new(),
            log_w: Vec::new(),
            log_g: Vec::new(),
            w: Vec::new(),
        }
    }

    /// Forget the nodes, keeping the capacity.
    pub fn clear(&mut self) {
        self.points.clear();
        self.log_w.clear();
        self.log_g.clear();
        self.w.clear();
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether there are no nodes.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Add a node.
    pub fn push(&mut self, p: SVector<f64, D>, log_w: f64, log_g: f64) {
        self.points.push(p);
        self.log_w.push(log_w);
        self.log_g.push(log_g);
    }

    /// Fill [`Nodes::w`] with the normalised weights `e^{log w_j − max} / Σ_i e^{log w_i − max}`;
    /// returns `log Σ_j w_j`, the log of the integral `∫ g^λ N dp`. [`Nodes::log_w`] is left
    /// as it was. `k`, `lambda` label the error.
    ///
    /// By [`pf_core::weights::normalise_into`], whose maximum and sum run over interleaved
    /// partial results, so that the loops vectorise.
    ///
    /// # Errors
    /// [`pf_core::CoreError::NonFiniteWeight`] for a NaN or `+∞` log-weight,
    /// [`HomotopyError::DegenerateQuadrature`] without nodes or when every weight is zero.
    pub fn normalise(&mut self, k: usize, lambda: f64) -> Result<f64> {
        if self.is_empty() {
            return Err(HomotopyError::DegenerateQuadrature { k, lambda });
        }
        self.w.resize(self.log_w.len(), 0.0);
        pf_core::weights::normalise_into(k, &self.log_w, &mut self.w).map_err(|e| match e {
            pf_core::CoreError::AllWeightsZero { .. } => {
                HomotopyError::DegenerateQuadrature { k, lambda }
            }
            e => e.into(),
        })
    }

    /// `Σ_j w_j φ(p_j)` with the normalised weights.
    pub fn expect(&self, phi: impl Fn(&SVector<f64, D>) -> f64) -> f64 {
        self.points
            .iter()
            .zip(&self.w)
            .map(|(p, w)| w * phi(p))
            .sum()
    }
}

/// A rule for `∫ φ(p) g(y|p)^λ N(p; m, P) dp`; see the module docs.
pub trait TemperedQuadrature<const D: usize> {
    /// Clear `nodes` and fill them for the Gaussian `base` and homotopy value `lambda`.
    ///
    /// # Errors
    /// A `base` covariance that is not positive definite.
    fn fill(&self, base: &Gaussian<D>, lambda: f64, nodes: &mut Nodes<D>) -> Result<()>;

    /// `log g(y | p)`.
    fn log_likelihood(&self, p: &SVector<f64, D>) -> f64;
}

/// Resolution of the observer-centred polar grid.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PolarGridConfig {
    /// Number of bearing nodes `n_β`.
    pub n_bearing: usize,
    /// Number of range nodes `n_r` on each ray.
    pub n_range: usize,
    /// Half-width of the grid in standard deviations (of the Gaussian along each ray, of
    /// and of the bearing cone of the Gaussian seen from the observer).
    pub n_sigma: f64,
}

impl Default for PolarGridConfig {
    /// 48 × 24 nodes over ±5 standard deviations (the paper does not give its grid; see
    /// the README and the grid ablation).
    fn default() -> Self {
        Self {
            n_bearing: 48,
            n_range: 24,
            n_sigma: 5.0,
        }
    }
}

impl PolarGridConfig {
    /// Check the resolution.
    pub fn validate(&self) -> Result<()> {
        if self.n_bearing < 2 {
            return Err(HomotopyError::Param(ParamError {
                name: "n_bearing",
                value: self.n_bearing as f64,
                reason: "the bearing grid needs at least 2 nodes",
            }));
        }
        if self.n_range < 2 {
            return Err(HomotopyError::Param(ParamError {
                name: "n_range",
                value: self.n_range as f64,
                reason: "the range grid needs at least 2 nodes",
            }));
        }
        // Each node holds a point and three weights, about 64 bytes in the plane's 4-D
        // state: a grid past the count limit or the machine's memory is an error here.
        const WHAT: &str = "the polar grid's nodes n_β·n_r";
        let nodes =
            pf_core::limits::check_count(WHAT, self.n_bearing.saturating_mul(self.n_range))?;
        pf_core::limits::check_memory(WHAT, nodes, nodes.saturating_mul(64))?;
        positive("n_sigma", self.n_sigma)?;
        Ok(())
    }
}

/// The paper's polar-coordinate grid for a bearing measurement `y ~ N(h(p, ρ), σ²)`.
#[derive(Debug, Clone)]
pub struct PolarGrid {
    /// The λ-free part of the last base's fill (see [`PreGrid`]).
    pre: std::cell::RefCell<PreGrid>,
    /// Resolution.
    pub config: PolarGridConfig,
    /// Observer position ρ = (ξ, ζ).
    pub rho: [f64; 2],
    /// The bearing `y_k`.
    pub y: f64,
    /// Bearing noise standard deviation σ.
    pub sigma: f64,
}

/// Points of the `c`-σ ellipse's outline that [`bearing_extent`] visits.
const OUTLINE: usize = 256;

/// `(cos t_i, sin t_i)`, `t_i = 2π i / OUTLINE`: the unit circle that [`bearing_extent`]
/// maps onto the ellipse's outline, the same for every ellipse.
static UNIT_CIRCLE: std::sync::LazyLock<[[f64; 2]; OUTLINE]> = std::sync::LazyLock::new(|| {
    std::array::from_fn(|i| {
        let t = std::f64::consts::TAU * i as f64 / OUTLINE as f64;
        [t.cos(), t.sin()]
    })
});

/// Bearing extent of the `c`-σ ellipse of `g` seen from `rho`: `(β_c, lo, hi)` with the
/// interval `[β_c + lo, β_c + hi]`, or `None` when `rho` lies inside the ellipse.
///
/// The extremes are found in two passes: every outline point ranked by a pseudo-angle of
/// its bearing relative to `β_c` (the "diamond angle" [`diamond`], monotone in the angle
/// over the whole circle, one division instead of an `atan2`), then, for the points within
/// `10⁻⁹` of the smallest or largest pseudo-angle, the bearing by the C library's `atan2`,
/// whose extremes are returned. The pseudo-angle changes at least half as fast as the
/// angle, so the second pass sees every point that rounding could have misranked: the
/// result is the exact extreme of the C library's bearings, at a few `atan2` calls instead
/// of 256.
fn bearing_extent(
    g: &Gaussian<2>,
    l: &SMatrix<f64, 2, 2>,
    lambda_mat: &SMatrix<f64, 2, 2>,
    rho: [f64; 2],
    c: f64,
) -> Option<(f64, f64, f64)> {
    let d = g.mean - Vector2::new(rho[0], rho[1]);
    if d.dot(&(lambda_mat * d)) <= c * c {
        return None;
    }
    let bc = d[1].atan2(d[0]);
    // The ellipse is convex and excludes ρ, so its extreme bearings lie on its outline;
    // 256 outline points place them within a chord error of cos(π/256) ≈ 1 − 7.5e-5 of the
    // true tangent, which the 2 % padding below covers.
    let circle = &*UNIT_CIRCLE;
    // The outline point `d + c L (cos t, sin t)` as the exact pass computes it.
    let point = |u: &[f64; 2]| d + c * l * Vector2::new(u[0], u[1]);
    let exact = |u: &[f64; 2]| {
        let q = point(u);
        wrap_angle(q[1].atan2(q[0]) - bc)
    };
    // First pass: the pseudo-angle of q turned by −β_c (by d, whose length does not
    // matter to an angle).
    let (sb, cb) = (d[1], d[0]);
    let cl = c * l;
    let (l00, l01, l10, l11) = (cl[(0, 0)], cl[(0, 1)], cl[(1, 0)], cl[(1, 1)]);
    let (mut lo_a, mut hi_a) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut approx = [0.0; OUTLINE];
    for (a, u) in approx.iter_mut().zip(circle) {
        let q0 = d[0] + (l00 * u[0] + l01 * u[1]);
        let q1 = d[1] + (l10 * u[0] + l11 * u[1]);
        *a = diamond(cb * q1 - sb * q0, cb * q0 + sb * q1);
        lo_a = lo_a.min(*a);
        hi_a = hi_a.max(*a);
    }
    const TOL: f64 = 1e-9;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (a, u) in approx.iter().zip(circle) {
        if *a <= lo_a + TOL {
            lo = lo.min(exact(u));
        }
        if *a >= hi_a - TOL {
            hi = hi.max(exact(u));
        }
    }
    let pad = 0.02 * (hi - lo);
    Some((bc, lo - pad, hi + pad))
}

/// The log of the ray mass along the unit direction `u` from the observer,
/// `log ∫_0^∞ r N(ρ + r u) dr` up to a constant, for the Gaussian with precision `Λ` and
/// `d = m − ρ`, `dd = dᵀΛd`: along the ray `(p − m)ᵀΛ(p − m) = a r² − 2 b r + dᵀΛd`.
#[inline(always)]
fn log_ray_mass(
    lambda_mat: &SMatrix<f64, 2, 2>,
    d: &Vector2<f64>,
    dd: f64,
    u: Vector2<f64>,
) -> f64 {
    let lu = lambda_mat * u;
    let a = u.dot(&lu);
    let b = lu.dot(d);
    let (r_star, s_r) = (b / a, a.sqrt().recip());
    // ∫_0^∞ r exp(−(r − r*)²/2s²) dr = s² e^{−x²/2} + r* s √(2π) Φ(x), x = r*/s.
    let x = r_star / s_r;
    let i = s_r * s_r * exp_nonpositive(-0.5 * x * x)
        + r_star
            * s_r
            * (2.0 * std::f64::consts::PI).sqrt()
            * 0.5
            * erfc(-x / std::f64::consts::SQRT_2);
    -0.5 * (dd - b * b / a) + ln(i.max(f64::MIN_POSITIVE))
}

/// The diamond angle of `(x, y)`: `t = y/(|x| + |y|)` for `x ≥ 0`, `±2 − t` for `x < 0`
/// (the sign of `y`), in `[−2, 2]`, increasing with `atan2(y, x)` over `(−π, π]`, with
/// derivative `1/(|cos| + |sin|)² ≥ ½` in the angle.
#[inline(always)]
fn diamond(y: f64, x: f64) -> f64 {
    let t = y / (x.abs() + y.abs());
    if x >= 0.0 { t } else { 2.0f64.copysign(y) - t }
}

/// What [`PolarGrid::fill`] computes from its base Gaussian alone, whatever λ: kept from
/// one call to the next while the base is the same, as it is over the HΔE's whole flow,
/// which fills for the prior `f(·; θ_{k|k−1})` at every λ (the AHΔE's base moves with θ).
#[derive(Debug, Clone, Default)]
struct PreGrid {
    /// The base's mean and covariance (`None` before the first fill or after a failed one).
    key: Option<(SVector<f64, 2>, SMatrix<f64, 2, 2>)>,
    /// `Λ = P⁻¹`, `log det P`, `d = m − ρ` and `dᵀΛd`.
    lambda_mat: SMatrix<f64, 2, 2>,
    ln_det: f64,
    d: Vector2<f64>,
    dd: f64,
    /// The pre-grid: its first bearing `centre + lo0`, spacing and size.
    centre: f64,
    lo0: f64,
    h_pre: f64,
    /// Per pre-grid bearing: the log ray mass, `log ∫_0^∞ r N(ρ + r u_β) dr` up to a
    /// constant, and `log g(y | β)` (empty until a fill with λ ≠ 0 needs it).
    log_mass: Vec<f64>,
    log_g: Vec<f64>,
    /// Scratch: the placement density.
    q: Vec<f64>,
    /// Scratch: the pre-grid's unit directions `u_β`.
    dirs: Vec<Vector2<f64>>,
}

impl PolarGrid {
    /// The grid for measurement `y` from observer `rho`.
    pub fn new(config: PolarGridConfig, rho: [f64; 2], y: f64, sigma: f64) -> Self {
        Self {
            pre: std::cell::RefCell::new(PreGrid::default()),
            config,
            rho,
            y,
            sigma,
        }
    }

    /// `log g(y | β) = log N(wrap_angle(y − β); 0, σ²)`, eq. (21), as a function of the bearing β.
    pub fn log_g_bearing(&self, beta: f64) -> f64 {
        self.log_g_with(beta, self.sigma.ln())
    }

    /// [`log_g_bearing`](Self::log_g_bearing) with `ln σ` given, for loops that hoist it.
    #[inline]
    fn log_g_with(&self, beta: f64, ln_sigma: f64) -> f64 {
        let e = wrap_angle(self.y - beta) / self.sigma;
        -0.5 * (LN_2PI + e * e) - ln_sigma
    }

    /// The λ-free part of a fill for `base` into `pre`.
    fn pre_grid(&self, base: &Gaussian<2>, pre: &mut PreGrid) -> Result<()> {
        pre.key = None;
        let c = self.config.n_sigma;
        let l = base.chol().ok_or(pf_core::CoreError::NotPositiveDefinite {
            what: "polar grid base covariance",
            pivot: 0,
            value: base.cov[(0, 0)],
        })?;
        let lambda_mat = base
            .cov
            .try_inverse()
            .ok_or(pf_core::CoreError::NotPositiveDefinite {
                what: "polar grid base covariance",
                pivot: 1,
                value: base.cov.determinant(),
            })?;
        let ln_det = 2.0 * (l[(0, 0)] * l[(1, 1)]).ln();
        let rho = Vector2::new(self.rho[0], self.rho[1]);
        let d = base.mean - rho;
        // Bearing interval: where the bearing marginal of g^λ·N has its mass. Candidates are
        // the Gaussian's c-σ cone seen from ρ (the whole circle when ρ is inside the
        // ellipse); on a fine pre-grid over them, the marginal is
        // m_λ(β) = g(β)^λ ∫_0^∞ r N(ρ + r u_β) dr, in closed form.
        let extent = bearing_extent(base, &l, &lambda_mat, self.rho, c);
        let (centre, lo0, hi0, n_pre) = match extent {
            Some((bc, lo, hi)) => (bc, lo, hi, 256),
            None => (
                d[1].atan2(d[0]),
                -std::f64::consts::PI,
                std::f64::consts::PI,
                2048,
            ),
        };
        let dd = d.dot(&(lambda_mat * d));
        let h_pre = (hi0 - lo0) / n_pre as f64;
        pre.log_g.clear();
        // The directions of the pre-grid by rotation, one step of h_pre at a time: after
        // 2048 steps the rounding has moved them by about 10⁻¹³, far below what placing the
        // nodes can see, and a step costs four products instead of a `sincos`.
        let beta0 = centre + lo0 + 0.5 * h_pre;
        let (sh, ch) = h_pre.sin_cos();
        let (mut s_dir, mut c_dir) = beta0.sin_cos();
        pre.dirs.clear();
        for _ in 0..n_pre {
            pre.dirs.push(Vector2::new(c_dir, s_dir));
            (c_dir, s_dir) = (c_dir * ch - s_dir * sh, s_dir * ch + c_dir * sh);
        }
        // The masses in a loop of plain arithmetic (pf-core's `exp` and `ln`, this module's
        // `erfc`), which LLVM vectorises.
        pre.log_mass.clear();
        pre.log_mass.resize(n_pre, 0.0);
        let (dirs, log_mass) = (&pre.dirs[..], &mut pre.log_mass[..]);
        pf_core::simd::vectorised(
            #[inline(always)]
            || {
                for (m, &u) in log_mass.iter_mut().zip(dirs) {
                    *m = log_ray_mass(&lambda_mat, &d, dd, u);
                }
            },
        );
        *pre = PreGrid {
            key: Some((base.mean, base.cov)),
            lambda_mat,
            ln_det,
            d,
            dd,
            centre,
            lo0,
            h_pre,
            log_mass: std::mem::take(&mut pre.log_mass),
            log_g: std::mem::take(&mut pre.log_g),
            q: std::mem::take(&mut pre.q),
            dirs: std::mem::take(&mut pre.dirs),
        };
        Ok(())
    }
}

impl TemperedQuadrature<2> for PolarGrid {
    fn log_likelihood(&self, p: &SVector<f64, 2>) -> f64 {
        self.log_g_bearing((p[1] - self.rho[1]).atan2(p[0] - self.rho[0]))
    }

    fn fill(&self, base: &Gaussian<2>, lambda: f64, nodes: &mut Nodes<2>) -> Result<()> {
        nodes.clear();
        let cfg = self.config;
        let c = cfg.n_sigma;
        let pre = &mut *self.pre.borrow_mut();
        if pre.key != Some((base.mean, base.cov)) {
            self.pre_grid(base, pre)?;
        }
        let (lambda_mat, ln_det, d, dd) = (pre.lambda_mat, pre.ln_det, pre.d, pre.dd);
        let (centre, lo0, h_pre) = (pre.centre, pre.lo0, pre.h_pre);
        let n_pre = pre.log_mass.len();
        let rho = Vector2::new(self.rho[0], self.rho[1]);
        let ln_sigma = self.sigma.ln();
        // The tempered bearing marginal's log on the pre-grid, `log m_0 + λ log g`; at
        // λ = 0 (the AHΔE) that is `log m_0` itself (`log g` is finite, so `0 · log g`
        // adds a zero).
        let mut best = (f64::NEG_INFINITY, 0usize);
        let q = &mut pre.q;
        q.clear();
        if lambda == 0.0 {
            q.extend_from_slice(&pre.log_mass);
        } else {
            if pre.log_g.len() != n_pre {
                pre.log_g.clear();
                pre.log_g.extend(
                    (0..n_pre).map(|i| {
                        self.log_g_with(centre + lo0 + (i as f64 + 0.5) * h_pre, ln_sigma)
                    }),
                );
            }
            q.extend(
                pre.log_mass
                    .iter()
                    .zip(&pre.log_g)
                    .map(|(m, g)| m + lambda * g),
            );
        }
        for (i, &v) in q.iter().enumerate() {
            if v > best.0 {
                best = (v, i);
            }
        }
        if !best.0.is_finite() {
            return Err(HomotopyError::DegenerateQuadrature { k: 0, lambda });
        }
        // Bearing nodes by a change of variables β = β(u), u uniform: midpoints in u of the
        // placement density q ∝ m_λ^{1/2} (piecewise constant on the pre-grid), node
        // spacing Δβ_j = Δu / q(β_j). The square root spreads nodes into the tails and over
        // secondary mass (when ρ is inside the ellipse, part of the Gaussian lies behind the
        // observer, all around it) while keeping most of them on the main lobe.
        let mut total = 0.0;
        for v in q.iter_mut() {
            *v = exp_nonpositive(0.5 * (*v - best.0)) * h_pre;
            total += *v;
        }
        let nb = cfg.n_bearing;
        let du = total / nb as f64;
        let (mut cell, mut acc) = (0usize, 0.0);
        let q = &pre.q[..];
        pf_core::simd::vectorised(
            #[inline(always)]
            || {
                for ib in 0..nb {
                    let u_target = (ib as f64 + 0.5) * du;
                    while cell + 1 < n_pre && acc + q[cell] < u_target {
                        acc += q[cell];
                        cell += 1;
                    }
                    let frac = ((u_target - acc) / q[cell]).clamp(0.0, 1.0);
                    let beta = centre + lo0 + (cell as f64 + frac) * h_pre;
                    let db = du * h_pre / q[cell];
                    let u = Vector2::new(beta.cos(), beta.sin());
                    // Along the ray ρ + r u: (p − m)ᵀΛ(p − m) = a r² − 2 b r + dᵀΛd.
                    let lu = lambda_mat * u;
                    let a = u.dot(&lu);
                    let b = lu.dot(&d);
                    let r_star = b / a;
                    let s_r = a.sqrt().recip();
                    let r_lo = (r_star - c * s_r).max(0.0);
                    let r_hi = r_star + c * s_r;
                    if r_hi <= 0.0 {
                        continue;
                    }
                    let log_g = self.log_g_with(beta, ln_sigma);
                    let dr = (r_hi - r_lo) / cfg.n_range as f64;
                    // The ray's nodes in one loop of plain arithmetic (pf-core's `ln`), which LLVM
                    // vectorises.
                    let start = nodes.len();
                    let end = start + cfg.n_range;
                    nodes.points.resize(end, SVector::zeros());
                    nodes.log_w.resize(end, 0.0);
                    nodes.log_g.resize(end, log_g);
                    let ray = nodes.points[start..]
                        .iter_mut()
                        .zip(&mut nodes.log_w[start..]);
                    for (ir, (p, lw)) in ray.enumerate() {
                        let r = r_lo + (ir as f64 + 0.5) * dr;
                        let q = -0.5 * (a * r * r - 2.0 * b * r + dd);
                        let log_n = -LN_2PI - 0.5 * ln_det + q;
                        *lw = ln(r * dr * db) + log_n + lambda * log_g;
                        *p = rho + r * u;
                    }
                }
            },
        );
        Ok(())
    }
}

/// Resolution of the whitened tensor grid.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WhitenedGridConfig {
    /// Nodes per dimension.
    pub n: usize,
    /// Half-width in standard deviations.
    pub n_sigma: f64,
}

impl Default for WhitenedGridConfig {
    fn default() -> Self {
        Self {
            n: 64,
            n_sigma: 7.0,
        }
    }
}

/// A tensor midpoint grid in the whitened coordinates `z` of `N(m, P)`, `p = m + L z`,
/// `z ∈ [−c, c]^D`, for a likelihood given as a closure `log g(y | p)`.
pub struct WhitenedGrid<const D: usize, G> {
    /// Resolution.
    pub config: WhitenedGridConfig,
    /// `p ↦ log g(y | p)`.
    pub log_g: G,
}

impl<const D: usize, G: Fn(&SVector<f64, D>) -> f64 + Sync> TemperedQuadrature<D>
    for WhitenedGrid<D, G>
{
    fn log_likelihood(&self, p: &SVector<f64, D>) -> f64 {
        (self.log_g)(p)
    }

    fn fill(&self, base: &Gaussian<D>, lambda: f64, nodes: &mut Nodes<D>) -> Result<()> {
        nodes.clear();
        let l = base.chol().ok_or(pf_core::CoreError::NotPositiveDefinite {
            what: "whitened grid base covariance",
            pivot: 0,
            value: base.cov[(0, 0)],
        })?;
        let n = self.config.n;
        let c = self.config.n_sigma;
        let h = 2.0 * c / n as f64;
        let ln_det_l: f64 = (0..D).map(|i| l[(i, i)].ln()).sum();
        let log_cell = D as f64 * h.ln() + ln_det_l;
        let total = n.pow(D as u32);
        let mut idx = [0usize; 16];
        for _ in 0..total {
            let mut z = SVector::<f64, D>::zeros();
            for i in 0..D {
                z[i] = -c + (idx[i] as f64 + 0.5) * h;
            }
            let p = base.mean + l * z;
            let log_n = -0.5 * D as f64 * LN_2PI - ln_det_l - 0.5 * z.norm_squared();
            let lg = (self.log_g)(&p);
            nodes.push(p, log_cell + log_n + lambda * lg, lg);
            for slot in idx.iter_mut().take(D) {
                *slot += 1;
                if *slot < n {
                    break;
                }
                *slot = 0;
            }
        }
        Ok(())
    }
}

/// Mean and covariance of `N(m, P)` restricted to the nodes, as `log N` would give them:
/// used to check a rule (eq. (25) at λ = 0 reduces to these moments).
pub fn node_moments<const D: usize>(nodes: &Nodes<D>) -> (SVector<f64, D>, SMatrix<f64, D, D>) {
    let mut m = SVector::<f64, D>::zeros();
    for (p, w) in nodes.points.iter().zip(&nodes.w) {
        m += *w * p;
    }
    let mut c = SMatrix::<f64, D, D>::zeros();
    for (p, w) in nodes.points.iter().zip(&nodes.w) {
        let e = p - m;
        c += *w * e * e.transpose();
    }
    (m, c)
}

/// `log N(p; g)` for a Gaussian `g`, or NaN if its covariance is singular.
pub fn log_density<const D: usize>(g: &Gaussian<D>, p: &SVector<f64, D>) -> f64 {
    match (g.cov.try_inverse(), g.chol()) {
        (Some(lm), Some(l)) => {
            let ln_det = 2.0 * (0..D).map(|i| l[(i, i)].ln()).sum::<f64>();
            log_normal(p, &g.mean, &lm, ln_det)
        }
        _ => f64::NAN,
    }
}

/// The complementary error function, `erfc(x) = 1 − erf(x)`, to a relative error below
/// 1.2·10⁻⁷ everywhere (Chebyshev fit of W. H. Press et al., *Numerical Recipes*, 2nd ed.,
/// §6.2, `erfcc`). Used only to place the bearing grid, where this accuracy is ample; no
/// workspace dependency provides it.
///
/// Plain arithmetic and pf-core's branch-free [`exp`] (within 1 ulp of glibc's), so that a
/// loop over it vectorises.
#[inline(always)]
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * exp(poly);
    if x >= 0.0 { r } else { 2.0 - r }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix2;
    use pf_core::mc::stream_rng;
    use rand::RngExt;

    /// The extremes every outline point's C-library bearing gives, as `bearing_extent`
    /// computed them before its first pass by pseudo-angle.
    fn extent_by_atan2(g: &Gaussian<2>, rho: [f64; 2], c: f64) -> Option<(f64, f64, f64)> {
        let l = g.chol()?;
        let lm = g.cov.try_inverse()?;
        let d = g.mean - Vector2::new(rho[0], rho[1]);
        if d.dot(&(lm * d)) <= c * c {
            return None;
        }
        let bc = d[1].atan2(d[0]);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for i in 0..OUTLINE {
            let t = std::f64::consts::TAU * i as f64 / OUTLINE as f64;
            let q = d + c * l * Vector2::new(t.cos(), t.sin());
            let db = wrap_angle(q[1].atan2(q[0]) - bc);
            lo = lo.min(db);
            hi = hi.max(db);
        }
        let pad = 0.02 * (hi - lo);
        Some((bc, lo - pad, hi + pad))
    }

    /// The normalised weights and the log normaliser are pf-core's `normalise`'s to a few
    /// ulp, the log-weights are left as given, and a NaN, a `+∞` or no positive weight is
    /// an error.
    #[test]
    fn nodes_normalise_as_pf_core_does() {
        for n in [1usize, 7, 8, 9, 1152] {
            let mut nodes = Nodes::<2>::new();
            for j in 0..n {
                let lw =
                    -0.5 * (j as f64 * 0.01 - 3.0).powi(2) + if j % 5 == 0 { -800.0 } else { 0.0 };
                nodes.push(SVector::zeros(), lw, 0.0);
            }
            let given = nodes.log_w.clone();
            let c = nodes.normalise(0, 1.0).unwrap();
            let (mut l, mut w) = (given.clone(), vec![0.0; n]);
            let c_ref = pf_core::weights::normalise(0, &mut l, &mut w).unwrap();
            assert!((c - c_ref).abs() <= 1e-14 * c_ref.abs().max(1.0), "n = {n}");
            for (a, b) in nodes.w.iter().zip(&w) {
                assert!(
                    (a - b).abs() <= 4.0 * f64::EPSILON * b,
                    "n = {n}: {a} against {b}"
                );
            }
            assert_eq!(nodes.log_w, given);
        }
        for bad in [f64::NAN, f64::INFINITY] {
            let mut nodes = Nodes::<2>::new();
            for j in 0..11 {
                nodes.push(SVector::zeros(), if j == 9 { bad } else { 0.0 }, 0.0);
            }
            assert!(matches!(
                nodes.normalise(3, 0.5),
                Err(HomotopyError::Core(pf_core::CoreError::NonFiniteWeight {
                    t: 3,
                    index: 9,
                    ..
                }))
            ));
        }
        let mut nodes = Nodes::<2>::new();
        nodes.push(SVector::zeros(), f64::NEG_INFINITY, 0.0);
        assert!(matches!(
            nodes.normalise(2, 0.5),
            Err(HomotopyError::DegenerateQuadrature { k: 2, .. })
        ));
    }

    /// The diamond angle increases with the angle over the whole circle.
    #[test]
    fn the_diamond_angle_increases_with_the_angle() {
        let n = 100_000;
        let mut prev = f64::NEG_INFINITY;
        for i in 0..n {
            let a = -std::f64::consts::PI + std::f64::consts::TAU * (i as f64 + 0.5) / n as f64;
            let p = diamond(3.0 * a.sin(), 3.0 * a.cos());
            assert!(p > prev, "not increasing at angle {a}: {p} after {prev}");
            prev = p;
        }
    }

    /// The two-pass extent is the one-pass extent to the last bit, over random ellipses
    /// seen from near and far (thin, round, tilted; from beside an elongated one, where the
    /// bearings reach more than π/2 from the centre's).
    #[test]
    fn the_bearing_extent_is_the_c_librarys_to_the_last_bit() {
        let mut rng = stream_rng(7, 0);
        let mut seen = 0;
        for _ in 0..2000 {
            let mean = Vector2::new(rng.random_range(-5e3..5e3), rng.random_range(-5e3..5e3));
            let (s1, s2) = (rng.random_range(1.0..3e3f64), rng.random_range(1.0..3e3f64));
            let th: f64 = rng.random_range(0.0..std::f64::consts::PI);
            let (s, c) = th.sin_cos();
            let rot = Matrix2::new(c, -s, s, c);
            let cov = rot * Matrix2::new(s1 * s1, 0.0, 0.0, s2 * s2) * rot.transpose();
            let g = Gaussian::new(mean, 0.5 * (cov + cov.transpose()));
            let rho = [rng.random_range(-6e3..6e3), rng.random_range(-6e3..6e3)];
            let (l, lm) = (g.chol().unwrap(), g.cov.try_inverse().unwrap());
            let two_pass = bearing_extent(&g, &l, &lm, rho, 5.0);
            let one_pass = extent_by_atan2(&g, rho, 5.0);
            let bits = |e: Option<(f64, f64, f64)>| e.map(|(a, b, c)| [a, b, c].map(f64::to_bits));
            assert_eq!(bits(two_pass), bits(one_pass), "{g:?} from {rho:?}");
            seen += usize::from(two_pass.is_some());
        }
        assert!(seen > 500, "only {seen} ellipses excluded the observer");
    }

    /// Filling for one base at several λ, in any order, gives the nodes a fresh grid gives:
    /// the kept pre-grid is the one the base would build.
    #[test]
    fn a_kept_pre_grid_fills_as_a_fresh_one() {
        let base = Gaussian::new(
            Vector2::new(3500.0, 3500.0),
            Matrix2::new(1e6, 9e5, 9e5, 1e6),
        );
        let other = Gaussian::new(
            Vector2::new(2000.0, 4000.0),
            Matrix2::new(4e5, 0.0, 0.0, 9e5),
        );
        let grid = || PolarGrid::new(PolarGridConfig::default(), [0.0, 0.0], 0.87, 0.0175);
        let kept = grid();
        let mut nodes = Nodes::new();
        for (g, lambda) in [
            (&base, 0.0),
            (&base, 0.3),
            (&other, 0.0),
            (&base, 1.0),
            (&base, 0.3),
        ] {
            kept.fill(g, lambda, &mut nodes).unwrap();
            let mut fresh = Nodes::new();
            grid().fill(g, lambda, &mut fresh).unwrap();
            let bits = |n: &Nodes<2>| {
                let mut v: Vec<u64> = n
                    .log_w
                    .iter()
                    .chain(&n.log_g)
                    .map(|x| x.to_bits())
                    .collect();
                v.extend(
                    n.points
                        .iter()
                        .flat_map(|p| [p[0].to_bits(), p[1].to_bits()]),
                );
                v
            };
            assert_eq!(bits(&nodes), bits(&fresh), "λ = {lambda}");
        }
    }
}
