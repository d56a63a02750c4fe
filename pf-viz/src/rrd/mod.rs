//! Rerun recordings (`.rrd`), for scrubbing through a run in the Rerun viewer.
//!
//! Compiled only with the `rrd` feature. Every recording is written atomically through
//! [`save_rrd`]; the loggers in the submodules map plain result data to Rerun archetypes on a
//! `step` timeline and send a blueprint, so the viewer opens on a meaningful layout.
//!
//! | module | recording |
//! |---|---|
//! | [`genealogy`] | particle genealogy and ESS trace |
//! | [`smooth`] | `smooth.rrd`: genealogy on `step`, SEM chains on `iteration` |
//! | [`mpf`] | `mpf.rrd`: particle clouds and KF means per partition on `step` |
//! | [`homotopy`] | `homotopy.rrd`: ellipses on `lambda`; scenario and estimates on `step` |
//! | [`dredge`] | `dredge.rrd`: signals and the (Q_o, ρ_o) cloud on `time` |
//! | [`epf`] | `epf.rrd`: detections, clouds, associations, gates on `frame` |
//! | [`layout`] | the blueprint each recording opens on, with its views' bounds, time ranges and legends |
//!
//! Entity paths start with the paper's name (`smooth/genealogy/lineage_3`,
//! `homotopy/ellipse/lambda`).

pub mod dredge;
pub mod epf;
pub mod genealogy;
pub mod homotopy;
pub mod layout;
pub mod mpf;
pub mod smooth;

use std::path::Path;

use rerun::{RecordingStream, RecordingStreamBuilder};

use crate::error::{Result, VizError};
use crate::io::write_atomic_path;

/// The application id of every pf-viz recording.
pub const APP_ID: &str = "pf";

/// The filter's time index `k`.
pub const STEP: &str = "step";
/// The homotopy parameter λ ∈ [0, 1].
pub const LAMBDA: &str = "lambda";
/// An EM / SEM iteration.
pub const ITERATION: &str = "iteration";
/// Physical time in seconds.
pub const TIME: &str = "time";
/// A video frame index.
pub const FRAME: &str = "frame";

/// Map a Rerun error to [`VizError::Rrd`] for the recording at `path`.
pub fn rrd_err<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> VizError + '_ {
    move |e| VizError::Rrd {
        path: path.to_owned(),
        message: e.to_string(),
    }
}

/// Record to the `.rrd` file `path`, atomically: `log` writes into a recording saved to a
/// temporary sibling, which is flushed, closed and renamed over `path` only if `log`
/// succeeded.
///
/// # Errors
/// The logger's error, or [`VizError::Rrd`] / [`VizError::Io`] naming `path`.
pub fn save_rrd<F>(path: &Path, recording_name: &str, log: F) -> Result<()>
where
    F: FnOnce(&RecordingStream, &Path) -> Result<()>,
{
    write_atomic_path(path, |tmp| {
        let rec = RecordingStreamBuilder::new(APP_ID)
            .recording_name(recording_name)
            .default_enabled(true)
            .save(tmp)
            .map_err(rrd_err(path))?;
        if !rec.is_enabled() {
            return Err(VizError::Rrd {
                path: path.to_owned(),
                message: "recording is disabled (is the RERUN environment variable set to off?)"
                    .into(),
            });
        }
        log(&rec, path)?;
        rec.flush_blocking().map_err(rrd_err(path))?;
        // Dropping the last handle joins the writer thread, which writes the footer.
        drop(rec);
        Ok(())
    })
}
