//! Report section for Morelande et al.: the optimal homotopy filter for bearings-only tracking.

use super::{Context, Section, SectionReport};
use crate::error::Result;

/// The section's registry entry.
pub const SECTION: Section = Section {
    name: "homotopy",
    title: "Morelande et al.: the optimal homotopy filter for bearings-only tracking",
    run: run_section,
};

fn run_section(_ctx: &Context<'_>) -> Result<SectionReport> {
    Ok(SectionReport::default())
}
