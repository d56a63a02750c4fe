//! The static relations of the sedimentation model, Section II: overflow rate (4)–(5), the
//! linear density profile (6) with its slope `k_ρ`, settling (7) and scouring (8).
//!
//! The paper leaves every physical constant unstated; [`HopperParams::default`] holds the
//! values this crate chose for a ~10 000 m³ trailing suction hopper dredger (see the README).

use crate::error::Result;
use pf_core::params::{ParamError, positive};
use serde::{Deserialize, Serialize};

/// How the overflow pipe discharges.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OverflowRegime {
    /// Free (weir) flow over the rim, eq. (4).
    Free,
    /// A full pipe (orifice flow), eq. (5).
    Full,
    /// Whichever of (4) and (5) is smaller: weir control at low heads, pipe (orifice) control
    /// once the pipe runs full. The switch is continuous.
    #[default]
    Limiting,
}

/// Physical constants of the hopper (Appendix, "Parameters"). Units are SI.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HopperParams {
    /// `A`, hopper area (m²).
    pub area: f64,
    /// `k_o`, free-overflow coefficient of eq. (4) (m^{3/2}/s).
    pub k_o: f64,
    /// `k'_o`, full-pipe coefficient of eq. (5) (m²).
    pub k_o_full: f64,
    /// Which overflow law applies.
    pub regime: OverflowRegime,
    /// `k_c`, scouring parameter of eq. (8) (m⁴/s²).
    pub k_c: f64,
    /// `v_s`, undisturbed settling velocity (m/s).
    pub v_s: f64,
    /// `β`, the hindered-settling exponent of eq. (7).
    pub beta: f64,
    /// `ρ_q`, quartz density (kg/m³).
    pub rho_q: f64,
    /// `ρ_s`, density of the sand bed (kg/m³).
    pub rho_s: f64,
    /// `ρ_w`, water density (kg/m³).
    pub rho_w: f64,
    /// `g`, acceleration due to gravity (m/s²).
    pub g: f64,
}

impl Default for HopperParams {
    fn default() -> Self {
        HopperParams {
            area: 1000.0,
            k_o: 13.9,
            k_o_full: 2.95,
            regime: OverflowRegime::Limiting,
            k_c: 20.0,
            v_s: 0.025,
            beta: 3.8,
            rho_q: 2650.0,
            rho_s: 2000.0,
            rho_w: 1025.0,
            g: 9.81,
        }
    }
}

impl HopperParams {
    /// Check that every constant is physical: positive, and `ρ_w < ρ_s < ρ_q`.
    ///
    /// # Errors
    /// [`DredgeError::Param`](crate::DredgeError::Param) naming the
    /// constant.
    pub fn validate(&self) -> Result<()> {
        positive("A", self.area)?;
        positive("k_o", self.k_o)?;
        positive("k'_o", self.k_o_full)?;
        positive("k_c", self.k_c)?;
        positive("v_s", self.v_s)?;
        positive("beta", self.beta)?;
        positive("rho_w", self.rho_w)?;
        positive("g", self.g)?;
        if self.rho_s.is_nan() || self.rho_s <= self.rho_w {
            return Err(crate::DredgeError::Param(ParamError {
                name: "rho_s",
                value: self.rho_s,
                reason: "the sand bed must be denser than water (rho_s > rho_w)",
            }));
        }
        if !(self.rho_q > self.rho_s && self.rho_q.is_finite()) {
            return Err(crate::DredgeError::Param(ParamError {
                name: "rho_q",
                value: self.rho_q,
                reason: "quartz must be denser than the sand bed (rho_q > rho_s)",
            }));
        }
        Ok(())
    }

    /// Overflow rate `Q_o` for a head `h_t − h_o`: eq. (4), eq. (5), or the smaller of the two.
    pub fn overflow_rate(&self, h_t: f64, h_o: f64) -> f64 {
        let head = (h_t - h_o).max(0.0);
        let free = self.k_o * head.powf(1.5);
        let full = self.k_o_full * (2.0 * self.g * head).sqrt();
        match self.regime {
            OverflowRegime::Free => free,
            OverflowRegime::Full => full,
            OverflowRegime::Limiting => free.min(full),
        }
    }

    /// `ρ_m = ρ_s (m_t − m_s) / (V_t ρ_s − m_s)`, the mean density of the mixture above the bed.
    pub fn mixture_density(&self, v_t: f64, m_t: f64, m_s: f64) -> f64 {
        self.rho_s * (m_t - m_s) / (v_t * self.rho_s - m_s)
    }

    /// Heights `(h_t, h_s, h_m)`: content `V_t/A`, bed `m_s/(ρ_s A)`, mixture `h_t − h_s`.
    pub fn heights(&self, v_t: f64, m_s: f64) -> (f64, f64, f64) {
        let h_t = v_t / self.area;
        let h_s = m_s / (self.rho_s * self.area);
        (h_t, h_s, h_t - h_s)
    }

    /// The slope `k_ρ` of the profile (6), solved from the mass balance so that the profile's
    /// mean over the mixture layer is `ρ_m`. `+∞` when `ρ_m ≤ ρ_w` (clear water: the profile
    /// drops to `ρ_w` at once).
    pub fn k_rho(&self, rho_m: f64, h_m: f64) -> f64 {
        if rho_m <= self.rho_w || h_m <= 0.0 {
            f64::INFINITY
        } else if rho_m > 0.5 * (self.rho_w + self.rho_s) {
            2.0 * (self.rho_s - rho_m) / h_m
        } else {
            (self.rho_s - self.rho_w).powi(2) / (2.0 * h_m * (rho_m - self.rho_w))
        }
    }

    /// `ρ(h) = max(ρ_s − k_ρ (h − h_s), ρ_w)`: the profile (6) at height `h` above the hopper
    /// floor (the overflow density when `h = h_o`).
    pub fn profile_density(&self, k_rho: f64, h: f64, h_s: f64) -> f64 {
        let dh = (h - h_s).max(0.0);
        if k_rho.is_infinite() {
            // ρ_s − ∞·dh with dh = 0 would be NaN: at the bed itself the density is ρ_s.
            return if dh > 0.0 { self.rho_w } else { self.rho_s };
        }
        (self.rho_s - k_rho * dh).max(self.rho_w)
    }

    /// Settling function (7): `f_s(ρ_m) = A ρ_s v_s (ρ_m − ρ_w)/(ρ_s − ρ_m) ((ρ_q − ρ_m)/(ρ_q − ρ_w))^β`
    /// (kg/s), zero for clear water and clamped to zero outside `ρ_w < ρ_m < ρ_s`.
    pub fn settling(&self, rho_m: f64) -> f64 {
        if rho_m <= self.rho_w || rho_m >= self.rho_s {
            return 0.0;
        }
        self.area * self.rho_s * self.v_s * (rho_m - self.rho_w) / (self.rho_s - rho_m)
            * ((self.rho_q - rho_m) / (self.rho_q - self.rho_w)).powf(self.beta)
    }

    /// Scouring function (8): `f_e(Q_o, h_m) = max(1 − Q_o²/(k_c h_m²), 0)`.
    pub fn scouring(&self, q_o: f64, h_m: f64) -> f64 {
        if h_m <= 0.0 {
            return 0.0;
        }
        (1.0 - q_o * q_o / (self.k_c * h_m * h_m)).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The profile's mean over the mixture layer must equal ρ_m: that is how k_ρ is defined.
    /// Checked by the trapezoid rule on 20 000 cells (error O(h²) ≪ 1e-3 kg/m³) in both
    /// branches of the slope formula.
    #[test]
    fn profile_mean_is_the_mixture_density() {
        let p = HopperParams::default();
        let (h_s, h_m) = (2.0, 6.0);
        for rho_m in [1030.0, 1200.0, 1500.0, 1600.0, 1900.0] {
            let k = p.k_rho(rho_m, h_m);
            let n = 20_000;
            let dh = h_m / n as f64;
            let mean: f64 = (0..n)
                .map(|i| {
                    let a = p.profile_density(k, h_s + i as f64 * dh, h_s);
                    let b = p.profile_density(k, h_s + (i + 1) as f64 * dh, h_s);
                    0.5 * (a + b) * dh
                })
                .sum::<f64>()
                / h_m;
            assert!((mean - rho_m).abs() < 1e-3, "rho_m {rho_m}: mean {mean}");
        }
    }

    #[test]
    fn overflow_laws_and_their_switch() {
        let mut p = HopperParams::default();
        assert_eq!(p.overflow_rate(5.0, 6.0), 0.0);
        p.regime = OverflowRegime::Free;
        assert!((p.overflow_rate(7.0, 6.0) - p.k_o).abs() < 1e-12);
        p.regime = OverflowRegime::Full;
        assert!((p.overflow_rate(7.0, 6.0) - p.k_o_full * (2.0 * p.g).sqrt()).abs() < 1e-12);
        p.regime = OverflowRegime::Limiting;
        // Below the crossover head k'_o √(2g) / k_o the weir limits; above it the pipe does.
        let h_x = p.k_o_full * (2.0 * p.g).sqrt() / p.k_o;
        let free = p.k_o * (0.5 * h_x).powf(1.5);
        assert!((p.overflow_rate(0.5 * h_x, 0.0) - free).abs() < 1e-12);
        let full = p.k_o_full * (2.0 * p.g * 2.0 * h_x).sqrt();
        assert!((p.overflow_rate(2.0 * h_x, 0.0) - full).abs() < 1e-12);
    }

    #[test]
    fn settling_and_scouring_limits() {
        let p = HopperParams::default();
        assert_eq!(p.settling(p.rho_w), 0.0);
        assert!(p.settling(1200.0) > p.settling(1100.0));
        assert_eq!(p.scouring(0.0, 3.0), 1.0);
        assert_eq!(p.scouring(100.0, 1.0), 0.0);
        assert!(p.validate().is_ok());
        let bad = HopperParams { rho_s: 900.0, ..p };
        assert!(bad.validate().is_err());
    }
}
