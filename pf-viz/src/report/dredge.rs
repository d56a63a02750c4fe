//! Report section for Babuška et al.: on-line estimation of overflow losses in a hopper
//! dredger.
//!
//! Figures: `dredge-fig3-inputs.png` and `dredge-fig3-density.png` (the inputs),
//! `dredge-fig4-phases.png` (volume and mass through the three loading phases),
//! `dredge-fig5-qo.png` and `dredge-fig5-rho.png` (simulated against estimated in phase 3),
//! `dredge-fig6-residuals-qo.png` and `dredge-fig6-residuals-rho.png` (residual histograms),
//! `dredge-fig7-direct.png` (PF against the direct computation), `dredge-fig8-band.png` (25
//! runs on the same data), `dredge-n-sweep.png` (residual std against N), and a residual
//! table beside the paper's. `dredge.rrd`: signals and the (Q_o, ρ_o) particle cloud on the
//! `time` timeline.

use pf_dredge::experiments::{
    CycleConfig, Fig7Config, Fig8Config, Fig56Config, NSweepConfig, ResidualReport,
    Scale as DredgeScale, cycle, fig5_6, fig7, fig8, n_sweep,
};
use serde::Serialize;

use super::{Context, Figure, Section, SectionReport, Table, to_json};
use crate::cli::Scale;
use crate::error::{Result, VizError};
use crate::png;
use crate::png::histogram::HistogramPlot;
use crate::png::line::{Band, LinePlot, Series};
use crate::png::style::LegendPos;

/// The section's registry entry.
pub const SECTION: Section = Section {
    name: "dredge",
    title: "Babuška et al.: on-line estimation of overflow losses in a hopper dredger",
    run: run_section,
};

/// Every number behind the section.
#[derive(Debug, Clone, Serialize)]
pub struct DredgeResult {
    /// The master seed.
    pub seed: u64,
    /// Figs. 3–4: the simulated cycle.
    pub cycle: pf_dredge::Cycle,
    /// Figs. 5–6.
    pub fig5_6: pf_dredge::experiments::Fig56Result,
    /// Fig. 7.
    pub fig7: pf_dredge::experiments::Fig7Result,
    /// Fig. 8.
    pub fig8: pf_dredge::experiments::Fig8Result,
    /// The N sweep.
    pub n_sweep: pf_dredge::experiments::NSweepResult,
}

fn scale(s: Scale) -> DredgeScale {
    match s {
        Scale::Quick => DredgeScale::Quick,
        Scale::Default => DredgeScale::Default,
        Scale::Full => DredgeScale::Full,
    }
}

fn series(name: &str, x: &[f64], y: &[f64]) -> Series {
    Series {
        name: name.into(),
        x: x.to_vec(),
        y: y.to_vec(),
        band: None,
    }
}

/// A series from optional values, keeping only the defined ones.
fn series_opt(name: &str, x: &[f64], y: &[Option<f64>]) -> Series {
    let (x, y): (Vec<f64>, Vec<f64>) = x
        .iter()
        .zip(y)
        .filter_map(|(&x, y)| y.map(|y| (x, y)))
        .unzip();
    Series {
        name: name.into(),
        x,
        y,
        band: None,
    }
}

fn line(title: &str, y_label: &str, series: Vec<Series>, legend: LegendPos) -> LinePlot {
    LinePlot {
        title: title.into(),
        x_label: "time t (s)".into(),
        y_label: y_label.into(),
        series,
        ref_lines: vec![],
        y_range: None,
        legend,
    }
}

fn run_section(ctx: &Context<'_>) -> Result<SectionReport> {
    let dredge = VizError::paper("dredge");
    let sc = scale(ctx.scale);
    let seed = ctx.seed;
    let bar = ctx.progress.bar("dredge", 5);
    bar.set_message("Figs. 3-4: the cycle");
    let c = cycle(&CycleConfig {
        seed,
        ..CycleConfig::default()
    })
    .map_err(dredge)?;
    bar.inc(1);
    bar.set_message("Figs. 5-6");
    let f56 = fig5_6(&Fig56Config {
        seed,
        ..Fig56Config::at_scale(sc)
    })
    .map_err(dredge)?;
    bar.inc(1);
    bar.set_message("Fig. 7");
    let f7 = fig7(&Fig7Config {
        seed,
        ..Fig7Config::at_scale(sc)
    })
    .map_err(dredge)?;
    bar.inc(1);
    bar.set_message("Fig. 8");
    let f8_cfg = Fig8Config {
        seed,
        ..Fig8Config::at_scale(sc)
    };
    let f8 = fig8(&f8_cfg).map_err(dredge)?;
    bar.inc(1);
    bar.set_message("N sweep");
    let sweep_cfg = NSweepConfig {
        seed,
        ..NSweepConfig::at_scale(sc)
    };
    let sweep = n_sweep(&sweep_cfg).map_err(dredge)?;
    bar.inc(1);
    bar.finish_and_clear();

    let mut figures = Vec::new();
    let mut fig = |file: &str, caption: String, plot: &LinePlot| -> Result<()> {
        png::line::render(&ctx.path(file), plot)?;
        figures.push(Figure {
            file: file.into(),
            caption,
        });
        Ok(())
    };
    let t = &c.t;
    fig(
        "dredge-fig3-inputs.png",
        "Fig. 3: the manipulated inputs of the simulated loading cycle, incoming flow-rate \
         Q_i and overflow height h_o (the PID controller moves h_o in phase 3)."
            .into(),
        &line(
            "Fig. 3: inputs Q_i and h_o",
            "Q_i (m³/s), h_o (m)",
            vec![
                series("Q_i (m³/s)", t, &c.q_i),
                series("h_o (m)", t, &c.h_o),
            ],
            LegendPos::LowerRight,
        ),
    )?;
    fig(
        "dredge-fig3-density.png",
        "Fig. 3: the measured disturbance, incoming density ρ_i, and the simulated overflow \
         density ρ_o."
            .into(),
        &line(
            "Fig. 3: densities ρ_i and ρ_o",
            "density (kg/m³)",
            vec![
                series("ρ_i", t, &c.rho_i),
                series("ρ_o (simulated)", t, &c.rho_o),
            ],
            LegendPos::UpperLeft,
        ),
    )?;
    let tonnes: Vec<f64> = c.m_t.iter().map(|m| m / 1000.0).collect();
    let sand: Vec<f64> = c.m_s.iter().map(|m| m / 1000.0).collect();
    fig(
        "dredge-fig4-phases.png",
        format!(
            "Fig. 4: the three loading phases: filling without overflow, overflow at constant \
             volume (from t = {} s), constant mass held by the PID controller (from t = {} s).",
            c.phase2_start
                .map_or("—".into(), |k| format!("{:.0}", c.t[k])),
            c.phase3_start
                .map_or("—".into(), |k| format!("{:.0}", c.t[k]))
        ),
        &line(
            "Fig. 4: hopper volume and mass through the loading phases",
            "V_t (m³), m_t and m_s (t)",
            vec![
                series("volume V_t (m³)", t, &c.v_t),
                series("total mass m_t (t)", t, &tonnes),
                series("sand bed m_s (t)", t, &sand),
            ],
            LegendPos::LowerRight,
        ),
    )?;
    let t3 = &f56.t;
    fig(
        "dredge-fig5-qo.png",
        "Fig. 5: simulated against estimated overflow flow-rate Q_o in phase 3 (bootstrap PF, \
         N = 1000 at the default scale)."
            .into(),
        &line(
            "Fig. 5: overflow flow-rate in phase 3",
            "Q_o (m³/s)",
            vec![
                series("simulated Q_o", t3, &f56.q_o_true),
                series("estimated Q̂_o (PF)", t3, &f56.q_o_hat),
            ],
            LegendPos::LowerRight,
        ),
    )?;
    fig(
        "dredge-fig5-rho.png",
        "Fig. 5: simulated against estimated overflow density ρ_o in phase 3.".into(),
        &line(
            "Fig. 5: overflow density in phase 3",
            "ρ_o (kg/m³)",
            vec![
                series("simulated ρ_o", t3, &f56.rho_o_true),
                series("estimated ρ̂_o (PF)", t3, &f56.rho_o_hat),
            ],
            LegendPos::LowerRight,
        ),
    )?;
    for (file, what, unit, rep, hist) in [
        (
            "dredge-fig6-residuals-qo.png",
            "Q_o",
            "m³/s",
            &f56.q_o,
            &f56.q_o_hist,
        ),
        (
            "dredge-fig6-residuals-rho.png",
            "ρ_o",
            "kg/m³",
            &f56.rho_o,
            &f56.rho_o_hist,
        ),
    ] {
        let s = &rep.ours;
        png::histogram::render(
            &ctx.path(file),
            &HistogramPlot {
                title: format!("Fig. 6: residuals of {what} in phase 3"),
                x_label: format!("{what} − estimate ({unit})"),
                edges: hist.edges.clone(),
                counts: hist.counts.clone(),
                annotation: vec![
                    format!(
                        "ours: mean {:.3}, std {:.3}, max |·| {:.3}",
                        s.mean, s.std, s.max_abs
                    ),
                    format!(
                        "paper: mean {:.3}, std {:.3}",
                        rep.paper.mean, rep.paper.std
                    ),
                    format!(
                        "std / signal range: ours {:.1} %, paper {:.1} %",
                        100.0 * rep.relative_std,
                        100.0 * rep.paper.std / rep.paper.nominal_range
                    ),
                ],
                ref_lines: vec![(0.0, "zero".into()), (s.mean, "mean".into())],
            },
        )?;
        figures.push(Figure {
            file: file.into(),
            caption: format!(
                "Fig. 6: distribution of the {what} residuals (simulated − estimated) in \
                 phase 3, with their mean, standard deviation and largest magnitude, beside \
                 the paper's."
            ),
        });
    }
    let t7 = &f7.t;
    let mut fig = |file: &str, caption: String, plot: &LinePlot| -> Result<()> {
        png::line::render(&ctx.path(file), plot)?;
        figures.push(Figure {
            file: file.into(),
            caption,
        });
        Ok(())
    };
    fig(
        "dredge-fig7-direct.png",
        "Fig. 7: the PF estimate of ρ_o against the direct computation (15)–(16) from \
         zero-phase low-passed volume and mass (0.001 Hz), and the simulated value."
            .into(),
        &line(
            "Fig. 7: PF against direct computation, overflow density",
            "ρ_o (kg/m³)",
            vec![
                series("simulated ρ_o", t7, &f7.rho_o_true),
                series("PF ρ̂_o", t7, &f7.rho_o_pf),
                series_opt("direct computation", t7, &f7.rho_o_direct),
            ],
            LegendPos::LowerRight,
        ),
    )?;
    let t8 = &f8.t;
    let mut band_series = series(
        &format!("mean of {} PF runs", f8_cfg.runs),
        t8,
        &f8.rho_o.mean,
    );
    band_series.band = Some(Band {
        lower: f8.rho_o.min.clone(),
        upper: f8.rho_o.max.clone(),
    });
    fig(
        "dredge-fig8-band.png",
        format!(
            "Fig. 8: min–max band and mean of {} independent PF runs on the same data, \
             overflow density ρ_o; mean band width in phase 3 {:.1} kg/m³.",
            f8_cfg.runs, f8.mean_rho_o_width_phase3
        ),
        &line(
            "Fig. 8: spread of independent PF runs",
            "ρ_o (kg/m³)",
            vec![band_series, series("simulated ρ_o", t8, &f8.rho_o_true)],
            LegendPos::LowerRight,
        ),
    )?;
    let ns: Vec<f64> = sweep.rows.iter().map(|r| r.n as f64).collect();
    let mut q = series(
        "std of Q_o residual (m³/s) × 100",
        &ns,
        &sweep
            .rows
            .iter()
            .map(|r| 100.0 * r.q_o_std)
            .collect::<Vec<_>>(),
    );
    q.band = Some(Band {
        lower: sweep
            .rows
            .iter()
            .map(|r| 100.0 * (r.q_o_std - 2.0 * r.q_o_std_se))
            .collect(),
        upper: sweep
            .rows
            .iter()
            .map(|r| 100.0 * (r.q_o_std + 2.0 * r.q_o_std_se))
            .collect(),
    });
    let mut rho = series(
        "std of ρ_o residual (kg/m³)",
        &ns,
        &sweep.rows.iter().map(|r| r.rho_o_std).collect::<Vec<_>>(),
    );
    rho.band = Some(Band {
        lower: sweep
            .rows
            .iter()
            .map(|r| r.rho_o_std - 2.0 * r.rho_o_std_se)
            .collect(),
        upper: sweep
            .rows
            .iter()
            .map(|r| r.rho_o_std + 2.0 * r.rho_o_std_se)
            .collect(),
    });
    png::line::render(
        &ctx.path("dredge-n-sweep.png"),
        &LinePlot {
            title: "Beyond the paper: residual std in phase 3 against N".into(),
            x_label: "particles N".into(),
            y_label: "residual std".into(),
            series: vec![q, rho],
            ref_lines: vec![],
            y_range: None,
            legend: LegendPos::UpperRight,
        },
    )?;
    figures.push(Figure {
        file: "dredge-n-sweep.png".into(),
        caption: format!(
            "Beyond the paper: the phase-3 residual standard deviation of Q_o (×100) and ρ_o \
             against the number of particles, mean over {} runs with ±2 standard errors, so \
             a user can choose N for the on-board time budget.",
            sweep_cfg.reps
        ),
    });

    let row = |what: &str, unit: &str, r: &ResidualReport| {
        vec![
            format!("{what} ({unit})"),
            format!("{:.3} [{:.3}]", r.ours.mean, r.paper.mean),
            format!("{:.3} [{:.3}]", r.ours.std, r.paper.std),
            format!("{:.3} [≈{:.0}]", r.ours.max_abs, r.paper.max_abs_about),
            format!(
                "{:.1} % [{:.1} %]",
                100.0 * r.relative_std,
                100.0 * r.paper.std / r.paper.nominal_range
            ),
        ]
    };
    let direct = |s: Option<pf_core::metrics::ResidualSummary>| {
        s.map_or("—".to_owned(), |s| format!("{:.3}", s.std))
    };
    let tables = vec![
        Table {
            id: "residuals".into(),
            caption: "Fig. 6: phase-3 residuals (simulated − PF estimate); the paper's values \
                      in brackets. The last column divides the std by the signal's range (ours: \
                      over phase 3; the paper's: its plotted range)."
                .into(),
            header: vec![
                "signal".into(),
                "mean [paper]".into(),
                "std [paper]".into(),
                "max |·| [paper]".into(),
                "std / range [paper]".into(),
            ],
            rows: vec![
                row("Q_o", "m³/s", &f56.q_o),
                row("ρ_o", "kg/m³", &f56.rho_o),
            ],
        },
        Table {
            id: "direct".into(),
            caption: "Fig. 7: residual standard deviation in phase 3, PF against the direct \
                      computation (15)–(16)."
                .into(),
            header: vec!["signal".into(), "PF".into(), "direct".into()],
            rows: vec![
                vec![
                    "Q_o (m³/s)".into(),
                    direct(f7.pf_residuals.q_o),
                    direct(f7.direct_residuals.q_o),
                ],
                vec![
                    "ρ_o (kg/m³)".into(),
                    direct(f7.pf_residuals.rho_o),
                    direct(f7.direct_residuals.rho_o),
                ],
            ],
        },
    ];
    let notes = vec![
        format!(
            "Our simulator is not the paper's: the paper gives no values for A, k_o, k'_o, \
             k_c, v_s, β or the densities, so ours are chosen in the pf-dredge README. The \
             Q_o residual std is {:.3} m³/s (paper 0.345), the ρ_o residual std {:.1} kg/m³ \
             (paper 13.2): relative to the signal range {:.1} % and {:.1} % against the \
             paper's {:.1} % and {:.1} %. Measured (default scale, seed 1): part of the gap is \
             lag, since raising the filter's ρ_o random-walk σ from the paper's 5 to 10 kg/m³ \
             cuts the ρ_o residual std from 43 to 34 kg/m³ and its mean from 12 to 4; beyond \
             that it levels off (33 kg/m³ at σ = 20), the floor that the volume and mass \
             noise of the paper's size sets on this simulator. The rest of the difference \
             lies in the plant, which the paper does not specify.",
            f56.q_o.ours.std,
            f56.rho_o.ours.std,
            100.0 * f56.q_o.relative_std,
            100.0 * f56.rho_o.relative_std,
            100.0 * f56.q_o.paper.std / f56.q_o.paper.nominal_range,
            100.0 * f56.rho_o.paper.std / f56.rho_o.paper.nominal_range
        ),
        "Measurement noise is the paper's size, σ(ε_y) = [10 m³, 12000 kg]; the filter is \
         the paper's: N = 1000, σ(ε_x) = [0, 3000, 0.2, 5], N_T = 900, systematic \
         resampling, T_s = 5 s."
            .into(),
    ];

    let mut files = Vec::new();
    if ctx.write_rrd() {
        #[cfg(feature = "rrd")]
        {
            let data = c.to_data();
            let filter = pf_dredge::EstimatorConfig::default()
                .with_particles(if ctx.scale == Scale::Quick { 200 } else { 1000 });
            let mut clouds = pf_core::observe::CloudRecorder::new();
            let run = pf_dredge::estimator::run_filter_observed(
                &data,
                &filter,
                &mut pf_core::mc::stream_rng(seed, 9),
                &mut clouds,
            )
            .map_err(dredge)?;
            crate::rrd::dredge::save(&ctx.path("dredge.rrd"), &c, &run, &clouds)?;
            files.push("dredge.rrd".to_owned());
        }
    }

    let result = DredgeResult {
        seed,
        cycle: c,
        fig5_6: f56,
        fig7: f7,
        fig8: f8,
        n_sweep: sweep,
    };
    Ok(SectionReport {
        result: to_json(ctx, &result)?,
        figures,
        tables,
        notes,
        files,
        ..SectionReport::default()
    })
}
