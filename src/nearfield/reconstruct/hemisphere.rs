//! Whether a set of unit vectors lies in an open hemisphere: the test that lets a one-sided
//! emitter survive carving. A point may hold a surface that emits towards the cameras that see it
//! lit and not towards those that see it dark exactly when some plane through it has every lit
//! camera in front and every dark one behind, i.e. when the lit directions and the negated dark
//! ones lie in one open hemisphere, i.e. when the origin is outside their convex hull. That distance
//! comes from GJK (Gilbert, Johnson, Keerthi 1988) on the point set.

use glam::DVec3;

/// Whether some unit `n` has `n·v > 0` for every `v` in `vs` (true for an empty set).
pub fn in_open_hemisphere(vs: &[DVec3]) -> bool {
    let Some(&first) = vs.first() else { return true };
    origin_outside_hull(first, &|x| lowest(vs, x))
}

/// Whether some plane (not necessarily through the origin) has every point of `a` strictly on one
/// side and every point of `b` strictly on the other: their convex hulls do not meet, i.e. the
/// origin lies outside the hull of the Minkowski difference `a − b` (true when either is empty).
/// For directions towards cameras: `a` fits in a cap (a cone of any width) that holds no point of
/// `b`, the test for a directional emitter.
pub fn separable(a: &[DVec3], b: &[DVec3]) -> bool {
    let (Some(&a0), Some(&b0)) = (a.first(), b.first()) else {
        return true;
    };
    origin_outside_hull(a0 - b0, &|x| lowest(a, x) - lowest(b, -x))
}

/// The point of `vs` with the least dot product with `x`.
fn lowest(vs: &[DVec3], x: DVec3) -> DVec3 {
    vs.iter()
        .copied()
        .min_by(|p, q| p.dot(x).total_cmp(&q.dot(x)))
        .unwrap_or(DVec3::ZERO)
}

/// GJK: whether the origin lies strictly outside the convex hull of a point set given by its
/// support (`support(x)`: the point of the set with the least dot product with `x`), starting from
/// one of its points.
fn origin_outside_hull(first: DVec3, support: &dyn Fn(DVec3) -> DVec3) -> bool {
    let mut simplex: Vec<DVec3> = vec![first];
    let mut x = first;
    for _ in 0..64 {
        let xx = x.length_squared();
        if xx < 1e-24 {
            return false;
        }
        // Support point of the hull in direction −x.
        let w = support(x);
        if w.dot(x) > 0.0 {
            // Every point is strictly on x's side: x separates.
            return true;
        }
        if xx - x.dot(w) <= 1e-12 * xx.max(1e-12) {
            // No progress: |x| is the distance (> 0).
            return true;
        }
        simplex.push(w);
        match closest_on_simplex(&simplex) {
            Some((p, kept)) => {
                x = p;
                simplex = kept;
            }
            None => return false,
        }
    }
    // Not converged: treat as touching (the origin within rounding of the hull).
    false
}

/// The point of the simplex's hull nearest the origin and the smallest face holding it; `None`
/// when the origin is inside (a tetrahedron) or on it.
fn closest_on_simplex(s: &[DVec3]) -> Option<(DVec3, Vec<DVec3>)> {
    let n = s.len();
    if n == 4 && inside_tetrahedron(s) {
        return None;
    }
    let mut best: Option<(f64, DVec3, Vec<DVec3>)> = None;
    // Every non-empty subset (faces of every dimension).
    for mask in 1u32..(1 << n) {
        let pts: Vec<DVec3> = (0..n).filter(|i| mask & (1 << i) != 0).map(|i| s[i]).collect();
        let Some(p) = affine_closest(&pts) else { continue };
        let d = p.length_squared();
        if best.as_ref().is_none_or(|b| d < b.0 - 1e-30) {
            best = Some((d, p, pts));
        }
    }
    best.map(|(_, p, pts)| (p, pts))
}

/// The origin's projection onto the affine hull of `pts` (1–3 points) when it falls strictly
/// inside their simplex, else `None`. Four points: `None` (handled by the inside test).
fn affine_closest(pts: &[DVec3]) -> Option<DVec3> {
    match pts.len() {
        1 => Some(pts[0]),
        2 => {
            let (a, b) = (pts[0], pts[1]);
            let ab = b - a;
            let l = ab.length_squared();
            if l <= 0.0 {
                return None;
            }
            let t = -a.dot(ab) / l;
            (t > 0.0 && t < 1.0).then(|| a + t * ab)
        }
        3 => {
            let (a, b, c) = (pts[0], pts[1], pts[2]);
            let n = (b - a).cross(c - a);
            let nn = n.length_squared();
            if nn <= 0.0 {
                return None;
            }
            let p = n * (a.dot(n) / nn);
            // Barycentric coordinates of p.
            let u = (b - p).cross(c - p).dot(n);
            let v = (c - p).cross(a - p).dot(n);
            let w = (a - p).cross(b - p).dot(n);
            (u > 0.0 && v > 0.0 && w > 0.0).then_some(p)
        }
        _ => None,
    }
}

/// Whether the origin lies inside (or on) the tetrahedron.
fn inside_tetrahedron(s: &[DVec3]) -> bool {
    let side = |a: DVec3, b: DVec3, c: DVec3, d: DVec3| {
        let n = (b - a).cross(c - a);
        let sd = n.dot(d - a);
        let so = n.dot(-a);
        sd * so >= 0.0
    };
    side(s[0], s[1], s[2], s[3])
        && side(s[1], s[2], s[3], s[0])
        && side(s[2], s[3], s[0], s[1])
        && side(s[3], s[0], s[1], s[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(theta_deg: f64, phi_deg: f64) -> DVec3 {
        let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
        DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), -t.cos())
    }

    #[test]
    fn a_cap_against_its_back_is_one_sided_and_a_ring_around_a_cap_is_not() {
        // Lit from every direction below up to 89° from the nadir; dark from just above the
        // horizon (a one-sided emitter's back): separable by the horizontal plane.
        let mut lit = Vec::new();
        for t in (0..=89).step_by(7) {
            for p in (0..360).step_by(15) {
                lit.push(dir(f64::from(t), f64::from(p)));
            }
        }
        let back: Vec<DVec3> = (0..360).step_by(20).map(|p| -dir(91.0, f64::from(p))).collect();
        let v: Vec<DVec3> = lit.iter().copied().chain(back).collect();
        assert!(in_open_hemisphere(&v));
        // Dark from a ring of grazing directions below (a point in front of the emitter): the dark
        // ring surrounds the lit cap, so no plane separates them.
        let lit_cap: Vec<DVec3> = lit
            .iter()
            .copied()
            .filter(|d| d.z < -(80f64.to_radians().cos()))
            .collect();
        let ring: Vec<DVec3> = (0..360).step_by(20).map(|p| -dir(88.0, f64::from(p))).collect();
        let v2: Vec<DVec3> = lit_cap.into_iter().chain(ring).collect();
        assert!(!in_open_hemisphere(&v2));
        // Trivial cases.
        assert!(in_open_hemisphere(&[]));
        assert!(in_open_hemisphere(&[DVec3::X, DVec3::Y]));
        assert!(!in_open_hemisphere(&[DVec3::X, -DVec3::X]));
        assert!(!in_open_hemisphere(&[
            DVec3::X,
            DVec3::Y,
            DVec3::Z,
            -(DVec3::ONE.normalize())
        ]));
        // A tiny margin still separates.
        assert!(in_open_hemisphere(&[dir(89.9, 0.0), dir(89.9, 180.0), dir(0.0, 0.0)]));
    }

    #[test]
    fn a_narrow_cap_is_separable_from_the_dark_around_it_and_a_ring_between_dark_is_not() {
        // A beam: lit within 20° of the nadir, dark from 30° to 90° (and the back): one cap.
        let cap: Vec<DVec3> = (0..=20)
            .step_by(5)
            .flat_map(|t| (0..360).step_by(30).map(move |p| dir(f64::from(t), f64::from(p))))
            .collect();
        let rest: Vec<DVec3> = (30..=180)
            .step_by(10)
            .flat_map(|t| (0..360).step_by(30).map(move |p| dir(f64::from(t), f64::from(p))))
            .collect();
        assert!(separable(&cap, &rest));
        assert!(separable(&rest, &cap));
        // Not a hemisphere test: the lit and the negated dark do not lie in one open hemisphere.
        let mixed: Vec<DVec3> = cap.iter().copied().chain(rest.iter().map(|d| -*d)).collect();
        assert!(!in_open_hemisphere(&mixed));
        // Dark at the cap's centre as well as around it: the lit ring lies between dark
        // directions, and no plane separates.
        let ring: Vec<DVec3> = cap
            .iter()
            .copied()
            .filter(|d| d.z > -(4f64.to_radians().cos()))
            .collect();
        let mut dark = rest.clone();
        dark.push(dir(0.0, 0.0));
        assert!(!separable(&ring, &dark));
        // Lit towards both poles, dark around the equator: no plane either.
        let two: Vec<DVec3> = cap.iter().copied().chain(cap.iter().map(|d| -*d)).collect();
        let equator: Vec<DVec3> = (0..360).step_by(30).map(|p| dir(90.0, f64::from(p))).collect();
        assert!(!separable(&two, &equator));
        assert!(separable(&[], &rest) && separable(&cap, &[]));
    }
}
