//! From carved cells to triangles: naive surface nets on the cells' centres (one vertex per dual
//! cube the surface crosses, at the mean of its crossed edges' midpoints; two triangles per crossed
//! edge, wound outwards), then a few passes of Taubin smoothing that keep each vertex inside its
//! dual cube (no shrinking, no vertex moves more than half a cell).

use std::collections::HashMap;

use glam::DVec3;

use super::carve::{Cells, Occupancy};
use crate::nearfield::synth::proxy::{ProxyMesh, ProxySurface};

/// A triangle mesh: vertices and index triples (m, luminaire frame).
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    /// Vertices (m).
    pub vertices: Vec<DVec3>,
    /// Triangles, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// Three vertices per triangle, as f32 (the pack's proxy layout).
    pub fn soup(&self) -> Vec<[f32; 3]> {
        self.triangles
            .iter()
            .flat_map(|t| t.iter().map(|&i| self.vertices[i as usize].as_vec3().to_array()))
            .collect()
    }

    /// Total area (m²).
    pub fn area(&self) -> f64 {
        self.triangles.iter().map(|t| tri_area(self.corners(t))).sum()
    }

    /// As a [`ProxyMesh`] (one surface, area-weighted vertex normals) for glTF export.
    pub fn to_proxy_mesh(&self, name: &str, surface: &str) -> ProxyMesh {
        let normals = vertex_normals(self);
        let mut m = ProxyMesh::new(name);
        m.surfaces.push(ProxySurface {
            name: surface.to_string(),
            positions: self.vertices.clone(),
            normals: normals
                .into_iter()
                .map(|n| if n == DVec3::ZERO { DVec3::Z } else { n })
                .collect(),
            indices: self.triangles.iter().flat_map(|t| t.iter().copied()).collect(),
        });
        m
    }

    pub(crate) fn corners(&self, t: &[u32; 3]) -> [DVec3; 3] {
        t.map(|i| self.vertices[i as usize])
    }
}

/// Area (m²) of a triangle.
pub fn tri_area(t: [DVec3; 3]) -> f64 {
    0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()
}

/// Smoothing passes (each a λ step then a μ step).
const SMOOTHING_PASSES: usize = 4;

/// The surface between occupied and empty cells (outside the grid counts as empty).
pub fn surface_nets(occ: &Occupancy) -> Mesh {
    let n = occ.n as i64;
    let at = |x: i64, y: i64, z: i64| occ.at(x, y, z);
    // Dual cube (x, y, z) spans cell centres x..x+1 etc., for x in −1..n.
    let key = |x: i64, y: i64, z: i64| (((z + 1) * (n + 1) + (y + 1)) * (n + 1) + (x + 1)) as u64;
    let mut index: HashMap<u64, u32> = HashMap::new();
    let mut cube_of: Vec<[i64; 3]> = Vec::new();
    let mut vertices: Vec<DVec3> = Vec::new();
    let mut vertex = |x: i64, y: i64, z: i64, vertices: &mut Vec<DVec3>| -> u32 {
        *index.entry(key(x, y, z)).or_insert_with(|| {
            // Mean of the crossings of the cube's 12 edges.
            let mut sum = DVec3::ZERO;
            let mut k = 0.0;
            for a in 0..3 {
                for i in 0..2 {
                    for j in 0..2 {
                        let mut p = [0i64; 3];
                        p[(a + 1) % 3] = i;
                        p[(a + 2) % 3] = j;
                        let mut q = p;
                        q[a] = 1;
                        if at(x + p[0], y + p[1], z + p[2]) != at(x + q[0], y + q[1], z + q[2]) {
                            let mut m = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
                            m[a] = 0.5;
                            sum += m;
                            k += 1.0;
                        }
                    }
                }
            }
            let local = if k > 0.0 { sum / k } else { DVec3::splat(0.5) };
            vertices.push(occ.origin + (DVec3::new(x as f64, y as f64, z as f64) + 0.5 + local) * occ.voxel_m);
            cube_of.push([x, y, z]);
            (vertices.len() - 1) as u32
        })
    };
    let mut triangles = Vec::new();
    for z in -1..n {
        for y in -1..n {
            for x in -1..n {
                let here = at(x, y, z);
                for a in 0..3 {
                    let mut d = [0i64; 3];
                    d[a] = 1;
                    let there = at(x + d[0], y + d[1], z + d[2]);
                    if here == there {
                        continue;
                    }
                    // The four dual cubes around the edge (x,y,z)→(x,y,z)+e_a share it; they sit at
                    // offsets 0/−1 along the two other axes.
                    let (b, c) = ((a + 1) % 3, (a + 2) % 3);
                    let cube = |ob: i64, oc: i64| {
                        let mut p = [x, y, z];
                        p[b] += ob;
                        p[c] += oc;
                        p
                    };
                    let q = [cube(-1, -1), cube(0, -1), cube(0, 0), cube(-1, 0)];
                    let v: Vec<u32> = q.iter().map(|p| vertex(p[0], p[1], p[2], &mut vertices)).collect();
                    // Outward normal is +e_a when the inside is `here`.
                    if here {
                        triangles.push([v[0], v[1], v[2]]);
                        triangles.push([v[0], v[2], v[3]]);
                    } else {
                        triangles.push([v[0], v[2], v[1]]);
                        triangles.push([v[0], v[3], v[2]]);
                    }
                }
            }
        }
    }
    let mut mesh = Mesh { vertices, triangles };
    smooth(&mut mesh, &cube_of, occ);
    mesh
}

/// Taubin smoothing (λ = 0.5, μ = −0.53), each vertex clamped to its dual cube.
fn smooth(mesh: &mut Mesh, cube_of: &[[i64; 3]], occ: &Occupancy) {
    let neighbours = neighbours(mesh);
    let bounds: Vec<(DVec3, DVec3)> = cube_of
        .iter()
        .map(|&[x, y, z]| {
            let lo = occ.origin + (DVec3::new(x as f64, y as f64, z as f64) + 0.5) * occ.voxel_m;
            (lo, lo + DVec3::splat(occ.voxel_m))
        })
        .collect();
    for _ in 0..SMOOTHING_PASSES {
        for factor in [0.5, -0.53] {
            let old = mesh.vertices.clone();
            for (i, nb) in neighbours.iter().enumerate() {
                if nb.is_empty() {
                    continue;
                }
                let mean = nb.iter().map(|&j| old[j as usize]).sum::<DVec3>() / nb.len() as f64;
                let p = old[i] + factor * (mean - old[i]);
                mesh.vertices[i] = p.clamp(bounds[i].0, bounds[i].1);
            }
        }
    }
}

/// Distances between two surfaces, sampled: points spread over each (by area, deterministic), each
/// measured to the nearest triangle of the other.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Chamfer {
    /// Mean distance (m) of the first mesh's samples to the second.
    pub mean_ab_m: f64,
    /// Mean distance (m) of the second mesh's samples to the first.
    pub mean_ba_m: f64,
    /// Mean over both directions (m): the symmetric Chamfer distance.
    pub mean_m: f64,
    /// 95th percentile over the samples of both directions (m).
    pub p95_m: f64,
    /// Largest sampled distance (m), both directions.
    pub max_m: f64,
}

/// Samples about `samples` points on each of `a` and `b` (triangle soups, three vertices each) and
/// measures [`Chamfer`].
pub fn chamfer(a: &[[f32; 3]], b: &[[f32; 3]], samples: usize) -> Chamfer {
    use rayon::prelude::*;
    let ta = soup_triangles(a);
    let tb = soup_triangles(b);
    let (ga, gb) = (TriangleBvh::new(&ta), TriangleBvh::new(&tb));
    let pa = sample(&ta, samples);
    let pb = sample(&tb, samples);
    let dab: Vec<f64> = pa.par_iter().map(|&p| gb.distance(p)).collect();
    let dba: Vec<f64> = pb.par_iter().map(|&p| ga.distance(p)).collect();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let mut all: Vec<f64> = dab.iter().chain(&dba).copied().collect();
    all.sort_by(f64::total_cmp);
    let p95 = all
        .get(((all.len() as f64 * 0.95) as usize).min(all.len().saturating_sub(1)))
        .copied()
        .unwrap_or(0.0);
    let (mab, mba) = (mean(&dab), mean(&dba));
    Chamfer {
        mean_ab_m: mab,
        mean_ba_m: mba,
        mean_m: 0.5 * (mab + mba),
        p95_m: p95,
        max_m: all.last().copied().unwrap_or(0.0),
    }
}

fn soup_triangles(s: &[[f32; 3]]) -> Vec<[DVec3; 3]> {
    s.chunks_exact(3)
        .map(|t| [0, 1, 2].map(|k| DVec3::from(t[k].map(f64::from))))
        .filter(|t| tri_area(*t) > 0.0)
        .collect()
}

/// About `n` points spread over the triangles by area: each triangle gets its share (rounded
/// stochastically with a fixed sequence), placed on a low-discrepancy (R2) sequence.
fn sample(tris: &[[DVec3; 3]], n: usize) -> Vec<DVec3> {
    let total: f64 = tris.iter().map(|t| tri_area(*t)).sum();
    if total <= 0.0 {
        return Vec::new();
    }
    let mut out = Vec::with_capacity(n + tris.len());
    let mut carry = 0.0;
    let (g1, g2) = (0.754_877_666_246_692_7, 0.569_840_290_998_053_2);
    let mut seq = 0u64;
    for t in tris {
        carry += tri_area(*t) / total * n as f64;
        while carry >= 1.0 {
            carry -= 1.0;
            seq += 1;
            let (mut u, mut v) = ((0.5 + g1 * seq as f64).fract(), (0.5 + g2 * seq as f64).fract());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            out.push(t[0] + u * (t[1] - t[0]) + v * (t[2] - t[0]));
        }
    }
    out
}

/// A bounding-volume hierarchy over triangles for nearest-triangle queries (median splits on the
/// longest axis, leaves of up to four triangles, best-first search pruned by box distance).
struct TriangleBvh<'t> {
    tris: &'t [[DVec3; 3]],
    /// Nodes: box, then (first child, 0) for inner nodes or (first triangle, count) for leaves.
    nodes: Vec<(DVec3, DVec3, u32, u32)>,
    order: Vec<u32>,
}

impl<'t> TriangleBvh<'t> {
    fn new(tris: &'t [[DVec3; 3]]) -> Self {
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let centroid = |i: u32| {
            let t = &tris[i as usize];
            (t[0] + t[1] + t[2]) / 3.0
        };
        let mut nodes = Vec::with_capacity(2 * tris.len() / 4 + 1);
        // (node index, range) to fill.
        nodes.push((DVec3::ZERO, DVec3::ZERO, 0, 0));
        let mut stack = vec![(0usize, 0usize, tris.len())];
        while let Some((node, lo, hi)) = stack.pop() {
            let (mut bmin, mut bmax) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            for &i in &order[lo..hi] {
                for p in &tris[i as usize] {
                    bmin = bmin.min(*p);
                    bmax = bmax.max(*p);
                }
            }
            if hi - lo <= 4 {
                nodes[node] = (bmin, bmax, lo as u32, (hi - lo) as u32);
                continue;
            }
            let ext = bmax - bmin;
            let axis = if ext.x >= ext.y && ext.x >= ext.z {
                0
            } else if ext.y >= ext.z {
                1
            } else {
                2
            };
            let mid = (lo + hi) / 2;
            order[lo..hi].select_nth_unstable_by(mid - lo, |&a, &b| centroid(a)[axis].total_cmp(&centroid(b)[axis]));
            let first = nodes.len();
            nodes.push((DVec3::ZERO, DVec3::ZERO, 0, 0));
            nodes.push((DVec3::ZERO, DVec3::ZERO, 0, 0));
            nodes[node] = (bmin, bmax, first as u32, 0);
            stack.push((first, lo, mid));
            stack.push((first + 1, mid, hi));
        }
        Self { tris, nodes, order }
    }

    /// Distance (m) from `p` to the nearest triangle (∞ when there is none).
    fn distance(&self, p: DVec3) -> f64 {
        if self.tris.is_empty() {
            return f64::INFINITY;
        }
        let box_d2 = |n: usize| {
            let (lo, hi, _, _) = self.nodes[n];
            let d = (lo - p).max(p - hi).max(DVec3::ZERO);
            d.length_squared()
        };
        let mut best = f64::INFINITY;
        let mut stack = vec![(0usize, box_d2(0))];
        while let Some((n, d2)) = stack.pop() {
            if d2 >= best * best {
                continue;
            }
            let (_, _, a, count) = self.nodes[n];
            if count > 0 {
                for &i in &self.order[a as usize..(a + count) as usize] {
                    best = best.min(point_triangle_distance(p, &self.tris[i as usize]));
                }
            } else {
                let (l, r) = (a as usize, a as usize + 1);
                let (dl, dr) = (box_d2(l), box_d2(r));
                // Nearer child last, so it is searched first.
                if dl < dr {
                    stack.push((r, dr));
                    stack.push((l, dl));
                } else {
                    stack.push((l, dl));
                    stack.push((r, dr));
                }
            }
        }
        best
    }
}

/// Distance from `p` to triangle `t` (Ericson, Real-Time Collision Detection, 5.1.5).
pub fn point_triangle_distance(p: DVec3, t: &[DVec3; 3]) -> f64 {
    let [a, b, c] = *t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (p - a).length();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (p - b).length();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (p - (a + v * ab)).length();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (p - c).length();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (p - (a + w * ac)).length();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + w * (c - b))).length();
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (p - (a + ab * v + ac * w)).length()
}

/// Collapses the thin parts of a carved surface onto their middle. Carving leaves a flat emitter as
/// a lens: only cameras that graze its plane can carve just in front of and behind it, so its top
/// and bottom lie a few cells off the true surface, on either side. For each vertex, the line
/// inward along its normal is followed through `occ` until it leaves the volume; where it does so
/// within `max_thickness_m`, the vertex moves to the middle of that chord (the lens's two faces
/// meet on its mid-surface). Vertices whose chord is longer (a thick body, or the rim of a lens,
/// whose inward line runs along it) stay. Then the moves are smoothed over neighbours (two passes
/// of averaging the displacement) so that the collapsed sheet keeps no stair steps.
///
/// A beam's lens is different (`axes`: per vertex, the axis of the beam its part emits, or `None`):
/// a flat source seen only from a cone of directions about `a` carves to the double cone of
/// points every one of those cameras sees on the source, as thick at the middle as the source's
/// radius over the tangent of the cone's half-angle (cos100: 1.8 radii), so a vertex's normal no
/// longer points across it. Such a vertex follows the axis instead (towards the other sheet:
/// against its normal's side of `a`) up to `axis_max_m`; the chord's middle would be on the
/// source's plane if the double cone were symmetric about it, which perspective spoils, so the
/// part then goes onto the plane of its rim (`beam_lenses_onto_rim_planes`). Vertices whose normal
/// is within [`AXIS_MIN_COS`] of square to the axis (the lens's rim) take the ring moves below.
///
/// Returns the number of vertices moved.
pub fn collapse_thin(
    mesh: &mut Mesh,
    occ: &Occupancy,
    max_thickness_m: f64,
    axes: &[Option<DVec3>],
    axis_max_m: f64,
) -> usize {
    use rayon::prelude::*;
    let normals = vertex_normals(mesh);
    let step = occ.voxel_m * 0.25;
    let cell = |p: DVec3| {
        let q = (p - occ.origin) / occ.voxel_m;
        occ.at(q.x.floor() as i64, q.y.floor() as i64, q.z.floor() as i64)
    };
    // Whether the volume reaches further than `t` across `n` from `m` (along one of two directions
    // square to `n`, both ways): a face of a thin part, not its rim. A small part's rim is thin
    // along its normal too: a 3 mm dot's lens, 1.7 mm thick, is 3 mm across, and its rim vertices,
    // moved to the middle of that chord, shrank the dot to half its radius (a quarter of its light).
    let wider_across = |m: DVec3, n: DVec3, t: f64| {
        let u = n.any_orthonormal_vector();
        [u, n.cross(u)].into_iter().any(|d| {
            let run = |d: DVec3| {
                let mut r = 0.0;
                while r <= t && cell(m + d * (r + step)) {
                    r += step;
                }
                r
            };
            run(d) + run(-d) > t
        })
    };
    // Each vertex's move and the length of its chord.
    let found: Vec<Option<(DVec3, f64)>> = mesh
        .vertices
        .par_iter()
        .zip(&normals)
        .enumerate()
        .map(|(i, (&v, &n))| {
            if n == DVec3::ZERO {
                return None;
            }
            // The unit direction across the part (towards its other face) and how far to look.
            let (n, max_thickness_m, beam) = match axes.get(i).copied().flatten() {
                Some(a) if n.dot(a).abs() >= AXIS_MIN_COS => (a * n.dot(a).signum(), axis_max_m, true),
                Some(_) => return None,
                None => (n, max_thickness_m, false),
            };
            let mut inside = false;
            let mut s = step;
            while s <= max_thickness_m + step {
                let here = cell(v - n * s);
                if here {
                    inside = true;
                } else if inside {
                    // Left the volume: the far face lies between the last two samples.
                    let t = s - 0.5 * step;
                    if t > max_thickness_m || !(beam || wider_across(v - n * (0.5 * t), n, t)) {
                        return None;
                    }
                    return Some((-n * (0.5 * t), t));
                } else if s > 1.5 * occ.voxel_m {
                    return None;
                }
                s += step;
            }
            None
        })
        .collect();
    let mut moves: Vec<Option<DVec3>> = found.iter().map(|f| f.map(|(m, _)| m)).collect();
    let on_rim_plane = beam_lenses_onto_rim_planes(mesh, axes, &found, &mut moves, occ.voxel_m);
    let moved = moves.iter().filter(|m| m.is_some()).count();
    let mut disp: Vec<DVec3> = moves.iter().map(|m| m.unwrap_or(DVec3::ZERO)).collect();
    let neighbours = neighbours(mesh);
    for _ in 0..2 {
        let old = disp.clone();
        for (i, nb) in neighbours.iter().enumerate() {
            if moves[i].is_none() || nb.is_empty() || on_rim_plane[i] {
                continue;
            }
            let (sum, k) = nb
                .iter()
                .filter(|&&j| moves[j as usize].is_some())
                .fold((old[i], 1.0), |(s, k), &j| (s + old[j as usize], k + 1.0));
            disp[i] = sum / k;
        }
    }
    // A thin part's rim stays where carving left it (its inward line runs along the part), a skirt
    // as tall as the lens is thick there that stands out at grazing views. Rings of unmoved vertices
    // next to moved ones take their neighbours' mean move, so the skirt folds onto the middle too.
    let mut done: Vec<bool> = moves.iter().map(Option::is_some).collect();
    for _ in 0..RIM_RINGS {
        let ring: Vec<(usize, DVec3)> = neighbours
            .iter()
            .enumerate()
            .filter(|&(i, _)| !done[i])
            .filter_map(|(i, nb)| {
                let (sum, k) = nb
                    .iter()
                    .filter(|&&j| done[j as usize])
                    .fold((DVec3::ZERO, 0.0), |(s, k), &j| (s + disp[j as usize], k + 1.0));
                (k > 0.0).then(|| (i, sum / k))
            })
            .collect();
        for (i, d) in ring {
            disp[i] = d;
            done[i] = true;
        }
    }
    for (v, d) in mesh.vertices.iter_mut().zip(disp) {
        *v += d;
    }
    for _ in 0..TWIN_PASSES {
        merge_twin_sheets(mesh, &normals, &done, 2.0 * occ.voxel_m);
    }
    moved
}

/// A beam's lens is not symmetric about the source: a camera sees a point in front of the source
/// spread further over it than a point as far behind (perspective: by h / (D cos θ ∓ h)), so more is
/// carved in front, and the chords' middles lie behind the source by up to a tenth of the lens's
/// thickness (cos100 at rigo:300: 8 mm at the middle, a dish). Where the lens is thin, at its rim,
/// that is negligible, and the rim is where every camera sees the source's outline. So each
/// connected part with a beam axis whose vertices with a chord of at most [`RIM_CHORD_CELLS`] cells
/// (their middles) lie on a plane (at least half of them within two cells, those within a cell RMS)
/// goes onto that plane along the axis, every vertex. Returns which vertices did (their moves in `moves`).
fn beam_lenses_onto_rim_planes(
    mesh: &Mesh,
    axes: &[Option<DVec3>],
    found: &[Option<(DVec3, f64)>],
    moves: &mut [Option<DVec3>],
    voxel_m: f64,
) -> Vec<bool> {
    let mut done = vec![false; mesh.vertices.len()];
    if !axes.iter().any(Option::is_some) {
        return done;
    }
    // A part's vertices share its axis (or have none).
    for vs in members(&components(mesh)).values() {
        let Some(axis) = axes.get(vs[0]).copied().flatten() else {
            continue;
        };
        let rim: Vec<DVec3> = vs
            .iter()
            .filter_map(|&i| {
                let (m, t) = found[i]?;
                (t <= RIM_CHORD_CELLS * voxel_m).then(|| mesh.vertices[i] + m)
            })
            .collect();
        if rim.len() < 16 {
            continue;
        }
        // Robustly: from the plane across the axis at the rim's median height, twice the plane of
        // the rim vertices within two cells of the last one (the caps where the content's box cut
        // the lens, and stray ends, have short chords too).
        let mut heights: Vec<f64> = rim.iter().map(|p| p.dot(axis)).collect();
        heights.sort_by(f64::total_cmp);
        let mut plane = (axis * heights[heights.len() / 2], axis);
        let mut inliers = Vec::new();
        for _ in 0..2 {
            let (c, n) = plane;
            inliers = rim
                .iter()
                .copied()
                .filter(|p| (*p - c).dot(n).abs() <= 2.0 * voxel_m)
                .collect();
            match (inliers.len() >= 16)
                .then(|| super::refine::plane_of(&inliers))
                .flatten()
            {
                Some((c, n, _)) => plane = (c, n),
                None => break,
            }
        }
        let (c, n) = plane;
        let rms = (inliers.iter().map(|p| (*p - c).dot(n).powi(2)).sum::<f64>() / inliers.len().max(1) as f64).sqrt();
        let facing = n.dot(axis);
        if 2 * inliers.len() < rim.len() || rms > voxel_m || facing.abs() < 0.5 {
            continue;
        }
        for &i in vs {
            moves[i] = Some(axis * ((c - mesh.vertices[i]).dot(n) / facing));
            done[i] = true;
        }
    }
    done
}

/// A beam lens's rim: its vertices whose chord along the axis is at most this many cells.
pub const RIM_CHORD_CELLS: f64 = 4.0;

/// A vertex of a beam's lens follows the beam's axis across it when its normal's cosine with the
/// axis is at least this (the double cone's faces: 0.48 for cos100, 0.97 for cos10); flatter to
/// the axis, it is on the lens's rim.
pub const AXIS_MIN_COS: f64 = 0.2;

/// Passes of [`merge_twin_sheets`] after a collapse.
const TWIN_PASSES: usize = 2;

/// Brings a collapsed part's two sheets onto one surface. Each sheet was moved to the middle of its
/// own chord, and where the lens was lopsided the two middles differ (star-panel: 5th / 95th
/// percentile −0.9 / +1.0 mm about the panel), so a view sees whichever sheet is nearer and the
/// surface it samples alternates along edges. Every vertex that moved (`moved`) looks along its
/// normal from before the collapse (`normals`), both ways within `reach_m`, for the nearest
/// triangle of the other sheet (its corners' normals from before the collapse face the other way)
/// and goes half way there; all at once, so the two sheets meet in the middle.
fn merge_twin_sheets(mesh: &mut Mesh, normals: &[DVec3], moved: &[bool], reach_m: f64) {
    use rayon::prelude::*;
    use std::collections::HashMap;
    let key = |p: DVec3| -> [i64; 3] {
        let q = p / reach_m;
        [q.x.floor() as i64, q.y.floor() as i64, q.z.floor() as i64]
    };
    // Triangles of moved vertices only, by the cells their boxes overlap.
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
    // A triangle's normal from its corners' (worked out where needed: held for every triangle it
    // was 2.6 MB of the reconstruction's peak on the full-size disc).
    let tri_normal = |t: &[u32; 3]| {
        t.iter()
            .map(|&i| normals[i as usize])
            .sum::<DVec3>()
            .normalize_or_zero()
    };
    for (ti, t) in mesh.triangles.iter().enumerate() {
        if !t.iter().any(|&i| moved[i as usize]) {
            continue;
        }
        let [a, b, c] = mesh.corners(t);
        let (lo, hi) = (key(a.min(b).min(c)), key(a.max(b).max(c)));
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    grid.entry([x, y, z]).or_default().push(ti as u32);
                }
            }
        }
    }
    let moves: Vec<DVec3> = mesh
        .vertices
        .par_iter()
        .enumerate()
        .map(|(i, &v)| {
            let n = normals[i];
            if !moved[i] || n == DVec3::ZERO {
                return DVec3::ZERO;
            }
            let (lo, hi) = (
                key((v - reach_m * n).min(v + reach_m * n)),
                key((v - reach_m * n).max(v + reach_m * n)),
            );
            let mut best: Option<f64> = None;
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        let Some(list) = grid.get(&[x, y, z]) else { continue };
                        for &ti in list {
                            let t = &mesh.triangles[ti as usize];
                            if t.contains(&(i as u32)) || tri_normal(t).dot(n) > -0.3 {
                                continue;
                            }
                            if let Some(d) = line_triangle(v, n, mesh.corners(t)) {
                                if d.abs() <= reach_m && best.is_none_or(|b| d.abs() < b.abs()) {
                                    best = Some(d);
                                }
                            }
                        }
                    }
                }
            }
            best.map_or(DVec3::ZERO, |d| 0.5 * d * n)
        })
        .collect();
    for (v, d) in mesh.vertices.iter_mut().zip(moves) {
        *v += d;
    }
}

/// Where the line `o + d·dir` (any real d) crosses triangle `t`: d, or `None` when it misses or runs
/// parallel (Möller–Trumbore without the ray's sign test).
fn line_triangle(o: DVec3, dir: DVec3, t: [DVec3; 3]) -> Option<f64> {
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-18 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - t[0];
    let u = s.dot(p) * inv;
    if !(-1e-9..=1.0 + 1e-9).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let w = dir.dot(q) * inv;
    if w < -1e-9 || u + w > 1.0 + 1e-9 {
        return None;
    }
    Some(e2.dot(q) * inv)
}

/// Rings of vertices around a collapsed part that follow its moves ([`collapse_thin`]).
const RIM_RINGS: usize = 3;

/// Area-weighted vertex normals (unit, outward for a mesh wound outwards; zero where undefined).
fn vertex_normals(mesh: &Mesh) -> Vec<DVec3> {
    let mut normals = vec![DVec3::ZERO; mesh.vertices.len()];
    for t in &mesh.triangles {
        let [a, b, c] = mesh.corners(t);
        let n = (b - a).cross(c - a);
        for &i in t {
            normals[i as usize] += n;
        }
    }
    normals.into_iter().map(|n| n.normalize_or_zero()).collect()
}

/// Each vertex's neighbours along the triangles' edges.
fn neighbours(mesh: &Mesh) -> Vec<Vec<u32>> {
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); mesh.vertices.len()];
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if !neighbours[a as usize].contains(&b) {
                neighbours[a as usize].push(b);
                neighbours[b as usize].push(a);
            }
        }
    }
    neighbours
}

/// The connected component (sharing vertices along triangles) of every vertex, as the index of one
/// of its vertices.
pub fn components(mesh: &Mesh) -> Vec<u32> {
    components_of(mesh.vertices.len(), &mesh.triangles)
}

/// [`components`] of the triangles `triangles` over `n` vertices (a vertex no triangle uses is its
/// own component).
pub fn components_of<'a>(n: usize, triangles: impl IntoIterator<Item = &'a [u32; 3]>) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn root(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            let up = parent[parent[x as usize] as usize];
            parent[x as usize] = up;
            x = up;
        }
        x
    }
    for t in triangles {
        for k in 1..3 {
            let (a, b) = (root(&mut parent, t[0]), root(&mut parent, t[k]));
            if a != b {
                parent[a as usize] = b;
            }
        }
    }
    (0..n as u32).map(|v| root(&mut parent, v)).collect()
}

/// The vertices of each connected component, keyed by the component's id in `component` (as
/// [`components`] gives it), in index order.
pub fn members(component: &[u32]) -> std::collections::BTreeMap<u32, Vec<usize>> {
    let mut parts: std::collections::BTreeMap<u32, Vec<usize>> = std::collections::BTreeMap::new();
    for (i, &c) in component.iter().enumerate() {
        parts.entry(c).or_default().push(i);
    }
    parts
}

/// `mesh` without its connected components (sharing vertices) of fewer than `min_fraction` of its
/// triangles, and how many triangles went. Unused vertices are dropped and the rest renumbered in
/// order.
pub fn without_small_components(mesh: &Mesh, min_fraction: f64) -> (Mesh, usize) {
    let n = mesh.vertices.len();
    let component = components(mesh);
    let mut size = vec![0usize; n];
    for t in &mesh.triangles {
        size[component[t[0] as usize] as usize] += 1;
    }
    let min = (min_fraction * mesh.triangles.len() as f64).ceil() as usize;
    let kept: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .copied()
        .filter(|t| size[component[t[0] as usize] as usize] >= min)
        .collect();
    let dropped = mesh.triangles.len() - kept.len();
    (compacted(&mesh.vertices, kept), dropped)
}

/// The mesh of `triangles` (indices into `vertices`) with only the vertices they use, renumbered
/// in the order the triangles first use them.
pub fn compacted(vertices: &[DVec3], triangles: impl IntoIterator<Item = [u32; 3]>) -> Mesh {
    let mut index = vec![u32::MAX; vertices.len()];
    let mut out = Mesh::default();
    for t in triangles {
        let t = t.map(|v| {
            if index[v as usize] == u32::MAX {
                index[v as usize] = out.vertices.len() as u32;
                out.vertices.push(vertices[v as usize]);
            }
            index[v as usize]
        });
        out.triangles.push(t);
    }
    out
}

/// The cells of `occ`'s grid that `mesh` passes through (each triangle sampled every quarter cell),
/// as an occupancy: to measure how much light a mesh that no longer bounds a volume explains.
pub fn cells_of(mesh: &Mesh, occ: &Occupancy) -> Occupancy {
    let n = occ.n as i64;
    let mut cells = Cells::new(occ.cells.len());
    let mut mark = |p: DVec3| {
        let q = ((p - occ.origin) / occ.voxel_m).floor();
        let (x, y, z) = (q.x as i64, q.y as i64, q.z as i64);
        if (0..n).contains(&x) && (0..n).contains(&y) && (0..n).contains(&z) {
            cells.set(((z * n + y) * n + x) as usize, true);
        }
    };
    for t in &mesh.triangles {
        let [a, b, c] = mesh.corners(t);
        let longest = (b - a).length().max((c - b).length()).max((a - c).length());
        let k = ((longest / (0.25 * occ.voxel_m)).ceil() as usize).clamp(1, 64);
        for i in 0..=k {
            for j in 0..=(k - i) {
                let (u, v) = (i as f64 / k as f64, j as f64 / k as f64);
                mark(a + (b - a) * u + (c - a) * v);
            }
        }
    }
    occ.with_cells(cells)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ball(n: usize, r_cells: f64) -> Occupancy {
        let mut cells = Cells::new(n * n * n);
        let c = n as f64 / 2.0;
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let p = DVec3::new(x as f64 + 0.5, y as f64 + 0.5, z as f64 + 0.5) - c;
                    cells.set((z * n + y) * n + x, p.length() <= r_cells);
                }
            }
        }
        Occupancy {
            origin: DVec3::ZERO,
            voxel_m: 1.0 / n as f64,
            n,
            cells,
            tests: 0,
        }
    }

    /// The cells of an `n`³ grid over the unit cube whose centres, in cells from the grid's centre,
    /// satisfy `inside`.
    fn shape(n: usize, inside: impl Fn(DVec3) -> bool) -> Occupancy {
        let mut occ = ball(n, 0.0);
        let c = n as f64 / 2.0;
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let d = DVec3::new(x as f64, y as f64, z as f64) + 0.5 - c;
                    occ.cells.set((z * n + y) * n + x, inside(d));
                }
            }
        }
        occ
    }

    /// A lens-like slab: a disc of radius `r_cells`, `thick` cells thick about z = n/2.
    fn slab(n: usize, r_cells: f64, thick: usize) -> Occupancy {
        let mut occ = ball(n, 0.0);
        let c = n as f64 / 2.0;
        for z in (n - thick) / 2..(n + thick) / 2 {
            for y in 0..n {
                for x in 0..n {
                    let (dx, dy) = (x as f64 + 0.5 - c, y as f64 + 0.5 - c);
                    occ.cells.set((z * n + y) * n + x, dx.hypot(dy) <= r_cells);
                }
            }
        }
        occ
    }

    /// A beam's lens: a double cone on a disc of 14 cells' radius in z = n/2, its apexes 20 cells
    /// above and 16 below (a camera spreads a point in front of a source further over it than one
    /// behind). Along its normals the collapse cannot cross it (the chords are longer than the
    /// limit); along the beam's axis every vertex goes onto the rim's plane, and the disc keeps
    /// its radius.
    #[test]
    fn a_beams_lopsided_double_cone_goes_onto_the_plane_of_its_rim() {
        let n = 64;
        let cell = 1.0 / n as f64;
        let (r, above, below) = (14.0, 20.0, 16.0);
        let occ = shape(n, |d| {
            let height = if d.z >= 0.0 { above } else { below };
            d.x.hypot(d.y) <= r * (1.0 - d.z.abs() / height)
        });
        let original = surface_nets(&occ);
        let mut m = original.clone();
        assert_eq!(
            collapse_thin(&mut m, &occ, 4.0 * cell, &[], 0.0),
            0,
            "too thick along the normals"
        );
        let axes = vec![Some(DVec3::Z); m.vertices.len()];
        let moved = collapse_thin(&mut m, &occ, 4.0 * cell, &axes, 1.0);
        assert!(moved > m.vertices.len() * 9 / 10, "{moved} of {}", m.vertices.len());
        let worst = m
            .vertices
            .iter()
            .map(|v| ((v.z - 0.5) / cell).abs())
            .fold(0.0, f64::max);
        assert!(worst < 0.6, "farthest vertex {worst:.2} cells off the plane");
        let radius = m
            .vertices
            .iter()
            .map(|v| (v.x - 0.5).hypot(v.y - 0.5) / cell)
            .fold(0.0, f64::max);
        assert!((radius - r).abs() < 1.0, "radius {radius:.2} cells, not {r}");
        // Without the rim's plane (the chords' middles alone) the middle would sit lower.
        let mids: Vec<f64> = original
            .vertices
            .iter()
            .filter(|v| (v.x - 0.5).hypot(v.y - 0.5) / cell < 3.0)
            .map(|v| (v.z - 0.5) / cell)
            .collect();
        let (top, bottom) = mids
            .iter()
            .fold((f64::MIN, f64::MAX), |(t, b), &z| (t.max(z), b.min(z)));
        assert!(
            0.5 * (top + bottom) > 1.0,
            "chord middle at the axis {:.2} cells",
            0.5 * (top + bottom)
        );
    }

    /// A wedge: flat on top, its bottom tilted, 3 to 9 cells thick. Each sheet's own chord
    /// midpoint differs (the bottom's chords run along its tilted normal); after the collapse the
    /// two sheets are one surface: every moved vertex lies within 0.1 cell of the other sheet.
    #[test]
    fn a_lopsided_lens_collapses_onto_one_surface() {
        let n = 48;
        let cell = 1.0 / n as f64;
        let occ = shape(n, |d| {
            let top = 1.5;
            let bottom = top - (3.0 + 6.0 * (d.x + 18.0) / 36.0);
            d.x.abs() <= 18.0 && d.y.abs() <= 18.0 && d.z <= top && d.z >= bottom
        });
        let original = surface_nets(&occ);
        let normals = vertex_normals(&original);
        let mut m = original.clone();
        let moved = collapse_thin(&mut m, &occ, 12.0 * cell, &[], 0.0);
        assert!(moved > m.vertices.len() / 2, "{moved} of {}", m.vertices.len());
        let up: Vec<[DVec3; 3]> = m
            .triangles
            .iter()
            .filter(|t| t.iter().map(|&i| normals[i as usize]).sum::<DVec3>().z > 0.0)
            .map(|t| m.corners(t))
            .collect();
        let down: Vec<[DVec3; 3]> = m
            .triangles
            .iter()
            .filter(|t| t.iter().map(|&i| normals[i as usize]).sum::<DVec3>().z < 0.0)
            .map(|t| m.corners(t))
            .collect();
        let mut worst = 0.0f64;
        for (i, v) in m.vertices.iter().enumerate() {
            let (dx, dy) = ((v.x - 0.5) / cell, (v.y - 0.5) / cell);
            if dx.abs() > 14.0 || dy.abs() > 14.0 {
                continue; // the rim
            }
            let other = if normals[i].z > 0.0 { &down } else { &up };
            let d = other
                .iter()
                .map(|t| point_triangle_distance(*v, t))
                .fold(f64::INFINITY, f64::min);
            worst = worst.max(d / cell);
        }
        assert!(worst < 0.1, "a vertex {worst} cells from the other sheet");
    }

    #[test]
    fn a_thin_slab_collapses_onto_its_middle_and_a_ball_does_not() {
        let n = 48;
        let cell = 1.0 / n as f64;
        let occ = slab(n, 18.0, 6);
        let mut m = surface_nets(&occ);
        let moved = collapse_thin(&mut m, &occ, 10.0 * cell, &[], 0.0);
        assert!(moved > m.vertices.len() / 2, "{moved} of {}", m.vertices.len());
        // The faces' vertices (away from the rim) sit on the mid-plane z = 0.5 within a quarter cell.
        let mut faces = 0;
        for v in &m.vertices {
            let r = (v.x - 0.5).hypot(v.y - 0.5);
            if r < 14.0 * cell {
                faces += 1;
                assert!(
                    (v.z - 0.5).abs() < 0.25 * cell,
                    "{v} off the mid-plane by {} cells",
                    (v.z - 0.5) / cell
                );
            }
        }
        assert!(faces > 100);
        // A body thicker than the limit keeps its surface.
        let occ = ball(32, 10.0);
        let mut m = surface_nets(&occ);
        let before = m.vertices.clone();
        assert_eq!(collapse_thin(&mut m, &occ, 8.0 / 32.0, &[], 0.0), 0);
        assert_eq!(m.vertices, before);
        // The collapsed slab still passes through the cells the carved one lit up: its cells lie in
        // the slab's middle layers.
        let occ = slab(n, 18.0, 6);
        let mut m = surface_nets(&occ);
        collapse_thin(&mut m, &occ, 10.0 * cell, &[], 0.0);
        let cells = cells_of(&m, &occ);
        assert!(cells.count() > 0);
        for (i, c) in cells.cells.iter().enumerate() {
            let z = i / (n * n);
            if c {
                let (x, y) = (i % n, (i / n) % n);
                let r = (x as f64 + 0.5 - 24.0).hypot(y as f64 + 0.5 - 24.0);
                assert!(r > 14.0 || (z == 23 || z == 24), "cell {x},{y},{z}");
            }
        }
    }

    #[test]
    fn a_voxel_ball_becomes_a_closed_sphere_of_its_radius() {
        let occ = ball(32, 10.0);
        let m = surface_nets(&occ);
        // Closed: every edge is shared by exactly two triangles, opposite ways.
        let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
        for t in &m.triangles {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        assert!(edges
            .iter()
            .all(|(&(a, b), &c)| c == 1 && edges.get(&(b, a)) == Some(&1)));
        // Outward: the signed volume is positive and close to the ball's.
        let vol: f64 = m
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.vertices[i as usize] - DVec3::splat(0.5));
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        let r = 10.0 / 32.0;
        let exact = 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
        assert!((vol / exact - 1.0).abs() < 0.08, "volume {vol} vs {exact}");
        // Every vertex within half a cell of the sphere.
        for v in &m.vertices {
            assert!(((*v - DVec3::splat(0.5)).length() - r).abs() < 0.75 / 32.0, "{v}");
        }
    }

    #[test]
    fn chamfer_of_a_shifted_square_is_the_shift() {
        let sq = |z: f32| -> Vec<[f32; 3]> {
            vec![
                [0.0, 0.0, z],
                [1.0, 0.0, z],
                [1.0, 1.0, z],
                [0.0, 0.0, z],
                [1.0, 1.0, z],
                [0.0, 1.0, z],
            ]
        };
        let c = chamfer(&sq(0.0), &sq(0.01), 5000);
        assert!((c.mean_m - 0.01).abs() < 1e-6 && (c.p95_m - 0.01).abs() < 1e-6, "{c:?}");
        let same = chamfer(&sq(0.0), &sq(0.0), 1000);
        assert!(same.max_m < 1e-9);
        // A point far off: distance is exact.
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        assert!((point_triangle_distance(DVec3::new(0.2, 0.2, 3.0), &t) - 3.0).abs() < 1e-12);
        assert!((point_triangle_distance(DVec3::new(-1.0, 0.0, 0.0), &t) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn small_components_go_and_the_rest_keeps_its_shape() {
        // A 10 × 10 quad grid (200 triangles) and a lone triangle far away.
        let mut m = Mesh::default();
        for y in 0..=10 {
            for x in 0..=10 {
                m.vertices.push(DVec3::new(f64::from(x), f64::from(y), 0.0));
            }
        }
        for y in 0..10u32 {
            for x in 0..10u32 {
                let v = y * 11 + x;
                m.triangles.push([v, v + 1, v + 12]);
                m.triangles.push([v, v + 12, v + 11]);
            }
        }
        let lone = m.vertices.len() as u32;
        m.vertices.extend([
            DVec3::new(50.0, 0.0, 0.0),
            DVec3::new(51.0, 0.0, 0.0),
            DVec3::new(50.0, 1.0, 0.0),
        ]);
        m.triangles.push([lone, lone + 1, lone + 2]);
        let (kept, dropped) = without_small_components(&m, 0.01);
        assert_eq!(dropped, 1);
        assert_eq!(kept.triangles.len(), 200);
        assert_eq!(kept.vertices.len(), 121);
        assert!((kept.area() - 100.0).abs() < 1e-9);
        // Nothing below the fraction: the mesh is unchanged.
        let (same, none) = without_small_components(&m, 0.0);
        assert_eq!((same.triangles.len(), none), (201, 0));
    }
}
