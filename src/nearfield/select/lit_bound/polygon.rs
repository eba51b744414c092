//! Plane geometry of the bounding polygons (screen pixels): bounding-box overlap, signed area,
//! growing a convex polygon or a triangle outwards, clipping convex polygons, and the convex hull.

use glam::Vec2;

/// Whether the bounding boxes of two point sets are disjoint.
pub(super) fn disjoint(a: &[Vec2], b: &[Vec2]) -> bool {
    let bbox = |p: &[Vec2]| {
        p.iter().fold(
            (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
            |(lo, hi), q| (lo.min(*q), hi.max(*q)),
        )
    };
    let ((alo, ahi), (blo, bhi)) = (bbox(a), bbox(b));
    ahi.x < blo.x || bhi.x < alo.x || ahi.y < blo.y || bhi.y < alo.y
}

/// Twice the signed area of a polygon (positive counter-clockwise, y up).
fn twice_area(p: &[Vec2]) -> f32 {
    (0..p.len()).map(|i| p[i].perp_dot(p[(i + 1) % p.len()])).sum()
}

/// A convex polygon (pixels, either orientation) with each edge moved `d` pixels outwards; `None`
/// when degenerate.
pub(super) fn grow_convex(p: &[Vec2], d: f32) -> Option<Vec<Vec2>> {
    let n = p.len();
    let area = twice_area(p);
    if area.is_nan() || area.abs() <= 1e-6 {
        return None;
    }
    let s = area.signum();
    let line = |k: usize| {
        let (a, b) = (p[k], p[(k + 1) % n]);
        let t = (b - a).normalize_or_zero();
        (a + Vec2::new(t.y, -t.x) * s * d, t)
    };
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let (a0, t0) = line(k);
        let (a1, t1) = line((k + 1) % n);
        let den = t0.perp_dot(t1);
        if den.abs() < 1e-6 {
            // Collinear edges (or a zero-length one): the shared vertex, moved out.
            out.push(a1);
            continue;
        }
        out.push(a0 + t0 * ((a1 - a0).perp_dot(t1) / den));
    }
    Some(out)
}

/// A triangle (pixels) with each edge moved `d` pixels outwards; `None` when degenerate.
pub(super) fn grow_triangle(p: [Vec2; 3], d: f32) -> Option<Vec<Vec2>> {
    let area = (p[1] - p[0]).perp_dot(p[2] - p[0]);
    if area.is_nan() || area.abs() <= 1e-6 {
        return None;
    }
    let s = area.signum();
    // Edge k from p[k] to p[k+1], outward normal.
    let line = |k: usize| {
        let (a, b) = (p[k], p[(k + 1) % 3]);
        let t = (b - a).normalize();
        let nrm = Vec2::new(t.y, -t.x) * s;
        (a + nrm * d, t)
    };
    let mut out = Vec::with_capacity(3);
    for k in 0..3 {
        // Vertex k+1 is where edge k and edge k+1 meet.
        let (a0, t0) = line(k);
        let (a1, t1) = line((k + 1) % 3);
        let den = t0.perp_dot(t1);
        if den.abs() < 1e-6 {
            return None;
        }
        let u = (a1 - a0).perp_dot(t1) / den;
        out.push(a0 + t0 * u);
    }
    Some(out)
}

/// The intersection of two convex polygons (either orientation): `subject` clipped by each edge of
/// `clip` (Sutherland–Hodgman).
pub(super) fn clip_convex(subject: &[Vec2], clip: &[Vec2]) -> Vec<Vec2> {
    let orient = if twice_area(clip) >= 0.0 { 1.0 } else { -1.0 };
    let mut out = subject.to_vec();
    for i in 0..clip.len() {
        out = clip_half(&out, clip[i], clip[(i + 1) % clip.len()], orient);
        if out.is_empty() {
            break;
        }
    }
    out
}

/// The part of convex `subject` where `orient · (b − a) ⊥· (p − a) ≥ 0` (the left of a → b for
/// `orient` 1).
fn clip_half(subject: &[Vec2], a: Vec2, b: Vec2, orient: f32) -> Vec<Vec2> {
    let side = |p: Vec2| orient * (b - a).perp_dot(p - a);
    let mut out = Vec::with_capacity(subject.len() + 1);
    for k in 0..subject.len() {
        let (p, q) = (subject[k], subject[(k + 1) % subject.len()]);
        let (sp, sq) = (side(p), side(q));
        if sp >= 0.0 {
            out.push(p);
        }
        if (sp >= 0.0) != (sq >= 0.0) {
            out.push(p + (q - p) * (sp / (sp - sq)));
        }
    }
    out
}

/// Convex hull (Andrew's monotone chain) of 2D points carrying a payload, counter-clockwise, without
/// collinear points.
pub(super) fn convex_hull<T: Copy>(mut p: Vec<(f32, f32, T)>) -> Vec<(f32, f32, T)> {
    p.retain(|q| q.0.is_finite() && q.1.is_finite());
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    if p.len() < 3 {
        return p;
    }
    let cross = |o: &(f32, f32, T), a: &(f32, f32, T), b: &(f32, f32, T)| {
        f64::from(a.0 - o.0) * f64::from(b.1 - o.1) - f64::from(a.1 - o.1) * f64::from(b.0 - o.0)
    };
    let mut h: Vec<(f32, f32, T)> = Vec::with_capacity(2 * p.len());
    // Lower chain on the way right.
    for q in &p {
        while h.len() >= 2 && cross(&h[h.len() - 2], &h[h.len() - 1], q) <= 0.0 {
            h.pop();
        }
        h.push(*q);
    }
    // Upper chain on the way back, never popping into the lower one.
    let floor = h.len() + 1;
    for q in p.iter().rev().skip(1) {
        while h.len() >= floor && cross(&h[h.len() - 2], &h[h.len() - 1], q) <= 0.0 {
            h.pop();
        }
        h.push(*q);
    }
    h.pop();
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn growing_a_convex_polygon_moves_every_edge_out() {
        // Clockwise, to check the orientation is handled.
        let sq = [
            Vec2::new(0.0, 0.0),
            Vec2::new(0.0, 2.0),
            Vec2::new(2.0, 2.0),
            Vec2::new(2.0, 0.0),
        ];
        let g = grow_convex(&sq, 1.0).unwrap();
        let area = 0.5 * twice_area(&g);
        assert!((area.abs() - 16.0).abs() < 1e-4, "{g:?}");
        let t = grow_triangle([Vec2::new(0.0, 0.0), Vec2::new(4.0, 0.0), Vec2::new(0.0, 3.0)], 0.5).unwrap();
        // Every original vertex lies inside the grown triangle, at least 0.5 from each edge.
        for v in [Vec2::new(0.0, 0.0), Vec2::new(4.0, 0.0), Vec2::new(0.0, 3.0)] {
            for i in 0..3 {
                let (a, b) = (t[i], t[(i + 1) % 3]);
                let dist = (b - a).perp_dot(v - a) / (b - a).length();
                assert!(dist.abs() >= 0.5 - 1e-4, "{v} {t:?}");
            }
        }
        assert!(grow_convex(&[Vec2::ZERO, Vec2::X, Vec2::X * 2.0], 1.0).is_none());
    }

    #[test]
    fn clipping_two_squares() {
        let a = [
            Vec2::new(0.0, 0.0),
            Vec2::new(2.0, 0.0),
            Vec2::new(2.0, 2.0),
            Vec2::new(0.0, 2.0),
        ];
        // Clockwise clip polygon: orientation must not matter.
        let b = [
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 3.0),
            Vec2::new(3.0, 3.0),
            Vec2::new(3.0, 1.0),
        ];
        let c = clip_convex(&a, &b);
        let area = 0.5 * twice_area(&c);
        assert!((area.abs() - 1.0).abs() < 1e-5, "{c:?}");
        let far = [Vec2::new(5.0, 5.0), Vec2::new(6.0, 5.0), Vec2::new(6.0, 6.0)];
        assert!(clip_convex(&a, &far).is_empty());
    }

    #[test]
    fn hull_of_a_square_with_inner_points() {
        let mut p = vec![(0.0, 0.0, 0), (1.0, 0.0, 1), (1.0, 1.0, 2), (0.0, 1.0, 3)];
        p.push((0.5, 0.5, 4));
        p.push((0.2, 0.7, 5));
        p.push((0.5, 0.0, 6)); // on an edge
        let h = convex_hull(p);
        let ids: Vec<i32> = h.iter().map(|q| q.2).collect();
        assert_eq!(ids.len(), 4, "{ids:?}");
        for id in [0, 1, 2, 3] {
            assert!(ids.contains(&id), "{ids:?}");
        }
        // Counter-clockwise: positive area.
        let area: f32 = (0..h.len())
            .map(|i| {
                let (a, b) = (h[i], h[(i + 1) % h.len()]);
                a.0 * b.1 - b.0 * a.1
            })
            .sum();
        assert!(area > 0.0);
    }

    #[test]
    fn hull_of_degenerate_input() {
        assert!(convex_hull::<u8>(vec![]).is_empty());
        assert_eq!(convex_hull(vec![(0.0, 0.0, 0u8), (1.0, 1.0, 1)]).len(), 2);
        assert_eq!(
            convex_hull(vec![(0.0, 0.0, 0u8), (1.0, 1.0, 1), (2.0, 2.0, 2)]).len(),
            2
        );
        assert_eq!(convex_hull(vec![(f32::NAN, 0.0, 0u8)]).len(), 0);
    }
}
