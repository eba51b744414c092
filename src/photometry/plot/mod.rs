//! Diagrams for lighting designers, drawn with one bundled font into SVG and PNG. Each diagram is
//! computed once into a scene of drawing primitives that the SVG writer and the PNG rasteriser
//! both draw, so the two outputs agree. What the diagrams share lives here: the output format
//! ([`PlotFormat`]), the errors ([`PlotError`]), the size limits and the title and caption text.
//!
//! - `polar.rs`: the polar intensity diagram ([`PolarPlot`]) and its writers.
//! - `layout.rs`: the polar diagram's page layout and the primitives that draw it.
//! - `isolux/`: the isolux diagram of illuminance on a floor plane ([`IsoluxPlot`]).
//! - [`legend`]: a labelled logarithmic scale bar to put under an image ([`legend::ScaleBar`]).
//! - `scene.rs`: the drawing primitives (colours, line styles, text, shapes, images) and the scene.
//! - `svg.rs`: the scene as an SVG document.
//! - `raster.rs`: the scene rasterised onto a pixmap.

mod isolux;
mod layout;
pub mod legend;
mod polar;
mod raster;
mod scene;
mod svg;

use std::path::{Path, PathBuf};

use crate::draw::text::Typeface;
use crate::photometry::luminaire::Photometry;

pub use self::isolux::{write_isolux, ContourLabel, IsoluxPlot, IsoluxPlotOptions};
pub use self::polar::{
    write_plot, write_png, write_svg, PlaneCurve, PlotOptions, PlotUnit, PolarPlot, Ring, SAMPLE_STEP_DEG,
};
pub use self::scene::{LineStyle, Rgba};

/// Smallest accepted image width in pixels.
pub const MIN_SIZE_PX: u32 = 320;

/// Largest accepted image width in pixels.
pub const MAX_SIZE_PX: u32 = 8192;

/// Cap height of DejaVu Sans as a fraction of the font size (digits are as tall).
const CAP_HEIGHT: f64 = 0.73;

/// Separator between the parts of a text line; no-break spaces survive SVG whitespace collapsing.
const SEP: &str = "\u{a0} · \u{a0}";

/// Output format of a plot file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlotFormat {
    /// Scalable vector graphics text.
    Svg,
    /// Anti-aliased raster image, 8-bit RGBA.
    Png,
}

impl PlotFormat {
    /// The format named by a file's extension (`.svg` or `.png`, any case).
    ///
    /// # Errors
    /// [`PlotError::UnsupportedFormat`] naming the path for any other extension.
    pub fn from_path(path: &Path) -> Result<Self, PlotError> {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("svg") => Ok(PlotFormat::Svg),
            Some("png") => Ok(PlotFormat::Png),
            _ => Err(PlotError::UnsupportedFormat {
                path: path.to_path_buf(),
            }),
        }
    }
}

/// An error while computing or writing a diagram (polar or isolux).
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The output file name has neither `.svg` nor `.png` as its extension.
    #[error("{path}: unsupported plot format: the file name must end in .svg or .png")]
    UnsupportedFormat {
        /// The output path as given.
        path: PathBuf,
    },
    /// The requested size is out of range.
    #[error("plot size {size} px is outside {MIN_SIZE_PX}…{MAX_SIZE_PX} px")]
    Size {
        /// The size asked for, pixels.
        size: u32,
    },
    /// cd/klm was asked for but there is no positive flux to divide by.
    #[error("{file}: cannot plot in cd/klm: {reason}")]
    NoFlux {
        /// The photometric file's name.
        file: String,
        /// Which flux is missing or zero.
        reason: String,
    },
    /// No point of an isolux grid is lit, so there is no line to draw.
    #[error("{file}: no light reaches the floor plane {height_m} m below it (0 lx on the whole grid): no isolux line to draw")]
    NoIlluminance {
        /// The photometric file's name.
        file: String,
        /// The mounting height, metres.
        height_m: f64,
    },
    /// The output file could not be written.
    #[error("{path}: cannot write file: {source}")]
    Io {
        /// The output path.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// Rasterising or PNG encoding failed.
    #[error("cannot render the PNG: {message}")]
    Render {
        /// What failed.
        message: String,
    },
}

/// The bundled font ([`crate::draw::text`]), its error as the plot's.
fn typeface() -> Result<Typeface, PlotError> {
    Typeface::load().map_err(|message| PlotError::Render { message })
}

/// A diagram's scene rasterised, anti-aliased, onto an opaque white pixmap of `width × height`:
/// what the polar and isolux diagrams' `to_pixmap` return.
fn scene_pixmap(width: u32, height: u32, scene: &scene::Scene) -> Result<tiny_skia::Pixmap, PlotError> {
    raster::render(width, height, scene, &typeface()?)
}

/// A diagram's scene as PNG file bytes (8-bit RGBA): what the diagrams' `to_png` return.
fn scene_png(width: u32, height: u32, scene: &scene::Scene) -> Result<Vec<u8>, PlotError> {
    scene_pixmap(width, height, scene)?
        .encode_png()
        .map_err(|e| PlotError::Render {
            message: format!("PNG encoding: {e}"),
        })
}

/// First non-empty label among `keys` (case-insensitive), whitespace collapsed to single spaces.
fn label(p: &Photometry, keys: &[&str]) -> Option<String> {
    keys.iter().find_map(|k| {
        p.labels
            .iter()
            .find(|(key, v)| key.eq_ignore_ascii_case(k) && !v.trim().is_empty())
            .map(|(_, v)| v.split_whitespace().collect::<Vec<_>>().join(" "))
    })
}

fn file_name(p: &Photometry) -> String {
    Path::new(&p.source)
        .file_name()
        .map_or_else(|| p.source.clone(), |f| f.to_string_lossy().into_owned())
}

/// The luminaire's name from its labels, else its catalogue number, else the first free label
/// line, else the file name.
fn title_of(p: &Photometry) -> String {
    label(p, &["LUMINAIRE", "luminaire name"])
        .or_else(|| label(p, &["LUMCAT", "luminaire number"]))
        .or_else(|| label(p, &[""]))
        .unwrap_or_else(|| file_name(p))
}

/// Joins `parts` with [`SEP`] into as few lines as fit `max_width`, breaking only between parts.
fn wrap_parts(face: &Typeface, parts: &[String], size: f64, max_width: f64) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for part in parts {
        match lines.last_mut() {
            Some(last) if face.width(&format!("{last}{SEP}{part}"), size) <= max_width => {
                last.push_str(SEP);
                last.push_str(part);
            }
            _ => lines.push(part.clone()),
        }
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_from_extension() {
        assert_eq!(PlotFormat::from_path(Path::new("a/b.SVG")).ok(), Some(PlotFormat::Svg));
        assert_eq!(PlotFormat::from_path(Path::new("b.png")).ok(), Some(PlotFormat::Png));
        let e = PlotFormat::from_path(Path::new("out/plot.jpg"));
        assert!(matches!(&e, Err(PlotError::UnsupportedFormat { .. })));
        assert!(e
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
            .contains("out/plot.jpg"));
        assert!(PlotFormat::from_path(Path::new("noext")).is_err());
    }

    #[test]
    fn the_font_has_the_glyphs_used() {
        use ab_glyph::Font;
        let face = typeface().map_err(|e| e.to_string());
        assert!(face.is_ok(), "{:?}", face.as_ref().err());
        if let Ok(face) = face {
            for ch in "0123456789°γ–·…\u{a0}cd/klmC()".chars() {
                assert_ne!(face.font.glyph_id(ch).0, 0, "{ch:?} missing from the bundled font");
            }
        }
    }
}
