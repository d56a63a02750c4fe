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

    /// The last init frame over all targets; tracking starts after it.
    pub fn last_frame(&self) -> i64 {
        self.targets
            .iter()
            .filter_map(|t| t.points.last().map(|p| p.0))
            .max()
            .unwrap_or(i64::MIN)
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
