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
//! writers both draw.

use std::path::Path;

use super::layout::Bounds;
use super::scene::{LineStyle, RasterImage, Rgba, Scene, Shape, TextAnchor, GREY_TEXT, INK, RED, WHITE};
use super::{
    file_name, label, raster, svg, title_of, typeface, wrap_parts, PlotError, PlotFormat, CAP_HEIGHT, MAX_SIZE_PX,
    MIN_SIZE_PX, SEP,
};
use crate::draw::text::Typeface;
use crate::draw::colormap::YELLOW_ORANGE_BROWN;
use crate::draw::ticks::{label_trimmed, step_for_span, symmetric_ticks, trim_number};
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

/// Sizes and positions of the page for an image `width` pixels wide (scaled like the polar
/// diagram: strokes with the width, text never below 75 % of its 800 px size).
struct Page {
    width: f64,
    line: f64,
    text: f64,
    margin: f64,
    title_size: f64,
    subtitle_size: f64,
    tick_size: f64,
    axis_size: f64,
    label_size: f64,
    legend_size: f64,
    caption_size: f64,
    title_baseline: f64,
    subtitle_baseline: f64,
    axis_title_baseline: f64,
    /// The plotted square.
    area: Bounds,
    /// The colour bar's swatches (when filled).
    bar: Option<Bounds>,
}

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
        raster::render(self.width, self.height, &self.scene, &typeface()?)
    }

    /// The diagram as PNG file bytes (8-bit RGBA).
    ///
    /// # Errors
    /// [`PlotError::Render`] if rasterising or encoding fails.
    pub fn to_png(&self) -> Result<Vec<u8>, PlotError> {
        self.to_pixmap()?.encode_png().map_err(|e| PlotError::Render {
            message: format!("PNG encoding: {e}"),
        })
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

/// Floor metres to pixels: x right, y up, equal scale, origin at the square's centre.
struct Mapping {
    area: Bounds,
    half_width_m: f64,
}

impl Mapping {
    fn scale(&self) -> f64 {
        (self.area.max[0] - self.area.min[0]) / (2.0 * self.half_width_m)
    }

    fn point(&self, x_m: f64, y_m: f64) -> [f64; 2] {
        let s = self.scale();
        [
            self.area.min[0] + (x_m + self.half_width_m) * s,
            self.area.min[1] + (self.half_width_m - y_m) * s,
        ]
    }
}

impl Page {
    fn new(width: f64, fill: bool, face: &Typeface, ticks: &[f64], levels: &[f64]) -> Page {
        let u = width / 800.0;
        let t = u.max(0.75);
        let margin = 22.0 * t;
        let title_size = 21.0 * t;
        let tick_size = 11.5 * t;
        let axis_size = 12.5 * t;
        let title_baseline = margin + 0.78 * title_size;
        let subtitle_baseline = title_baseline + 21.0 * t;
        let axis_title_baseline = subtitle_baseline + 28.0 * t;
        let top = (axis_title_baseline + 10.0 * t).round();
        let tick_w = ticks
            .iter()
            .map(|&v| face.width(&label_trimmed(v), tick_size))
            .fold(0.0, f64::max);
        let left = (margin + tick_w + 8.0 * t).round();
        let (right, bar_block) = if fill {
            let label_w = levels
                .iter()
                .map(|&l| face.width(&fmt_level(l), tick_size))
                .fold(0.0, f64::max);
            let header_w = face.width(BAR_HEADER, axis_size);
            let block = (16.0 * t + 6.0 * t + label_w).max(header_w);
            (width - margin - block - 20.0 * t, Some(block))
        } else {
            // Room for half the last x tick label beyond the square.
            (width - margin - tick_w / 2.0, None)
        };
        let side = (right - left).floor().max(16.0);
        let area = Bounds {
            min: [left, top],
            max: [left + side, top + side],
        };
        let bar = bar_block.map(|_| {
            let bands = levels.len() as f64;
            let h = (bands * 46.0 * t).min(side);
            let x = area.max[0] + 20.0 * t;
            Bounds {
                min: [x, top],
                max: [x + 16.0 * t, top + h],
            }
        });
        Page {
            width,
            line: u.max(0.6),
            text: t,
            margin,
            title_size,
            subtitle_size: 13.0 * t,
            tick_size,
            axis_size,
            label_size: 11.5 * t,
            legend_size: 13.5 * t,
            caption_size: 12.5 * t,
            title_baseline,
            subtitle_baseline,
            axis_title_baseline,
            area,
            bar,
        }
    }

    fn stroke(&self, width: f64, colour: Rgba) -> LineStyle {
        LineStyle {
            colour,
            width: width * self.line,
            dash: None,
        }
    }

    fn x_tick_baseline(&self) -> f64 {
        self.area.max[1] + 7.0 * self.text + CAP_HEIGHT * self.tick_size
    }
}

/// The colour bar's title.
const BAR_HEADER: &str = "E in lx";

/// A length for the title and caption: at most three decimals.
fn fmt_metres(v: f64) -> String {
    trim_number(format!("{v:.3}"))
}

/// An isolux level as written on its line: 1-2-5 values print exactly (0.05, 20, 500).
fn fmt_level(v: f64) -> String {
    trim_number(format!("{v:.6}"))
}

/// An illuminance for the legend: no decimals from 100 up, three significant digits below.
fn fmt_lux(v: f64) -> String {
    if v >= 100.0 {
        format!("{v:.0}")
    } else if v >= 10.0 {
        format!("{v:.1}")
    } else if v >= 1.0 {
        format!("{v:.2}")
    } else {
        trim_number(format!("{v:.4}"))
    }
}

/// 1 × 10ⁿ levels thicker, the others thin; dark grey.
fn contour_style(page: &Page, level: f64) -> LineStyle {
    let mantissa = level / 10f64.powf(level.log10().floor());
    let major = (mantissa - 1.0).abs() < 1e-6 || (mantissa - 10.0).abs() < 1e-6;
    page.stroke(if major { 2.1 } else { 1.3 }, Rgba::grey(25))
}

/// The colour of band `i` of `n` (band 0 lies between the two lowest levels): the fill's colour map
/// ([`YELLOW_ORANGE_BROWN`]: light, so the dark lines and their white labels stay readable on every
/// band) spread over the bands.
fn band_colour(i: usize, n: usize) -> Rgba {
    let [r, g, b] = YELLOW_ORANGE_BROWN.class(i, n);
    Rgba([r, g, b, 255])
}

/// The false-colour fill of the square, one image pixel per page pixel: E interpolated bilinearly
/// from the grid, coloured by its band; transparent below the lowest level.
fn fill_image(grid: &IsoluxGrid, page: &Page, levels: &[f64]) -> Result<RasterImage, PlotError> {
    let side = (page.area.max[0] - page.area.min[0]) as u32;
    let n = grid.points_per_side();
    let k = grid.half_points as f64;
    let hw = grid.half_width_m();
    let colours: Vec<Rgba> = (0..levels.len()).map(|i| band_colour(i, levels.len())).collect();
    let sample = |g: f64| {
        let g = g.clamp(0.0, (n - 1) as f64);
        let i = (g.floor() as usize).min(n - 2);
        (i, g - i as f64)
    };
    let mut rgba = vec![0u8; side as usize * side as usize * 4];
    for (j, row) in rgba.chunks_mut(side as usize * 4).enumerate() {
        let y_m = hw - (j as f64 + 0.5) / f64::from(side) * 2.0 * hw;
        let (iy, fy) = sample(y_m / grid.step_m + k);
        for (i, px) in row.chunks_mut(4).enumerate() {
            let x_m = -hw + (i as f64 + 0.5) / f64::from(side) * 2.0 * hw;
            let (ix, fx) = sample(x_m / grid.step_m + k);
            let at = |a: usize, b: usize| grid.e_lx[(iy + b) * n + ix + a];
            let e = (at(0, 0) * (1.0 - fx) + at(1, 0) * fx) * (1.0 - fy) + (at(0, 1) * (1.0 - fx) + at(1, 1) * fx) * fy;
            let band = levels.iter().filter(|&&l| e >= l).count();
            if band > 0 {
                px.copy_from_slice(&colours[band - 1].0);
            }
        }
    }
    RasterImage::new([page.area.min[0] as u32, page.area.min[1] as u32], side, side, rgba)
}

/// Grid lines, the two axes through the origin, the frame, ticks and their labels, axis titles and
/// the C-plane names at the axis ends. Returns the boxes labels must not cover.
fn draw_axes(scene: &mut Scene, page: &Page, face: &Typeface, to_px: &Mapping, ticks: &[f64]) -> Vec<Bounds> {
    let a = page.area;
    let t = page.text;
    let (minor, axis, frame) = (
        page.stroke(0.7, Rgba::grey(200).with_alpha(200)),
        page.stroke(1.0, Rgba::grey(120)),
        page.stroke(1.2, Rgba::grey(70)),
    );
    for &v in ticks {
        let [x, y] = to_px.point(v, v);
        let style = if v == 0.0 { axis.clone() } else { minor.clone() };
        scene.push(
            "grid",
            Shape::Line {
                from: [x, a.min[1]],
                to: [x, a.max[1]],
                stroke: style.clone(),
            },
        );
        scene.push(
            "grid",
            Shape::Line {
                from: [a.min[0], y],
                to: [a.max[0], y],
                stroke: style,
            },
        );
    }
    for &v in ticks {
        let [x, y] = to_px.point(v, v);
        // Tick marks outside the frame, labels below and left.
        let tick = 4.0 * t;
        scene.push(
            "axes",
            Shape::Line {
                from: [x, a.max[1]],
                to: [x, a.max[1] + tick],
                stroke: frame.clone(),
            },
        );
        scene.push(
            "axes",
            Shape::Line {
                from: [a.min[0] - tick, y],
                to: [a.min[0], y],
                stroke: frame.clone(),
            },
        );
        let label = label_trimmed(v);
        let base = page.x_tick_baseline();
        scene.text(
            "axes",
            [x, base],
            page.tick_size,
            TextAnchor::Middle,
            GREY_TEXT,
            label.clone(),
        );
        let mid = y + CAP_HEIGHT * page.tick_size / 2.0;
        scene.text(
            "axes",
            [a.min[0] - tick - 3.0 * t, mid],
            page.tick_size,
            TextAnchor::End,
            GREY_TEXT,
            label,
        );
    }
    let corners = vec![a.min, [a.max[0], a.min[1]], a.max, [a.min[0], a.max[1]]];
    scene.push(
        "axes",
        Shape::Polyline {
            points: corners,
            closed: true,
            stroke: frame,
        },
    );
    scene.text(
        "axes",
        [(a.min[0] + a.max[0]) / 2.0, page.x_tick_baseline() + 20.0 * t],
        page.axis_size,
        TextAnchor::Middle,
        INK,
        "x in m, towards C0 \u{2192}".to_string(),
    );
    scene.text(
        "axes",
        [page.margin, page.axis_title_baseline],
        page.axis_size,
        TextAnchor::Start,
        INK,
        "\u{2191} y in m, towards C90".to_string(),
    );
    // The C planes at the ends of the axes, inside the square, on light boxes.
    let [cx, cy] = to_px.point(0.0, 0.0);
    let h = CAP_HEIGHT * page.tick_size;
    let gap = 5.0 * t;
    let names = [
        ("C0", [a.max[0] - gap, cy - gap], TextAnchor::End),
        ("C180", [a.min[0] + gap, cy - gap], TextAnchor::Start),
        ("C90", [cx + gap, a.min[1] + gap + h], TextAnchor::Start),
        ("C270", [cx + gap, a.max[1] - gap], TextAnchor::Start),
    ];
    let mut boxes = Vec::new();
    for (name, at, anchor) in names {
        let w = face.width(name, page.tick_size);
        let x0 = match anchor {
            TextAnchor::End => at[0] - w,
            TextAnchor::Middle => at[0] - w / 2.0,
            TextAnchor::Start => at[0],
        };
        let b = Bounds {
            min: [x0, at[1] - h],
            max: [x0 + w, at[1]],
        };
        let pad = 2.0 * t;
        scene.push(
            "axes",
            Shape::Rect {
                min: [b.min[0] - pad, b.min[1] - pad],
                max: [b.max[0] + pad, b.max[1] + pad],
                fill: WHITE.with_alpha(200),
            },
        );
        scene.text("axes", at, page.tick_size, anchor, GREY_TEXT, name.to_string());
        boxes.push(b.grown(pad));
    }
    boxes
}

/// The luminaire at the origin (a ring) and the maximum (a red ×). Returns their boxes.
fn draw_markers(scene: &mut Scene, page: &Page, to_px: &Mapping, max: &MaxPoint) -> Vec<Bounds> {
    let t = page.text;
    let o = to_px.point(0.0, 0.0);
    draw_luminaire_symbol(scene, "markers", page, o);
    let m = to_px.point(max.x_m, max.y_m);
    draw_max_symbol(scene, "markers", page, m);
    let r = 7.0 * t;
    [o, m]
        .iter()
        .map(|c| Bounds {
            min: [c[0] - r, c[1] - r],
            max: [c[0] + r, c[1] + r],
        })
        .collect()
}

fn draw_luminaire_symbol(scene: &mut Scene, layer: &'static str, page: &Page, at: [f64; 2]) {
    scene.push(
        layer,
        Shape::Circle {
            centre: at,
            radius: 5.5 * page.text,
            stroke: page.stroke(1.6, Rgba::rgb(28, 84, 196)),
        },
    );
}

fn draw_max_symbol(scene: &mut Scene, layer: &'static str, page: &Page, at: [f64; 2]) {
    let arm = 4.0 * page.text;
    for (dx, dy) in [(arm, arm), (arm, -arm)] {
        scene.push(
            layer,
            Shape::Line {
                from: [at[0] - dx, at[1] - dy],
                to: [at[0] + dx, at[1] + dy],
                stroke: page.stroke(2.0, RED),
            },
        );
    }
}

/// Label positions: for each line (highest level first, longest line first), candidate points
/// along it; a label must lie inside the square and clear of other labels, markers and axis names;
/// among those, the one whose box other lines cross least, then with the fewest other lines close
/// by (where lines are spread out), then the nearest to the lower-right diagonal (so the values of
/// concentric lines line up).
fn place_labels(
    page: &Page,
    face: &Typeface,
    levels: &[f64],
    contours: &[IsoluxContour],
    screen_lines: &[Vec<Vec<[f64; 2]>>],
    obstacles: &[Bounds],
) -> Vec<ContourLabel> {
    let t = page.text;
    let h = CAP_HEIGHT * page.label_size;
    let pad = 2.5 * t;
    let inner = page.area.grown(-2.0 * t);
    let centre = [
        (page.area.min[0] + page.area.max[0]) / 2.0,
        (page.area.min[1] + page.area.max[1]) / 2.0,
    ];
    let preferred = std::f64::consts::FRAC_PI_4; // screen angle, y down: towards the lower right
    let mut placed: Vec<Bounds> = obstacles.to_vec();
    let mut labels = Vec::new();
    let mut order: Vec<(usize, usize, f64)> = Vec::new();
    for (ci, lines) in screen_lines.iter().enumerate() {
        for (li, pts) in lines.iter().enumerate() {
            order.push((ci, li, polyline_length(pts, contours[ci].lines[li].closed)));
        }
    }
    order.sort_by(|a, b| b.0.cmp(&a.0).then(b.2.total_cmp(&a.2)));
    for (ci, li, length) in order {
        let text = fmt_level(levels[ci]);
        let w = face.width(&text, page.label_size);
        if length < 2.5 * (w + 2.0 * pad) {
            continue;
        }
        let pts = &screen_lines[ci][li];
        let closed = contours[ci].lines[li].closed;
        let mut best: Option<(f64, [f64; 2], Bounds)> = None;
        for c in points_along(pts, closed, (w / 3.0).max(4.0 * t)) {
            let b = Bounds {
                min: [c[0] - w / 2.0 - pad, c[1] - h / 2.0 - pad],
                max: [c[0] + w / 2.0 + pad, c[1] + h / 2.0 + pad],
            };
            let inside = b.min[0] >= inner.min[0]
                && b.min[1] >= inner.min[1]
                && b.max[0] <= inner.max[0]
                && b.max[1] <= inner.max[1];
            if !inside || placed.iter().any(|o| o.overlaps(&b.grown(2.0 * t))) {
                continue;
            }
            // Other lines through the box (they would be hidden), and near it (crowding).
            let (near, wide) = (b.grown(1.0 * t), b.grown(12.0 * t));
            let (mut crossing, mut crowding) = (0usize, 0usize);
            for (cj, lines) in screen_lines.iter().enumerate() {
                for (lj, other) in lines.iter().enumerate() {
                    if (cj, lj) == (ci, li) {
                        continue;
                    }
                    let hits = |bx: &Bounds| other.windows(2).any(|s| bx.hits_segment(s[0], s[1]));
                    if hits(&wide) {
                        crowding += 1;
                        crossing += usize::from(hits(&near));
                    }
                }
            }
            let angle = (c[1] - centre[1]).atan2(c[0] - centre[0]);
            let mut off = (angle - preferred).abs() % std::f64::consts::TAU;
            if off > std::f64::consts::PI {
                off = std::f64::consts::TAU - off;
            }
            let score = 10.0 * crossing as f64 + 2.0 * crowding as f64 + off;
            if best.as_ref().is_none_or(|(s, _, _)| score < *s) {
                best = Some((score, c, b));
            }
        }
        if let Some((_, c, b)) = best {
            placed.push(b);
            labels.push(ContourLabel {
                level_lx: levels[ci],
                text,
                centre_px: c,
            });
        }
    }
    labels
}

fn polyline_length(pts: &[[f64; 2]], closed: bool) -> f64 {
    let open: f64 = pts
        .windows(2)
        .map(|s| (s[1][0] - s[0][0]).hypot(s[1][1] - s[0][1]))
        .sum();
    match (closed, pts.first(), pts.last()) {
        (true, Some(a), Some(b)) => open + (a[0] - b[0]).hypot(a[1] - b[1]),
        _ => open,
    }
}

/// Points every `spacing` pixels of arc length along a polyline (from its start).
fn points_along(pts: &[[f64; 2]], closed: bool, spacing: f64) -> Vec<[f64; 2]> {
    let mut segments: Vec<([f64; 2], [f64; 2])> = pts.windows(2).map(|s| (s[0], s[1])).collect();
    if closed && pts.len() > 2 {
        segments.push((pts[pts.len() - 1], pts[0]));
    }
    let mut out = Vec::new();
    let mut next = spacing / 2.0;
    let mut walked = 0.0;
    for (a, b) in segments {
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        while next <= walked + len && len > 0.0 {
            let f = (next - walked) / len;
            out.push([a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f]);
            next += spacing;
        }
        walked += len;
    }
    out
}

/// Each label on a white box that interrupts its line.
fn draw_labels(scene: &mut Scene, page: &Page, face: &Typeface, labels: &[ContourLabel]) {
    let h = CAP_HEIGHT * page.label_size;
    let pad = 2.0 * page.text;
    for l in labels {
        let w = face.width(&l.text, page.label_size);
        let c = l.centre_px;
        scene.push(
            "isolux-labels",
            Shape::Rect {
                min: [c[0] - w / 2.0 - pad, c[1] - h / 2.0 - pad],
                max: [c[0] + w / 2.0 + pad, c[1] + h / 2.0 + pad],
                fill: WHITE.with_alpha(235),
            },
        );
        scene.text(
            "isolux-labels",
            [c[0], c[1] + h / 2.0],
            page.label_size,
            TextAnchor::Middle,
            INK,
            l.text.clone(),
        );
    }
}

/// One swatch per band, lowest at the bottom, the levels at the band boundaries, the unit above.
fn draw_colour_bar(scene: &mut Scene, page: &Page, bar: Bounds, levels: &[f64]) {
    let n = levels.len();
    let band_h = (bar.max[1] - bar.min[1]) / n as f64;
    for i in 0..n {
        let bottom = bar.max[1] - band_h * i as f64;
        scene.push(
            "colour-bar",
            Shape::Rect {
                min: [bar.min[0], bottom - band_h],
                max: [bar.max[0], bottom],
                fill: band_colour(i, n),
            },
        );
    }
    scene.push(
        "colour-bar",
        Shape::Polyline {
            points: vec![bar.min, [bar.max[0], bar.min[1]], bar.max, [bar.min[0], bar.max[1]]],
            closed: true,
            stroke: page.stroke(0.8, Rgba::grey(110)),
        },
    );
    for (i, &level) in levels.iter().enumerate() {
        let y = bar.max[1] - band_h * i as f64;
        scene.push(
            "colour-bar",
            Shape::Line {
                from: [bar.max[0], y],
                to: [bar.max[0] + 4.0 * page.text, y],
                stroke: page.stroke(0.8, Rgba::grey(110)),
            },
        );
        scene.text(
            "colour-bar",
            [bar.max[0] + 6.0 * page.text, y + CAP_HEIGHT * page.tick_size / 2.0],
            page.tick_size,
            TextAnchor::Start,
            INK,
            fmt_level(level),
        );
    }
    scene.text(
        "colour-bar",
        [bar.min[0], page.axis_title_baseline],
        page.axis_size,
        TextAnchor::Start,
        INK,
        BAR_HEADER.to_string(),
    );
}

/// Title (luminaire name, mounting height) and a subtitle with manufacturer, catalogue number,
/// file and format.
fn draw_header(scene: &mut Scene, page: &Page, face: &Typeface, p: &Photometry, title: &str) {
    let mut parts = vec!["Isolux diagram".to_string()];
    for keys in [["MANUFAC", "company"], ["LUMCAT", "luminaire number"]] {
        if let Some(v) = label(p, &keys) {
            if !title.starts_with(&v) {
                parts.push(v);
            }
        }
    }
    parts.push(format!("{} ({})", file_name(p), p.format.name()));
    let max_w = page.width - 2.0 * page.margin;
    let mid = page.width / 2.0;
    let (t, size) = face.fit(title, page.title_size, max_w);
    scene.text("title", [mid, page.title_baseline], size, TextAnchor::Middle, INK, t);
    let (t, size) = face.fit(&parts.join(SEP), page.subtitle_size, max_w);
    scene.text(
        "title",
        [mid, page.subtitle_baseline],
        size,
        TextAnchor::Middle,
        GREY_TEXT,
        t,
    );
}

/// A rule, then three rows: the isolux levels with a line sample, the luminaire symbol and the
/// maximum. Returns the last row's baseline.
fn draw_legend(
    scene: &mut Scene,
    page: &Page,
    face: &Typeface,
    levels: &[f64],
    max: &MaxPoint,
    height_m: f64,
    styles: &[LineStyle],
) -> f64 {
    let t = page.text;
    let rule_y = page.x_tick_baseline() + 20.0 * t + 14.0 * t;
    scene.push(
        "legend",
        Shape::Line {
            from: [page.margin, rule_y],
            to: [page.width - page.margin, rule_y],
            stroke: page.stroke(0.8, Rgba::grey(200)),
        },
    );
    let first = rule_y + 26.0 * t;
    let step = 23.0 * t;
    let sample_len = 40.0 * t;
    let text_x = page.margin + sample_len + 10.0 * t;
    let values: Vec<String> = levels.iter().map(|&l| fmt_level(l)).collect();
    let rows = [
        format!("Isolux lines in lx: {}", values.join(", ")),
        format!("Luminaire at (0, 0), {} m above the floor", fmt_metres(height_m)),
        format!(
            "Max. E {} lx at x = {} m, y = {} m",
            fmt_lux(max.e_lx),
            label_trimmed(max.x_m),
            label_trimmed(max.y_m)
        ),
    ];
    let mut y = first;
    for (i, row) in rows.iter().enumerate() {
        y = first + step * i as f64;
        let mid = y - CAP_HEIGHT * page.legend_size / 2.0;
        match i {
            0 => {
                // A thin and a thick sample when both kinds are drawn.
                let major = styles.iter().map(|s| s.width).fold(0.0, f64::max);
                let minor = styles.iter().map(|s| s.width).fold(f64::INFINITY, f64::min);
                let half = sample_len / 2.0 - 2.0 * t;
                let style = |w: f64| LineStyle {
                    width: w,
                    ..styles.first().cloned().unwrap_or_else(|| page.stroke(1.3, INK))
                };
                scene.push(
                    "legend",
                    Shape::Line {
                        from: [page.margin, mid],
                        to: [page.margin + half, mid],
                        stroke: style(minor),
                    },
                );
                scene.push(
                    "legend",
                    Shape::Line {
                        from: [page.margin + sample_len - half, mid],
                        to: [page.margin + sample_len, mid],
                        stroke: style(major),
                    },
                );
            }
            1 => draw_luminaire_symbol(scene, "legend", page, [page.margin + sample_len / 2.0, mid]),
            _ => draw_max_symbol(scene, "legend", page, [page.margin + sample_len / 2.0, mid]),
        }
        let (text, size) = face.fit(row, page.legend_size, page.width - page.margin - text_x);
        scene.text("legend", [text_x, y], size, TextAnchor::Start, INK, text);
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_and_colours() {
        assert_eq!(fmt_level(0.05), "0.05");
        assert_eq!(fmt_level(200.0), "200");
        assert_eq!(fmt_lux(292.01), "292");
        assert_eq!(fmt_lux(0.01234), "0.0123");
        let stops = YELLOW_ORANGE_BROWN.stops();
        assert_eq!(band_colour(0, 6).0[..3], stops[0]);
        assert_eq!(band_colour(5, 6).0[..3], stops[5]);
        assert_eq!(band_colour(0, 1).0[..3], stops[0]);
    }

    #[test]
    fn points_along_a_square() {
        let sq = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
        assert_eq!(polyline_length(&sq, true), 40.0);
        assert_eq!(polyline_length(&sq, false), 30.0);
        let pts = points_along(&sq, true, 10.0);
        assert_eq!(pts, [[5.0, 0.0], [10.0, 5.0], [5.0, 10.0], [0.0, 5.0]]);
    }
}
