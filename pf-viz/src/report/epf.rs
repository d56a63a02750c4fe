//! Report section for El Abed et al.: the energetic particle filter for multiple targets.

use super::{Context, Section, SectionReport};
use crate::error::Result;

/// The section's registry entry.
pub const SECTION: Section = Section {
    name: "epf",
    title: "El Abed et al.: the energetic particle filter for multiple targets",
    run: run_section,
};

fn run_section(_ctx: &Context<'_>) -> Result<SectionReport> {
    Ok(SectionReport::default())
}
