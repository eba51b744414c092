//! The proxy from the scan itself: the luminous surfaces recovered from the capture images and
//! their poses, as a triangle mesh for parallax-correct rendering.
//!
//! **Status: under development (issue 17); nothing in `pack`, `render` or the C API calls it yet.**
//! The masks, the octree, the mesh and the Chamfer measure are tested; the carving rule is not yet
//! right for one-sided emitters. Measured on synthetic scans (rigo:300 per hemisphere, 256 × 256 px,
//! 1024 cameras at most): a dark camera behind a one-sided emitter carves it away under the plain
//! visual-hull rule (`two-planes` lost its front tiles; `led-dots` vanished: point-sampled dots are
//! missed by grazing cameras), and the one-sided rule in [`carve`] keeps a rim of cells that only
//! grazing cameras see (Chamfer p95 15 % of the diameter for `disc`) and costs minutes.
//!
//! 1. **Cameras**: up to [`ReconstructOptions::max_cameras`], spread evenly over the directions of
//!    the scan's cameras (the one nearest each point of a Fibonacci sphere).
//! 2. **Masks** ([`mask`]): each image's lit pixels (at or above
//!    [`ReconstructOptions::lit_relative`] of its own maximum), kept as runs per row plus a coarse
//!    distance map. Cameras whose brightest pixel is below [`ReconstructOptions::camera_relative`]
//!    of the brightest camera's see the back of the source or nothing: they carry no evidence and
//!    are left out (a dark camera cannot tell "empty" from "not emitting this way").
//! 3. **Carving** ([`carve`]): the content ball (where any camera saw light) in a cube, split as an
//!    octree down to cells of about one capture pixel's footprint (at most
//!    [`ReconstructOptions::max_cells`] per axis); a cell is empty when one camera that sees all of it
//!    sees only darkness there. What survives is the lit visual hull: the intersection of the
//!    cones of light every informative camera saw.
//! 4. **Mesh** ([`mesh`]): naive surface nets over the surviving cells, Taubin-smoothed within each
//!    cell.
//!
//! The hull encloses the light (it is a bound, not the surface itself): concave or layered sources
//! are filled in. Pure CPU, both cores (rayon); memory is the masks (a few tens of KB per camera)
//! plus one byte per finest cell.

pub mod carve;
pub mod hemisphere;
pub mod mask;
pub mod mesh;

use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;

use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::rayset::{LuminanceImage, RayImageSet};

pub use carve::{Occupancy, View};
pub use mask::LitMask;
pub use mesh::{chamfer, Chamfer, Mesh};

/// How [`reconstruct`] works.
#[derive(Debug, Clone, PartialEq)]
pub struct ReconstructOptions {
    /// Most cameras read (spread evenly over the scan's directions); default 1024.
    pub max_cameras: usize,
    /// Most cells per axis of the finest carving level (rounded down to 8·2ᵏ); default 256.
    pub max_cells: usize,
    /// A pixel is lit at or above this fraction of its image's maximum; default 1e-4.
    pub lit_relative: f32,
    /// A camera is used when its maximum is at least this fraction of the brightest camera's;
    /// default 1e-6.
    pub camera_relative: f32,
}

impl Default for ReconstructOptions {
    fn default() -> Self {
        Self {
            max_cameras: 1024,
            max_cells: 256,
            lit_relative: 1e-4,
            camera_relative: 1e-6,
        }
    }
}

impl ReconstructOptions {
    /// Checks every value.
    pub fn validate(&self) -> Result<()> {
        if self.max_cameras < 4 {
            return Err(NearfieldError::invalid(
                "reconstruct.max_cameras",
                format!("{} is below 4", self.max_cameras),
            ));
        }
        if !(16..=1024).contains(&self.max_cells) {
            return Err(NearfieldError::invalid(
                "reconstruct.max_cells",
                format!("{} is outside 16…1024", self.max_cells),
            ));
        }
        for (v, name) in [
            (self.lit_relative, "reconstruct.lit_relative"),
            (self.camera_relative, "reconstruct.camera_relative"),
        ] {
            if !(v.is_finite() && v > 0.0 && v < 1.0) {
                return Err(NearfieldError::invalid(name, format!("{v} is outside (0, 1)")));
            }
        }
        Ok(())
    }
}

/// What [`reconstruct`] did.
#[derive(Debug, Clone, PartialEq)]
pub struct ReconstructReport {
    /// Cameras read.
    pub cameras_read: usize,
    /// Cameras that saw enough light to carve.
    pub cameras_used: usize,
    /// Radius (m) of the ball about the capture centre where light was seen.
    pub content_radius_m: f64,
    /// Edge of a finest cell (m).
    pub voxel_m: f64,
    /// Finest cells per axis.
    pub cells_per_axis: usize,
    /// Cells kept.
    pub occupied_cells: usize,
    /// Triangles of the mesh.
    pub triangles: usize,
    /// Cube-against-camera tests made.
    pub tests: u64,
    /// Bytes of the masks held.
    pub mask_bytes: usize,
    /// Seconds reading images and building masks, carving, meshing.
    pub seconds: [f64; 3],
}

/// A reconstructed proxy.
#[derive(Debug, Clone)]
pub struct Reconstruction {
    /// The mesh (m, luminaire frame), enclosing the light.
    pub mesh: Mesh,
    /// The carved cells.
    pub occupancy: Occupancy,
    /// What was done.
    pub report: ReconstructReport,
}

/// Progress of [`reconstruct`]: `(stage, done, total)`, stage `"masks"` or `"carving"`.
pub type Progress<'a> = &'a (dyn Fn(&str, usize, usize) + Sync);

/// Recovers the surfaces where the scan's light appears from `set`'s cameras and their images
/// (`image(i)` gives camera i's luminance in cd/m²).
///
/// Errors: invalid options, an image error (as `image` reports it, naming the image), or a scan in
/// which no camera saw light ([`NearfieldError::InvalidArgument`] on `scan`).
pub fn reconstruct(
    set: &RayImageSet,
    image: &(dyn Fn(usize) -> Result<LuminanceImage> + Sync),
    opts: &ReconstructOptions,
    progress: Progress,
) -> Result<Reconstruction> {
    opts.validate()?;
    let t0 = Instant::now();
    let chosen = spread_cameras(set, opts.max_cameras);
    let done = std::sync::atomic::AtomicUsize::new(0);
    let masks: Vec<Option<LitMask>> = chosen
        .par_iter()
        .map(|&i| {
            let img = image(i)?;
            let m = LitMask::of(&img, opts.lit_relative);
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress("masks", d, chosen.len());
            Ok(m)
        })
        .collect::<Result<_>>()?;
    let brightest = masks.iter().flatten().map(|m| m.max_cd_m2).fold(0.0f32, f32::max);
    if brightest <= 0.0 {
        return Err(NearfieldError::invalid(
            "scan",
            format!(
                "none of the {} cameras read sees any light: nothing to reconstruct",
                chosen.len()
            ),
        ));
    }
    let centre = set.sphere.centre_m;
    let mut views = Vec::new();
    let mut content: f64 = 0.0;
    let mut footprint = f64::INFINITY;
    for (&i, m) in chosen.iter().zip(masks) {
        let Some(m) = m else { continue };
        if m.max_cd_m2 < opts.camera_relative * brightest {
            continue;
        }
        let cam = &set.cameras[i];
        let k = *set.intrinsics_of(i);
        let d = (cam.position_m - centre).length();
        if let Some([c0, c1, r0, r1]) = m.lit_box() {
            for (u, v) in [(c0, r0), (c1, r0), (c0, r1), (c1, r1)] {
                let ray = k.ray_camera(u, v);
                content = content.max(d * (ray.x * ray.x + ray.y * ray.y).sqrt());
            }
        }
        footprint = footprint.min(d / k.focal_px.x.max(k.focal_px.y));
        views.push(View {
            camera: cam.clone(),
            intrinsics: k,
            mask: m,
        });
    }
    let content = (content * 1.02).min(set.sphere.radius_m * 0.999);
    let mask_bytes = views.iter().map(|v| v.mask.bytes()).sum();
    let t1 = Instant::now();
    // Finest cell: about one capture pixel's footprint at the centre, at most max_cells per axis.
    let max_levels = (opts.max_cells / carve::BASE_CELLS).max(1).ilog2();
    let want = (2.0 * content / (carve::BASE_CELLS as f64 * footprint))
        .max(1.0)
        .log2()
        .ceil() as u32;
    let levels = want.clamp(1, max_levels);
    let occupancy = carve::carve(&views, centre, content, content, levels, &|d, t| {
        progress("carving", d as usize, t as usize)
    });
    let t2 = Instant::now();
    let mesh = mesh::surface_nets(&occupancy);
    let t3 = Instant::now();
    let report = ReconstructReport {
        cameras_read: chosen.len(),
        cameras_used: views.len(),
        content_radius_m: content,
        voxel_m: occupancy.voxel_m,
        cells_per_axis: occupancy.n,
        occupied_cells: occupancy.count(),
        triangles: mesh.triangles.len(),
        tests: occupancy.tests,
        mask_bytes,
        seconds: [
            (t1 - t0).as_secs_f64(),
            (t2 - t1).as_secs_f64(),
            (t3 - t2).as_secs_f64(),
        ],
    };
    Ok(Reconstruction {
        mesh,
        occupancy,
        report,
    })
}

/// Up to `max` camera indices spread evenly over the directions of `set`'s cameras from the
/// capture centre: the camera nearest each point of a Fibonacci sphere of `max` points (all
/// cameras when there are at most `max`), in index order.
pub fn spread_cameras(set: &RayImageSet, max: usize) -> Vec<usize> {
    let n = set.cameras.len();
    if n <= max {
        return (0..n).collect();
    }
    let dirs: Vec<DVec3> = set
        .cameras
        .iter()
        .map(|c| c.direction_from(set.sphere.centre_m))
        .collect();
    let mut picked: Vec<usize> = crate::nearfield::raykde::bandwidth::fibonacci(max)
        .into_par_iter()
        .map(|p| {
            let mut best = (f64::NEG_INFINITY, 0usize);
            for (i, d) in dirs.iter().enumerate() {
                let c = d.dot(p);
                if c > best.0 {
                    best = (c, i);
                }
            }
            best.1
        })
        .collect();
    picked.sort_unstable();
    picked.dedup();
    picked
}
