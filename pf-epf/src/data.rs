//! Unlabelled detections per frame and each target's first positions: the tracker's input.
//!
//! Frames are integers; a missed frame simply has no row. Row indices are 0-based in file
//! order (header excluded), the contract of `pf-viz epf track`.

use crate::error::{EpfError, Result};
use crate::geometry::Vec2;
use std::ops::Range;

/// One detection: a position at a frame, with the target that produced it when known
/// (simulations; `None` = clutter or unknown).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Detection {
    /// Frame.
    pub frame: i64,
    /// Position `y_j` in the image plane.
    pub position: Vec2,
    /// The true source: a target id, or `None` for clutter (or unlabelled data).
    pub target: Option<i64>,
}

/// The largest frame magnitude, 2⁵³: every frame, and every difference of two, is then an
/// exact `f64` and an `i64` that cannot overflow.
const MAX_FRAME: i64 = 1 << 53;

/// `Ok` for a frame within ±[`MAX_FRAME`].
fn check_frame(file: &'static str, row: usize, frame: i64) -> Result<()> {
    if (-MAX_FRAME..=MAX_FRAME).contains(&frame) {
        Ok(())
    } else {
        Err(EpfError::FrameOutOfRange { file, row, frame })
    }
}

/// Detections in frame order, validated.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Detections {
    rows: Vec<Detection>,
}

impl Detections {
    /// Validate `rows`: finite coordinates, frames within ±2⁵³ and never decreasing.
    ///
    /// # Errors
    /// [`EpfError::NonFiniteData`], [`EpfError::FrameOutOfRange`] or
    /// [`EpfError::FrameBackwards`] naming the row.
    pub fn new(rows: Vec<Detection>) -> Result<Self> {
        for (row, d) in rows.iter().enumerate() {
            check_frame("detections", row, d.frame)?;
            for (what, value) in [("x", d.position.x), ("y", d.position.y)] {
                if !value.is_finite() {
                    return Err(EpfError::NonFiniteData {
                        file: "detections",
                        row,
                        what,
                        value,
                    });
                }
            }
            if row > 0 && d.frame < rows[row - 1].frame {
                return Err(EpfError::FrameBackwards {
                    file: "detections",
                    row,
                    frame: d.frame,
                    previous: rows[row - 1].frame,
                });
            }
        }
        Ok(Detections { rows })
    }

    /// All rows, in file order.
    pub fn rows(&self) -> &[Detection] {
        &self.rows
    }

    /// The distinct frames, increasing.
    pub fn frames(&self) -> Vec<i64> {
        let mut f: Vec<i64> = self.rows.iter().map(|d| d.frame).collect();
        f.dedup();
        f
    }

    /// The rows of `frame` (empty when it has none).
    pub fn frame_rows(&self, frame: i64) -> Range<usize> {
        let lo = self.rows.partition_point(|d| d.frame < frame);
        let hi = self.rows.partition_point(|d| d.frame <= frame);
        lo..hi
    }

    /// The positions of `frame`'s detections into `ys` (cleared first, so a caller's buffer is
    /// reused frame after frame); returns their rows, whose start maps an index into `ys` back
    /// to its row.
    pub fn positions_into(&self, frame: i64, ys: &mut Vec<Vec2>) -> Range<usize> {
        let rows = self.frame_rows(frame);
        ys.clear();
        ys.extend(self.rows[rows.clone()].iter().map(|d| d.position));
        rows
    }
}

/// One init row: a target's position at one of its first frames.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InitRow {
    /// Target id.
    pub target: i64,
    /// Frame.
    pub frame: i64,
    /// Position.
    pub position: Vec2,
}

/// A target's first positions, frames increasing.
#[derive(Debug, Clone, PartialEq)]
pub struct TargetInit {
    /// Target id.
    pub id: i64,
    /// `(frame, position)`, at least two, frames strictly increasing.
    pub points: Vec<(i64, Vec2)>,
}

/// Every target's first positions, in order of first appearance.
#[derive(Debug, Clone, PartialEq)]
pub struct Init {
    targets: Vec<TargetInit>,
}

impl Init {
    /// Group `rows` by target and validate them.
    ///
    /// # Errors
    /// [`EpfError::NoTargets`]; [`EpfError::NonFiniteData`]; [`EpfError::FrameOutOfRange`];
    /// [`EpfError::FrameBackwards`] when a target's frames decrease; [`EpfError::DuplicateInitFrame`];
    /// [`EpfError::TooFewInitFrames`] when a target has fewer than the two frames the
    /// energies need (`Â(t−2)` and `Â(t−1)`).
    pub fn new(rows: &[InitRow]) -> Result<Self> {
        let mut targets: Vec<TargetInit> = Vec::new();
        for (row, r) in rows.iter().enumerate() {
            check_frame("init", row, r.frame)?;
            for (what, value) in [("x", r.position.x), ("y", r.position.y)] {
                if !value.is_finite() {
                    return Err(EpfError::NonFiniteData {
                        file: "init",
                        row,
                        what,
                        value,
                    });
                }
            }
            let t = match targets.iter_mut().position(|t| t.id == r.target) {
                Some(i) => &mut targets[i],
                None => {
                    targets.push(TargetInit {
                        id: r.target,
                        points: Vec::new(),
                    });
                    targets.last_mut().expect("just pushed")
                }
            };
            if let Some(&(previous, _)) = t.points.last() {
                if r.frame < previous {
                    return Err(EpfError::FrameBackwards {
                        file: "init",
                        row,
                        frame: r.frame,
                        previous,
                    });
                }
                if r.frame == previous {
                    return Err(EpfError::DuplicateInitFrame {
                        target: r.target,
                        frame: r.frame,
                    });
                }
            }
            t.points.push((r.frame, r.position));
        }
        if targets.is_empty() {
            return Err(EpfError::NoTargets);
        }
        if let Some(t) = targets.iter().find(|t| t.points.len() < 2) {
            return Err(EpfError::TooFewInitFrames {
                target: t.id,
                frames: t.points.len(),
            });
        }
        Ok(Init { targets })
    }

    /// The targets, in order of first appearance.
    pub fn targets(&self) -> &[TargetInit] {
        &self.targets
    }

    /// Estimate `q` and `r` from the init tracks (see [`NoiseEstimate`]); `None` when no
    /// target has the four init frames the estimator needs.
    pub fn estimate_noise(&self) -> Option<NoiseEstimate> {
        NoiseEstimate::from_tracks(self.targets.iter().map(|t| t.points.as_slice()))
    }

    /// The last init frame over all targets; tracking starts after it.
    pub fn last_frame(&self) -> i64 {
        self.targets
            .iter()
            .filter_map(|t| t.points.last().map(|p| p.0))
            .max()
            .unwrap_or(i64::MIN)
    }
}

/// `q` and `r` estimated from labelled tracks by the method of moments on the chord
/// prediction residuals.
///
/// For a track observed at frames `τ_0 < τ_1 < …` with detections `y_i = x_i + v_i`,
/// `v_i ~ N(0, r²I)`, the tracker predicts `y_{i+1}` by extending the chord through `y_{i−1}`
/// and `y_i` (the model of [`crate::model`]): the residual, per coordinate, is
///
/// `e_i = y_{i+1} − y_i − ρ_i (y_i − y_{i−1})`,  `ρ_i = (τ_{i+1} − τ_i)/(τ_i − τ_{i−1})`.
///
/// If the true path's own chord residuals are independent with variance `q²Δ_{i+1}`
/// (`Δ_{i+1} = τ_{i+1} − τ_i`: the tracker's process noise, `q²` per frame), then
///
/// `E[e_i²] = q²Δ_{i+1} + r² a_i`, `a_i = 1 + (1 + ρ_i)² + ρ_i²`,
/// `E[e_i e_{i+1}] = −r² b_i`, `b_i = (1 + ρ_{i+1}) + ρ_{i+1}(1 + ρ_i)`
///
/// (on evenly spaced frames `a = 6`, `b = 4`: the second differences' variance and lag-1
/// covariance). Summing over targets, coordinates and `i`:
///
/// `r̂² = −Σ e_i e_{i+1} / Σ b_i`,  `q̂² = Σ (e_i² − r̂² a_i) / Σ Δ_{i+1}`,
///
/// both unbiased under the model ([`NoiseEstimate::r2_raw`], [`NoiseEstimate::q2_raw`]).
/// Either can come out below zero by chance (or when the path's residuals are positively
/// correlated, as they are for smooth turns); the estimates used are floored at 1 % of
/// `m = Σ e_i² / Σ a_i` (all the residual variance read as detection noise), `r̂² ≥ 0.01 m`,
/// `q̂² ≥ 0.01 m / Δ̄` (`Δ̄` the mean spacing), so `q̂`, `r̂` ≥ 0.1 √m, scale-free. `r̂ = √r̂²`
/// and `q̂ = √q̂²` are biased low by Jensen's inequality (a few per cent with tens of
/// residuals), and the floors bias them up when the true value is near zero: a straight
/// path (`q = 0`) gives `q̂ ≈ 0.1 r`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NoiseEstimate {
    /// `q̂`, process noise standard deviation per √frame (floored).
    pub q: f64,
    /// `r̂`, detection noise standard deviation (floored).
    pub r: f64,
    /// The unbiased moment estimate of `q²`, before the floor.
    pub q2_raw: f64,
    /// The unbiased moment estimate of `r²`, before the floor.
    pub r2_raw: f64,
    /// Residuals `e_i` used, per coordinate.
    pub residuals: usize,
    /// Lag-1 pairs `(e_i, e_{i+1})` used, per coordinate.
    pub pairs: usize,
}

impl NoiseEstimate {
    /// The smallest share of `m` the floors keep.
    pub const FLOOR: f64 = 0.01;

    /// The estimate from tracks of `(frame, position)` points, frames strictly increasing
    /// within each; `None` unless some track has at least four points (one lag-1 pair).
    pub fn from_tracks<'a>(tracks: impl Iterator<Item = &'a [(i64, Vec2)]>) -> Option<Self> {
        let (mut sum_cross, mut sum_b) = (0.0, 0.0);
        let (mut sum_sq, mut sum_a, mut sum_dt) = (0.0, 0.0, 0.0);
        let (mut residuals, mut pairs) = (0usize, 0usize);
        for pts in tracks {
            // (e_i, a_i, Δ_{i+1}, ρ_i) of the previous residual.
            let mut prev: Option<(Vec2, f64)> = None;
            for w in pts.windows(3) {
                let [(t0, y0), (t1, y1), (t2, y2)] = [w[0], w[1], w[2]];
                let (d1, d2) = ((t1 - t0) as f64, (t2 - t1) as f64);
                let rho = d2 / d1;
                let e = y2 - y1 - (y1 - y0) * rho;
                let a = 1.0 + (1.0 + rho) * (1.0 + rho) + rho * rho;
                sum_sq += e.norm_squared();
                sum_a += 2.0 * a;
                sum_dt += 2.0 * d2;
                residuals += 1;
                if let Some((e_prev, rho_prev)) = prev {
                    sum_cross += e_prev.dot(&e);
                    sum_b += 2.0 * ((1.0 + rho) + rho * (1.0 + rho_prev));
                    pairs += 1;
                }
                prev = Some((e, rho));
            }
        }
        if pairs == 0 || !(sum_a > 0.0 && sum_dt > 0.0) {
            return None;
        }
        let r2_raw = -sum_cross / sum_b;
        let q2_raw = (sum_sq - r2_raw * sum_a) / sum_dt;
        let m = sum_sq / sum_a;
        let mean_dt = sum_dt / (2.0 * residuals as f64);
        let r2 = r2_raw.max(Self::FLOOR * m);
        let q2 = q2_raw.max(Self::FLOOR * m / mean_dt);
        if !(r2 > 0.0 && q2 > 0.0 && r2.is_finite() && q2.is_finite()) {
            // Every init track exactly on a straight line at constant speed: nothing to
            // estimate from.
            return None;
        }
        Some(NoiseEstimate {
            q: q2.sqrt(),
            r: r2.sqrt(),
            q2_raw,
            r2_raw,
            residuals,
            pairs,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn det(frame: i64, x: f64) -> Detection {
        Detection {
            frame,
            position: Vec2::new(x, 0.0),
            target: None,
        }
    }

    fn row(target: i64, frame: i64) -> InitRow {
        InitRow {
            target,
            frame,
            position: Vec2::zeros(),
        }
    }

    #[test]
    fn detections_are_validated_and_indexed_by_frame() {
        let d = Detections::new(vec![det(2, 0.0), det(2, 1.0), det(5, 2.0)]).unwrap();
        assert_eq!(d.frames(), [2, 5]);
        assert_eq!(d.frame_rows(2), 0..2);
        let mut ys = vec![Vec2::new(9.0, 9.0)];
        assert_eq!(d.positions_into(5, &mut ys), 2..3);
        assert_eq!(ys, [Vec2::new(2.0, 0.0)]);
        assert_eq!(d.positions_into(3, &mut ys), 2..2);
        assert!(ys.is_empty());
        assert_eq!(d.frame_rows(3), 2..2);
        assert_eq!(d.frame_rows(5), 2..3);
        let e = Detections::new(vec![det(3, 0.0), det(2, 0.0)]).unwrap_err();
        assert_eq!(
            e,
            EpfError::FrameBackwards {
                file: "detections",
                row: 1,
                frame: 2,
                previous: 3
            }
        );
        assert!(matches!(
            Detections::new(vec![det(1, f64::NAN)]),
            Err(EpfError::NonFiniteData {
                row: 0,
                what: "x",
                ..
            })
        ));
    }

    #[test]
    fn init_needs_two_increasing_frames_per_target() {
        let init = Init::new(&[row(7, 0), row(3, 0), row(7, 1), row(3, 2)]).unwrap();
        assert_eq!(init.targets().len(), 2);
        assert_eq!(init.targets()[0].id, 7, "order of first appearance");
        assert_eq!(init.last_frame(), 2);
        assert_eq!(
            Init::new(&[row(1, 0), row(1, 1), row(2, 1)]).unwrap_err(),
            EpfError::TooFewInitFrames {
                target: 2,
                frames: 1
            }
        );
        assert!(matches!(
            Init::new(&[row(1, 1), row(1, 0)]),
            Err(EpfError::FrameBackwards {
                file: "init",
                row: 1,
                ..
            })
        ));
        assert!(matches!(
            Init::new(&[row(1, 1), row(1, 1)]),
            Err(EpfError::DuplicateInitFrame {
                target: 1,
                frame: 1
            })
        ));
        assert_eq!(Init::new(&[]).unwrap_err(), EpfError::NoTargets);
    }

    /// Frames beyond ±2⁵³ are refused where they come in: their differences could overflow
    /// (`i64::MIN` init frames, then a frame 5, did in the tracker) and their `f64` times
    /// would not be exact. ±2⁵³ itself is accepted.
    #[test]
    fn frames_beyond_two_to_the_53_are_errors() {
        let edge = 1i64 << 53;
        assert!(Detections::new(vec![det(-edge, 0.0), det(edge, 0.0)]).is_ok());
        assert_eq!(
            Detections::new(vec![det(0, 0.0), det(edge + 1, 0.0)]).unwrap_err(),
            EpfError::FrameOutOfRange {
                file: "detections",
                row: 1,
                frame: edge + 1
            }
        );
        assert_eq!(
            Init::new(&[row(1, i64::MIN), row(1, i64::MIN + 1)]).unwrap_err(),
            EpfError::FrameOutOfRange {
                file: "init",
                row: 0,
                frame: i64::MIN
            }
        );
    }
}
