//! The engine's own section: the genealogy of a bootstrap filter (Cappé & Moulines, Fig. 1),
//! computed by [`pf_core::experiments::genealogy`] and drawn here.
//!
//! Files: `genealogy.png`, `ess.png`, and `genealogy.rrd` (when recordings are on).

use pf_core::experiments::{GenealogyConfig, GenealogyResult, genealogy};
use serde::Serialize;

use super::{Context, Figure, Section, SectionReport, to_json};
use crate::error::{Result, VizError};
use crate::png;
use crate::png::genealogy::GenealogyLabels;
use crate::png::line::{LinePlot, RefLine, Series};
use crate::png::style::{AxisScale, LegendPos};

/// The section's registry entry.
pub const SECTION: Section = Section {
    name: "core",
    title: "engine: particle genealogy of a bootstrap filter",
    run: run_section,
};

const NAME: &str = "core";

/// The experiment's numbers and the files drawn from them.
#[derive(Debug, Clone, Serialize)]
pub struct CoreResult {
    /// Every number behind the figures, at the top level of the JSON.
    #[serde(flatten)]
    pub run: GenealogyResult,
    /// The report's master seed (`summary.json`'s `core.seed`; also in `config`).
    pub seed: u64,
    /// Files written, relative to the output directory.
    pub files: Vec<String>,
}

fn run_section(ctx: &Context<'_>) -> Result<SectionReport> {
    let result = run(
        ctx,
        &GenealogyConfig {
            seed: ctx.seed,
            ..GenealogyConfig::default()
        },
    )?;
    let n = result.run.config.filter.n_particles;
    Ok(SectionReport {
        result: to_json(ctx, &result)?,
        figures: vec![
            Figure {
                file: "genealogy.png".into(),
                caption: format!(
                    "Genealogy of a bootstrap filter with N = {n} particles on the noisy AR(1) \
                     model (cf. Cappé & Moulines, Fig. 1): grey, every particle's path from \
                     its parent; blue, the lineages of the final particles; dashed black, the \
                     true state; the red line marks the lineages' coalescence."
                ),
            },
            Figure {
                file: "ess.png".into(),
                caption: "Effective sample size after reweighting, and the number of distinct \
                          ancestors of the final particles at each step (path degeneracy)."
                    .into(),
            },
        ],
        files: result
            .files
            .iter()
            .filter(|f| f.ends_with(".rrd"))
            .cloned()
            .collect(),
        ..SectionReport::default()
    })
}

/// Run the experiment with `config` and draw its files.
///
/// # Errors
/// An engine error (bad configuration, weight collapse) or a file error.
pub fn run(ctx: &Context<'_>, config: &GenealogyConfig) -> Result<CoreResult> {
    let r = genealogy(config).map_err(VizError::core(NAME))?;
    let n_particles = config.filter.n_particles;

    let mut files = Vec::new();
    let labels = GenealogyLabels {
        title: format!(
            "Particle genealogy: bootstrap filter, N = {n_particles}, {} resampling at every step",
            config.filter.resampler
        ),
        x: "time index k (steps)".into(),
        y: "particle position ξₖⁱ (state units)".into(),
    };
    png::genealogy::render(&ctx.path("genealogy.png"), &r.genealogy, &labels)?;
    files.push("genealogy.png".to_owned());

    let step_axis: Vec<f64> = (0..r.genealogy.n_steps()).map(|k| k as f64).collect();
    let ess_plot = LinePlot {
        title: format!("Effective sample size and surviving ancestors, N = {n_particles}"),
        x_label: "time index k (steps)".into(),
        x_scale: AxisScale::Linear,
        y_label: "number of particles".into(),
        series: vec![
            Series {
                name: "effective sample size (after reweighting)".into(),
                x: step_axis.clone(),
                y: r.ess.clone(),
                band: None,
            },
            Series {
                name: "distinct ancestors of the final particles".into(),
                x: step_axis,
                y: r.surviving_per_step.iter().map(|&c| c as f64).collect(),
                band: None,
            },
        ],
        ref_lines: vec![RefLine {
            y: n_particles as f64,
            label: format!("N = {n_particles}"),
        }],
        // Headroom above N for the legend.
        y_range: Some((0.0, n_particles as f64 * 1.34)),
        legend: LegendPos::UpperLeft,
    };
    png::line::render(&ctx.path("ess.png"), &ess_plot)?;
    files.push("ess.png".to_owned());

    if ctx.write_rrd() {
        #[cfg(feature = "rrd")]
        {
            use crate::rrd::genealogy::{GenealogyExtras, save};
            save(
                &ctx.path("genealogy.rrd"),
                &r.genealogy,
                &GenealogyExtras {
                    genealogy: &r.lineage,
                    weights: &r.weights,
                    ess: &r.ess,
                },
            )?;
            files.push("genealogy.rrd".to_owned());
        }
    }

    Ok(CoreResult {
        seed: config.seed,
        run: r,
        files,
    })
}
