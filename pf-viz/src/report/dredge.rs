//! Report section for Babuška et al.: on-line estimation of overflow losses in a hopper dredger.
//!
//! Figures 3–8 of the paper on our simulated cycle, the residual table with the paper's
//! numbers beside ours and beside the filter's on data from its own model (13), the
//! consistency table (NEES, and the estimate against the truth of `k` and `k − 1`), the `N`
//! sweep, and `dredge.rrd`. The experiments are
//! [`pf_dredge::experiments`]; this file only draws them.

use serde::Serialize;

use super::{Context, Figure, Section, SectionReport, Table, to_json};
use crate::error::{Result, VizError};
use crate::png::histogram::{self, HistData, HistPanel, HistStats, HistogramPlot};
use crate::png::line::{self, Band, LinePlot, Series};
use crate::png::style::{AxisScale, LegendPos};
use pf_dredge::experiments::{
    self as ex, Alignment, ConsistencyConfig, ConsistencyResult, CycleConfig, FLAT_WINDOW,
    Fig7Config, Fig7Result, Fig8Config, Fig8Result, Fig56Config, Fig56Result, FlatStretch,
    NOISE_FLOOR, NSweepConfig, NSweepResult,
};
use pf_dredge::simulator::Cycle;

/// The section's registry entry.
pub const SECTION: Section = Section {
    name: "dredge",
    title: "Babuška et al.: on-line estimation of overflow losses in a hopper dredger",
    run: run_section,
};

/// Every number behind the section's figures and table, with the configs.
#[derive(Debug, Serialize)]
struct DredgeResult {
    seed: u64,
    cycle_config: CycleConfig,
    cycle: Cycle,
    fig5_6_config: Fig56Config,
    fig5_6: Fig56Result,
    fig7_config: Fig7Config,
    fig7: Fig7Result,
    fig8_config: Fig8Config,
    fig8: Fig8Result,
    n_sweep_config: NSweepConfig,
    n_sweep: NSweepResult,
    /// Fig. 5's `Q̂_o`, `ρ̂_o` against the truth of sample `k` and of `k − 1`.
    fig5_alignment: [Alignment; 2],
    consistency_config: ConsistencyConfig,
    consistency: ConsistencyResult,
}

const PAPER: &str = "dredge";

fn series(name: &str, x: &[f64], y: impl IntoIterator<Item = f64>) -> Series {
    Series {
        name: name.into(),
        x: x.to_vec(),
        y: y.into_iter().collect(),
        band: None,
    }
}

/// The defined points of a series with gaps.
fn defined(name: &str, x: &[f64], y: &[Option<f64>], factor: f64) -> Series {
    let (x, y): (Vec<f64>, Vec<f64>) = x
        .iter()
        .zip(y)
        .filter_map(|(&x, y)| y.map(|y| (x, y * factor)))
        .unzip();
    Series {
        name: name.into(),
        x,
        y,
        band: None,
    }
}

/// Every `stride`-th point: series 2 and 3 of [`crate::png::style::SERIES`] carry markers,
/// which must stay sparse to be read.
fn thin(mut s: Series, stride: usize) -> Series {
    let keep = |v: &[f64]| v.iter().step_by(stride.max(1)).copied().collect::<Vec<_>>();
    s.x = keep(&s.x);
    s.y = keep(&s.y);
    s
}

/// The stride that leaves about 60 points of `n`.
fn stride(n: usize) -> usize {
    (n / 60).max(1)
}

fn plot(title: &str, y_label: &str, series: Vec<Series>, legend: LegendPos) -> LinePlot {
    LinePlot {
        title: title.into(),
        x_label: "time t (s)".into(),
        x_scale: AxisScale::Linear,
        y_label: y_label.into(),
        series,
        ref_lines: vec![],
        y_range: None,
        legend,
    }
}

/// Point (2) of the ρₒ note: [`FlatStretch`] in words.
fn flat_stretch_note(f: FlatStretch) -> String {
    match f {
        FlatStretch::Empty => "(2) phase 3 is empty in this run".into(),
        FlatStretch::TooShort { start, samples } => format!(
            "(2) the noise floor cannot be measured on this run: the simulated ρₒ leaves \
             {start:.0} kg/m³ within {samples} samples of phase 3"
        ),
        FlatStretch::Measured {
            start,
            from,
            to,
            share,
            std,
            window_range: [lo, hi],
            at_noise_floor,
        } => {
            let (lead, verdict) = if at_noise_floor {
                ("not the noise", "of the order of")
            } else {
                ("the noise floor", "above")
            };
            format!(
                "(2) {lead}: while our simulated ρₒ stays at {start:.0} kg/m³ ({from:.0}–{to:.0} \
                 s, {:.0} % of phase 3) the residual std is {std:.1} kg/m³, and {lo:.1}–{hi:.1} \
                 over {FLAT_WINDOW}-sample windows, {verdict} the {NOISE_FLOOR} kg/m³ that the \
                 measurement noise alone leaves in the linearised filter",
                100.0 * share,
            )
        }
    }
}

/// The N sweep's ρₒ residual std (mean ± s.e. of its replications) at the figures' `n`
/// and at its largest N, against the paper's 13.2 kg/m³: the note that rules out Monte Carlo
/// error and the sweep's caption both quote it.
fn sweep_rho_std(ns: &ex::NSweepResult, n: usize) -> String {
    let at = |r: &ex::NSweepRow| {
        format!(
            "{:.1} ± {:.1} kg/m³ at N = {}",
            r.rho_o_std, r.rho_o_std_se, r.n
        )
    };
    let Some(big) = ns.rows.iter().max_by_key(|r| r.n) else {
        return "not measured".into();
    };
    let both = match ns.rows.iter().find(|r| r.n == n && r.n < big.n) {
        Some(here) => format!("{} and {}", at(here), at(big)),
        None => at(big),
    };
    format!(
        "{both} (mean ± s.e.), {:.1}× the paper's 13.2",
        big.rho_o_std / 13.226
    )
}

fn run_section(ctx: &Context<'_>) -> Result<SectionReport> {
    let sc = ctx.scale;
    let err = VizError::paper(PAPER);
    let seed = ctx.seed;
    let bar = ctx.progress.bar("dredge", 6);

    let cycle_config = CycleConfig {
        seed,
        ..CycleConfig::at_scale(sc)
    };
    let c = ex::cycle(&cycle_config).map_err(err)?;
    bar.inc(1);
    let fig5_6_config = Fig56Config {
        seed,
        ..Fig56Config::at_scale(sc)
    };
    let f56 = ex::fig5_6(&fig5_6_config).map_err(err)?;
    bar.inc(1);
    let fig7_config = Fig7Config {
        seed,
        ..Fig7Config::at_scale(sc)
    };
    let f7 = ex::fig7(&fig7_config).map_err(err)?;
    bar.inc(1);
    let fig8_config = Fig8Config {
        seed,
        ..Fig8Config::at_scale(sc)
    };
    let f8 = ex::fig8(&fig8_config).map_err(err)?;
    bar.inc(1);
    let n_sweep_config = NSweepConfig {
        seed,
        ..NSweepConfig::at_scale(sc)
    };
    let ns = ex::n_sweep(&n_sweep_config).map_err(err)?;
    bar.inc(1);
    let consistency_config = ConsistencyConfig {
        seed,
        ..ConsistencyConfig::at_scale(sc)
    };
    let cons = ex::consistency(&consistency_config).map_err(err)?;
    let align = ex::fig5_alignment(&f56).map_err(err)?;
    bar.inc(1);
    bar.finish_and_clear();

    let mut figures = Vec::new();
    let mut fig = |file: &str, caption: String| {
        figures.push(Figure {
            file: file.into(),
            caption,
        })
    };

    // Fig. 3: inputs.
    line::render(
        &ctx.path("dredge-fig3-inputs.png"),
        &plot(
            "Fig. 3: incoming mixture",
            "ρᵢ (kg/m³); Qᵢ × 100 (m³/s)",
            vec![
                series("ρᵢ (kg/m³)", &c.t, c.rho_i.iter().copied()),
                series("Qᵢ × 100 (m³/s)", &c.t, c.q_i.iter().map(|q| q * 100.0)),
            ],
            LegendPos::LowerRight,
        ),
    )?;
    fig(
        "dredge-fig3-inputs.png",
        "Fig. 3. Paper: flow-rate and density of the incoming mixture of one real cycle. Ours: \
         the simulator's inputs (Qᵢ scaled by 100 to share the axis): the dredge pump's flow \
         and the mixture density, the measured disturbance."
            .into(),
    );

    // Fig. 4: loading phases.
    let m_kt: Vec<f64> = c.m_t.iter().map(|m| m / 1e3).collect();
    let hi = c
        .v_t
        .iter()
        .chain(&m_kt)
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    let mut s4 = vec![
        series("mₜ (tonnes)", &c.t, m_kt.iter().copied()),
        series("Vₜ (m³)", &c.t, c.v_t.iter().copied()),
        thin(
            series("hₒ × 1000 (m)", &c.t, c.h_o.iter().map(|h| h * 1000.0)),
            stride(c.len()),
        ),
    ];
    // Phase 2 as one dotted bracket (up at its start, across, down at its end): a fifth
    // series would reuse the first series' look.
    if let (Some(k2), Some(k3)) = (c.phase2_start, c.phase3_start) {
        let (a, b) = (c.t[k2], c.t[k3]);
        s4.push(series(
            "phase 2 (inside the dotted bracket)",
            &[a, a, b, b],
            [0.0, hi, hi, 0.0],
        ));
    }
    line::render(
        &ctx.path("dredge-fig4-phases.png"),
        &plot(
            "Fig. 4: loading phases",
            "mₜ (tonnes); Vₜ (m³); hₒ × 1000 (m)",
            s4,
            LegendPos::LowerRight,
        ),
    )?;
    fig(
        "dredge-fig4-phases.png",
        "Fig. 4. Paper: hopper mass and volume of a real cycle as the overflow height is \
         manipulated, phase transitions dashed. Ours (phase 2 bracketed): the simulated \
         cycle (true mₜ, Vₜ, and hₒ); phase 1 fills without overflow, in phase 2 Vₜ levels \
         off once the overflow carries as much as the pump brings (Qₒ ≈ Qᵢ) while mₜ still \
         rises, in phase 3 the PID on hₒ holds mₜ at m_max while Vₜ falls."
            .into(),
    );

    // Fig. 5: estimates in phase 3.
    line::render(
        &ctx.path("dredge-fig5-estimates.png"),
        &plot(
            "Fig. 5: simulated and estimated overflow, phase 3",
            "ρₒ (kg/m³); Qₒ × 100 (m³/s)",
            vec![
                series("ρₒ simulated", &f56.t, f56.rho_o_true.iter().copied()),
                series("ρₒ PF estimate", &f56.t, f56.rho_o_hat.iter().copied()),
                thin(
                    series(
                        "Qₒ × 100 simulated",
                        &f56.t,
                        f56.q_o_true.iter().map(|q| q * 100.0),
                    ),
                    stride(f56.t.len()),
                ),
                thin(
                    series(
                        "Qₒ × 100 PF estimate",
                        &f56.t,
                        f56.q_o_hat.iter().map(|q| q * 100.0),
                    ),
                    stride(f56.t.len()),
                ),
            ],
            LegendPos::UpperLeft,
        ),
    )?;
    fig(
        "dredge-fig5-estimates.png",
        format!(
            "Fig. 5. Paper: simulated (thin) and PF-estimated (thick) Qₒ and ρₒ in phase 3. \
             Ours: the same with N = {}, σ(ε_x) = [0, 3000, 0.2, 5], σ(ε_y) = [10, 12000]. \
             ρₒ is tracked well while it is flat and lags on the fast rises and falls of our \
             simulated ρₒ (see notes): shifting the estimate back by {:.0} s matches the two \
             best.",
            fig5_6_config.filter.n_particles,
            f56.rho_o_lag()
        ),
    );

    // Fig. 6: residual histograms.
    let panel = |name: &str, unit: &str, h: &ex::Histogram, r: &ex::ResidualReport| HistPanel {
        title: format!("{name} residual (simulated − estimated)"),
        x_label: format!("{name} residual ({unit})"),
        y_label: "samples".into(),
        data: HistData::Binned {
            edges: h.edges.clone(),
            counts: h.counts.clone(),
        },
        stats: Some((
            HistStats {
                mean: r.ours.mean,
                std: r.ours.std,
                max_abs: r.ours.max_abs,
            },
            unit.into(),
        )),
    };
    histogram::render(
        &ctx.path("dredge-fig6-residuals.png"),
        &HistogramPlot {
            title: "Fig. 6: residual distributions, phase 3".into(),
            panels: vec![
                panel("Qₒ", "m³/s", &f56.q_o_hist, &f56.q_o),
                panel("ρₒ", "kg/m³", &f56.rho_o_hist, &f56.rho_o),
            ],
        },
    )?;
    fig(
        "dredge-fig6-residuals.png",
        format!(
            "Fig. 6. Paper: residual histograms, Qₒ mean −0.023, std 0.345 m³/s; ρₒ mean \
             3.613, std 13.226 kg/m³. Ours: Qₒ mean {:.3}, std {:.3} m³/s; ρₒ mean {:.2}, \
             std {:.2} kg/m³ (table dredge-residuals puts them beside the paper's, relative to \
             the signal ranges).",
            f56.q_o.ours.mean, f56.q_o.ours.std, f56.rho_o.ours.mean, f56.rho_o.ours.std
        ),
    );

    // Fig. 7: PF against direct computation.
    let t7 = &f7.t;
    // ρ̄ₒ of (16) divides by a noisy Q̄ₒ: where Q̄ₒ is barely above the threshold (phase
    // 1, filter start-up at the edges) it shoots to thousands; the axis is held to the
    // range of the PF estimate so the overflow period stays readable.
    let rho_top = f7.rho_o_pf.iter().copied().fold(1100.0, f64::max) * 1.3;
    let mut p7 = plot(
        "Fig. 7: PF against direct computation (15)–(16)",
        "ρₒ (kg/m³); Qₒ × 100 (m³/s)",
        vec![
            series("ρₒ PF", t7, f7.rho_o_pf.iter().copied()),
            defined("ρₒ direct", t7, &f7.rho_o_direct, 1.0),
            thin(
                series("Qₒ × 100 PF", t7, f7.q_o_pf.iter().map(|q| q * 100.0)),
                stride(t7.len()),
            ),
            thin(
                defined("Qₒ × 100 direct", t7, &f7.q_o_direct, 100.0),
                stride(t7.len()),
            ),
        ],
        // The lower right is empty: Qₒ and ρₒ both run high there.
        LegendPos::LowerRight,
    );
    p7.y_range = Some((-50.0, rho_top));
    line::render(&ctx.path("dredge-fig7-direct.png"), &p7)?;
    fig(
        "dredge-fig7-direct.png",
        format!(
            "Fig. 7. Paper: on real data, PF estimates (thick) against the direct computation \
             (15)–(16) on zero-phase low-passed (0.001 Hz) Vₜ, mₜ (thin). Ours: the same on \
             the simulated cycle (we have no ship data); ρ̄ₒ is left out where Q̄ₒ < 0.5 \
             m³/s, and the axis is clipped at 1.3 × the PF's largest ρₒ: in phase 1 ρ̄ₒ \
             divides by a Q̄ₒ that is only start-up noise and reaches thousands.{} The \
             direct computation is anti-causal, so it cannot run on line.",
            match f7.q_o_direct.iter().flatten().next() {
                Some(q) => format!(
                    " The direct Q̄ₒ starts at {q:.1} m³/s where no overflow runs yet: the \
                     zero-phase filter's transient at the record's edge."
                ),
                None => String::new(),
            }
        ),
    );

    // Fig. 8: 25-run band.
    let t8 = &f8.t;
    line::render(
        &ctx.path("dredge-fig8-band.png"),
        &plot(
            "Fig. 8: spread of ρₒ estimates over independent runs",
            "ρₒ (kg/m³)",
            vec![
                Series {
                    name: format!("mean of {} runs, min–max", fig8_config.runs),
                    x: t8.clone(),
                    y: f8.rho_o.mean.clone(),
                    band: Some(Band {
                        lower: f8.rho_o.min.clone(),
                        upper: f8.rho_o.max.clone(),
                    }),
                },
                series("ρₒ simulated", t8, f8.rho_o_true.iter().copied()),
            ],
            LegendPos::UpperLeft,
        ),
    )?;
    fig(
        "dredge-fig8-band.png",
        format!(
            "Fig. 8. Paper: grey band = min–max of ρₒ estimates over 25 independent PF runs on \
             the same real data, bold = their mean. Ours: {} runs with N = {} on one simulated \
             cycle; mean band width in phase 3: {:.1} kg/m³.",
            fig8_config.runs, fig8_config.filter.n_particles, f8.mean_rho_o_width_phase3
        ),
    );

    // N sweep.
    let n: Vec<f64> = ns.rows.iter().map(|r| r.n as f64).collect();
    let band = |m: &dyn Fn(&ex::NSweepRow) -> (f64, f64), k: f64| Band {
        lower: ns
            .rows
            .iter()
            // A std is never negative: the band stops at 0.
            .map(|r| ((m(r).0 - 2.0 * m(r).1) * k).max(0.0))
            .collect(),
        upper: ns
            .rows
            .iter()
            .map(|r| (m(r).0 + 2.0 * m(r).1) * k)
            .collect(),
    };
    let mut sweep = plot(
        "Residual std against the number of particles N",
        "ρₒ std (kg/m³); Qₒ std × 10 (m³/s)",
        vec![
            Series {
                name: "ρₒ residual std, ± 2 s.e.".into(),
                x: n.clone(),
                y: ns.rows.iter().map(|r| r.rho_o_std).collect(),
                band: Some(band(&|r| (r.rho_o_std, r.rho_o_std_se), 1.0)),
            },
            Series {
                name: "Qₒ residual std × 10, ± 2 s.e.".into(),
                x: n.clone(),
                y: ns.rows.iter().map(|r| r.q_o_std * 10.0).collect(),
                band: Some(band(&|r| (r.q_o_std, r.q_o_std_se), 10.0)),
            },
        ],
        LegendPos::UpperRight,
    );
    sweep.x_label = "number of particles N".into();
    sweep.x_scale = AxisScale::Log10;
    line::render(&ctx.path("dredge-n-sweep.png"), &sweep)?;
    fig(
        "dredge-n-sweep.png",
        format!(
            "Beyond the paper: phase-3 residual std against N ({} replications per N on the \
             figures' cycle, band ± 2 standard errors), to choose N for the on-board time \
             budget. Below a few hundred particles some runs lose the track of ρₒ (wide band \
             at N = 100). Its ρₒ std is {}.",
            n_sweep_config.reps,
            sweep_rho_std(&ns, fig5_6_config.filter.n_particles)
        ),
    );

    // Residual table.
    let q = &f56.q_o;
    let r = &f56.rho_o;
    let d = &f7.direct_residuals;
    let dstd = |s: Option<pf_core::metrics::ResidualSummary>| {
        s.map_or("–".to_owned(), |s| format!("{:.3}", s.std))
    };
    let pm = |m: ex::MeanSe, digits: usize| format!("{:.*} ± {:.*}", digits, m.mean, digits, m.se);
    let row = |name: &str,
               x: &ex::ResidualReport,
               direct: String,
               a: &Alignment,
               m: &ex::ConsistencySignal| {
        vec![
            name.to_owned(),
            format!("{}", x.paper.mean),
            format!("{}", x.paper.std),
            format!("≈ {}", x.paper.max_abs_about),
            format!("≈ {}", x.paper.nominal_range),
            format!("{:.1} %", 100.0 * x.paper.std / x.paper.nominal_range),
            format!("{:.3}", x.ours.mean),
            format!("{:.3}", x.ours.std),
            format!("{:.3}", x.ours.max_abs),
            format!("{:.3}", x.signal_range),
            format!("{:.1} %", 100.0 * x.relative_std),
            direct,
            format!("{:.3}", a.against_k_minus_1.std),
            pm(m.residual_std, 3),
            format!("{:.3}", m.posterior_sd.mean),
        ]
    };
    let mut tables = vec![Table {
        id: "residuals".into(),
        caption: "Phase-3 residuals (simulated − PF estimate), the paper's (Section V-B, Fig. 6) \
                  beside ours; ranges are the signal ranges (paper: its \"nominal\" range, from \
                  max |·| ≈ 10 % of it), std / range makes the two comparable. \"direct std\": the \
                  direct computation's (15)–(16) residual std in phase 3, where defined. \
                  \"our std vs k−1\": our estimate at k against the truth of sample k − 1 (the \
                  flow that made the measurement at k). Last two: the same filter on data drawn \
                  from its own model (13) over our phase 3 (table dredge-consistency): residual \
                  std (mean ± s.e. over the runs) and the filter's posterior sd; paper → model \
                  (13) → ours shows how much of the gap is the filter and how much the scenario."
            .into(),
        header: [
            "signal",
            "paper mean",
            "paper std",
            "paper max |·|",
            "paper range",
            "paper std/range",
            "our mean",
            "our std",
            "our max |·|",
            "our range",
            "our std/range",
            "direct std",
            "our std vs k−1",
            "model (13) std",
            "model (13) posterior sd",
        ]
        .map(String::from)
        .to_vec(),
        rows: vec![
            row("Qₒ (m³/s)", q, dstd(d.q_o), &align[0], &cons.q_o),
            row("ρₒ (kg/m³)", r, dstd(d.rho_o), &align[1], &cons.rho_o),
        ],
    }];

    let crow = |name: &str, m: &ex::ConsistencySignal, spaced: f64, a: &Alignment, d: usize| {
        vec![
            name.to_owned(),
            pm(m.nees, 2),
            format!("{spaced:.2}"),
            pm(m.residual_std, d),
            pm(m.posterior_sd, d),
            pm(m.residual_std_k_minus_1, d),
            format!("{:.*}", d, a.against_k.std),
            format!("{:.*}", d, a.against_k_minus_1.std),
        ]
    };
    tables.push(Table {
        id: "consistency".into(),
        caption: format!(
            "Beyond the paper: the filter (N = {}) on {} data sets drawn from its own model \
             (13) over our phase 3 ({} samples: our cycle's ρᵢ and times, Qᵢ holding the \
             volume on the measurements, prior Qₒ ~ N({:.2}, {}²), ρₒ ~ N({:.0}, {}²) for data \
             and filter). NEES = (truth − estimate)² / posterior variance, mean 1 for a consistent \
             filter (joint: (Qₒ, ρₒ) with the covariance, halved), as mean ± s.e. over runs and \
             as the mean of {} values {} samples apart. Alignment: residual std against the \
             truth of sample k (the average over [t_k, t_k+1)) and of k − 1, on model-(13) \
             data and on our simulator (Fig. 5's run).",
            consistency_config.filter.n_particles,
            consistency_config.runs,
            cons.samples,
            cons.prior.q_o_mean,
            cons.prior.q_o_std,
            cons.prior.rho_o_mean,
            cons.prior.rho_o_std,
            cons.spaced_count,
            consistency_config.spacing,
        ),
        header: [
            "signal",
            "NEES",
            "NEES, spaced",
            "model (13) std vs k",
            "model (13) posterior sd",
            "model (13) std vs k−1",
            "simulator std vs k",
            "simulator std vs k−1",
        ]
        .map(String::from)
        .to_vec(),
        rows: vec![
            crow(
                "Qₒ (m³/s)",
                &cons.q_o,
                cons.spaced_nees_mean[0],
                &align[0],
                3,
            ),
            crow(
                "ρₒ (kg/m³)",
                &cons.rho_o,
                cons.spaced_nees_mean[1],
                &align[1],
                1,
            ),
            vec![
                "(Qₒ, ρₒ) joint / 2".into(),
                pm(cons.joint_nees, 2),
                format!("{:.2}", cons.spaced_nees_mean[2]),
                "".into(),
                "".into(),
                "".into(),
                "".into(),
                "".into(),
            ],
        ],
    });

    let notes = vec![
        format!(
            "Qₒ: our residual std {:.3} m³/s against the paper's 0.345; a linearised Kalman \
             filter with the paper's noise levels (σ(ε_x) = [0, 3000, 0.2, 5], σ(ε_y) = [10, \
             12000], T_s = 5 s, Qₒ ≈ 9 m³/s, ρₒ ≈ 1200 kg/m³) has a steady-state posterior std \
             of 0.40 m³/s for Qₒ, so both are at what these noise levels allow.",
            q.ours.std
        ),
        format!(
            "ρₒ: our residual std {:.1} kg/m³ is about {:.1}× the paper's 13.2 ({:.1} % of our \
             range {:.0} kg/m³ against about 3.3 % of the paper's ≈ 400). Found out, not \
             guessed: (1) not Monte Carlo error: over the N sweep's replications the std is \
             {}; {}; (3) it is our \
             simulator's ρₒ: when the sand bed reaches the overflow the linear profile (6) \
             makes ρₒ rise by ~200 kg/m³ in ~150 s, and the PID moving hₒ through the steep \
             profile swings it by ±100 kg/m³ within minutes. The random walk σ(ε_x4) = 5 kg/m³ \
             per 5 s gives the linearised filter an ~85 s lag (a shift of {:.0} s best \
             realigns this run's estimate, Fig. 5; a 0.5 kg/m³-per-step ramp alone costs a \
             ~9 kg/m³ bias, hence our positive mean); these transients make the excess. The \
             paper's own tuning has a steady-state ρₒ posterior std of 21 kg/m³ in the \
             linearised filter, so its 13.2 implies a smoother simulated ρₒ than ours.",
            r.ours.std,
            r.ours.std / 13.226,
            100.0 * r.relative_std,
            r.signal_range,
            sweep_rho_std(&ns, fig5_6_config.filter.n_particles),
            flat_stretch_note(f56.rho_o_flat_stretch()),
            f56.rho_o_lag(),
        ),
        format!(
            "The filter against its own model (table dredge-consistency): on data drawn from \
             model (13) over our phase 3, Qₒ is consistent (NEES {}, residual std {} against \
             posterior sd {} m³/s), and ρₒ's residual std is {} kg/m³ against a posterior sd \
             of {} (NEES {}; at N = {} the particle approximation adds Monte Carlo error to \
             ρ̂ₒ, at N = 10 000 the NEES is 1.01 ± 0.04, crate README). So the paper's tuning, \
             on a ρₒ that moves as its own random walk, leaves about {:.0} kg/m³: of the gap \
             from the paper's 13.2 to our {:.1}, the part above {:.0} is our scenario (the \
             transients of point 3), the part below it says the paper's simulated ρₒ was \
             smoother than the filter's random walk.",
            pm(cons.q_o.nees, 2),
            pm(cons.q_o.residual_std, 3),
            pm(cons.q_o.posterior_sd, 3),
            pm(cons.rho_o.residual_std, 1),
            pm(cons.rho_o.posterior_sd, 1),
            pm(cons.rho_o.nees, 2),
            consistency_config.filter.n_particles,
            cons.rho_o.residual_std.mean,
            r.ours.std,
            cons.rho_o.residual_std.mean,
        ),
        format!(
            "Alignment: the truth at k is the average over [t_k, t_k+1), the flow that moves \
             V_k to V_k+1; the estimate at k has seen V_k and m_k, made by the flow of sample \
             k − 1, and under the random walks (11)–(12) it is at once the filtered value of \
             k − 1 and the prediction of k. Against the truth of k − 1 our Qₒ residual std is \
             {:.3} m³/s on the simulator and {} on model-(13) data, against k {:.3} and {}: \
             the paper's 0.345 is below the {:.3} that its filter's own posterior gives for \
             Qₒ,k (the volume equation is linear, so this sd does not depend on the scenario) \
             and at what the pairing with k − 1 gives. So Fig. 5 most likely shows the \
             estimate at t_k beside the flow that produced the measurement at t_k (a \
             simulator sampled at the end of each period); a pairing with k would need a \
             simulated Qₒ much smoother than the filter's random walk. For ρₒ \
             the pairing moves the std little ({:.1} → {:.1} kg/m³ on the simulator): its \
             error is the lag, not the half-sample.",
            align[0].against_k_minus_1.std,
            pm(cons.q_o.residual_std_k_minus_1, 3),
            align[0].against_k.std,
            pm(cons.q_o.residual_std, 3),
            cons.q_o.posterior_sd.mean,
            align[1].against_k.std,
            align[1].against_k_minus_1.std,
        ),
        "Values the paper leaves unstated, chosen physically plausible (crate README lists them \
         with units): hopper area A, k_o, k'_o, k_c, v_s, β, ρ_q, ρ_s, ρ_w, the inflow \
         profiles, PID gains, m_max; the prior p(x_0) (centred on the first measurement); the \
         direct computation's threshold Q̄ₒ ≥ 0.5 m³/s below which (16) is not divided."
            .into(),
        "Figs. 3, 5 and 7 draw two signals of different units on one axis, Q scaled by 100; the \
         paper's Fig. 7 and 8 are on real ship data, which we do not have: ours are on the \
         simulated cycle."
            .into(),
    ];

    #[cfg_attr(not(feature = "rrd"), allow(unused_mut))] // only the recording adds files
    let mut files = Vec::new();
    if ctx.write_rrd() {
        #[cfg(feature = "rrd")]
        {
            let run = ex::online(&ex::OnlineConfig {
                cycle: cycle_config,
                filter: fig5_6_config.filter,
                ..ex::OnlineConfig::at_scale(ctx.scale)
            })
            .map_err(err)?;
            crate::rrd::dredge::save(&ctx.path("dredge.rrd"), &run)?;
            files.push("dredge.rrd".to_owned());
        }
    }

    let result = to_json(
        ctx,
        &DredgeResult {
            seed,
            cycle_config,
            cycle: c,
            fig5_6_config,
            fig5_6: f56,
            fig7_config,
            fig7: f7,
            fig8_config,
            fig8: f8,
            n_sweep_config,
            n_sweep: ns,
            fig5_alignment: align,
            consistency_config,
            consistency: cons,
        },
    )?;
    Ok(SectionReport {
        result,
        figures,
        tables,
        notes,
        files,
        timing_dependent: vec![],
    })
}
