//! A bounding-volume hierarchy over a proxy mesh, for the near-field pass's visibility test: is the
//! straight path from a proxy point to a capture camera blocked by the proxy itself? (A camera that
//! cannot see the point sees something else there, and must not vote on its luminance.)
//!
//! Built on the CPU by median splits along the longest axis of the triangles' centroids, at most
//! [`LEAF_TRIANGLES`] triangles per leaf; the depth is at most ⌈log₂(n / LEAF)⌉ + 1, far below the
//! builder's limit of [`MAX_DEPTH`]. [`ProxyBvh::occluded`] is the CPU twin of the shader's traversal
//! (shaders/nearfield/visibility.wgsl, `occluded`), used by the tests.
//!
//! Nodes are stored in depth-first preorder, each interior node with its *escape* (the first node
//! after its subtree), so the traversal needs no stack: on a hit go to the next node (an interior
//! node's left child), on a miss jump to the escape (a leaf's escape is the next node). The index only
//! grows, so it ends after at most one visit per node. On lavapipe this halved the proxy mode's frame
//! (the stack was a per-lane array that WGSL zero-fills on every call, three calls per fragment).
//!
//! # GPU layout (`[f32; 4]` words, little-endian)
//! - node i: `[min.xyz, bits(a)]`, `[max.xyz, bits(b)]`; a leaf has b > 0: triangles a … a + b − 1;
//!   an interior node has b = 0 and escape a; its children are i + 1 and the node after the left
//!   child's subtree. Node 0 is the root.
//! - triangle j: `[v0.xyz, 0]`, `[e1.xyz, 0]`, `[e2.xyz, 0]` with e1 = v1 − v0, e2 = v2 − v0, in the
//!   order the leaves refer to.

use glam::Vec3;

use super::error::{NearfieldError, Result};

/// Most triangles in a leaf.
pub const LEAF_TRIANGLES: usize = 4;

/// The builder refuses deeper trees (its recursion).
pub const MAX_DEPTH: usize = 32;

/// Largest proxy accepted (triangles): keeps the GPU buffer under 128 MiB.
pub const MAX_TRIANGLES: usize = 2_000_000;

/// Whether a triangle list (three vertices per triangle) lies in one plane, within 10⁻⁶ of its extent.
/// Such a proxy cannot block the segment from a point on it to a camera off its plane (the segment
/// meets the plane only at that point), so it needs no hierarchy and no visibility test.
pub fn is_planar(vertices: &[[f32; 3]]) -> bool {
    let v: Vec<Vec3> = vertices.iter().map(|p| Vec3::from(*p)).collect();
    let (lo, hi) = v.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let extent = (hi - lo).length();
    if !extent.is_finite() || extent <= 0.0 {
        return false;
    }
    // The plane of the triangle with the largest area.
    let Some((p0, n)) = v
        .chunks_exact(3)
        .map(|t| (t[0], (t[1] - t[0]).cross(t[2] - t[0])))
        .max_by(|a, b| a.1.length_squared().total_cmp(&b.1.length_squared()))
    else {
        return false;
    };
    let n = n.normalize_or_zero();
    n != Vec3::ZERO && v.iter().all(|p| (*p - p0).dot(n).abs() <= 1e-6 * extent)
}

/// A built hierarchy in its GPU layout.
#[derive(Debug, Clone, PartialEq)]
pub struct ProxyBvh {
    /// Two words per node.
    pub nodes: Vec<[f32; 4]>,
    /// Three words per triangle.
    pub triangles: Vec<[f32; 4]>,
    /// Depth of the deepest leaf (root = 1).
    pub depth: usize,
}

#[derive(Clone, Copy)]
struct Tri {
    v: [Vec3; 3],
    centroid: Vec3,
}

impl ProxyBvh {
    /// Builds the hierarchy of a triangle list (three vertices per triangle, luminaire frame, m).
    ///
    /// Errors (argument `proxy`): no triangles, a count that is not a multiple of 3, more than
    /// [`MAX_TRIANGLES`], non-finite positions.
    pub fn build(vertices: &[[f32; 3]]) -> Result<Self> {
        if vertices.is_empty() || !vertices.len().is_multiple_of(3) {
            return Err(NearfieldError::invalid(
                "proxy",
                format!("{} vertices do not form a non-empty triangle list", vertices.len()),
            ));
        }
        if vertices.len() / 3 > MAX_TRIANGLES {
            return Err(NearfieldError::invalid(
                "proxy",
                format!(
                    "{} triangles; at most {MAX_TRIANGLES} are supported",
                    vertices.len() / 3
                ),
            ));
        }
        if vertices.iter().any(|v| !v.iter().all(|x| x.is_finite())) {
            return Err(NearfieldError::invalid("proxy", "a vertex is not finite"));
        }
        let mut tris: Vec<Tri> = vertices
            .chunks_exact(3)
            .map(|c| {
                let v = [Vec3::from(c[0]), Vec3::from(c[1]), Vec3::from(c[2])];
                Tri {
                    v,
                    centroid: (v[0] + v[1] + v[2]) / 3.0,
                }
            })
            .collect();
        let mut bvh = ProxyBvh {
            nodes: Vec::new(),
            triangles: Vec::with_capacity(tris.len() * 3),
            depth: 0,
        };
        bvh.split(&mut tris[..], 1)?;
        Ok(bvh)
    }

    fn set_node(&mut self, node: usize, lo: Vec3, hi: Vec3, a: u32, b: u32) {
        self.nodes[2 * node] = [lo.x, lo.y, lo.z, f32::from_bits(a)];
        self.nodes[2 * node + 1] = [hi.x, hi.y, hi.z, f32::from_bits(b)];
    }

    /// Appends the subtree of `tris` in preorder.
    fn split(&mut self, tris: &mut [Tri], depth: usize) -> Result<()> {
        if depth > MAX_DEPTH {
            return Err(NearfieldError::invalid(
                "proxy",
                format!("the hierarchy would be deeper than {MAX_DEPTH} levels"),
            ));
        }
        self.depth = self.depth.max(depth);
        let node = self.nodes.len() / 2;
        self.nodes.extend([[0.0; 4]; 2]);
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        let (mut clo, mut chi) = (lo, hi);
        for t in tris.iter() {
            for v in t.v {
                lo = lo.min(v);
                hi = hi.max(v);
            }
            clo = clo.min(t.centroid);
            chi = chi.max(t.centroid);
        }
        if tris.len() <= LEAF_TRIANGLES {
            let start = (self.triangles.len() / 3) as u32;
            for t in tris.iter() {
                let (e1, e2) = (t.v[1] - t.v[0], t.v[2] - t.v[0]);
                self.triangles.push([t.v[0].x, t.v[0].y, t.v[0].z, 0.0]);
                self.triangles.push([e1.x, e1.y, e1.z, 0.0]);
                self.triangles.push([e2.x, e2.y, e2.z, 0.0]);
            }
            self.set_node(node, lo, hi, start, tris.len() as u32);
            return Ok(());
        }
        let ext = chi - clo;
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let mid = tris.len() / 2;
        tris.select_nth_unstable_by(mid, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
        let (l, r) = tris.split_at_mut(mid);
        self.split(l, depth + 1)?;
        self.split(r, depth + 1)?;
        let escape = self.nodes.len() / 2;
        self.set_node(node, lo, hi, escape as u32, 0);
        Ok(())
    }

    /// Whether a triangle blocks the segment from `from` towards `to` at a parameter t in
    /// (`eps`, 1 − `eps`) of the segment (t = 0 at `from`).
    pub fn occluded(&self, from: Vec3, to: Vec3, eps: f32) -> bool {
        let d = to - from;
        let inv = Vec3::ONE / d;
        let count_nodes = self.nodes.len() / 2;
        let mut n = 0usize;
        while n < count_nodes {
            let (a, b) = (self.nodes[2 * n], self.nodes[2 * n + 1]);
            let lo = Vec3::new(a[0], a[1], a[2]);
            let hi = Vec3::new(b[0], b[1], b[2]);
            let t0 = (lo - from) * inv;
            let t1 = (hi - from) * inv;
            let tmin = t0.min(t1).max_element().max(eps);
            let tmax = t0.max(t1).min_element().min(1.0 - eps);
            let (first, count) = (a[3].to_bits(), b[3].to_bits());
            if tmin > tmax {
                // Missed: skip the subtree.
                n = if count > 0 { n + 1 } else { first as usize };
                continue;
            }
            if count > 0 {
                for j in first..first + count {
                    let j = 3 * j as usize;
                    let v0 = Vec3::from_slice(&self.triangles[j][..3]);
                    let e1 = Vec3::from_slice(&self.triangles[j + 1][..3]);
                    let e2 = Vec3::from_slice(&self.triangles[j + 2][..3]);
                    if let Some(t) = hit(from, d, v0, e1, e2) {
                        if t > eps && t < 1.0 - eps {
                            return true;
                        }
                    }
                }
            }
            n += 1;
        }
        false
    }
}

/// Möller–Trumbore: the parameter t of `o + t·d` where it crosses the triangle, if it does.
fn hit(o: Vec3, d: Vec3, v0: Vec3, e1: Vec3, e2: Vec3) -> Option<f32> {
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-20 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - v0;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(e2.dot(q) * inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(z: f32, x0: f32, x1: f32, y0: f32, y1: f32) -> Vec<[f32; 3]> {
        vec![
            [x0, y0, z],
            [x1, y0, z],
            [x1, y1, z],
            [x0, y0, z],
            [x1, y1, z],
            [x0, y1, z],
        ]
    }

    #[test]
    fn a_tile_in_front_blocks_the_back_plane_and_brute_force_agrees() {
        // The two-planes layout: 5 × 5 tiles at z = 0 in front of a back plane at z = 0.05.
        let mut v = quad(0.05, -0.1, 0.1, -0.1, 0.1);
        for i in 0..5 {
            for j in 0..5 {
                let (x, y) = (-0.08 + 0.04 * i as f32, -0.08 + 0.04 * j as f32);
                v.extend(quad(0.0, x - 0.015, x + 0.015, y - 0.015, y + 0.015));
            }
        }
        let bvh = ProxyBvh::build(&v).unwrap();
        assert!(bvh.depth <= 8, "{}", bvh.depth);
        let camera = Vec3::new(0.3, -0.2, -1.0);
        // A back-plane point right behind the centre tile is hidden; one in a gap seen straight on is not.
        assert!(bvh.occluded(Vec3::new(0.0, 0.0, 0.05), Vec3::new(0.0, 0.0, -1.0), 1e-4));
        assert!(!bvh.occluded(Vec3::new(0.02, 0.0, 0.05), Vec3::new(0.02, 0.0, -1.0), 1e-4));
        // A point on a tile is never blocked by its own tile.
        assert!(!bvh.occluded(Vec3::new(0.0, 0.0, 0.0), camera, 1e-4));
        // Against brute force over a grid of back-plane points.
        let mut blocked = 0;
        for i in 0..60 {
            for j in 0..60 {
                let p = Vec3::new(-0.099 + 0.198 * i as f32 / 59.0, -0.099 + 0.198 * j as f32 / 59.0, 0.05);
                let brute = v.chunks_exact(3).any(|t| {
                    let (a, b, c) = (Vec3::from(t[0]), Vec3::from(t[1]), Vec3::from(t[2]));
                    hit(p, camera - p, a, b - a, c - a).is_some_and(|t| t > 1e-4 && t < 1.0 - 1e-4)
                });
                assert_eq!(bvh.occluded(p, camera, 1e-4), brute, "{p}");
                blocked += usize::from(brute);
            }
        }
        assert!(blocked > 500 && blocked < 3000, "{blocked}");
    }

    #[test]
    fn planar_meshes_are_told_apart() {
        let mut flat = quad(0.0, -0.1, 0.1, -0.1, 0.1);
        flat.extend(quad(0.0, 0.2, 0.3, -0.1, 0.1));
        assert!(is_planar(&flat));
        // Tilted, still one plane.
        let tilted: Vec<[f32; 3]> = flat.iter().map(|p| [p[0], p[1] * 0.6, p[1] * 0.8 + 0.3]).collect();
        assert!(is_planar(&tilted));
        let mut two = flat.clone();
        two.extend(quad(0.05, -0.1, 0.1, -0.1, 0.1));
        assert!(!is_planar(&two));
        assert!(!is_planar(&[]));
        assert!(!is_planar(&[[0.0; 3]; 3]));
    }

    #[test]
    fn bad_meshes_are_refused_by_name() {
        for v in [vec![], vec![[0.0; 3]; 4], vec![[f32::NAN, 0.0, 0.0]; 3]] {
            match ProxyBvh::build(&v) {
                Err(NearfieldError::InvalidArgument { name, .. }) => assert_eq!(name, "proxy"),
                other => panic!("{other:?}"),
            }
        }
    }

    #[test]
    fn many_triangles_stay_shallow() {
        let mut v = Vec::new();
        for i in 0..20_000 {
            let x = (i % 200) as f32 * 0.001;
            let y = (i / 200) as f32 * 0.001;
            v.extend([[x, y, 0.0], [x + 0.001, y, 0.0], [x, y + 0.001, 0.0]]);
        }
        let bvh = ProxyBvh::build(&v).unwrap();
        assert!(bvh.depth <= 14, "{}", bvh.depth);
        assert_eq!(bvh.triangles.len(), 3 * 20_000);
    }
}
