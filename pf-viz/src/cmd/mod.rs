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

use std::io::Write;

use serde::Serialize;

use crate::error::{Result, VizError};

/// Print `value` as one line of JSON on stdout (the `--json` contract: nothing else there).
///
/// # Errors
/// [`VizError::Argument`] if the value cannot be serialised (a bug, reported not panicked);
/// an I/O error if stdout is closed (a reader that stopped early), instead of a panic.
pub fn print_json<T: Serialize + ?Sized>(value: &T) -> Result<()> {
    let json = serde_json::to_string(value).map_err(|e| VizError::Argument {
        message: format!("cannot serialise the result: {e}"),
    })?;
    let mut out = std::io::stdout().lock();
    writeln!(out, "{json}")
        .and_then(|()| out.flush())
        .map_err(VizError::io("<stdout>"))
}
