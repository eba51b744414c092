//! Exact ray casting of analytic luminaires into pinhole and orthographic images.
//!
//! What a pixel means: with `supersample = 1` a pixel holds the luminance seen along the single ray
//! through its centre `(col + 0.5, row + 0.5)` (a point sample, the convention of
//! `rayset.rs`); with `supersample = n` it holds the mean of n × n rays through the centres of an
//! n × n grid of sub-pixels, `(col + (a + 0.5)/n, row + (b + 0.5)/n)` — an estimate of the pixel's
//! box-filtered average luminance. Only pixels inside the projection of the luminaire's bounding box
//! ([`pixel_bounds`]) are ray-cast; all others are 0 without a ray.
//!
//! Orthographic views ([`OrthoView`]) look along −ω at the luminaire with square pixels of a given
//! size in metres; Σ L·ΔA over such a render is the luminous intensity I(ω) ([`ortho_intensity`]).

use glam::DVec3;
use rayon::prelude::*;

use super::{unit, Aabb, Luminaire};
use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::rayset::{look_at_basis, Camera, Intrinsics, LuminanceImage};

/// The largest supersampling factor (n × n rays per pixel).
pub const MAX_SUPERSAMPLE: u32 = 16;

/// Largest orthographic view (pixels): 2²⁸ (integrals only; a rendered image is limited to
/// [`MAX_IMAGE_PIXELS`]).
pub const MAX_ORTHO_PIXELS: u64 = 1 << 28;

/// Largest image rendered into memory (pixels): 2²⁶, 256 MiB of f32 (a full-size capture image has
/// 1.24 · 10⁶).
pub const MAX_IMAGE_PIXELS: u64 = 1 << 26;

/// Checks that a `width × height` image may be allocated; `what` names the argument.
fn check_image_size(what: &str, width: u32, height: u32) -> Result<()> {
    if u64::from(width) * u64::from(height) > MAX_IMAGE_PIXELS {
        return Err(NearfieldError::invalid(
            what,
            format!("{width}×{height} px is more than {MAX_IMAGE_PIXELS} pixels per rendered image"),
        ));
    }
    Ok(())
}

/// A rectangle of pixels, half-open: columns `col0..col1`, rows `row0..row1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelRect {
    /// First column.
    pub col0: u32,
    /// One past the last column.
    pub col1: u32,
    /// First row.
    pub row0: u32,
    /// One past the last row.
    pub row1: u32,
}

impl PixelRect {
    /// Number of pixels inside.
    pub fn pixel_count(&self) -> u64 {
        u64::from(self.col1 - self.col0) * u64::from(self.row1 - self.row0)
    }
}

/// Checks a supersampling factor (argument `supersample`).
pub fn check_supersample(n: u32) -> Result<()> {
    if !(1..=MAX_SUPERSAMPLE).contains(&n) {
        return Err(NearfieldError::invalid(
            "supersample",
            format!("{n} is outside 1…{MAX_SUPERSAMPLE}"),
        ));
    }
    Ok(())
}

/// The pixels of a pinhole camera that can see anything of `bounds`: the bounding rectangle of the
/// projected box corners (the projection of a convex box is the convex hull of its projected
/// corners), widened to whole pixels and clipped to the image. The whole image when a corner lies
/// behind or on the camera plane (the camera is close to or inside the box); `None` when every
/// corner lies behind the camera or the rectangle misses the image.
pub fn pixel_bounds(bounds: &Aabb, cam: &Camera, k: &Intrinsics) -> Option<PixelRect> {
    let full = PixelRect {
        col0: 0,
        col1: k.width,
        row0: 0,
        row1: k.height,
    };
    let mut behind = 0;
    let (mut umin, mut umax, mut vmin, mut vmax) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for p in bounds.corners() {
        let d = cam.to_camera(p - cam.position_m);
        if d.z <= 1e-9 * (1.0 + d.x.abs() + d.y.abs()) {
            behind += 1;
            continue;
        }
        let Some(uv) = k.project(d) else {
            behind += 1;
            continue;
        };
        umin = umin.min(uv.x);
        umax = umax.max(uv.x);
        vmin = vmin.min(uv.y);
        vmax = vmax.max(uv.y);
    }
    if behind == 8 {
        return None;
    }
    if behind > 0 {
        return Some(full);
    }
    if !(umin.is_finite() && umax.is_finite() && vmin.is_finite() && vmax.is_finite()) {
        return Some(full);
    }
    let clip = |v: f64, hi: u32| -> u32 { v.clamp(0.0, f64::from(hi)) as u32 };
    let r = PixelRect {
        col0: clip(umin.floor(), k.width),
        col1: clip(umax.ceil(), k.width),
        row0: clip(vmin.floor(), k.height),
        row1: clip(vmax.ceil(), k.height),
    };
    (r.col1 > r.col0 && r.row1 > r.row0).then_some(r)
}

/// Renders what the pinhole camera `cam` with intrinsics `k` sees of `lum` (cd/m², row 0 at the top),
/// with `supersample`² rays per pixel (1: point sample at the pixel centre). Single-threaded: callers
/// render many images in parallel. Pixels outside [`pixel_bounds`] are 0 without a ray.
///
/// Errors: bad intrinsics or more than [`MAX_IMAGE_PIXELS`] (named after the camera's label), or a
/// supersampling factor outside 1…[`MAX_SUPERSAMPLE`].
pub fn render_pinhole(lum: &dyn Luminaire, cam: &Camera, k: &Intrinsics, supersample: u32) -> Result<LuminanceImage> {
    k.validate(&cam.label)?;
    check_image_size(&format!("{}: intrinsics size", cam.label), k.width, k.height)?;
    check_supersample(supersample)?;
    let mut img = LuminanceImage::zeros(k.width, k.height);
    let Some(r) = pixel_bounds(&lum.bounds(), cam, k) else {
        return Ok(img);
    };
    let n = supersample as usize;
    let inv_n = 1.0 / n as f64;
    let weight = 1.0 / (n * n) as f64;
    let width = k.width as usize;
    let o = cam.position_m;
    // Camera-space x of every sub-column, once.
    let xs: Vec<f64> = (r.col0 as usize * n..r.col1 as usize * n)
        .map(|s| ((s as f64 + 0.5) * inv_n - k.principal_px.x) / k.focal_px.x)
        .collect();
    for row in r.row0 as usize..r.row1 as usize {
        let line = &mut img.data[row * width + r.col0 as usize..row * width + r.col1 as usize];
        if n == 1 {
            let y = (row as f64 + 0.5 - k.principal_px.y) / k.focal_px.y;
            let base = cam.forward + cam.down * y;
            for (px, &x) in line.iter_mut().zip(&xs) {
                *px = lum.radiance(o, base + cam.right * x) as f32;
            }
            continue;
        }
        for (c, px) in line.iter_mut().enumerate() {
            let mut sum = 0.0;
            for b in 0..n {
                let y = ((row * n + b) as f64 + 0.5) * inv_n;
                let y = (y - k.principal_px.y) / k.focal_px.y;
                let base = cam.forward + cam.down * y;
                for &x in &xs[c * n..(c + 1) * n] {
                    sum += lum.radiance(o, base + cam.right * x);
                }
            }
            *px = (sum * weight) as f32;
        }
    }
    Ok(img)
}

/// An orthographic view of the luminaire from direction ω: parallel rays along −ω through a grid of
/// square pixels of `pixel_m` metres in the plane through `centre_m` perpendicular to ω. The image
/// basis is [`look_at_basis`]`(−ω)` (as a capture camera at ω would have), row 0 at the top.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrthoView {
    /// Unit direction from the luminaire towards the viewer (photometric ω).
    pub direction: DVec3,
    /// Point of the luminaire frame at the image centre (m).
    pub centre_m: DVec3,
    /// Pixel size (m).
    pub pixel_m: f64,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl OrthoView {
    /// The view from `direction` that holds the whole projected `bounds` (plus one pixel of margin on
    /// each side), centred on the box's centre.
    ///
    /// Errors: `direction` zero or not finite (argument `direction`); `pixel_m` not finite or ≤ 0, or so
    /// small that the image would exceed 65,536 pixels a side or [`MAX_ORTHO_PIXELS`] (argument
    /// `pixel size`).
    pub fn framing(bounds: &Aabb, direction: DVec3, pixel_m: f64) -> Result<Self> {
        let w = unit(direction).ok_or_else(|| NearfieldError::invalid("direction", "must be finite and non-zero"))?;
        if !pixel_m.is_finite() || pixel_m <= 0.0 {
            return Err(NearfieldError::invalid(
                "pixel size",
                format!("{pixel_m} m must be finite and > 0"),
            ));
        }
        let (right, down, _) = look_at_basis(-w);
        let c = bounds.centre();
        let (mut ex, mut ey) = (0.0f64, 0.0f64);
        for p in bounds.corners() {
            ex = ex.max((p - c).dot(right).abs());
            ey = ey.max((p - c).dot(down).abs());
        }
        let size = |e: f64| -> Result<u32> {
            let n = (2.0 * e / pixel_m).ceil() + 2.0;
            if n > 65_536.0 {
                return Err(NearfieldError::invalid(
                    "pixel size",
                    format!("{pixel_m} m needs {n} pixels across the luminaire; at most 65536"),
                ));
            }
            Ok(n as u32)
        };
        let (width, height) = (size(ex)?, size(ey)?);
        if u64::from(width) * u64::from(height) > MAX_ORTHO_PIXELS {
            return Err(NearfieldError::invalid(
                "pixel size",
                format!("{pixel_m} m needs {width} × {height} pixels; at most {MAX_ORTHO_PIXELS}"),
            ));
        }
        Ok(Self {
            direction: w,
            centre_m: c,
            pixel_m,
            width,
            height,
        })
    }

    /// Area of one pixel perpendicular to ω (m²).
    pub fn pixel_area_m2(&self) -> f64 {
        self.pixel_m * self.pixel_m
    }

    /// Checks direction, pixel size and image size.
    pub fn validate(&self) -> Result<()> {
        if unit(self.direction).is_none() || !self.centre_m.is_finite() {
            return Err(NearfieldError::invalid(
                "orthographic view",
                "direction must be finite and non-zero, centre finite",
            ));
        }
        if !self.pixel_m.is_finite() || self.pixel_m <= 0.0 {
            return Err(NearfieldError::invalid("pixel size", "must be finite and > 0"));
        }
        if self.width == 0
            || self.height == 0
            || self.width > 65_536
            || self.height > 65_536
            || u64::from(self.width) * u64::from(self.height) > MAX_ORTHO_PIXELS
        {
            return Err(NearfieldError::invalid(
                "orthographic view",
                format!(
                    "{}×{} px is outside 1…65536 a side or too many pixels",
                    self.width, self.height
                ),
            ));
        }
        Ok(())
    }

    /// The ray through pixel coordinates (u, v) (pixel centres at +0.5): an origin in front of
    /// everything within `reach_m` of the centre, and the direction −ω.
    fn ray(&self, basis: &(DVec3, DVec3, DVec3), u: f64, v: f64, reach_m: f64) -> (DVec3, DVec3) {
        let (right, down, forward) = *basis;
        let p = self.centre_m
            + right * ((u - 0.5 * f64::from(self.width)) * self.pixel_m)
            + down * ((v - 0.5 * f64::from(self.height)) * self.pixel_m);
        (p - forward * reach_m, forward)
    }
}

/// Sum of the supersampled luminance over one row of an orthographic view (not yet divided by n²).
fn ortho_row(lum: &dyn Luminaire, view: &OrthoView, row: u32, n: u32, reach: f64, out: &mut [f32]) -> f64 {
    let w = unit(view.direction).unwrap_or(DVec3::NEG_Z);
    let basis = look_at_basis(-w);
    let inv_n = 1.0 / f64::from(n);
    let weight = inv_n * inv_n;
    let mut row_sum = 0.0;
    for col in 0..view.width {
        let mut s = 0.0;
        for b in 0..n {
            let v = f64::from(row) + (f64::from(b) + 0.5) * inv_n;
            for a in 0..n {
                let u = f64::from(col) + (f64::from(a) + 0.5) * inv_n;
                let (o, d) = view.ray(&basis, u, v, reach);
                s += lum.radiance(o, d);
            }
        }
        if let Some(px) = out.get_mut(col as usize) {
            *px = (s * weight) as f32;
        }
        row_sum += s;
    }
    row_sum
}

/// Distance from the view centre to the farthest box corner plus a metre: ray origins that far along
/// ω lie in front of the whole luminaire.
fn reach(lum: &dyn Luminaire, view: &OrthoView) -> f64 {
    let b = lum.bounds();
    b.corners()
        .iter()
        .map(|p| (*p - view.centre_m).length())
        .fold(0.0, f64::max)
        + 1.0
}

/// Renders an orthographic view (cd/m² per pixel; parallel over rows).
///
/// Errors: an invalid view, more than [`MAX_IMAGE_PIXELS`], or a bad supersampling factor.
pub fn render_ortho(lum: &dyn Luminaire, view: &OrthoView, supersample: u32) -> Result<LuminanceImage> {
    view.validate()?;
    check_image_size("orthographic view", view.width, view.height)?;
    check_supersample(supersample)?;
    let mut img = LuminanceImage::zeros(view.width, view.height);
    let reach = reach(lum, view);
    img.data
        .par_chunks_mut(view.width as usize)
        .enumerate()
        .for_each(|(row, line)| {
            ortho_row(lum, view, row as u32, supersample, reach, line);
        });
    Ok(img)
}

/// Luminous intensity (cd) towards `direction` as the orthographic integral Σ L·ΔA over a view framed
/// by [`OrthoView::framing`] with `pixel_m` pixels and `supersample`² rays each (ΔA = (pixel/n)²).
/// Summed in f64 per row, rows in order: deterministic. Parallel over rows.
///
/// Errors: as [`OrthoView::framing`] and [`check_supersample`].
pub fn ortho_intensity(lum: &dyn Luminaire, direction: DVec3, pixel_m: f64, supersample: u32) -> Result<f64> {
    check_supersample(supersample)?;
    let view = OrthoView::framing(&lum.bounds(), direction, pixel_m)?;
    let reach = reach(lum, &view);
    let rows: Vec<f64> = (0..view.height)
        .into_par_iter()
        .map(|row| ortho_row(lum, &view, row, supersample, reach, &mut []))
        .collect();
    let sub = pixel_m / f64::from(supersample);
    Ok(rows.iter().sum::<f64>() * sub * sub)
}

#[cfg(test)]
mod tests {
    use super::super::luminaire;
    use super::*;
    use crate::nearfield::rayset::{CaptureSphere, Hemisphere};
    use glam::DVec2;

    fn intrinsics(w: u32, h: u32, f: f64) -> Intrinsics {
        Intrinsics {
            width: w,
            height: h,
            principal_px: DVec2::new(f64::from(w) / 2.0, f64::from(h) / 2.0),
            focal_px: DVec2::splat(f),
        }
    }

    #[test]
    fn bounds_cover_everything_lit() {
        let lum = luminaire("two-planes").unwrap();
        let sphere = CaptureSphere {
            centre_m: DVec3::ZERO,
            radius_m: 1.117,
        };
        let k = intrinsics(120, 100, 300.0);
        for d in [
            DVec3::new(0.3, 0.2, -1.0),
            DVec3::new(1.0, 0.0, -0.2),
            DVec3::new(0.0, 0.0, -1.0),
        ] {
            let cam = Camera::on_sphere(&sphere, d, Hemisphere::Lower, "t".into());
            let r = pixel_bounds(&lum.bounds(), &cam, &k).unwrap();
            // Brute force over the whole image: nothing lit outside the rectangle.
            for row in 0..k.height {
                for col in 0..k.width {
                    let dir = cam.to_world(k.ray_camera(f64::from(col) + 0.5, f64::from(row) + 0.5));
                    let l = lum.radiance(cam.position_m, dir);
                    let inside = col >= r.col0 && col < r.col1 && row >= r.row0 && row < r.row1;
                    assert!(inside || l == 0.0, "lit pixel ({col}, {row}) outside {r:?}");
                }
            }
        }
    }

    #[test]
    fn camera_inside_the_box_renders_the_whole_image() {
        let lum = luminaire("two-planes").unwrap();
        let cam = Camera::on_sphere(
            &CaptureSphere {
                centre_m: DVec3::new(0.0, 0.0, 0.02),
                radius_m: 0.001,
            },
            -DVec3::Z,
            Hemisphere::Lower,
            "inside".into(),
        );
        let k = intrinsics(8, 8, 4.0);
        assert_eq!(
            pixel_bounds(&lum.bounds(), &cam, &k),
            Some(PixelRect {
                col0: 0,
                col1: 8,
                row0: 0,
                row1: 8
            })
        );
    }

    #[test]
    fn bad_arguments_are_errors() {
        let lum = luminaire("disc").unwrap();
        assert!(ortho_intensity(lum.as_ref(), -DVec3::Z, 0.0, 1).is_err());
        assert!(ortho_intensity(lum.as_ref(), DVec3::ZERO, 0.001, 1).is_err());
        assert!(ortho_intensity(lum.as_ref(), -DVec3::Z, 1e-9, 1).is_err());
        assert!(ortho_intensity(lum.as_ref(), -DVec3::Z, 0.001, 0).is_err());
        assert!(ortho_intensity(lum.as_ref(), -DVec3::Z, f64::NAN, 1).is_err());
    }
}
