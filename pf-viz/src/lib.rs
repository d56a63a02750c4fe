//! # pf-viz: figures and recordings for the pf papers
//!
//! The `pf-viz` binary runs the experiments of the paper crates and turns their result
//! structs into PNG figures (plotters, headless, embedded font), Rerun recordings (`.rrd`,
//! behind the default feature `rrd`) and one `summary.json`. It draws; it does no
//! statistics.
//!
//! | module | holds |
//! |---|---|
//! | [`cli`] | the clap command line |
//! | [`report`] | `pf-viz report`: the registry of sections, one file per paper |
//! | [`png`] | plot kinds, each a function from plain data to a PNG |
//! | `rrd` | Rerun loggers (feature `rrd`) |
//! | [`io`] | atomic file writes |
//! | [`error`] | [`VizError`], printed by the binary as one line |

pub mod cli;
pub mod error;
pub mod io;
pub mod png;
pub mod report;
#[cfg(feature = "rrd")]
pub mod rrd;

pub use error::{Result, VizError};

use cli::{Cli, Command};

/// Execute a parsed command line.
///
/// # Errors
/// Whatever the subcommand fails with; nothing half-written is left behind.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Report(args) => {
            let summary = report::run(&args)?;
            println!(
                "pf-viz: wrote {} section(s) to {}",
                summary.sections.len(),
                args.out.display()
            );
            Ok(())
        }
    }
}
