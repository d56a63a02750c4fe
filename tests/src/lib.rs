//! Cross-crate integration tests of the `pf` workspace live in `tests/tests/`.
//!
//! The workspace README is included here so that its code examples compile and run as
//! doctests under `cargo test --workspace`.
#![doc = include_str!("../../README.md")]
