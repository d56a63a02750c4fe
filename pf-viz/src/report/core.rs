//! The engine's own section: the genealogy of a bootstrap filter (Cappé & Moulines, Fig. 1).
//!
//! The noisy AR(1) model `X_{k+1} = φ X_k + σ U_k`, `Y_k = X_k + ρ V_k` with the paper's
//! `φ = 0.98, σ = 0.2, ρ = 1` (Section 5), stationary initial law, `n = 100` (observations
//! `y_0 … y_n`), filtered by the bootstrap filter with `N = 50` particles and multinomial
//! resampling at every step. The data are drawn from stream 0 of the master seed and the
//! filter from stream 1, so changing the filter never changes the data.
//!
//! Files: `genealogy.png`, `ess.png`, and `genealogy.rrd` (when recordings are on).

use pf_core::filter::{FilterConfig, ParticleFilter, ResamplePolicy};
use pf_core::mc::stream_rng;
use pf_core::models::NoisyAr1;
use pf_core::observe::{CloudRecorder, EssRecorder, GenealogyRecorder};
use pf_core::resample::Resampler;
use serde::{Deserialize, Serialize};

use super::{Context, Figure, Section, SectionReport, to_json};
use crate::error::{Result, VizError};
use crate::figure::GenealogyData;
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

/// The experiment's configuration; `Default` is the paper's model with the figure's `N`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CoreConfig {
    /// φ, the AR coefficient.
    pub phi: f64,
    /// σ, the state noise standard deviation.
    pub sigma: f64,
    /// ρ, the observation noise standard deviation.
    pub rho: f64,
    /// `n`: observations `y_0 … y_n`, so `n + 1` filter steps.
    pub n: usize,
    /// The particle filter.
    pub filter: FilterConfig,
    /// Random stream (under the master seed) of the simulated data.
    pub data_stream: u64,
    /// Random stream (under the master seed) of the filter.
    pub filter_stream: u64,
}

impl Default for CoreConfig {
    fn default() -> Self {
        CoreConfig {
            phi: 0.98,
            sigma: 0.2,
            rho: 1.0,
            n: 100,
            filter: FilterConfig {
                n_particles: 50,
                resampler: Resampler::Multinomial,
                policy: ResamplePolicy::Always,
            },
            data_stream: 0,
            filter_stream: 1,
        }
    }
}

/// Every number behind the section's figures.
#[derive(Debug, Clone, Serialize)]
pub struct CoreResult {
    /// The configuration that was run.
    pub config: CoreConfig,
    /// The master seed.
    pub seed: u64,
    /// The filter's log-likelihood estimate `log p̂(y_{0:n})`.
    pub log_lik: f64,
    /// Most recent step at which all surviving lineages share one ancestor.
    pub coalescence_time: Option<usize>,
    /// Number of distinct surviving ancestors at each step.
    pub surviving_per_step: Vec<usize>,
    /// Effective sample size at each step (after reweighting).
    pub ess: Vec<f64>,
    /// Whether each step resampled.
    pub resampled: Vec<bool>,
    /// The simulated observations `y_k`.
    pub observations: Vec<f64>,
    /// The genealogy figure's data (positions, ancestors, survival flags, true states).
    pub genealogy: GenealogyData,
    /// Normalised weights `W_k^i`.
    pub weights: Vec<Vec<f64>>,
    /// Files written, relative to the output directory.
    pub files: Vec<String>,
}

fn run_section(ctx: &Context<'_>) -> Result<SectionReport> {
    let result = run(ctx, CoreConfig::default())?;
    let n = result.config.filter.n_particles;
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

/// Run the experiment with `config` and write its files.
///
/// # Errors
/// An engine error (bad configuration, weight collapse) or a file error.
pub fn run(ctx: &Context<'_>, config: CoreConfig) -> Result<CoreResult> {
    let core = VizError::core(NAME);
    let model = NoisyAr1::new(config.phi, config.sigma, config.rho).map_err(core)?;
    let (xs, ys) = model.simulate(config.n, &mut stream_rng(ctx.seed, config.data_stream));
    let obs: Vec<Option<f64>> = ys.iter().copied().map(Some).collect();

    let mut pf = ParticleFilter::bootstrap(model, config.filter).map_err(core)?;
    let mut observers = (
        CloudRecorder::new(),
        GenealogyRecorder::new(),
        EssRecorder::new(),
    );
    let mut rng = stream_rng(ctx.seed, config.filter_stream);
    let summary = pf.run(&obs, None, &mut rng, &mut observers).map_err(core)?;
    let (clouds, genealogy, ess_rec) = observers;
    let g = genealogy.genealogy();
    let data = GenealogyData::recorded(&clouds, g, Some(xs));
    let weights: Vec<Vec<f64>> = clouds.clouds.iter().map(|c| c.weights.clone()).collect();
    let ess = ess_rec.ess();
    let surviving_per_step = g.surviving_counts();
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
    png::genealogy::render(&ctx.path("genealogy.png"), &data, &labels)?;
    files.push("genealogy.png".to_owned());

    let step_axis: Vec<f64> = (0..g.n_steps()).map(|k| k as f64).collect();
    let ess_plot = LinePlot {
        title: format!("Effective sample size and surviving ancestors, N = {n_particles}"),
        x_label: "time index k (steps)".into(),
        x_scale: AxisScale::Linear,
        y_label: "number of particles".into(),
        series: vec![
            Series {
                name: "effective sample size (after reweighting)".into(),
                x: step_axis.clone(),
                y: ess.clone(),
                band: None,
            },
            Series {
                name: "distinct ancestors of the final particles".into(),
                x: step_axis,
                y: surviving_per_step.iter().map(|&c| c as f64).collect(),
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
                &data,
                &GenealogyExtras {
                    genealogy: g,
                    weights: &weights,
                    ess: &ess,
                },
            )?;
            files.push("genealogy.rrd".to_owned());
        }
    }

    Ok(CoreResult {
        config,
        seed: ctx.seed,
        log_lik: summary.log_lik,
        coalescence_time: data.coalescence_time,
        surviving_per_step,
        ess,
        resampled: ess_rec.resampled(),
        observations: ys,
        genealogy: data,
        weights,
        files,
    })
}
