//! Page layout of the polar diagram: where the diagram, its labels, the legend and the caption go,
//! and the primitives that draw them. Every label is measured with the bundled font so nothing
//! overlaps; the ring labels go beside the axis the curves cross least.

use super::polar::{PlaneCurve, PlotUnit, Ring};
use super::scene::{LineStyle, Rgba, Scene, Shape, TextAnchor, GREY_TEXT, INK, WHITE};
use super::{file_name, label, CAP_HEIGHT, SEP};
use crate::draw::text::Typeface;
use crate::photometry::luminaire::Photometry;

/// An axis-aligned box, pixels.
#[derive(Debug, Clone, Copy)]
pub(super) struct Bounds {
    pub(super) min: [f64; 2],
    pub(super) max: [f64; 2],
}

impl Bounds {
    pub(super) fn grown(&self, by: f64) -> Bounds {
        Bounds {
            min: [self.min[0] - by, self.min[1] - by],
            max: [self.max[0] + by, self.max[1] + by],
        }
    }

    pub(super) fn overlaps(&self, o: &Bounds) -> bool {
        self.min[0] < o.max[0] && o.min[0] < self.max[0] && self.min[1] < o.max[1] && o.min[1] < self.max[1]
    }

    /// Whether the segment a–b passes through the box (Liang–Barsky clipping).
    pub(super) fn hits_segment(&self, a: [f64; 2], b: [f64; 2]) -> bool {
        let d = [b[0] - a[0], b[1] - a[1]];
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for k in 0..2 {
            if d[k].abs() < 1e-12 {
                if a[k] < self.min[k] || a[k] > self.max[k] {
                    return false;
                }
                continue;
            }
            let (mut ta, mut tb) = ((self.min[k] - a[k]) / d[k], (self.max[k] - a[k]) / d[k]);
            if ta > tb {
                std::mem::swap(&mut ta, &mut tb);
            }
            t0 = t0.max(ta);
            t1 = t1.min(tb);
            if t0 > t1 {
                return false;
            }
        }
        true
    }
}

/// Positions and sizes of the page for an image `width` pixels wide. Shapes scale with the width;
/// text scales with it too but never below 75 % of its size at 800 px, so small images stay legible.
pub(super) struct Layout {
    pub(super) width: f64,
    /// Scale of strokes (1 at 800 px).
    pub(super) line: f64,
    /// Scale of text and of the spacing around text.
    pub(super) text: f64,
    pub(super) margin: f64,
    pub(super) title_size: f64,
    pub(super) subtitle_size: f64,
    pub(super) spoke_size: f64,
    pub(super) ring_size: f64,
    pub(super) legend_size: f64,
    pub(super) caption_size: f64,
    pub(super) title_baseline: f64,
    pub(super) subtitle_baseline: f64,
    pub(super) polar_top: f64,
    /// Gap between the outer ring and the γ labels.
    pub(super) pad: f64,
    pub(super) centre: [f64; 2],
    pub(super) radius: f64,
    pub(super) polar_bottom: f64,
}

impl Layout {
    /// `spoke_label_width(size)`: the widest γ label at that font size.
    pub(super) fn new(width: f64, spoke_label_width: impl Fn(f64) -> f64) -> Self {
        let u = width / 800.0;
        let t = u.max(0.75);
        let margin = 22.0 * t;
        let title_size = 21.0 * t;
        let spoke_size = 12.5 * t;
        let pad = 7.0 * t;
        let title_baseline = margin + 0.78 * title_size;
        let subtitle_baseline = title_baseline + 21.0 * t;
        let polar_top = subtitle_baseline + 12.0 * t;
        let spoke_h = CAP_HEIGHT * spoke_size;
        let radius = (width - 2.0 * margin - 2.0 * (spoke_label_width(spoke_size) + pad)) / 2.0;
        let centre = [width / 2.0, polar_top + spoke_h + pad + radius];
        Layout {
            width,
            line: u.max(0.6),
            text: t,
            margin,
            title_size,
            subtitle_size: 13.0 * t,
            spoke_size,
            ring_size: 11.5 * t,
            legend_size: 13.5 * t,
            caption_size: 12.5 * t,
            title_baseline,
            subtitle_baseline,
            polar_top,
            pad,
            centre,
            radius,
            polar_bottom: centre[1] + radius + pad + spoke_h,
        }
    }

    fn grid_line(&self, width: f64, grey: u8) -> LineStyle {
        LineStyle {
            colour: Rgba::grey(grey),
            width: width * self.line,
            dash: None,
        }
    }
}

/// The γ labels: 0°…180° on the right half, 15°…165° on the left.
pub(super) fn spoke_labels() -> Vec<(f64, bool, String)> {
    (0..=12u32)
        .flat_map(|k| {
            let g = 15.0 * f64::from(k);
            let right = (g, true, format!("{}°", 15 * k));
            let left = (k > 0 && k < 12).then(|| (g, false, format!("{}°", 15 * k)));
            std::iter::once(right).chain(left)
        })
        .collect()
}

/// Spokes every 15° (the 0°, 90° and 180° axes darker) and the rings (the outer one darker).
pub(super) fn draw_grid(scene: &mut Scene, lay: &Layout, rings: &[Ring]) {
    let c = lay.centre;
    for k in 0..12u32 {
        let a = (15.0 * f64::from(k)).to_radians();
        let d = [a.sin() * lay.radius, a.cos() * lay.radius];
        let stroke = if k % 6 == 0 {
            lay.grid_line(1.0, 150)
        } else {
            lay.grid_line(0.7, 212)
        };
        scene.push(
            "grid",
            Shape::Line {
                from: [c[0] - d[0], c[1] - d[1]],
                to: [c[0] + d[0], c[1] + d[1]],
                stroke,
            },
        );
    }
    for (i, ring) in rings.iter().enumerate() {
        let stroke = if i + 1 == rings.len() {
            lay.grid_line(1.3, 110)
        } else {
            lay.grid_line(0.8, 190)
        };
        scene.push(
            "grid",
            Shape::Circle {
                centre: c,
                radius: ring.radius,
                stroke,
            },
        );
    }
}

/// γ labels outside the outer ring, each box just clear of the ring along its spoke; every 15°,
/// or every 30° where 15° would crowd them (small images).
pub(super) fn draw_gamma_labels(scene: &mut Scene, lay: &Layout, face: &Typeface, spokes: &[(f64, bool, String)]) {
    let h = CAP_HEIGHT * lay.spoke_size;
    let placed: Vec<(f64, Bounds, &String)> = spokes
        .iter()
        .map(|(g, right, text)| {
            let a = g.to_radians();
            let dir = [if *right { a.sin() } else { -a.sin() }, a.cos()];
            let w = face.width(text, lay.spoke_size);
            // Distance from the box centre to its edge along `dir`.
            let reach = |half: f64, d: f64| if d.abs() < 1e-9 { f64::INFINITY } else { half / d.abs() };
            let dist = lay.radius + lay.pad + reach(w / 2.0, dir[0]).min(reach(h / 2.0, dir[1]));
            let mid = [lay.centre[0] + dir[0] * dist, lay.centre[1] + dir[1] * dist];
            let b = Bounds {
                min: [mid[0] - w / 2.0, mid[1] - h / 2.0],
                max: [mid[0] + w / 2.0, mid[1] + h / 2.0],
            };
            (*g, b, text)
        })
        .collect();
    let gap = 1.0 * lay.spoke_size;
    let crowded = placed.iter().enumerate().any(|(i, (_, a, _))| {
        placed[..i]
            .iter()
            .any(|(_, b, _)| a.grown(gap / 2.0).overlaps(&b.grown(gap / 2.0)))
    });
    for (g, b, text) in placed {
        if crowded && g % 30.0 != 0.0 {
            continue;
        }
        let at = [(b.min[0] + b.max[0]) / 2.0, b.max[1]];
        scene.text(
            "gamma-labels",
            at,
            lay.spoke_size,
            TextAnchor::Middle,
            GREY_TEXT,
            text.clone(),
        );
    }
}

/// Ring values beside the axis the curves cross least, on white boxes.
pub(super) fn draw_ring_labels(
    scene: &mut Scene,
    lay: &Layout,
    face: &Typeface,
    rings: &[Ring],
    curves: &[PlaneCurve],
) {
    let h = CAP_HEIGHT * lay.ring_size;
    let widths: Vec<f64> = rings.iter().map(|r| face.width(&r.label, lay.ring_size)).collect();
    let boxes = ring_label_boxes(rings, &widths, h, lay, curves);
    let pad = 2.0 * lay.text;
    for (ring, b) in rings.iter().zip(&boxes) {
        scene.push(
            "ring-labels",
            Shape::Rect {
                min: [b.min[0] - pad, b.min[1] - pad],
                max: [b.max[0] + pad, b.max[1] + pad],
                fill: WHITE.with_alpha(220),
            },
        );
        scene.text(
            "ring-labels",
            [b.min[0], b.max[1]],
            lay.ring_size,
            TextAnchor::Start,
            GREY_TEXT,
            ring.label.clone(),
        );
    }
}

/// Boxes for the ring labels: along one axis, just inside each ring, on the side of the axis
/// where the curves cross them least (labels overlapping each other or leaving the outer ring
/// rule a placement out).
fn ring_label_boxes(rings: &[Ring], widths: &[f64], h: f64, lay: &Layout, curves: &[PlaneCurve]) -> Vec<Bounds> {
    // (axis direction, side), in order of preference: up the top axis first (most luminaires
    // emit downwards), then the bottom axis, then the horizontal axis.
    let candidates: [([f64; 2], [f64; 2]); 8] = [
        ([0.0, -1.0], [1.0, 0.0]),
        ([0.0, -1.0], [-1.0, 0.0]),
        ([0.0, 1.0], [1.0, 0.0]),
        ([0.0, 1.0], [-1.0, 0.0]),
        ([1.0, 0.0], [0.0, -1.0]),
        ([-1.0, 0.0], [0.0, -1.0]),
        ([1.0, 0.0], [0.0, 1.0]),
        ([-1.0, 0.0], [0.0, 1.0]),
    ];
    let c = lay.centre;
    let (along_gap, side_gap, grow) = (3.0 * lay.text, 4.0 * lay.text, 2.0 * lay.text);
    let mut best: Option<(usize, Vec<Bounds>)> = None;
    for (d, side) in candidates {
        let boxes: Vec<Bounds> = rings
            .iter()
            .zip(widths)
            .map(|(ring, &w)| {
                let (ext_d, ext_s) = if d[0] == 0.0 { (h, w) } else { (w, h) };
                let at = |along: f64, across: f64| {
                    [
                        c[0] + d[0] * (ring.radius - along) + side[0] * across,
                        c[1] + d[1] * (ring.radius - along) + side[1] * across,
                    ]
                };
                let (a, b) = (at(along_gap, side_gap), at(along_gap + ext_d, side_gap + ext_s));
                Bounds {
                    min: [a[0].min(b[0]), a[1].min(b[1])],
                    max: [a[0].max(b[0]), a[1].max(b[1])],
                }
            })
            .collect();
        let mut score = 0;
        for (i, b) in boxes.iter().enumerate() {
            let g = b.grown(grow);
            for curve in curves {
                score += curve.points.windows(2).filter(|s| g.hits_segment(s[0], s[1])).count();
            }
            score += 1000 * boxes[..i].iter().filter(|o| o.overlaps(b)).count();
            let corners = [b.min, b.max, [b.min[0], b.max[1]], [b.max[0], b.min[1]]];
            if corners.iter().any(|k| (k[0] - c[0]).hypot(k[1] - c[1]) > lay.radius) {
                score += 1000;
            }
        }
        if best.as_ref().is_none_or(|(s, _)| score < *s) {
            best = Some((score, boxes));
        }
    }
    best.map(|(_, b)| b).unwrap_or_default()
}

/// The unit in the top-left corner; which half is which, colour-coded, in the bottom corners.
pub(super) fn draw_corner_labels(scene: &mut Scene, lay: &Layout, curves: &[PlaneCurve], unit: PlotUnit) {
    let top = lay.polar_top + CAP_HEIGHT * lay.legend_size;
    scene.text(
        "corner-labels",
        [lay.margin, top],
        lay.legend_size,
        TextAnchor::Start,
        INK,
        unit.symbol().to_string(),
    );
    for (i, c) in curves.iter().enumerate() {
        let y = lay.polar_bottom - (curves.len() - 1 - i) as f64 * 18.0 * lay.text;
        let sides = [
            (lay.margin, TextAnchor::Start, c.left_c_deg),
            (lay.width - lay.margin, TextAnchor::End, c.right_c_deg),
        ];
        for (x, anchor, angle) in sides {
            scene.text(
                "corner-labels",
                [x, y],
                lay.legend_size,
                anchor,
                c.style.colour,
                format!("C{angle}"),
            );
        }
    }
}

/// Title (luminaire name) and a subtitle with manufacturer, catalogue number, file and format.
pub(super) fn draw_header(scene: &mut Scene, lay: &Layout, face: &Typeface, p: &Photometry, title: &str) {
    let mut parts: Vec<String> = Vec::new();
    for keys in [["MANUFAC", "company"], ["LUMCAT", "luminaire number"]] {
        if let Some(v) = label(p, &keys) {
            if v != title {
                parts.push(v);
            }
        }
    }
    parts.push(format!("{} ({})", file_name(p), p.format.name()));
    let max_w = lay.width - 2.0 * lay.margin;
    let mid = lay.width / 2.0;
    let (t, size) = face.fit(title, lay.title_size, max_w);
    scene.text("title", [mid, lay.title_baseline], size, TextAnchor::Middle, INK, t);
    let (t, size) = face.fit(&parts.join(SEP), lay.subtitle_size, max_w);
    scene.text(
        "title",
        [mid, lay.subtitle_baseline],
        size,
        TextAnchor::Middle,
        GREY_TEXT,
        t,
    );
}

/// A rule, then one row per plane (line sample, name, which side is which) with the unit and the
/// γ convention on the right.
pub(super) fn draw_legend(
    scene: &mut Scene,
    lay: &Layout,
    face: &Typeface,
    curves: &[PlaneCurve],
    unit: PlotUnit,
) -> LegendEnd {
    let t = lay.text;
    let rule_y = lay.polar_bottom + 12.0 * t;
    let rule = Shape::Line {
        from: [lay.margin, rule_y],
        to: [lay.width - lay.margin, rule_y],
        stroke: lay.grid_line(0.8, 200),
    };
    scene.push("legend", rule);
    let first = rule_y + 26.0 * t;
    let step = 23.0 * t;
    let sample_len = 40.0 * t;
    let text_x = lay.margin + sample_len + 10.0 * t;
    let notes = [
        format!("Luminous intensity in {}", unit.symbol()),
        "γ from nadir: 0° down, 180° up".to_string(),
    ];
    let notes_w = notes
        .iter()
        .map(|n| face.width(n, lay.caption_size))
        .fold(0.0, f64::max);
    let names: Vec<String> = curves
        .iter()
        .map(|c| {
            format!(
                "{} plane\u{a0}\u{a0}(right: C{}, left: C{})",
                c.name, c.right_c_deg, c.left_c_deg
            )
        })
        .collect();
    let names_w = names.iter().map(|n| face.width(n, lay.legend_size)).fold(0.0, f64::max);
    // The notes stand right of the names where there is room; otherwise the caption carries them.
    let with_notes = text_x + names_w + 16.0 * t + notes_w <= lay.width - lay.margin;
    let mut y = first;
    for (i, (c, name)) in curves.iter().zip(names).enumerate() {
        y = first + step * i as f64;
        let mid = y - CAP_HEIGHT * lay.legend_size / 2.0;
        let sample = Shape::Line {
            from: [lay.margin, mid],
            to: [lay.margin + sample_len, mid],
            stroke: c.style.clone(),
        };
        scene.push("legend", sample);
        let (name, size) = face.fit(&name, lay.legend_size, lay.width - lay.margin - text_x);
        scene.text("legend", [text_x, y], size, TextAnchor::Start, INK, name);
        match notes.get(i) {
            Some(note) if with_notes => {
                let at = [lay.width - lay.margin, y];
                scene.text("legend", at, lay.caption_size, TextAnchor::End, GREY_TEXT, note.clone());
            }
            _ => {}
        }
    }
    LegendEnd {
        baseline: y,
        notes: (!with_notes).then(|| notes.join(SEP)),
    }
}

/// Where the legend ended, and the notes it had no room for.
pub(super) struct LegendEnd {
    pub(super) baseline: f64,
    pub(super) notes: Option<String>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_box_intersection() {
        let b = Bounds {
            min: [0.0, 0.0],
            max: [1.0, 1.0],
        };
        assert!(b.hits_segment([-1.0, 0.5], [2.0, 0.5]));
        assert!(!b.hits_segment([-1.0, 2.0], [2.0, 2.0]));
        assert!(b.hits_segment([0.5, 0.5], [0.6, 0.6]));
        assert!(!b.hits_segment([2.0, 0.0], [3.0, 1.0]));
    }
}
