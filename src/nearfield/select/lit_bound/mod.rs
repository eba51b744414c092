//! A tight bounding polygon for the near-field pass without a proxy.
//!
//! Without a proxy, the fragment of view line (eye, v) finds Q, the line's first point on the capture
//! sphere, selects cameras around Q, and samples each selected camera j at the pixel `K_j · R_j · v`
//! (the view ray rotated into the camera; see shaders/nearfield/pass.wgsl). So the pixel can hold light only
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
//!
//! - this file: each camera's cone and reach ([`LitDirections::new`], with ρ per selection mode),
//!   the hull polygon ([`LitDirections::bound`]) and what a view can select
//!   ([`LitDirections::selectable`]);
//! - `raster.rs`: a view's rasters, one polygon per selection triangle (continuous,
//!   [`LitDirections::continuous_raster`]) or per camera's Voronoi cell (nearest,
//!   [`LitDirections::nearest_raster`]);
//! - `polygon.rs`: the plane geometry they use: convex hull, clipping, growing a polygon.

mod polygon;
mod raster;

use glam::{DVec2, DVec3, Mat4, Vec2, Vec3, Vec4};
use rayon::prelude::*;

use self::polygon::{clip_convex, convex_hull};
use super::view::orthonormal;
use super::{Reach, Selection, SelectionMode};
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
        let reach = |v: usize| Reach {
            circumradius: circ[v],
            max_gap,
            longest_edge: edge[v],
        };
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
                    rho: SelectionMode::ALL.map(|m| grow(m.reach(&reach(v)))),
                    cell: cells[v].clone().filter(|c| c.len() >= 3),
                }))
            })
            .collect::<Result<Vec<_>, NearfieldError>>()?;
        let vertex_rho = (0..dirs.len())
            .map(|v| {
                SelectionMode::ALL.map(|m| {
                    let r = m.reach(&reach(v));
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
        let tris = if mode.blends_triangles() {
            (0..sel.triangles().len() as u32)
                .filter(|&t| sel.triangles()[t as usize].iter().all(|&v| ok[v as usize]))
                .collect()
        } else {
            Vec::new()
        };
        Some((cams, tris))
    }
}
