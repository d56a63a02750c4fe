//! One plain function per figure and table: config struct → result struct, raw numbers.
//!
//! | function | paper |
//! |---|---|
//! | [`ratio`] | Figs. 1 and 2: `N(k)/N_PF` for `m = 3…9`, `n = 2` |
//! | [`fig3`] | Fig. 3: predicted against measured time for every partition |
//! | [`table2`] | Table II: constant time (and RMSE over time per partition) |
//! | [`table3`] | Table III: constant velocity RMSE |
//! | [`calibrate`](crate::calibrate::calibrate) | Section IV-A: `flop_ns`, `c1`, `c2`, `c3` |

mod fig3;
mod ratio;
mod tables;

pub use fig3::{Fig3Config, Fig3Result, Fig3Row, fig3};
pub use ratio::{RatioConfig, RatioCurve, RatioResult, ratio};
pub use tables::{
    RmseCurve, TableConfig, TableReport, TableResult, TableRow, paper_table2, paper_table3, table2,
    table3,
};

use serde::{Deserialize, Serialize};

/// How big an experiment is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Scale {
    /// Seconds: for tests and smoke runs.
    Quick,
    /// A minute or less.
    #[default]
    Default,
    /// The paper's sizes.
    Full,
}
