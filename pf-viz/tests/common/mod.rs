//! Helpers shared by the `pf-viz` integration tests, which all drive the binary the way
//! other tools do: run it, read its one-line JSON, check its one-line errors.
//!
//! Each `tests/*.rs` file is its own crate and compiles this module separately, using only
//! part of it; hence the crate-wide `dead_code` allowance rather than one per item.
#![allow(dead_code)]

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

/// The binary under test, built by Cargo for the integration tests.
pub const BIN: &str = env!("CARGO_BIN_EXE_pf-viz");

/// Runs `pf-viz` with `args` and captures its exit status, stdout and stderr.
pub fn pf_viz(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().expect("run pf-viz")
}

/// Runs `pf-viz` with `args` and asserts it succeeded, showing its stderr if not.
pub fn pf_viz_ok(args: &[&str]) -> Output {
    let out = pf_viz(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs a `--json` command, asserts it succeeded, and parses its stdout, which the JSON
/// contract says is exactly one line holding one JSON value.
pub fn pf_viz_json(args: &[&str]) -> Value {
    let out = pf_viz_ok(args);
    let text = String::from_utf8(out.stdout).unwrap();
    assert_eq!(
        text.lines().count(),
        1,
        "{args:?}: --json prints exactly one line: {text}"
    );
    serde_json::from_str(&text).unwrap()
}

/// Asserts `out` is a failed run whose stderr is exactly one line containing every one of
/// `needles`, and returns that line. This is how every `pf-viz` error reports; the exit
/// code, the `error:` prefix and an empty stdout are left to the callers, since not every
/// command promises all of them. `what` names the case in failure messages.
pub fn one_line_error(out: &Output, what: &str, needles: &[&str]) -> String {
    assert!(!out.status.success(), "{what}: should fail");
    let err = String::from_utf8(out.stderr.clone()).unwrap();
    assert_eq!(err.lines().count(), 1, "{what}: one line: {err:?}");
    for n in needles {
        assert!(err.contains(n), "{what}: {n:?} not in {err:?}");
    }
    err
}

/// A fresh scratch directory, removed on drop.
///
/// The name carries the test file (its crate name), the tag and the process id, so tests in
/// different files, different tests of one file and concurrent runs never share one.
pub struct Scratch(PathBuf);

impl Scratch {
    /// Creates (after clearing any leftover) the directory for `tag`.
    pub fn new(tag: &str) -> Self {
        let dir = std::env::temp_dir().join(format!(
            "pf-viz-{}-{tag}-{}",
            env!("CARGO_CRATE_NAME"),
            std::process::id()
        ));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    /// The directory itself.
    pub fn dir(&self) -> &Path {
        &self.0
    }

    /// Writes `text` to `name` in the directory and returns its path as a string, ready
    /// to go into an argument list.
    pub fn file(&self, name: &str, text: &str) -> String {
        let p = self.path(name);
        fs::write(&p, text).unwrap();
        p
    }

    /// The path of `name` in the directory (not created) as a string, for argument lists.
    pub fn path(&self, name: &str) -> String {
        self.0
            .join(name)
            .into_os_string()
            .into_string()
            .expect("UTF-8 temporary path")
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
}
