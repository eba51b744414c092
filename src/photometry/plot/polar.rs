//! The polar intensity diagram ("LDC", light distribution curve) that lighting designers read: the
//! C0–C180 and C90–C270 planes drawn over the full circle, γ = 0 (nadir) pointing down, rings at
//! round 1-2-5 values, spokes every 15°, a legend and a caption with maximum intensity and flux.
//!
//! [`PolarPlot::new`] computes the whole diagram once — curve points, ring values, every label and
//! its position, measured with the bundled DejaVu Sans — into a list of drawing primitives. The
//! SVG writer ([`PolarPlot::to_svg`]) and the PNG rasteriser ([`PolarPlot::to_png`]: tiny-skia for
//! shapes, ab_glyph for text) both walk that same list, so the two outputs agree.
//!
//! Screen frame: x to the right, y down, origin at the top-left corner, lengths in PNG pixels (the
//! SVG's user units). The right half of the diagram shows C0 (resp. C90) with γ running from 0 at
//! the bottom to 180 at the top; the left half shows C180 (resp. C270).

use std::fmt::Write as _;
use std::path::Path;

use tiny_skia::Pixmap;

use super::layout::{
    draw_corner_labels, draw_gamma_labels, draw_grid, draw_header, draw_legend, draw_ring_labels, spoke_labels, Layout,
};
use super::scene::{LineStyle, Scene, Shape, TextAnchor, BLUE, INK, RED};
use super::{svg, title_of, typeface, wrap_parts, PlotError, PlotFormat, MAX_SIZE_PX, MIN_SIZE_PX};
use crate::draw::ticks::{label_at_step, step_and_count, trim_number};
use crate::photometry::luminaire::Photometry;

/// Angular step of the curve samples, degrees.
pub const SAMPLE_STEP_DEG: f64 = 0.5;

/// Most rings drawn; the ring step is the smallest 1-2-5 value that needs no more.
const MAX_RINGS: usize = 7;

/// The unit of the plotted intensities.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PlotUnit {
    /// Absolute luminous intensity, cd.
    #[default]
    Candela,
    /// Intensity per 1000 lm: of the rated lamp flux, or for absolute photometry of the integrated
    /// luminaire flux (the caption says which).
    CandelaPerKilolumen,
}

impl PlotUnit {
    /// The unit as printed on the diagram: `cd` or `cd/klm`.
    pub fn symbol(self) -> &'static str {
        match self {
            PlotUnit::Candela => "cd",
            PlotUnit::CandelaPerKilolumen => "cd/klm",
        }
    }
}

/// Choices for a polar diagram.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotOptions {
    /// The unit of the rings and curves.
    pub unit: PlotUnit,
    /// Image width in pixels, [`MIN_SIZE_PX`]…[`MAX_SIZE_PX`]; the height follows from the layout
    /// (about 1.17 × the width). Lengths and font sizes scale with it.
    pub size_px: u32,
}

impl Default for PlotOptions {
    fn default() -> Self {
        PlotOptions {
            unit: PlotUnit::Candela,
            size_px: 800,
        }
    }
}

/// One plane of the diagram: two opposite C half-planes drawn as one closed curve.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneCurve {
    /// Identifier, also the SVG element id: `curve-c0-c180` or `curve-c90-c270`.
    pub id: &'static str,
    /// The plane's name, e.g. `C0–C180`.
    pub name: String,
    /// C angle drawn on the right half, degrees (0 or 90).
    pub right_c_deg: f64,
    /// C angle drawn on the left half, degrees (180 or 270).
    pub left_c_deg: f64,
    /// The sampled γ angles, degrees: 0…180 in steps of [`SAMPLE_STEP_DEG`].
    pub gamma_deg: Vec<f64>,
    /// Intensity on the right half-plane at each γ, in the plot's unit.
    pub right: Vec<f64>,
    /// Intensity on the left half-plane at each γ, in the plot's unit.
    pub left: Vec<f64>,
    /// The closed polyline in pixels: right half γ 0→180, then left half γ 180→0.
    pub points: Vec<[f64; 2]>,
    /// Stroke style: solid red for C0–C180, dashed blue for C90–C270.
    pub style: LineStyle,
}

impl PlaneCurve {
    /// The largest intensity on this plane, in the plot's unit.
    pub fn max_value(&self) -> f64 {
        self.right.iter().chain(&self.left).copied().fold(0.0, f64::max)
    }
}

/// A concentric ring of constant intensity.
#[derive(Debug, Clone, PartialEq)]
pub struct Ring {
    /// Intensity in the plot's unit.
    pub value: f64,
    /// Radius in pixels.
    pub radius: f64,
    /// The number written beside it (the unit stands in the diagram's top-left corner).
    pub label: String,
}

/// The complete polar diagram of one luminaire: geometry, values and every label, in pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct PolarPlot {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Unit of ring values and curve values.
    pub unit: PlotUnit,
    /// Centre of the diagram (the luminaire), pixels.
    pub centre: [f64; 2],
    /// Radius of the outermost ring, pixels.
    pub radius: f64,
    /// Value of the outermost ring in the plot's unit (the value drawn at [`PolarPlot::radius`]).
    pub outer_value: f64,
    /// The rings, innermost first; the last has `outer_value`.
    pub rings: Vec<Ring>,
    /// The C0–C180 curve, then the C90–C270 curve.
    pub curves: Vec<PlaneCurve>,
    /// Factor from cd to the plot's unit (1, or 1000 lm / flux).
    pub cd_to_unit: f64,
    /// Title line (luminaire name, else file name).
    pub title: String,
    /// Caption lines below the legend (maximum intensity, flux, what cd/klm refers to).
    pub caption: Vec<String>,
    scene: Scene,
}

impl PolarPlot {
    /// Computes the diagram of `p`.
    ///
    /// # Errors
    /// [`PlotError::Size`] for a size outside [`MIN_SIZE_PX`]…[`MAX_SIZE_PX`];
    /// [`PlotError::NoFlux`] for cd/klm when the lamp flux (or, for absolute photometry, the
    /// integrated flux) is not positive; [`PlotError::Render`] if the bundled font cannot be read.
    pub fn new(p: &Photometry, opts: &PlotOptions) -> Result<Self, PlotError> {
        if !(MIN_SIZE_PX..=MAX_SIZE_PX).contains(&opts.size_px) {
            return Err(PlotError::Size { size: opts.size_px });
        }
        let face = typeface()?;
        let spokes = spoke_labels();
        let lay = Layout::new(f64::from(opts.size_px), |size| {
            spokes.iter().map(|(_, _, t)| face.width(t, size)).fold(0.0, f64::max)
        });

        let integrated_lm = p.flux_lm();
        let (cd_to_unit, unit_note) = unit_factor(p, opts.unit, integrated_lm)?;
        let mut curves = sample_curves(p, cd_to_unit, lay.line);
        let plotted_max = curves.iter().map(PlaneCurve::max_value).fold(0.0, f64::max);
        let (step, count) = ring_step(plotted_max);
        let outer_value = step * count as f64;
        for c in &mut curves {
            let at = |right: bool| {
                move |(&g, &v): (&f64, &f64)| canvas_point(lay.centre, lay.radius, outer_value, right, g, v)
            };
            let right = c.gamma_deg.iter().zip(&c.right).map(at(true));
            let left = c.gamma_deg.iter().zip(&c.left).rev().map(at(false));
            c.points = right.chain(left).collect();
        }
        let rings: Vec<Ring> = (1..=count)
            .map(|i| {
                let value = step * i as f64;
                Ring {
                    value,
                    radius: lay.radius * value / outer_value,
                    label: label_at_step(value, step),
                }
            })
            .collect();

        let mut scene = Scene::default();
        draw_grid(&mut scene, &lay, &rings);
        draw_gamma_labels(&mut scene, &lay, &face, &spokes);
        for c in &curves {
            scene.push(
                "curves",
                Shape::Curve {
                    id: c.id,
                    points: c.points.clone(),
                    fill: c.style.colour.with_alpha(20),
                    stroke: c.style.clone(),
                },
            );
        }
        draw_ring_labels(&mut scene, &lay, &face, &rings, &curves);
        draw_corner_labels(&mut scene, &lay, &curves, opts.unit);
        let title = title_of(p);
        draw_header(&mut scene, &lay, &face, p, &title);
        let legend = draw_legend(&mut scene, &lay, &face, &curves, opts.unit);

        let mut parts = caption_parts(p, opts.unit, cd_to_unit, integrated_lm, plotted_max, unit_note);
        parts.extend(legend.notes.map(|n| vec![n]));
        let max_w = lay.width - 2.0 * lay.margin;
        let caption: Vec<String> = parts
            .iter()
            .flat_map(|line| wrap_parts(&face, line, lay.caption_size, max_w))
            .collect();
        let row = 19.0 * lay.text;
        let mut y = legend.baseline + 30.0 * lay.text;
        for line in &caption {
            let (t, size) = face.fit(line, lay.caption_size, max_w);
            scene.text("caption", [lay.margin, y], size, TextAnchor::Start, INK, t);
            y += row;
        }
        let height = (y - row + lay.margin).ceil() as u32;

        Ok(PolarPlot {
            width: opts.size_px,
            height,
            unit: opts.unit,
            centre: lay.centre,
            radius: lay.radius,
            outer_value,
            rings,
            curves,
            cd_to_unit,
            title,
            caption,
            scene,
        })
    }

    /// Where the value `value` (plot unit) at γ `gamma_deg` lies in the image, pixels: on the
    /// right half (C0 / C90) when `right`, else on the left half (C180 / C270).
    pub fn to_canvas(&self, right: bool, gamma_deg: f64, value: f64) -> [f64; 2] {
        canvas_point(self.centre, self.radius, self.outer_value, right, gamma_deg, value)
    }

    /// The diagram as a standalone SVG document (UTF-8 text starting with `<svg`).
    pub fn to_svg(&self) -> String {
        svg::document(
            self.width,
            self.height,
            &format!("Polar intensity diagram: {}", self.title),
            &self.scene,
        )
    }

    /// The diagram rasterised, anti-aliased, onto an opaque white pixmap of `width × height`.
    ///
    /// # Errors
    /// [`PlotError::Render`] if the pixmap cannot be allocated.
    pub fn to_pixmap(&self) -> Result<Pixmap, PlotError> {
        super::scene_pixmap(self.width, self.height, &self.scene)
    }

    /// The diagram as PNG file bytes (8-bit RGBA).
    ///
    /// # Errors
    /// [`PlotError::Render`] if rasterising or encoding fails.
    pub fn to_png(&self) -> Result<Vec<u8>, PlotError> {
        super::scene_png(self.width, self.height, &self.scene)
    }
}

/// Writes the diagram as SVG text to `path`.
///
/// # Errors
/// [`PlotError::Io`] naming the path when it cannot be written.
pub fn write_svg(plot: &PolarPlot, path: &Path) -> Result<(), PlotError> {
    std::fs::write(path, plot.to_svg()).map_err(|source| PlotError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes the diagram as a PNG image to `path`.
///
/// # Errors
/// [`PlotError::Render`] if rendering fails, [`PlotError::Io`] naming the path when it cannot be
/// written.
pub fn write_png(plot: &PolarPlot, path: &Path) -> Result<(), PlotError> {
    let bytes = plot.to_png()?;
    std::fs::write(path, bytes).map_err(|source| PlotError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Computes the diagram of `p` and writes it to `path`, as SVG or PNG by the path's extension.
///
/// # Errors
/// [`PlotError::UnsupportedFormat`] for any other extension (checked before any work), and the
/// errors of [`PolarPlot::new`], [`write_svg`] and [`write_png`].
pub fn write_plot(p: &Photometry, opts: &PlotOptions, path: &Path) -> Result<(), PlotError> {
    let format = PlotFormat::from_path(path)?;
    let plot = PolarPlot::new(p, opts)?;
    match format {
        PlotFormat::Svg => write_svg(&plot, path),
        PlotFormat::Png => write_png(&plot, path),
    }
}

fn canvas_point(centre: [f64; 2], radius: f64, outer: f64, right: bool, gamma_deg: f64, value: f64) -> [f64; 2] {
    let r = if outer > 0.0 { radius * value / outer } else { 0.0 };
    let a = gamma_deg.to_radians();
    let side = if right { 1.0 } else { -1.0 };
    [centre[0] + side * r * a.sin(), centre[1] + r * a.cos()]
}

/// Factor from cd to the unit and, for cd/klm, the sentence saying which flux the klm is.
fn unit_factor(p: &Photometry, unit: PlotUnit, integrated_lm: f64) -> Result<(f64, Option<String>), PlotError> {
    if unit == PlotUnit::Candela {
        return Ok((1.0, None));
    }
    match p.lamp_flux_lm {
        Some(f) if f.is_finite() && f > 0.0 => Ok((
            1000.0 / f,
            Some(format!("cd/klm per 1000 lm of rated lamp flux ({} lm)", fmt_value(f))),
        )),
        Some(f) => Err(PlotError::NoFlux {
            file: p.source.clone(),
            reason: format!("the rated lamp flux is {f} lm"),
        }),
        None if integrated_lm.is_finite() && integrated_lm > 0.0 => Ok((
            1000.0 / integrated_lm,
            Some(format!(
                "cd/klm per 1000 lm of integrated luminaire flux ({} lm)",
                fmt_value(integrated_lm)
            )),
        )),
        None => Err(PlotError::NoFlux {
            file: p.source.clone(),
            reason: "absolute photometry, and the integrated luminaire flux is zero".to_string(),
        }),
    }
}

/// The two planes sampled every [`SAMPLE_STEP_DEG`] in the plot's unit (points still empty).
fn sample_curves(p: &Photometry, cd_to_unit: f64, line: f64) -> Vec<PlaneCurve> {
    let n = (180.0 / SAMPLE_STEP_DEG).round() as usize;
    let gammas: Vec<f64> = (0..=n).map(|i| i as f64 * SAMPLE_STEP_DEG).collect();
    let sample = |c: f64, g: f64| {
        let v = p.web.sample(c, g) * cd_to_unit;
        if v.is_finite() {
            v.max(0.0)
        } else {
            0.0
        }
    };
    let planes = [
        ("curve-c0-c180", 0.0, 180.0, RED, None),
        ("curve-c90-c270", 90.0, 270.0, BLUE, Some([9.0 * line, 5.0 * line])),
    ];
    planes
        .iter()
        .map(|&(id, rc, lc, colour, dash)| PlaneCurve {
            id,
            name: format!("C{rc}–C{lc}"),
            right_c_deg: rc,
            left_c_deg: lc,
            gamma_deg: gammas.clone(),
            right: gammas.iter().map(|&g| sample(rc, g)).collect(),
            left: gammas.iter().map(|&g| sample(lc, g)).collect(),
            points: Vec::new(),
            style: LineStyle {
                colour,
                width: 2.2 * line,
                dash,
            },
        })
        .collect()
}

/// The ring step (1-2-5 series) and ring count (at most [`MAX_RINGS`]) for a maximum value.
fn ring_step(max: f64) -> (f64, usize) {
    step_and_count(max, MAX_RINGS).unwrap_or((1.0, 5))
}

/// The caption, as lines of parts (joined with [`SEP`](super::SEP), wrapped between parts where
/// too wide): maximum intensity and where; integrated and rated flux; what cd/klm refers to.
fn caption_parts(
    p: &Photometry,
    unit: PlotUnit,
    cd_to_unit: f64,
    integrated_lm: f64,
    plotted_max: f64,
    unit_note: Option<String>,
) -> Vec<Vec<String>> {
    let peak = p.peak();
    let (max_cd, max_c, max_g) = (peak.cd, peak.c_deg, peak.gamma_deg);
    let sym = unit.symbol();
    let mut max = match unit {
        PlotUnit::Candela => format!("Max. intensity {} cd", fmt_value(max_cd)),
        PlotUnit::CandelaPerKilolumen => format!(
            "Max. intensity {} {sym} ({} cd)",
            fmt_value(max_cd * cd_to_unit),
            fmt_value(max_cd)
        ),
    };
    let _ = write!(max, " at C {}°, γ {}°", fmt_angle(max_c), fmt_angle(max_g));
    let mut first = vec![max];
    if plotted_max < max_cd * cd_to_unit * 0.995 {
        first.push(format!("max. in the plotted planes {} {sym}", fmt_value(plotted_max)));
    }
    let mut second = vec![format!("Luminaire flux {} lm (integrated)", fmt_value(integrated_lm))];
    match p.lamp_flux_lm {
        Some(f) => {
            second.push(format!("rated lamp flux {} lm", fmt_value(f)));
            if let Some(lor) = p.integrated_lor() {
                second.push(format!("LOR {:.1} %", lor * 100.0));
            }
        }
        None => second.push("absolute photometry (no rated lamp flux)".to_string()),
    }
    let mut lines = vec![first, second];
    lines.extend(unit_note.map(|n| vec![n]));
    lines
}

/// A value for display: no decimals from 100 up, three significant digits below.
fn fmt_value(v: f64) -> String {
    if !v.is_finite() {
        "—".to_string()
    } else if v.abs() >= 100.0 || v == 0.0 {
        format!("{v:.0}")
    } else if v.abs() >= 10.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

/// An angle with at most two decimals, trailing zeros dropped.
fn fmt_angle(a: f64) -> String {
    trim_number(format!("{a:.2}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ring_steps_follow_1_2_5() {
        assert_eq!(ring_step(6019.0), (1000.0, 7));
        assert_eq!(ring_step(2866.0), (500.0, 6));
        assert_eq!(ring_step(463.0), (100.0, 5));
        assert_eq!(ring_step(1000.0), (200.0, 5));
        assert_eq!(ring_step(0.0), (1.0, 5));
        let (s, n) = ring_step(0.37);
        assert!((s - 0.1).abs() < 1e-12 && n == 4);
    }

    #[test]
    fn numbers_for_display() {
        assert_eq!(fmt_angle(62.5), "62.5");
        assert_eq!(fmt_angle(65.0), "65");
        assert_eq!(fmt_angle(-0.001), "0");
        assert_eq!(fmt_value(9560.8), "9561");
        assert_eq!(fmt_value(46.34), "46.3");
        assert_eq!(fmt_value(f64::NAN), "—");
    }
}
