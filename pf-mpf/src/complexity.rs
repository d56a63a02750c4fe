//! The equivalent-flop (EF) complexity model of Section III.
//!
//! A flop is one addition, subtraction, multiplication or division. Likelihood evaluation,
//! resampling and random-number generation are not matrix arithmetic; their cost per
//! particle is expressed in flops of equal time (Definition 1) through the coefficients
//! `c1` (likelihood), `c2` (resampling) and `c3` (one random number).

use crate::error::Result;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// The EF coefficients `c1`, `c2`, `c3`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EfCoefficients {
    /// `c1`: Gaussian likelihood evaluation, per particle.
    pub c1: f64,
    /// `c2`: resampling, per particle.
    pub c2: f64,
    /// `c3`: one random number.
    pub c3: f64,
}

impl Default for EfCoefficients {
    /// The paper's values (Section IV-A, Sun Blade 100): `c1 = 445`, `c2 = 487`, `c3 = 125`.
    fn default() -> Self {
        Self {
            c1: 445.0,
            c2: 487.0,
            c3: 125.0,
        }
    }
}

impl EfCoefficients {
    /// Check that every coefficient is finite and non-negative.
    ///
    /// # Errors
    /// [`MpfError::Param`](crate::MpfError::Param) naming the coefficient.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [("c1", self.c1), ("c2", self.c2), ("c3", self.c3)] {
            pf_core::params::non_negative(name, v)?;
        }
        Ok(())
    }
}

/// Which complexity expression applies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CtCase {
    /// `C_t = 0`: eq. (11), one Riccati recursion for all particles.
    #[default]
    Zero,
    /// `C_t ≠ 0`: eq. (12), a Riccati recursion per particle.
    NonZero,
}

/// The EF complexity of one MPF step split as `constant + per_particle · N`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EfCost {
    /// Part independent of `N`.
    pub constant: f64,
    /// Part per particle.
    pub per_particle: f64,
}

impl EfCost {
    /// `constant + per_particle · N`.
    pub fn at(&self, n: f64) -> f64 {
        self.constant + self.per_particle * n
    }
}

/// Eq. (11), `C_t = 0`:
/// `C(p,k,N) = 4pk² + 8kp² + 4/3 p³ + 5k³ − 5kp + 2p²
///  + (6kp + 4p² + 2k² + p − k + p c3 + c1 + c2) N`.
pub fn ef_ct_zero(p: usize, k: usize, c: &EfCoefficients) -> EfCost {
    let (p, k) = (p as f64, k as f64);
    EfCost {
        constant: 4.0 * p * k * k + 8.0 * k * p * p + 4.0 / 3.0 * p.powi(3) + 5.0 * k.powi(3)
            - 5.0 * k * p
            + 2.0 * p * p,
        per_particle: 6.0 * k * p + 4.0 * p * p + 2.0 * k * k + p - k + p * c.c3 + c.c1 + c.c2,
    }
}

/// Eq. (12), `C_t ≠ 0`: every term of eq. (11) plus `k³` (the per-particle measurement
/// update), all per particle.
pub fn ef_ct_nonzero(p: usize, k: usize, c: &EfCoefficients) -> EfCost {
    let z = ef_ct_zero(p, k, c);
    EfCost {
        constant: 0.0,
        per_particle: z.per_particle + z.constant + (k as f64).powi(3),
    }
}

/// `C(p, k, ·)` for the given case.
pub fn ef_cost(case: CtCase, p: usize, k: usize, c: &EfCoefficients) -> EfCost {
    match case {
        CtCase::Zero => ef_ct_zero(p, k, c),
        CtCase::NonZero => ef_ct_nonzero(p, k, c),
    }
}

/// `N(k)` solving `C(p+k, 0, N_PF) = C(p, k, N(k))` (Section III-A).
///
/// The standard PF is always costed by eq. (11) at `k = 0`: it has no Riccati recursion, so
/// the per-particle Riccati terms of eq. (12) do not apply to it. The MPF side uses `case`.
pub fn equal_cost_particles(
    case: CtCase,
    p: usize,
    k: usize,
    n_pf: f64,
    c: &EfCoefficients,
) -> f64 {
    let pf = ef_ct_zero(p + k, 0, c).at(n_pf);
    let mpf = ef_cost(case, p, k, c);
    (pf - mpf.constant) / mpf.per_particle
}

/// The ratio `N(k)/N_PF` of Figs. 1 and 2.
pub fn particle_ratio(case: CtCase, p: usize, k: usize, n_pf: f64, c: &EfCoefficients) -> f64 {
    equal_cost_particles(case, p, k, n_pf, c) / n_pf
}

/// The factor of eq. (14): `N_PF = (1 − (4c3 + 56)/(c1 + c2 + 6c3 + 150)) N_MPF` for the
/// radar model, full PF (6, 0) against full marginalization (2, 4), constants neglected.
pub fn eq14_factor(c: &EfCoefficients) -> f64 {
    1.0 - (4.0 * c.c3 + 56.0) / (c.c1 + c.c2 + 6.0 * c.c3 + 150.0)
}

/// The per-particle EF of eq. (11) (`C_t = 0`) split into its four sources, to show which
/// term makes the MPF cheaper than the standard PF, or fails to.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PerParticleTerms {
    /// Matrix arithmetic, `6kp + 4p² + 2k² + p − k` (Table I).
    pub flops: f64,
    /// Random numbers, `p·c3`.
    pub random_numbers: f64,
    /// Likelihood, `c1`.
    pub likelihood: f64,
    /// Resampling, `c2`.
    pub resampling: f64,
    /// The extension's `c_m·(p + k)` ([`ef_structural`]); 0 in the paper's form.
    #[serde(default)]
    pub state_traffic: f64,
}

impl PerParticleTerms {
    /// Their sum: eq. (11)'s coefficient of `N` (plus the extension's term).
    pub fn total(&self) -> f64 {
        self.flops + self.random_numbers + self.likelihood + self.resampling + self.state_traffic
    }
}

/// Eq. (11)'s coefficient of `N`, term by term, with the extension's `c_m` (0: the paper's
/// form).
pub fn per_particle_terms(p: usize, k: usize, c: &EfCoefficients, c_m: f64) -> PerParticleTerms {
    let (pf, kf) = (p as f64, k as f64);
    PerParticleTerms {
        flops: 6.0 * kf * pf + 4.0 * pf * pf + 2.0 * kf * kf + pf - kf,
        random_numbers: pf * c.c3,
        likelihood: c.c1,
        resampling: c.c2,
        state_traffic: c_m * (pf + kf),
    }
}

/// The extension's `c_m` from one measured time of the standard PF, whose cost without it
/// is `base` (EF per step): the EF per state value per particle that the model leaves
/// unexplained, `(seconds/(t_f·flop_ns·10⁻⁹) − base(N))/(m·N)` for `m` states, `N`
/// particles and `t_f` steps, floored at 0 (a model that already over-predicts gets none).
pub fn fit_state_traffic(
    base: &EfCost,
    m: usize,
    n: usize,
    t_f: usize,
    seconds: f64,
    flop_ns: f64,
) -> f64 {
    let measured_ef = seconds / (t_f as f64 * flop_ns * 1e-9);
    let c_m = (measured_ef - base.at(n as f64)) / (m as f64 * n as f64);
    if c_m.is_finite() { c_m.max(0.0) } else { 0.0 }
}

/// Flops of `y = A x` per particle when the structural zeros of `A` are skipped: one
/// multiplication per nonzero and one addition per nonzero beyond the first of its row
/// (`r(2c − 1)` for a dense `r×c` matrix, Table I's count).
pub fn product_flops(a: &DMatrix<f64>) -> f64 {
    let tol = 1e-12 * a.amax();
    let mut flops = 0usize;
    for row in a.row_iter() {
        let nnz = row.iter().filter(|v| v.abs() > tol).count();
        flops += (2 * nnz).saturating_sub(1);
    }
    flops as f64
}

/// The matrices of Alg. 1's per-particle rows of Table I (`C_t = 0`) for one partition:
/// `A^p, A^k, F^p, F^k` of model (5), and the `T1 = chol(M)` and gain `L` of the shared
/// Riccati recursion.
#[derive(Debug, Clone, PartialEq)]
pub struct Alg1Matrices {
    /// `A^p` (p×p).
    pub a_p: DMatrix<f64>,
    /// `A^k` (p×k).
    pub a_k: DMatrix<f64>,
    /// `F^p` (k×p).
    pub f_p: DMatrix<f64>,
    /// `F^k` (k×k).
    pub f_k: DMatrix<f64>,
    /// `T1 = chol(M)`, `M = A^k P A^kᵀ + Q^p` (p×p, lower triangular).
    pub t1: DMatrix<f64>,
    /// `L = F^k P A^kᵀ M⁻¹` (k×p).
    pub l: DMatrix<f64>,
}

impl Alg1Matrices {
    /// From model (5)'s matrices and the shared covariance after `steps` Riccati recursions
    /// from `P_0` (the structure of `T1` and `L` settles within a few; `None` if `M` is not
    /// positive definite).
    #[allow(clippy::too_many_arguments)]
    pub fn from_model(
        a_p: DMatrix<f64>,
        a_k: DMatrix<f64>,
        f_p: DMatrix<f64>,
        f_k: DMatrix<f64>,
        q_p: &DMatrix<f64>,
        q_k: &DMatrix<f64>,
        p0_k: &DMatrix<f64>,
        steps: usize,
    ) -> Option<Self> {
        let mut p = p0_k.clone();
        let mut out = None;
        for _ in 0..steps.max(1) {
            let pa = &p * a_k.transpose();
            let m = &a_k * &pa + q_p;
            let chol = m.clone().cholesky()?;
            let l = &f_k * &pa * chol.inverse();
            let next = &f_k * &p * f_k.transpose() + q_k - &l * &m * l.transpose();
            out = Some((chol.l(), l));
            p = 0.5 * (&next + next.transpose());
        }
        let (t1, l) = out?;
        Some(Self {
            a_p,
            a_k,
            f_p,
            f_k,
            t1,
            l,
        })
    }

    /// `p`, the PF states.
    pub fn p(&self) -> usize {
        self.a_p.nrows()
    }

    /// `k`, the KF states.
    pub fn k(&self) -> usize {
        self.f_k.nrows()
    }

    /// Table I's per-particle flops counted on these matrices' nonzeros (the extension's
    /// flop term): `w := T1·T2`, `T3 := A^p x^p`, `T4 := A^k x^k`, `x^p := T3 + T4 + w`
    /// and, with `k > 0`, `T7 := F^k x^k`, `T8 := F^p x^p`, `T9 := x^p − T3 − T4`,
    /// `x^k := T7 + T8 + L T9`. For dense matrices this is eq. (11)'s
    /// `6kp + 4p² + 2k² + p − k` less `p(p − 1)` (`T1` is triangular, which eq. (11)
    /// ignores) and, at `k = 0`, less the `2p` of the absent `T4` and `T9` rows (tested); a
    /// filter that skips structural zeros does fewer still.
    pub fn flops_per_particle(&self) -> f64 {
        let (p, k) = (self.p() as f64, self.k() as f64);
        let base = product_flops(&self.t1) + product_flops(&self.a_p);
        if self.k() == 0 {
            // T4 and the Kalman rows vanish; x^p := T3 + w.
            return base + p;
        }
        base + product_flops(&self.a_k)
            + 2.0 * p
            + product_flops(&self.f_k)
            + product_flops(&self.f_p)
            + 2.0 * p
            + product_flops(&self.l)
            + 2.0 * k
    }
}

/// The extended model, beyond the paper: eq. (11) with two changes. Its flops per
/// particle are Table I's rows counted on the model's nonzeros
/// ([`Alg1Matrices::flops_per_particle`]), as a filter that skips structural zeros executes
/// them; and `c_m (p + k)` EF per particle is added for reading, writing and moving each
/// particle's `p + k` state values, which costs time but no flop (`c_m` fitted on the
/// standard PF's time, [`fit_state_traffic`]; 0 where the rest already explains it).
/// The `N`-independent part is eq. (11)'s.
pub fn ef_structural(m: &Alg1Matrices, c: &EfCoefficients, c_m: f64) -> EfCost {
    let (p, k) = (m.p(), m.k());
    EfCost {
        constant: ef_ct_zero(p, k, c).constant,
        per_particle: structural_terms(m, c, c_m).total(),
    }
}

/// [`ef_structural`]'s per-particle cost, term by term.
pub fn structural_terms(m: &Alg1Matrices, c: &EfCoefficients, c_m: f64) -> PerParticleTerms {
    let (p, k) = (m.p(), m.k());
    PerParticleTerms {
        flops: m.flops_per_particle(),
        ..per_particle_terms(p, k, c, c_m)
    }
}

/// `N(k)` at which the extended model of the MPF `mpf` costs what it gives the standard PF
/// `pf` with `N_PF` particles (Section III-A's equation, [`ef_structural`] for `C`).
pub fn equal_cost_particles_structural(
    pf: &Alg1Matrices,
    mpf: &Alg1Matrices,
    n_pf: f64,
    c: &EfCoefficients,
    c_m: f64,
) -> f64 {
    let cost = ef_structural(mpf, c, c_m);
    (ef_structural(pf, c, c_m).at(n_pf) - cost.constant) / cost.per_particle
}

/// One row of Table I: an instruction and its flop counts, with `N` factored out where the
/// row scales with it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TableIRow {
    /// The instruction as the paper writes it.
    pub instruction: &'static str,
    /// Multiplications.
    pub mult: f64,
    /// Additions.
    pub add: f64,
    /// Other (EF) operations: Cholesky, inverse, random numbers.
    pub other: f64,
}

/// Table I evaluated at `(p, k, N)`, `C_t = 0`. Its rows sum to eq. (11) except for the
/// likelihood (`c1 N`) and resampling (`c2 N`), which the table leaves out, and one `k³`:
/// the rows give `4k³` where eq. (11) prints `5k³` (see the crate README).
pub fn table_one(p: usize, k: usize, n: usize, c: &EfCoefficients) -> Vec<TableIRow> {
    let (p, k, n) = (p as f64, k as f64, n as f64);
    let row = |instruction, mult, add, other| TableIRow {
        instruction,
        mult,
        add,
        other,
    };
    vec![
        row(
            "P_A := P_{t|t} (A^k_t)^T",
            p * k * k,
            (k - 1.0) * k * p,
            0.0,
        ),
        row(
            "M := A^k_t P_A + Q^p_t",
            k * p * p,
            (k - 1.0) * p * p + p * p,
            0.0,
        ),
        row("T1 := chol(M)", 0.0, 0.0, p.powi(3) / 3.0 + 2.0 * p * p),
        row("T2 := randn(p, N)", 0.0, 0.0, p * n * c.c3),
        row("w := T1 * T2", p * p * n, (p - 1.0) * p * n, 0.0),
        row("T3 := A^p x^p", p * p * n, (p - 1.0) * p * n, 0.0),
        row("T4 := A^k x^k", p * k * n, (k - 1.0) * p * n, 0.0),
        row("x^p_{t+1|t} := T3 + T4 + w", 0.0, 2.0 * p * n, 0.0),
        row("invM := M^{-1}", 0.0, 0.0, p.powi(3)),
        row(
            "L := F^k_t P_A invM",
            k * k * p + k * p * p,
            k * k * p + p * p * k - 2.0 * k * p,
            0.0,
        ),
        row(
            "T5 := F^k_t P_{t|t} (F^k_t)^T",
            2.0 * k.powi(3),
            2.0 * (k - 1.0) * k * k,
            0.0,
        ),
        row(
            "T6 := L_t M_t L_t^T",
            2.0 * k * p * p,
            2.0 * (p - 1.0) * p * k,
            0.0,
        ),
        row("P := T5 + Q^k_t - T6", 0.0, 2.0 * k * k, 0.0),
        row("T7 := F^k_t x^k", k * k * n, (k - 1.0) * k * n, 0.0),
        row("T8 := F^p_t x^p", k * p * n, (p - 1.0) * k * n, 0.0),
        row("T9 := x^p_{t+1|t} - T3 - T4", 0.0, 2.0 * p * n, 0.0),
        row(
            "x^k_{t+1|t} := T7 + T8 + L T9",
            k * p * n,
            (p + 1.0) * k * n,
            0.0,
        ),
    ]
}

/// Sum of every count of Table I.
pub fn table_one_total(p: usize, k: usize, n: usize, c: &EfCoefficients) -> f64 {
    table_one(p, k, n, c)
        .iter()
        .map(|r| r.mult + r.add + r.other)
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_terms_sum_to_eq_11() {
        let c = EfCoefficients::default();
        for k in 0..=4 {
            let p = 6 - k;
            let t = per_particle_terms(p, k, &c, 0.0);
            assert!((t.total() - ef_ct_zero(p, k, &c).per_particle).abs() < 1e-9);
            let e = per_particle_terms(p, k, &c, 7.0);
            assert!((e.total() - t.total() - 7.0 * 6.0).abs() < 1e-9);
        }
    }

    #[test]
    fn structural_flops_are_table_one_for_dense_matrices_and_fewer_for_sparse() {
        let dense = |r: usize, c: usize, seed: usize| {
            DMatrix::from_fn(r, c, |i, j| 1.0 + ((i * 31 + j * 17 + seed) % 7) as f64)
        };
        for (p, k) in [(6, 0), (5, 1), (4, 2), (3, 3), (2, 4)] {
            let eye = |n: usize| DMatrix::<f64>::identity(n, n);
            let q_p = dense(p, p, 1) * dense(p, p, 1).transpose() + eye(p);
            let m = Alg1Matrices::from_model(
                dense(p, p, 2),
                dense(p, k, 3),
                dense(k, p, 4),
                dense(k, k, 5),
                &q_p,
                &eye(k),
                &(dense(k, k, 6) * dense(k, k, 6).transpose() + eye(k)),
                3,
            )
            .unwrap();
            // A dense T1 is lower triangular: eq. (11) counts w := T1·T2 as a full p×p
            // product, so the structural count is p(p − 1) flops lower.
            let table_one = 6 * k * p + 4 * p * p + 2 * k * k + p - k;
            let got = m.flops_per_particle() + (p * (p - 1)) as f64;
            // At k = 0 eq. (11) still counts the rows of T4 (−p flops for an empty
            // product) and T9 (2p); without them the standard PF is 4p² − p.
            let want = if k == 0 { 4 * p * p - p } else { table_one } as f64;
            assert_eq!(got, want, "p = {p}, k = {k}");
        }
        // A diagonal matrix costs one multiplication per row.
        assert_eq!(product_flops(&DMatrix::identity(4, 4)), 4.0);
        assert_eq!(product_flops(&DMatrix::zeros(3, 3)), 0.0);
    }

    #[test]
    fn the_state_traffic_fit_recovers_its_coefficient() {
        let c = EfCoefficients::default();
        let (m, n, t_f, flop_ns) = (6, 2000, 50, 0.04);
        let base = ef_ct_zero(m, 0, &c);
        let ef = base.at(n as f64) + 12.5 * (m * n) as f64;
        let seconds = ef * t_f as f64 * flop_ns * 1e-9;
        let c_m = fit_state_traffic(&base, m, n, t_f, seconds, flop_ns);
        assert!((c_m - 12.5).abs() < 1e-9, "{c_m}");
        // A measured time below the model's: no extension, never negative.
        assert_eq!(
            fit_state_traffic(&base, m, n, t_f, 0.5 * seconds, flop_ns),
            0.0
        );
        assert_eq!(fit_state_traffic(&base, m, n, t_f, f64::NAN, flop_ns), 0.0);
    }

    #[test]
    fn the_extended_model_buys_more_particles_when_zeros_are_skipped() {
        // The radar's PF (identity-plus-shift A) against a dense model of the same sizes.
        let c = EfCoefficients::default();
        let eye = |n: usize| DMatrix::<f64>::identity(n, n);
        let sparse = |p: usize, k: usize| {
            Alg1Matrices::from_model(
                eye(p),
                DMatrix::from_fn(p, k, |i, j| if i == j { 1.0 } else { 0.0 }),
                DMatrix::zeros(k, p),
                eye(k),
                &eye(p),
                &eye(k),
                &eye(k),
                3,
            )
            .unwrap()
        };
        let (pf, mpf) = (sparse(6, 0), sparse(2, 4));
        assert!(pf.flops_per_particle() < ef_ct_zero(6, 0, &c).per_particle - 6.0 * c.c3);
        let n = equal_cost_particles_structural(&pf, &mpf, 2000.0, &c, 0.0);
        // Random numbers dominate what marginalization saves: still more particles.
        assert!(n > 2000.0 && n.is_finite(), "{n}");
        // The state traffic is the same for both and dilutes the gain.
        let diluted = equal_cost_particles_structural(&pf, &mpf, 2000.0, &c, 500.0);
        assert!(diluted < n && diluted > 2000.0);
    }
}
