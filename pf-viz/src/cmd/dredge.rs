//! `pf-viz dredge …`: Babuška et al.: on-line estimation of overflow losses in a hopper dredger.

use clap::Subcommand;

use crate::error::{Result, VizError};

/// The subcommands of `pf-viz dredge`.
#[derive(Debug, Clone, Subcommand)]
pub enum DredgeCommand {
    /// Not yet wired.
    #[command(hide = true)]
    Pending,
}

/// Run a `pf-viz dredge` subcommand.
///
/// # Errors
/// Bad input, as a one-line message naming what and where.
pub fn run(cmd: DredgeCommand) -> Result<()> {
    match cmd {
        DredgeCommand::Pending => Err(VizError::Argument {
            message: "pf-viz dredge: not yet available".into(),
        }),
    }
}
