//! `epf.rrd`: the example run of each scenario of [`pf_epf::experiments::section4`] on the
//! `frame` timeline.
//!
//! | entity | archetype | at frame `f` |
//! |---|---|---|
//! | `epf/<scenario>/scene/truth` | `LineStrips2D` | the true paths up to `f`, light grey |
//! | `epf/<scenario>/scene/detections` | `Points2D` | the detections of `f` (clutter included), white |
//! | `epf/<scenario>/<method>/particles/T<k>` | `Points2D` | target `k`'s particle cloud after the update |
//! | `epf/<scenario>/<method>/tracks` | `LineStrips2D` | the estimated paths up to `f`, labelled `T<k>` |
//! | `epf/<scenario>/<method>/associations` | `LineStrips2D` | estimate → associated detection |
//! | `epf/<scenario>/<method>/gates` | `LineStrips2D` | the validation ellipses around `Â(f)` |
//!
//! `<method>` is `epf` or `nnsf`. Rerun's 2D y-axis points down, so points are logged at
//! `(x, −y)` to keep the plane the right way up.

use std::path::Path;

use pf_epf::experiments::{ScenarioResult, Section4Result};
use rerun::components::Radius;
use rerun::{LineStrips2D, Points2D, RecordingStream};

use super::layout::{self, Node, View};
use super::{FRAME, rrd_err, save_rrd};
use crate::error::Result;

const TRUTH: [u8; 4] = [170, 170, 170, 255];
/// White: the viewer's background is dark.
const DETECTION: [u8; 4] = [240, 240, 240, 255];
/// Per-target colours (Rerun is interactive, so colour may carry the target).
const TARGET: [[u8; 4]; 6] = [
    [31, 119, 180, 255],
    [214, 39, 40, 255],
    [44, 160, 44, 255],
    [148, 103, 189, 255],
    [255, 127, 14, 255],
    [23, 190, 207, 255],
];

fn flip(p: [f64; 2]) -> [f32; 2] {
    [p[0] as f32, -p[1] as f32]
}

fn method_path(label: &str) -> &'static str {
    if label == "EPF" { "epf" } else { "nnsf" }
}

/// Write `epf.rrd` (atomically).
///
/// # Errors
/// A Rerun or I/O error naming `path`.
pub fn save(path: &Path, result: &Section4Result) -> Result<()> {
    save_rrd(path, "pf-viz: energetic particle filter", |rec, path| {
        layout::send(rec, &blueprint(result), Some(FRAME)).map_err(rrd_err(path))?;
        for s in &result.scenarios {
            log_scenario(rec, path, s)?;
        }
        Ok(())
    })
}

fn log_scenario(rec: &RecordingStream, path: &Path, s: &ScenarioResult) -> Result<()> {
    let err = rrd_err(path);
    let root = format!("epf/{}", s.scenario.name());
    for (fi, &f) in s.frames.iter().enumerate() {
        rec.set_time_sequence(FRAME, f);
        rec.log(
            format!("{root}/scene/truth"),
            &LineStrips2D::new(s.truth.iter().map(|t| {
                t.position[..=fi]
                    .iter()
                    .map(|&p| flip(p))
                    .collect::<Vec<_>>()
            }))
            .with_colors([TRUTH])
            .with_radii([Radius::new_ui_points(1.0)])
            .with_draw_order(1.0),
        )
        .map_err(&err)?;
        let dets: Vec<[f32; 2]> = s
            .detections
            .iter()
            .filter(|d| d.frame == f)
            .map(|d| flip(d.position))
            .collect();
        rec.log(
            format!("{root}/scene/detections"),
            &Points2D::new(dets)
                .with_colors([DETECTION])
                .with_radii([Radius::new_ui_points(4.0)])
                .with_draw_order(30.0),
        )
        .map_err(&err)?;
        for (m, res) in &s.example {
            let mroot = format!("{root}/{}", method_path(m.label()));
            let Some(ri) = res.frames.iter().position(|&x| x == f) else {
                continue;
            };
            let frame = &res.records[ri];
            for (k, t) in frame.targets.iter().enumerate() {
                rec.log(
                    format!("{mroot}/particles/T{}", k + 1),
                    &Points2D::new(t.particles.iter().map(|&p| flip(p)))
                        .with_colors([{
                            let mut c = TARGET[k % TARGET.len()];
                            c[3] = 90;
                            c
                        }])
                        .with_radii([Radius::new_ui_points(1.5)])
                        .with_draw_order(5.0),
                )
                .map_err(&err)?;
            }
            let colors: Vec<[u8; 4]> = (0..res.tracks.len())
                .map(|k| TARGET[k % TARGET.len()])
                .collect();
            rec.log(
                format!("{mroot}/tracks"),
                &LineStrips2D::new(res.tracks.iter().map(|t| {
                    t.position[..=ri]
                        .iter()
                        .map(|&p| flip(p))
                        .collect::<Vec<_>>()
                }))
                .with_colors(colors.clone())
                .with_labels(res.tracks.iter().map(|t| format!("T{}", t.target + 1)))
                .with_radii([Radius::new_ui_points(2.0)])
                .with_draw_order(20.0),
            )
            .map_err(&err)?;
            let (assoc, assoc_colors): (Vec<Vec<[f32; 2]>>, Vec<[u8; 4]>) = frame
                .targets
                .iter()
                .enumerate()
                .filter_map(|(k, t)| {
                    t.detection.map(|j| {
                        let y = s.detections[j].position;
                        (vec![flip(t.estimate), flip(y)], TARGET[k % TARGET.len()])
                    })
                })
                .unzip();
            rec.log(
                format!("{mroot}/associations"),
                &LineStrips2D::new(assoc)
                    .with_colors(assoc_colors)
                    .with_radii([Radius::new_ui_points(1.5)])
                    .with_draw_order(25.0),
            )
            .map_err(&err)?;
            rec.log(
                format!("{mroot}/gates"),
                &LineStrips2D::new(frame.targets.iter().map(|t| {
                    let mut pts: Vec<[f32; 2]> = t.gate.points(72).into_iter().map(flip).collect();
                    pts.push(pts[0]);
                    pts
                }))
                .with_colors(colors)
                .with_radii([Radius::new_ui_points(1.0)])
                .with_draw_order(15.0),
            )
            .map_err(&err)?;
        }
    }
    Ok(())
}

fn blueprint(result: &Section4Result) -> Node {
    let rows = result.scenarios.iter().map(|s| {
        let root = format!("/epf/{}", s.scenario.name());
        let view = |method: &str, label: &str| {
            View::spatial_2d(format!("{}: {label}", s.scenario.name()), root.clone())
                .with_contents([
                    format!("+ {root}/scene/**"),
                    format!("+ {root}/{method}/**"),
                ])
                .into()
        };
        layout::horizontal([
            view("epf", "EPF (energy association)"),
            view("nnsf", "NNSF (nearest neighbour)"),
        ])
    });
    layout::vertical(rows)
}
