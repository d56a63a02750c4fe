//! Two measurements of Fig. 5's `ρ_o` track that explain its residual: the delay by which the
//! estimate follows the simulated density, and the residual while that density is still flat.

use super::Fig56Result;
use pf_core::mc::mean_and_sd;
use serde::{Deserialize, Serialize};

/// Samples per window of [`flat_stretch`]'s local spread (150 s at `T_s` = 5 s).
pub const FLAT_WINDOW: usize = 30;

/// The `ρ_o` residual std (kg/m³) that the measurement noise alone leaves in the linearised
/// filter with the paper's noise levels (crate README).
pub const NOISE_FLOOR: f64 = 7.2;

/// The delay (s) by which `estimate` best follows `truth`: the shift, up to a fifth of the
/// record, that minimises their mean squared difference. 0 for records too short to shift.
pub fn best_lag(t: &[f64], truth: &[f64], estimate: &[f64]) -> f64 {
    let n = truth.len().min(estimate.len()).min(t.len());
    let mse = |s: usize| {
        let d = truth[..n - s]
            .iter()
            .zip(&estimate[s..n])
            .map(|(a, b)| (a - b).powi(2));
        d.sum::<f64>() / (n - s) as f64
    };
    let best = (0..n / 5)
        .min_by(|&a, &b| mse(a).total_cmp(&mse(b)))
        .unwrap_or(0);
    if best == 0 { 0.0 } else { t[best] - t[0] }
}

/// The residual where the simulated density has not yet left the value it starts phase 3
/// at: what the filter leaves on a signal it can follow, against [`NOISE_FLOOR`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FlatStretch {
    /// Phase 3 has no samples.
    Empty,
    /// The density moves (by 1 kg/m³ or more) within fewer than two windows of samples.
    TooShort {
        /// The starting density (kg/m³).
        start: f64,
        /// Samples before it moves.
        samples: usize,
    },
    /// Measured on the flat start.
    Measured {
        /// The flat density (kg/m³).
        start: f64,
        /// First and last time of the stretch (s).
        from: f64,
        /// Last time of the stretch (s).
        to: f64,
        /// The stretch's share of phase 3's samples.
        share: f64,
        /// Residual std over the stretch (kg/m³).
        std: f64,
        /// Least and largest residual std over [`FLAT_WINDOW`]-sample windows (kg/m³).
        window_range: [f64; 2],
        /// Whether `std` is within twice [`NOISE_FLOOR`]: the measurement noise explains it.
        at_noise_floor: bool,
    },
}

/// Measure the [`FlatStretch`] of a phase-3 track: times `t`, simulated `truth`, estimate
/// `hat`.
pub fn flat_stretch(t: &[f64], truth: &[f64], hat: &[f64]) -> FlatStretch {
    let len = t.len().min(truth.len()).min(hat.len());
    let Some(&start) = truth.first() else {
        return FlatStretch::Empty;
    };
    let n = truth[..len]
        .iter()
        .take_while(|&&r| (r - start).abs() < 1.0)
        .count();
    if n < 2 * FLAT_WINDOW {
        return FlatStretch::TooShort { start, samples: n };
    }
    let resid: Vec<f64> = truth[..n].iter().zip(hat).map(|(a, b)| b - a).collect();
    let window_range = resid
        .chunks_exact(FLAT_WINDOW)
        .map(|w| mean_and_sd(w).1)
        .fold([f64::INFINITY, f64::NEG_INFINITY], |[l, h], w| {
            [l.min(w), h.max(w)]
        });
    let std = mean_and_sd(&resid).1;
    FlatStretch::Measured {
        start,
        from: t[0],
        to: t[n - 1],
        share: n as f64 / truth.len() as f64,
        std,
        window_range,
        at_noise_floor: std <= 2.0 * NOISE_FLOOR,
    }
}

impl Fig56Result {
    /// The delay (s) by which the `ρ̂_o` of Fig. 5 best follows the simulated `ρ_o`.
    pub fn rho_o_lag(&self) -> f64 {
        best_lag(&self.t, &self.rho_o_true, &self.rho_o_hat)
    }

    /// The `ρ_o` residual on the flat start of phase 3.
    pub fn rho_o_flat_stretch(&self) -> FlatStretch {
        flat_stretch(&self.t, &self.rho_o_true, &self.rho_o_hat)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ramp and the same ramp 7 samples late: the lag is 7 sample intervals.
    #[test]
    fn best_lag_finds_a_known_delay() {
        let t: Vec<f64> = (0..200).map(|k| 5.0 * k as f64).collect();
        let truth: Vec<f64> = (0..200).map(|k| (k as f64 / 10.0).sin()).collect();
        let late: Vec<f64> = (0..200).map(|k| truth[k.max(7) - 7]).collect();
        assert_eq!(best_lag(&t, &truth, &late), 35.0);
        assert_eq!(best_lag(&t, &truth, &truth), 0.0);
        assert_eq!(best_lag(&[], &[], &[]), 0.0);
    }

    /// The noise floor is measured on the flat start only: 60 flat samples with residuals
    /// ±1 (std ≈ 1.008), then a ramp whose large residuals must not count.
    #[test]
    fn the_flat_stretch_is_measured_before_the_density_moves() {
        let t: Vec<f64> = (0..100).map(|k| 5.0 * k as f64).collect();
        let truth: Vec<f64> = (0..100)
            .map(|k| {
                if k < 60 {
                    1025.0
                } else {
                    1025.0 + 10.0 * (k - 59) as f64
                }
            })
            .collect();
        let hat: Vec<f64> = (0..100)
            .map(|k| {
                if k < 60 {
                    1025.0 + if k % 2 == 0 { 1.0 } else { -1.0 }
                } else {
                    1025.0
                }
            })
            .collect();
        let FlatStretch::Measured {
            start,
            from,
            to,
            share,
            std,
            window_range,
            at_noise_floor,
        } = flat_stretch(&t, &truth, &hat)
        else {
            panic!("a flat start of 60 samples is measured");
        };
        assert_eq!((start, from, to, share), (1025.0, 0.0, 295.0, 0.6));
        // ±1 alternating: sd = √(60/59) over the stretch, √(30/29) in each window.
        assert!((std - (60.0f64 / 59.0).sqrt()).abs() < 1e-12, "{std}");
        for w in window_range {
            assert!((w - (30.0f64 / 29.0).sqrt()).abs() < 1e-12, "{w}");
        }
        assert!(at_noise_floor);
        // Too short a flat start says so rather than measuring noise on a ramp.
        assert_eq!(
            flat_stretch(&t[..40], &truth[20..60], &hat[..40]),
            FlatStretch::TooShort {
                start: 1025.0,
                samples: 40
            }
        );
        assert_eq!(flat_stretch(&[], &[], &[]), FlatStretch::Empty);
        // A residual 30 times larger is far above the linearised filter's floor.
        let noisy: Vec<f64> = hat
            .iter()
            .zip(&truth)
            .map(|(h, r)| r + 30.0 * (h - r))
            .collect();
        let FlatStretch::Measured { at_noise_floor, .. } = flat_stretch(&t, &truth, &noisy) else {
            panic!("measured");
        };
        assert!(!at_noise_floor);
    }
}
