//! The radar benchmark of `pf-viz bench filter --model radar`: Karlsson et al.'s model
//! (13) with every state in the particle filter (`PPPPPP`), bootstrap proposal, systematic
//! resampling at every step, on pf-core's batch engine.
//!
//! The scenario is [`RadarConfig::default`] (its true trajectory, its `Q`, `R` and prior);
//! the measurements are simulated from stream `(seed, 0)` or read from a CSV file with
//! header `range,azimuth` ([`parse_observations_csv`]), so that other implementations can
//! run on the same data.

use crate::error::{MpfError, Result};
use crate::mpf::{MpfConfig, SharedMpf};
use crate::radar::{Partition, RadarConfig, RadarObs, RangeAzimuth};
use pf_core::filter::{BatchFilter, Bootstrap};
use pf_core::mc::{Par, stream_rng};
use pf_core::params::ParamError;

/// One benchmark: the filter and its observations. [`run`](Self::run) runs the filter from
/// the start over all of them.
pub struct RadarBench {
    filter: BatchFilter<SharedMpf<6, 0, 2, RangeAzimuth>, Bootstrap>,
    ys: Vec<Option<RadarObs>>,
}

impl std::fmt::Debug for RadarBench {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RadarBench")
            .field("steps", &self.ys.len())
            .finish_non_exhaustive()
    }
}

impl RadarBench {
    /// `steps` measurements of the default scenario's true trajectory, simulated from
    /// stream `(seed, 0)`, and a filter of `particles` particles whose streams come from
    /// `seed`.
    ///
    /// # Errors
    /// Fewer than two steps, no particles, or more than the machine holds.
    pub fn new(particles: usize, steps: usize, seed: u64) -> Result<Self> {
        let cfg = RadarConfig {
            n_steps: steps,
            ..RadarConfig::default()
        };
        cfg.validate()?;
        let truth = cfg.truth();
        let ys = cfg.measure(&truth, &mut stream_rng(seed, 0));
        Self::with_observations(ys, particles, seed)
    }

    /// The filter on given measurements `ys` (`None` = missing) of the default scenario.
    ///
    /// # Errors
    /// No observation, a non-finite one, no particles, or more than the machine holds.
    pub fn with_observations(
        ys: Vec<Option<RadarObs>>,
        particles: usize,
        seed: u64,
    ) -> Result<Self> {
        if ys.is_empty() {
            return Err(MpfError::TooFewObservations { got: 0, need: 1 });
        }
        crate::model::check_observations(&ys)?;
        let mpf = MpfConfig::new(particles);
        mpf.validate()?;
        let part: Partition = "PPPPPP".parse()?;
        let model = SharedMpf::new(part.model::<6, 0>(&RadarConfig::default())?)?;
        let filter = BatchFilter::new(model, mpf.batch(seed, Par::Rayon))?;
        Ok(Self { filter, ys })
    }

    /// Run pf-core's `simd` copy of the kernels (the same estimate, at that copy's speed).
    pub fn set_simd(&mut self, simd: pf_core::simd::Simd) {
        self.filter.set_simd(simd);
    }

    /// The observations.
    pub fn observations(&self) -> &[Option<RadarObs>] {
        &self.ys
    }

    /// One full run from the start (the same random streams every time), on the caller's
    /// rayon pool; returns the log-likelihood estimate `log p̂(y_{0:T})`.
    ///
    /// # Errors
    /// From the engine (all weights zero).
    pub fn run(&mut self) -> Result<f64> {
        self.filter.reset();
        Ok(self.filter.run(&self.ys)?.log_lik)
    }
}

/// Measurements from a CSV text with the header `range,azimuth` (one row per step; a row
/// whose two cells are empty is a missing measurement).
///
/// # Errors
/// A wrong header, a row without two cells, one cell empty and not the other, or a cell
/// that is not a finite number; the error names the line (counting from 1).
pub fn parse_observations_csv(text: &str) -> Result<Vec<Option<RadarObs>>> {
    let bad = |line: usize, reason: &'static str| {
        MpfError::Param(ParamError {
            name: "observations CSV line",
            value: line as f64,
            reason,
        })
    };
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, h)) if h.trim().replace(' ', "") == "range,azimuth" => {}
        _ => return Err(bad(1, "the header must be `range,azimuth`")),
    }
    let mut ys = Vec::new();
    for (i, line) in lines {
        let n = i + 1;
        let line = line.trim_end_matches('\r');
        if line.trim().is_empty() {
            continue;
        }
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let [r, a] = cells[..] else {
            return Err(bad(n, "expected two cells, range and azimuth"));
        };
        let y = match (r.is_empty(), a.is_empty()) {
            (true, true) => None,
            (false, false) => {
                let num = |s: &str| {
                    s.parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or(bad(n, "a cell is not a finite number"))
                };
                Some(RadarObs::new(num(r)?, num(a)?))
            }
            _ => return Err(bad(n, "range and azimuth must both be given or both empty")),
        };
        ys.push(y);
    }
    Ok(ys)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_reads_values_and_gaps_and_names_the_bad_line() {
        let ys = parse_observations_csv("range,azimuth\n2500.5,0.64\n,\n2490,-0.1\n").unwrap();
        assert_eq!(ys.len(), 3);
        assert_eq!(ys[0], Some(RadarObs::new(2500.5, 0.64)));
        assert_eq!(ys[1], None);
        assert_eq!(ys[2], Some(RadarObs::new(2490.0, -0.1)));
        let line = |e: MpfError| match e {
            MpfError::Param(p) => p.value,
            e => panic!("{e}"),
        };
        let e = parse_observations_csv("range,azimuth\n1,2\n3,x\n").unwrap_err();
        assert_eq!(line(e), 3.0);
        let e = parse_observations_csv("range,azimuth\n1,\n").unwrap_err();
        assert_eq!(line(e), 2.0);
        let e = parse_observations_csv("range,azimuth\n1,2,3\n").unwrap_err();
        assert_eq!(line(e), 2.0);
        let e = parse_observations_csv("r,a\n1,2\n").unwrap_err();
        assert_eq!(line(e), 1.0);
        let e = parse_observations_csv("range,azimuth\nNaN,2\n").unwrap_err();
        assert_eq!(line(e), 2.0);
    }
}
