//! Flat parts of a refined proxy made lean: once [`super::refine`] has put a flat part on its plane,
//! the part is two coplanar sheets (the collapsed lens's two faces, joined at the outline) finely
//! tessellated by the carving's cells: tens of thousands of triangles that say no more than their
//! outline does. Inside a plane a triangle's size does not matter. Both sheets are kept (each made
//! lean): keeping only one was measured to leave pinholes where that sheet had a gap the other
//! covered (a one-pixel black speck on a two-planes tile in the README's view).
//!
//! Promises:
//! - Only triangles whose three vertices lie on one of the given planes are touched; everything else
//!   (curved or unflattened parts) is kept as it is.
//! - Vertices are removed by edge collapse where that changes nothing a view can see: a vertex
//!   whose triangles are all flat, on one plane and facing one way moves onto a neighbour when no
//!   triangle turns over or becomes thinner than [`MIN_HEIGHT_UNITS`], and the mesh stays
//!   manifold there (link condition). A vertex of the outline moves only along it, onto an outline
//!   neighbour, and only while every outline point it stood for stays within [`OUTLINE_TOLERANCE_UNITS`]
//!   of the straightened outline. The outline therefore keeps its shape to that tolerance, and the
//!   covered region is unchanged inside it.
//! - Unused vertices are dropped; triangles keep their winding.

use std::collections::HashMap;

use glam::{DVec2, DVec3};

use super::mesh::Mesh;

/// An outline point stays within this many units of the simplified outline.
pub const OUTLINE_TOLERANCE_UNITS: f64 = 0.05;

/// No triangle made by a collapse is thinner (twice its area over its longest edge) than this many
/// units.
pub const MIN_HEIGHT_UNITS: f64 = 1e-3;

/// What [`simplify_flat`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Simplified {
    /// Triangles before.
    pub triangles_before: usize,
    /// Vertices removed by edge collapse.
    pub vertices_collapsed: usize,
}

/// `mesh` with its flat parts made lean (see the module's promises). `planes` are the planes
/// (a point and a unit normal, m) that [`super::refine::refine_flat_parts`] put flat parts on; a
/// vertex is on a plane within 10⁻⁶ units; `unit_m` is the refinement's unit.
pub fn simplify_flat(mesh: &Mesh, planes: &[(DVec3, DVec3)], unit_m: f64) -> (Mesh, Simplified) {
    let mut report = Simplified {
        triangles_before: mesh.triangles.len(),
        ..Simplified::default()
    };
    if planes.is_empty() || mesh.triangles.is_empty() {
        return (mesh.clone(), report);
    }
    let eps = 1e-9 + 1e-6 * unit_m;
    // The plane each vertex lies on, if any.
    let plane_of: Vec<Option<u32>> = mesh
        .vertices
        .iter()
        .map(|v| {
            planes
                .iter()
                .position(|(p, n)| (*v - *p).dot(*n).abs() <= eps)
                .map(|k| k as u32)
        })
        .collect();
    // Each triangle's plane and facing (+1 along the plane's normal, −1 against), when flat.
    let flat: Vec<Option<(u32, i8)>> = mesh
        .triangles
        .iter()
        .map(|t| {
            let k = plane_of[t[0] as usize]?;
            if t.iter().any(|&i| plane_of[i as usize] != Some(k)) {
                return None;
            }
            let [a, b, c] = mesh.corners(t);
            let s = (b - a).cross(c - a).dot(planes[k as usize].1);
            (s != 0.0).then_some((k, if s > 0.0 { 1 } else { -1 }))
        })
        .collect();
    let mut d = Decimator::new(mesh, &flat, planes, unit_m);
    report.vertices_collapsed = d.run();
    (d.finish(), report)
}

/// Edge collapse over the flat sheets.
struct Decimator<'a> {
    vertices: &'a [DVec3],
    triangles: Vec<[u32; 3]>,
    alive: Vec<bool>,
    /// Plane and facing of each triangle (flat ones).
    flat: &'a [Option<(u32, i8)>],
    /// Alive triangles around each vertex.
    around: Vec<Vec<u32>>,
    /// In-plane coordinates of each vertex on a plane (m).
    uv: Vec<Option<DVec2>>,
    /// Outline points (in-plane) each outline edge stands for, beyond its ends.
    stands_for: HashMap<(u32, u32), Vec<DVec2>>,
    tolerance_m: f64,
    min_height_m: f64,
}

fn key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// Twice the signed area of the in-plane triangle.
fn cross(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + t * ab - p).length()
}

impl<'a> Decimator<'a> {
    fn new(mesh: &'a Mesh, flat: &'a [Option<(u32, i8)>], planes: &[(DVec3, DVec3)], unit_m: f64) -> Self {
        let mut around = vec![Vec::new(); mesh.vertices.len()];
        for (i, t) in mesh.triangles.iter().enumerate() {
            for &v in t {
                around[v as usize].push(i as u32);
            }
        }
        let basis: Vec<(DVec3, DVec3, DVec3)> = planes
            .iter()
            .map(|(p, n)| {
                let e1 = n.any_orthonormal_vector();
                (*p, e1, n.cross(e1))
            })
            .collect();
        let mut uv = vec![None; mesh.vertices.len()];
        for (t, f) in mesh.triangles.iter().zip(flat) {
            if let Some((k, _)) = f {
                let (p, e1, e2) = basis[*k as usize];
                for &v in t {
                    let d = mesh.vertices[v as usize] - p;
                    uv[v as usize] = Some(DVec2::new(d.dot(e1), d.dot(e2)));
                }
            }
        }
        Self {
            vertices: &mesh.vertices,
            triangles: mesh.triangles.clone(),
            alive: vec![true; mesh.triangles.len()],
            flat,
            around,
            uv,
            stands_for: HashMap::new(),
            tolerance_m: OUTLINE_TOLERANCE_UNITS * unit_m,
            min_height_m: MIN_HEIGHT_UNITS * unit_m,
        }
    }

    /// Passes over every vertex until none can go; returns how many went.
    fn run(&mut self) -> usize {
        let mut removed = 0;
        loop {
            let before = removed;
            for u in 0..self.vertices.len() as u32 {
                if self.try_remove(u) {
                    removed += 1;
                }
            }
            if removed == before {
                return removed;
            }
        }
    }

    /// Removes `u` by collapsing it onto a neighbour when the module's promises allow.
    fn try_remove(&mut self, u: u32) -> bool {
        let tris = &self.around[u as usize];
        if tris.is_empty() {
            return false;
        }
        let Some(pu) = self.uv[u as usize] else { return false };
        // All its triangles flat, on one plane, facing one way.
        let Some(f0) = self.flat[tris[0] as usize] else {
            return false;
        };
        if tris.iter().any(|&t| self.flat[t as usize] != Some(f0)) {
            return false;
        }
        // Edges around u: how many of its triangles share each.
        let mut edges: HashMap<u32, u32> = HashMap::new();
        for &t in tris {
            for &w in &self.triangles[t as usize] {
                if w != u {
                    *edges.entry(w).or_insert(0) += 1;
                }
            }
        }
        if edges.values().any(|&c| c > 2) {
            return false;
        }
        let outline: Vec<u32> = edges.iter().filter(|(_, &c)| c == 1).map(|(&w, _)| w).collect();
        let candidates: Vec<u32> = match outline.len() {
            0 => {
                let mut c: Vec<u32> = edges.keys().copied().collect();
                c.sort_by(|a, b| {
                    let d = |w: &u32| (self.vertices[*w as usize] - self.vertices[u as usize]).length_squared();
                    d(a).total_cmp(&d(b)).then(a.cmp(b))
                });
                c
            }
            2 => {
                let (a, b) = (outline[0], outline[1]);
                let (Some(pa), Some(pb)) = (self.uv[a as usize], self.uv[b as usize]) else {
                    return false;
                };
                let mut pts: Vec<DVec2> = vec![pu];
                for w in [a, b] {
                    pts.extend(self.stands_for.get(&key(u, w)).into_iter().flatten());
                }
                if pts.iter().any(|p| segment_distance(*p, pa, pb) > self.tolerance_m) {
                    return false;
                }
                let mut c = vec![a, b];
                c.sort();
                c
            }
            _ => return false,
        };
        for v in candidates {
            if self.collapse_ok(u, v) {
                self.collapse(u, v, &outline);
                return true;
            }
        }
        false
    }

    /// Whether moving `u` onto `v` keeps every other triangle of `u` facing the way it faced (its
    /// in-plane winding keeps its sign), not too thin, and the mesh manifold (the neighbours `u`
    /// and `v` share are exactly the third corners of the triangles on their edge).
    fn collapse_ok(&self, u: u32, v: u32) -> bool {
        let Some(pv) = self.uv[v as usize] else { return false };
        let tris = &self.around[u as usize];
        let mut opposite = Vec::new();
        for &t in tris {
            let tri = self.triangles[t as usize];
            if tri.contains(&v) {
                opposite.extend(tri.iter().copied().filter(|&w| w != u && w != v));
                continue;
            }
            let p = tri.map(|w| {
                if w == u {
                    pv
                } else {
                    self.uv[w as usize].unwrap_or(DVec2::ZERO)
                }
            });
            let c = cross(p[0], p[1], p[2]);
            let before = {
                let q = tri.map(|w| self.uv[w as usize].unwrap_or(DVec2::ZERO));
                cross(q[0], q[1], q[2])
            };
            if c * before <= 0.0 {
                return false;
            }
            let longest = (p[1] - p[0])
                .length()
                .max((p[2] - p[1]).length())
                .max((p[0] - p[2]).length());
            if c.abs() < self.min_height_m * longest {
                return false;
            }
        }
        let neighbours = |x: u32| -> std::collections::HashSet<u32> {
            self.around[x as usize]
                .iter()
                .flat_map(|&t| self.triangles[t as usize])
                .filter(|&w| w != x)
                .collect()
        };
        let (nu, nv) = (neighbours(u), neighbours(v));
        let shared = nu.intersection(&nv).count();
        opposite.sort();
        opposite.dedup();
        shared == opposite.len() && !opposite.is_empty()
    }

    fn collapse(&mut self, u: u32, v: u32, outline: &[u32]) {
        let tris = std::mem::take(&mut self.around[u as usize]);
        for t in tris {
            let tri = &mut self.triangles[t as usize];
            if tri.contains(&v) {
                self.alive[t as usize] = false;
                for w in *tri {
                    if w != u {
                        self.around[w as usize].retain(|&x| x != t);
                    }
                }
                continue;
            }
            for w in tri.iter_mut() {
                if *w == u {
                    *w = v;
                }
            }
            self.around[v as usize].push(t);
        }
        if outline.contains(&v) {
            // u went along the outline onto v: the outline edge (v, other) now stands for u and
            // for what (u, v) and (u, other) stood for.
            let other = if outline[0] == v { outline[1] } else { outline[0] };
            let mut pts = self.stands_for.remove(&key(u, v)).unwrap_or_default();
            pts.extend(self.stands_for.remove(&key(u, other)).unwrap_or_default());
            pts.extend(self.uv[u as usize]);
            self.stands_for.entry(key(v, other)).or_default().extend(pts);
        }
    }

    /// The mesh of the alive triangles, unused vertices dropped.
    fn finish(self) -> Mesh {
        let alive = self.alive;
        let kept = self
            .triangles
            .into_iter()
            .zip(alive)
            .filter(|(_, a)| *a)
            .map(|(t, _)| t);
        super::mesh::compacted(self.vertices, kept)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid of `n` × `n` unit-square cells over [0, 1]² at z = 0 (counter-clockwise seen from
    /// +z), without the cells where `skip(i, j)`.
    fn grid(n: usize, skip: &dyn Fn(usize, usize) -> bool) -> Mesh {
        let mut m = Mesh::default();
        for j in 0..=n {
            for i in 0..=n {
                m.vertices
                    .push(DVec3::new(i as f64 / n as f64, j as f64 / n as f64, 0.0));
            }
        }
        let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        for j in 0..n {
            for i in 0..n {
                if skip(i, j) {
                    continue;
                }
                m.triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                m.triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        m
    }

    fn facing(m: &Mesh) -> Vec<f64> {
        m.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = m.corners(t);
                (b - a).cross(c - a).z.signum()
            })
            .collect()
    }

    const Z: (DVec3, DVec3) = (DVec3::ZERO, DVec3::Z);

    #[test]
    fn a_flat_sheet_keeps_its_outline_with_few_triangles() {
        // An L: the square without its upper right quarter (area 3/4), 40 × 40 cells.
        let m = grid(40, &|i, j| i >= 20 && j >= 20);
        let (lean, rep) = simplify_flat(&m, &[Z], 0.01);
        assert_eq!(rep.triangles_before, m.triangles.len());
        assert!(lean.triangles.len() <= 40, "{} triangles", lean.triangles.len());
        assert!((lean.area() - 0.75).abs() < 1e-12, "{}", lean.area());
        assert!(facing(&lean).iter().all(|s| *s > 0.0));
        // The outline is where it was: every vertex on the L's border or inside it.
        for v in &lean.vertices {
            assert!(v.x >= -1e-12 && v.y >= -1e-12 && v.x <= 1.0 + 1e-12 && v.y <= 1.0 + 1e-12);
            assert!(!(v.x > 0.5 + 1e-12 && v.y > 0.5 + 1e-12), "{v}");
        }
    }

    #[test]
    fn both_coplanar_sheets_stay_lean_and_other_triangles_stay() {
        // Two sheets over the same square, facing opposite ways, sharing the outline's vertices
        // (the collapsed lens's two faces folded at its rim), and a triangle off the plane.
        let n = 10;
        let mut m = grid(n, &|_, _| false);
        let sheet = m.triangles.clone();
        let mut twin = vec![0u32; m.vertices.len()];
        for (k, v) in m.vertices.clone().iter().enumerate() {
            let rim = v.x == 0.0 || v.y == 0.0 || v.x == 1.0 || v.y == 1.0;
            twin[k] = if rim {
                k as u32
            } else {
                m.vertices.push(*v);
                (m.vertices.len() - 1) as u32
            };
        }
        for t in &sheet {
            m.triangles
                .push([twin[t[0] as usize], twin[t[2] as usize], twin[t[1] as usize]]);
        }
        let apex = m.vertices.len() as u32;
        m.vertices.push(DVec3::new(0.5, 0.5, 0.3));
        m.triangles.push([0, n as u32, apex]);
        let (lean, rep) = simplify_flat(&m, &[Z], 0.01);
        assert!(rep.vertices_collapsed > 0);
        let flat: Vec<usize> = (0..lean.triangles.len())
            .filter(|&k| lean.corners(&lean.triangles[k]).iter().all(|v| v.z == 0.0))
            .collect();
        assert_eq!(flat.len(), lean.triangles.len() - 1, "the off-plane triangle stays");
        let facing_up: f64 = flat
            .iter()
            .map(|&k| lean.corners(&lean.triangles[k]))
            .filter(|[a, b, c]| (*b - *a).cross(*c - *a).z > 0.0)
            .map(super::super::mesh::tri_area)
            .sum();
        let all: f64 = flat
            .iter()
            .map(|&k| super::super::mesh::tri_area(lean.corners(&lean.triangles[k])))
            .sum();
        assert!(
            (facing_up - 1.0).abs() < 1e-12 && (all - 2.0).abs() < 1e-12,
            "{facing_up} {all}"
        );
        // 401 before; the shared rim (40 vertices, each with triangles facing both ways) stays.
        assert!(lean.triangles.len() < 100, "{}", lean.triangles.len());
        assert!(lean.vertices.iter().any(|v| v.z == 0.3));
    }

    #[test]
    fn a_ragged_outline_is_kept_to_the_tolerance() {
        // A square whose right edge zigzags by 0.2 cells: with a unit of a cell, the tolerance
        // (0.05 units) keeps every zig.
        let n = 20;
        let mut m = grid(n, &|_, _| false);
        for (k, v) in m.vertices.iter_mut().enumerate() {
            if v.x == 1.0 && k % 2 == 0 {
                v.x += 0.2 / n as f64;
            }
        }
        let before = m.area();
        let (lean, _) = simplify_flat(&m, &[Z], 1.0 / n as f64);
        assert!((lean.area() - before).abs() < 1e-12);
        let right = lean.vertices.iter().filter(|v| v.x > 1.0 - 1e-9).count();
        assert_eq!(right, n + 1, "every vertex of the zigzag stays");
    }
}
