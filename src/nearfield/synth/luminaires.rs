//! The planar analytic luminaires: Lambertian disc and rectangle, Siemens-star panel, thin strips, an
//! LED-dot array, cosⁿ discs and a 10⁶ cd/m² peak on a 1 cd/m² background (the two planes at
//! different depths are in `two_planes.rs`), and the plane-geometry helpers they share. All emit
//! downwards from planes parallel to z = 0; their backs are black and opaque. Intensities and fluxes
//! are closed forms (docs/synthetic.md writes them out).

use std::f64::consts::PI;

use glam::DVec3;

use super::proxy::ProxyMesh;
use super::{unit, Aabb, Luminaire};
use crate::nearfield::error::{NearfieldError, Result};

/// An axis-aligned rectangle in a plane z = const (m); half-open: [x0, x1) × [y0, y1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Rect {
    pub x0: f64,
    pub x1: f64,
    pub y0: f64,
    pub y1: f64,
}

impl Rect {
    /// The rectangle centred at (cx, cy) with full sizes (w, h).
    pub fn centred(cx: f64, cy: f64, w: f64, h: f64) -> Self {
        Self {
            x0: cx - 0.5 * w,
            x1: cx + 0.5 * w,
            y0: cy - 0.5 * h,
            y1: cy + 0.5 * h,
        }
    }
    pub fn contains(&self, x: f64, y: f64) -> bool {
        x >= self.x0 && x < self.x1 && y >= self.y0 && y < self.y1
    }
    pub fn area(&self) -> f64 {
        (self.x1 - self.x0) * (self.y1 - self.y0)
    }
    pub fn shifted(&self, dx: f64, dy: f64) -> Self {
        Self {
            x0: self.x0 + dx,
            x1: self.x1 + dx,
            y0: self.y0 + dy,
            y1: self.y1 + dy,
        }
    }
    /// The overlap, or `None` when it is empty.
    pub fn intersect(&self, o: &Rect) -> Option<Rect> {
        let r = Rect {
            x0: self.x0.max(o.x0),
            x1: self.x1.min(o.x1),
            y0: self.y0.max(o.y0),
            y1: self.y1.min(o.y1),
        };
        (r.x1 > r.x0 && r.y1 > r.y0).then_some(r)
    }
}

/// Where a ray meets the plane z = `z` travelling upwards (so it sees the plane's downward-facing,
/// emitting side), at t > 0: the (x, y) of the hit.
#[inline]
pub(crate) fn hit_from_below(o: DVec3, d: DVec3, z: f64) -> Option<(f64, f64)> {
    if d.z <= 0.0 {
        return None;
    }
    let t = (z - o.z) / d.z;
    if t.is_nan() || t <= 0.0 {
        return None;
    }
    Some((o.x + t * d.x, o.y + t * d.y))
}

/// cos γ of a unit emission direction measured from nadir, or `None` when it does not point below
/// the horizon (a downward emitter sends nothing there).
#[inline]
pub(crate) fn cos_below(dir: DVec3) -> Option<f64> {
    let u = unit(dir)?;
    let c = -u.z;
    (c > 0.0).then_some(c)
}

pub(crate) fn rect_bounds(r: &Rect, z0: f64, z1: f64) -> Aabb {
    Aabb {
        min: DVec3::new(r.x0, r.y0, z0),
        max: DVec3::new(r.x1, r.y1, z1),
    }
}

/// Segments of proxy-mesh discs (polygons of the disc's area, [`ProxyMesh::add_disc`]).
const DISC_SEGMENTS: u32 = 128;

// ---------------------------------------------------------------------------------------------------

/// A Lambertian disc facing down: radius r, uniform luminance L. I(γ) = L·πr²·cos γ, Φ = π·L·πr².
#[derive(Debug, Clone, PartialEq)]
pub struct LambertDisc {
    /// Centre of the disc (m); the disc lies in the plane z = centre.z.
    pub centre: DVec3,
    /// Radius (m).
    pub radius_m: f64,
    /// Luminance (cd/m²).
    pub luminance: f64,
}

impl LambertDisc {
    /// `disc`: radius 0.1 m at the origin, 10,000 cd/m².
    pub fn standard() -> Self {
        Self {
            centre: DVec3::ZERO,
            radius_m: 0.1,
            luminance: 10_000.0,
        }
    }
    /// The disc's area (m²).
    pub fn area_m2(&self) -> f64 {
        PI * self.radius_m * self.radius_m
    }
}

impl Luminaire for LambertDisc {
    fn name(&self) -> &str {
        "disc"
    }
    fn description(&self) -> String {
        format!(
            "Lambertian disc facing down, radius {} mm, {} cd/m²",
            self.radius_m * 1e3,
            self.luminance
        )
    }
    fn radiance(&self, origin: DVec3, dir: DVec3) -> f64 {
        match hit_from_below(origin, dir, self.centre.z) {
            Some((x, y)) => {
                let (dx, dy) = (x - self.centre.x, y - self.centre.y);
                if dx * dx + dy * dy < self.radius_m * self.radius_m {
                    self.luminance
                } else {
                    0.0
                }
            }
            None => 0.0,
        }
    }
    fn intensity_cd(&self, dir: DVec3) -> f64 {
        cos_below(dir).map_or(0.0, |c| self.luminance * self.area_m2() * c)
    }
    fn flux_lm(&self) -> f64 {
        PI * self.luminance * self.area_m2()
    }
    fn bounds(&self) -> Aabb {
        let r = DVec3::new(self.radius_m, self.radius_m, 0.0);
        Aabb {
            min: self.centre - r,
            max: self.centre + r,
        }
    }
    fn max_luminance(&self) -> f64 {
        self.luminance
    }
    fn proxy(&self) -> ProxyMesh {
        let mut m = ProxyMesh::new(self.name());
        m.add_disc("disc", self.centre, self.radius_m, DISC_SEGMENTS);
        m
    }
}

// ---------------------------------------------------------------------------------------------------

/// A Lambertian rectangle facing down. I(γ) = L·A·cos γ, Φ = π·L·A.
#[derive(Debug, Clone, PartialEq)]
pub struct LambertRect {
    /// Length along X (m).
    pub length_m: f64,
    /// Width along Y (m).
    pub width_m: f64,
    /// Luminance (cd/m²).
    pub luminance: f64,
}

impl LambertRect {
    /// `rect`: 0.6 m (X) × 0.15 m (Y) centred at the origin in z = 0, 5,000 cd/m².
    pub fn standard() -> Self {
        Self {
            length_m: 0.6,
            width_m: 0.15,
            luminance: 5_000.0,
        }
    }
    fn rect(&self) -> Rect {
        Rect::centred(0.0, 0.0, self.length_m, self.width_m)
    }
}

impl Luminaire for LambertRect {
    fn name(&self) -> &str {
        "rect"
    }
    fn description(&self) -> String {
        format!(
            "Lambertian rectangle facing down, {} mm (X) × {} mm (Y), {} cd/m²",
            self.length_m * 1e3,
            self.width_m * 1e3,
            self.luminance
        )
    }
    fn radiance(&self, origin: DVec3, dir: DVec3) -> f64 {
        match hit_from_below(origin, dir, 0.0) {
            Some((x, y)) if self.rect().contains(x, y) => self.luminance,
            _ => 0.0,
        }
    }
    fn intensity_cd(&self, dir: DVec3) -> f64 {
        cos_below(dir).map_or(0.0, |c| self.luminance * self.rect().area() * c)
    }
    fn flux_lm(&self) -> f64 {
        PI * self.luminance * self.rect().area()
    }
    fn bounds(&self) -> Aabb {
        rect_bounds(&self.rect(), 0.0, 0.0)
    }
    fn max_luminance(&self) -> f64 {
        self.luminance
    }
    fn proxy(&self) -> ProxyMesh {
        let mut m = ProxyMesh::new(self.name());
        let r = self.rect();
        m.add_rect("rect", r.x0, r.x1, r.y0, r.y1, 0.0);
        m
    }
}

// ---------------------------------------------------------------------------------------------------

/// A Lambertian panel with a textured luminance L(x, y): a Siemens star on the left half and an
/// exponential luminance ramp on the right half. I(γ) = cos γ · ∫L dA, Φ = π ∫L dA.
#[derive(Debug, Clone, PartialEq)]
pub struct StarPanel {
    panel: Rect,
    star_centre: (f64, f64),
    star_radius: f64,
    /// Number of bright spokes (as many dark ones between them).
    spokes: u32,
    l_bright: f64,
    l_dark: f64,
    l_background: f64,
    /// The ramp covers x ∈ [ramp_x0, panel.x1]: L = l_ramp0 · ratio^((x − ramp_x0)/width).
    ramp_x0: f64,
    l_ramp0: f64,
    ramp_ratio: f64,
}

impl StarPanel {
    /// `star-panel`: 400 mm (X) × 200 mm (Y) in z = 0. Left half (x < 0): background 2,000 cd/m² with
    /// a Siemens star of radius 90 mm at (−100, 0) mm, 16 bright spokes of 8,000 cd/m² and 16 dark
    /// ones of 800 cd/m² (equal 11.25° sectors, the first bright sector starting at φ = −180°). Right
    /// half (x ≥ 0): L = 10 · 1000^(x / 0.2 m) cd/m², from 10 to 10,000 cd/m².
    pub fn standard() -> Self {
        Self {
            panel: Rect::centred(0.0, 0.0, 0.4, 0.2),
            star_centre: (-0.1, 0.0),
            star_radius: 0.09,
            spokes: 16,
            l_bright: 8_000.0,
            l_dark: 800.0,
            l_background: 2_000.0,
            ramp_x0: 0.0,
            l_ramp0: 10.0,
            ramp_ratio: 1000.0,
        }
    }

    /// The luminance (cd/m²) at (x, y) in the panel plane; 0 outside the panel.
    pub fn luminance_at(&self, x: f64, y: f64) -> f64 {
        if !self.panel.contains(x, y) {
            return 0.0;
        }
        if x >= self.ramp_x0 {
            let w = self.panel.x1 - self.ramp_x0;
            return self.l_ramp0 * ((x - self.ramp_x0) / w * self.ramp_ratio.ln()).exp();
        }
        let (dx, dy) = (x - self.star_centre.0, y - self.star_centre.1);
        if dx * dx + dy * dy >= self.star_radius * self.star_radius {
            return self.l_background;
        }
        let sectors = 2 * self.spokes;
        let phi = dy.atan2(dx) + PI; // 0…2π
        let s = ((phi / (2.0 * PI) * sectors as f64).floor() as i64).rem_euclid(sectors as i64);
        if s % 2 == 0 {
            self.l_bright
        } else {
            self.l_dark
        }
    }

    /// ∫ L dA over the panel (cd·m²/m² = cd at normal incidence).
    pub fn integral(&self) -> f64 {
        let left = Rect {
            x1: self.ramp_x0,
            ..self.panel
        };
        let star_area = PI * self.star_radius * self.star_radius;
        let star = 0.5 * (self.l_bright + self.l_dark) * star_area;
        let background = self.l_background * (left.area() - star_area);
        let w = self.panel.x1 - self.ramp_x0;
        let h = self.panel.y1 - self.panel.y0;
        let ramp = self.l_ramp0 * w * (self.ramp_ratio - 1.0) / self.ramp_ratio.ln() * h;
        star + background + ramp
    }
}

impl Luminaire for StarPanel {
    fn name(&self) -> &str {
        "star-panel"
    }
    fn description(&self) -> String {
        "Lambertian panel 400 × 200 mm facing down: Siemens star (r 90 mm, 16 spokes, 8,000/800 cd/m²) \
         on a 2,000 cd/m² left half; exponential ramp 10 → 10,000 cd/m² across the right half"
            .into()
    }
    fn radiance(&self, origin: DVec3, dir: DVec3) -> f64 {
        hit_from_below(origin, dir, 0.0).map_or(0.0, |(x, y)| self.luminance_at(x, y))
    }
    fn intensity_cd(&self, dir: DVec3) -> f64 {
        cos_below(dir).map_or(0.0, |c| self.integral() * c)
    }
    fn flux_lm(&self) -> f64 {
        PI * self.integral()
    }
    fn bounds(&self) -> Aabb {
        rect_bounds(&self.panel, 0.0, 0.0)
    }
    fn max_luminance(&self) -> f64 {
        self.l_bright
            .max(self.l_background)
            .max(self.l_ramp0 * self.ramp_ratio.max(1.0))
    }
    fn proxy(&self) -> ProxyMesh {
        let mut m = ProxyMesh::new(self.name());
        let r = self.panel;
        m.add_rect("panel", r.x0, r.x1, r.y0, r.y1, 0.0);
        m
    }
}

// ---------------------------------------------------------------------------------------------------

/// Thin Lambertian strips along X facing down. I(γ) = L·ΣA·cos γ, Φ = π·L·ΣA.
#[derive(Debug, Clone, PartialEq)]
pub struct Strips {
    count: usize,
    width_m: f64,
    length_m: f64,
    pitch_m: f64,
    luminance: f64,
}

impl Strips {
    /// `strips`: 5 strips 1 mm wide (Y) and 300 mm long (X) in z = 0, centred at y = −40, −20, 0, 20,
    /// 40 mm, 20,000 cd/m².
    pub fn standard() -> Self {
        Self {
            count: 5,
            width_m: 0.001,
            length_m: 0.3,
            pitch_m: 0.02,
            luminance: 20_000.0,
        }
    }
    fn offset(&self) -> f64 {
        0.5 * (self.count as f64 - 1.0)
    }
    fn strip(&self, k: usize) -> Rect {
        Rect::centred(
            0.0,
            (k as f64 - self.offset()) * self.pitch_m,
            self.length_m,
            self.width_m,
        )
    }
}

impl Luminaire for Strips {
    fn name(&self) -> &str {
        "strips"
    }
    fn description(&self) -> String {
        format!(
            "{} Lambertian strips facing down, {} mm × {} mm at {} mm pitch, {} cd/m²",
            self.count,
            self.length_m * 1e3,
            self.width_m * 1e3,
            self.pitch_m * 1e3,
            self.luminance
        )
    }
    fn radiance(&self, origin: DVec3, dir: DVec3) -> f64 {
        let Some((x, y)) = hit_from_below(origin, dir, 0.0) else {
            return 0.0;
        };
        let k = (y / self.pitch_m + self.offset()).round();
        if !(k >= 0.0 && k < self.count as f64) {
            return 0.0;
        }
        if self.strip(k as usize).contains(x, y) {
            self.luminance
        } else {
            0.0
        }
    }
    fn intensity_cd(&self, dir: DVec3) -> f64 {
        cos_below(dir).map_or(0.0, |c| {
            self.luminance * self.count as f64 * self.width_m * self.length_m * c
        })
    }
    fn flux_lm(&self) -> f64 {
        PI * self.luminance * self.count as f64 * self.width_m * self.length_m
    }
    fn bounds(&self) -> Aabb {
        let (a, b) = (self.strip(0), self.strip(self.count - 1));
        rect_bounds(
            &Rect {
                x0: a.x0,
                x1: a.x1,
                y0: a.y0,
                y1: b.y1,
            },
            0.0,
            0.0,
        )
    }
    fn max_luminance(&self) -> f64 {
        self.luminance
    }
    fn proxy(&self) -> ProxyMesh {
        let mut m = ProxyMesh::new(self.name());
        for k in 0..self.count {
            let r = self.strip(k);
            m.add_rect(&format!("strip {k}"), r.x0, r.x1, r.y0, r.y1, 0.0);
        }
        m
    }
}

// ---------------------------------------------------------------------------------------------------

/// An array of small Lambertian discs facing down (LED dots). I(γ) = L·N·πr²·cos γ.
#[derive(Debug, Clone, PartialEq)]
pub struct LedDots {
    nx: usize,
    ny: usize,
    pitch_m: f64,
    radius_m: f64,
    luminance: f64,
}

impl LedDots {
    /// `led-dots`: 8 (X) × 4 (Y) discs of radius 1.5 mm at a 25 mm pitch, centred, in z = 0,
    /// 300,000 cd/m².
    pub fn standard() -> Self {
        Self {
            nx: 8,
            ny: 4,
            pitch_m: 0.025,
            radius_m: 0.0015,
            luminance: 300_000.0,
        }
    }
    fn centre(&self, i: usize, j: usize) -> (f64, f64) {
        (
            (i as f64 - 0.5 * (self.nx as f64 - 1.0)) * self.pitch_m,
            (j as f64 - 0.5 * (self.ny as f64 - 1.0)) * self.pitch_m,
        )
    }
    fn total_area(&self) -> f64 {
        (self.nx * self.ny) as f64 * PI * self.radius_m * self.radius_m
    }
}

impl Luminaire for LedDots {
    fn name(&self) -> &str {
        "led-dots"
    }
    fn description(&self) -> String {
        format!(
            "{} × {} Lambertian dots facing down, radius {} mm at {} mm pitch, {} cd/m²",
            self.nx,
            self.ny,
            self.radius_m * 1e3,
            self.pitch_m * 1e3,
            self.luminance
        )
    }
    fn radiance(&self, origin: DVec3, dir: DVec3) -> f64 {
        let Some((x, y)) = hit_from_below(origin, dir, 0.0) else {
            return 0.0;
        };
        let i = (x / self.pitch_m + 0.5 * (self.nx as f64 - 1.0)).round();
        let j = (y / self.pitch_m + 0.5 * (self.ny as f64 - 1.0)).round();
        if !(i >= 0.0 && i < self.nx as f64 && j >= 0.0 && j < self.ny as f64) {
            return 0.0;
        }
        let (cx, cy) = self.centre(i as usize, j as usize);
        let (dx, dy) = (x - cx, y - cy);
        if dx * dx + dy * dy < self.radius_m * self.radius_m {
            self.luminance
        } else {
            0.0
        }
    }
    fn intensity_cd(&self, dir: DVec3) -> f64 {
        cos_below(dir).map_or(0.0, |c| self.luminance * self.total_area() * c)
    }
    fn flux_lm(&self) -> f64 {
        PI * self.luminance * self.total_area()
    }
    fn bounds(&self) -> Aabb {
        let (x0, y0) = self.centre(0, 0);
        let (x1, y1) = self.centre(self.nx - 1, self.ny - 1);
        let r = self.radius_m;
        Aabb {
            min: DVec3::new(x0 - r, y0 - r, 0.0),
            max: DVec3::new(x1 + r, y1 + r, 0.0),
        }
    }
    fn max_luminance(&self) -> f64 {
        self.luminance
    }
    fn feature_centre(&self) -> DVec3 {
        let (x, y) = self.centre((self.nx - 1) / 2, (self.ny - 1) / 2);
        DVec3::new(x, y, 0.0)
    }
    fn proxy(&self) -> ProxyMesh {
        let mut m = ProxyMesh::new(self.name());
        for j in 0..self.ny {
            for i in 0..self.nx {
                let (x, y) = self.centre(i, j);
                m.add_disc(
                    &format!("dot {i},{j}"),
                    DVec3::new(x, y, 0.0),
                    self.radius_m,
                    DISC_SEGMENTS,
                );
            }
        }
        m
    }
}

// ---------------------------------------------------------------------------------------------------

/// A disc facing down whose luminance falls off as L(γ) = L₀·cos^(n−1) γ, so I(γ) = L₀·πr²·cosⁿ γ and
/// Φ = L₀·πr²·2π/(n + 1). n = 1 is Lambertian.
#[derive(Debug, Clone, PartialEq)]
pub struct CosineDisc {
    name: String,
    n: f64,
    radius_m: f64,
    l0: f64,
}

impl CosineDisc {
    /// A cosⁿ disc named `name`: radius 50 mm at the origin, on-axis luminance 10,000 cd/m².
    ///
    /// Errors: `n` not finite or below 1 (argument `n`).
    pub fn new(name: &str, n: f64) -> Result<Self> {
        if !n.is_finite() || n < 1.0 {
            return Err(NearfieldError::invalid("n", format!("{n} must be finite and ≥ 1")));
        }
        Ok(Self {
            name: name.to_string(),
            n,
            radius_m: 0.05,
            l0: 10_000.0,
        })
    }
    fn area(&self) -> f64 {
        PI * self.radius_m * self.radius_m
    }
    /// c^(n + k): integer powers by multiplication (exact and fast for n = 1, 10, 100).
    fn cos_pow(&self, c: f64, k: i32) -> f64 {
        let e = self.n + f64::from(k);
        if e.fract() == 0.0 && e.abs() <= 1024.0 {
            c.powi(e as i32)
        } else {
            c.powf(e)
        }
    }

    /// The exponent n of I ∝ cosⁿ γ.
    pub fn exponent(&self) -> f64 {
        self.n
    }
}

impl Luminaire for CosineDisc {
    fn name(&self) -> &str {
        &self.name
    }
    fn description(&self) -> String {
        format!(
            "disc facing down, radius {} mm, L = {} · cos^{} γ cd/m² (I ∝ cos^{} γ)",
            self.radius_m * 1e3,
            self.l0,
            self.n - 1.0,
            self.n
        )
    }
    fn radiance(&self, origin: DVec3, dir: DVec3) -> f64 {
        let Some((x, y)) = hit_from_below(origin, dir, 0.0) else {
            return 0.0;
        };
        if x * x + y * y >= self.radius_m * self.radius_m {
            return 0.0;
        }
        // Emission direction −dir; its cos γ from nadir is dir.z/|dir| (> 0 here).
        let c = dir.z / dir.length();
        self.l0 * self.cos_pow(c, -1)
    }
    fn intensity_cd(&self, dir: DVec3) -> f64 {
        cos_below(dir).map_or(0.0, |c| self.l0 * self.area() * self.cos_pow(c, 0))
    }
    fn flux_lm(&self) -> f64 {
        self.l0 * self.area() * 2.0 * PI / (self.n + 1.0)
    }
    fn bounds(&self) -> Aabb {
        let r = DVec3::new(self.radius_m, self.radius_m, 0.0);
        Aabb { min: -r, max: r }
    }
    fn max_luminance(&self) -> f64 {
        self.l0
    }
    fn proxy(&self) -> ProxyMesh {
        let mut m = ProxyMesh::new(self.name());
        m.add_disc("disc", DVec3::ZERO, self.radius_m, DISC_SEGMENTS);
        m
    }
}

// ---------------------------------------------------------------------------------------------------

/// A very bright small disc on a dim Lambertian background, coplanar, facing down.
#[derive(Debug, Clone, PartialEq)]
pub struct Peak {
    background: Rect,
    l_background: f64,
    centre: (f64, f64),
    radius_m: f64,
    l_peak: f64,
}

impl Peak {
    /// `peak`: background 200 × 200 mm at 1 cd/m² in z = 0; a disc of radius 2.5 mm centred at
    /// (30, 20) mm at 10⁶ cd/m² (replacing the background there).
    pub fn standard() -> Self {
        Self {
            background: Rect::centred(0.0, 0.0, 0.2, 0.2),
            l_background: 1.0,
            centre: (0.03, 0.02),
            radius_m: 0.0025,
            l_peak: 1.0e6,
        }
    }
    fn integral(&self) -> f64 {
        let a = PI * self.radius_m * self.radius_m;
        self.l_background * (self.background.area() - a) + self.l_peak * a
    }
}

impl Luminaire for Peak {
    fn name(&self) -> &str {
        "peak"
    }
    fn description(&self) -> String {
        "10⁶ cd/m² disc (radius 2.5 mm at (30, 20) mm) on a 200 × 200 mm background of 1 cd/m², facing down".into()
    }
    fn radiance(&self, origin: DVec3, dir: DVec3) -> f64 {
        let Some((x, y)) = hit_from_below(origin, dir, 0.0) else {
            return 0.0;
        };
        let (dx, dy) = (x - self.centre.0, y - self.centre.1);
        if dx * dx + dy * dy < self.radius_m * self.radius_m {
            self.l_peak
        } else if self.background.contains(x, y) {
            self.l_background
        } else {
            0.0
        }
    }
    fn intensity_cd(&self, dir: DVec3) -> f64 {
        cos_below(dir).map_or(0.0, |c| self.integral() * c)
    }
    fn flux_lm(&self) -> f64 {
        PI * self.integral()
    }
    fn bounds(&self) -> Aabb {
        rect_bounds(&self.background, 0.0, 0.0)
    }
    fn max_luminance(&self) -> f64 {
        self.l_peak.max(self.l_background)
    }
    fn feature_centre(&self) -> DVec3 {
        DVec3::new(self.centre.0, self.centre.1, 0.0)
    }
    fn proxy(&self) -> ProxyMesh {
        let mut m = ProxyMesh::new(self.name());
        let b = self.background;
        m.add_rect("background", b.x0, b.x1, b.y0, b.y1, 0.0);
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn star_panel_sectors_alternate_and_ramp_spans_three_decades() {
        let p = StarPanel::standard();
        // Just above and below φ = 0 (relative to the star centre) are different sectors.
        let a = p.luminance_at(-0.1 + 0.05, 0.001);
        let b = p.luminance_at(-0.1 + 0.05, -0.001);
        assert!(a != b && (a == 8000.0 || a == 800.0) && (b == 8000.0 || b == 800.0));
        assert_eq!(p.luminance_at(-0.19, 0.095), 2000.0);
        assert!((p.luminance_at(0.0, 0.0) - 10.0).abs() < 1e-9);
        assert!((p.luminance_at(0.2 - 1e-12, 0.0) - 10_000.0).abs() < 1e-6);
        assert_eq!(p.luminance_at(0.3, 0.0), 0.0);
    }
}
