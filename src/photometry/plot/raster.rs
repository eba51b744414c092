//! The PNG rasteriser of the diagrams: tiny-skia (anti-aliased) for the shapes, ab_glyph
//! coverage blended source-over for the text, onto an opaque white pixmap.

use ab_glyph::{point, Font};
use tiny_skia::{
    Color, FillRule, IntSize, LineCap, LineJoin, Paint, PathBuilder, Pixmap, PixmapPaint, Rect, Stroke, StrokeDash,
    Transform,
};

use super::{LineStyle, PlotError, Rgba, Scene, Shape, TextAnchor, TextItem, Typeface};

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

/// Rasterises a line of text with ab_glyph and blends its coverage source-over.
fn draw_text(pm: &mut Pixmap, face: &Typeface, t: &TextItem) {
    let (glyphs, width) = face.layout(&t.text, t.size);
    let x0 = match t.anchor {
        TextAnchor::Start => t.pos[0],
        TextAnchor::Middle => t.pos[0] - width / 2.0,
        TextAnchor::End => t.pos[0] - width,
    };
    let (w, h) = (i64::from(pm.width()), i64::from(pm.height()));
    let alpha = f32::from(t.colour.0[3]) / 255.0;
    let data = pm.data_mut();
    for mut g in glyphs {
        g.position = point(g.position.x + x0 as f32, t.pos[1] as f32);
        let Some(outline) = face.font.outline_glyph(g) else {
            continue;
        };
        let bounds = outline.px_bounds();
        let (bx, by) = (bounds.min.x as i64, bounds.min.y as i64);
        outline.draw(|gx, gy, coverage| {
            let (x, y) = (bx + i64::from(gx), by + i64::from(gy));
            let a = coverage.clamp(0.0, 1.0) * alpha;
            if x < 0 || y < 0 || x >= w || y >= h || a <= 0.0 {
                return;
            }
            // Premultiplied RGBA, source-over; channels stay ≤ alpha because both blends are the
            // same monotone mix.
            let i = ((y * w + x) * 4) as usize;
            for k in 0..3 {
                let src = f32::from(t.colour.0[k]) * a;
                data[i + k] = (src + f32::from(data[i + k]) * (1.0 - a)).round().min(255.0) as u8;
            }
            data[i + 3] = (255.0 * a + f32::from(data[i + 3]) * (1.0 - a)).round().min(255.0) as u8;
        });
    }
}
