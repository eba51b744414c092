//! The isolux diagram: illuminance on the floor plane below a luminaire, seen from above, as a
//! lighting designer reads it.
//!
//! Promises:
//! - One square plot, equal scale on both axes: x (along C0) to the right, y (along C90) up, the
//!   origin — directly below the photometric centre — in the middle, marked with the luminaire
//!   symbol. The plotted square is the grid's (`IsoluxGrid::half_width_m`, ≥ the extent asked for).
//! - The grid's isolux lines at its 1-2-5 levels ([`crate::photometry::isolux::isolux_levels`]);
//!   1 × 10ⁿ levels are drawn thicker. Each line long enough to carry it gets its value (lx) on a
//!   white box placed where it covers no other label, marker or axis name and crosses the fewest
//!   other lines; [`IsoluxPlot::labels`] lists them.
//! - Optionally a false-colour fill: each band between consecutive levels in one colour (nothing
//!   below the lowest level), with a colour bar labelled in lx at the right.
//! - Axes: grid lines and ticks in metres at a 1-2-5 step, axis titles with units, C0/C90/C180/C270
//!   at the ends of the axes; the maximum marked with a red ×.
//! - Title: luminaire name (else catalogue number or file name) and mounting height; subtitle:
//!   manufacturer, file and format; legend: the isolux levels in lx, the luminaire position, the
//!   maximum illuminance and where; caption: units, formula, frame and grid.
//!
//! Like the polar diagram, the whole page is computed once into a scene that the SVG and PNG
//! writers both draw. [`IsoluxPlot::new`] here puts the parts together:
//!
//! - `page.rs`: the page layout for a width, floor metres to pixels, line styles, numbers as written.
//! - `fill.rs`: the false-colour bands and the colour bar.
//! - `axes.rs`: grid, axes, ticks and their labels, C-plane names, the luminaire and maximum markers.
//! - `labels.rs`: where the values go on the isolux lines, and their boxes.
//! - `titles.rs`: title and subtitle above the diagram, the legend below.

mod axes;
mod fill;
mod labels;
mod page;
mod titles;

use std::path::Path;

use self::axes::{draw_axes, draw_markers};
use self::fill::{draw_colour_bar, fill_image};
use self::labels::{draw_labels, place_labels};
use self::page::{contour_style, fmt_metres, Mapping, Page};
use self::titles::{draw_header, draw_legend};
use super::layout::Bounds;
use super::scene::{LineStyle, Scene, Shape, TextAnchor, INK};
use super::{svg, title_of, typeface, wrap_parts, PlotError, PlotFormat, MAX_SIZE_PX, MIN_SIZE_PX, SEP};
use crate::draw::ticks::{step_for_span, symmetric_ticks};
use crate::photometry::isolux::{IsoluxContour, IsoluxGrid, MaxPoint};
use crate::photometry::luminaire::Photometry;
use tiny_skia::Pixmap;

/// Choices for an isolux diagram.
#[derive(Debug, Clone, PartialEq)]
pub struct IsoluxPlotOptions {
    /// Image width in pixels, [`MIN_SIZE_PX`]…[`MAX_SIZE_PX`]; the height follows from the layout
    /// (about 1.2 × the width).
    pub size_px: u32,
    /// Fill the bands between isolux levels with colours and draw the colour bar.
    pub fill: bool,
}

impl Default for IsoluxPlotOptions {
    fn default() -> Self {
        IsoluxPlotOptions {
            size_px: 800,
            fill: true,
        }
    }
}

/// A value written on an isolux line.
#[derive(Debug, Clone, PartialEq)]
pub struct ContourLabel {
    /// The line's illuminance, lx.
    pub level_lx: f64,
    /// The text drawn (the value without unit; the legend and colour bar say lx).
    pub text: String,
    /// Centre of the label on the line, pixels.
    pub centre_px: [f64; 2],
}

/// The complete isolux diagram of one luminaire and floor grid, in pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct IsoluxPlot {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Top-left corner of the plotted square, pixels (whole pixels).
    pub area_min_px: [f64; 2],
    /// Side of the plotted square, pixels (whole pixels).
    pub area_size_px: f64,
    /// Half-width of the plotted square, metres.
    pub half_width_m: f64,
    /// Mounting height: the floor's distance below the photometric centre, metres.
    pub height_m: f64,
    /// Spacing of the axis ticks, metres.
    pub tick_step_m: f64,
    /// The isolux levels, ascending, lx.
    pub levels_lx: Vec<f64>,
    /// The isolux lines of each level, floor metres.
    pub contours: Vec<IsoluxContour>,
    /// The values written on the lines.
    pub labels: Vec<ContourLabel>,
    /// The largest illuminance on the grid and where.
    pub max: MaxPoint,
    /// Title line (luminaire name and mounting height).
    pub title: String,
    /// Caption lines below the legend.
    pub caption: Vec<String>,
    scene: Scene,
}

/// Most axis intervals across the square; the tick step is the smallest 1-2-5 value that needs no
/// more.
const MAX_TICK_INTERVALS: f64 = 10.0;

impl IsoluxPlot {
    /// Lays out the diagram of `grid`, sampled from `p`.
    ///
    /// # Errors
    /// [`PlotError::Size`] for a size outside [`MIN_SIZE_PX`]…[`MAX_SIZE_PX`];
    /// [`PlotError::NoIlluminance`] when no point of the grid is lit; [`PlotError::Render`] if the
    /// bundled font cannot be read or the fill cannot be encoded.
    pub fn new(p: &Photometry, grid: &IsoluxGrid, opts: &IsoluxPlotOptions) -> Result<Self, PlotError> {
        if !(MIN_SIZE_PX..=MAX_SIZE_PX).contains(&opts.size_px) {
            return Err(PlotError::Size { size: opts.size_px });
        }
        let max = grid.max();
        let levels_lx = grid.levels();
        if levels_lx.is_empty() {
            return Err(PlotError::NoIlluminance {
                file: p.source.clone(),
                height_m: grid.height_m,
            });
        }
        let face = typeface()?;
        let half_width_m = grid.half_width_m();
        let tick_step_m = step_for_span(2.0 * half_width_m, MAX_TICK_INTERVALS);
        let ticks = symmetric_ticks(half_width_m, tick_step_m);
        let page = Page::new(f64::from(opts.size_px), opts.fill, &face, &ticks, &levels_lx);
        let contours = grid.contours(&levels_lx);
        let to_px = Mapping {
            area: page.area,
            half_width_m,
        };

        let mut scene = Scene::default();
        if opts.fill {
            scene.push("fill", Shape::Image(fill_image(grid, &page, &levels_lx)?));
        }
        let obstacles = draw_axes(&mut scene, &page, &face, &to_px, &ticks);
        let line_styles: Vec<LineStyle> = levels_lx.iter().map(|&l| contour_style(&page, l)).collect();
        let screen_lines: Vec<Vec<Vec<[f64; 2]>>> = contours
            .iter()
            .map(|c| {
                c.lines
                    .iter()
                    .map(|l| l.points.iter().map(|q| to_px.point(q[0], q[1])).collect())
                    .collect()
            })
            .collect();
        for ((c, lines), style) in contours.iter().zip(&screen_lines).zip(&line_styles) {
            for (line, points) in c.lines.iter().zip(lines) {
                scene.push(
                    "isolux-lines",
                    Shape::Polyline {
                        points: points.clone(),
                        closed: line.closed,
                        stroke: style.clone(),
                    },
                );
            }
        }
        let markers = draw_markers(&mut scene, &page, &to_px, &max);
        let mut obstacles = obstacles;
        obstacles.extend(markers);
        let labels = place_labels(&page, &face, &levels_lx, &contours, &screen_lines, &obstacles);
        draw_labels(&mut scene, &page, &face, &labels);
        if let Some(bar) = page.bar {
            draw_colour_bar(&mut scene, &page, bar, &levels_lx);
        }
        let title = format!("{}{SEP}mounting height {} m", title_of(p), fmt_metres(grid.height_m));
        draw_header(&mut scene, &page, &face, p, &title);
        let legend_end = draw_legend(&mut scene, &page, &face, &levels_lx, &max, grid.height_m, &line_styles);

        let n = grid.points_per_side();
        let mut parts = vec![
            vec![
                "Illuminance E in lux (lx) on the horizontal floor plane".to_string(),
                "E = I(C, γ) · cos³γ / H², direct light of a point source".to_string(),
            ],
            vec![
                "x along C0, y along C90, in metres, seen from above".to_string(),
                format!("grid {n} × {n} points every {} m", fmt_metres(grid.step_m)),
            ],
        ];
        if opts.fill {
            parts.push(vec![
                "colours: E between consecutive isolux levels (scale at the right)".to_string(),
            ]);
        }
        let max_w = page.width - 2.0 * page.margin;
        let caption: Vec<String> = parts
            .iter()
            .flat_map(|line| wrap_parts(&face, line, page.caption_size, max_w))
            .collect();
        let row = 19.0 * page.text;
        let mut y = legend_end + 30.0 * page.text;
        for line in &caption {
            let (t, size) = face.fit(line, page.caption_size, max_w);
            scene.text("caption", [page.margin, y], size, TextAnchor::Start, INK, t);
            y += row;
        }
        let height = (y - row + page.margin).ceil() as u32;

        Ok(IsoluxPlot {
            width: opts.size_px,
            height,
            area_min_px: page.area.min,
            area_size_px: page.area.max[0] - page.area.min[0],
            half_width_m,
            height_m: grid.height_m,
            tick_step_m,
            levels_lx,
            contours,
            labels,
            max,
            title,
            caption,
            scene,
        })
    }

    /// Where the floor point (x, y) in metres lies in the image, pixels.
    pub fn to_canvas(&self, x_m: f64, y_m: f64) -> [f64; 2] {
        Mapping {
            area: Bounds {
                min: self.area_min_px,
                max: [
                    self.area_min_px[0] + self.area_size_px,
                    self.area_min_px[1] + self.area_size_px,
                ],
            },
            half_width_m: self.half_width_m,
        }
        .point(x_m, y_m)
    }

    /// The diagram as a standalone SVG document (UTF-8 text starting with `<svg`); the fill is an
    /// embedded PNG.
    pub fn to_svg(&self) -> String {
        svg::document(
            self.width,
            self.height,
            &format!("Isolux diagram: {}", self.title),
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

/// Lays out the isolux diagram of `grid` and writes it to `path`, as SVG or PNG by the path's
/// extension.
///
/// # Errors
/// [`PlotError::UnsupportedFormat`] for any other extension (checked before any work), the errors
/// of [`IsoluxPlot::new`], and [`PlotError::Io`] naming the path when it cannot be written.
pub fn write_isolux(p: &Photometry, grid: &IsoluxGrid, opts: &IsoluxPlotOptions, path: &Path) -> Result<(), PlotError> {
    let format = PlotFormat::from_path(path)?;
    let plot = IsoluxPlot::new(p, grid, opts)?;
    let bytes = match format {
        PlotFormat::Svg => plot.to_svg().into_bytes(),
        PlotFormat::Png => plot.to_png()?,
    };
    std::fs::write(path, bytes).map_err(|source| PlotError::Io {
        path: path.to_path_buf(),
        source,
    })
}
