//! `pf-viz homotopy …`: Morelande et al.: the optimal homotopy filter for bearings-only tracking.

use clap::Subcommand;

use crate::error::{Result, VizError};

/// The subcommands of `pf-viz homotopy`.
#[derive(Debug, Clone, Subcommand)]
pub enum HomotopyCommand {
    /// Not yet wired.
    #[command(hide = true)]
    Pending,
}

/// Run a `pf-viz homotopy` subcommand.
///
/// # Errors
/// Bad input, as a one-line message naming what and where.
pub fn run(cmd: HomotopyCommand) -> Result<()> {
    match cmd {
        HomotopyCommand::Pending => Err(VizError::Argument {
            message: "pf-viz homotopy: not yet available".into(),
        }),
    }
}
