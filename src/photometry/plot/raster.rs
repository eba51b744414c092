//! The PNG rasteriser of the diagrams: tiny-skia (anti-aliased) for the shapes, ab_glyph
//! coverage blended source-over for the text, onto an opaque white pixmap.

use crate::draw::text::Anchor;
use tiny_skia::{
    Color, FillRule, IntSize, LineCap, LineJoin, Paint, PathBuilder, Pixmap, PixmapPaint, Rect, Stroke, StrokeDash,
    Transform,
};

use super::scene::{LineStyle, Rgba, Scene, Shape, TextAnchor, TextItem};
use super::PlotError;
use crate::draw::text::Typeface;

/// Draws every primitive of `scene`, in order, onto an opaque white `width × height` pixmap.
pub(super) fn render(width: u32, height: u32, scene: &Scene, face: &Typeface) -> Result<Pixmap, PlotError> {
    let mut pm = Pixmap::new(width, height).ok_or_else(|| PlotError::Render {
        message: format!("cannot allocate a {width} × {height} image"),
    })?;
    pm.fill(Color::WHITE);
    for (_, shape) in &scene.items {
        draw(&mut pm, face, shape);
    }
    Ok(pm)
}

fn paint(c: Rgba) -> Paint<'static> {
    let mut paint = Paint::default();
    paint.set_color_rgba8(c.0[0], c.0[1], c.0[2], c.0[3]);
    paint.anti_alias = true;
    paint
}

fn stroke(s: &LineStyle) -> Stroke {
    Stroke {
        width: s.width as f32,
        line_cap: LineCap::Butt,
        line_join: LineJoin::Round,
        dash: s.dash.and_then(|[d, g]| StrokeDash::new(vec![d as f32, g as f32], 0.0)),
        ..Stroke::default()
    }
}

fn draw(pm: &mut Pixmap, face: &Typeface, shape: &Shape) {
    let id = Transform::identity();
    match shape {
        Shape::Rect { min, max, fill } => {
            if let Some(r) = Rect::from_ltrb(min[0] as f32, min[1] as f32, max[0] as f32, max[1] as f32) {
                pm.fill_rect(r, &paint(*fill), id, None);
            }
        }
        Shape::Circle {
            centre,
            radius,
            stroke: st,
        } => {
            if let Some(path) = PathBuilder::from_circle(centre[0] as f32, centre[1] as f32, *radius as f32) {
                pm.stroke_path(&path, &paint(st.colour), &stroke(st), id, None);
            }
        }
        Shape::Line { from, to, stroke: st } => {
            let mut pb = PathBuilder::new();
            pb.move_to(from[0] as f32, from[1] as f32);
            pb.line_to(to[0] as f32, to[1] as f32);
            if let Some(path) = pb.finish() {
                pm.stroke_path(&path, &paint(st.colour), &stroke(st), id, None);
            }
        }
        Shape::Curve {
            points,
            fill,
            stroke: st,
            ..
        } => {
            let mut pb = PathBuilder::new();
            for (i, p) in points.iter().enumerate() {
                if i == 0 {
                    pb.move_to(p[0] as f32, p[1] as f32);
                } else {
                    pb.line_to(p[0] as f32, p[1] as f32);
                }
            }
            pb.close();
            if let Some(path) = pb.finish() {
                pm.fill_path(&path, &paint(*fill), FillRule::Winding, id, None);
                pm.stroke_path(&path, &paint(st.colour), &stroke(st), id, None);
            }
        }
        Shape::Polyline {
            points,
            closed,
            stroke: st,
        } => {
            let mut pb = PathBuilder::new();
            for (i, p) in points.iter().enumerate() {
                if i == 0 {
                    pb.move_to(p[0] as f32, p[1] as f32);
                } else {
                    pb.line_to(p[0] as f32, p[1] as f32);
                }
            }
            if *closed {
                pb.close();
            }
            if let Some(path) = pb.finish() {
                pm.stroke_path(&path, &paint(st.colour), &stroke(st), id, None);
            }
        }
        Shape::Image(img) => {
            let image = IntSize::from_wh(img.width, img.height).and_then(|s| Pixmap::from_vec(img.rgba.clone(), s));
            if let Some(image) = image {
                let (x, y) = (
                    i32::try_from(img.min[0]).unwrap_or(i32::MAX),
                    i32::try_from(img.min[1]).unwrap_or(i32::MAX),
                );
                pm.draw_pixmap(x, y, image.as_ref(), &PixmapPaint::default(), id, None);
            }
        }
        Shape::Text(t) => draw_text(pm, face, t),
    }
}

/// Rasterises a line of text (`draw::text`: ab_glyph coverage blended source-over; premultiplied
/// RGBA, channels stay ≤ alpha because both blends are the same monotone mix).
fn draw_text(pm: &mut Pixmap, face: &Typeface, t: &TextItem) {
    let anchor = match t.anchor {
        TextAnchor::Start => Anchor::Start,
        TextAnchor::Middle => Anchor::Middle,
        TextAnchor::End => Anchor::End,
    };
    face.text(pm, &t.text, t.pos[0], t.pos[1], t.size, t.colour.0, anchor);
}
