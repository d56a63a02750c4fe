//! One recorded run of each partition, step by step: what `mpf.rrd` shows.

use super::{Scale, TableConfig};
use crate::error::Result;
use crate::mpf::MpfConfig;
use crate::radar::{Partition, RadarConfig, RadarState, RunTrace, trace_partition};
use pf_core::mc::stream_rng;
use serde::{Deserialize, Serialize};

/// Which runs to record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TracesConfig {
    /// The scenario (Tables II and III's).
    pub radar: RadarConfig,
    /// The partitions to run, in order.
    pub partitions: Vec<Partition>,
    /// Particles of every run.
    pub particles: usize,
    /// Seed: every partition sees the measurements of stream `(seed, 7)`.
    pub seed: u64,
}

impl Default for TracesConfig {
    fn default() -> Self {
        Self::at_scale(Scale::Full)
    }
}

impl TracesConfig {
    /// The tables' scenario at `scale`, with 100 particles at `Quick` and 500 otherwise
    /// (enough to see the cloud, few enough to record).
    pub fn at_scale(scale: Scale) -> Self {
        let table = TableConfig::at_scale(scale);
        Self {
            radar: table.radar,
            partitions: Partition::paper(),
            particles: if scale == Scale::Quick { 100 } else { 500 },
            seed: table.seed,
        }
    }
}

/// The true trajectory and one traced run per partition.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TracesResult {
    /// The true states, one per step.
    pub truth: Vec<RadarState>,
    /// `(partition name, its run)`, in the configuration's order.
    pub runs: Vec<(String, RunTrace)>,
}

/// Run and trace every partition on the same measurements.
///
/// # Errors
/// An invalid scenario or particle count, or the first failing run.
pub fn traces(cfg: &TracesConfig) -> Result<TracesResult> {
    cfg.radar.validate()?;
    let mpf = MpfConfig::new(cfg.particles);
    mpf.validate()?;
    let truth = cfg.radar.truth();
    let mut runs = Vec::with_capacity(cfg.partitions.len());
    for part in &cfg.partitions {
        // The measurement draws come first on the stream, so every partition sees the same.
        let mut rng = stream_rng(cfg.seed, 7);
        let ys = cfg.radar.measure(&truth, &mut rng);
        let (_, trace) = trace_partition(part, &cfg.radar, mpf, &truth, &ys, &mut rng)?;
        runs.push((part.name(), trace));
    }
    Ok(TracesResult { truth, runs })
}
