//! The one error type of pf-viz. The binary prints it as a single `error: …` line.

use std::path::PathBuf;

use pf_core::CoreError;
use thiserror::Error;

/// Everything that can go wrong while producing a report.
///
/// Every variant that touches the file system names the path at fault, so the one-line
/// message printed by the binary is enough to act on.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum VizError {
    /// A data file is missing or malformed; `line` is 1-based, counting the header.
    #[error("{}{}: {message}", path.display(), line.map(|l| format!(", line {l}")).unwrap_or_default())]
    Data {
        /// The file.
        path: PathBuf,
        /// The line at fault, when known.
        line: Option<u64>,
        /// What is wrong.
        message: String,
    },
    /// A command-line value is out of range (clap checks the syntax, this the meaning).
    #[error("{message}")]
    Argument {
        /// What is wrong.
        message: String,
    },
    /// The engine rejected a configuration or failed during a run.
    #[error("{section}: {source}")]
    Core {
        /// The report section (or subcommand) that ran the engine.
        section: &'static str,
        /// The engine's error.
        #[source]
        source: CoreError,
    },
    /// The output directory cannot be created or written to.
    #[error("output directory {}: {source}", path.display())]
    OutDir {
        /// The directory.
        path: PathBuf,
        /// What the file system said.
        #[source]
        source: std::io::Error,
    },
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the file system said.
        #[source]
        source: std::io::Error,
    },
    /// Serialising a result to JSON failed.
    #[error("{}: cannot serialise JSON: {source}", path.display())]
    Json {
        /// The file being written.
        path: PathBuf,
        /// serde_json's error.
        #[source]
        source: serde_json::Error,
    },
    /// A paper crate rejected its input or failed during a run.
    #[error("{paper}: {source}")]
    Paper {
        /// The paper (`smooth`, `mpf`, `homotopy`, `dredge`, `epf`).
        paper: &'static str,
        /// The paper crate's own error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync + 'static>,
    },
    /// plotters failed to draw or encode a figure.
    #[error("{}: cannot draw figure: {message}", path.display())]
    Plot {
        /// The figure being written.
        path: PathBuf,
        /// plotters' message.
        message: String,
    },
    /// Data handed to a plot are inconsistent (a bug in the caller, reported, not panicked).
    #[error("{what}: {message}")]
    PlotData {
        /// Which figure.
        what: &'static str,
        /// What was inconsistent.
        message: String,
    },
    /// Rerun failed to record or save an `.rrd` file.
    #[error("{}: cannot write Rerun recording: {message}", path.display())]
    Rrd {
        /// The recording being written.
        path: PathBuf,
        /// Rerun's message.
        message: String,
    },
}

impl VizError {
    /// Wrap an engine error raised in `section`.
    pub fn core(section: &'static str) -> impl Fn(CoreError) -> VizError + Copy {
        move |source| VizError::Core { section, source }
    }

    /// Wrap an error of the paper crate `paper`.
    pub fn paper<E>(paper: &'static str) -> impl Fn(E) -> VizError + Copy
    where
        E: std::error::Error + Send + Sync + 'static,
    {
        move |source| VizError::Paper {
            paper,
            source: Box::new(source),
        }
    }

    /// Wrap an I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> VizError {
        let path = path.into();
        move |source| VizError::Io { path, source }
    }
}

/// Result alias for pf-viz.
pub type Result<T, E = VizError> = std::result::Result<T, E>;
