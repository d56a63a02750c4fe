//! One plain function per figure of Section V (and one beyond the paper): config struct in,
//! result struct of raw numbers out, `XConfig::at_scale` giving the preset of a [`Scale`].
//! Each is deterministic for its seed: the cycle's inputs and measurement noise use the
//! streams `(seed, 0)` and `(seed, 1)`, filter run `r` the stream `(seed + 0x5eedf117, r)`
//! ([`pf_core::mc::stream_rng`]).
//!
//! | function | paper |
//! |---|---|
//! | [`cycle()`] | Figs. 3–4: inputs, loading phases |
//! | [`fig5_6()`] | Figs. 5–6: simulated against estimated `Q_o`, `ρ_o` in phase 3; residual histograms |
//! | [`fig7()`] | Fig. 7: PF against the direct computation (15)–(16) |
//! | [`fig8()`] | Fig. 8: min–max band and mean of 25 runs on the same data |
//! | [`n_sweep()`] | beyond the paper: residual std against `N` |
//! | [`best_lag()`], [`flat_stretch()`] | Fig. 5's `ρ_o`: the estimate's delay, and its residual on the flat start |
//! | [`consistency()`], [`fig5_alignment()`] | beyond the paper: the filter on data from its own model (13) (NEES), and the estimate against the truth of `k` and `k − 1` |

mod consistency;
mod cycle;
mod fig5_6;
mod fig7;
mod fig8;
mod lag;
mod n_sweep;
mod online;

pub use consistency::{
    Alignment, ConsistencyConfig, ConsistencyResult, ConsistencyRun, ConsistencySignal, MeanSe,
    Model13Data, MomentRecorder, consistency, fig5_alignment, model13_data,
};
pub use cycle::{CycleConfig, cycle};
pub use fig5_6::{Fig56Config, Fig56Result, PaperResiduals, ResidualReport, fig5_6};
pub use fig7::{Fig7Config, Fig7Result, fig7};
pub use fig8::{Band, Fig8Config, Fig8Result, fig8};
pub use lag::{FLAT_WINDOW, FlatStretch, NOISE_FLOOR, best_lag, flat_stretch};
pub use n_sweep::{NSweepConfig, NSweepResult, NSweepRow, n_sweep};
pub use online::{Cloud, OnlineConfig, OnlineResult, online};
/// Fig. 6's histograms are pf-core's (re-exported where they used to be defined).
pub use pf_core::metrics::Histogram;

/// The experiments' size presets, shared with the other paper crates.
pub use pf_core::mc::Scale;

/// The stream seed of filter runs, kept apart from the simulation's streams.
pub(crate) fn filter_seed(seed: u64) -> u64 {
    seed.wrapping_add(0x5eed_f117)
}

/// Indices of phase-3 samples of a cycle.
pub(crate) fn phase3(c: &crate::simulator::Cycle) -> crate::Result<std::ops::Range<usize>> {
    let start = c
        .phase3_start
        .ok_or(crate::DredgeError::PhaseNotReached { phase: 3 })?;
    Ok(start..c.len())
}
