//! The words around the isolux diagram: the title and subtitle above it and the legend below (the
//! levels with a line sample, the luminaire, the maximum).

use super::axes::{draw_luminaire_symbol, draw_max_symbol};
use super::page::{fmt_level, fmt_lux, fmt_metres, Page};
use crate::draw::text::Typeface;
use crate::draw::ticks::label_trimmed;
use crate::photometry::isolux::MaxPoint;
use crate::photometry::luminaire::Photometry;
use crate::photometry::plot::scene::{LineStyle, Rgba, Scene, Shape, TextAnchor, GREY_TEXT, INK};
use crate::photometry::plot::{file_name, label, CAP_HEIGHT, SEP};

/// Title (luminaire name, mounting height) and a subtitle with manufacturer, catalogue number,
/// file and format.
pub(super) fn draw_header(scene: &mut Scene, page: &Page, face: &Typeface, p: &Photometry, title: &str) {
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
pub(super) fn draw_legend(
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
