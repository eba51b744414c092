//! A labelled scale bar: what each colour of an image means, on a logarithmic axis with ticks at
//! 1-2-5 values ([`log_ticks`]), as a strip to put under the image (a render's luminance in cd/m², say). The
//! caller maps a value to its colour, so the bar shows exactly the image's own mapping.

use tiny_skia::Pixmap;

use super::scene::{LineStyle, Rgba, Scene, Shape, TextAnchor};
use super::{raster, typeface, PlotError};
use crate::draw::ticks::{label_short, log_ticks};

/// A logarithmic scale bar.
pub struct ScaleBar<'a> {
    /// Width of the strip, pixels (at least 160).
    pub width_px: u32,
    /// Lowest value on the bar (> 0).
    pub min: f64,
    /// Highest value on the bar (> `min`).
    pub max: f64,
    /// The caption, with the unit, e.g. `luminance in cd/m² (exposure 1e-3 m²/cd)`.
    pub caption: String,
    /// The colour of a value, sRGB 8-bit.
    pub colour_of: &'a dyn Fn(f64) -> [u8; 3],
}

impl ScaleBar<'_> {
    /// The strip as an opaque image (black background, light text), `width_px` wide.
    ///
    /// # Errors
    /// [`PlotError::Render`] for a width below 160 px, a range that is not positive and
    /// increasing, or when the font cannot be read or the image allocated.
    pub fn to_pixmap(&self) -> Result<Pixmap, PlotError> {
        if self.width_px < 160 || !(self.min > 0.0 && self.max > self.min && self.max.is_finite()) {
            return Err(PlotError::Render {
                message: format!(
                    "scale bar {} px wide over {}…{}: needs at least 160 px and 0 < min < max",
                    self.width_px, self.min, self.max
                ),
            });
        }
        let face = typeface()?;
        let w = f64::from(self.width_px);
        let text = (w / 60.0).clamp(10.0, 16.0);
        let margin = 1.2 * text;
        let bar_top = 0.8 * text;
        let bar_h = 1.1 * text;
        let height = (bar_top + bar_h + 0.5 * text + 2.6 * text + 0.6 * text + 1.2 * text).ceil();
        let mut scene = Scene::default();
        scene.push(
            "background",
            Shape::Rect {
                min: [0.0, 0.0],
                max: [w, height],
                fill: Rgba::rgb(0, 0, 0),
            },
        );
        let (x0, x1) = (margin, w - margin);
        let (l0, l1) = (self.min.log10(), self.max.log10());
        let x_of = |v: f64| x0 + (x1 - x0) * (v.log10() - l0) / (l1 - l0);
        let n = (x1 - x0).ceil() as usize;
        for i in 0..n {
            let xa = x0 + i as f64;
            let v = 10f64.powf(l0 + (l1 - l0) * (i as f64 + 0.5) / (x1 - x0));
            let [r, g, b] = (self.colour_of)(v);
            scene.push(
                "bar",
                Shape::Rect {
                    min: [xa, bar_top],
                    max: [(xa + 1.0).min(x1), bar_top + bar_h],
                    fill: Rgba::rgb(r, g, b),
                },
            );
        }
        let light = Rgba::grey(230);
        let tick = LineStyle {
            colour: light,
            width: 1.0,
            dash: None,
        };
        let label_w = face.width("500k", text);
        let max_ticks = ((x1 - x0) / (1.6 * label_w)).floor().max(2.0) as usize;
        let baseline = bar_top + bar_h + 0.5 * text + text;
        for t in log_ticks(self.min, self.max, max_ticks) {
            let x = x_of(t);
            scene.push(
                "ticks",
                Shape::Line {
                    from: [x, bar_top + bar_h],
                    to: [x, bar_top + bar_h + 0.4 * text],
                    stroke: tick.clone(),
                },
            );
            scene.text("ticks", [x, baseline], text, TextAnchor::Middle, light, label_short(t));
        }
        let (caption, size) = face.fit(&self.caption, text, w - 2.0 * margin);
        scene.text(
            "caption",
            [margin, baseline + 1.6 * text],
            size,
            TextAnchor::Start,
            light,
            caption,
        );
        raster::render(self.width_px, height as u32, &scene, &face)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bar_shows_the_callers_colours() {
        let colour = |v: f64| {
            let g = (255.0 * v / 100.0).round().clamp(0.0, 255.0) as u8;
            [g, g, g]
        };
        let bar = ScaleBar {
            width_px: 400,
            min: 1.0,
            max: 100.0,
            caption: "test in cd/m²".into(),
            colour_of: &colour,
        };
        let pm = bar.to_pixmap().unwrap();
        assert_eq!(pm.width(), 400);
        // Left end dark, right end bright, in the bar's row.
        let y = (0.8 * (400.0f64 / 60.0).clamp(10.0, 16.0) + 3.0) as u32;
        let px = |x: u32| pm.pixel(x, y).unwrap().red();
        assert!(px(22) < 20 && px(377) > 200, "{} {}", px(22), px(377));
    }
}
