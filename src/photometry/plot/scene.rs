//! The drawing primitives of a diagram: colours, line styles, placed text, shapes and embedded
//! images, collected in a [`Scene`] by layer. A diagram is computed once into a scene; the SVG
//! writer (`svg.rs`) and the PNG rasteriser (`raster.rs`) both draw exactly that list, in order,
//! so the two outputs agree.

use tiny_skia::Pixmap;

use super::PlotError;

/// An sRGB colour with straight (not premultiplied) alpha, 8 bits per channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rgba(pub [u8; 4]);

impl Rgba {
    pub(super) const fn rgb(r: u8, g: u8, b: u8) -> Self {
        Rgba([r, g, b, 255])
    }

    pub(super) const fn with_alpha(self, a: u8) -> Self {
        Rgba([self.0[0], self.0[1], self.0[2], a])
    }

    pub(super) const fn grey(v: u8) -> Self {
        Rgba::rgb(v, v, v)
    }
}

pub(super) const WHITE: Rgba = Rgba::grey(255);
pub(super) const INK: Rgba = Rgba::grey(34);
pub(super) const GREY_TEXT: Rgba = Rgba::grey(85);
/// Colour of the C0–C180 curve.
pub(super) const RED: Rgba = Rgba::rgb(204, 32, 39);
/// Colour of the C90–C270 curve.
pub(super) const BLUE: Rgba = Rgba::rgb(28, 84, 196);

/// How a line is stroked.
#[derive(Debug, Clone, PartialEq)]
pub struct LineStyle {
    /// Stroke colour.
    pub colour: Rgba,
    /// Stroke width, pixels.
    pub width: f64,
    /// Dash and gap lengths in pixels; `None` for a solid line.
    pub dash: Option<[f64; 2]>,
}

/// Horizontal alignment of a text relative to its anchor point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum TextAnchor {
    /// The text starts at the point.
    Start,
    /// The text is centred on the point.
    Middle,
    /// The text ends at the point.
    End,
}

/// A placed line of text.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct TextItem {
    /// Anchor point, pixels: x as [`TextItem::anchor`] says, y on the baseline.
    pub(super) pos: [f64; 2],
    /// Font size (em), pixels.
    pub(super) size: f64,
    /// Horizontal alignment.
    pub(super) anchor: TextAnchor,
    /// Fill colour.
    pub(super) colour: Rgba,
    /// The text.
    pub(super) text: String,
}

/// A drawing primitive; the SVG and PNG writers both render exactly this list, in order.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Shape {
    Rect {
        min: [f64; 2],
        max: [f64; 2],
        fill: Rgba,
    },
    Circle {
        centre: [f64; 2],
        radius: f64,
        stroke: LineStyle,
    },
    Line {
        from: [f64; 2],
        to: [f64; 2],
        stroke: LineStyle,
    },
    Curve {
        id: &'static str,
        points: Vec<[f64; 2]>,
        fill: Rgba,
        stroke: LineStyle,
    },
    /// A stroked, unfilled polyline, closed back to its first point when `closed`.
    Polyline {
        points: Vec<[f64; 2]>,
        closed: bool,
        stroke: LineStyle,
    },
    /// A raster image drawn pixel for pixel with its top-left corner at `min` (whole pixels).
    Image(RasterImage),
    Text(TextItem),
}

/// An RGBA8 image placed in a scene, kept both as premultiplied pixels (for the PNG writer) and
/// as PNG bytes (embedded in the SVG).
#[derive(Clone, PartialEq)]
pub(super) struct RasterImage {
    /// Top-left corner, whole pixels.
    pub(super) min: [u32; 2],
    pub(super) width: u32,
    pub(super) height: u32,
    /// Premultiplied RGBA8, row-major from the top, `width × height × 4` bytes.
    pub(super) rgba: Vec<u8>,
    /// The same image encoded as PNG.
    pub(super) png: Vec<u8>,
}

impl RasterImage {
    /// An image from premultiplied RGBA8 pixels.
    ///
    /// # Errors
    /// [`PlotError::Render`] when the size does not match the pixels or PNG encoding fails.
    pub(super) fn new(min: [u32; 2], width: u32, height: u32, rgba: Vec<u8>) -> Result<Self, PlotError> {
        let size = tiny_skia::IntSize::from_wh(width, height).ok_or_else(|| PlotError::Render {
            message: format!("empty {width} × {height} image"),
        })?;
        let pixmap = Pixmap::from_vec(rgba.clone(), size).ok_or_else(|| PlotError::Render {
            message: format!("{} bytes are not a {width} × {height} RGBA image", rgba.len()),
        })?;
        let png = pixmap.encode_png().map_err(|e| PlotError::Render {
            message: format!("PNG encoding of the {width} × {height} fill: {e}"),
        })?;
        Ok(RasterImage {
            min,
            width,
            height,
            rgba,
            png,
        })
    }
}

impl std::fmt::Debug for RasterImage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RasterImage")
            .field("min", &self.min)
            .field("width", &self.width)
            .field("height", &self.height)
            .field("png_bytes", &self.png.len())
            .finish_non_exhaustive()
    }
}

/// Primitives grouped by layer (the SVG's `<g id>`), in drawing order.
#[derive(Debug, Clone, PartialEq, Default)]
pub(super) struct Scene {
    pub(super) items: Vec<(&'static str, Shape)>,
}

impl Scene {
    pub(super) fn push(&mut self, layer: &'static str, shape: Shape) {
        self.items.push((layer, shape));
    }

    pub(super) fn text(
        &mut self,
        layer: &'static str,
        pos: [f64; 2],
        size: f64,
        anchor: TextAnchor,
        colour: Rgba,
        text: String,
    ) {
        self.push(
            layer,
            Shape::Text(TextItem {
                pos,
                size,
                anchor,
                colour,
                text,
            }),
        );
    }
}
