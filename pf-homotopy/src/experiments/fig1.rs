//! Fig. 1: the scenario geometry.

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::model::ScenarioConfig;

/// Observer trajectory and nominal (noise-free) target trajectory at the sampling instants.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScenarioGeometry {
    /// Times `(k − 1)T`, s.
    pub time: Vec<f64>,
    /// Observer positions ρ_k.
    pub observer: Vec<[f64; 2]>,
    /// Nominal target positions.
    pub target: Vec<[f64; 2]>,
    /// Sampling instants at which the observer's turn starts and ends.
    pub turn: [usize; 2],
}

/// Fig. 1 for a scenario.
///
/// # Errors
/// An invalid scenario.
pub fn scenario_geometry(scenario: &ScenarioConfig) -> Result<ScenarioGeometry> {
    scenario.validate()?;
    Ok(ScenarioGeometry {
        time: (0..scenario.n_samples)
            .map(|k| k as f64 * scenario.t)
            .collect(),
        observer: scenario.observer_track().iter().map(|o| o.pos).collect(),
        target: scenario
            .nominal_target()
            .iter()
            .map(|x| [x[0], x[1]])
            .collect(),
        turn: [scenario.turn_start, scenario.turn_end],
    })
}
