//! The one error type of pf-viz, which the binary prints as a single `error: …` line, and
//! the argument limits that the CLI and library callers share.

use std::path::{Path, PathBuf};

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
    /// Some report sections failed; every other one was written, and the pages and
    /// `summary.json` in `out` name the failures.
    #[error("{}", sections_message(out, *ran, failed))]
    Sections {
        /// The output directory.
        out: PathBuf,
        /// How many sections ran.
        ran: usize,
        /// Each failed section's name and one-line error, in the order they ran.
        failed: Vec<(String, String)>,
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

/// The one line of [`VizError::Sections`]: each failure once, prefixed by its section's name
/// unless the error already starts with it.
fn sections_message(out: &Path, ran: usize, failed: &[(String, String)]) -> String {
    let each: Vec<String> = failed
        .iter()
        .map(|(name, e)| {
            if e.starts_with(&format!("{name}: ")) {
                e.clone()
            } else {
                format!("{name}: {e}")
            }
        })
        .collect();
    format!(
        "{} of {ran} report section(s) failed (summary.json and the pages in {} name them): {}",
        failed.len(),
        out.display(),
        each.join("; ")
    )
}

/// Most worker threads `--threads` and `--jobs` accept: far beyond any machine's cores, and
/// small enough that building the pool takes well under a second (10 000 took minutes).
pub const MAX_THREADS: usize = 1024;

/// Check a thread count given as `flag`, for callers of the library that bypass clap: zero
/// does nothing and more than [`MAX_THREADS`] takes minutes to start, so both are refused
/// before any work.
///
/// # Errors
/// [`VizError::Argument`] naming `flag` and the limit.
pub fn check_threads(flag: &str, n: usize) -> Result<()> {
    if (1..=MAX_THREADS).contains(&n) {
        Ok(())
    } else {
        Err(VizError::Argument {
            message: format!("{flag} must be between 1 and {MAX_THREADS}, got {n}"),
        })
    }
}

/// Result alias for pf-viz.
pub type Result<T, E = VizError> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thread_counts_are_bounded() {
        assert!(check_threads("--jobs", 1).is_ok());
        assert!(check_threads("--jobs", MAX_THREADS).is_ok());
        for n in [0, MAX_THREADS + 1, usize::MAX] {
            let e = check_threads("--jobs", n).unwrap_err();
            assert!(e.to_string().contains("--jobs"), "{e}");
        }
    }

    /// Each failure once, on one line, without naming its section twice.
    #[test]
    fn failed_sections_fit_one_line() {
        let e = VizError::Sections {
            out: PathBuf::from("out"),
            ran: 3,
            failed: vec![
                ("mpf".into(), "mpf: calibration failed".into()),
                ("core".into(), "out/genealogy.png: Is a directory".into()),
            ],
        };
        assert_eq!(
            e.to_string(),
            "2 of 3 report section(s) failed (summary.json and the pages in out name them): \
             mpf: calibration failed; core: out/genealogy.png: Is a directory"
        );
    }
}
