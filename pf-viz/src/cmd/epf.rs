//! `pf-viz epf …`: El Abed et al.: the energetic particle filter for multiple targets.

use clap::Subcommand;

use crate::error::{Result, VizError};

/// The subcommands of `pf-viz epf`.
#[derive(Debug, Clone, Subcommand)]
pub enum EpfCommand {
    /// Not yet wired.
    #[command(hide = true)]
    Pending,
}

/// Run a `pf-viz epf` subcommand.
///
/// # Errors
/// Bad input, as a one-line message naming what and where.
pub fn run(cmd: EpfCommand) -> Result<()> {
    match cmd {
        EpfCommand::Pending => Err(VizError::Argument {
            message: "pf-viz epf: not yet available".into(),
        }),
    }
}
