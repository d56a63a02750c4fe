//! `pf-viz smooth …`: Cappé & Moulines: smoothed additive functionals, EM, SEM and the score.

use clap::Subcommand;

use crate::error::{Result, VizError};

/// The subcommands of `pf-viz smooth`.
#[derive(Debug, Clone, Subcommand)]
pub enum SmoothCommand {
    /// Not yet wired.
    #[command(hide = true)]
    Pending,
}

/// Run a `pf-viz smooth` subcommand.
///
/// # Errors
/// Bad input, as a one-line message naming what and where.
pub fn run(cmd: SmoothCommand) -> Result<()> {
    match cmd {
        SmoothCommand::Pending => Err(VizError::Argument {
            message: "pf-viz smooth: not yet available".into(),
        }),
    }
}
