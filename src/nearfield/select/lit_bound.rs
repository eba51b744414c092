//! A tight bounding polygon for the near-field pass without a proxy.
//!
//! Without a proxy, the fragment of view line (eye, v) finds Q, the line's first point on the capture
//! sphere, selects cameras around Q, and samples each selected camera j at the pixel `K_j · R_j · v`
//! (the view ray rotated into the camera; see shaders/nearfield.wgsl). So the pixel can hold light only
//! if, for some camera j the view can select,
//! - v lies in D_j, the cone of directions camera j maps into the convex hull of its lit pixels
//!   (widened by the bilinear footprint), and
//! - Q lies where j can be selected: within ρ_j (great-circle) of j's vertex, ρ_j being the farthest a
//!   point selecting j can be (continuous: j's longest edge to a neighbour in a non-hole triangle, as a
//!   point of a triangle is nearest its farthest vertex at a vertex; nearest: the largest circumradius
//!   around j, which bounds j's Voronoi cell, at most the selection's max gap; idw4: the max gap). The
//!   lines from the eye whose first hit lies in that cap leave the eye (forwards from outside the
//!   sphere, backwards from inside) within the cone E_j around the direction of j's vertex point,
//!   of half-angle asin(chord / distance) where chord is the cap's chord.
//!
//! On the screen both cones are convex polygons (while every direction involved lies in front of the
//! eye), E_j taken as the octagon circumscribing its circle; the convex hull of the intersections
//! D_j ∩ E_j over the selectable cameras contains every pixel that can be lit. The pass draws that hull,
//! placed on the plane through the capture centre facing the eye, instead of the content ball's box:
//! a fragment anywhere on a view line computes the same luminance (the shader works on the line and
//! writes the stand-in depth itself), so moving the drawn surface along the lines changes only which
//! fragments run. D_j alone is not enough: from an eye farther than the capture sphere a camera's
//! cone of directions is wider than the luminaire as seen from the eye.

use glam::{DVec2, DVec3, Mat4, Vec2, Vec3, Vec4};
use rayon::prelude::*;

use super::view::orthonormal;
use super::{Selection, SelectionMode};
use crate::nearfield::pack::{Pack, EMPTY_TILE};
use crate::nearfield::{NearfieldError, RayImageSet};

/// How far (camera pixels) a kept tile can light a sample outside it: the bilinear footprint reaches
/// half a pixel beyond a texel centre; 0.1 more for rounding.
pub const FOOTPRINT_PX: f64 = 0.6;

/// The margin (screen pixels) a raster polygon is grown by beyond the sagitta of its arcs (×1.5):
/// the rasteriser covers a pixel by its centre, so only rounding needs room.
pub const GROW_PX: f32 = 0.25;

/// Per camera: the corner directions of D_j, and the cap radii ρ_j (rad) for the three modes.
#[derive(Debug, Clone)]
struct CameraCone {
    /// Unit directions (luminaire frame) of the corners of the convex hull of the camera's lit
    /// pixels (each widened by [`FOOTPRINT_PX`]): the edges of its cone D.
    corners: Vec<Vec3>,
    /// Unit direction of the camera's selection vertex from the capture centre.
    vertex: DVec3,
    /// ρ for nearest, idw4, continuous.
    rho: [f64; SelectionMode::ALL.len()],
    /// The corners of the camera's Voronoi cell (unit directions: the circumcentres of the triangles
    /// around its vertex); `None` where a triangle around it is a hole or folded (its region then
    /// reaches out to the max gap: the cap of radius ρ stands in).
    cell: Option<Vec<DVec3>>,
}

/// The per-camera data of the bounding polygon.
#[derive(Debug, Clone, Default)]
pub struct LitDirections {
    cameras: Vec<Option<CameraCone>>,
    /// Per selection vertex: its camera's ρ for nearest, idw4, continuous (rad), lit or not, with its
    /// cosine and sine.
    vertex_rho: Vec<[(f64, f64, f64); SelectionMode::ALL.len()]>,
    /// Capture centre (m) and radius (m).
    sphere: (DVec3, f64),
}

impl LitDirections {
    /// The cones of every camera of a pack that has kept tiles and is a selection vertex: over the
    /// convex hull of its lit pixels where `pixels` (which reads the tiles at the ends of every tile
    /// row: for a pack that goes to the GPU whole, whose pages are read anyway), else of its kept
    /// tiles (from the tile tables alone: a streamed pack's pages are read when they are needed).
    ///
    /// Errors: a tile that cannot be read or decoded (a damaged page), naming the pack and page.
    pub fn new(set: &RayImageSet, pack: &Pack, sel: &Selection, pixels: bool) -> Result<Self, NearfieldError> {
        let t = f64::from(pack.layout().tile_size);
        let dirs = sel.vertex_directions();
        let angle = |a: DVec3, b: DVec3| a.cross(b).length().atan2(a.dot(b));
        let max_gap = sel.max_gap_rad();
        // Per vertex: longest edge in a non-hole triangle, largest circumradius (capped at max_gap).
        let mut edge = vec![0f64; dirs.len()];
        let mut circ = vec![0f64; dirs.len()];
        let mut cells: Vec<Option<Vec<DVec3>>> = vec![Some(Vec::new()); dirs.len()];
        for (i, tri) in sel.triangles().iter().enumerate() {
            let r = sel.circumcap(i).map_or(max_gap, |c| c.1).min(max_gap);
            let open = sel.is_hole(i) || sel.is_folded(i) || r >= max_gap;
            for k in 0..3 {
                let v = tri[k] as usize;
                circ[v] = circ[v].max(r);
                match (open, sel.circumcap(i), &mut cells[v]) {
                    (false, Some((cc, _)), Some(list)) => list.push(cc),
                    _ => cells[v] = None,
                }
                if !sel.is_hole(i) {
                    for o in [tri[(k + 1) % 3], tri[(k + 2) % 3]] {
                        edge[v] = edge[v].max(angle(dirs[v], dirs[o as usize]));
                    }
                }
            }
        }
        let mut vertex_of = vec![None; set.cameras.len()];
        for (v, &c) in sel.vertex_camera().iter().enumerate() {
            if let Some(slot) = vertex_of.get_mut(c as usize) {
                *slot = Some(v);
            }
        }
        // In parallel: the tile tables of a full-size scan hold hundreds of millions of entries.
        let cameras = (0..set.cameras.len().min(pack.images().len()))
            .into_par_iter()
            .map(|i| {
                let (c, e) = (&set.cameras[i], &pack.images()[i]);
                let Some(v) = vertex_of[i] else {
                    return Ok(None);
                };
                if e.bbox.w == 0 || e.bbox.h == 0 {
                    return Ok(None);
                }
                let k = set.intrinsics_of(i);
                let dir = |px: f64, py: f64| {
                    let n = (DVec2::new(px, py) - k.principal_px) / k.focal_px;
                    (c.right * n.x + c.down * n.y + c.forward).normalize().as_vec3()
                };
                // Per pixel row, the leftmost and rightmost lit pixel (widened by the footprint),
                // read from the kept tiles of its tile row from either end inwards until every pixel
                // row has found its light (a row dark in the first kept tile has its light further
                // in, where a slanted edge crosses the tile row). Without `pixels` a kept tile counts
                // as lit throughout.
                let table = pack.tile_table(i).unwrap_or(&[]);
                let ts = t as usize;
                let mut pts = Vec::new();
                let mut values = vec![0f32; ts * ts];
                for r in 0..e.bbox.h as usize {
                    let row = table
                        .get(r * e.bbox.w as usize..(r + 1) * e.bbox.w as usize)
                        .unwrap_or(&[]);
                    let kept: Vec<usize> = (0..row.len()).filter(|&k| row[k] != EMPTY_TILE).collect();
                    if kept.is_empty() {
                        continue;
                    }
                    let ty = e.bbox.y0 as usize + r;
                    let rows_in_image = (e.height as usize).saturating_sub(ty * ts).min(ts);
                    // first[y]: left edge of the leftmost lit pixel; last[y]: right edge of the rightmost.
                    let mut first: Vec<Option<usize>> = vec![None; rows_in_image];
                    let mut last: Vec<Option<usize>> = vec![None; rows_in_image];
                    for (out, leftmost) in [(&mut first, true), (&mut last, false)] {
                        let order: Box<dyn Iterator<Item = &usize>> = if leftmost {
                            Box::new(kept.iter())
                        } else {
                            Box::new(kept.iter().rev())
                        };
                        for &k in order {
                            if out.iter().all(Option::is_some) {
                                break;
                            }
                            let x_tile = (e.bbox.x0 as usize + k) * ts;
                            // A damaged page is an error at once (the pack remembers it), not a tile
                            // taken as lit and read again for every tile of every row.
                            let readable = pixels && pack.decode_slot(row[k], &mut values).map(|_| true)?;
                            for (y, o) in out.iter_mut().enumerate() {
                                if o.is_some() {
                                    continue;
                                }
                                let line = &values[y * ts..(y + 1) * ts];
                                let lit = |v: &f32| !readable || *v > 0.0;
                                let hit = if leftmost {
                                    line.iter().position(lit)
                                } else {
                                    line.iter().rposition(lit)
                                };
                                *o = hit.map(|x| x_tile + x + usize::from(!leftmost));
                            }
                        }
                    }
                    for y in 0..rows_in_image {
                        // A pixel row without light in any kept tile is dark.
                        let (Some(l), Some(rr)) = (first[y], last[y]) else {
                            continue;
                        };
                        let py = (ty * ts + y) as f64;
                        let (y0, y1) = (py - FOOTPRINT_PX, py + 1.0 + FOOTPRINT_PX);
                        let (x0, x1) = (l as f64 - FOOTPRINT_PX, rr as f64 + FOOTPRINT_PX);
                        for (x, y) in [(x0, y0), (x1, y0), (x1, y1), (x0, y1)] {
                            pts.push((x as f32, y as f32, ()));
                        }
                    }
                }
                let hull = convex_hull(pts);
                if hull.len() < 3 {
                    return Ok(None);
                }
                // 1 % and 10⁻⁶ rad of margin over the exact radii (rounding at triangle edges).
                let grow = |r: f64| r * 1.01 + 1e-6;
                Ok(Some(CameraCone {
                    corners: hull.iter().map(|h| dir(f64::from(h.0), f64::from(h.1))).collect(),
                    vertex: dirs[v],
                    rho: [grow(circ[v]), grow(max_gap), grow(edge[v])],
                    cell: cells[v].clone().filter(|c| c.len() >= 3),
                }))
            })
            .collect::<Result<Vec<_>, NearfieldError>>()?;
        let vertex_rho = (0..dirs.len())
            .map(|v| {
                [circ[v], max_gap, edge[v]].map(|r| {
                    let r = r * 1.01 + 1e-6;
                    (r, r.cos(), r.sin())
                })
            })
            .collect();
        Ok(LitDirections {
            cameras,
            vertex_rho,
            sphere: (set.sphere.centre_m, set.sphere.radius_m),
        })
    }

    /// The bounding polygon of a perspective view from `eye` (luminaire frame, m) in `mode` for the
    /// selectable `cameras`, as a triangle list (luminaire frame, m) on the plane through the capture
    /// centre facing the eye; `clip_from_local` is the draw's matrix. An empty list: no pixel can be
    /// lit. `None` when the bound does not apply (a direction at or behind the eye's plane, a cap
    /// around the eye, a plane seen edge-on): draw the box instead.
    pub fn bound(
        &self,
        cameras: &[u32],
        mode: SelectionMode,
        clip_from_local: Mat4,
        eye: Vec3,
    ) -> Option<Vec<[f32; 3]>> {
        let (centre, r_s) = self.sphere;
        let e = eye.as_dvec3();
        let n = (e - centre).normalize_or_zero();
        if n == DVec3::ZERO {
            return None;
        }
        let m = mode.index() as usize;
        // Lines leave the eye towards their first hit from outside the sphere, away from it inside.
        let sign = if (e - centre).length() > r_s { 1.0 } else { -1.0 };
        let project = |d: DVec3| -> Option<Vec2> {
            let h = clip_from_local * Vec4::new(d.x as f32, d.y as f32, d.z as f32, 0.0);
            (h.w > 1e-6 * h.truncate().length()).then(|| Vec2::new(h.x / h.w, h.y / h.w))
        };
        let mut pts: Vec<Vec2> = Vec::with_capacity(cameras.len() * 8);
        for &c in cameras {
            let Some(Some(cone)) = self.cameras.get(c as usize) else {
                continue;
            };
            // E_j: the octagon around the cone to the cap's chord ball.
            let q = centre + cone.vertex * r_s;
            let to_q = q - e;
            let dist = to_q.length();
            let chord = 2.0 * r_s * (0.5 * cone.rho[m]).min(std::f64::consts::FRAC_PI_2).sin();
            if chord >= 0.95 * dist {
                return None;
            }
            let axis = to_q / dist * sign;
            let tan_g = (chord / dist).asin().tan() / (std::f64::consts::PI / 8.0).cos();
            if tan_g > 5.0 {
                return None;
            }
            let (b1, b2) = orthonormal(axis);
            let mut oct = Vec::with_capacity(8);
            for k in 0..8 {
                let a = std::f64::consts::TAU * f64::from(k) / 8.0;
                oct.push(project(axis + (b1 * a.cos() + b2 * a.sin()) * tan_g)?);
            }
            let mut quad = Vec::with_capacity(4);
            for d in &cone.corners {
                quad.push(project(d.as_dvec3())?);
            }
            pts.extend(clip_convex(&oct, &quad));
        }
        let hull = convex_hull(pts.into_iter().map(|p| (p.x, p.y, ())).collect());
        if hull.len() < 3 {
            return Some(Vec::new());
        }
        // Each hull vertex back onto the plane through the centre facing the eye.
        let local_from_clip = clip_from_local.inverse();
        let dist = (centre - e).dot(n);
        let mut on_plane = Vec::with_capacity(hull.len());
        for (x, y, ()) in hull {
            let p = local_from_clip * Vec4::new(x, y, 0.5, 1.0);
            let d = (p.truncate() / p.w).as_dvec3() - e;
            let dn = d.dot(n);
            // (NaN included.)
            if dn.is_nan() || dn >= -1e-9 * d.length() {
                return None;
            }
            on_plane.push((e + d * (dist / dn)).as_vec3().to_array());
        }
        let mut out = Vec::with_capacity((on_plane.len() - 2) * 3);
        for i in 1..on_plane.len() - 1 {
            out.extend([on_plane[0], on_plane[i], on_plane[i + 1]]);
        }
        Some(out)
    }
}

/// A vertex of a frame's bounding polygons: a point (luminaire frame, m) and, in the continuous
/// raster, the selection triangle whose region it covers ([`EMPTY_TRIANGLE`] in the hull polygon).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PolygonVertex {
    /// Position (m, luminaire frame).
    pub pos: [f32; 3],
    /// Selection triangle.
    pub tri: u32,
}

/// The `tri` of a hull polygon's vertices.
pub const EMPTY_TRIANGLE: u32 = u32::MAX;

/// What a frame's bounding polygons are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PolygonKind {
    /// The convex hull ([`LitDirections::bound`]); `tri` is [`EMPTY_TRIANGLE`].
    Hull,
    /// The continuous raster ([`LitDirections::continuous_raster`]); `tri` is a selection triangle.
    Triangles,
    /// The nearest raster ([`LitDirections::nearest_raster`]); `tri` is a camera.
    Cells,
}

/// Screen geometry of one view: NDC ↔ pixels, the sign that puts first sphere hits in front.
struct Screen {
    clip_from_local: Mat4,
    half: Vec2,
    /// 1 from outside the sphere; −1 from inside, where a line's first hit lies behind the eye.
    sign: f32,
}

impl Screen {
    /// Pixel position (from the centre) of a point (w = 1) or direction (w = 0); `None` when it is not
    /// in front of the eye.
    fn px(&self, x: Vec4, sign: f32) -> Option<Vec2> {
        let h = self.clip_from_local * x * sign;
        (h.w > 1e-6 * h.truncate().length()).then(|| Vec2::new(h.x / h.w, h.y / h.w) * self.half)
    }
}

impl LitDirections {
    /// What a perspective view from `eye` (outside the content ball of radius `content_m`) can
    /// select in `mode`: its cameras, and its selection triangles (continuous). Found without the
    /// cell grid, in one pass over the vertices (the view's cost on the CPU matters: with the grid, a
    /// 56,000-camera scan took 4–17 ms a frame). The configuration is symmetric about the line from
    /// the centre to the eye, so the lines through the content ball meet the sphere first inside a
    /// cap around that line's direction; its radius is the largest angle of the lines at the ball's
    /// rim, sampled (the angle grows with the line's tilt), plus 10⁻³ rad. A camera is selectable
    /// when its vertex lies within the cap's radius plus its ρ; a triangle when all three vertices
    /// are (a triangle meeting the cap has every vertex within its longest edge of the cap).
    /// `None` when the eye is inside the ball.
    pub fn selectable(
        &self,
        sel: &Selection,
        eye: Vec3,
        content_m: f64,
        mode: SelectionMode,
    ) -> Option<(Vec<u32>, Vec<u32>)> {
        let (centre, r_s) = self.sphere;
        let e = eye.as_dvec3() - centre;
        let dist = e.length();
        if dist <= content_m * 1.0001 {
            return None;
        }
        let axis = e / dist;
        let beta = (content_m / dist).min(1.0).asin();
        let (b1, _) = orthonormal(axis);
        let mut alpha: f64 = 0.0;
        for k in 0..=32 {
            let b = beta * f64::from(k) / 32.0;
            // A line from the eye towards the ball, tilted by b; its first point on the sphere.
            let d = -axis * b.cos() + b1 * b.sin();
            let bb = e.dot(d);
            let disc = bb * bb - (dist * dist - r_s * r_s);
            if disc < 0.0 {
                continue;
            }
            let q = e + d * (-bb - disc.sqrt());
            alpha = alpha.max(q.normalize().dot(axis).clamp(-1.0, 1.0).acos());
        }
        alpha += 1e-3;
        let m = mode.index() as usize;
        let dirs = sel.vertex_directions();
        // angle(u, axis) ≤ α + ρ as cos(angle) ≥ cos α cos ρ − sin α sin ρ (no arccosine per vertex).
        let (ca, sa) = (alpha.cos(), alpha.sin());
        let ok: Vec<bool> = dirs
            .iter()
            .zip(&self.vertex_rho)
            .map(|(u, rho)| {
                let (r, cr, sr) = rho[m];
                alpha + r >= std::f64::consts::PI || u.dot(axis) >= ca * cr - sa * sr
            })
            .collect();
        let mut cams: Vec<u32> = sel
            .vertex_camera()
            .iter()
            .zip(&ok)
            .filter(|(_, ok)| **ok)
            .map(|(c, _)| *c)
            .collect();
        cams.sort_unstable();
        cams.dedup();
        let tris = if mode == SelectionMode::Continuous {
            (0..sel.triangles().len() as u32)
                .filter(|&t| sel.triangles()[t as usize].iter().all(|&v| ok[v as usize]))
                .collect()
        } else {
            Vec::new()
        };
        Some((cams, tris))
    }

    /// The continuous-mode raster of a perspective view from `eye` (outside the content ball of radius
    /// `content_m`) for a `viewport` of pixels: the selection triangles whose regions the view's lines
    /// reach (`triangles`, from the selection's cell lists), each drawn where its lines can be lit.
    ///
    /// A pixel shows triangle T's blend when its line's first hit on the sphere lies in T. On the
    /// screen that region is T's three sphere points joined by the images of great-circle arcs, which
    /// bow off the straight edges by at most the arcs' sagitta; each triangle is grown by 1.5× that
    /// plus [`GROW_PX`], cut to the content ball's silhouette (an octagon around its cone: lines that miss the
    /// ball are discarded anyway) and to the hull of its cameras' cones D (a line outside all three
    /// is dark), and placed on the plane through the centre facing the eye. The shader keeps a
    /// fragment only where the line's first hit lies in its own triangle (a small tolerance: a hair of
    /// overlap with the neighbour, never a crack), so each pixel is shaded by about one triangle and
    /// needs no search. `None`: a point or direction involved is not in front of the eye; draw the
    /// hull polygon or the box.
    pub fn continuous_raster(
        &self,
        sel: &Selection,
        triangles: &[u32],
        clip_from_local: Mat4,
        eye: Vec3,
        content_m: f64,
        viewport: (u32, u32),
    ) -> Option<Vec<PolygonVertex>> {
        let view = self.view(clip_from_local, eye, content_m, viewport)?;
        let dirs = sel.vertex_directions();
        let cams = sel.vertex_camera();
        // Per item in parallel (a large scan's view holds thousands); any `None` gives up.
        let per: Option<Vec<Vec<PolygonVertex>>> = triangles
            .par_iter()
            .with_min_len(16)
            .map(|&t| -> Option<Vec<PolygonVertex>> {
                let mut out = Vec::new();
                let ti = t as usize;
                if sel.is_hole(ti) || sel.is_folded(ti) {
                    return Some(out);
                }
                let Some(tri) = sel.triangles().get(ti) else {
                    return Some(out);
                };
                // The hull of the cameras' cones (none lit: the whole triangle is dark).
                let mut corners = Vec::with_capacity(12);
                for &v in tri {
                    if let Some(Some(cone)) = cams.get(v as usize).and_then(|&c| self.cameras.get(c as usize)) {
                        for d in &cone.corners {
                            let p = view.direction(*d)?;
                            corners.push((p.x, p.y, ()));
                        }
                    }
                }
                let d_hull: Vec<Vec2> = convex_hull(corners)
                    .into_iter()
                    .map(|(x, y, ())| Vec2::new(x, y))
                    .collect();
                if d_hull.len() < 3 || disjoint(&d_hull, &view.ball) {
                    return Some(out);
                }
                // The triangle's sphere points, grown by its arcs' sagitta.
                let mut p = [Vec2::ZERO; 3];
                let mut grow = GROW_PX;
                for k in 0..3 {
                    let (a, b) = (dirs[tri[k] as usize], dirs[tri[(k + 1) % 3] as usize]);
                    p[k] = view.on_sphere(a)?;
                    grow = grow.max(GROW_PX + view.sagitta(a, b)? * 1.5);
                }
                let Some(grown) = grow_triangle(p, grow) else {
                    return Some(out);
                };
                view.emit(&clip_convex(&clip_convex(&grown, &view.ball), &d_hull), t, &mut out)?;
                Some(out)
            })
            .collect();
        Some(per?.concat())
    }
}

impl LitDirections {
    /// The nearest-mode raster of a perspective view from `eye` (outside the content ball of radius
    /// `content_m`) for a `viewport` of pixels: per selectable camera, the screen region of its
    /// Voronoi cell (the lines whose first sphere hit is nearest to it; the convex hull of its
    /// corners' images grown by the arcs' sagitta and [`GROW_PX`]; the cap of radius ρ where the cell is
    /// open), cut to the content ball's silhouette and to the camera's own cone D; each vertex names
    /// the camera. The shader runs the usual nearest selection and keeps a fragment only where it
    /// picks the polygon's camera, so each pixel is written once however the grown cells overlap.
    /// `None`: a point or direction involved is not in front of the eye.
    pub fn nearest_raster(
        &self,
        cameras: &[u32],
        clip_from_local: Mat4,
        eye: Vec3,
        content_m: f64,
        viewport: (u32, u32),
    ) -> Option<Vec<PolygonVertex>> {
        let view = self.view(clip_from_local, eye, content_m, viewport)?;
        // Per item in parallel (a large scan's view holds thousands); any `None` gives up.
        let per: Option<Vec<Vec<PolygonVertex>>> = cameras
            .par_iter()
            .with_min_len(16)
            .map(|&c| -> Option<Vec<PolygonVertex>> {
                let mut out = Vec::new();
                let Some(Some(cone)) = self.cameras.get(c as usize) else {
                    return Some(out);
                };
                let mut d = Vec::with_capacity(cone.corners.len());
                for q in &cone.corners {
                    d.push(view.direction(*q)?);
                }
                // A cone that misses the ball's silhouette: nothing to draw (most of a far view's cameras).
                if disjoint(&d, &view.ball) {
                    return Some(out);
                }
                // The cell's corners on the sphere: its Voronoi corners, or an octagon around the cap.
                let corners: Vec<DVec3> = match &cone.cell {
                    Some(cell) => cell.clone(),
                    None => {
                        let (b1, b2) = orthonormal(cone.vertex);
                        let tan_r = cone.rho[0].min(1.4).tan() / (std::f64::consts::PI / 8.0).cos();
                        (0..8)
                            .map(|k| {
                                let a = std::f64::consts::TAU * f64::from(k) / 8.0;
                                (cone.vertex + (b1 * a.cos() + b2 * a.sin()) * tan_r).normalize()
                            })
                            .collect()
                    }
                };
                let mut pts = Vec::with_capacity(corners.len());
                for q in &corners {
                    let p = view.on_sphere(*q)?;
                    pts.push((p.x, p.y, *q));
                }
                let hull = convex_hull(pts);
                if hull.len() < 3 {
                    return Some(out);
                }
                // Grow by the largest sagitta of an edge's arc, and the margin.
                let mut grow = GROW_PX;
                for i in 0..hull.len() {
                    let (a, b) = (hull[i].2, hull[(i + 1) % hull.len()].2);
                    grow = grow.max(GROW_PX + view.sagitta(a, b)? * 1.5);
                }
                let poly: Vec<Vec2> = hull.iter().map(|h| Vec2::new(h.0, h.1)).collect();
                let Some(grown) = grow_convex(&poly, grow) else {
                    return Some(out);
                };
                view.emit(&clip_convex(&clip_convex(&grown, &view.ball), &d), c, &mut out)?;
                Some(out)
            })
            .collect();
        Some(per?.concat())
    }
}

/// Whether the bounding boxes of two point sets are disjoint.
fn disjoint(a: &[Vec2], b: &[Vec2]) -> bool {
    let bbox = |p: &[Vec2]| {
        p.iter().fold(
            (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
            |(lo, hi), q| (lo.min(*q), hi.max(*q)),
        )
    };
    let ((alo, ahi), (blo, bhi)) = (bbox(a), bbox(b));
    ahi.x < blo.x || bhi.x < alo.x || ahi.y < blo.y || bhi.y < alo.y
}

/// One perspective view of the rasters: its screen, the content ball's silhouette, and the plane
/// through the capture centre facing the eye that the polygons are placed on.
struct View {
    screen: Screen,
    /// The silhouette: an octagon (pixels) around the ball's cone from the eye.
    ball: Vec<Vec2>,
    eye: DVec3,
    /// Unit, from the eye to the centre, and the distance.
    axis: DVec3,
    dist: f64,
    local_from_clip: Mat4,
    sphere: (DVec3, f64),
}

impl LitDirections {
    /// The view from `eye` outside the content ball (radius `content_m`); `None` inside it, or when
    /// the ball's cone is too wide to bound.
    fn view(&self, clip_from_local: Mat4, eye: Vec3, content_m: f64, viewport: (u32, u32)) -> Option<View> {
        let (centre, r_s) = self.sphere;
        let e = eye.as_dvec3();
        let to_c = centre - e;
        let dist = to_c.length();
        if dist <= content_m * 1.0001 {
            return None;
        }
        let screen = Screen {
            clip_from_local,
            half: Vec2::new(viewport.0 as f32, viewport.1 as f32) * 0.5,
            sign: if dist > r_s { 1.0 } else { -1.0 },
        };
        let axis = to_c / dist;
        let tan_b = (content_m / dist).min(1.0).asin().tan() / (std::f64::consts::PI / 8.0).cos();
        if tan_b > 5.0 {
            return None;
        }
        let (b1, b2) = orthonormal(axis);
        let mut ball = Vec::with_capacity(8);
        for k in 0..8 {
            let a = std::f64::consts::TAU * f64::from(k) / 8.0;
            let d = axis + (b1 * a.cos() + b2 * a.sin()) * tan_b;
            ball.push(screen.px(Vec4::new(d.x as f32, d.y as f32, d.z as f32, 0.0), 1.0)?);
        }
        Some(View {
            screen,
            ball,
            eye: e,
            axis,
            dist,
            local_from_clip: clip_from_local.inverse(),
            sphere: self.sphere,
        })
    }
}

impl View {
    /// Pixel of a direction (at infinity).
    fn direction(&self, d: Vec3) -> Option<Vec2> {
        self.screen.px(Vec4::new(d.x, d.y, d.z, 0.0), 1.0)
    }

    /// Pixel of the lines whose first point on the sphere is at unit direction `u` from its centre.
    fn on_sphere(&self, u: DVec3) -> Option<Vec2> {
        self.point(self.sphere.0 + u * self.sphere.1)
    }

    fn point(&self, q: DVec3) -> Option<Vec2> {
        self.screen
            .px(Vec4::new(q.x as f32, q.y as f32, q.z as f32, 1.0), self.screen.sign)
    }

    /// How far (pixels) the image of the great-circle arc between unit directions `a` and `b` bows
    /// off the straight segment, at its middle.
    fn sagitta(&self, a: DVec3, b: DVec3) -> Option<f32> {
        let (centre, r_s) = self.sphere;
        let arc = self.on_sphere((a + b).normalize())?;
        let chord = self.point(centre + (a + b) * (0.5 * r_s))?;
        Some((arc - chord).length())
    }

    /// Appends a convex polygon (pixels) as a fan of triangles on the plane through the centre
    /// facing the eye, every vertex naming `tri`. `None` when a vertex's line does not cross the
    /// plane in front of the eye.
    fn emit(&self, poly: &[Vec2], tri: u32, out: &mut Vec<PolygonVertex>) -> Option<()> {
        if poly.len() < 3 {
            return Some(());
        }
        let mut on_plane = Vec::with_capacity(poly.len());
        for v in poly {
            let ndc = *v / self.screen.half;
            let h = self.local_from_clip * Vec4::new(ndc.x, ndc.y, 0.5, 1.0);
            let d = (h.truncate() / h.w).as_dvec3() - self.eye;
            let dn = d.dot(self.axis);
            if dn.is_nan() || dn <= 1e-9 * d.length() {
                return None;
            }
            on_plane.push((self.eye + d * (self.dist / dn)).as_vec3().to_array());
        }
        for i in 1..on_plane.len() - 1 {
            for pos in [on_plane[0], on_plane[i], on_plane[i + 1]] {
                out.push(PolygonVertex { pos, tri });
            }
        }
        Some(())
    }
}

/// Twice the signed area of a polygon (positive counter-clockwise, y up).
fn twice_area(p: &[Vec2]) -> f32 {
    (0..p.len()).map(|i| p[i].perp_dot(p[(i + 1) % p.len()])).sum()
}

/// A convex polygon (pixels, either orientation) with each edge moved `d` pixels outwards; `None`
/// when degenerate.
fn grow_convex(p: &[Vec2], d: f32) -> Option<Vec<Vec2>> {
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
fn grow_triangle(p: [Vec2; 3], d: f32) -> Option<Vec<Vec2>> {
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
fn clip_convex(subject: &[Vec2], clip: &[Vec2]) -> Vec<Vec2> {
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
fn convex_hull<T: Copy>(mut p: Vec<(f32, f32, T)>) -> Vec<(f32, f32, T)> {
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
