//! CPU geometry for the far-field pass, in the luminaire frame (metres): the luminous opening as
//! triangles (its shape and size from the file, centred on the photometric centre), the
//! photometric-solid wireframe and the housing box as line lists.

use std::f32::consts::TAU;

use crate::photometry::web::direction;
use crate::photometry::{LuminousOpening, OpeningShape, PhotometricWeb};

/// Segments around round shapes.
const SEGMENTS: usize = 96;

/// A triangle list (positions only).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Triangles {
    /// Vertex positions, three per triangle.
    pub positions: Vec<[f32; 3]>,
}

impl Triangles {
    fn tri(&mut self, a: [f32; 3], b: [f32; 3], c: [f32; 3]) {
        self.positions.extend_from_slice(&[a, b, c]);
    }
    fn quad(&mut self, a: [f32; 3], b: [f32; 3], c: [f32; 3], d: [f32; 3]) {
        self.tri(a, b, c);
        self.tri(a, c, d);
    }
}

/// Ellipse point at angle `t` with semi-axes (a, b) in the plane spanned by two axes.
fn ell(a: f32, b: f32, t: f32) -> (f32, f32) {
    (a * t.cos(), b * t.sin())
}

/// Triangles of a luminous opening; empty for a point opening. Flat shapes are single-sided
/// geometry drawn without culling (they emit to both sides, as A_proj counts them).
pub fn opening_triangles(o: &LuminousOpening) -> Triangles {
    let (l, w, h) = (o.size_x_m as f32, o.size_y_m as f32, o.height_m as f32);
    let (hl, hw, hh) = (l / 2.0, w / 2.0, h / 2.0);
    let mut t = Triangles::default();
    let n = SEGMENTS;
    let angle = |i: usize| TAU * i as f32 / n as f32;
    match o.shape {
        OpeningShape::Point => {}
        OpeningShape::Rectangle => {
            t.quad([-hl, -hw, 0.0], [hl, -hw, 0.0], [hl, hw, 0.0], [-hl, hw, 0.0]);
        }
        OpeningShape::Box => box_faces(&mut t, [-hl, -hw, -hh], [hl, hw, hh]),
        OpeningShape::Ellipse => {
            for i in 0..n {
                let (x0, y0) = ell(hl, hw, angle(i));
                let (x1, y1) = ell(hl, hw, angle(i + 1));
                t.tri([0.0, 0.0, 0.0], [x0, y0, 0.0], [x1, y1, 0.0]);
            }
        }
        OpeningShape::VerticalCylinder => {
            for i in 0..n {
                let (x0, y0) = ell(hl, hw, angle(i));
                let (x1, y1) = ell(hl, hw, angle(i + 1));
                t.quad([x0, y0, -hh], [x1, y1, -hh], [x1, y1, hh], [x0, y0, hh]);
                t.tri([0.0, 0.0, -hh], [x0, y0, -hh], [x1, y1, -hh]);
                t.tri([0.0, 0.0, hh], [x1, y1, hh], [x0, y0, hh]);
            }
        }
        OpeningShape::HorizontalCylinderAlongLength => {
            for i in 0..n {
                let (y0, z0) = ell(hw, hh, angle(i));
                let (y1, z1) = ell(hw, hh, angle(i + 1));
                t.quad([-hl, y0, z0], [-hl, y1, z1], [hl, y1, z1], [hl, y0, z0]);
                t.tri([-hl, 0.0, 0.0], [-hl, y1, z1], [-hl, y0, z0]);
                t.tri([hl, 0.0, 0.0], [hl, y0, z0], [hl, y1, z1]);
            }
        }
        OpeningShape::HorizontalCylinderAlongWidth => {
            for i in 0..n {
                let (x0, z0) = ell(hl, hh, angle(i));
                let (x1, z1) = ell(hl, hh, angle(i + 1));
                t.quad([x0, -hw, z0], [x1, -hw, z1], [x1, hw, z1], [x0, hw, z0]);
                t.tri([0.0, -hw, 0.0], [x0, -hw, z0], [x1, -hw, z1]);
                t.tri([0.0, hw, 0.0], [x1, hw, z1], [x0, hw, z0]);
            }
        }
        OpeningShape::VerticalEllipseFacingC0 => {
            for i in 0..n {
                let (y0, z0) = ell(hw, hh, angle(i));
                let (y1, z1) = ell(hw, hh, angle(i + 1));
                t.tri([0.0, 0.0, 0.0], [0.0, y0, z0], [0.0, y1, z1]);
            }
        }
        OpeningShape::VerticalEllipseFacingC90 => {
            for i in 0..n {
                let (x0, z0) = ell(hl, hh, angle(i));
                let (x1, z1) = ell(hl, hh, angle(i + 1));
                t.tri([0.0, 0.0, 0.0], [x0, 0.0, z0], [x1, 0.0, z1]);
            }
        }
        OpeningShape::Ellipsoid => {
            let rings = n / 2;
            let p = |i: usize, j: usize| {
                let th = std::f32::consts::PI * j as f32 / rings as f32;
                let ph = angle(i);
                [hl * th.sin() * ph.cos(), hw * th.sin() * ph.sin(), -hh * th.cos()]
            };
            for j in 0..rings {
                for i in 0..n {
                    t.quad(p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
                }
            }
        }
        OpeningShape::RectangleWithSides => {
            // Bottom face at z = 0; each side wall rises to its own height (C0 at +X, C90 at +Y, ...).
            let [h0, h90, h180, h270] = o.side_heights_m.map(|v| v as f32);
            t.quad([-hl, -hw, 0.0], [hl, -hw, 0.0], [hl, hw, 0.0], [-hl, hw, 0.0]);
            if h0 > 0.0 {
                t.quad([hl, -hw, 0.0], [hl, hw, 0.0], [hl, hw, h0], [hl, -hw, h0]);
            }
            if h180 > 0.0 {
                t.quad([-hl, hw, 0.0], [-hl, -hw, 0.0], [-hl, -hw, h180], [-hl, hw, h180]);
            }
            if h90 > 0.0 {
                t.quad([hl, hw, 0.0], [-hl, hw, 0.0], [-hl, hw, h90], [hl, hw, h90]);
            }
            if h270 > 0.0 {
                t.quad([-hl, -hw, 0.0], [hl, -hw, 0.0], [hl, -hw, h270], [-hl, -hw, h270]);
            }
        }
        OpeningShape::DiscWithSides => {
            let hs = o.side_heights_m.map(|v| v as f32);
            // Wall height blends the four side heights by how squarely each quarter faces the segment,
            // the same weighting as the projected-area formula.
            let wall = |t: f32| {
                let (cx, cy) = (t.cos(), t.sin());
                let wts = [cx.max(0.0), cy.max(0.0), (-cx).max(0.0), (-cy).max(0.0)];
                let s: f32 = wts.iter().sum();
                wts.iter().zip(hs).map(|(a, b)| a * b).sum::<f32>() / s
            };
            for i in 0..n {
                let (x0, y0) = ell(hl, hl, angle(i));
                let (x1, y1) = ell(hl, hl, angle(i + 1));
                t.tri([0.0, 0.0, 0.0], [x0, y0, 0.0], [x1, y1, 0.0]);
                let (z0, z1) = (wall(angle(i)), wall(angle(i + 1)));
                if z0 > 0.0 || z1 > 0.0 {
                    t.quad([x0, y0, 0.0], [x1, y1, 0.0], [x1, y1, z1], [x0, y0, z0]);
                }
            }
        }
    }
    t
}

fn box_faces(t: &mut Triangles, lo: [f32; 3], hi: [f32; 3]) {
    let c = |x: usize, y: usize, z: usize| {
        [
            if x == 0 { lo[0] } else { hi[0] },
            if y == 0 { lo[1] } else { hi[1] },
            if z == 0 { lo[2] } else { hi[2] },
        ]
    };
    t.quad(c(0, 0, 0), c(1, 0, 0), c(1, 1, 0), c(0, 1, 0));
    t.quad(c(0, 0, 1), c(0, 1, 1), c(1, 1, 1), c(1, 0, 1));
    t.quad(c(0, 0, 0), c(0, 0, 1), c(1, 0, 1), c(1, 0, 0));
    t.quad(c(0, 1, 0), c(1, 1, 0), c(1, 1, 1), c(0, 1, 1));
    t.quad(c(0, 0, 0), c(0, 1, 0), c(0, 1, 1), c(0, 0, 1));
    t.quad(c(1, 0, 0), c(1, 0, 1), c(1, 1, 1), c(1, 1, 0));
}

/// Line list (pairs of positions) of the housing box `size_m` = (extents along X, Y and Z;
/// `Photometry::luminaire_size_m`), hanging from the photometric centre's plane: z from 0 up to the height (the
/// luminous opening is at the bottom of the housing).
pub fn housing_lines(size_m: [f64; 3]) -> Vec<[f32; 3]> {
    let (hl, hw, h) = ((size_m[0] / 2.0) as f32, (size_m[1] / 2.0) as f32, size_m[2] as f32);
    let p = |x: usize, y: usize, z: usize| {
        [
            if x == 0 { -hl } else { hl },
            if y == 0 { -hw } else { hw },
            if z == 0 { 0.0 } else { h },
        ]
    };
    let mut out = Vec::with_capacity(24);
    for z in 0..2 {
        out.extend_from_slice(&[
            p(0, 0, z),
            p(1, 0, z),
            p(1, 0, z),
            p(1, 1, z),
            p(1, 1, z),
            p(0, 1, z),
            p(0, 1, z),
            p(0, 0, z),
        ]);
    }
    for (x, y) in [(0, 0), (1, 0), (1, 1), (0, 1)] {
        out.extend_from_slice(&[p(x, y, 0), p(x, y, 1)]);
    }
    out
}

/// Line list of the photometric-solid wireframe (r ∝ I, the largest intensity at `radius_m`):
/// meridians every 15° of C and rings every 10° of γ, each polyline sampled every 2.5°.
pub fn solid_lines(web: &PhotometricWeb, radius_m: f64) -> Vec<[f32; 3]> {
    let (max_cd, _, _) = web.max_intensity();
    if max_cd.is_nan() || max_cd <= 0.0 || radius_m.is_nan() || radius_m <= 0.0 {
        return Vec::new();
    }
    let point = |c: f64, g: f64| {
        let r = radius_m * web.sample(c, g) / max_cd;
        let d = direction(c, g);
        [(r * d[0]) as f32, (r * d[1]) as f32, (r * d[2]) as f32]
    };
    let mut out = Vec::new();
    for k in 0..24 {
        let c = 15.0 * k as f64;
        for j in 0..72 {
            out.push(point(c, 2.5 * j as f64));
            out.push(point(c, 2.5 * (j + 1) as f64));
        }
    }
    for k in 1..18 {
        let g = 10.0 * k as f64;
        for i in 0..144 {
            out.push(point(2.5 * i as f64, g));
            out.push(point(2.5 * (i + 1) as f64, g));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(t: &Triangles, d: [f32; 3]) -> f32 {
        // Projected area of a closed or flat mesh seen along d: half the sum of |n·d| (closed) or the
        // sum (flat); here the shapes used are flat so the sum is the projected area.
        t.positions
            .chunks_exact(3)
            .map(|p| {
                let u = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
                let v = [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]];
                let n = [
                    u[1] * v[2] - u[2] * v[1],
                    u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0],
                ];
                0.5 * (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]).abs()
            })
            .sum()
    }

    #[test]
    fn flat_shapes_have_the_declared_area() {
        let r = opening_triangles(&LuminousOpening::new(OpeningShape::Rectangle, 0.6, 0.2, 0.0));
        assert!((area(&r, [0.0, 0.0, 1.0]) - 0.12).abs() < 1e-6);
        let e = opening_triangles(&LuminousOpening::new(OpeningShape::Ellipse, 0.3, 0.3, 0.0));
        let exact = std::f32::consts::PI * 0.15 * 0.15;
        assert!((area(&e, [0.0, 0.0, 1.0]) / exact - 1.0).abs() < 1e-3);
        assert!(opening_triangles(&LuminousOpening::point()).positions.is_empty());
    }

    #[test]
    fn closed_shapes_project_twice_their_silhouette() {
        let b = opening_triangles(&LuminousOpening::new(OpeningShape::Box, 0.4, 0.2, 0.1));
        assert!((area(&b, [1.0, 0.0, 0.0]) / 2.0 - 0.02).abs() < 1e-6);
        assert_eq!(housing_lines([1.0, 0.5, 0.1]).len(), 24);
    }
}
