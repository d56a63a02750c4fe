//! `pf-viz mpf …`: Karlsson, Schön & Gustafsson: the marginalized particle filter and its complexity.

use clap::Subcommand;

use crate::error::{Result, VizError};

/// The subcommands of `pf-viz mpf`.
#[derive(Debug, Clone, Subcommand)]
pub enum MpfCommand {
    /// Not yet wired.
    #[command(hide = true)]
    Pending,
}

/// Run a `pf-viz mpf` subcommand.
///
/// # Errors
/// Bad input, as a one-line message naming what and where.
pub fn run(cmd: MpfCommand) -> Result<()> {
    match cmd {
        MpfCommand::Pending => Err(VizError::Argument {
            message: "pf-viz mpf: not yet available".into(),
        }),
    }
}
