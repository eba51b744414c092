//! The SVG writer of the diagrams: one element per primitive of a scene, grouped by layer, text as
//! `<text>` in DejaVu Sans (the font the layout was measured with).

use std::fmt::Write as _;

use super::scene::{LineStyle, Rgba, Scene, Shape, TextAnchor};
use crate::draw::ticks::trim_number;

/// Font family written into the SVG; DejaVu Sans first so the metrics match the layout.
const FONT_FAMILY: &str = "'DejaVu Sans', Verdana, Arial, sans-serif";

/// The whole document: `width × height` user units (pixels), a `<title>`, a white background and
/// the scene.
pub(super) fn document(width: u32, height: u32, title: &str, scene: &Scene) -> String {
    let mut s = String::with_capacity(64 * 1024);
    let (w, h) = (width, height);
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="{FONT_FAMILY}">"#
    );
    let title = escape(title);
    let _ = writeln!(s, "<title>{title}</title>");
    let _ = writeln!(s, r##"<rect width="{w}" height="{h}" fill="#ffffff"/>"##);
    let mut open: Option<&str> = None;
    for (layer, shape) in &scene.items {
        if open != Some(*layer) {
            if open.is_some() {
                s.push_str("</g>\n");
            }
            let _ = writeln!(s, r#"<g id="{layer}">"#);
            open = Some(*layer);
        }
        shape_element(&mut s, shape);
    }
    if open.is_some() {
        s.push_str("</g>\n");
    }
    s.push_str("</svg>\n");
    s
}

/// A coordinate: two decimals, trailing zeros dropped.
fn num(v: f64) -> String {
    trim_number(format!("{v:.2}"))
}

/// Text content and attribute values: markup characters escaped, control characters dropped.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for ch in text.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if c.is_control() => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

fn colour(c: Rgba) -> String {
    format!("#{:02x}{:02x}{:02x}", c.0[0], c.0[1], c.0[2])
}

fn opacity(c: Rgba) -> String {
    num(f64::from(c.0[3]) / 255.0)
}

fn stroke(s: &LineStyle) -> String {
    let mut out = format!(r#"stroke="{}" stroke-width="{}""#, colour(s.colour), num(s.width));
    if s.colour.0[3] < 255 {
        let _ = write!(out, r#" stroke-opacity="{}""#, opacity(s.colour));
    }
    if let Some([dash, gap]) = s.dash {
        let _ = write!(out, r#" stroke-dasharray="{} {}""#, num(dash), num(gap));
    }
    out
}

fn fill(c: Rgba) -> String {
    let mut out = format!(r#"fill="{}""#, colour(c));
    if c.0[3] < 255 {
        let _ = write!(out, r#" fill-opacity="{}""#, opacity(c));
    }
    out
}

fn shape_element(s: &mut String, shape: &Shape) {
    let _ = match shape {
        Shape::Rect { min, max, fill: f } => writeln!(
            s,
            r#"<rect x="{}" y="{}" width="{}" height="{}" {}/>"#,
            num(min[0]),
            num(min[1]),
            num(max[0] - min[0]),
            num(max[1] - min[1]),
            fill(*f)
        ),
        Shape::Circle {
            centre,
            radius,
            stroke: st,
        } => writeln!(
            s,
            r#"<circle cx="{}" cy="{}" r="{}" fill="none" {}/>"#,
            num(centre[0]),
            num(centre[1]),
            num(*radius),
            stroke(st)
        ),
        Shape::Line { from, to, stroke: st } => writeln!(
            s,
            r#"<line x1="{}" y1="{}" x2="{}" y2="{}" {}/>"#,
            num(from[0]),
            num(from[1]),
            num(to[0]),
            num(to[1]),
            stroke(st)
        ),
        Shape::Curve {
            id,
            points,
            fill: f,
            stroke: st,
        } => {
            let mut d = String::with_capacity(points.len() * 16);
            for (i, p) in points.iter().enumerate() {
                let _ = write!(d, "{}{} {}", if i == 0 { "M" } else { " L" }, num(p[0]), num(p[1]));
            }
            d.push_str(" Z");
            writeln!(
                s,
                r#"<path id="{id}" d="{d}" {} {} stroke-linejoin="round"/>"#,
                fill(*f),
                stroke(st)
            )
        }
        Shape::Polyline {
            points,
            closed,
            stroke: st,
        } => {
            let mut d = String::with_capacity(points.len() * 16);
            for (i, p) in points.iter().enumerate() {
                let _ = write!(d, "{}{} {}", if i == 0 { "M" } else { " L" }, num(p[0]), num(p[1]));
            }
            if *closed {
                d.push_str(" Z");
            }
            writeln!(
                s,
                r#"<path d="{d}" fill="none" {} stroke-linejoin="round"/>"#,
                stroke(st)
            )
        }
        Shape::Image(img) => writeln!(
            s,
            r#"<image x="{}" y="{}" width="{}" height="{}" preserveAspectRatio="none" href="data:image/png;base64,{}"/>"#,
            img.min[0],
            img.min[1],
            img.width,
            img.height,
            base64(&img.png)
        ),
        Shape::Text(t) => {
            let anchor = match t.anchor {
                TextAnchor::Start => "start",
                TextAnchor::Middle => "middle",
                TextAnchor::End => "end",
            };
            writeln!(
                s,
                r#"<text x="{}" y="{}" font-size="{}" text-anchor="{anchor}" {}>{}</text>"#,
                num(t.pos[0]),
                num(t.pos[1]),
                num(t.size),
                fill(t.colour),
                escape(&t.text)
            )
        }
    };
}

/// Standard base64 (RFC 4648, with padding), for images embedded as data URLs.
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(char::from(ALPHABET[((n >> (18 - 6 * k)) & 63) as usize]));
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_of_rfc_4648_vectors() {
        let cases = [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ];
        for (plain, encoded) in cases {
            assert_eq!(base64(plain.as_bytes()), encoded);
        }
    }

    #[test]
    fn escapes_markup() {
        assert_eq!(escape("A&B <c> \"d\"\n"), "A&amp;B &lt;c&gt; &quot;d&quot; ");
    }

    #[test]
    fn coordinates_are_short() {
        assert_eq!(num(12.0), "12");
        assert_eq!(num(12.345), "12.35");
        assert_eq!(num(-0.001), "0");
    }
}
