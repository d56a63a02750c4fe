//! Report section for Karlsson, Schön & Gustafsson: the marginalized particle filter and its complexity.

use super::{Context, Section, SectionReport};
use crate::error::Result;

/// The section's registry entry.
pub const SECTION: Section = Section {
    name: "mpf",
    title: "Karlsson, Schön & Gustafsson: the marginalized particle filter and its complexity",
    run: run_section,
};

fn run_section(_ctx: &Context<'_>) -> Result<SectionReport> {
    Ok(SectionReport::default())
}
