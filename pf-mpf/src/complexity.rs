//! The equivalent-flop (EF) complexity model of Section III.
//!
//! A flop is one addition, subtraction, multiplication or division. Likelihood evaluation,
//! resampling and random-number generation are not matrix arithmetic; their cost per
//! particle is expressed in flops of equal time (Definition 1) through the coefficients
//! `c1` (likelihood), `c2` (resampling) and `c3` (one random number).

use crate::error::Result;
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
    /// The extension's `c_m·(p + k)` ([`ef_ct_zero_extended`]); 0 in the paper's form.
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

/// An extension of eq. (11) beyond the paper: `C(p,k,N) + c_m·(p + k)·N`.
///
/// Table I counts the arithmetic of Alg. 1, and `c1, c2, c3` its likelihood, resampling and
/// random numbers. A filter also reads, writes and moves every particle's `p + k` state
/// values several times a step (the resampled copies, the intermediate `T_i` blocks, the
/// estimate), which costs time but no flop. `c_m` is that cost per state value per particle
/// in EF; it is fitted on the standard PF's measured time (see
/// [`fit_state_traffic`]), and the paper's form is `c_m = 0`.
pub fn ef_ct_zero_extended(p: usize, k: usize, c: &EfCoefficients, c_m: f64) -> EfCost {
    let z = ef_ct_zero(p, k, c);
    EfCost {
        constant: z.constant,
        per_particle: z.per_particle + c_m * (p + k) as f64,
    }
}

/// `N(k)` solving `C_ext(p+k, 0, N_PF) = C_ext(p, k, N(k))` with [`ef_ct_zero_extended`]
/// (`c_m = 0` gives [`equal_cost_particles`] with [`CtCase::Zero`]).
pub fn equal_cost_particles_extended(
    p: usize,
    k: usize,
    n_pf: f64,
    c: &EfCoefficients,
    c_m: f64,
) -> f64 {
    let pf = ef_ct_zero_extended(p + k, 0, c, c_m).at(n_pf);
    let mpf = ef_ct_zero_extended(p, k, c, c_m);
    (pf - mpf.constant) / mpf.per_particle
}

/// The extension's `c_m` from one measured time of the standard PF (`m = p + k` states, `N`
/// particles, `t_f` steps, `seconds` in all) and the flop time: the EF per state value per
/// particle that eq. (11) leaves unexplained, `(seconds/(t_f·flop_ns·10⁻⁹) − C(m,0,N))/(m·N)`,
/// floored at 0 (a model that already over-predicts gets no extension).
pub fn fit_state_traffic(
    m: usize,
    n: usize,
    t_f: usize,
    seconds: f64,
    flop_ns: f64,
    c: &EfCoefficients,
) -> f64 {
    let measured_ef = seconds / (t_f as f64 * flop_ns * 1e-9);
    let model = ef_ct_zero(m, 0, c).at(n as f64);
    let c_m = (measured_ef - model) / (m as f64 * n as f64);
    if c_m.is_finite() { c_m.max(0.0) } else { 0.0 }
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
    fn the_terms_sum_to_eq_11_and_the_extension_reduces_to_it() {
        let c = EfCoefficients::default();
        for k in 0..=4 {
            let p = 6 - k;
            let t = per_particle_terms(p, k, &c, 0.0);
            assert!((t.total() - ef_ct_zero(p, k, &c).per_particle).abs() < 1e-9);
            assert_eq!(ef_ct_zero_extended(p, k, &c, 0.0), ef_ct_zero(p, k, &c));
            let a = equal_cost_particles_extended(p, k, 2000.0, &c, 0.0);
            let b = equal_cost_particles(CtCase::Zero, p, k, 2000.0, &c);
            assert!((a - b).abs() < 1e-9);
            let e = per_particle_terms(p, k, &c, 7.0);
            assert!((e.total() - ef_ct_zero_extended(p, k, &c, 7.0).per_particle).abs() < 1e-9);
        }
        // The extension's term is the same for every partition of six states, so it dilutes
        // the MPF's advantage: the particle ratio falls towards 1 as c_m grows.
        let r0 = equal_cost_particles_extended(2, 4, 2000.0, &c, 0.0);
        let r1 = equal_cost_particles_extended(2, 4, 2000.0, &c, 500.0);
        assert!(r0 > r1 && r1 > 2000.0);
    }

    #[test]
    fn the_state_traffic_fit_recovers_its_coefficient() {
        let c = EfCoefficients::default();
        let (m, n, t_f, flop_ns) = (6, 2000, 50, 0.04);
        let ef = ef_ct_zero_extended(m, 0, &c, 12.5).at(n as f64);
        let seconds = ef * t_f as f64 * flop_ns * 1e-9;
        let c_m = fit_state_traffic(m, n, t_f, seconds, flop_ns, &c);
        assert!((c_m - 12.5).abs() < 1e-9, "{c_m}");
        // A measured time below the model's: no extension, never negative.
        assert_eq!(
            fit_state_traffic(m, n, t_f, 0.5 * seconds, flop_ns, &c),
            0.0
        );
        assert_eq!(fit_state_traffic(m, n, t_f, f64::NAN, flop_ns, &c), 0.0);
    }
}
