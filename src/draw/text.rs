//! Text with the one bundled font (DejaVu Sans, licence `assets/fonts/DejaVuSans-LICENSE.txt`;
//! every label of the plots and pictures is measured and rasterised with it): layout with kerning, measuring,
//! fitting into a width, and drawing onto RGBA8 pixels (ab_glyph coverage blended source-over).

use ab_glyph::{point, Font, FontRef, Glyph, PxScale, ScaleFont};
use tiny_skia::Pixmap;

/// The bundled font's path in the repository (for messages).
pub const FONT_PATH: &str = "assets/fonts/DejaVuSans.ttf";
const FONT_TTF: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Where a line of text sits relative to its x coordinate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Anchor {
    /// Text starts at x.
    Start,
    /// Text is centred on x.
    Middle,
    /// Text ends at x.
    End,
}

/// The bundled font, with measuring and drawing.
#[derive(Debug)]
pub struct Typeface {
    /// The parsed font (for callers that rasterise glyphs themselves).
    pub font: FontRef<'static>,
}

impl Typeface {
    /// Parses the bundled font. Errors: a message naming [`FONT_PATH`] (only if the bundled file
    /// were damaged).
    pub fn load() -> Result<Self, String> {
        FontRef::try_from_slice(FONT_TTF)
            .map(|font| Typeface { font })
            .map_err(|e| format!("bundled font {FONT_PATH}: {e}"))
    }

    /// ab_glyph scales to ascent − descent; convert an em size (px) to that.
    pub fn px_scale(&self, size: f64) -> PxScale {
        let upem = self.font.units_per_em().unwrap_or(2048.0);
        PxScale::from(size as f32 * self.font.height_unscaled() / upem)
    }

    /// Glyphs of `text` laid out (with kerning) from x = 0 on the baseline y = 0, and the advance
    /// width (px).
    pub fn layout(&self, text: &str, size: f64) -> (Vec<Glyph>, f64) {
        let scale = self.px_scale(size);
        let scaled = self.font.as_scaled(scale);
        let mut glyphs = Vec::with_capacity(text.len());
        let mut x = 0.0f32;
        let mut prev = None;
        for ch in text.chars() {
            let id = scaled.glyph_id(ch);
            if let Some(p) = prev {
                x += scaled.kern(p, id);
            }
            glyphs.push(id.with_scale_and_position(scale, point(x, 0.0)));
            x += scaled.h_advance(id);
            prev = Some(id);
        }
        (glyphs, f64::from(x))
    }

    /// The advance width of `text` at `size` (px).
    pub fn width(&self, text: &str, size: f64) -> f64 {
        self.layout(text, size).1
    }

    /// Shrinks (to 85 %) and then shortens with an ellipsis until `text` fits `max_width`; the text
    /// and the size to draw it at.
    pub fn fit(&self, text: &str, size: f64, max_width: f64) -> (String, f64) {
        if self.width(text, size) <= max_width {
            return (text.to_string(), size);
        }
        let small = size * 0.85;
        if self.width(text, small) <= max_width {
            return (text.to_string(), small);
        }
        let mut chars: Vec<char> = text.chars().collect();
        while chars.pop().is_some() {
            let candidate = format!("{}…", chars.iter().collect::<String>().trim_end());
            if self.width(&candidate, small) <= max_width {
                return (candidate, small);
            }
        }
        ("…".to_string(), small)
    }

    /// Draws one line of text with its baseline at `y` (px), source-over in `colour` (RGBA8, its
    /// alpha scaling the glyph coverage).
    #[allow(clippy::too_many_arguments)]
    pub fn text(&self, pm: &mut Pixmap, text: &str, x: f64, y: f64, size: f64, colour: [u8; 4], anchor: Anchor) {
        let (glyphs, width) = self.layout(text, size);
        let x0 = match anchor {
            Anchor::Start => x,
            Anchor::Middle => x - width / 2.0,
            Anchor::End => x - width,
        };
        let (w, h) = (i64::from(pm.width()), i64::from(pm.height()));
        let alpha = f32::from(colour[3]) / 255.0;
        let data = pm.data_mut();
        for mut g in glyphs {
            g.position = point(g.position.x + x0 as f32, y as f32);
            let Some(outline) = self.font.outline_glyph(g) else {
                continue;
            };
            let bounds = outline.px_bounds();
            let (bx, by) = (bounds.min.x as i64, bounds.min.y as i64);
            outline.draw(|gx, gy, coverage| {
                let (px, py) = (bx + i64::from(gx), by + i64::from(gy));
                let a = coverage.clamp(0.0, 1.0) * alpha;
                if px < 0 || py < 0 || px >= w || py >= h || a <= 0.0 {
                    return;
                }
                let i = ((py * w + px) * 4) as usize;
                for k in 0..3 {
                    let src = f32::from(colour[k]) * a;
                    data[i + k] = (src + f32::from(data[i + k]) * (1.0 - a)).round().min(255.0) as u8;
                }
                data[i + 3] = (255.0 * a + f32::from(data[i + 3]) * (1.0 - a)).round().min(255.0) as u8;
            });
        }
    }
}
