//! The proxy from the scan itself: the luminous surfaces recovered from the capture images and
//! their poses, as a triangle mesh for parallax-correct rendering.
//!
//! **Status (issue 17, in progress):** `lumiview pack` (manifests, `--synth`) and the loaders of
//! `render` and `lumi_luminaire_load` (manifests) store it as the pack's proxy through
//! [`scan_proxy`]; `lumiview proxy` writes it as glTF and measures it (docs/proxy.md). Measured on
//! synthetic scans (rigo:300, 256 × 256 px, 3 × 3 rays per pixel): Chamfer p95 within the limit
//! for 10 of the 11 luminaires (flat sources, beams, small features, `peak`'s 10⁶ cd/m² spot on a
//! 1 cd/m² background); nothing useful survives for `reflector` (a mirror): that scan renders
//! without a proxy, with a warning.
//!
//! 1. **Cameras**: up to [`ReconstructOptions::max_cameras`], spread evenly over the directions of
//!    the scan's cameras (the one nearest each point of a Fibonacci sphere).
//! 2. **Masks** ([`mask`]): each image's lit pixels (at or above
//!    [`ReconstructOptions::lit_relative`] of its own maximum and above its noise,
//!    [`LitMask::above_noise`]), kept as runs per row plus a coarse
//!    distance map. Cameras whose brightest pixel is below [`ReconstructOptions::camera_relative`]
//!    of the brightest camera's see the back of the source or nothing: every pixel of theirs counts
//!    as dark, unless they lie on the lit side (within 90° of the mean direction of the cameras
//!    that see light): they are outside a beam and are not used. The masks are then made again
//!    down to [`ReconstructOptions::deep_relative`] of each image's maximum, but above its noise
//!    ([`LitMask::above_noise`]), and everything below is done again with them when the first
//!    masks' mesh explains less than [`MIN_COVERAGE`] of the light and these light
//!    [`DEEP_MIN_GAIN`] more pixels (the result that explains more is kept), or when these light
//!    [`DEEP_TRIGGER_GAIN`] more (kept when it explains enough of its light): a dim background
//!    beside a bright spot.
//! 3. **Carving** ([`carve`]): the content ball (where any camera saw light) in a cube, split as an
//!    octree down to cells of about one capture pixel's footprint (at most
//!    [`ReconstructOptions::max_cells`] per axis). A coarse cell is empty when a camera that sees all
//!    of it sees only darkness there and none sees light in it; a finest cell survives when no camera
//!    sees it dark, or when the cameras that see it lit and those that see it dark fit one emitter
//!    facing a half-space (the dark ones see its back; dark cameras within
//!    [`ReconstructOptions::grazing_deg`] of its plane are not counted; when that explains less
//!    than [`MIN_COVERAGE`] of the light, again within [`SMALL_FEATURE_GRAZING_DEG`]: small features
//!    that point-sampled cameras missed edge-on).
//! 4. **Mesh** ([`mesh`]): naive surface nets over the surviving cells, Taubin-smoothed within each
//!    cell; thin parts collapsed onto their middle, a beam's lens along its axis onto the plane
//!    of its rim ([`mesh::collapse_thin`]).
//! 5. **Flat parts** ([`refine`]): each part that is flat within a cell (and the parts too small to
//!    be, together) is put on the plane its cameras' images agree on (luminance consistency), with
//!    the vertices of a lens in front of it that the cameras see better on the plane; small parts
//!    are redrawn as polygons and lines (a 1 mm strip) as flat bands from the images. The images
//!    read here are the carved ones, or finer ones of the same cameras where given
//!    ([`reconstruct_refined`], [`FineImages`]: a synthetic scan carved from captures rendered
//!    again at 256 px refines from its own captures, as a real scan's reads its images).
//! 6. **Lean flat parts** ([`simplify`]): only the triangles each flat part's outline needs.
//! 7. **Check** ([`coverage`]): the fraction of lit pixels whose line of sight meets the carved
//!    volume; [`scan_proxy`] drops a mesh below [`MIN_COVERAGE`] (a surface proxy would hide the
//!    light it misses).
//!
//! Luminance consistency is used for flat parts only: a curved emitter keeps its carved surface,
//! about a cell off, and what is hidden behind a lit surface from every camera is filled in. Pure
//! CPU, both cores (rayon); memory is the masks (runs of the lit rows and distances around them:
//! 3.5 KB a camera for the full-size disc), one bit per finest cell, one octree level's split
//! cells, the mesh's per-vertex tables and the refinement's cropped images (at most
//! [`REFINE_PIXELS`], two bytes each, or [`REFINE_MIN_CAMERAS`] crops), whatever the number of
//! images; freed memory goes back to the system between the stages ([`crate::memory`]).

pub mod carve;
pub mod hemisphere;
pub mod mask;
pub mod mesh;
pub mod refine;
pub mod simplify;

use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;

use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::pack::PackProxy;
use crate::nearfield::rayset::{Intrinsics, LuminanceImage, RayImageSet, Scan};
use crate::nearfield::synth::{pixel_bounds, Aabb};

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
    /// A pixel is lit at or above this fraction of its image's maximum (and above the image's
    /// noise, [`LitMask::above_noise`]); default 1e-4.
    pub lit_relative: f32,
    /// A camera is used when its maximum is at least this fraction of the brightest camera's;
    /// default 1e-6.
    pub camera_relative: f32,
    /// The masks are made again down to this fraction of each image's maximum, but above its noise
    /// ([`LitMask::above_noise`]), and the scan carved again with them when they light more pixels
    /// ([`reconstruct`], step 2 of the module's list); equal to [`Self::lit_relative`] or above:
    /// never. Default 1e-7: `peak`'s 1 cd/m² background beside its 10⁶ cd/m² spot.
    pub deep_relative: f32,
    /// Dark cameras within this angle (degrees) of a surface's plane do not carve it (a camera that
    /// samples points can miss a surface seen that obliquely); default 1. Below
    /// [`SMALL_FEATURE_GRAZING_DEG`], a carving that explains too little of the light is tried
    /// again with that.
    pub grazing_deg: f64,
    /// Thin parts of the carved volume (a flat emitter's lens) are collapsed onto their middle when
    /// thinner than this fraction of the content's diameter ([`mesh::collapse_thin`]); 0 keeps the
    /// carved surface. Default 0.05.
    pub thin_fraction: f64,
    /// When the one-sided rule leaves a mesh that explains less than [`MIN_COVERAGE`] of the light
    /// (beams, small features), carve again with [`carve::Rule::Directional`] and keep whichever
    /// explains more. Default false: experimental (docs/proxy.md: it keeps most of the content
    /// ball, takes minutes and gives meshes of up to a million triangles).
    pub directional_fallback: bool,
    /// Move flat parts onto the plane the cameras agree on ([`refine`]); default true.
    pub refine_flat: bool,
    /// Then keep only the triangles each flat part's outline needs ([`simplify`]); default true.
    pub simplify: bool,
}

impl Default for ReconstructOptions {
    fn default() -> Self {
        Self {
            max_cameras: 1024,
            max_cells: 256,
            lit_relative: 1e-4,
            camera_relative: 1e-6,
            deep_relative: 1e-7,
            grazing_deg: 1.0,
            thin_fraction: 0.05,
            directional_fallback: false,
            refine_flat: true,
            simplify: true,
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
            (self.deep_relative, "reconstruct.deep_relative"),
        ] {
            if !(v.is_finite() && v > 0.0 && v < 1.0) {
                return Err(NearfieldError::invalid(name, format!("{v} is outside (0, 1)")));
            }
        }
        if !(0.0..45.0).contains(&self.grazing_deg) {
            return Err(NearfieldError::invalid(
                "reconstruct.grazing_deg",
                format!("{} is outside [0, 45)", self.grazing_deg),
            ));
        }
        if !(0.0..=0.5).contains(&self.thin_fraction) {
            return Err(NearfieldError::invalid(
                "reconstruct.thin_fraction",
                format!("{} is outside [0, 0.5]", self.thin_fraction),
            ));
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
    /// The masks' threshold, as a fraction of each image's maximum:
    /// [`ReconstructOptions::lit_relative`], or [`ReconstructOptions::deep_relative`] when the masks
    /// made above the images' noise were kept.
    pub lit_relative: f32,
    /// Lit pixels of the masks of the cameras that carve.
    pub lit_pixels: u64,
    /// Cameras whose masks' threshold was set by their image's noise rather than by
    /// `lit_relative` (0 for noise-free images).
    pub noise_floored: usize,
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
    /// Fraction of the lit pixels (sampled over up to 64 cameras) whose line of sight meets the
    /// carved volume: how much of the light the proxy explains (1: all of it).
    pub coverage: f64,
    /// Mesh vertices moved onto the middle of a thin part ([`mesh::collapse_thin`]); 0 when
    /// nothing was thin or the collapse was undone because it explained less of the light.
    pub collapsed_vertices: usize,
    /// [`Self::coverage`] of the collapsed mesh itself (cells it passes through, grown by one), or
    /// of the carved volume when nothing was collapsed.
    pub collapsed_coverage: f64,
    /// Triangles of small disconnected parts dropped (fewer than [`STRAY_FRACTION`] of the
    /// mesh's each, explaining no light the rest does not).
    pub stray_triangles: usize,
    /// Whether the directional rule's carving was kept (the one-sided rule's explained too little).
    pub directional: bool,
    /// The grazing tolerance (degrees) of the one-sided carving kept: [`ReconstructOptions::grazing_deg`],
    /// or [`SMALL_FEATURE_GRAZING_DEG`] when that explained more of the light (0 for the directional
    /// rule).
    pub grazing_deg: f64,
    /// The flat parts moved onto the plane their cameras agree on ([`refine`]), one entry each.
    pub flat_parts: Vec<refine::PlaneFit>,
    /// What [`simplify`] did (triangles before, vertices collapsed).
    pub simplified: simplify::Simplified,
    /// Seconds reading images and building masks, carving, meshing, refining and simplifying flat
    /// parts (reading their images again included).
    pub seconds: [f64; 4],
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

impl Reconstruction {
    /// The mesh as a `.lvpack` stores a proxy: a surface (not a bound), its source saying how it
    /// was made.
    pub fn to_pack_proxy(&self) -> PackProxy {
        let r = &self.report;
        PackProxy {
            triangles: self.mesh.soup(),
            bound: PROXY_IS_BOUND,
            source: format!(
                "reconstructed from the scan ({} of {} cameras carving, {:.2} mm cells, {} triangles)",
                r.cameras_used,
                r.cameras_read,
                r.voxel_m * 1e3,
                r.triangles
            ),
        }
    }
}

/// Rays per pixel edge of the synthetic captures a synthetic scan's proxy is reconstructed from
/// (`pack --synth`, `proxy --synth`, `eval --reconstructed-proxy`): the synthetic goniophotometer
/// otherwise samples pixel centres, and a camera that does misses surfaces seen edge-on that a real
/// one, integrating over its pixel, sees.
pub const CAPTURE_SUPERSAMPLE: u32 = 3;

/// Whether a reconstructed proxy is stored as a bound (the renderer samples the images plainly and
/// dark cameras vote) rather than a surface (only cameras that see light vote where any does).
pub const PROXY_IS_BOUND: bool = false;

/// When the one-sided carving explains less than [`MIN_COVERAGE`] of the light, the scan is carved
/// again with dark cameras within this angle (degrees) of a surface's plane not counted, and the
/// carving that explains more is kept. Small features seen edge-on are missed by a camera that
/// samples points instead of integrating its pixels: a 3 mm dot seen at elevation e covers
/// 3 mm · sin e across, thinner than the 0.32 mm between the rays of a 3 × 3-sampled 0.95 mm pixel
/// below 6° (`led-dots`), a 1 mm strip thinner than 0.51 mm below 31° (`strips`), so those cameras
/// carved them away. The lens this leaves in front of a source is as thick as the source is wide
/// times tan 30°: a small feature's is thin enough for the thin-part collapse, a wide source's
/// would not be, and a wide source is explained at 1°.
pub const SMALL_FEATURE_GRAZING_DEG: f64 = 30.0;

/// Largest thickness, as a fraction of the content's diameter, collapsed after directional carving
/// (which keeps the space in front of and behind a flat source: the whole content ball across).
pub const DIRECTIONAL_THIN_FRACTION: f64 = 1.0;

/// Most coverage (fraction of the lit pixels) the thin-part collapse may lose against the carved
/// volume's before it is undone.
pub const COLLAPSE_COVERAGE_LOSS: f64 = 0.02;

/// Connected parts of the mesh with fewer than this fraction of its triangles are dropped when
/// that loses at most [`STRAY_COVERAGE_LOSS`] of the light: carving leaves slivers of space that
/// only cameras at the layout's grazing ring could have carved (star-panel: wires 21 mm in front of
/// the panel, 22–72 vertices each), and a surface proxy draws them in front of the light.
pub const STRAY_FRACTION: f64 = 0.01;

/// Most coverage (fraction of the lit pixels) dropping the stray parts may lose.
pub const STRAY_COVERAGE_LOSS: f64 = 0.002;

/// Least [`ReconstructReport::coverage`] of a proxy [`scan_proxy`] keeps: a mesh that misses more
/// of the light would hide it (a surface proxy shows light only where it is).
pub const MIN_COVERAGE: f64 = 0.8;

/// The proxy stored for a scan given without one (by `lumiview pack`, and by `render` and
/// `lumi_luminaire_load` when they pack a manifest): [`reconstruct`] with the default options.
/// `Ok(None)` with a warning naming `what` when nothing could be recovered (no camera saw light,
/// or nothing survived carving): the scan then renders without a proxy, as before.
///
/// Errors: an image that cannot be read (as the scan's source reports it).
pub fn scan_proxy(
    scan: &Scan,
    what: &str,
    progress: Progress,
    warnings: &mut Vec<String>,
) -> Result<Option<Reconstruction>> {
    scan_proxy_refined(scan, None, what, progress, warnings)
}

/// [`scan_proxy`], refining from `fine` images where given ([`reconstruct_refined`]).
///
/// Errors: as [`scan_proxy`].
pub fn scan_proxy_refined(
    scan: &Scan,
    fine: Option<FineImages>,
    what: &str,
    progress: Progress,
    warnings: &mut Vec<String>,
) -> Result<Option<Reconstruction>> {
    let rec = match reconstruct_refined(
        &scan.set,
        &|i| scan.source.image(i),
        fine,
        &ReconstructOptions::default(),
        progress,
    ) {
        Ok(rec) => rec,
        Err(NearfieldError::InvalidArgument { name, message }) if name == "scan" => {
            warnings.push(format!("{what}: no proxy reconstructed: {message}"));
            return Ok(None);
        }
        Err(e) => return Err(e),
    };
    if rec.mesh.triangles.is_empty() || rec.report.coverage < MIN_COVERAGE {
        if !rec.mesh.triangles.is_empty() {
            warnings.push(format!(
                "{what}: the reconstructed proxy was dropped: it explains {:.1} % of the lit pixels (below {:.0} %); \
                 the scan renders without a proxy",
                rec.report.coverage * 100.0,
                MIN_COVERAGE * 100.0
            ));
            return Ok(None);
        }
        warnings.push(format!(
            "{what}: no proxy reconstructed: no luminous surface survived carving ({} cameras, {:.2} mm cells); \
             the scan renders without a proxy",
            rec.report.cameras_used,
            rec.report.voxel_m * 1e3
        ));
        return Ok(None);
    }
    Ok(Some(rec))
}

/// Progress of [`reconstruct`]: `(stage, done, total)`, stage `"masks"` or `"carving"`.
pub type Progress<'a> = &'a (dyn Fn(&str, usize, usize) + Sync);

/// Recovers the surfaces where the scan's light appears from `set`'s cameras and their images
/// (`image(i)` gives camera i's luminance in cd/m²).
///
/// Errors: invalid options, an image error (as `image` reports it, naming the image), or a scan in
/// which no camera saw light above its noise ([`NearfieldError::InvalidArgument`] on `scan`).
pub fn reconstruct(
    set: &RayImageSet,
    image: &(dyn Fn(usize) -> Result<LuminanceImage> + Sync),
    opts: &ReconstructOptions,
    progress: Progress,
) -> Result<Reconstruction> {
    reconstruct_refined(set, image, None, opts, progress)
}

/// The images the refinement reads when they differ from the ones carved: the same cameras, in the
/// same order, at a finer resolution. A synthetic scan's reconstruction carves its captures
/// rendered again at most 256 px across (as a sensor integrates; `eval --reconstructed-proxy`) and
/// refines from them at the captures' own resolution, as a real scan's reconstruction reads its
/// images: a 1 mm strip is 0.65 of a 1.54 mm pixel, and no image that coarse says how wide it is.
#[derive(Clone, Copy)]
pub struct FineImages<'a> {
    /// The cameras (the carved set's poses, in its order) with the fine intrinsics.
    pub set: &'a RayImageSet,
    /// Camera `i`'s image cut to columns `[c0, c1)` and rows `[r0, r1)` (`[c0, c1, r0, r1]`),
    /// luminance in cd/m².
    pub window: &'a (dyn Fn(usize, [u32; 4]) -> Result<LuminanceImage> + Sync),
}

/// [`reconstruct`], refining from `fine` images where given.
///
/// Errors: as [`reconstruct`]; `fine` with other cameras than `set`'s
/// ([`NearfieldError::InvalidArgument`] on `fine`).
pub fn reconstruct_refined(
    set: &RayImageSet,
    image: &(dyn Fn(usize) -> Result<LuminanceImage> + Sync),
    fine: Option<FineImages>,
    opts: &ReconstructOptions,
    progress: Progress,
) -> Result<Reconstruction> {
    opts.validate()?;
    if let Some(f) = fine {
        let same = |a: &crate::nearfield::rayset::Camera, b: &crate::nearfield::rayset::Camera| {
            (a.position_m, a.right, a.down, a.forward) == (b.position_m, b.right, b.down, b.forward)
        };
        if f.set.cameras.len() != set.cameras.len() || !f.set.cameras.iter().zip(&set.cameras).all(|(a, b)| same(a, b))
        {
            return Err(NearfieldError::invalid(
                "fine",
                "the fine images' cameras are not the scan's",
            ));
        }
    }
    let deep = opts.deep_relative < opts.lit_relative;
    let (first, deep_lit_pixels) =
        reconstruct_with(set, image, fine, opts, Masks::Relative { count_deep: deep }, progress)?;
    if !deep {
        return Ok(first);
    }
    // Light below the masks' threshold beside a much brighter spot (peak): every camera that sees
    // the spot carves it. Looked for again above the images' noise when the mesh explains too
    // little of the light, or when those masks light far more pixels (the coverage is sampled
    // over 64 cameras, and the few that miss the spot, which see the dim surface lit, may be
    // among them or not).
    let explained = first.report.coverage >= MIN_COVERAGE;
    let gain = if explained { DEEP_TRIGGER_GAIN } else { DEEP_MIN_GAIN };
    let more_than = (1.0 + gain) * first.report.lit_pixels as f64;
    // Counted while the first masks were made: the images are read again only to carve.
    if deep_lit_pixels as f64 <= more_than {
        return Ok(first);
    }
    let first_s = first.report.seconds;
    let (deep, _) = reconstruct_with(set, image, fine, opts, Masks::AboveNoise, progress)?;
    let deep_s = deep.report.seconds;
    // Taken when it explains more of the light, or (the first explaining enough of its own) when
    // it explains enough of its larger share.
    let take = if explained {
        deep.report.coverage >= MIN_COVERAGE.max(first.report.coverage - DEEP_COVERAGE_SLACK)
    } else {
        deep.report.coverage > first.report.coverage
    };
    let mut best = if take { deep } else { first };
    best.report.seconds = std::array::from_fn(|k| first_s[k] + deep_s[k]);
    Ok(best)
}

/// How [`reconstruct_with`] makes the masks.
#[derive(Clone, Copy, PartialEq)]
enum Masks {
    /// [`LitMask::above_noise`] at [`ReconstructOptions::lit_relative`] (as [`LitMask::of`] for an
    /// image whose noise lies below that); with `count_deep`, the pixels
    /// [`Self::AboveNoise`]'s masks would light are counted too.
    Relative { count_deep: bool },
    /// [`LitMask::above_noise`] at [`ReconstructOptions::deep_relative`].
    AboveNoise,
}

/// When the first masks' mesh explains too little of the light, the masks made above the noise are
/// carved only when they light at least this fraction more pixels than the first masks: else (a
/// noisy camera whose noise lies above 10⁻⁴ of its maximum, a mirror) carving them again would
/// give the same result at twice the cost.
pub const DEEP_MIN_GAIN: f64 = 0.01;

/// When the first masks' mesh explains enough of the light, the masks made above the noise are
/// still carved when they light at least this fraction more pixels (a dim surface the first masks
/// left out) ...
pub const DEEP_TRIGGER_GAIN: f64 = 0.1;

/// ... and that mesh is taken when it explains at least [`MIN_COVERAGE`] of its light and no less
/// than the first's coverage minus this.
pub const DEEP_COVERAGE_SLACK: f64 = 0.02;

/// [`reconstruct`] with one kind of masks. Also: the pixels the masks above the noise would light
/// in the cameras that would carve with them (counted with `Masks::Relative { count_deep: true }`,
/// else 0), which decides whether they add anything without reading the images again.
///
/// Errors: as [`reconstruct`]; a scan in which no camera read sees light, or whose masks light no
/// pixel of a camera that carves (every image's light within its noise).
fn reconstruct_with(
    set: &RayImageSet,
    image: &(dyn Fn(usize) -> Result<LuminanceImage> + Sync),
    fine: Option<FineImages>,
    opts: &ReconstructOptions,
    masks_kind: Masks,
    progress: Progress,
) -> Result<(Reconstruction, u64)> {
    let t0 = Instant::now();
    let chosen = spread_cameras(set, opts.max_cameras);
    let done = std::sync::atomic::AtomicUsize::new(0);
    let (masks, deep_counts): (Vec<Option<LitMask>>, Vec<u64>) = chosen
        .par_iter()
        .map(|&i| {
            let img = image(i)?;
            let sigma = mask::noise_sigma(&img);
            let (m, deep) = match masks_kind {
                Masks::Relative { count_deep } => (
                    LitMask::above_noise_with(&img, opts.lit_relative, sigma),
                    if count_deep {
                        LitMask::count_above_noise_with(&img, opts.deep_relative, sigma).unwrap_or(0)
                    } else {
                        0
                    },
                ),
                Masks::AboveNoise => (LitMask::above_noise_with(&img, opts.deep_relative, sigma), 0),
            };
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress("masks", d, chosen.len());
            Ok((m, deep))
        })
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .unzip();
    // The images read are freed: their pages go back before carving (each stage's peak then stands
    // on what is in use, not on what the allocator kept from the one before).
    crate::memory::return_freed_memory();
    let lit_relative = match masks_kind {
        Masks::Relative { .. } => opts.lit_relative,
        Masks::AboveNoise => opts.deep_relative,
    };
    let noise_floored = masks
        .iter()
        .flatten()
        .filter(|m| m.floor_cd_m2 > lit_relative * m.max_cd_m2 * 1.001)
        .count();
    let brightest = masks.iter().flatten().map(|m| m.max_cd_m2).fold(0.0f32, f32::max);
    // A camera sees light when its brightest pixel is not far below the brightest camera's and
    // some pixel of its mask is lit (above its image's noise, when the masks are made so).
    let sees_light = |m: &LitMask| m.max_cd_m2 >= opts.camera_relative * brightest && m.lit_pixels > 0;
    // As `lit_pixels` below would count them with the masks above the noise: a camera carves with
    // those when its brightest pixel is bright enough and they light some pixel.
    let deep_lit_pixels: u64 = masks
        .iter()
        .zip(&deep_counts)
        .filter(|(m, _)| {
            m.as_ref()
                .is_some_and(|m| m.max_cd_m2 >= opts.camera_relative * brightest)
        })
        .map(|(_, n)| n)
        .sum();
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
    // The side the light comes out of: the mean direction towards the cameras that see it (zero
    // when it comes out of every side alike).
    let lit_axis = chosen
        .iter()
        .zip(&masks)
        .filter(|(_, m)| m.as_ref().is_some_and(sees_light))
        .map(|(&i, _)| set.cameras[i].direction_from(centre))
        .sum::<DVec3>()
        .normalize_or_zero();
    let mut views = Vec::new();
    // Cameras on the lit side that see no light: the scan holds a beam.
    let mut outside_beam = 0usize;
    let mut content: f64 = 0.0;
    let mut footprint = f64::INFINITY;
    for (&i, m) in chosen.iter().zip(masks) {
        let Some(mut m) = m else { continue };
        let cam = &set.cameras[i];
        if !sees_light(&m) {
            if cam.direction_from(centre).dot(lit_axis) > 0.0 {
                outside_beam += 1;
                // On the lit side, yet no light: outside a beam. Its darkness says nothing about
                // where the source is (counted as dark, the cameras beyond 75° of cos10's axis,
                // which see its front, carved it away).
                continue;
            }
            // Sees the back of the source or nothing: all dark (the one-sided test takes that as
            // the back of an emitter, not as empty space).
            let (w, h) = m.size();
            m = LitMask::unlit(w, h);
        }
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
    // Lit pixels of the cameras that carve (a camera that sees no light counts none, whatever its
    // noise lit).
    let lit_pixels: u64 = views.iter().map(|v| v.mask.lit_pixels).sum();
    if lit_pixels == 0 {
        return Err(NearfieldError::invalid(
            "scan",
            "no camera read sees any light above its noise: nothing to reconstruct",
        ));
    }
    let content = (content * 1.02).min(set.sphere.radius_m * 0.999);
    let mask_bytes = views.iter().map(|v| v.mask.bytes()).sum();
    // Every prefix spread over the sphere (the chosen cameras are in index order, often by ring).
    let mut slots: Vec<Option<View>> = views.into_iter().map(Some).collect();
    let views: Vec<View> = carve::spread_order(slots.len())
        .into_iter()
        .filter_map(|i| slots[i].take())
        .collect();
    let t1 = Instant::now();
    // Finest cell: about one capture pixel's footprint at the centre, at most max_cells per axis.
    let max_levels = (opts.max_cells / carve::BASE_CELLS).max(1).ilog2();
    let want = (2.0 * content / (carve::BASE_CELLS as f64 * footprint))
        .max(1.0)
        .log2()
        .ceil() as u32;
    let levels = want.clamp(1, max_levels);
    let grazing = opts.grazing_deg.to_radians().sin();
    let run = |rule: carve::Rule, thin_fraction: f64, stage: &str| {
        let t = Instant::now();
        let occupancy = carve::carve(&views, centre, content, content, levels, rule, &|d, t| {
            progress(stage, d as usize, t as usize)
        });
        let carve_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        // A beam's lens is collapsed along its axis only when some camera saw the beam from
        // outside (a part that only steep cameras see lit, such as a lens's floating bottom
        // under a sparsely scanned disc, is no beam).
        let beam_thin_m = if outside_beam > 0 { 2.0 * content } else { 0.0 };
        crate::memory::return_freed_memory();
        progress("meshing", 0, 1);
        let attempt = Attempt::mesh(&views, occupancy, rule, thin_fraction * 2.0 * content, beam_thin_m);
        progress("meshing", 1, 1);
        (attempt, carve_s, t.elapsed().as_secs_f64())
    };
    let (mut best, mut carve_s, mut mesh_s) = run(carve::Rule::OneSided { grazing }, opts.thin_fraction, "carving");
    if best.coverage < MIN_COVERAGE && opts.grazing_deg < SMALL_FEATURE_GRAZING_DEG {
        let (other, c, m) = run(
            carve::Rule::OneSided {
                grazing: SMALL_FEATURE_GRAZING_DEG.to_radians().sin(),
            },
            opts.thin_fraction,
            "carving (small features)",
        );
        (carve_s, mesh_s) = (carve_s + c, mesh_s + m);
        if other.coverage > best.coverage {
            best = other;
        }
    }
    if opts.directional_fallback && best.coverage < MIN_COVERAGE {
        let (other, c, m) = run(
            carve::Rule::Directional,
            DIRECTIONAL_THIN_FRACTION,
            "carving (directional)",
        );
        (carve_s, mesh_s) = (carve_s + c, mesh_s + m);
        if other.coverage > best.coverage {
            best = other;
        }
    }
    let Attempt {
        occupancy,
        mut mesh,
        rule,
        coverage,
        collapsed_vertices,
        collapsed_coverage,
        stray_triangles,
    } = best;
    let cameras_used = views.len();
    drop(views);
    crate::memory::return_freed_memory();
    // Flat parts onto the plane the images agree on, from up to REFINE_CAMERAS cameras spread over
    // the sphere (read again: the masks kept no luminance), within REFINE_PIXELS.
    let t_refine = Instant::now();
    let flat_parts = if opts.refine_flat && !mesh.triangles.is_empty() {
        // Each image cut to where the mesh's box (grown by the refinement's reach) projects; at most
        // REFINE_PIXELS pixels held together (a full-size image is 1.24 M), at least
        // REFINE_MIN_CAMERAS cameras.
        let reach = 4.0 * occupancy.voxel_m.max(footprint);
        let (lo, hi) = mesh.vertices.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), v| (lo.min(*v), hi.max(*v)),
        );
        let bounds = Aabb {
            min: lo - DVec3::splat(reach),
            max: hi + DVec3::splat(reach),
        };
        let refine_set = fine.map_or(set, |f| f.set);
        let mut held = 0usize;
        let picks: Vec<(usize, [u32; 4])> = carve::spread_order(chosen.len())
            .into_iter()
            .map(|k| chosen[k])
            .map(|i| (i, box_crop(refine_set, i, &bounds)))
            .take_while(|(_, [c0, c1, r0, r1])| {
                held += (c1 - c0) as usize * (r1 - r0) as usize;
                held <= REFINE_PIXELS
            })
            .take(REFINE_CAMERAS)
            .collect();
        let picks = if picks.len() >= REFINE_MIN_CAMERAS {
            picks
        } else {
            let order = carve::spread_order(chosen.len());
            order
                .into_iter()
                .take(REFINE_MIN_CAMERAS)
                .map(|k| (chosen[k], box_crop(refine_set, chosen[k], &bounds)))
                .collect()
        };
        // One image at a time: each is read whole (5 MB at full size) and only its crop kept; read
        // two at once, the allocator kept 13 MB more resident (full-size disc).
        let shots: Vec<refine::Shot> = picks
            .iter()
            .map(|&(i, crop)| {
                let (intrinsics, image) = match fine {
                    Some(f) => {
                        let img = (f.window)(i, crop)?;
                        let k = window_intrinsics(f.set.intrinsics_of(i), crop);
                        if (img.width, img.height) != (k.width, k.height) {
                            return Err(NearfieldError::invalid(
                                "fine",
                                format!(
                                    "camera {i}'s window is {}×{} px, asked for {}×{}",
                                    img.width, img.height, k.width, k.height
                                ),
                            ));
                        }
                        (k, img)
                    }
                    None => cropped(set.intrinsics_of(i), &image(i)?, crop),
                };
                Ok(refine::Shot {
                    camera: set.cameras[i].clone(),
                    intrinsics,
                    image: refine::Crop::of(&image),
                })
            })
            .collect::<Result<_>>()?;
        crate::memory::return_freed_memory();
        progress("refining", 0, 1);
        let fits = refine::refine_flat_parts(&mut mesh, occupancy.voxel_m.max(footprint), &shots);
        progress("refining", 1, 1);
        fits
    } else {
        Vec::new()
    };
    let simplified = if opts.simplify {
        let planes: Vec<(DVec3, DVec3)> = flat_parts.iter().map(|f| (f.point_m, f.normal)).collect();
        let (lean, s) = simplify::simplify_flat(&mesh, &planes, occupancy.voxel_m.max(footprint));
        mesh = lean;
        s
    } else {
        simplify::Simplified::default()
    };
    // What the caller does next (`lumiview pack` writes the pack) starts from what is in use.
    crate::memory::return_freed_memory();
    let report = ReconstructReport {
        cameras_read: chosen.len(),
        cameras_used,
        lit_relative,
        lit_pixels,
        noise_floored,
        content_radius_m: content,
        voxel_m: occupancy.voxel_m,
        cells_per_axis: occupancy.n,
        occupied_cells: occupancy.count(),
        triangles: mesh.triangles.len(),
        tests: occupancy.tests,
        mask_bytes,
        coverage,
        collapsed_vertices,
        collapsed_coverage,
        stray_triangles,
        directional: rule == carve::Rule::Directional,
        grazing_deg: match rule {
            carve::Rule::OneSided { grazing } => grazing.asin().to_degrees(),
            carve::Rule::Directional => 0.0,
        },
        flat_parts,
        simplified,
        seconds: [
            (t1 - t0).as_secs_f64(),
            carve_s,
            mesh_s,
            t_refine.elapsed().as_secs_f64(),
        ],
    };
    Ok((
        Reconstruction {
            mesh,
            occupancy,
            report,
        },
        deep_lit_pixels,
    ))
}

/// The pixels `[c0, c1) × [r0, r1)` of camera `i`'s image that can show `bounds` (luminaire
/// frame, m): [`crate::nearfield::synth::pixel_bounds`], one pixel wider each way; one pixel when the
/// camera sees none of it.
fn box_crop(set: &RayImageSet, i: usize, bounds: &Aabb) -> [u32; 4] {
    let k = set.intrinsics_of(i);
    match pixel_bounds(bounds, &set.cameras[i], k) {
        Some(r) => [
            r.col0.saturating_sub(1),
            (r.col1 + 1).min(k.width),
            r.row0.saturating_sub(1),
            (r.row1 + 1).min(k.height),
        ],
        None => [0, 1, 0, 1],
    }
}

/// `img` (taken with `k`) cut to `[c0, c1) × [r0, r1)`, with the intrinsics of the cut image.
fn cropped(k: &Intrinsics, img: &LuminanceImage, [c0, c1, r0, r1]: [u32; 4]) -> (Intrinsics, LuminanceImage) {
    let (c1, r1) = (c1.min(img.width), r1.min(img.height));
    let (c0, r0) = (c0.min(c1.saturating_sub(1)), r0.min(r1.saturating_sub(1)));
    let mut out = LuminanceImage::zeros(c1 - c0, r1 - r0);
    for r in r0..r1 {
        let src = (r * img.width + c0) as usize..(r * img.width + c1) as usize;
        let dst = ((r - r0) * out.width) as usize..((r - r0 + 1) * out.width) as usize;
        out.data[dst].copy_from_slice(&img.data[src]);
    }
    (window_intrinsics(k, [c0, c1, r0, r1]), out)
}

/// The intrinsics of the image `k` takes, cut to `[c0, c1) × [r0, r1)` (at least one pixel each
/// way).
pub fn window_intrinsics(k: &Intrinsics, [c0, c1, r0, r1]: [u32; 4]) -> Intrinsics {
    Intrinsics {
        width: c1.saturating_sub(c0).max(1),
        height: r1.saturating_sub(r0).max(1),
        principal_px: k.principal_px - glam::DVec2::new(f64::from(c0), f64::from(r0)),
        focal_px: k.focal_px,
    }
}

/// Cameras read again for [`refine`], at most ...
pub const REFINE_CAMERAS: usize = 64;
/// ... and as many as hold at most this many pixels together (each image cut to where the content
/// can be, 16 MiB as f16, 6.8 whole full-size 1216 × 1021 images; the refinement holds only each
/// crop's rows between their first and last lit pixel: [`refine::Crop`]), but at least
/// [`REFINE_MIN_CAMERAS`].
pub const REFINE_PIXELS: usize = 1 << 23;
/// Cameras read again for [`refine`] whatever their pixels. The refinement of lines depends on
/// which cameras it reads (2026-11-27, session 27): strips refined from 1024 px images came out
/// 2.2 % too large and 4.8° tilted with 16 cameras of 2²² pixels, 1.1 % and 2.7° with the cameras
/// 2²³ pixels hold; at the contract's pitch rule (2,354 px) 24 cameras drew strips' orthographic
/// intensity up to 49.8 % off against 5.9 % with 16. So the budget was left as it is: 2²² pixels
/// with at least 24 cameras, tried for memory, changed what the refinement sees.
pub const REFINE_MIN_CAMERAS: usize = 16;

/// One carving rule's result, meshed and checked.
struct Attempt {
    occupancy: Occupancy,
    mesh: Mesh,
    rule: carve::Rule,
    coverage: f64,
    collapsed_vertices: usize,
    collapsed_coverage: f64,
    stray_triangles: usize,
}

impl Attempt {
    /// Meshes `occupancy`, collapses its parts thinner than `max_thin_m` (a beam's lens, along
    /// its axis, up to `beam_thin_m`; 0: no beams) unless that hides light, and measures the
    /// coverage.
    fn mesh(views: &[View], occupancy: Occupancy, rule: carve::Rule, max_thin_m: f64, beam_thin_m: f64) -> Self {
        let mut mesh = mesh::surface_nets(&occupancy);
        let carved = coverage(views, &occupancy);
        let (mut collapsed_vertices, mut collapsed_coverage) = (0, carved);
        if max_thin_m > 0.0 && !mesh.triangles.is_empty() {
            let mut thin = mesh.clone();
            let axes = if beam_thin_m > 0.0 {
                beam_axes(&mesh, views)
            } else {
                Vec::new()
            };
            let moved = mesh::collapse_thin(&mut thin, &occupancy, max_thin_m, &axes, beam_thin_m);
            if moved > 0 {
                let c = coverage(views, &mesh::cells_of(&thin, &occupancy));
                // The collapse must not hide light the carved volume explained (a thin tube
                // collapsed to a line would).
                if c >= carved - COLLAPSE_COVERAGE_LOSS {
                    mesh = thin;
                    collapsed_vertices = moved;
                    collapsed_coverage = c;
                }
            }
        }
        let (kept, stray_triangles) = mesh::without_small_components(&mesh, STRAY_FRACTION);
        // The mesh's own coverage: measured above when the collapse was kept.
        let stray_triangles = if stray_triangles > 0 && {
            let before = if collapsed_vertices > 0 {
                collapsed_coverage
            } else {
                coverage(views, &mesh::cells_of(&mesh, &occupancy))
            };
            coverage(views, &mesh::cells_of(&kept, &occupancy)) >= before - STRAY_COVERAGE_LOSS
        } {
            mesh = kept;
            stray_triangles
        } else {
            0
        };
        Self {
            occupancy,
            coverage: if mesh.triangles.is_empty() { 0.0 } else { carved },
            mesh,
            rule,
            collapsed_vertices,
            collapsed_coverage,
            stray_triangles,
        }
    }
}

/// Half-angle (degrees) of the cone about its mean within which every camera that sees a part of
/// the carved surface lit lies, below which the part is a beam's lens (`beam_axes`). A source
/// seen from every direction of its half-space leaves a lens a few cells thick (the cameras 1°
/// above its plane carve it); cos10 is seen within 75.5° of its axis (beyond, under 10⁻⁶ of its
/// peak), cos100 within 29°.
pub const BEAM_CONE_DEG: f64 = 80.0;

/// Vertices of each connected part sampled by [`beam_axes`].
const BEAM_SAMPLES: usize = 64;

/// Per vertex of `mesh` (the carved surface): the axis of the beam its connected part emits, or
/// `None`. From up to [`BEAM_SAMPLES`] vertices of the part, the directions towards the views that
/// see light at them; their mean is the axis when all but 1 % of them lie within
/// [`BEAM_CONE_DEG`] of it.
fn beam_axes(mesh: &Mesh, views: &[View]) -> Vec<Option<DVec3>> {
    let component = mesh::components(mesh);
    let members = mesh::members(&component);
    let cone_cos = BEAM_CONE_DEG.to_radians().cos();
    let axis_of: std::collections::BTreeMap<u32, DVec3> = members
        .par_iter()
        .filter_map(|(&c, vs)| {
            let step = vs.len().div_ceil(BEAM_SAMPLES).max(1);
            let mut dirs = Vec::new();
            for &i in vs.iter().step_by(step) {
                let p = mesh.vertices[i];
                for v in views {
                    let Some(px) = v.intrinsics.project(v.camera.to_camera(p - v.camera.position_m)) else {
                        continue;
                    };
                    if v.mask.dark(px.x, px.y, 0.5) == Some(false) {
                        dirs.push((v.camera.position_m - p).normalize_or_zero());
                    }
                }
            }
            let axis = dirs.iter().copied().sum::<DVec3>().normalize_or_zero();
            if dirs.len() < 16 || axis == DVec3::ZERO {
                return None;
            }
            let outside = dirs.iter().filter(|d| d.dot(axis) < cone_cos).count();
            (outside * 100 <= dirs.len()).then_some((c, axis))
        })
        .collect();
    component.iter().map(|c| axis_of.get(c).copied()).collect()
}

/// Fraction of the lit pixels of up to 64 views (the first in `views`' order; up to 2000 pixels
/// each) whose line of sight passes through or beside (one cell) an occupied cell of `occ` (1 when
/// no pixel is lit). Beside: a pixel is lit when any of its light is, so its centre may look just
/// past a silhouette.
pub fn coverage(views: &[View], occ: &Occupancy) -> f64 {
    let occ = &dilated(occ);
    let (hit, all) = views
        .iter()
        .filter(|v| v.mask.lit_pixels > 0)
        .take(64)
        .collect::<Vec<_>>()
        .par_iter()
        .map(|v| {
            let pts = v.mask.lit_centres(2000);
            let hits = pts
                .iter()
                .filter(|&&(u, w)| {
                    let dir = v.camera.to_world(v.intrinsics.ray_camera(u, w)).normalize_or_zero();
                    meets(occ, v.camera.position_m, dir)
                })
                .count();
            (hits, pts.len())
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    if all == 0 {
        1.0
    } else {
        hit as f64 / all as f64
    }
}

/// `occ` grown by one cell (26-neighbourhood): three separable passes.
fn dilated(occ: &Occupancy) -> Occupancy {
    let n = occ.n;
    let mut cells = occ.cells.clone();
    for stride in [1, n, n * n] {
        let src = cells.clone();
        for i in 0..src.len() {
            let k = (i / stride) % n;
            let on = src.get(i) || (k > 0 && src.get(i - stride)) || (k + 1 < n && src.get(i + stride));
            cells.set(i, on);
        }
    }
    occ.with_cells(cells)
}

/// Whether the ray from `origin` along unit `dir` passes through an occupied cell (sampled every
/// half cell inside the grid).
fn meets(occ: &Occupancy, origin: DVec3, dir: DVec3) -> bool {
    let lo = occ.origin;
    let hi = occ.origin + DVec3::splat(occ.voxel_m * occ.n as f64);
    // Slab test.
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for a in 0..3 {
        if dir[a].abs() < 1e-15 {
            if origin[a] < lo[a] || origin[a] > hi[a] {
                return false;
            }
            continue;
        }
        let (ta, tb) = ((lo[a] - origin[a]) / dir[a], (hi[a] - origin[a]) / dir[a]);
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
    }
    if t0 > t1 {
        return false;
    }
    let step = occ.voxel_m * 0.5;
    let mut t = t0 + step * 0.5;
    while t < t1 {
        let p = (origin + dir * t - lo) / occ.voxel_m;
        if occ.at(p.x.floor() as i64, p.y.floor() as i64, p.z.floor() as i64) {
            return true;
        }
        t += step;
    }
    false
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
