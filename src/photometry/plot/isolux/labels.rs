//! The values written on the isolux lines: where each label goes (inside the square, clear of
//! the other labels, markers and axis names, over as few other lines as possible) and its white
//! box.

use super::page::{fmt_level, Page};
use super::ContourLabel;
use crate::draw::text::Typeface;
use crate::photometry::isolux::IsoluxContour;
use crate::photometry::plot::layout::Bounds;
use crate::photometry::plot::scene::{Scene, Shape, TextAnchor, INK, WHITE};
use crate::photometry::plot::CAP_HEIGHT;

/// Label positions: for each line (highest level first, longest line first), candidate points
/// along it; a label must lie inside the square and clear of other labels, markers and axis names;
/// among those, the one whose box other lines cross least, then with the fewest other lines close
/// by (where lines are spread out), then the nearest to the lower-right diagonal (so the values of
/// concentric lines line up).
pub(super) fn place_labels(
    page: &Page,
    face: &Typeface,
    levels: &[f64],
    contours: &[IsoluxContour],
    screen_lines: &[Vec<Vec<[f64; 2]>>],
    obstacles: &[Bounds],
) -> Vec<ContourLabel> {
    let t = page.text;
    let h = CAP_HEIGHT * page.label_size;
    let pad = 2.5 * t;
    let inner = page.area.grown(-2.0 * t);
    let centre = [
        (page.area.min[0] + page.area.max[0]) / 2.0,
        (page.area.min[1] + page.area.max[1]) / 2.0,
    ];
    let preferred = std::f64::consts::FRAC_PI_4; // screen angle, y down: towards the lower right
    let mut placed: Vec<Bounds> = obstacles.to_vec();
    let mut labels = Vec::new();
    let mut order: Vec<(usize, usize, f64)> = Vec::new();
    for (ci, lines) in screen_lines.iter().enumerate() {
        for (li, pts) in lines.iter().enumerate() {
            order.push((ci, li, polyline_length(pts, contours[ci].lines[li].closed)));
        }
    }
    order.sort_by(|a, b| b.0.cmp(&a.0).then(b.2.total_cmp(&a.2)));
    for (ci, li, length) in order {
        let text = fmt_level(levels[ci]);
        let w = face.width(&text, page.label_size);
        if length < 2.5 * (w + 2.0 * pad) {
            continue;
        }
        let pts = &screen_lines[ci][li];
        let closed = contours[ci].lines[li].closed;
        let mut best: Option<(f64, [f64; 2], Bounds)> = None;
        for c in points_along(pts, closed, (w / 3.0).max(4.0 * t)) {
            let b = Bounds {
                min: [c[0] - w / 2.0 - pad, c[1] - h / 2.0 - pad],
                max: [c[0] + w / 2.0 + pad, c[1] + h / 2.0 + pad],
            };
            let inside = b.min[0] >= inner.min[0]
                && b.min[1] >= inner.min[1]
                && b.max[0] <= inner.max[0]
                && b.max[1] <= inner.max[1];
            if !inside || placed.iter().any(|o| o.overlaps(&b.grown(2.0 * t))) {
                continue;
            }
            // Other lines through the box (they would be hidden), and near it (crowding).
            let (near, wide) = (b.grown(1.0 * t), b.grown(12.0 * t));
            let (mut crossing, mut crowding) = (0usize, 0usize);
            for (cj, lines) in screen_lines.iter().enumerate() {
                for (lj, other) in lines.iter().enumerate() {
                    if (cj, lj) == (ci, li) {
                        continue;
                    }
                    let hits = |bx: &Bounds| other.windows(2).any(|s| bx.hits_segment(s[0], s[1]));
                    if hits(&wide) {
                        crowding += 1;
                        crossing += usize::from(hits(&near));
                    }
                }
            }
            let angle = (c[1] - centre[1]).atan2(c[0] - centre[0]);
            let mut off = (angle - preferred).abs() % std::f64::consts::TAU;
            if off > std::f64::consts::PI {
                off = std::f64::consts::TAU - off;
            }
            let score = 10.0 * crossing as f64 + 2.0 * crowding as f64 + off;
            if best.as_ref().is_none_or(|(s, _, _)| score < *s) {
                best = Some((score, c, b));
            }
        }
        if let Some((_, c, b)) = best {
            placed.push(b);
            labels.push(ContourLabel {
                level_lx: levels[ci],
                text,
                centre_px: c,
            });
        }
    }
    labels
}

fn polyline_length(pts: &[[f64; 2]], closed: bool) -> f64 {
    let open: f64 = pts
        .windows(2)
        .map(|s| (s[1][0] - s[0][0]).hypot(s[1][1] - s[0][1]))
        .sum();
    match (closed, pts.first(), pts.last()) {
        (true, Some(a), Some(b)) => open + (a[0] - b[0]).hypot(a[1] - b[1]),
        _ => open,
    }
}

/// Points every `spacing` pixels of arc length along a polyline (from its start).
fn points_along(pts: &[[f64; 2]], closed: bool, spacing: f64) -> Vec<[f64; 2]> {
    let mut segments: Vec<([f64; 2], [f64; 2])> = pts.windows(2).map(|s| (s[0], s[1])).collect();
    if closed && pts.len() > 2 {
        segments.push((pts[pts.len() - 1], pts[0]));
    }
    let mut out = Vec::new();
    let mut next = spacing / 2.0;
    let mut walked = 0.0;
    for (a, b) in segments {
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        while next <= walked + len && len > 0.0 {
            let f = (next - walked) / len;
            out.push([a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f]);
            next += spacing;
        }
        walked += len;
    }
    out
}

/// Each label on a white box that interrupts its line.
pub(super) fn draw_labels(scene: &mut Scene, page: &Page, face: &Typeface, labels: &[ContourLabel]) {
    let h = CAP_HEIGHT * page.label_size;
    let pad = 2.0 * page.text;
    for l in labels {
        let w = face.width(&l.text, page.label_size);
        let c = l.centre_px;
        scene.push(
            "isolux-labels",
            Shape::Rect {
                min: [c[0] - w / 2.0 - pad, c[1] - h / 2.0 - pad],
                max: [c[0] + w / 2.0 + pad, c[1] + h / 2.0 + pad],
                fill: WHITE.with_alpha(235),
            },
        );
        scene.text(
            "isolux-labels",
            [c[0], c[1] + h / 2.0],
            page.label_size,
            TextAnchor::Middle,
            INK,
            l.text.clone(),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_along_a_square() {
        let sq = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
        assert_eq!(polyline_length(&sq, true), 40.0);
        assert_eq!(polyline_length(&sq, false), 30.0);
        let pts = points_along(&sq, true, 10.0);
        assert_eq!(pts, [[5.0, 0.0], [10.0, 5.0], [5.0, 10.0], [0.0, 5.0]]);
    }
}
