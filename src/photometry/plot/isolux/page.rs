//! The isolux diagram's page: where the square, its ticks, the colour bar and the text go for an
//! image of a given width, the mapping from floor metres to pixels, the line style of each level
//! and how numbers are written on the page.

use crate::draw::text::Typeface;
use crate::draw::ticks::{label_trimmed, trim_number};
use crate::photometry::plot::layout::Bounds;
use crate::photometry::plot::scene::{LineStyle, Rgba};
use crate::photometry::plot::CAP_HEIGHT;

/// Sizes and positions of the page for an image `width` pixels wide (scaled like the polar
/// diagram: strokes with the width, text never below 75 % of its 800 px size).
pub(super) struct Page {
    pub(super) width: f64,
    pub(super) line: f64,
    pub(super) text: f64,
    pub(super) margin: f64,
    pub(super) title_size: f64,
    pub(super) subtitle_size: f64,
    pub(super) tick_size: f64,
    pub(super) axis_size: f64,
    pub(super) label_size: f64,
    pub(super) legend_size: f64,
    pub(super) caption_size: f64,
    pub(super) title_baseline: f64,
    pub(super) subtitle_baseline: f64,
    pub(super) axis_title_baseline: f64,
    /// The plotted square.
    pub(super) area: Bounds,
    /// The colour bar's swatches (when filled).
    pub(super) bar: Option<Bounds>,
}

/// Floor metres to pixels: x right, y up, equal scale, origin at the square's centre.
pub(super) struct Mapping {
    pub(super) area: Bounds,
    pub(super) half_width_m: f64,
}

impl Mapping {
    fn scale(&self) -> f64 {
        (self.area.max[0] - self.area.min[0]) / (2.0 * self.half_width_m)
    }

    pub(super) fn point(&self, x_m: f64, y_m: f64) -> [f64; 2] {
        let s = self.scale();
        [
            self.area.min[0] + (x_m + self.half_width_m) * s,
            self.area.min[1] + (self.half_width_m - y_m) * s,
        ]
    }
}

impl Page {
    pub(super) fn new(width: f64, fill: bool, face: &Typeface, ticks: &[f64], levels: &[f64]) -> Page {
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

    pub(super) fn stroke(&self, width: f64, colour: Rgba) -> LineStyle {
        LineStyle {
            colour,
            width: width * self.line,
            dash: None,
        }
    }

    pub(super) fn x_tick_baseline(&self) -> f64 {
        self.area.max[1] + 7.0 * self.text + CAP_HEIGHT * self.tick_size
    }
}

/// The colour bar's title.
pub(super) const BAR_HEADER: &str = "E in lx";

/// A length for the title and caption: at most three decimals.
pub(super) fn fmt_metres(v: f64) -> String {
    trim_number(format!("{v:.3}"))
}

/// An isolux level as written on its line: 1-2-5 values print exactly (0.05, 20, 500).
pub(super) fn fmt_level(v: f64) -> String {
    trim_number(format!("{v:.6}"))
}

/// An illuminance for the legend: no decimals from 100 up, three significant digits below.
pub(super) fn fmt_lux(v: f64) -> String {
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
pub(super) fn contour_style(page: &Page, level: f64) -> LineStyle {
    let mantissa = level / 10f64.powf(level.log10().floor());
    let major = (mantissa - 1.0).abs() < 1e-6 || (mantissa - 10.0).abs() < 1e-6;
    page.stroke(if major { 2.1 } else { 1.3 }, Rgba::grey(25))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_on_the_page() {
        assert_eq!(fmt_level(0.05), "0.05");
        assert_eq!(fmt_level(200.0), "200");
        assert_eq!(fmt_lux(292.01), "292");
        assert_eq!(fmt_lux(0.01234), "0.0123");
    }
}
