//! Report section for Babuška et al.: on-line estimation of overflow losses in a hopper dredger.

use super::{Context, Section, SectionReport};
use crate::error::Result;

/// The section's registry entry.
pub const SECTION: Section = Section {
    name: "dredge",
    title: "Babuška et al.: on-line estimation of overflow losses in a hopper dredger",
    run: run_section,
};

fn run_section(_ctx: &Context<'_>) -> Result<SectionReport> {
    Ok(SectionReport::default())
}
