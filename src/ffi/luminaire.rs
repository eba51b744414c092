//! Luminaires and instances: load from a file (photometry or a near-field scan), query,
//! host-lighting look-up tables, instances with model matrices and near-field settings, and the CPU
//! illuminance a host's lighting should reproduce.

use std::ffi::c_char;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::context::{with_context, ContextInner};
use super::handle;
use super::{lumi_status, path_arg, write_out, FfiError, LUMI_STATUS_BUFFER_TOO_SMALL};
use crate::gpu::nearfield::{NearfieldOptions, DEFAULT_BUDGET_BYTES};
use crate::gpu::renderer::Luminaire;
use crate::gpu::{Arg, GpuError, LogLevel, LuminaireId};
use crate::photometry::{OpeningShape, Photometry};
use crate::source::{self, Source, SourceError, SourceOptions};

/// Handle of a luminaire, owned by its context (0 is never a valid handle).
pub type lumi_luminaire = u64;
/// Handle of an instance, owned by its context (0 is never a valid handle).
pub type lumi_instance = u64;

/// Luminaire kind: far-field photometry (IES LM-63 or EULUMDAT).
pub const LUMI_LUMINAIRE_FARFIELD: u32 = 0;
/// Luminaire kind: a near-field scan (`.lvpack`, JSON scan manifest or TM-25 ray file) drawn with
/// its measured luminance. The far-field-only calls (`lumi_luminaire_sample`, `lumi_luminaire_lut`,
/// `lumi_instance_illuminance`) refuse it with `LUMI_STATUS_INVALID_ARGUMENT`.
pub const LUMI_LUMINAIRE_NEARFIELD: u32 = 1;

/// Opening shapes reported by `lumi_luminaire_get_info` (values fixed).
pub const LUMI_OPENING_POINT: u32 = 0;
/// Flat rectangle (extents X × Y).
pub const LUMI_OPENING_RECTANGLE: u32 = 1;
/// Box with luminous sides, centred on the photometric centre (z from −Z/2 to +Z/2).
pub const LUMI_OPENING_BOX: u32 = 2;
/// Flat ellipse / disc.
pub const LUMI_OPENING_ELLIPSE: u32 = 3;
/// Vertical cylinder.
pub const LUMI_OPENING_VERTICAL_CYLINDER: u32 = 4;
/// Ellipsoid / sphere.
pub const LUMI_OPENING_ELLIPSOID: u32 = 5;
/// Horizontal cylinder along X (the C0–C180 axis; an IES file's length).
pub const LUMI_OPENING_HORIZONTAL_CYLINDER_X: u32 = 6;
/// Horizontal cylinder along Y (the C90–C270 axis; an IES file's width).
pub const LUMI_OPENING_HORIZONTAL_CYLINDER_Y: u32 = 7;
/// Vertical ellipse facing C0.
pub const LUMI_OPENING_VERTICAL_ELLIPSE_C0: u32 = 8;
/// Vertical ellipse facing C90.
pub const LUMI_OPENING_VERTICAL_ELLIPSE_C90: u32 = 9;
/// EULUMDAT rectangle in z = 0 with luminous side walls rising from it (+Z) to their heights.
pub const LUMI_OPENING_RECTANGLE_WITH_SIDES: u32 = 10;
/// EULUMDAT disc in z = 0 with a luminous side wall rising from it (+Z) to its height.
pub const LUMI_OPENING_DISC_WITH_SIDES: u32 = 11;

/// Facts about a luminaire. Units: cd, lm, m. The far-field fields (`max_intensity_cd` …
/// `housing_size_m`) are 0 (`opening_shape` `LUMI_OPENING_POINT`) for a near-field luminaire, and
/// the near-field fields (`camera_count` … `budget_bytes`) are 0 / false for a far-field one.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct lumi_luminaire_info {
    /// `LUMI_LUMINAIRE_FARFIELD` or `LUMI_LUMINAIRE_NEARFIELD`.
    pub kind: u32,
    /// Largest intensity (cd) and its direction (C, γ in degrees, lumiview's Type C frame), at
    /// a C angle the file stores (not the mirror image of a symmetric file).
    pub max_intensity_cd: f64,
    /// C angle of the maximum, degrees.
    pub max_c_deg: f64,
    /// γ angle of the maximum, degrees.
    pub max_gamma_deg: f64,
    /// Luminous flux integrated from the intensity distribution (lm).
    pub flux_lm: f64,
    /// One of `LUMI_OPENING_*`.
    pub opening_shape: u32,
    /// Opening extents along X (C0–C180), Y (C90–C270) and Z, metres. An IES file's length is X,
    /// its width Y; an EULUMDAT file's width is X, its length Y (docs/conventions.md). For the
    /// `_WITH_SIDES` shapes Z is the tallest side height. Where each shape sits relative to the
    /// photometric centre: docs/conventions.md, "Where the opening sits".
    pub opening_size_m: [f64; 3],
    /// Housing extents along X, Y and Z in metres (EULUMDAT luminaire dimensions: width along X,
    /// length along Y); all 0 when the file gives none.
    pub housing_size_m: [f64; 3],
    /// Near-field: capture cameras (images) in the scan.
    pub camera_count: u32,
    /// Near-field: the luminaire has a proxy mesh (loaded from `lumi_luminaire_desc.proxy_path`, or
    /// the one stored in the scan's `.lvpack`, e.g. the grown hull of a ray file's ray origins).
    pub has_proxy: bool,
    /// Near-field: centre of the capture sphere in the luminaire frame, metres.
    pub capture_centre_m: [f64; 3],
    /// Near-field: radius of the capture sphere (the cameras' distance from its centre), metres.
    pub capture_radius_m: f64,
    /// Near-field: radius of the ball around the capture centre that holds everything the cameras
    /// saw (`lumi_luminaire_desc.content_radius_m`, or derived from the scan), metres.
    pub content_radius_m: f64,
    /// Near-field: bytes of GPU memory the luminaire holds (never above `budget_bytes`).
    pub gpu_bytes: u64,
    /// Near-field: the GPU budget it was loaded with (`lumi_luminaire_desc.budget_bytes`), bytes.
    pub budget_bytes: u64,
}

/// How to load a luminaire (`lumi_luminaire_load_ex`). Start from `lumi_luminaire_desc_default()`.
/// The near-field fields apply to scans (`.lvpack`, JSON scan manifest, TM-25 ray file); for a
/// photometric file (IES, EULUMDAT) `cache_dir` is ignored, `budget_bytes` is checked (> 0, as for
/// every file) but otherwise unused, and `proxy_path` and `content_radius_m` must keep their
/// defaults (NULL, 0).
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct lumi_luminaire_desc {
    /// Near-field: GPU bytes the luminaire may hold (camera records, selection tables and tile
    /// pool together), > 0; default 512 MiB. A scan that does not fit is streamed: each frame makes
    /// resident the tiles of the cameras the view can select (least recently used evicted); a view
    /// that needs more than the budget fails `lumi_render` with `LUMI_STATUS_INVALID_ARGUMENT`.
    pub budget_bytes: u64,
    /// Near-field: optional proxy mesh, a glTF 2.0 file (`.glb`, or `.gltf` with its buffers) of the
    /// surfaces where the luminance appears, in the luminaire frame with glTF's axes (+Y up: glTF
    /// (X, Y, Z) is luminaire (X, −Z, Y)), metres, inside the capture sphere. NUL-terminated UTF-8,
    /// borrowed for the call; NULL for the scan's own proxy where its `.lvpack` stores one (a TM-25
    /// ray file's scan does: the hull of its ray origins), else none. With a proxy, each fragment is
    /// reprojected through its surface point (parallax-correct) and depth comes from the proxy.
    pub proxy_path: *const c_char,
    /// Near-field: radius (m) of the ball around the capture centre holding everything the cameras
    /// saw; 0 derives it from the scan's tile bounding boxes. Otherwise finite, > 0 and below the
    /// capture radius.
    pub content_radius_m: f64,
    /// Folder for the `.lvpack` a manifest or ray file is packed into (created if needed);
    /// NUL-terminated UTF-8, borrowed for the call; NULL for the default: `$LUMIVIEW_CACHE_DIR`,
    /// else `$XDG_CACHE_HOME/lumiview/packs`, else `$HOME/.cache/lumiview/packs`, else
    /// `<temp>/lumiview-cache/packs` (docs/ffi-conventions.md, "Near-field scans").
    pub cache_dir: *const c_char,
}

/// A default luminaire description: budget 512 MiB, no proxy, content radius derived from the scan,
/// default cache folder.
#[no_mangle]
pub extern "C" fn lumi_luminaire_desc_default() -> lumi_luminaire_desc {
    lumi_luminaire_desc {
        budget_bytes: DEFAULT_BUDGET_BYTES,
        proxy_path: std::ptr::null(),
        content_radius_m: 0.0,
        cache_dir: std::ptr::null(),
    }
}

/// The renderer's id of luminaire handle `lum` (argument `arg`) of this context.
pub(crate) fn luminaire_id(c: &ContextInner, lum: lumi_luminaire, arg: &str) -> Result<LuminaireId, FfiError> {
    handle::decode(c.tag, handle::Kind::Luminaire, lum, arg).map(LuminaireId)
}

pub(crate) fn luminaire_of(c: &ContextInner, lum: lumi_luminaire) -> Result<&Luminaire, FfiError> {
    let id = luminaire_id(c, lum, "luminaire")?;
    c.renderer
        .luminaire(id)
        .map_err(|_| FfiError::invalid("luminaire", format!("no luminaire with handle {lum:#x} (destroyed?)")))
}

/// The photometry of luminaire handle `lum`: a far-field file's own, or a near-field scan's far
/// field (estimated from its images on first use, `nearfield::farfield`).
pub(crate) fn photometry_of(c: &ContextInner, lum: lumi_luminaire) -> Result<Arc<Photometry>, FfiError> {
    luminaire_of(c, lum)?;
    Ok(c.renderer.light_of(luminaire_id(c, lum, "luminaire")?)?)
}

/// The near-field description from C, checked.
struct ScanDesc {
    budget_bytes: u64,
    proxy: Option<PathBuf>,
    content_radius_m: Option<f64>,
    cache_dir: Option<PathBuf>,
}

/// Reads a `lumi_luminaire_desc` (NULL: the defaults).
///
/// # Safety
/// `desc` is NULL or valid; its strings NULL or NUL-terminated.
unsafe fn scan_desc(desc: *const lumi_luminaire_desc) -> Result<ScanDesc, FfiError> {
    // SAFETY: NULL or a valid descriptor per the caller's contract.
    let d = unsafe { desc.as_ref() }
        .copied()
        .unwrap_or_else(|| lumi_luminaire_desc_default());
    if d.budget_bytes == 0 {
        return Err(FfiError::invalid("desc.budget_bytes", "must be > 0"));
    }
    if !(d.content_radius_m.is_finite() && d.content_radius_m >= 0.0) {
        return Err(FfiError::invalid(
            "desc.content_radius_m",
            format!(
                "{} must be finite and ≥ 0 (0: derived from the scan)",
                d.content_radius_m
            ),
        ));
    }
    let opt_path = |p: *const c_char, name: &str| -> Result<Option<PathBuf>, FfiError> {
        if p.is_null() {
            Ok(None)
        } else {
            // SAFETY: non-NULL and NUL-terminated per the caller's contract.
            unsafe { path_arg(p, name) }.map(Some)
        }
    };
    Ok(ScanDesc {
        budget_bytes: d.budget_bytes,
        proxy: opt_path(d.proxy_path, "desc.proxy_path")?,
        content_radius_m: (d.content_radius_m > 0.0).then_some(d.content_radius_m),
        cache_dir: opt_path(d.cache_dir, "desc.cache_dir")?,
    })
}

/// Puts the file's name in front of an error's text unless it is there already.
fn in_file(path: &Path, e: FfiError) -> FfiError {
    let p = path.display().to_string();
    if e.message.contains(&p) {
        e
    } else {
        FfiError::new(e.status, format!("{p}: {}", e.message))
    }
}

/// A near-field upload error, with the descriptor's field names.
fn upload_error(e: GpuError) -> FfiError {
    match e {
        GpuError::InvalidArgument { arg, message } => {
            let field = match arg {
                Arg::BudgetBytes => "desc.budget_bytes",
                Arg::ContentRadius => "desc.content_radius_m",
                Arg::Proxy => "desc.proxy_path",
                other => other.name(),
            };
            FfiError::invalid(field, message)
        }
        other => other.into(),
    }
}

/// Loads any luminaire file: a scan (detected by its first bytes) or photometry.
fn load_any(c: &mut ContextInner, path: &Path, d: &ScanDesc) -> Result<LuminaireId, FfiError> {
    let kind = source::detect(path)?;
    if !kind.is_scan() {
        if d.proxy.is_some() {
            return Err(FfiError::invalid(
                "desc.proxy_path",
                format!(
                    "{} is a photometric file, not a near-field scan: no proxy applies",
                    path.display()
                ),
            ));
        }
        if d.content_radius_m.is_some() {
            return Err(FfiError::invalid(
                "desc.content_radius_m",
                format!(
                    "{} is a photometric file, not a near-field scan: must be 0",
                    path.display()
                ),
            ));
        }
    }
    let opts = SourceOptions {
        cache_dir: d.cache_dir.clone(),
        ..SourceOptions::default()
    };
    let mut warnings = Vec::new();
    let opened = source::open(path, kind, &opts, &mut warnings);
    let pack = match opened {
        Ok(Source::Photometry(p)) => {
            // Warnings (each names the file) go to the host's log callback.
            for w in &p.warnings {
                c.renderer.ctx.log(LogLevel::Warning, w);
            }
            return Ok(c.renderer.add_photometry(Arc::new(p))?);
        }
        Ok(Source::Scan { pack, .. }) => pack,
        Err(SourceError::Photometry(e)) => return Err(GpuError::from(e).into()),
        Err(SourceError::Nearfield(e)) => return Err(in_file(path, e.into())),
    };
    for w in &warnings {
        c.renderer
            .ctx
            .log(LogLevel::Warning, &format!("{}: {w}", path.display()));
    }
    // The caller's mesh wins; else the pack's own (a ray file's grown hull bounds the light).
    let (proxy, bound) = match &d.proxy {
        Some(p) => (Some(crate::nearfield::proxy::load_gltf(p)?), false),
        None => match pack.proxy() {
            Some(pp) => (Some(pp.triangles.clone()), pp.bound),
            None => (None, false),
        },
    };
    let opts = NearfieldOptions {
        budget_bytes: d.budget_bytes,
        content_radius_m: d.content_radius_m,
        proxy_is_bound: bound,
        ..NearfieldOptions::default()
    };
    c.renderer
        .add_pack(Arc::new(pack), proxy, &opts)
        .map_err(|e| in_file(path, upload_error(e)))
}

fn shape_code(s: OpeningShape) -> u32 {
    match s {
        OpeningShape::Point => LUMI_OPENING_POINT,
        OpeningShape::Rectangle => LUMI_OPENING_RECTANGLE,
        OpeningShape::Box => LUMI_OPENING_BOX,
        OpeningShape::Ellipse => LUMI_OPENING_ELLIPSE,
        OpeningShape::VerticalCylinder => LUMI_OPENING_VERTICAL_CYLINDER,
        OpeningShape::Ellipsoid => LUMI_OPENING_ELLIPSOID,
        OpeningShape::HorizontalCylinderAlongLength => LUMI_OPENING_HORIZONTAL_CYLINDER_X,
        OpeningShape::HorizontalCylinderAlongWidth => LUMI_OPENING_HORIZONTAL_CYLINDER_Y,
        OpeningShape::VerticalEllipseFacingC0 => LUMI_OPENING_VERTICAL_ELLIPSE_C0,
        OpeningShape::VerticalEllipseFacingC90 => LUMI_OPENING_VERTICAL_ELLIPSE_C90,
        OpeningShape::RectangleWithSides => LUMI_OPENING_RECTANGLE_WITH_SIDES,
        OpeningShape::DiscWithSides => LUMI_OPENING_DISC_WITH_SIDES,
    }
}

/// Loads a luminaire from a file and uploads it, with the defaults of `lumi_luminaire_desc_default()`
/// (`lumi_luminaire_load_ex(ctx, path, NULL, out)`). The format is detected from the file's first
/// bytes:
///
/// - `.lvpack` (magic `LVPACK`): a near-field scan, opened as it is;
/// - a JSON scan manifest (first non-blank character `{`) or an IES TM-25 ray file (magic `TM25`): a
///   near-field scan, packed with default options into a cached `.lvpack` on first load (the cache:
///   `lumi_luminaire_desc.cache_dir`, docs/ffi-conventions.md "Near-field scans"); later loads of
///   the unchanged file only open the cached pack;
/// - anything else: far-field photometry, IES LM-63 (1986–2019) or EULUMDAT (`.ldt`).
///
/// - `path`: NUL-terminated UTF-8 path, borrowed for the call.
/// - `out`: receives the handle (owned by the context; free with `lumi_luminaire_destroy` or by
///   destroying the context); written only on success.
///
/// Errors: `LUMI_STATUS_IO`, `LUMI_STATUS_PARSE` (the text names the file, and the line, field,
/// section or image), `LUMI_STATUS_UNSUPPORTED` (a scan feature lumiview does not read),
/// `LUMI_STATUS_INVALID_ARGUMENT` (a scan whose tables exceed the device's binding limits),
/// `LUMI_STATUS_NULL_POINTER`, `LUMI_STATUS_GPU`, `LUMI_STATUS_OUT_OF_MEMORY`.
///
/// Threading: one thread at a time per context. Packing a large manifest or ray file on first load
/// takes as long as `lumiview pack` (seconds to minutes) and holds the context's lock meanwhile.
///
/// # Safety
/// `ctx` is a live context; `path` a NUL-terminated string; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn lumi_luminaire_load(
    ctx: *mut crate::ffi::context::lumi_context,
    path: *const c_char,
    out: *mut lumi_luminaire,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_luminaire_load", ctx, |c| {
            let path = path_arg(path, "path")?;
            if out.is_null() {
                return Err(FfiError::null("out"));
            }
            let id = load_any(c, &path, &scan_desc(std::ptr::null())?)?;
            write_out(out, handle::encode(c.tag, handle::Kind::Luminaire, id.0));
            Ok(())
        })
    }
}

/// Loads a luminaire like `lumi_luminaire_load` (same format detection, same errors) with a
/// description: the near-field GPU budget, proxy mesh, content radius and cache folder.
///
/// - `path`: NUL-terminated UTF-8 path, borrowed for the call.
/// - `desc`: NULL for the defaults (`lumi_luminaire_desc_default()`); read during the call only.
/// - `out`: receives the handle (owned by the context); written only on success.
///
/// Errors, besides those of `lumi_luminaire_load`: `LUMI_STATUS_INVALID_ARGUMENT` naming the field
/// (`desc.budget_bytes` 0, a negative or non-finite `desc.content_radius_m` or one not below the
/// capture radius, a proxy vertex outside the capture sphere, `desc.proxy_path` or
/// `desc.content_radius_m` set for a photometric file); `LUMI_STATUS_IO` / `LUMI_STATUS_PARSE`
/// naming the proxy file or the cache folder.
///
/// Threading: one thread at a time per context.
///
/// # Safety
/// `ctx` is a live context; `path` a NUL-terminated string; `desc` NULL or valid, with its paths
/// NULL or NUL-terminated; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn lumi_luminaire_load_ex(
    ctx: *mut crate::ffi::context::lumi_context,
    path: *const c_char,
    desc: *const lumi_luminaire_desc,
    out: *mut lumi_luminaire,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_luminaire_load_ex", ctx, |c| {
            let path = path_arg(path, "path")?;
            if out.is_null() {
                return Err(FfiError::null("out"));
            }
            let d = scan_desc(desc)?;
            let id = load_any(c, &path, &d)?;
            write_out(out, handle::encode(c.tag, handle::Kind::Luminaire, id.0));
            Ok(())
        })
    }
}

/// Frees a luminaire and all its instances. Handle 0 is ignored; a stale handle is an error.
///
/// # Safety
/// `ctx` is a live context.
#[no_mangle]
pub unsafe extern "C" fn lumi_luminaire_destroy(
    ctx: *mut crate::ffi::context::lumi_context,
    luminaire: lumi_luminaire,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_luminaire_destroy", ctx, |c| {
            if luminaire == 0 {
                return Ok(());
            }
            let id = luminaire_id(c, luminaire, "luminaire")?;
            c.renderer.remove_luminaire(id).map_err(|_| {
                FfiError::invalid(
                    "luminaire",
                    format!("no luminaire with handle {luminaire:#x} (destroyed?)"),
                )
            })
        })
    }
}

/// Describes a luminaire: its kind and, per kind, the far-field or near-field facts
/// (`lumi_luminaire_info` says which fields apply to which).
///
/// Errors: `LUMI_STATUS_INVALID_ARGUMENT` (stale handle), `LUMI_STATUS_NULL_POINTER` (out).
///
/// # Safety
/// `ctx` is a live context; `out` writable (written only on success).
#[no_mangle]
pub unsafe extern "C" fn lumi_luminaire_get_info(
    ctx: *const crate::ffi::context::lumi_context,
    luminaire: lumi_luminaire,
    out: *mut lumi_luminaire_info,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_luminaire_get_info", ctx, |c| {
            if out.is_null() {
                return Err(FfiError::null("out"));
            }
            let mut info = lumi_luminaire_info {
                kind: LUMI_LUMINAIRE_FARFIELD,
                max_intensity_cd: 0.0,
                max_c_deg: 0.0,
                max_gamma_deg: 0.0,
                flux_lm: 0.0,
                opening_shape: LUMI_OPENING_POINT,
                opening_size_m: [0.0; 3],
                housing_size_m: [0.0; 3],
                camera_count: 0,
                has_proxy: false,
                capture_centre_m: [0.0; 3],
                capture_radius_m: 0.0,
                content_radius_m: 0.0,
                gpu_bytes: 0,
                budget_bytes: 0,
            };
            match luminaire_of(c, luminaire)? {
                Luminaire::Farfield(f) => {
                    let p = &f.photometry;
                    let peak = p.peak();
                    let (max_cd, mc, mg) = (peak.cd, peak.c_deg, peak.gamma_deg);
                    let o = &p.opening;
                    info.max_intensity_cd = max_cd;
                    info.max_c_deg = mc;
                    info.max_gamma_deg = mg;
                    info.flux_lm = p.flux_lm();
                    info.opening_shape = shape_code(o.shape);
                    info.opening_size_m = [o.size_x_m, o.size_y_m, o.height_m];
                    info.housing_size_m = p.luminaire_size_m.unwrap_or([0.0; 3]);
                }
                Luminaire::Nearfield(n) => {
                    let r = n.residency();
                    info.kind = LUMI_LUMINAIRE_NEARFIELD;
                    info.camera_count = u32::try_from(n.pack.rayset().cameras.len()).unwrap_or(u32::MAX);
                    info.has_proxy = n.has_proxy();
                    info.capture_centre_m = n.sphere.0.to_array();
                    info.capture_radius_m = n.sphere.1;
                    info.content_radius_m = n.content_radius_m;
                    info.gpu_bytes = r.gpu_bytes;
                    info.budget_bytes = r.budget_bytes;
                }
            }
            write_out(out, info);
            Ok(())
        })
    }
}

/// The capture cameras of a near-field luminaire (its scan's layout), in the scan's camera order
/// (the order of `lumiview info SCAN` and of the pack): camera i's position is
/// `positions_m[3i..3i+3]` and its optical axis (unit vector from the camera towards the scene)
/// `directions[3i..3i+3]`, both in the luminaire frame (metres; X C0, Y C90, Z up). For a ray
/// file these are its virtual scan's cameras. `lumi_luminaire_info.camera_count` is the count.
///
/// - `positions_m`, `directions`: NULL, or room for `capacity` × 3 doubles each; with both NULL
///   only `count` is written (a size query).
/// - `count`: receives the number of cameras, also on `LUMI_STATUS_BUFFER_TOO_SMALL`.
///
/// Errors: `LUMI_STATUS_BUFFER_TOO_SMALL` (`capacity` below the count with a buffer given; nothing
/// written but `count`), `LUMI_STATUS_INVALID_ARGUMENT` (a far-field luminaire, or a stale, foreign
/// or wrong-kind handle), `LUMI_STATUS_NULL_POINTER` (`count`).
///
/// # Safety
/// `ctx` is a live context; `positions_m` and `directions` NULL or `capacity × 3` writable doubles;
/// `count` writable.
#[no_mangle]
pub unsafe extern "C" fn lumi_luminaire_cameras(
    ctx: *const crate::ffi::context::lumi_context,
    luminaire: lumi_luminaire,
    positions_m: *mut f64,
    directions: *mut f64,
    capacity: usize,
    count: *mut usize,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_luminaire_cameras", ctx, |c| {
            if count.is_null() {
                return Err(FfiError::null("count"));
            }
            let Luminaire::Nearfield(n) = luminaire_of(c, luminaire)? else {
                return Err(FfiError::invalid(
                    "luminaire",
                    "a far-field luminaire (photometric file) has no capture cameras",
                ));
            };
            let cameras = &n.pack.rayset().cameras;
            if positions_m.is_null() && directions.is_null() {
                write_out(count, cameras.len());
                return Ok(());
            }
            if capacity < cameras.len() {
                write_out(count, cameras.len());
                return Err(FfiError::new(
                    LUMI_STATUS_BUFFER_TOO_SMALL,
                    format!("capacity {capacity} < {} cameras", cameras.len()),
                ));
            }
            for (i, cam) in cameras.iter().enumerate() {
                if !positions_m.is_null() {
                    std::ptr::copy_nonoverlapping(cam.position_m.to_array().as_ptr(), positions_m.add(3 * i), 3);
                }
                if !directions.is_null() {
                    std::ptr::copy_nonoverlapping(cam.forward.to_array().as_ptr(), directions.add(3 * i), 3);
                }
            }
            write_out(count, cameras.len());
            Ok(())
        })
    }
}

/// Luminous intensity (cd) of a luminaire towards (C, γ) in degrees, and the luminance (cd/m²) of
/// its luminous opening seen from there (0 where the projected area is zero). Either out-pointer may
/// be NULL; both are written only on success.
///
/// A near-field scan (`LUMI_LUMINAIRE_NEARFIELD`) answers from its far field, estimated from its
/// images on the first call that needs it (docs/scene-lighting.md, "Scans as light sources"); the
/// luminance is then the mean over its measured luminous extent.
///
/// Errors: `LUMI_STATUS_INVALID_ARGUMENT` for angles out of range, a stale handle, or a scan
/// whose images cannot be read.
///
/// # Safety
/// `ctx` is a live context; non-NULL out-pointers writable.
#[no_mangle]
pub unsafe extern "C" fn lumi_luminaire_sample(
    ctx: *const crate::ffi::context::lumi_context,
    luminaire: lumi_luminaire,
    c_deg: f64,
    gamma_deg: f64,
    intensity_cd: *mut f64,
    luminance_cd_m2: *mut f64,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_luminaire_sample", ctx, |c| {
            if !c_deg.is_finite() || !gamma_deg.is_finite() {
                return Err(FfiError::invalid("c_deg/gamma_deg", "must be finite"));
            }
            if !(0.0..=180.0).contains(&gamma_deg) {
                return Err(FfiError::invalid("gamma_deg", format!("{gamma_deg} is outside 0…180")));
            }
            let p = photometry_of(c, luminaire)?;
            let i = p.intensity(c_deg.rem_euclid(360.0), gamma_deg);
            let l = p.luminance(c_deg.rem_euclid(360.0), gamma_deg).unwrap_or(0.0);
            if !intensity_cd.is_null() {
                write_out(intensity_cd, i);
            }
            if !luminance_cd_m2.is_null() {
                write_out(luminance_cd_m2, l);
            }
            Ok(())
        })
    }
}
