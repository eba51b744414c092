//! A specular paraboloid reflector around a small Lambertian sphere at its focus: the one luminaire
//! whose intensity and flux have no closed form. Rays are traced exactly (specular reflection, up to
//! a fixed number of bounces); intensity is the orthographic integral Σ L·ΔA at a fine pixel, flux a
//! forward quasi-Monte-Carlo integral over the source's emission (docs/synthetic.md gives accuracies).

use std::f64::consts::PI;
use std::sync::OnceLock;

use glam::DVec3;
use rayon::prelude::*;

use super::proxy::ProxyMesh;
use super::raycast::ortho_intensity;
use super::{unit, Aabb, Luminaire};

/// Where a traced ray ends.
#[derive(Debug, Clone, Copy, PartialEq)]
enum End {
    /// It met the source sphere after `bounces` reflections, carrying weight ρ^bounces.
    Source(f64, u32),
    /// It left the reflector (through the aperture, or it never entered), carrying ρ^bounces.
    Escaped(f64),
    /// It met the black outside of the shell, carrying ρ^bounces.
    Housing(f64),
    /// Still inside after the bounce limit, with its weight.
    Trapped(f64),
}

/// Where the flux of the source goes, from forward tracing (lm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FluxBudget {
    /// Flux emitted by the source sphere: π·L·4πr² (exact).
    pub source_lm: f64,
    /// Flux leaving the luminaire (the luminaire's flux).
    pub escaped_lm: f64,
    /// Flux absorbed by the mirror ((1 − ρ) per reflection).
    pub mirror_absorbed_lm: f64,
    /// Flux reflected back onto the source (absorbed there).
    pub returned_to_source_lm: f64,
    /// Flux still inside after the bounce limit (dropped, as in backward tracing).
    pub trapped_lm: f64,
    /// Number of quasi-random samples used.
    pub samples: usize,
}

/// A specular paraboloid reflector, axis along Z, opening downwards, with a Lambertian sphere at its
/// focus. The mirror's inside reflects with reflectance ρ (perfectly specular); its outside is a black
/// housing; the sphere is black for incoming light.
#[derive(Debug)]
pub struct Reflector {
    /// Focal length f (m): the surface is z = f − (x² + y²)/(4f), the focus at the origin.
    pub focal_m: f64,
    /// Aperture radius (m): the mirror is cut by the plane z = f − R²/(4f).
    pub aperture_radius_m: f64,
    /// Source sphere radius (m), centred at the focus.
    pub source_radius_m: f64,
    /// Source luminance (cd/m², uniform, Lambertian).
    pub source_luminance: f64,
    /// Mirror reflectance ρ (0…1).
    pub reflectance: f64,
    /// Bounces followed before a ray is dropped (luminance 0).
    pub max_bounces: u32,
    flux: OnceLock<FluxBudget>,
}

/// Samples of the forward flux integral (2²⁰ Halton points).
pub(crate) const FLUX_SAMPLES: usize = 1 << 20;
/// Pixel (m) and supersampling of the orthographic intensity integral.
pub(crate) const INTENSITY_PIXEL_M: f64 = 0.25e-3;
pub(crate) const INTENSITY_SUPERSAMPLE: u32 = 2;

impl Reflector {
    /// `reflector`: f = 25 mm, aperture radius 80 mm (mirror 64 mm deep, aperture plane z = −39 mm),
    /// source sphere of radius 5 mm at 10⁶ cd/m², ρ = 0.9, at most 16 bounces.
    pub fn standard() -> Self {
        Self {
            focal_m: 0.025,
            aperture_radius_m: 0.08,
            source_radius_m: 0.005,
            source_luminance: 1.0e6,
            reflectance: 0.9,
            max_bounces: 16,
            flux: OnceLock::new(),
        }
    }

    /// z of the aperture plane (m).
    pub fn aperture_z(&self) -> f64 {
        self.focal_m - self.aperture_radius_m * self.aperture_radius_m / (4.0 * self.focal_m)
    }

    /// Flux emitted by the source sphere (lm): π·L·4πr².
    pub fn source_flux_lm(&self) -> f64 {
        PI * self.source_luminance * 4.0 * PI * self.source_radius_m * self.source_radius_m
    }

    /// Smallest t > eps where the unit ray meets the source sphere.
    fn hit_sphere(&self, o: DVec3, d: DVec3, eps: f64) -> Option<f64> {
        let b = o.dot(d);
        let c = o.length_squared() - self.source_radius_m * self.source_radius_m;
        let disc = b * b - c;
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        let (t0, t1) = (-b - s, -b + s);
        if t0 > eps {
            Some(t0)
        } else if t1 > eps {
            Some(t1)
        } else {
            None
        }
    }

    /// Smallest t > eps where the unit ray meets the mirror (the paraboloid between the aperture
    /// plane and the vertex).
    fn hit_mirror(&self, o: DVec3, d: DVec3, eps: f64) -> Option<f64> {
        let f = self.focal_m;
        let a = d.x * d.x + d.y * d.y;
        let b = 2.0 * (o.x * d.x + o.y * d.y) + 4.0 * f * d.z;
        let c = o.x * o.x + o.y * o.y + 4.0 * f * o.z - 4.0 * f * f;
        let za = self.aperture_z();
        let ok = |t: f64| t > eps && o.z + t * d.z >= za;
        let mut roots = [f64::INFINITY; 2];
        if a < 1e-15 {
            if b != 0.0 {
                roots[0] = -c / b;
            }
        } else {
            let disc = b * b - 4.0 * a * c;
            if disc < 0.0 {
                return None;
            }
            // Numerically stable roots: q/a and c/q.
            let q = -0.5 * (b + if b >= 0.0 { 1.0 } else { -1.0 } * disc.sqrt());
            roots[0] = q / a;
            if q != 0.0 {
                roots[1] = c / q;
            }
        }
        if roots[1] < roots[0] {
            roots.swap(0, 1);
        }
        roots.into_iter().find(|&t| t.is_finite() && ok(t))
    }

    /// Whether `p` lies inside the mirror (between the paraboloid and the aperture plane).
    fn inside(&self, p: DVec3) -> bool {
        let f = self.focal_m;
        p.z >= self.aperture_z() && p.x * p.x + p.y * p.y + 4.0 * f * p.z - 4.0 * f * f < 0.0
    }

    /// Follows a ray (unit `d`) from an eye at `o`. From outside, light can only come out of the
    /// aperture disc, so a ray that does not cross it upwards sees nothing (the shell's outside is
    /// black): exact, and it spares most rays of a render the quadratic tests.
    fn trace_from_eye(&self, o: DVec3, d: DVec3) -> End {
        if self.inside(o) {
            return self.follow(o, d);
        }
        let za = self.aperture_z();
        if !(o.z < za && d.z > 0.0) {
            return End::Escaped(1.0);
        }
        let p = o + (za - o.z) / d.z * d;
        if p.x * p.x + p.y * p.y >= self.aperture_radius_m * self.aperture_radius_m {
            return End::Escaped(1.0);
        }
        self.follow(DVec3::new(p.x, p.y, za), d)
    }

    /// Follows a ray (unit `d`) through the mirror.
    fn follow(&self, mut o: DVec3, mut d: DVec3) -> End {
        let eps = 1e-9;
        let mut w = 1.0;
        for bounce in 0..=self.max_bounces {
            let ts = self.hit_sphere(o, d, eps);
            let tm = self.hit_mirror(o, d, eps);
            match (ts, tm) {
                (Some(s), m) if m.is_none_or(|m| s <= m) => return End::Source(w, bounce),
                (_, Some(t)) => {
                    let p = o + t * d;
                    let n = DVec3::new(2.0 * p.x, 2.0 * p.y, 4.0 * self.focal_m).normalize();
                    let dn = d.dot(n);
                    if dn <= 0.0 {
                        return End::Housing(w);
                    }
                    if bounce == self.max_bounces {
                        return End::Trapped(w);
                    }
                    d = (d - 2.0 * dn * n).normalize();
                    w *= self.reflectance;
                    o = p;
                }
                _ => return End::Escaped(w),
            }
        }
        End::Trapped(w)
    }

    /// Intensity (cd) of the source seen directly through the aperture towards unit `dir`:
    /// L · area(D ∩ E), where, in the plane perpendicular to ω, D is the source's disc (radius r) and E
    /// the aperture's projection (an ellipse with semi-axes R and R·cos γ, centred |z_a|·sin γ from D's
    /// centre). A ray through both crosses the aperture and, the mirror's inside being convex, meets
    /// the source before any mirror. Adaptive Simpson to 10⁻¹² of the disc's area.
    pub fn direct_intensity_cd(&self, dir: DVec3) -> f64 {
        let Some(u) = unit(dir) else { return 0.0 };
        let c = -u.z;
        if c <= 0.0 {
            return 0.0;
        }
        let sin = (1.0 - c * c).max(0.0).sqrt();
        let r = self.source_radius_m;
        let area = disc_ellipse_overlap(
            r,
            self.aperture_radius_m,
            self.aperture_radius_m * c,
            self.aperture_z().abs() * sin,
            1e-12 * PI * r * r,
        );
        self.source_luminance * area
    }

    /// Forward flux budget from `samples` Halton points (bases 2, 3, 5, 7) over the source's emission
    /// (uniform position on the sphere × cosine-weighted direction). Deterministic; parallel.
    pub fn forward_budget(&self, samples: usize) -> FluxBudget {
        let samples = samples.max(1);
        const CHUNK: usize = 4096;
        let parts: Vec<[f64; 4]> = (0..samples.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut acc = [0.0; 4]; // escaped, mirror absorbed, returned, trapped
                for i in c * CHUNK..((c + 1) * CHUNK).min(samples) {
                    let k = i as u64 + 1;
                    let (u1, u2, u3, u4) = (halton(k, 2), halton(k, 3), halton(k, 5), halton(k, 7));
                    // Uniform point on the sphere.
                    let z = 1.0 - 2.0 * u1;
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    let phi = 2.0 * PI * u2;
                    let n = DVec3::new(r * phi.cos(), r * phi.sin(), z);
                    // Cosine-weighted direction about n.
                    let (t1, t2) = orthonormal(n);
                    let sr = u3.sqrt();
                    let a = 2.0 * PI * u4;
                    let d = (t1 * (sr * a.cos()) + t2 * (sr * a.sin()) + n * (1.0 - u3).max(0.0).sqrt()).normalize();
                    let p = n * self.source_radius_m;
                    // Each reflection absorbs 1 − ρ of what arrives: 1 − w in all.
                    let (end, w) = match self.follow(p, d) {
                        End::Escaped(w) => (0, w),
                        // Light cannot reach the outside of the shell from the source; were it to,
                        // the shell absorbs it.
                        End::Housing(w) => (1, w),
                        End::Source(w, _) => (2, w),
                        End::Trapped(w) => (3, w),
                    };
                    acc[end] += w;
                    acc[1] += 1.0 - w;
                }
                acc
            })
            .collect();
        let mut tot = [0.0; 4];
        for p in &parts {
            for k in 0..4 {
                tot[k] += p[k];
            }
        }
        let s = self.source_flux_lm() / samples as f64;
        FluxBudget {
            source_lm: self.source_flux_lm(),
            escaped_lm: tot[0] * s,
            mirror_absorbed_lm: tot[1] * s,
            returned_to_source_lm: tot[2] * s,
            trapped_lm: tot[3] * s,
            samples,
        }
    }
}

/// The reflector seen only through its mirror: rays that meet the source after at least one reflection.
#[derive(Debug)]
struct Reflected<'a>(&'a Reflector);

impl Luminaire for Reflected<'_> {
    fn name(&self) -> &str {
        "reflector (reflected light only)"
    }
    fn description(&self) -> String {
        self.0.description()
    }
    fn radiance(&self, origin: DVec3, dir: DVec3) -> f64 {
        let Some(d) = unit(dir) else { return 0.0 };
        match self.0.trace_from_eye(origin, d) {
            End::Source(w, bounces) if bounces > 0 => w * self.0.source_luminance,
            _ => 0.0,
        }
    }
    fn intensity_cd(&self, _dir: DVec3) -> f64 {
        0.0
    }
    fn flux_lm(&self) -> f64 {
        0.0
    }
    fn bounds(&self) -> Aabb {
        self.0.bounds()
    }
    fn max_luminance(&self) -> f64 {
        self.0.source_luminance
    }
    fn proxy(&self) -> ProxyMesh {
        self.0.proxy()
    }
}

/// Area of the intersection of the disc x² + y² < r² and the ellipse x²/a² + (y − s)²/b² < 1, by
/// adaptive Simpson integration of the overlap of their vertical chords over x = r·sin t (which
/// removes the square-root ends of the disc's chords); absolute tolerance `tol` (m²).
fn disc_ellipse_overlap(r: f64, a: f64, b: f64, s: f64, tol: f64) -> f64 {
    if r <= 0.0 || a <= 0.0 || b <= 0.0 {
        return 0.0;
    }
    let chord = |t: f64| -> f64 {
        let x = r * t.sin();
        let hd = (r * r - x * x).max(0.0).sqrt();
        let q = 1.0 - (x / a).powi(2);
        if q <= 0.0 {
            return 0.0;
        }
        let he = b * q.sqrt();
        let lo = (-hd).max(s - he);
        let hi = hd.min(s + he);
        (hi - lo).max(0.0) * r * t.cos()
    };
    let half = std::f64::consts::FRAC_PI_2;
    adaptive_simpson(&chord, -half, half, tol, 40)
}

/// ∫ f over [a, b] by adaptive Simpson: 8 starting panels, each halved until its two halves agree
/// with it to 15·tol (tol halves with every split) or `max_depth` splits. Deterministic.
fn adaptive_simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64, tol: f64, max_depth: u32) -> f64 {
    struct Panel {
        a: f64,
        b: f64,
        fa: f64,
        fm: f64,
        fb: f64,
        tol: f64,
        depth: u32,
    }
    let simpson = |p: &Panel| (p.b - p.a) / 6.0 * (p.fa + 4.0 * p.fm + p.fb);
    const START: usize = 8;
    let mut stack = Vec::with_capacity(64);
    for i in 0..START {
        let x0 = a + (b - a) * i as f64 / START as f64;
        let x1 = a + (b - a) * (i + 1) as f64 / START as f64;
        stack.push(Panel {
            a: x0,
            b: x1,
            fa: f(x0),
            fm: f(0.5 * (x0 + x1)),
            fb: f(x1),
            tol: tol / START as f64,
            depth: max_depth,
        });
    }
    let mut total = 0.0;
    while let Some(p) = stack.pop() {
        let m = 0.5 * (p.a + p.b);
        let left = Panel {
            a: p.a,
            b: m,
            fa: p.fa,
            fm: f(0.5 * (p.a + m)),
            fb: p.fm,
            tol: 0.5 * p.tol,
            depth: p.depth.saturating_sub(1),
        };
        let right = Panel {
            a: m,
            b: p.b,
            fa: p.fm,
            fm: f(0.5 * (m + p.b)),
            fb: p.fb,
            tol: 0.5 * p.tol,
            depth: p.depth.saturating_sub(1),
        };
        let (l, r) = (simpson(&left), simpson(&right));
        let delta = l + r - simpson(&p);
        if p.depth == 0 || delta.abs() <= 15.0 * p.tol {
            total += l + r + delta / 15.0;
        } else {
            stack.push(left);
            stack.push(right);
        }
    }
    total
}

/// Radical inverse of `i` in `base` (Halton).
fn halton(mut i: u64, base: u64) -> f64 {
    let mut f = 1.0;
    let mut r = 0.0;
    let b = base as f64;
    while i > 0 {
        f /= b;
        r += f * (i % base) as f64;
        i /= base;
    }
    r
}

/// Two unit vectors completing `n` to an orthonormal basis.
fn orthonormal(n: DVec3) -> (DVec3, DVec3) {
    let a = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let t1 = n.cross(a).normalize();
    (t1, n.cross(t1))
}

impl Luminaire for Reflector {
    fn name(&self) -> &str {
        "reflector"
    }
    fn description(&self) -> String {
        format!(
            "specular paraboloid (f {} mm, aperture Ø {} mm, ρ {}, ≤ {} bounces) around a Lambertian sphere \
             (r {} mm, {} cd/m²) at its focus",
            self.focal_m * 1e3,
            2.0 * self.aperture_radius_m * 1e3,
            self.reflectance,
            self.max_bounces,
            self.source_radius_m * 1e3,
            self.source_luminance
        )
    }
    fn radiance(&self, origin: DVec3, dir: DVec3) -> f64 {
        let Some(d) = unit(dir) else { return 0.0 };
        match self.trace_from_eye(origin, d) {
            End::Source(w, _) => w * self.source_luminance,
            _ => 0.0,
        }
    }
    /// Direct part [`Reflector::direct_intensity_cd`] (a 1-D integral) plus the reflected part as the
    /// orthographic integral Σ L·ΔA over rays that reach the source after ≥ 1 reflection (0.25 mm
    /// pixels, 2 × 2 rays each); 0 at and above the horizon (light leaves only through the
    /// downward-facing aperture).
    fn intensity_cd(&self, dir: DVec3) -> f64 {
        let Some(u) = unit(dir) else { return 0.0 };
        if u.z >= 0.0 {
            return 0.0;
        }
        let reflected = ortho_intensity(&Reflected(self), u, INTENSITY_PIXEL_M, INTENSITY_SUPERSAMPLE).unwrap_or(0.0);
        self.direct_intensity_cd(u) + reflected
    }
    /// Forward quasi-Monte-Carlo integral over the source's emission (2²⁰ samples, computed once).
    fn flux_lm(&self) -> f64 {
        self.flux.get_or_init(|| self.forward_budget(FLUX_SAMPLES)).escaped_lm
    }
    fn closed_form(&self) -> bool {
        false
    }
    fn bounds(&self) -> Aabb {
        let r = self.aperture_radius_m;
        Aabb {
            min: DVec3::new(-r, -r, self.aperture_z()),
            max: DVec3::new(r, r, self.focal_m),
        }
    }
    fn max_luminance(&self) -> f64 {
        self.source_luminance
    }
    fn proxy(&self) -> ProxyMesh {
        let mut m = ProxyMesh::new(self.name());
        m.add_disc(
            "aperture",
            DVec3::new(0.0, 0.0, self.aperture_z()),
            self.aperture_radius_m,
            128,
        );
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nadir_view_sees_the_source_everywhere_in_the_aperture() {
        let r = Reflector::standard();
        // Looking straight up from below: the centre sees the source directly.
        assert_eq!(r.radiance(DVec3::new(0.0, 0.0, -1.0), DVec3::Z), 1.0e6);
        // Off axis, a vertical ray reflects once through the focus onto the source.
        for x in [0.01, 0.03, 0.06, 0.079] {
            let l = r.radiance(DVec3::new(x, 0.0, -1.0), DVec3::Z);
            assert!((l - 0.9e6).abs() < 1e-6, "x {x}: {l}");
        }
        // Outside the aperture: the black housing or nothing.
        assert_eq!(r.radiance(DVec3::new(0.081, 0.0, -1.0), DVec3::Z), 0.0);
        // From above: the black outside of the shell.
        assert_eq!(r.radiance(DVec3::new(0.0, 0.0, 1.0), -DVec3::Z), 0.0);
    }

    #[test]
    fn forward_budget_balances() {
        let r = Reflector::standard();
        let b = r.forward_budget(1 << 14);
        let sum = b.escaped_lm + b.mirror_absorbed_lm + b.returned_to_source_lm + b.trapped_lm;
        assert!(((sum - b.source_lm) / b.source_lm).abs() < 1e-9, "{b:?}");
        assert!(b.escaped_lm > 0.8 * b.source_lm && b.escaped_lm < b.source_lm, "{b:?}");
    }

    #[test]
    fn disc_ellipse_overlap_cases() {
        let pi = PI;
        // Disc inside the ellipse: its own area.
        assert!((disc_ellipse_overlap(1.0, 3.0, 2.0, 0.5, 1e-12) - pi).abs() < 1e-9);
        // Ellipse inside the disc: πab.
        assert!((disc_ellipse_overlap(2.0, 1.0, 0.5, 0.3, 1e-12) - pi * 0.5).abs() < 1e-9);
        // Disjoint.
        assert_eq!(disc_ellipse_overlap(1.0, 1.0, 1.0, 3.0, 1e-12), 0.0);
        // Two unit circles one radius apart: 2π/3 − √3/2 (lens).
        let lens = 2.0 * pi / 3.0 - 3f64.sqrt() / 2.0;
        assert!((disc_ellipse_overlap(1.0, 1.0, 1.0, 1.0, 1e-13) - lens).abs() < 1e-9);
    }

    #[test]
    fn direct_view_of_the_source() {
        let r = Reflector::standard();
        let full = 1e6 * PI * 25e-6;
        // At nadir and well inside the aperture's view: the whole source disc.
        assert!((r.direct_intensity_cd(-DVec3::Z) - full).abs() < 1e-9 * full);
        let d = |g: f64| DVec3::new(g.to_radians().sin(), 0.0, -g.to_radians().cos());
        assert!((r.direct_intensity_cd(d(45.0)) - full).abs() < 1e-9 * full);
        // Beyond the aperture's rim (z_a = −39 mm, R = 80 mm: tan γ > (80 + 5)/39 … hidden).
        assert_eq!(r.direct_intensity_cd(d(70.0)), 0.0);
        // Partly hidden in between.
        let g = ((0.08f64) / 0.039).atan().to_degrees();
        let part = r.direct_intensity_cd(d(g));
        assert!(part > 0.2 * full && part < 0.8 * full, "{part}");
    }

    #[test]
    fn halton_is_the_radical_inverse() {
        assert_eq!(halton(1, 2), 0.5);
        assert_eq!(halton(2, 2), 0.25);
        assert!((halton(1, 3) - 1.0 / 3.0).abs() < 1e-15);
    }
}
