//! Photometric luminaires as light sources of the reference path tracer: a point source at the
//! photometric centre, or the luminous opening as an area source.
//!
//! Promises:
//! - A luminaire is its [`Photometry`] (absolute candela) and the matrix from its luminaire frame
//!   (docs/conventions.md: nadir −Z, C0 +X, C90 +Y) to the scene; the matrix must be a rotation and
//!   a translation (no scale, no mirror), as [`super::place::placement`] makes.
//! - The intensity towards a scene direction is `Photometry::intensity` at the Type C angles
//!   (`photometry::web::angles_of`) of that direction turned into the luminaire frame.
//! - A luminaire whose opening has no area (`LuminousOpening::is_point`) is a point source: the
//!   illuminance at x with normal n is I(d)·max(0, n·(c − x)/r)/r² for d the direction from the
//!   centre c to x, r = |x − c|, and 0 where the segment is blocked.
//! - Otherwise it is an area source: N points are drawn on the opening, each carrying I(d_k)/N
//!   towards x, d_k the direction from that point to x, with its own distance, incidence and
//!   visibility. The far field is preserved (N points of I/N at one place are I), and penumbrae
//!   take the opening's size. The points are drawn as a uniform-luminance opening (L = I / A_proj,
//!   as the far-field pass shows it) emits towards x, seen from the direction of x from the centre:
//!   * flat shapes (rectangle, ellipse, the two vertical ellipses): uniform over the area;
//!   * boxes and EULUMDAT rectangles with sides: a face chosen with probability proportional to
//!     its projected area towards x (exactly the terms of `projected_area_dir`), uniform on it;
//!   * EULUMDAT discs with sides: the disc, or the side band uniform across its projected width
//!     and up to the height blended for that azimuth;
//!   * ellipsoids and cylinders: uniform over their silhouette (rejection in the projected
//!     bounding rectangle), each point on the surface facing x; after 64 misses (only edge-on
//!     degenerate solids) the centre is used.
//!
//!   N = m² points are stratified over an m × m grid of the flat and face parameterisations.
//! - Luminaires do not occlude anything, themselves included.

use std::sync::Arc;

use glam::{DMat3, DMat4, DVec3};

use super::bvh::Bvh;
use super::error::{Result, SceneError};
use super::sampling::{basis, Pcg32};
use crate::photometry::{LuminousOpening, OpeningShape, Photometry};

/// A photometric luminaire placed in a scene.
#[derive(Debug, Clone)]
pub struct SceneLuminaire {
    /// Its photometry (absolute candela).
    pub photometry: Arc<Photometry>,
    /// Luminaire frame → scene: a rotation and a translation ([`super::place::placement`]).
    pub scene_from_luminaire: DMat4,
}

impl SceneLuminaire {
    /// Checks that the model matrix is what the tracer can use: finite, affine, a rotation
    /// (columns orthonormal within 10⁻⁶, no scale or shear) that does not mirror, and a
    /// translation.
    ///
    /// Errors: why it is not, as text.
    pub fn check_placement(&self) -> std::result::Result<(), &'static str> {
        let m = self.scene_from_luminaire;
        if !m.is_finite() {
            return Err("the model matrix is not finite");
        }
        if m.row(3) != glam::DVec4::W {
            return Err("the model matrix is not affine (last row is not 0, 0, 0, 1)");
        }
        let r = DMat3::from_mat4(m);
        let gram = r.transpose() * r;
        let off = (gram - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |a, x| a.max(x.abs()));
        if off > 1e-6 {
            return Err("the model matrix scales or shears; it must be a rotation and a translation");
        }
        if r.determinant() < 0.0 {
            return Err("the model matrix mirrors; it must be a rotation and a translation");
        }
        Ok(())
    }
}

/// A flat emitting piece: centre + s·a + t·b for (s, t) in the unit square [−1, 1]² (a
/// parallelogram) or the unit disc (an ellipse), in the luminaire frame.
#[derive(Debug, Clone, Copy)]
struct Flat {
    centre: DVec3,
    a: DVec3,
    b: DVec3,
    ellipse: bool,
}

impl Flat {
    fn rect(centre: DVec3, a: DVec3, b: DVec3) -> Self {
        Flat {
            centre,
            a,
            b,
            ellipse: false,
        }
    }

    /// The point of the uniform numbers (u, v) in [0, 1)²: area-preserving, so a stratified (u, v)
    /// gives stratified points (Shirley–Chiu's concentric map for the disc).
    fn at(&self, u: f64, v: f64) -> DVec3 {
        let (s, t) = (2.0 * u - 1.0, 2.0 * v - 1.0);
        let (s, t) = if self.ellipse { concentric(s, t) } else { (s, t) };
        self.centre + s * self.a + t * self.b
    }
}

/// Shirley–Chiu concentric map from the square [−1, 1]² to the unit disc.
fn concentric(s: f64, t: f64) -> (f64, f64) {
    if s == 0.0 && t == 0.0 {
        return (0.0, 0.0);
    }
    let q = std::f64::consts::FRAC_PI_4;
    let (r, phi) = if s.abs() > t.abs() {
        (s, q * (t / s))
    } else {
        (t, 2.0 * q - q * (s / t))
    };
    (r * phi.cos(), r * phi.sin())
}

/// How points are drawn on an opening (luminaire frame).
#[derive(Debug, Clone)]
enum OpeningSampler {
    Point,
    Flat(Flat),
    /// Faces of a box or an EULUMDAT rectangle with sides.
    Faces(Vec<Face>),
    /// EULUMDAT disc with sides (diameter, side heights C0, C90, C180, C270).
    DiscWithSides {
        diameter_m: f64,
        side_heights_m: [f64; 4],
    },
    /// A convex solid centred on the origin: |p_k| ≤ half_k on the slab axes, Σ (p_k/half_k)² ≤ 1
    /// over the quadric axes.
    Solid {
        half: DVec3,
        quadric: [bool; 3],
    },
}

/// One face: its shape, and its outward normal when it is seen from one side only (`None`: a flat
/// opening's own surface, seen from both).
#[derive(Debug, Clone, Copy)]
struct Face {
    flat: Flat,
    normal: Option<DVec3>,
    area_m2: f64,
}

impl Face {
    fn weight(&self, d: DVec3) -> f64 {
        match self.normal {
            Some(n) => self.area_m2 * n.dot(d).max(0.0),
            None => {
                let n = self.flat.a.cross(self.flat.b).normalize_or_zero();
                self.area_m2 * n.dot(d).abs()
            }
        }
    }
}

impl OpeningSampler {
    fn of(o: &LuminousOpening) -> Self {
        if o.is_point() {
            return OpeningSampler::Point;
        }
        let (l, w, h) = (o.size_x_m, o.size_y_m, o.height_m);
        let (hx, hy, hz) = (DVec3::X * l / 2.0, DVec3::Y * w / 2.0, DVec3::Z * h / 2.0);
        let flat = |a: DVec3, b: DVec3, ellipse: bool| {
            OpeningSampler::Flat(Flat {
                centre: DVec3::ZERO,
                a,
                b,
                ellipse,
            })
        };
        use OpeningShape as S;
        match o.shape {
            S::Point => OpeningSampler::Point,
            S::Rectangle => flat(hx, hy, false),
            S::Ellipse => flat(hx, hy, true),
            S::VerticalEllipseFacingC0 => flat(hy, hz, true),
            S::VerticalEllipseFacingC90 => flat(hx, hz, true),
            S::Box => {
                let mut faces = Vec::new();
                for (axis, (p, q)) in [(hx, (hy, hz)), (hy, (hx, hz)), (hz, (hx, hy))] {
                    let area = 4.0 * p.cross(q).length();
                    for sign in [1.0, -1.0] {
                        faces.push(Face {
                            flat: Flat::rect(sign * axis, p, q),
                            normal: Some(sign * axis.normalize_or_zero()),
                            area_m2: area,
                        });
                    }
                }
                OpeningSampler::Faces(faces)
            }
            S::RectangleWithSides => {
                let [h0, h90, h180, h270] = o.side_heights_m;
                let mut faces = vec![Face {
                    flat: Flat::rect(DVec3::ZERO, hx, hy),
                    normal: None,
                    area_m2: l * w,
                }];
                // A side of height hs at ±X (spanning Y) or ±Y (spanning X), from z = 0 up.
                for (centre_dir, span, hs, span_len) in [
                    (DVec3::X, hy, h0, w),
                    (DVec3::Y, hx, h90, l),
                    (DVec3::NEG_X, hy, h180, w),
                    (DVec3::NEG_Y, hx, h270, l),
                ] {
                    if hs > 0.0 {
                        let off = if centre_dir.x != 0.0 { l / 2.0 } else { w / 2.0 };
                        faces.push(Face {
                            flat: Flat::rect(centre_dir * off + DVec3::Z * hs / 2.0, span, DVec3::Z * hs / 2.0),
                            normal: Some(centre_dir),
                            area_m2: span_len * hs,
                        });
                    }
                }
                OpeningSampler::Faces(faces)
            }
            S::DiscWithSides => OpeningSampler::DiscWithSides {
                diameter_m: l,
                side_heights_m: o.side_heights_m,
            },
            S::VerticalCylinder => OpeningSampler::Solid {
                half: DVec3::new(l, w, h) / 2.0,
                quadric: [true, true, false],
            },
            S::Ellipsoid => OpeningSampler::Solid {
                half: DVec3::new(l, w, h) / 2.0,
                quadric: [true, true, true],
            },
            S::HorizontalCylinderAlongLength => OpeningSampler::Solid {
                half: DVec3::new(l, w, h) / 2.0,
                quadric: [false, true, true],
            },
            S::HorizontalCylinderAlongWidth => OpeningSampler::Solid {
                half: DVec3::new(l, w, h) / 2.0,
                quadric: [true, false, true],
            },
        }
    }

    /// A point on the opening (luminaire frame) for light towards the unit direction `d` (from the
    /// centre towards the receiver), from the stratified pair (u, v) and the generator.
    fn sample(&self, d: DVec3, u: f64, v: f64, rng: &mut Pcg32) -> DVec3 {
        match self {
            OpeningSampler::Point => DVec3::ZERO,
            OpeningSampler::Flat(f) => f.at(u, v),
            OpeningSampler::Faces(faces) => {
                let total: f64 = faces.iter().map(|f| f.weight(d)).sum();
                if total.is_nan() || total <= 0.0 {
                    return DVec3::ZERO;
                }
                let mut pick = rng.next_f64() * total;
                for f in faces {
                    let wgt = f.weight(d);
                    if pick < wgt {
                        return f.flat.at(u, v);
                    }
                    pick -= wgt;
                }
                faces
                    .iter()
                    .rev()
                    .find(|f| f.weight(d) > 0.0)
                    .map_or(DVec3::ZERO, |f| f.flat.at(u, v))
            }
            OpeningSampler::DiscWithSides {
                diameter_m,
                side_heights_m,
            } => {
                let r = diameter_m / 2.0;
                let s = d.truncate().length(); // sin γ
                let disc = std::f64::consts::FRAC_PI_4 * diameter_m * diameter_m * d.z.abs();
                let (h_eff, c) = if s > 0.0 {
                    let (cx, cy) = (d.x / s, d.y / s);
                    let wts = [cx.max(0.0), cy.max(0.0), (-cx).max(0.0), (-cy).max(0.0)];
                    let sum: f64 = wts.iter().sum();
                    let h: f64 = wts.iter().zip(side_heights_m).map(|(a, b)| a * b).sum::<f64>() / sum;
                    (h, d.y.atan2(d.x))
                } else {
                    (0.0, 0.0)
                };
                let side = diameter_m * h_eff * s;
                if rng.next_f64() * (disc + side) < disc || side <= 0.0 {
                    let (x, y) = concentric(2.0 * u - 1.0, 2.0 * v - 1.0);
                    DVec3::new(r * x, r * y, 0.0)
                } else {
                    // Uniform across the projected width: φ = C + asin(w), w uniform in [−1, 1].
                    let phi = c + (2.0 * u - 1.0).clamp(-1.0, 1.0).asin();
                    DVec3::new(r * phi.cos(), r * phi.sin(), v * h_eff)
                }
            }
            OpeningSampler::Solid { half, quadric } => sample_silhouette(*half, *quadric, d, rng),
        }
    }
}

/// A uniform point of the convex solid's silhouette seen along `d`, on the surface facing `d`.
fn sample_silhouette(half: DVec3, quadric: [bool; 3], d: DVec3, rng: &mut Pcg32) -> DVec3 {
    let (e1, e2) = basis(d);
    let ext1 = (half * e1.abs()).element_sum();
    let ext2 = (half * e2.abs()).element_sum();
    for _ in 0..64 {
        let o = e1 * ext1 * (2.0 * rng.next_f64() - 1.0) + e2 * ext2 * (2.0 * rng.next_f64() - 1.0);
        let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
        let (mut qa, mut qb, mut qc) = (0.0, 0.0, -1.0);
        for k in 0..3 {
            if quadric[k] {
                if half[k] <= 0.0 {
                    t1 = f64::NEG_INFINITY; // a flat quadric: no volume to hit
                    continue;
                }
                let h2 = half[k] * half[k];
                qa += d[k] * d[k] / h2;
                qb += 2.0 * o[k] * d[k] / h2;
                qc += o[k] * o[k] / h2;
            } else if d[k] != 0.0 {
                let (a, b) = ((-half[k] - o[k]) / d[k], (half[k] - o[k]) / d[k]);
                t0 = t0.max(a.min(b));
                t1 = t1.min(a.max(b));
            } else if o[k].abs() > half[k] {
                t1 = f64::NEG_INFINITY;
            }
        }
        if qa > 0.0 {
            let disc = qb * qb - 4.0 * qa * qc;
            if disc < 0.0 {
                continue;
            }
            let sq = disc.sqrt();
            t0 = t0.max((-qb - sq) / (2.0 * qa));
            t1 = t1.min((-qb + sq) / (2.0 * qa));
        } else if qc > 0.0 {
            continue;
        }
        if t0 <= t1 && t1.is_finite() {
            return o + t1 * d;
        }
    }
    DVec3::ZERO
}

/// A luminaire prepared for tracing.
#[derive(Debug, Clone)]
pub(crate) struct Emitter {
    photometry: Arc<Photometry>,
    scene_from_luminaire: DMat4,
    luminaire_from_scene: DMat3,
    centre: DVec3,
    sampler: OpeningSampler,
}

impl Emitter {
    /// Checks and prepares the luminaires. Errors (argument `luminaires[i]`): a matrix that is not
    /// finite, not a rotation (columns orthonormal within 10⁻⁶) and translation, or mirrors.
    pub(crate) fn prepare(luminaires: &[SceneLuminaire]) -> Result<Vec<Emitter>> {
        luminaires
            .iter()
            .enumerate()
            .map(|(i, l)| {
                l.check_placement()
                    .map_err(|why| SceneError::invalid(format!("luminaires[{i}]"), why))?;
                let m = l.scene_from_luminaire;
                let r = DMat3::from_mat4(m);
                Ok(Emitter {
                    photometry: l.photometry.clone(),
                    scene_from_luminaire: m,
                    luminaire_from_scene: r.transpose(),
                    centre: m.w_axis.truncate(),
                    sampler: OpeningSampler::of(&l.photometry.opening),
                })
            })
            .collect()
    }

    /// Whether the luminaire is a point source.
    pub(crate) fn is_point(&self) -> bool {
        matches!(self.sampler, OpeningSampler::Point)
    }

    /// Intensity in cd towards the scene direction `d` (any length).
    pub(crate) fn intensity_towards(&self, d: DVec3) -> f64 {
        let l = self.luminaire_from_scene * d;
        self.photometry.web.sample_dir([l.x, l.y, l.z])
    }

    /// Intensity in cd towards the luminaire-frame unit direction `d`.
    pub(crate) fn intensity_local(&self, d: DVec3) -> f64 {
        self.photometry.web.sample_dir([d.x, d.y, d.z])
    }

    /// Where a photon leaving in the luminaire-frame unit direction `d` starts (a point of the
    /// opening drawn as for direct light) and its direction, both in scene coordinates.
    pub(crate) fn emit(&self, d: DVec3, rng: &mut Pcg32) -> (DVec3, DVec3) {
        let p = if self.is_point() {
            DVec3::ZERO
        } else {
            let (u, v) = (rng.next_f64(), rng.next_f64());
            self.sampler.sample(d, u, v, rng)
        };
        (
            self.scene_from_luminaire.transform_point3(p),
            self.scene_from_luminaire.transform_vector3(d).normalize_or_zero(),
        )
    }

    /// One estimate of the direct illuminance (lx) at `x` with unit normal `n`, from `samples`
    /// points on the opening (rounded up to a square; 1 for a point source). `offset_m` moves
    /// shadow rays off the surface at x.
    pub(crate) fn direct_lx(
        &self,
        bvh: &Bvh,
        x: DVec3,
        n: DVec3,
        samples: usize,
        offset_m: f64,
        rng: &mut Pcg32,
    ) -> f64 {
        if self.is_point() {
            return self.light_from_point(bvh, x, n, self.centre, offset_m);
        }
        let to_x = self.luminaire_from_scene * (x - self.centre);
        let d = to_x.normalize_or_zero();
        if d == DVec3::ZERO {
            return 0.0;
        }
        let m = (samples.max(1) as f64).sqrt().ceil() as usize;
        let mut sum = 0.0;
        for i in 0..m {
            for j in 0..m {
                let u = (i as f64 + rng.next_f64()) / m as f64;
                let v = (j as f64 + rng.next_f64()) / m as f64;
                let p = self.sampler.sample(d, u, v, rng);
                let s = self.scene_from_luminaire.transform_point3(p);
                sum += self.light_from_point(bvh, x, n, s, offset_m);
            }
        }
        sum / (m * m) as f64
    }

    /// I(s → x) · cos i / r², 0 when blocked: the light from a point `s` of the luminaire.
    fn light_from_point(&self, bvh: &Bvh, x: DVec3, n: DVec3, s: DVec3, offset_m: f64) -> f64 {
        let v = s - x;
        let r2 = v.length_squared();
        if r2.is_nan() || r2 <= 0.0 {
            return 0.0;
        }
        let r = r2.sqrt();
        let cos_i = n.dot(v) / r;
        if cos_i <= 0.0 {
            return 0.0;
        }
        let cd = self.intensity_towards(-v);
        if cd.is_nan() || cd <= 0.0 {
            return 0.0;
        }
        let o = x + n * offset_m;
        let w = s - o;
        let dist = w.length();
        if dist > offset_m && bvh.occluded(o, w / dist, dist - offset_m) {
            return 0.0;
        }
        cd * cos_i / r2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn centroid_and_spread(s: &OpeningSampler, d: DVec3, n: usize) -> (DVec3, DVec3, DVec3) {
        let mut rng = Pcg32::new(3, 4);
        let m = (n as f64).sqrt() as usize;
        let (mut sum, mut lo, mut hi) = (DVec3::ZERO, DVec3::INFINITY, DVec3::NEG_INFINITY);
        for i in 0..m {
            for j in 0..m {
                let p = s.sample(d, (i as f64 + 0.5) / m as f64, (j as f64 + 0.5) / m as f64, &mut rng);
                sum += p;
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        (sum / (m * m) as f64, lo, hi)
    }

    #[test]
    fn flat_openings_fill_their_extents() {
        let rect = OpeningSampler::of(&LuminousOpening::new(OpeningShape::Rectangle, 1.2, 0.1, 0.0));
        let (c, lo, hi) = centroid_and_spread(&rect, DVec3::NEG_Z, 400);
        assert!(c.length() < 1e-12);
        assert!((hi.x - 0.57).abs() < 1e-9 && (lo.x + 0.57).abs() < 1e-9, "{lo} {hi}");
        assert!((hi.y - 0.0475).abs() < 1e-9 && lo.z == 0.0 && hi.z == 0.0);
        let disc = OpeningSampler::of(&LuminousOpening::new(OpeningShape::Ellipse, 0.4, 0.4, 0.0));
        let (_, lo, hi) = centroid_and_spread(&disc, DVec3::NEG_Z, 400);
        assert!(hi.x < 0.2 && hi.x > 0.18 && lo.y > -0.2);
        let c0 = OpeningSampler::of(&LuminousOpening::new(
            OpeningShape::VerticalEllipseFacingC0,
            0.0,
            0.3,
            0.2,
        ));
        let (_, lo, hi) = centroid_and_spread(&c0, DVec3::X, 400);
        assert!(lo.x == 0.0 && hi.x == 0.0 && hi.z > 0.09 && hi.y > 0.14);
        assert!(matches!(
            OpeningSampler::of(&LuminousOpening::point()),
            OpeningSampler::Point
        ));
    }

    #[test]
    fn box_faces_follow_their_projected_areas() {
        // A 1 × 1 × 1 box seen from (1, 0, -1)/√2: the −Z face and the +X face, half each.
        let b = OpeningSampler::of(&LuminousOpening::new(OpeningShape::Box, 1.0, 1.0, 1.0));
        let d = DVec3::new(1.0, 0.0, -1.0).normalize();
        let mut rng = Pcg32::new(9, 9);
        let (mut bottom, mut side) = (0, 0);
        for _ in 0..4000 {
            let p = b.sample(d, rng.next_f64(), rng.next_f64(), &mut rng);
            if (p.z + 0.5).abs() < 1e-12 {
                bottom += 1;
            } else if (p.x - 0.5).abs() < 1e-12 {
                side += 1;
            } else {
                panic!("{p} is on a face not seen from {d}");
            }
        }
        assert!((bottom as f64 / 4000.0 - 0.5).abs() < 0.03, "{bottom} {side}");
    }

    #[test]
    fn solids_are_sampled_on_their_facing_surface() {
        let e = OpeningSampler::of(&LuminousOpening::new(OpeningShape::Ellipsoid, 0.4, 0.2, 0.2));
        let mut rng = Pcg32::new(1, 1);
        for d in [DVec3::NEG_Z, DVec3::X, DVec3::new(0.3, -0.5, -0.8).normalize()] {
            for _ in 0..200 {
                let p = e.sample(d, 0.5, 0.5, &mut rng);
                let q = (p.x / 0.2).powi(2) + (p.y / 0.1).powi(2) + (p.z / 0.1).powi(2);
                assert!((q - 1.0).abs() < 1e-9, "on the surface: {q}");
                // Facing d: the outward normal has a non-negative component along d.
                let n = DVec3::new(p.x / 0.04, p.y / 0.01, p.z / 0.01);
                assert!(n.dot(d) >= -1e-9);
            }
        }
        // A long thin cylinder end-on: all points on the end cap facing d.
        let c = OpeningSampler::of(&LuminousOpening::new(
            OpeningShape::HorizontalCylinderAlongLength,
            1.2,
            0.05,
            0.05,
        ));
        for _ in 0..100 {
            let p = c.sample(DVec3::X, 0.5, 0.5, &mut rng);
            assert!((p.x - 0.6).abs() < 1e-12 && p.y.hypot(p.z) <= 0.025 + 1e-12, "{p}");
        }
    }

    #[test]
    fn model_matrices_must_be_rigid() {
        let ies = "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 3 1 1 2 0 0 0\n1 1 10\n0 45 90\n0\n100 100 100\n";
        let p = Arc::new(crate::photometry::load_from_text(ies, "t.ies", &Default::default()).unwrap());
        let lum = |m: DMat4| SceneLuminaire {
            photometry: p.clone(),
            scene_from_luminaire: m,
        };
        assert!(Emitter::prepare(&[lum(crate::scene::place::placement(1.0, 2.0, 3.0, 30.0))]).is_ok());
        for (m, why) in [
            (DMat4::from_scale(DVec3::splat(2.0)), "scales"),
            (DMat4::from_scale(DVec3::new(1.0, 1.0, -1.0)), "mirrors"),
            (DMat4::from_cols_array(&[f64::NAN; 16]), "not finite"),
        ] {
            let e = Emitter::prepare(&[lum(DMat4::IDENTITY), lum(m)])
                .unwrap_err()
                .to_string();
            assert!(e.contains("luminaires[1]") && e.contains(why), "{e}");
        }
    }
}
