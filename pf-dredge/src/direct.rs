//! Direct computation of the overflow, Section V-A, eqs. (15)–(16): the reference the paper
//! uses on real data.
//!
//! ```text
//! Q̄_o,k = Q_i,k − (V_t,k+1 − V_t,k)/T_s                          (15)
//! ρ̄_o,k = (Q_i,k ρ_i,k − (m_t,k+1 − m_t,k)/T_s) / Q̄_o,k          (16)
//! ```
//! `V_t` and `m_t` are first smoothed by an anti-causal (zero-phase, forward–backward)
//! first-order low-pass filter with a 0.001 Hz cut-off. The forward difference leaves the
//! last sample undefined, and (16) is undefined where `Q̄_o` is too small to divide by: those
//! entries are `None` (`null` in JSON), never NaN.

use crate::data::DredgeData;
use crate::error::{DredgeError, Result};
use pf_core::params::{non_negative, positive};
use serde::{Deserialize, Serialize};

/// Settings of the direct computation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DirectConfig {
    /// Cut-off of the first-order low-pass applied forward and backward (Hz); `None` uses the
    /// raw signals. The paper's 0.001 Hz.
    pub cutoff_hz: Option<f64>,
    /// `ρ̄_o` is left undefined where `|Q̄_o|` is below this (m³/s): the division in (16)
    /// would only amplify noise.
    pub min_q_o: f64,
}

impl Default for DirectConfig {
    fn default() -> Self {
        DirectConfig {
            cutoff_hz: Some(0.001),
            min_q_o: 0.5,
        }
    }
}

impl DirectConfig {
    /// Check the settings.
    ///
    /// # Errors
    /// A non-positive cut-off or a negative `min_q_o`.
    pub fn validate(&self) -> Result<()> {
        if let Some(f) = self.cutoff_hz {
            positive("cutoff_hz", f)?;
        }
        non_negative("min_q_o", self.min_q_o)?;
        Ok(())
    }
}

/// `Q̄_o` and `ρ̄_o` per sample.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DirectEstimate {
    /// `Q̄_o,k` (m³/s); `None` at the last sample.
    #[serde(rename = "Q_o")]
    pub q_o: Vec<Option<f64>>,
    /// `ρ̄_o,k` (kg/m³); `None` at the last sample and where `|Q̄_o,k| < min_q_o`.
    #[serde(rename = "rho_o")]
    pub rho_o: Vec<Option<f64>>,
}

/// The zero-phase first-order low-pass: `y_k = a_k y_{k−1} + (1 − a_k) x_k` with
/// `a_k = exp(−2π f_c (t_k − t_{k−1}))`, run forward and then backward, each pass started at
/// its first sample (no start-up transient). The magnitude response is that of the
/// first-order filter squared, with no phase shift.
///
/// # Errors
/// Lengths that differ, or a non-positive cut-off.
pub fn zero_phase_lowpass(t: &[f64], x: &[f64], cutoff_hz: f64) -> Result<Vec<f64>> {
    positive("cutoff_hz", cutoff_hz)?;
    if t.len() != x.len() {
        return Err(DredgeError::ColumnLength {
            column: "signal to filter",
            expected: t.len(),
            got: x.len(),
        });
    }
    let mut y = x.to_vec();
    let w = 2.0 * std::f64::consts::PI * cutoff_hz;
    for k in 1..y.len() {
        let a = (-w * (t[k] - t[k - 1])).exp();
        y[k] = a * y[k - 1] + (1.0 - a) * y[k];
    }
    for k in (0..y.len().saturating_sub(1)).rev() {
        let a = (-w * (t[k + 1] - t[k])).exp();
        y[k] = a * y[k + 1] + (1.0 - a) * y[k];
    }
    Ok(y)
}

/// Fill missing values by linear interpolation in time (held constant before the first and
/// after the last known value). `None` if nothing is known.
fn interpolate(t: &[f64], x: &[Option<f64>]) -> Option<Vec<f64>> {
    let known: Vec<usize> = (0..x.len()).filter(|&k| x[k].is_some()).collect();
    let (&first, &last) = (known.first()?, known.last()?);
    let mut out = vec![0.0; x.len()];
    for (k, o) in out.iter_mut().enumerate() {
        *o = if k <= first {
            x[first].unwrap_or_default()
        } else if k >= last {
            x[last].unwrap_or_default()
        } else {
            // Neighbours among the known indices.
            let j = known.partition_point(|&i| i <= k);
            let (a, b) = (known[j - 1], known[j]);
            let (xa, xb) = (x[a].unwrap_or_default(), x[b].unwrap_or_default());
            if a == k {
                xa
            } else {
                xa + (xb - xa) * (t[k] - t[a]) / (t[b] - t[a])
            }
        };
    }
    Some(out)
}

/// Hold the last known value (zero-order hold), back-filling before the first one.
pub(crate) fn hold(x: &[Option<f64>]) -> Option<Vec<f64>> {
    let first = x.iter().flatten().next().copied()?;
    let mut last = first;
    Some(
        x.iter()
            .map(|v| {
                if let Some(v) = v {
                    last = *v;
                }
                last
            })
            .collect(),
    )
}

/// The direct computation (15)–(16) on a data set.
///
/// # Errors
/// Invalid data ([`DredgeData::validate`], at least 2 samples) or settings.
pub fn direct_computation(data: &DredgeData, cfg: &DirectConfig) -> Result<DirectEstimate> {
    cfg.validate()?;
    data.validate(2)?;
    let n = data.len();
    // validate() guarantees a complete first sample, so every column has a known value.
    let missing = |column| DredgeError::MissingFirstValue { column };
    let mut v = interpolate(&data.t, &data.v_t).ok_or(missing("V_t"))?;
    let mut m = interpolate(&data.t, &data.m_t).ok_or(missing("m_t"))?;
    let q_i = hold(&data.q_i).ok_or(missing("Q_i"))?;
    let rho_i = hold(&data.rho_i).ok_or(missing("rho_i"))?;
    if let Some(fc) = cfg.cutoff_hz {
        v = zero_phase_lowpass(&data.t, &v, fc)?;
        m = zero_phase_lowpass(&data.t, &m, fc)?;
    }
    let mut q_o = vec![None; n];
    let mut rho_o = vec![None; n];
    for k in 0..n - 1 {
        let t_s = data.t[k + 1] - data.t[k];
        let q = q_i[k] - (v[k + 1] - v[k]) / t_s;
        q_o[k] = Some(q);
        if q.abs() >= cfg.min_q_o.max(f64::MIN_POSITIVE) {
            rho_o[k] = Some((q_i[k] * rho_i[k] - (m[k + 1] - m[k]) / t_s) / q);
        }
    }
    Ok(DirectEstimate { q_o, rho_o })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lowpass_keeps_constants_and_lines_away_from_the_ends_and_has_no_lag() {
        let t: Vec<f64> = (0..2000).map(|k| 5.0 * k as f64).collect();
        let c = zero_phase_lowpass(&t, &vec![3.0; 2000], 0.001).unwrap();
        assert!(c.iter().all(|&y| (y - 3.0).abs() < 1e-12));
        // A symmetric pulse stays centred: zero phase means no lag.
        let mut x = vec![0.0; 2001];
        x[1000] = 1.0;
        let t: Vec<f64> = (0..2001).map(|k| 5.0 * k as f64).collect();
        let y = zero_phase_lowpass(&t, &x, 0.001).unwrap();
        let peak = (0..y.len()).max_by(|&a, &b| y[a].total_cmp(&y[b])).unwrap();
        assert_eq!(peak, 1000);
        assert!((y[990] - y[1010]).abs() < 1e-12);
    }

    #[test]
    fn interpolation_and_hold() {
        let t = [0.0, 1.0, 2.0, 4.0];
        let x = [None, Some(1.0), None, Some(4.0)];
        assert_eq!(interpolate(&t, &x).unwrap(), vec![1.0, 1.0, 2.0, 4.0]);
        assert_eq!(hold(&x).unwrap(), vec![1.0, 1.0, 1.0, 4.0]);
        assert!(interpolate(&t, &[None; 4]).is_none());
    }
}
