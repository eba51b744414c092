//! Synthetic scans: cameras laid out on the capture sphere (`layout.rs`), shared pinhole intrinsics
//! that frame the luminaire, and a [`SynthSource`] that ray-casts each camera's image on demand.

use std::sync::Arc;

use glam::DVec2;
use rayon::prelude::*;

use super::raycast::{check_supersample, render_pinhole};
use super::{luminaire, Luminaire};
use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::layout::{self, Layout};
use crate::nearfield::rayset::{CaptureSphere, ImageSource, Intrinsics, LuminanceImage, RayImageSet, Scan};

/// Image size of the reference goniophotometer's camera (px).
pub const FULL_SIZE: (u32, u32) = (1216, 1021);

/// The reference capture radius (m).
pub const DEFAULT_RADIUS_M: f64 = 1.117;

/// Default framing: the luminaire's bounding sphere spans this fraction of the image's shorter side.
pub const DEFAULT_FILL: f64 = 0.8;

/// Options of [`synth_scan`].
#[derive(Debug, Clone, PartialEq)]
pub struct SynthOptions {
    /// Registry name of the luminaire ([`super::NAMES`]).
    pub luminaire: String,
    /// Camera layout on the capture sphere.
    pub layout: Layout,
    /// Capture radius (m), centred at the photometric centre. Must exceed the luminaire's extent.
    pub radius_m: f64,
    /// Image size (px) when `intrinsics` is `None`.
    pub size: (u32, u32),
    /// Full field of view across the image height (degrees) when `intrinsics` is `None`; `None` frames
    /// the luminaire: its bounding sphere seen from the capture sphere spans [`DEFAULT_FILL`] of the
    /// shorter image side.
    pub fov_deg: Option<f64>,
    /// Explicit intrinsics (overrides `size` and `fov_deg`).
    pub intrinsics: Option<Intrinsics>,
    /// Rays per pixel: supersample² (1: point sample at the pixel centre).
    pub supersample: u32,
    /// Seed of the layout's jitter.
    pub seed: u64,
}

impl Default for SynthOptions {
    /// `disc`, a full-size `rigo` layout (28,000 cameras per hemisphere, 2° overlap, 0.05° jitter),
    /// r = 1.117 m, 1216 × 1021 px framing the luminaire, point samples, seed 0.
    fn default() -> Self {
        Self {
            luminaire: "disc".into(),
            layout: Layout::Rigo {
                per_hemisphere: 28_000,
                overlap_deg: 2.0,
                jitter_deg: 0.05,
            },
            radius_m: DEFAULT_RADIUS_M,
            size: FULL_SIZE,
            fov_deg: None,
            intrinsics: None,
            supersample: 1,
            seed: 0,
        }
    }
}

/// Intrinsics of `width × height` px with square pixels, the principal point at the image centre and
/// a vertical field of view `fov_deg` (full angle).
///
/// Errors: a zero or oversized image (argument `size`), or a field of view outside (0, 180)° (argument
/// `fov`).
pub fn intrinsics_for_fov(width: u32, height: u32, fov_deg: f64) -> Result<Intrinsics> {
    if !(fov_deg.is_finite() && fov_deg > 0.0 && fov_deg < 180.0) {
        return Err(NearfieldError::invalid(
            "fov",
            format!("{fov_deg}° is outside (0, 180)°"),
        ));
    }
    let f = 0.5 * f64::from(height) / (0.5 * fov_deg.to_radians()).tan();
    let k = Intrinsics {
        width,
        height,
        principal_px: DVec2::new(0.5 * f64::from(width), 0.5 * f64::from(height)),
        focal_px: DVec2::splat(f),
    };
    k.validate("size")?;
    Ok(k)
}

/// Intrinsics of `width × height` px that frame `lum` from every camera on a sphere of `radius_m`
/// around the origin: the angular radius of the luminaire's bounding sphere (as seen from the capture
/// sphere at its closest) spans [`DEFAULT_FILL`] of half the shorter image side.
///
/// Errors: as [`intrinsics_for_fov`], or the capture sphere does not enclose the luminaire (argument
/// `radius`).
pub fn framing_intrinsics(lum: &dyn Luminaire, width: u32, height: u32, radius_m: f64) -> Result<Intrinsics> {
    let b = lum.bounds();
    let extent = b.centre().length() + b.radius();
    check_radius(lum, radius_m)?;
    let alpha = (extent / radius_m).asin();
    let half_short = 0.5 * f64::from(width.min(height));
    let f = DEFAULT_FILL * half_short / alpha.tan();
    let k = Intrinsics {
        width,
        height,
        principal_px: DVec2::new(0.5 * f64::from(width), 0.5 * f64::from(height)),
        focal_px: DVec2::splat(f),
    };
    k.validate("size")?;
    Ok(k)
}

fn check_radius(lum: &dyn Luminaire, radius_m: f64) -> Result<()> {
    let b = lum.bounds();
    let extent = b.centre().length() + b.radius();
    if !(radius_m.is_finite() && radius_m > extent) {
        return Err(NearfieldError::invalid(
            "radius",
            format!(
                "{radius_m} m: the capture sphere must enclose '{}' (extent {extent:.4} m from the centre)",
                lum.name()
            ),
        ));
    }
    Ok(())
}

/// Renders the images of a scan's cameras by exact ray casting of an analytic luminaire. Deterministic,
/// `Send + Sync`; each [`ImageSource::image`] call renders on the calling thread.
#[derive(Debug, Clone)]
pub struct SynthSource {
    luminaire: Arc<dyn Luminaire>,
    set: Arc<RayImageSet>,
    supersample: u32,
}

impl SynthSource {
    /// A source rendering `set`'s cameras of `luminaire` with `supersample`² rays per pixel.
    ///
    /// Errors: an invalid set or supersampling factor.
    pub fn new(luminaire: Arc<dyn Luminaire>, set: RayImageSet, supersample: u32) -> Result<Self> {
        set.validate()?;
        check_supersample(supersample)?;
        Ok(Self {
            luminaire,
            set: Arc::new(set),
            supersample,
        })
    }

    /// The luminaire.
    pub fn luminaire(&self) -> &Arc<dyn Luminaire> {
        &self.luminaire
    }

    /// The cameras, sphere and intrinsics rendered.
    pub fn set(&self) -> &RayImageSet {
        &self.set
    }

    /// Number of images (cameras).
    pub fn len(&self) -> usize {
        self.set.cameras.len()
    }

    /// Whether there are no images.
    pub fn is_empty(&self) -> bool {
        self.set.cameras.is_empty()
    }

    /// All images, rendered in parallel on all cores (rayon), in camera order. Holds every image in
    /// memory: for small scans and tests (a full-size scan needs ~280 GB; render it image by image).
    ///
    /// Errors: the first failing image.
    pub fn render_all(&self) -> Result<Vec<LuminanceImage>> {
        render_all(self, self.len())
    }
}

impl ImageSource for SynthSource {
    fn image(&self, index: usize) -> Result<LuminanceImage> {
        let cam = self.set.cameras.get(index).ok_or_else(|| {
            NearfieldError::invalid(
                "image index",
                format!("{index} is outside 0…{}", self.set.cameras.len()),
            )
        })?;
        let k = self.set.intrinsics_of(index);
        render_pinhole(self.luminaire.as_ref(), cam, k, self.supersample)
    }
}

/// Images `0..count` of `source`, rendered in parallel on all cores (rayon), in index order.
///
/// Errors: the first failing image.
pub fn render_all(source: &dyn ImageSource, count: usize) -> Result<Vec<LuminanceImage>> {
    (0..count).into_par_iter().map(|i| source.image(i)).collect()
}

/// The cameras and intrinsics of a synthetic scan of `opts.luminaire` (no images yet).
///
/// Errors: an unknown luminaire, bad layout, radius, size, field of view, intrinsics or supersampling
/// factor, each naming its argument.
pub fn synth_set(opts: &SynthOptions) -> Result<(Arc<dyn Luminaire>, RayImageSet)> {
    let lum: Arc<dyn Luminaire> = Arc::from(luminaire(&opts.luminaire)?);
    check_radius(lum.as_ref(), opts.radius_m)?;
    check_supersample(opts.supersample)?;
    let (w, h) = opts.size;
    let intrinsics = match (&opts.intrinsics, opts.fov_deg) {
        (Some(k), _) => {
            k.validate("intrinsics")?;
            *k
        }
        (None, Some(fov)) => intrinsics_for_fov(w, h, fov)?,
        (None, None) => framing_intrinsics(lum.as_ref(), w, h, opts.radius_m)?,
    };
    if intrinsics.pixel_count() as u64 > super::raycast::MAX_IMAGE_PIXELS {
        return Err(NearfieldError::invalid(
            "size",
            format!(
                "{}×{} px is more than {} pixels per image",
                intrinsics.width,
                intrinsics.height,
                super::raycast::MAX_IMAGE_PIXELS
            ),
        ));
    }
    let sphere = CaptureSphere {
        centre_m: glam::DVec3::ZERO,
        radius_m: opts.radius_m,
    };
    let cameras = layout::cameras(&sphere, &opts.layout, opts.seed)?;
    let set = RayImageSet {
        sphere,
        intrinsics,
        cameras,
    };
    set.validate()?;
    Ok((lum, set))
}

/// A synthetic scan: the cameras of `opts.layout` on the capture sphere, looking at the centre, and a
/// [`SynthSource`] that renders their images on demand (nothing is rendered here).
///
/// Errors: as [`synth_set`].
pub fn synth_scan(opts: &SynthOptions) -> Result<Scan> {
    let (lum, set) = synth_set(opts)?;
    let source = SynthSource::new(lum, set.clone(), opts.supersample)?;
    Ok(Scan {
        set,
        source: Box::new(source),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pole_cameras_turn_with_their_meridian() {
        let (_, set) = synth_set(&SynthOptions {
            layout: Layout::Rigo {
                per_hemisphere: 2000,
                overlap_deg: 2.0,
                jitter_deg: 0.05,
            },
            size: (16, 16),
            ..SynthOptions::default()
        })
        .unwrap();
        set.validate().unwrap();
        let groups = set.coincident_groups(1e-6);
        assert_eq!(groups.len(), 2, "one group per pole");
        for g in groups {
            // Same position, pairwise different orientations; the next camera along each meridian
            // has nearly the same image axes as its pole camera.
            for (a, &i) in g.iter().enumerate() {
                for &j in &g[a + 1..] {
                    assert!(set.cameras[i].right.dot(set.cameras[j].right) < 1.0 - 1e-6);
                }
                let (p, n) = (&set.cameras[i], &set.cameras[i + 1]);
                assert!(p.down.dot(n.down) > 0.99, "camera {i}: {} vs {}", p.down, n.down);
                assert!(p.right.dot(n.right) > 0.99);
            }
        }
    }

    #[test]
    fn bad_options_name_their_argument() {
        let base = SynthOptions {
            layout: Layout::Fibonacci { count: 4 },
            size: (32, 24),
            ..SynthOptions::default()
        };
        let err = |o: SynthOptions| synth_scan(&o).unwrap_err().to_string();
        assert!(err(SynthOptions {
            luminaire: "x".into(),
            ..base.clone()
        })
        .contains("luminaire"));
        assert!(err(SynthOptions {
            radius_m: 0.05,
            ..base.clone()
        })
        .contains("radius"));
        assert!(err(SynthOptions {
            radius_m: f64::NAN,
            ..base.clone()
        })
        .contains("radius"));
        assert!(err(SynthOptions {
            size: (0, 10),
            ..base.clone()
        })
        .contains("size"));
        assert!(err(SynthOptions {
            size: (65_536, 65_536),
            ..base.clone()
        })
        .contains("size"));
        assert!(err(SynthOptions {
            fov_deg: Some(180.0),
            ..base.clone()
        })
        .contains("fov"));
        assert!(err(SynthOptions {
            supersample: 0,
            ..base.clone()
        })
        .contains("supersample"));
        assert!(err(SynthOptions {
            layout: Layout::Fibonacci { count: 0 },
            ..base.clone()
        })
        .contains("fibonacci"));
        let scan = synth_scan(&base).unwrap();
        assert!(scan.source.image(4).is_err());
        assert_eq!(scan.source.image(3).unwrap().width, 32);
    }
}
