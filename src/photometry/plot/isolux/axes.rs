//! The isolux diagram's frame of reference: grid lines, axes, ticks in metres and their labels, axis
//! titles, the C-plane names at the ends of the axes, and the markers of the luminaire (at the
//! origin) and of the maximum.

use super::page::{Mapping, Page};
use crate::draw::text::Typeface;
use crate::draw::ticks::label_trimmed;
use crate::photometry::isolux::MaxPoint;
use crate::photometry::plot::layout::Bounds;
use crate::photometry::plot::scene::{Rgba, Scene, Shape, TextAnchor, GREY_TEXT, INK, RED, WHITE};
use crate::photometry::plot::CAP_HEIGHT;

/// Grid lines, the two axes through the origin, the frame, ticks and their labels, axis titles and
/// the C-plane names at the axis ends. Returns the boxes labels must not cover.
pub(super) fn draw_axes(
    scene: &mut Scene,
    page: &Page,
    face: &Typeface,
    to_px: &Mapping,
    ticks: &[f64],
) -> Vec<Bounds> {
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
pub(super) fn draw_markers(scene: &mut Scene, page: &Page, to_px: &Mapping, max: &MaxPoint) -> Vec<Bounds> {
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

pub(super) fn draw_luminaire_symbol(scene: &mut Scene, layer: &'static str, page: &Page, at: [f64; 2]) {
    scene.push(
        layer,
        Shape::Circle {
            centre: at,
            radius: 5.5 * page.text,
            stroke: page.stroke(1.6, Rgba::rgb(28, 84, 196)),
        },
    );
}

pub(super) fn draw_max_symbol(scene: &mut Scene, layer: &'static str, page: &Page, at: [f64; 2]) {
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
