//! PNG figures, drawn headless with plotters and an embedded font.
//!
//! Each plot kind is one function from plain data to a PNG file, so a paper's figure is a
//! thin caller that fills the data struct. Renderers draw what they are given and compute
//! no statistics.
//!
//! | module | plot kind |
//! |---|---|
//! | [`genealogy`] | particle genealogy (Cappé & Moulines, Fig. 1) |
//! | [`line`](mod@line) | line plot with optional shaded bands and reference lines |
//! | [`boxplot`] | box plots per group, with reference lines |
//! | [`histogram`] | histograms with summary statistics |
//! | [`rec`] | REC curves |
//! | [`xy`] | the plane with equal axes: paths, points, rays, ellipses |
//! | [`table`] | tables as images |
//! | [`style`] | the shared look: size, font, colours, dash patterns |

pub mod boxplot;
pub mod genealogy;
pub mod histogram;
pub mod line;
pub mod rec;
pub mod style;
pub mod table;
pub mod xy;

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::{BitMapBackend, DrawingArea, IntoDrawingArea, WHITE};

use crate::error::Result;
use crate::io::write_atomic_path;

/// The drawing area every renderer draws on.
pub type Canvas<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// Render a [`style::SIZE`] figure on white to `path`, atomically: `draw` paints the canvas,
/// which is encoded to a temporary PNG and renamed over `path` only if everything succeeded.
///
/// # Errors
/// The drawing callback's error, or a plot or I/O error naming `path`.
pub fn render_png<F>(path: &Path, draw: F) -> Result<()>
where
    F: FnOnce(&Canvas<'_>) -> Result<()>,
{
    render_png_sized(path, style::SIZE, draw)
}

/// [`render_png`] at `size` (width, height) px, for figures whose size follows their content
/// (tables).
///
/// # Errors
/// As [`render_png`].
pub fn render_png_sized<F>(path: &Path, size: (u32, u32), draw: F) -> Result<()>
where
    F: FnOnce(&Canvas<'_>) -> Result<()>,
{
    style::init_fonts()?;
    write_atomic_path(path, |tmp| {
        let root = BitMapBackend::new(tmp, size).into_drawing_area();
        root.fill(&WHITE).map_err(style::plot_err(path))?;
        draw(&root)?;
        // `present` encodes the PNG; an error here must not be lost in `drop`.
        root.present().map_err(style::plot_err(path))
    })
}
