//! A bounding-volume hierarchy over a scene's triangles for the CPU ray queries of the reference
//! path tracer: the closest hit with its barycentric coordinates, and whether anything lies on a
//! segment (shadow rays).
//!
//! Promises:
//! - Built by binned SAH ([`SAH_BINS`] bins along the axis of the widest centroid spread), leaves
//!   of at most [`MAX_LEAF`] triangles unless their centroids coincide or the tree reaches
//!   [`MAX_DEPTH`] (then the leaf holds the rest: slower, never wrong). The build is iterative, so no input can exhaust the call stack, and the
//!   traversal's fixed stack of [`MAX_DEPTH`] entries cannot overflow.
//! - In f64 throughout: triangles are tested by Möller–Trumbore (a hit needs barycentrics u, v ≥ 0,
//!   u + v ≤ 1, each within [`BARY_TOLERANCE`] so that no ray slips between triangles sharing an
//!   edge or a vertex, and t inside the open interval (0, `t_max`)); degenerate triangles are
//!   never hit.
//!   Callers move ray origins off the surface they leave ([`offset_m`]), so there is no hidden
//!   `t_min` here. Surfaces are hit from both sides.
//! - The module separates the hierarchy from the scene's order: hits report the scene's own
//!   triangle index.

use glam::DVec3;

use super::model::{Aabb, Scene};

/// Most triangles in a leaf (larger only where centroids coincide or at [`MAX_DEPTH`]).
pub const MAX_LEAF: usize = 4;

/// Deepest node; the traversal stack has this many entries.
pub const MAX_DEPTH: usize = 64;

/// Centroid bins of the SAH split search.
pub const SAH_BINS: usize = 16;

/// How far (m) a ray's origin is moved off the surface it leaves, along that surface's normal,
/// in a scene of this `bounds`: 10⁻⁹ of its size plus 10⁻⁹ m (about 10⁶ times f64's resolution at
/// the scene's coordinates, far below any length that matters for lighting).
pub fn offset_m(bounds: &Aabb) -> f64 {
    let scale = bounds.min.abs().max(bounds.max.abs()).max_element();
    1e-9 * (1.0 + scale)
}

/// A ray's closest intersection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// The scene's triangle index.
    pub triangle: usize,
    /// Distance along the ray in units of its direction's length (metres for a unit direction).
    pub t: f64,
    /// Barycentric weight of the triangle's second vertex.
    pub b1: f64,
    /// Barycentric weight of the third vertex.
    pub b2: f64,
}

#[derive(Debug, Clone, Copy)]
struct Node {
    bounds: Aabb,
    /// Leaf: first triangle in `tris`; interior: index of the left child (the right is next).
    start: u32,
    /// Triangles in a leaf; 0 for an interior node.
    count: u32,
}

#[derive(Debug, Clone, Copy)]
struct PreTri {
    v0: DVec3,
    e1: DVec3,
    e2: DVec3,
}

/// The hierarchy over one scene's triangles.
#[derive(Debug, Clone)]
pub struct Bvh {
    nodes: Vec<Node>,
    tris: Vec<PreTri>,
    /// Scene index of each triangle in `tris`.
    ids: Vec<u32>,
    depth: usize,
}

struct Build {
    node: usize,
    start: usize,
    end: usize,
    depth: usize,
}

impl Bvh {
    /// Builds the hierarchy of `scene`'s triangles.
    pub fn build(scene: &Scene) -> Bvh {
        let tris = scene.triangles();
        let bounds_of = |t: &[DVec3; 3]| Aabb::EMPTY.grow(t[0]).grow(t[1]).grow(t[2]);
        let boxes: Vec<Aabb> = tris.iter().map(bounds_of).collect();
        let centroids: Vec<DVec3> = boxes.iter().map(|b| 0.5 * (b.min + b.max)).collect();
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let mut nodes = vec![Node {
            bounds: Aabb::EMPTY,
            start: 0,
            count: 0,
        }];
        let mut depth = 1;
        let mut work = vec![Build {
            node: 0,
            start: 0,
            end: order.len(),
            depth: 1,
        }];
        while let Some(b) = work.pop() {
            depth = depth.max(b.depth);
            let items = &mut order[b.start..b.end];
            let bounds = items.iter().fold(Aabb::EMPTY, |a, &i| a.union(boxes[i as usize]));
            nodes[b.node].bounds = padded(bounds);
            let n = items.len();
            let split = if n <= MAX_LEAF || b.depth >= MAX_DEPTH {
                None
            } else {
                split_sah(items, &boxes, &centroids)
            };
            match split {
                Some(mid) => {
                    let left = nodes.len();
                    nodes[b.node].start = left as u32;
                    nodes[b.node].count = 0;
                    for _ in 0..2 {
                        nodes.push(Node {
                            bounds: Aabb::EMPTY,
                            start: 0,
                            count: 0,
                        });
                    }
                    work.push(Build {
                        node: left + 1,
                        start: b.start + mid,
                        end: b.end,
                        depth: b.depth + 1,
                    });
                    work.push(Build {
                        node: left,
                        start: b.start,
                        end: b.start + mid,
                        depth: b.depth + 1,
                    });
                }
                None => {
                    nodes[b.node].start = b.start as u32;
                    nodes[b.node].count = n as u32;
                }
            }
        }
        let pre = order
            .iter()
            .map(|&i| {
                let t = &tris[i as usize];
                PreTri {
                    v0: t[0],
                    e1: t[1] - t[0],
                    e2: t[2] - t[0],
                }
            })
            .collect();
        Bvh {
            nodes,
            tris: pre,
            ids: order,
            depth,
        }
    }

    /// Depth of the deepest leaf (root = 1).
    pub fn depth(&self) -> usize {
        self.depth
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Number of triangles (the scene's, every one of them, degenerate ones included).
    pub fn triangle_count(&self) -> usize {
        self.ids.len()
    }

    /// The closest triangle hit by the ray `origin + t dir`, 0 < t < `t_max`.
    pub fn closest_hit(&self, origin: DVec3, dir: DVec3, t_max: f64) -> Option<Hit> {
        let inv = safe_recip(dir);
        let mut best: Option<Hit> = None;
        let mut t_best = t_max;
        let mut stack = [0u32; MAX_DEPTH];
        let mut sp = 0usize;
        let mut node = 0usize;
        slab(&self.nodes[0].bounds, origin, inv, t_best)?;
        loop {
            let n = &self.nodes[node];
            if n.count > 0 {
                let s = n.start as usize;
                for k in s..s + n.count as usize {
                    if let Some((t, b1, b2)) = intersect(&self.tris[k], origin, dir, t_best) {
                        t_best = t;
                        best = Some(Hit {
                            triangle: self.ids[k] as usize,
                            t,
                            b1,
                            b2,
                        });
                    }
                }
            } else {
                let (l, r) = (n.start as usize, n.start as usize + 1);
                let tl = slab(&self.nodes[l].bounds, origin, inv, t_best);
                let tr = slab(&self.nodes[r].bounds, origin, inv, t_best);
                match (tl, tr) {
                    (Some(a), Some(b)) => {
                        let (near, far) = if a <= b { (l, r) } else { (r, l) };
                        stack[sp] = far as u32;
                        sp += 1;
                        node = near;
                        continue;
                    }
                    (Some(_), None) => {
                        node = l;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = r;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop, skipping nodes the closer hits found meanwhile have ruled out.
            loop {
                if sp == 0 {
                    return best;
                }
                sp -= 1;
                let cand = stack[sp] as usize;
                if slab(&self.nodes[cand].bounds, origin, inv, t_best).is_some() {
                    node = cand;
                    break;
                }
            }
        }
    }

    /// Whether any triangle lies on the ray `origin + t dir`, 0 < t < `t_max` (a shadow ray to a
    /// point at `t_max`).
    pub fn occluded(&self, origin: DVec3, dir: DVec3, t_max: f64) -> bool {
        let inv = safe_recip(dir);
        let mut stack = [0u32; MAX_DEPTH];
        let mut sp = 0usize;
        if slab(&self.nodes[0].bounds, origin, inv, t_max).is_none() {
            return false;
        }
        let mut node = 0usize;
        loop {
            let n = &self.nodes[node];
            if n.count > 0 {
                let s = n.start as usize;
                if (s..s + n.count as usize).any(|k| intersect(&self.tris[k], origin, dir, t_max).is_some()) {
                    return true;
                }
            } else {
                let (l, r) = (n.start as usize, n.start as usize + 1);
                let hl = slab(&self.nodes[l].bounds, origin, inv, t_max).is_some();
                let hr = slab(&self.nodes[r].bounds, origin, inv, t_max).is_some();
                if hl && hr {
                    stack[sp] = r as u32;
                    sp += 1;
                    node = l;
                    continue;
                } else if hl {
                    node = l;
                    continue;
                } else if hr {
                    node = r;
                    continue;
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            node = stack[sp] as usize;
        }
    }
}

/// The SAH split of `items` (reordered so the left part comes first) at the bin boundary of least
/// cost Σ area × count; `None` when the centroids cannot be told apart and there are at most
/// 4 × [`MAX_LEAF`] items. Returns the number of items on the left, in 1…n−1.
fn split_sah(items: &mut [u32], boxes: &[Aabb], centroids: &[DVec3]) -> Option<usize> {
    let n = items.len();
    let cb = items.iter().fold(Aabb::EMPTY, |a, &i| a.grow(centroids[i as usize]));
    let ext = cb.size();
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let (lo, width) = (cb.min[axis], ext[axis]);
    if width.is_nan() || width <= 0.0 {
        // Every centroid in one place: halve by order (only to bound the leaf size).
        return (n > 4 * MAX_LEAF).then_some(n / 2);
    }
    let bin_of = |i: u32| (((centroids[i as usize][axis] - lo) / width * SAH_BINS as f64) as usize).min(SAH_BINS - 1);
    let mut counts = [0usize; SAH_BINS];
    let mut bin_bounds = [Aabb::EMPTY; SAH_BINS];
    for &i in items.iter() {
        let b = bin_of(i);
        counts[b] += 1;
        bin_bounds[b] = bin_bounds[b].union(boxes[i as usize]);
    }
    // Sweep from the right for suffix areas, then from the left.
    let mut right_area = [0.0f64; SAH_BINS];
    let mut right_count = [0usize; SAH_BINS];
    let (mut acc, mut cnt) = (Aabb::EMPTY, 0usize);
    for b in (1..SAH_BINS).rev() {
        acc = acc.union(bin_bounds[b]);
        cnt += counts[b];
        right_area[b] = acc.half_area();
        right_count[b] = cnt;
    }
    let (mut acc, mut cnt) = (Aabb::EMPTY, 0usize);
    let mut best: Option<(f64, usize)> = None;
    for b in 0..SAH_BINS - 1 {
        acc = acc.union(bin_bounds[b]);
        cnt += counts[b];
        let rc = right_count[b + 1];
        if cnt == 0 || rc == 0 {
            continue;
        }
        let cost = acc.half_area() * cnt as f64 + right_area[b + 1] * rc as f64;
        if best.is_none_or(|(c, _)| cost < c) {
            best = Some((cost, b));
        }
    }
    let (_, split_bin) = best?;
    let mut mid = 0;
    for k in 0..n {
        if bin_of(items[k]) <= split_bin {
            items.swap(k, mid);
            mid += 1;
        }
    }
    (mid > 0 && mid < n).then_some(mid)
}

/// `b` grown on every side by 10⁻⁹ of its largest extent plus 10⁻¹² of its coordinates' size:
/// more than [`BARY_TOLERANCE`] lets a triangle reach, so a ray that hits a triangle within its
/// tolerance (through a shared vertex or edge) is never culled by the triangle's box.
fn padded(b: Aabb) -> Aabb {
    let scale = b.min.abs().max(b.max.abs()).max_element();
    let pad = 1e-9 * b.size().max_element() + 1e-12 * (1.0 + scale);
    Aabb {
        min: b.min - pad,
        max: b.max + pad,
    }
}

/// 1 / d per component, with a zero component (either sign) read as ±10⁻³⁰⁰ so that the slab test
/// never multiplies 0 by ∞: a ray parallel to a slab and lying on one of its planes is inside it.
fn safe_recip(d: DVec3) -> DVec3 {
    let r = |c: f64| if c == 0.0 { 1e300 } else { 1.0 / c };
    DVec3::new(r(d.x), r(d.y), r(d.z))
}

/// Entry distance of the ray into `b` within [0, t_max], or `None` (`inv` from [`safe_recip`]).
fn slab(b: &Aabb, o: DVec3, inv: DVec3, t_max: f64) -> Option<f64> {
    let t1 = (b.min - o) * inv;
    let t2 = (b.max - o) * inv;
    let tmin = t1.min(t2);
    let tmax = t1.max(t2);
    let enter = tmin.x.max(tmin.y).max(tmin.z).max(0.0);
    let exit = tmax.x.min(tmax.y).min(tmax.z).min(t_max);
    (enter <= exit).then_some(enter)
}

/// How far outside a triangle, in barycentric units, a hit still counts: a ray through an edge or
/// a vertex shared by several triangles, whose rounding could put it outside each of them, hits one.
pub const BARY_TOLERANCE: f64 = 1e-10;

/// Möller–Trumbore: (t, b1, b2) of a hit with 0 < t < t_max.
fn intersect(tri: &PreTri, o: DVec3, d: DVec3, t_max: f64) -> Option<(f64, f64, f64)> {
    let p = d.cross(tri.e2);
    let det = tri.e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - tri.v0;
    let u = s.dot(p) * inv;
    if !(-BARY_TOLERANCE..=1.0 + BARY_TOLERANCE).contains(&u) {
        return None;
    }
    let q = s.cross(tri.e1);
    let v = d.dot(q) * inv;
    if v < -BARY_TOLERANCE || u + v > 1.0 + BARY_TOLERANCE {
        return None;
    }
    let t = tri.e2.dot(q) * inv;
    (t > 0.0 && t < t_max).then_some((t, u, v))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::model::{Material, SceneParts};

    /// A deterministic cloud of small triangles in the unit cube.
    fn cloud(n: usize) -> Scene {
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut triangles = Vec::new();
        for _ in 0..n {
            let c = DVec3::new(next(), next(), next());
            let a = DVec3::new(next(), next(), next()) * 0.05;
            let b = DVec3::new(next(), next(), next()) * 0.05;
            triangles.push([c, c + a, c + b]);
        }
        Scene::new(SceneParts {
            material_of: vec![0; triangles.len()],
            triangles,
            materials: vec![Material::grey(0.5)],
            ..Default::default()
        })
        .unwrap()
    }

    fn brute_closest(s: &Scene, o: DVec3, d: DVec3, t_max: f64) -> Option<(usize, f64)> {
        let mut best = None;
        let mut tb = t_max;
        for (i, t) in s.triangles().iter().enumerate() {
            let pre = PreTri {
                v0: t[0],
                e1: t[1] - t[0],
                e2: t[2] - t[0],
            };
            if let Some((t, _, _)) = intersect(&pre, o, d, tb) {
                tb = t;
                best = Some((i, t));
            }
        }
        best
    }

    #[test]
    fn hits_agree_with_brute_force() {
        let s = cloud(3000);
        let bvh = Bvh::build(&s);
        assert!(bvh.depth() < 40, "depth {}", bvh.depth());
        let mut k = 0u64;
        let mut hits = 0;
        for i in 0..2000 {
            k = k.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let a = (k >> 11) as f64 / (1u64 << 53) as f64 * std::f64::consts::TAU;
            let z = ((k >> 7) & 0xFFFF) as f64 / 65535.0 * 2.0 - 1.0;
            let d = DVec3::new((1.0 - z * z).sqrt() * a.cos(), (1.0 - z * z).sqrt() * a.sin(), z);
            let o = DVec3::new(0.5, 0.5, 0.5) + DVec3::new((i % 7) as f64, (i % 5) as f64, 0.0) * 0.03;
            let want = brute_closest(&s, o, d, 10.0);
            let got = bvh.closest_hit(o, d, 10.0);
            assert_eq!(want.map(|w| w.0), got.map(|g| g.triangle), "ray {i}");
            if let (Some(w), Some(g)) = (want, got) {
                hits += 1;
                assert_eq!(w.1, g.t);
                let t = s.triangles()[g.triangle];
                let p = t[0] + g.b1 * (t[1] - t[0]) + g.b2 * (t[2] - t[0]);
                assert!((p - (o + g.t * d)).length() < 1e-12, "barycentrics give the hit point");
                assert!(bvh.occluded(o, d, g.t * 1.000001));
                assert!(!bvh.occluded(o, d, g.t * 0.999999) || brute_closest(&s, o, d, g.t * 0.999999).is_some());
            } else {
                assert!(!bvh.occluded(o, d, 10.0));
            }
        }
        assert!(hits > 200, "{hits} hits: the test must exercise hits");
    }

    #[test]
    fn rays_through_shared_vertices_and_edges_hit() {
        // A fan of 8 triangles around the origin in the plane y = 0 (irrational-ish corners);
        // rays straight down through the shared centre and through each shared edge's midpoint.
        let ring: Vec<DVec3> = (0..8)
            .map(|k| {
                let a = f64::from(k) * std::f64::consts::TAU / 8.0 + 0.1;
                DVec3::new(a.cos() * 0.7, 0.0, a.sin() * 0.7)
            })
            .collect();
        let triangles: Vec<[DVec3; 3]> = (0..8).map(|k| [DVec3::ZERO, ring[k], ring[(k + 1) % 8]]).collect();
        let s = Scene::new(SceneParts {
            material_of: vec![0; 8],
            triangles,
            materials: vec![Material::grey(0.5)],
            ..Default::default()
        })
        .unwrap();
        let bvh = Bvh::build(&s);
        let mut targets = vec![DVec3::ZERO];
        targets.extend(ring.iter().map(|p| *p * 0.5));
        for t in targets {
            let o = t + DVec3::new(0.0, 1.3, 0.0);
            let h = bvh.closest_hit(o, DVec3::NEG_Y, 10.0);
            assert!(h.is_some_and(|h| (h.t - 1.3).abs() < 1e-12), "through {t}: {h:?}");
        }
        // A corner 10⁻¹⁶ m off the ray (as a UV sphere's pole is off its axis): the triangle's box
        // misses the ray by that much unless padded; the triangle's tolerance takes the hit.
        let corner = DVec3::new(1.2e-16, 0.0, 0.9e-16);
        let s = Scene::new(SceneParts {
            triangles: vec![[corner, DVec3::new(0.7, 0.0, 0.1), DVec3::new(0.1, 0.0, 0.7)]],
            material_of: vec![0],
            materials: vec![Material::grey(0.5)],
            ..Default::default()
        })
        .unwrap();
        let h = Bvh::build(&s).closest_hit(DVec3::new(0.0, 2.0, 0.0), DVec3::NEG_Y, 10.0);
        assert!(h.is_some_and(|h| h.t == 2.0), "{h:?}");
    }

    #[test]
    fn rays_along_a_box_face_plane_enter_the_box() {
        let b = Aabb {
            min: DVec3::new(0.0, -1.0, -1.0),
            max: DVec3::new(1.0, 1.0, 1.0),
        };
        let o = DVec3::new(0.0, 5.0, 0.0); // on the plane x = min.x
        assert_eq!(slab(&b, o, safe_recip(DVec3::NEG_Y), 10.0), Some(4.0));
        assert_eq!(slab(&b, o, safe_recip(DVec3::new(-0.0, -1.0, 0.0)), 10.0), Some(4.0));
        assert_eq!(
            slab(&b, DVec3::new(-1e-9, 5.0, 0.0), safe_recip(DVec3::NEG_Y), 10.0),
            None
        );
    }

    #[test]
    fn coincident_centroids_and_axis_parallel_rays() {
        // 100 copies of one triangle: a leaf, never a split of indistinguishable centroids.
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let s = Scene::new(SceneParts {
            triangles: vec![t; 100],
            material_of: vec![0; 100],
            materials: vec![Material::grey(0.5)],
            ..Default::default()
        })
        .unwrap();
        let bvh = Bvh::build(&s);
        let h = bvh
            .closest_hit(DVec3::new(0.25, 0.25, 1.0), DVec3::NEG_Z, f64::INFINITY)
            .unwrap();
        assert_eq!(h.t, 1.0);
        assert_eq!((h.b1, h.b2), (0.25, 0.25));
        // From below too (two-sided), and along the plane (never a hit of a degenerate view).
        assert!(bvh.occluded(DVec3::new(0.25, 0.25, -1.0), DVec3::Z, 2.0));
        assert!(!bvh.occluded(DVec3::new(0.25, 0.25, -1.0), DVec3::Z, 0.5));
        assert!(bvh.closest_hit(DVec3::new(-1.0, 0.1, 0.0), DVec3::X, 10.0).is_none());
    }
}
