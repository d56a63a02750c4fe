//! One plain function per figure and table: config struct → result struct, raw numbers.
//!
//! | function | paper |
//! |---|---|
//! | [`ratio()`] | Figs. 1 and 2: `N(k)/N_PF` for `m = 3…9`, `n = 2` |
//! | [`fig3()`] | Fig. 3: predicted against measured time for every partition |
//! | [`table2`] | Table II: constant time (and RMSE over time per partition) |
//! | [`table3`] | Table III: constant velocity RMSE |
//! | [`calibrate`](crate::calibrate::calibrate) | Section IV-A: `flop_ns`, `c1`, `c2`, `c3` |
//! | [`traces()`] | one recorded run per partition, step by step (for recordings) |
//! | [`bench::RadarBench`] | the standard PF on eq. (13), timed by `pf-viz bench filter` |
//!
//! Each takes `&XConfig` (with `XConfig::at_scale` giving the preset of a
//! [`Scale`]) and returns `Result<XResult>`; Tables II and III share [`TableConfig`].

pub mod bench;
mod fig3;
mod ratio;
mod tables;
mod traces;

pub use fig3::{
    Fig3Config, Fig3Result, Fig3Row, alg1_matrices, fig3, fig3_calibrated, fig3_with,
    partition_stage_times, predicted_time_s,
};
pub use ratio::{RatioConfig, RatioCurve, RatioResult, ratio};
pub use tables::{
    ModelPrediction, PartitionTerms, RmseCurve, TableConfig, TableReport, TableResult, TableRow,
    model_prediction, paper_table2, paper_table3, table2, table2_with, table3,
};
pub use traces::{TracesConfig, TracesResult, traces};

/// The experiments' size presets, shared with the other paper crates.
pub use pf_core::mc::Scale;
