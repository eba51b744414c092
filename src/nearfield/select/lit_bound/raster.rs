//! A view's rasters of the bounding polygon: per selection triangle in continuous mode
//! ([`LitDirections::continuous_raster`]) and per camera's Voronoi cell in nearest mode
//! ([`LitDirections::nearest_raster`]), each polygon cut to the content ball's silhouette and the
//! cameras' cones, and placed on the plane through the capture centre facing the eye.

use glam::{DVec3, Mat4, Vec2, Vec3, Vec4};
use rayon::prelude::*;

use super::polygon::{clip_convex, convex_hull, disjoint, grow_convex, grow_triangle};
use super::{LitDirections, PolygonVertex, GROW_PX};
use crate::nearfield::select::view::orthonormal;
use crate::nearfield::select::{Selection, SelectionMode};

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
                        let tan_r = cone.rho[SelectionMode::Nearest.index() as usize].min(1.4).tan()
                            / (std::f64::consts::PI / 8.0).cos();
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
