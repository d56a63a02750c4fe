//! The crate's error type: every variant says what was wrong and where.

use pf_core::CoreError;
use pf_core::params::ParamError;
use thiserror::Error;

/// Errors of pf-epf. Input errors name the row, target or frame at fault.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum EpfError {
    /// An engine error (filter degeneracy, bad filter configuration, metric input).
    #[error(transparent)]
    Core(#[from] CoreError),
    /// A parameter is outside its valid range (see [`pf_core::params`]).
    #[error(transparent)]
    Param(#[from] ParamError),
    /// A detection or init row holds a NaN or infinite coordinate.
    #[error("non-finite {what} {value} in {file} row {row}")]
    NonFiniteData {
        /// `"detections"` or `"init"`.
        file: &'static str,
        /// Row index (0-based, header excluded).
        row: usize,
        /// Which column.
        what: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A frame beyond ±2⁵³: frames are times, used in floating point and in differences,
    /// and are kept where both are exact.
    #[error("frame {frame} in {file} row {row} is beyond ±2^53")]
    FrameOutOfRange {
        /// `"detections"` or `"init"`.
        file: &'static str,
        /// Row index (0-based, header excluded).
        row: usize,
        /// The offending frame.
        frame: i64,
    },
    /// Frames must not decrease from one row to the next.
    #[error("frame goes backwards in {file} row {row}: {frame} after {previous}")]
    FrameBackwards {
        /// `"detections"` or `"init"`.
        file: &'static str,
        /// Row index (0-based, header excluded).
        row: usize,
        /// The frame of this row.
        frame: i64,
        /// The frame of the row before.
        previous: i64,
    },
    /// A target's init has fewer than the two frames the energies need.
    #[error("target {target} has {frames} init frame(s); the energies need at least 2")]
    TooFewInitFrames {
        /// Target id.
        target: i64,
        /// Number of distinct init frames given.
        frames: usize,
    },
    /// A target has two init rows for the same frame.
    #[error("target {target} has two init rows for frame {frame}")]
    DuplicateInitFrame {
        /// Target id.
        target: i64,
        /// The repeated frame.
        frame: i64,
    },
    /// The init file has no target at all.
    #[error("the init data hold no target")]
    NoTargets,
    /// A frame was asked for that the detections do not have after the init frames.
    #[error(
        "frame {frame} is not a tracked frame (tracked frames: {})",
        list_frames(tracked)
    )]
    UnknownFrame {
        /// The requested frame.
        frame: i64,
        /// The tracked frames, in order (sparse in some scenarios, so a range would mislead).
        tracked: Vec<i64>,
    },
    /// No detection lies after the init frames, so there is nothing to track.
    #[error("no detection lies after the last init frame {last_init}")]
    NothingToTrack {
        /// The last init frame over all targets.
        last_init: i64,
    },
}

/// Result alias for pf-epf.
pub type Result<T, E = EpfError> = std::result::Result<T, E>;

/// The frames of an error message: all of them when few, else the first and last few.
fn list_frames(frames: &[i64]) -> String {
    let show = |f: &[i64]| f.iter().map(i64::to_string).collect::<Vec<_>>().join(", ");
    match frames.len() {
        0 => "none".into(),
        n if n <= 12 => show(frames),
        n => format!(
            "{}, …, {} ({n} frames)",
            show(&frames[..3]),
            show(&frames[n - 3..])
        ),
    }
}
