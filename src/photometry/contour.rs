//! Contour lines of a scalar field sampled on a regular square grid (marching squares), for the
//! isolux diagram and any other iso-line plot.
//!
//! Promises:
//! - Every crossing point lies on a grid edge whose two end values straddle the level (one
//!   `>= level`, the other `< level`), placed by linear interpolation between them, so a field
//!   that is linear along the edge is crossed exactly where it equals the level.
//! - Segments are joined into polylines through their shared edge crossings: a line that leaves
//!   the grid is an open polyline from border to border; one that does not is closed (its first
//!   point is not repeated). Every crossing is used exactly once.
//! - Saddle cells (two opposite corners above the level, two below) are resolved by the mean of the
//!   four corners, so lines never cross each other and the result does not depend on the order of
//!   the cells.
//! - Values that are not finite count as below every level.
//!
//! Coordinates of the results are in grid units: x = column index, y = row index (fractional
//! between samples); the caller maps them to its own frame.

/// A contour polyline in grid units (x = column, y = row).
#[derive(Debug, Clone, PartialEq)]
pub struct Polyline {
    /// The vertices, in order along the line.
    pub points: Vec<[f64; 2]>,
    /// True when the line closes on itself (the last point joins the first; it is not repeated).
    pub closed: bool,
}

/// A grid edge, as the crossing's identity: the horizontal edge from (ix, iy) to (ix + 1, iy), or
/// the vertical edge from (ix, iy) to (ix, iy + 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Edge {
    Horizontal(usize, usize),
    Vertical(usize, usize),
}

/// Contour lines at `level` of the row-major field `values` (`rows × cols`, `values[iy * cols +
/// ix]`).
///
/// Returns no line when the grid has fewer than 2 × 2 samples, `values` is shorter than
/// `rows × cols`, or `level` is not finite.
pub fn contour_lines(values: &[f64], cols: usize, rows: usize, level: f64) -> Vec<Polyline> {
    if cols < 2 || rows < 2 || values.len() < cols * rows || !level.is_finite() {
        return Vec::new();
    }
    let at = |ix: usize, iy: usize| values[iy * cols + ix];
    let above = |v: f64| v.is_finite() && v >= level;
    // Where the level crosses an edge (straddle assumed); non-finite values behave as "far below".
    let cross = |a: f64, b: f64| -> f64 {
        if !a.is_finite() {
            return 1.0;
        }
        if !b.is_finite() {
            return 0.0;
        }
        let d = b - a;
        if d == 0.0 {
            0.5
        } else {
            ((level - a) / d).clamp(0.0, 1.0)
        }
    };
    let point_of = |e: Edge| -> [f64; 2] {
        match e {
            Edge::Horizontal(ix, iy) => [ix as f64 + cross(at(ix, iy), at(ix + 1, iy)), iy as f64],
            Edge::Vertical(ix, iy) => [ix as f64, iy as f64 + cross(at(ix, iy), at(ix, iy + 1))],
        }
    };

    // Segments, each joining two edge crossings.
    let mut segments: Vec<[Edge; 2]> = Vec::new();
    for iy in 0..rows - 1 {
        for ix in 0..cols - 1 {
            // Corners counter-clockwise in grid units: (0,0), (1,0), (1,1), (0,1).
            let v = [at(ix, iy), at(ix + 1, iy), at(ix + 1, iy + 1), at(ix, iy + 1)];
            let case = v
                .iter()
                .enumerate()
                .fold(0u8, |c, (k, &x)| c | (u8::from(above(x)) << k));
            // Edges of the cell: bottom (0–1), right (1–2), top (3–2), left (0–3).
            let bottom = Edge::Horizontal(ix, iy);
            let right = Edge::Vertical(ix + 1, iy);
            let top = Edge::Horizontal(ix, iy + 1);
            let left = Edge::Vertical(ix, iy);
            let centre_above = || {
                let finite: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
                finite.len() == 4 && finite.iter().sum::<f64>() / 4.0 >= level
            };
            match case {
                0 | 15 => {}
                1 | 14 => segments.push([left, bottom]),
                2 | 13 => segments.push([bottom, right]),
                3 | 12 => segments.push([left, right]),
                4 | 11 => segments.push([right, top]),
                6 | 9 => segments.push([bottom, top]),
                7 | 8 => segments.push([left, top]),
                // Saddles: corners 0 and 2 above (5) or 1 and 3 above (10).
                5 => {
                    if centre_above() {
                        segments.push([left, top]);
                        segments.push([bottom, right]);
                    } else {
                        segments.push([left, bottom]);
                        segments.push([right, top]);
                    }
                }
                _ => {
                    if centre_above() {
                        segments.push([left, bottom]);
                        segments.push([right, top]);
                    } else {
                        segments.push([left, top]);
                        segments.push([bottom, right]);
                    }
                }
            }
        }
    }
    join(&segments, point_of)
}

/// Joins segments sharing an edge crossing into polylines (each crossing belongs to at most two
/// segments: the two cells on either side of its edge).
fn join(segments: &[[Edge; 2]], point_of: impl Fn(Edge) -> [f64; 2]) -> Vec<Polyline> {
    use std::collections::HashMap;
    let mut by_edge: HashMap<Edge, Vec<usize>> = HashMap::with_capacity(segments.len() * 2);
    for (i, s) in segments.iter().enumerate() {
        for e in s {
            by_edge.entry(*e).or_default().push(i);
        }
    }
    let mut used = vec![false; segments.len()];
    let next_segment = |edge: Edge, from: usize, used: &[bool]| -> Option<usize> {
        by_edge
            .get(&edge)
            .and_then(|list| list.iter().copied().find(|&j| j != from && !used[j]))
    };
    // Walks from `start` through `edge`, appending crossings, until the chain ends or closes.
    let walk = |start: usize, mut edge: Edge, used: &mut [bool], out: &mut Vec<Edge>| {
        let mut current = start;
        while let Some(j) = next_segment(edge, current, used) {
            used[j] = true;
            let s = segments[j];
            edge = if s[0] == edge { s[1] } else { s[0] };
            out.push(edge);
            current = j;
        }
    };
    let mut lines = Vec::new();
    // Open chains first, from the crossings on only one segment (the grid border), then cycles.
    let mut starts: Vec<usize> = (0..segments.len())
        .filter(|&i| segments[i].iter().any(|e| by_edge.get(e).is_some_and(|l| l.len() == 1)))
        .collect();
    starts.extend(0..segments.len());
    for i in starts {
        if used[i] {
            continue;
        }
        used[i] = true;
        let s = segments[i];
        // Start at the border end of an open chain, so the walk covers it in one direction.
        let (first, second) = if by_edge.get(&s[1]).is_some_and(|l| l.len() == 1) {
            (s[1], s[0])
        } else {
            (s[0], s[1])
        };
        let mut forward = vec![first, second];
        walk(i, second, &mut used, &mut forward);
        let closed = forward.len() > 2 && forward.first() == forward.last();
        if closed {
            forward.pop();
        } else {
            // A chain found from its middle: extend backwards from the first crossing too.
            let mut backward = Vec::new();
            walk(i, first, &mut used, &mut backward);
            if !backward.is_empty() {
                backward.reverse();
                backward.extend(forward);
                forward = backward;
            }
        }
        lines.push(Polyline {
            points: forward.into_iter().map(&point_of).collect(),
            closed,
        });
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cone f = −distance from (cx, cy) on a `n × n` grid.
    fn cone(n: usize, cx: f64, cy: f64) -> Vec<f64> {
        (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f64, (i / n) as f64);
                -(x - cx).hypot(y - cy)
            })
            .collect()
    }

    #[test]
    fn a_cone_gives_one_closed_ring_at_the_right_radius() {
        let n = 21;
        let f = cone(n, 10.0, 10.0);
        let lines = contour_lines(&f, n, n, -6.0);
        assert_eq!(lines.len(), 1);
        let ring = &lines[0];
        assert!(ring.closed);
        assert!(ring.points.len() > 30);
        for p in &ring.points {
            let r = (p[0] - 10.0).hypot(p[1] - 10.0);
            // Linear interpolation of a cone along grid edges: within a few % of the radius.
            assert!((r - 6.0).abs() < 0.1, "{p:?} at r {r}");
        }
        // Consecutive points are neighbours (no jumps across the ring).
        let pts = &ring.points;
        for k in 0..pts.len() {
            let (a, b) = (pts[k], pts[(k + 1) % pts.len()]);
            assert!((a[0] - b[0]).hypot(a[1] - b[1]) <= 1.5, "{a:?} → {b:?}");
        }
    }

    #[test]
    fn a_ring_cut_by_the_border_is_one_open_line_from_border_to_border() {
        let n = 11;
        let f = cone(n, 0.0, 5.0); // centre on the left border
        let lines = contour_lines(&f, n, n, -4.0);
        assert_eq!(lines.len(), 1);
        let line = &lines[0];
        assert!(!line.closed);
        let on_border = |p: [f64; 2]| p[0] <= 1e-12 || p[1] <= 1e-12 || p[1] >= (n - 1) as f64 - 1e-12;
        assert!(on_border(line.points[0]) && on_border(line.points[line.points.len() - 1]));
        // A half ring of radius 4: from (0, 1) to (0, 9) through (4, 5).
        assert!(line
            .points
            .iter()
            .any(|p| (p[0] - 4.0).abs() < 1e-9 && (p[1] - 5.0).abs() < 1e-9));
    }

    #[test]
    fn linear_field_is_crossed_exactly() {
        // f = x + 2y on 5 × 4; the level 3.5 passes through (3.5, 0), (1.5, 1), (0, 1.75).
        let (cols, rows) = (5, 4);
        let f: Vec<f64> = (0..cols * rows)
            .map(|i| (i % cols) as f64 + 2.0 * (i / cols) as f64)
            .collect();
        let lines = contour_lines(&f, cols, rows, 3.5);
        assert_eq!(lines.len(), 1);
        for p in &lines[0].points {
            assert!((p[0] + 2.0 * p[1] - 3.5).abs() < 1e-12, "{p:?}");
        }
        assert!(!lines[0].closed);
    }

    #[test]
    fn two_peaks_give_two_rings_and_a_saddle_is_consistent() {
        // Two cones side by side: at a low level one ring round both, at a high level two.
        let n = 31;
        let (a, b) = (cone(n, 10.0, 15.0), cone(n, 20.0, 15.0));
        let f: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x.max(*y)).collect();
        let high = contour_lines(&f, n, n, -3.0);
        assert_eq!(high.len(), 2);
        assert!(high.iter().all(|l| l.closed));
        let low = contour_lines(&f, n, n, -8.0);
        assert_eq!(low.len(), 1);
        assert!(low[0].closed);
        // A 2 × 2 saddle, (0,0) and (1,1) above, mean above: the below corners are cut off.
        let saddle = [1.0, 0.0, 0.0, 1.0];
        let lines = contour_lines(&saddle, 2, 2, 0.4);
        assert_eq!(lines.len(), 2);
        assert!(lines.iter().all(|l| !l.closed && l.points.len() == 2));
    }

    #[test]
    fn degenerate_inputs_give_no_lines() {
        assert!(contour_lines(&[1.0; 4], 1, 4, 0.5).is_empty());
        assert!(contour_lines(&[1.0; 3], 2, 2, 0.5).is_empty());
        assert!(contour_lines(&[1.0; 4], 2, 2, f64::NAN).is_empty());
        assert!(contour_lines(&[1.0; 4], 2, 2, 0.5).is_empty()); // all above
        let with_nan = [f64::NAN, 1.0, 1.0, 1.0];
        let lines = contour_lines(&with_nan, 2, 2, 0.5);
        assert_eq!(lines.len(), 1);
        assert!(lines[0].points.iter().all(|p| p[0].is_finite() && p[1].is_finite()));
    }
}
