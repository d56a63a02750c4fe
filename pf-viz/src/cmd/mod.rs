//! The paper subcommands (`pf-viz smooth|mpf|homotopy|dredge|epf …`), one module each.
//!
//! Each module holds its clap argument types and a `run` that prints either a readable
//! summary or, with `--json`, exactly one JSON object on stdout. Their JSON shapes are
//! contracts that other tools call: add keys, never rename or drop them.

pub mod dredge;
pub mod epf;
pub mod homotopy;
pub mod mpf;
pub mod smooth;

use std::fmt::Display;
use std::io::Write;

use serde::Serialize;

use crate::error::{Result, VizError};

/// Print `value` as one line of JSON on stdout (the `--json` contract: nothing else there).
///
/// # Errors
/// [`VizError::Argument`] if the value cannot be serialised (a bug, reported not panicked);
/// otherwise as [`print_line`].
pub fn print_json<T: Serialize + ?Sized>(value: &T) -> Result<()> {
    let json = serde_json::to_string(value).map_err(|e| VizError::Argument {
        message: format!("cannot serialise the result: {e}"),
    })?;
    print_line(json)
}

/// Print one line of results on stdout and flush it; every result pf-viz prints goes
/// through here, because `println!` panics when stdout cannot be written.
///
/// A closed stdout (a reader such as `head` that stopped early: broken pipe) is an error
/// like any other, not a quiet success: the output was cut short, so the exit status says
/// so, as a shell's `pipefail` expects.
///
/// # Errors
/// [`VizError::Io`] naming `<stdout>` when the write or flush fails (broken pipe, full
/// disk, closed descriptor).
/// In an MPI run only rank 0 prints; the other ranks' lines are dropped.
pub fn print_line(line: impl Display) -> Result<()> {
    if !pf_core::mc::dist::is_root() {
        return Ok(());
    }
    let mut out = std::io::stdout().lock();
    writeln!(out, "{line}")
        .and_then(|()| out.flush())
        .map_err(VizError::io("<stdout>"))
}
