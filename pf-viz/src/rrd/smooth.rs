//! `smooth.rrd`: the genealogy of Fig. 1 on the `step` timeline (`smooth/genealogy/…`,
//! `smooth/ess`) and the stochastic EM chains of Fig. 4 on the `iteration` timeline
//! (`smooth/sem/<parameter>/chain_<c>` and `…/exact`). The blueprint puts the genealogy on
//! the left and one time series view per parameter on the right.

use std::path::Path;

use pf_smooth::ar1::Theta;
use pf_smooth::cli::SemOutput;
use rerun::blueprint::{
    Blueprint, BlueprintActivation, Horizontal, Spatial2DView, TimeSeriesView, Vertical,
};
use rerun::{Scalars, SeriesLines};

use super::genealogy::{GenealogyExtras, log_genealogy};
use super::{ITERATION, rrd_err, save_rrd};
use crate::error::Result;
use crate::png::genealogy::GenealogyData;

const EXACT: [u8; 4] = [240, 240, 240, 255];
const CHAINS: [[u8; 4]; 4] = [
    [90, 160, 255, 255],
    [240, 170, 40, 255],
    [120, 220, 120, 255],
    [230, 90, 230, 255],
];
const PARAMS: [(&str, &str); 3] = [("phi", "φ"), ("sigma2", "σ²"), ("rho2", "ρ²")];

fn value(t: &Theta, p: &str) -> f64 {
    match p {
        "phi" => t.phi,
        "sigma2" => t.sigma2,
        _ => t.rho2,
    }
}

/// Write `smooth.rrd`.
///
/// # Errors
/// Inconsistent genealogy data, or a Rerun or I/O error naming `path`.
pub fn save(
    path: &Path,
    data: &GenealogyData,
    extras: &GenealogyExtras<'_>,
    sem: &SemOutput,
) -> Result<()> {
    data.validate()?;
    save_rrd(path, "pf-viz: Cappé & Moulines", |rec, path| {
        let err = rrd_err(path);
        blueprint()
            .send(rec, BlueprintActivation::default())
            .map_err(&err)?;
        log_genealogy(rec, path, data, extras, "smooth")?;
        for (p, sym) in PARAMS {
            rec.log_static(
                format!("smooth/sem/{p}/exact"),
                &SeriesLines::new()
                    .with_names([format!("exact EM {sym}")])
                    .with_colors([EXACT])
                    .with_widths([3.0]),
            )
            .map_err(&err)?;
            for c in 0..sem.sem.len() {
                rec.log_static(
                    format!("smooth/sem/{p}/chain_{c}"),
                    &SeriesLines::new()
                        .with_names([format!("SEM chain {} {sym}", c + 1)])
                        .with_colors([CHAINS[c % CHAINS.len()]])
                        .with_widths([1.5]),
                )
                .map_err(&err)?;
            }
        }
        for (i, exact) in sem.exact.iter().enumerate() {
            rec.set_time_sequence(ITERATION, i as i64);
            for (p, _) in PARAMS {
                rec.log(
                    format!("smooth/sem/{p}/exact"),
                    &Scalars::single(value(exact, p)),
                )
                .map_err(&err)?;
                for (c, chain) in sem.sem.iter().enumerate() {
                    if let Some(t) = chain.get(i) {
                        rec.log(
                            format!("smooth/sem/{p}/chain_{c}"),
                            &Scalars::single(value(t, p)),
                        )
                        .map_err(&err)?;
                    }
                }
            }
        }
        Ok(())
    })
}

fn blueprint() -> Blueprint {
    Blueprint::new(
        Horizontal::new([
            Vertical::new([
                Spatial2DView::new("Fig. 1: genealogy (x: step k, y: position ξ)")
                    .with_origin("smooth/genealogy")
                    .into(),
                TimeSeriesView::new("effective sample size (step)")
                    .with_origin("smooth/ess")
                    .into(),
            ])
            .with_row_shares([3.0, 1.0])
            .into(),
            Vertical::new(PARAMS.iter().map(|(p, sym)| {
                TimeSeriesView::new(format!(
                    "Fig. 4: SEM chains and exact EM, {sym} (iteration)"
                ))
                .with_origin(format!("smooth/sem/{p}"))
                .into()
            }))
            .into(),
        ])
        .with_column_shares([3.0, 2.0]),
    )
}
