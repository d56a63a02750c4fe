//! Report section for Cappé & Moulines: smoothed additive functionals, EM, SEM and the score.

use super::{Context, Section, SectionReport};
use crate::error::Result;

/// The section's registry entry.
pub const SECTION: Section = Section {
    name: "smooth",
    title: "Cappé & Moulines: smoothed additive functionals, EM, SEM and the score",
    run: run_section,
};

fn run_section(_ctx: &Context<'_>) -> Result<SectionReport> {
    Ok(SectionReport::default())
}
