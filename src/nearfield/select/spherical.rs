//! Spherical geometry of the selection build: great-circle angles, the grid's (φ, θ) convention,
//! distances to great-circle arcs, and the exact test of a cap against a spherical triangle.

use std::f64::consts::{PI, TAU};

use glam::DVec3;

/// Great-circle angle between two unit vectors (rad), accurate at small and large angles alike
/// (`atan2(|a × b|, a · b)`; `acos(a · b)` loses half the digits near 0).
pub(super) fn angle(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// The grid's angles of a unit vector: φ = atan2(y, x) in [0, 2π), θ = acos(z) in [0, π] (θ from +Z).
pub(super) fn phi_theta(u: DVec3) -> (f64, f64) {
    let mut phi = u.y.atan2(u.x);
    if phi < 0.0 {
        phi += TAU;
    }
    (phi, u.z.clamp(-1.0, 1.0).acos())
}

/// The unit vector of grid angles (φ, θ).
pub(super) fn from_phi_theta(phi: f64, theta: f64) -> DVec3 {
    let (sp, cp) = phi.sin_cos();
    let (st, ct) = theta.sin_cos();
    DVec3::new(st * cp, st * sp, ct)
}

/// Great-circle distance (rad) from the unit vector `p` to the minor arc from `a` to `b` (unit
/// vectors, not antipodal).
pub(super) fn arc_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let n = a.cross(b);
    let len = n.length();
    let ends = || angle(p, a).min(angle(p, b));
    if len <= 1e-300 {
        return ends();
    }
    let n = n / len;
    // The foot of p on the great circle, q ∝ p − (p·n) n, lies on the arc iff it is on the inner side
    // of both end points: (a × q)·n ≥ 0 and (q × b)·n ≥ 0, i.e. p·(n × a) ≥ 0 and p·(b × n) ≥ 0.
    if p.dot(n.cross(a)) >= 0.0 && p.dot(b.cross(n)) >= 0.0 {
        let h = p.dot(n);
        let q = (p - h * n).length();
        if q > 0.0 {
            return h.abs().atan2(q);
        }
    }
    ends()
}

/// A spherical triangle (a, b, c), counter-clockwise seen from outside (det(a, b, c) > 0), with the unit
/// normals of its three great circles pointing inwards.
#[derive(Debug, Clone, Copy)]
pub(super) struct SphericalTriangle {
    /// The vertices.
    pub v: [DVec3; 3],
    /// normalize(b × c), normalize(c × a), normalize(a × b): x is inside iff x · n_i ≥ 0 for all i.
    pub n: [DVec3; 3],
}

impl SphericalTriangle {
    /// The triangle of three unit vectors (oriented so that det > 0 by the caller).
    pub fn new(a: DVec3, b: DVec3, c: DVec3) -> Self {
        Self {
            v: [a, b, c],
            n: [
                b.cross(c).normalize_or_zero(),
                c.cross(a).normalize_or_zero(),
                a.cross(b).normalize_or_zero(),
            ],
        }
    }

    /// Whether the cap of centre `c` (unit) and radius `rho` (< π/2) intersects the triangle: `c` is
    /// inside, or within `rho` of one of the three edges (great-circle arcs).
    pub fn meets_cap(&self, c: DVec3, rho: f64) -> bool {
        let s = [c.dot(self.n[0]), c.dot(self.n[1]), c.dot(self.n[2])];
        if s.iter().all(|&x| x >= 0.0) {
            return true;
        }
        // The triangle lies on the inner side of each great circle; a cap entirely on the outer side of
        // one (its centre more than rho beyond it) cannot meet it.
        let sin_rho = rho.min(0.5 * PI).sin();
        if s.iter().any(|&x| x < -sin_rho - 1e-12) {
            return false;
        }
        let [a, b, cc] = self.v;
        arc_distance(c, b, cc) <= rho || arc_distance(c, cc, a) <= rho || arc_distance(c, a, b) <= rho
    }

    /// A cap enclosing the triangle: the smaller of the circumcap and the cap around the normalised
    /// centroid through the farthest vertex. Both hold the spherical triangle when their radius is below
    /// π/2 (a cap that small is convex); otherwise the whole sphere is returned (radius π).
    pub fn enclosing_cap(&self, circumcentre: DVec3, circumradius: f64) -> (DVec3, f64) {
        let [a, b, c] = self.v;
        let m = (a + b + c).normalize_or_zero();
        let rm = angle(m, a).max(angle(m, b)).max(angle(m, c));
        let (centre, r) = if rm <= circumradius || !circumcentre.is_finite() {
            (m, rm)
        } else {
            (circumcentre, circumradius)
        };
        if r < 0.5 * PI && centre != DVec3::ZERO {
            (centre, r)
        } else {
            (DVec3::Z, PI)
        }
    }
}

/// The circumcentre (unit, on the side of a + b + c) and circumradius (rad) of the spherical triangle
/// (a, b, c): the pole of the plane through the three points, and its angle to `a`.
pub(super) fn circumcap(a: DVec3, b: DVec3, c: DVec3) -> (DVec3, f64) {
    let mut n = (b - a).cross(c - a).normalize_or_zero();
    if n.dot(a + b + c) < 0.0 {
        n = -n;
    }
    (n, angle(n, a))
}

/// det(a, b, c) = a · (b × c), evaluated as ((b − a) × (c − a)) · a (the same value, with less
/// cancellation for small triangles).
pub(super) fn det(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    (b - a).cross(c - a).dot(a)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn angle_is_accurate_near_zero_and_pi() {
        let a = DVec3::X;
        let b = DVec3::new(1.0, 1e-9, 0.0).normalize();
        assert!((angle(a, b) - 1e-9).abs() < 1e-20);
        assert!((angle(a, -b) - (PI - 1e-9)).abs() < 1e-15);
    }

    #[test]
    fn phi_theta_round_trips() {
        for &(p, t) in &[(0.0, 0.3), (1.0, 1.2), (3.5, 2.9), (6.2, 0.01)] {
            let (p2, t2) = phi_theta(from_phi_theta(p, t));
            assert!((p - p2).abs() < 1e-12 && (t - t2).abs() < 1e-12, "{p} {t} -> {p2} {t2}");
        }
        // −0.0 and the negative half map into [0, 2π).
        let (p, _) = phi_theta(DVec3::new(1.0, -0.0, 0.0));
        assert_eq!(p, 0.0);
        let (p, _) = phi_theta(DVec3::new(0.0, -1.0, 0.0));
        assert!((p - 1.5 * PI).abs() < 1e-15);
    }

    #[test]
    fn arc_distance_interior_and_ends() {
        let (a, b) = (DVec3::X, DVec3::Y);
        // Above the middle of the arc: distance = elevation.
        let p = DVec3::new(1.0, 1.0, 0.2f64.tan() * 2f64.sqrt()).normalize();
        assert!((arc_distance(p, a, b) - 0.2).abs() < 1e-12);
        // Beyond the end a: distance to a.
        let q = DVec3::new(1.0, -0.3, 0.1).normalize();
        assert!((arc_distance(q, a, b) - angle(q, a)).abs() < 1e-15);
        // Brute force along the arc.
        for p in [p, q, DVec3::new(-0.2, 0.5, -0.8).normalize()] {
            let brute = (0..=20_000)
                .map(|k| {
                    let t = 0.5 * PI * k as f64 / 20_000.0;
                    angle(p, DVec3::new(t.cos(), t.sin(), 0.0))
                })
                .fold(f64::MAX, f64::min);
            assert!((arc_distance(p, a, b) - brute).abs() < 1e-4, "{p}");
        }
    }

    #[test]
    fn cap_test_matches_sampling() {
        let t = SphericalTriangle::new(
            DVec3::new(1.0, 0.0, 0.1).normalize(),
            DVec3::new(0.0, 1.0, 0.1).normalize(),
            DVec3::new(0.1, 0.1, 1.0).normalize(),
        );
        assert!(det(t.v[0], t.v[1], t.v[2]) > 0.0);
        let inside = |x: DVec3| t.n.iter().all(|n| x.dot(*n) >= 0.0);
        // A cap that only grazes one edge.
        let c = DVec3::new(-0.3, -0.3, 1.0).normalize();
        let d = arc_distance(c, t.v[2], t.v[0]).min(arc_distance(c, t.v[1], t.v[2]));
        assert!(!inside(c));
        assert!(t.meets_cap(c, d + 1e-9));
        assert!(!t.meets_cap(c, d - 1e-6));
        // The enclosing cap holds sampled interior points.
        let (cc, r) = circumcap(t.v[0], t.v[1], t.v[2]);
        let (m, rm) = t.enclosing_cap(cc, r);
        for i in 0..=20 {
            for j in 0..=(20 - i) {
                let (x, y) = (i as f64 / 20.0, j as f64 / 20.0);
                let p = (t.v[0] * x + t.v[1] * y + t.v[2] * (1.0 - x - y)).normalize();
                assert!(angle(p, m) <= rm + 1e-12);
            }
        }
        // Circumcap: equidistant from the three vertices.
        for v in t.v {
            assert!((angle(cc, v) - r).abs() < 1e-12);
        }
    }
}
