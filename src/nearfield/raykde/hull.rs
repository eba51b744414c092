//! The source geometry a ray set implies: its rays start on (or near) the emitting surfaces, so the
//! convex hull of the start points, grown by the spatial kernel (the estimate spreads light that
//! far), is a proxy for parallax-correct rendering.
//!
//! The grown hull is built without a hull algorithm: for each vertex direction v of a geodesic
//! sphere, the point of the cloud farthest along v (its support point) plus `grow · v`. A convex
//! body grown by a ball is strictly convex, so this map from the sphere onto its boundary is one to
//! one and the geodesic sphere's triangles, moved to those points, tile the boundary (as chords: a
//! little inside it). A point source becomes a ball of radius `grow`.

use std::collections::HashMap;

use glam::DVec3;
use rayon::prelude::*;

use crate::nearfield::synth::proxy::{ProxyMesh, ProxySurface};

/// Most start points kept for the support functions (an even stride through the rays).
const MAX_POINTS: usize = 200_000;

/// Subdivisions of the icosahedron: 3 gives 642 vertices and 1280 triangles.
const SUBDIVISIONS: u32 = 3;

/// The ray start points, summarised.
#[derive(Debug, Clone)]
pub struct SourceCloud {
    /// Centre of their bounding box (m).
    pub centre: DVec3,
    /// Largest distance of a start point from `centre` (m).
    pub radius: f64,
    /// Bounding box (m).
    pub min: DVec3,
    /// Bounding box (m).
    pub max: DVec3,
    points: Vec<DVec3>,
}

impl SourceCloud {
    /// Summarises the `n` start points `origin(i)` (`None` for rays to skip).
    pub fn of(origin: impl Fn(usize) -> Option<DVec3> + Sync, n: usize) -> Self {
        let (min, max) = (0..n).into_par_iter().filter_map(&origin).map(|p| (p, p)).reduce(
            || (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
        let (min, max) = if min.x.is_finite() {
            (min, max)
        } else {
            (DVec3::ZERO, DVec3::ZERO)
        };
        let centre = (min + max) / 2.0;
        let stride = n.div_ceil(MAX_POINTS).max(1);
        let points: Vec<DVec3> = (0..n).step_by(stride).filter_map(&origin).collect();
        let radius = (0..n)
            .into_par_iter()
            .filter_map(&origin)
            .map(|p| (p - centre).length())
            .reduce(|| 0.0, f64::max);
        Self {
            centre,
            radius,
            min,
            max,
            points,
        }
    }

    /// The convex hull of the points grown by `grow` metres (> 0), as a one-surface proxy mesh with
    /// outward normals and counter-clockwise outward faces.
    pub fn proxy(&self, grow: f64, name: &str) -> ProxyMesh {
        let (dirs, tris) = geodesic_sphere(SUBDIVISIONS);
        let grow = grow.max(1e-9);
        let positions: Vec<DVec3> = dirs
            .par_iter()
            .map(|v| {
                let s = self
                    .points
                    .iter()
                    .copied()
                    .max_by(|a, b| a.dot(*v).total_cmp(&b.dot(*v)))
                    .unwrap_or(self.centre);
                s + *v * grow
            })
            .collect();
        let mut mesh = ProxyMesh::new(name);
        mesh.surfaces.push(ProxySurface {
            name: "grown hull of the ray start points".to_string(),
            positions,
            normals: dirs,
            indices: tris.iter().flat_map(|t| t.iter().copied()).collect(),
        });
        mesh
    }
}

/// The vertices (unit vectors) and counter-clockwise outward triangles of an icosahedron
/// subdivided `n` times.
pub fn geodesic_sphere(n: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<DVec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..n {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut next = Vec::with_capacity(f.len() * 4);
        let mut midpoint = |a: u32, b: u32, v: &mut Vec<DVec3>| -> u32 {
            let key = (a.min(b), a.max(b));
            *mid.entry(key).or_insert_with(|| {
                v.push(((v[a as usize] + v[b as usize]) / 2.0).normalize());
                (v.len() - 1) as u32
            })
        };
        for [a, b, c] in f {
            let ab = midpoint(a, b, &mut v);
            let bc = midpoint(b, c, &mut v);
            let ca = midpoint(c, a, &mut v);
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    (v, f)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn geodesic_sphere_is_closed_and_outward() {
        let (v, f) = geodesic_sphere(3);
        assert_eq!((v.len(), f.len()), (642, 1280));
        let mut area = 0.0;
        for [a, b, c] in &f {
            let (a, b, c) = (v[*a as usize], v[*b as usize], v[*c as usize]);
            let n = (b - a).cross(c - a);
            assert!(n.dot(a + b + c) > 0.0, "inward triangle");
            area += n.length() / 2.0;
        }
        assert!((area - 4.0 * std::f64::consts::PI).abs() < 0.05 * 4.0 * std::f64::consts::PI);
    }

    #[test]
    fn a_square_of_points_grows_into_a_flat_box() {
        let pts: Vec<DVec3> = (0..400)
            .map(|i| DVec3::new(f64::from(i % 20) * 0.001, f64::from(i / 20) * 0.001, 0.0))
            .collect();
        let c = SourceCloud::of(|i| pts.get(i).copied(), pts.len());
        assert!((c.centre - DVec3::new(0.0095, 0.0095, 0.0)).length() < 1e-12);
        let m = c.proxy(0.0005, "t");
        let p = &m.surfaces[0].positions;
        let zmax = p.iter().map(|q| q.z).fold(f64::MIN, f64::max);
        let xmax = p.iter().map(|q| q.x).fold(f64::MIN, f64::max);
        assert!(
            (zmax - 0.0005).abs() < 1e-9 && (xmax - 0.0195).abs() < 1e-9,
            "{zmax} {xmax}"
        );
        // A point becomes a ball.
        let one = [DVec3::new(0.1, 0.2, 0.3)];
        let b = SourceCloud::of(|i| one.get(i).copied(), 1).proxy(0.01, "p");
        assert!(b.surfaces[0]
            .positions
            .iter()
            .all(|q| ((*q - one[0]).length() - 0.01).abs() < 1e-12));
    }
}
