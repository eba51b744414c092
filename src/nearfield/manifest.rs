//! The JSON scan manifest: how a measured near-field scan (a set of luminance image files and their
//! camera poses) is described, imported ([`load_scan`]) and exported ([`write_scan`]).
//!
//! A manifest names the capture sphere, the shared pinhole intrinsics, and per image its file and
//! its camera pose: photometric angles (`phi_deg` = C, `theta_deg` = γ from nadir; the camera sits at
//! `centre + radius · dir` looking at the centre, oriented by
//! [`look_at_basis`](super::rayset::look_at_basis)) or a full basis (`position_m`, `right`, `down`,
//! `forward`). The complete description with an example is in docs/formats.md ("Scan manifest").
//!
//! Several manifests (e.g. one per hemisphere) merge into one scan when they share the sphere and
//! the intrinsics. Images are read lazily by a [`FileSource`]; importing opens each file only to check
//! its header (existence, format, size, length). Every inconsistency is an error naming the image,
//! unless [`ImportOptions::skip_bad`] (CLI: `--skip-bad-images`) drops the image with a warning.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::error::{NearfieldError, Result};
use super::images::{read_image, read_image_header, write_pf};
use super::layout::{direction_deg, MAX_CAMERAS};
use super::rayset::{
    Camera, CaptureSphere, Hemisphere, ImageMeta, ImageSource, Intrinsics, LuminanceImage, RayImageSet, Scan,
};

/// The `format` value of a manifest.
pub const MANIFEST_FORMAT: &str = "lumiview-scan-manifest";

/// The manifest version this reader understands and the writer writes.
pub const MANIFEST_VERSION: u32 = 1;

/// Largest manifest file read, bytes (≈ 2,000 bytes per image for 10⁵ images would be 200 MB).
pub const MAX_MANIFEST_BYTES: u64 = 1 << 30;

/// Two cameras whose directions from the capture centre are within this angle (rad) sit at the same
/// place; with the same orientation too they are a duplicate pose.
pub const DUPLICATE_TOLERANCE_RAD: f64 = 1e-6;

/// Largest allowed difference between a camera's distance from the centre and the sphere radius, as
/// a fraction of the radius (1 %; a larger one usually means millimetres given as metres).
pub const POSITION_TOLERANCE: f64 = 0.01;

/// How a scan is imported.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ImportOptions {
    /// Drop bad images (missing or unreadable file, wrong size, bad pose or intrinsics, duplicate
    /// pose, and with [`ImportOptions::verify_pixels`] non-finite or negative values) with a warning
    /// instead of failing. CLI flag: `--skip-bad-images`.
    pub skip_bad: bool,
    /// Read every image's pixels during the import and check them ([`LuminanceImage::validate`]:
    /// finite and ≥ 0), in parallel. Without it pixels are checked when an image is read through the
    /// [`FileSource`]. CLI flag: `--verify-images`.
    pub verify_pixels: bool,
}

/// What an import found besides errors.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ImportReport {
    /// One line per image dropped under [`ImportOptions::skip_bad`], naming the image and why.
    pub warnings: Vec<String>,
    /// Facts worth knowing: coincident camera positions with different orientations (legitimate,
    /// e.g. the meridian starts at a pole), and the number of cameras per manifest.
    pub info: Vec<String>,
    /// Number of images dropped.
    pub dropped: usize,
}

// ---------------------------------------------------------------------------------------------
// JSON schema (serde)
// ---------------------------------------------------------------------------------------------

/// A number or a pair (`fx` = `fy` when one number is given).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(untagged)]
enum OneOrTwo {
    One(f64),
    Two([f64; 2]),
}

impl OneOrTwo {
    fn pair(self) -> DVec2 {
        match self {
            Self::One(v) => DVec2::splat(v),
            Self::Two([a, b]) => DVec2::new(a, b),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
enum JsonHemisphere {
    Lower,
    Upper,
}

impl From<JsonHemisphere> for Hemisphere {
    fn from(h: JsonHemisphere) -> Self {
        match h {
            JsonHemisphere::Lower => Hemisphere::Lower,
            JsonHemisphere::Upper => Hemisphere::Upper,
        }
    }
}

impl From<Hemisphere> for JsonHemisphere {
    fn from(h: Hemisphere) -> Self {
        match h {
            Hemisphere::Lower => JsonHemisphere::Lower,
            Hemisphere::Upper => JsonHemisphere::Upper,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct JsonIntrinsics {
    width: u32,
    height: u32,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    principal_px: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    focal_px: Option<OneOrTwo>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pixel_scale_rad: Option<OneOrTwo>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct JsonImage {
    file: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    label: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    phi_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    theta_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    position_m: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    right: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    down: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    forward: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    hemisphere: Option<JsonHemisphere>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    exposure_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    overflow_count: Option<u64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    intrinsics: Option<JsonIntrinsics>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct JsonManifest {
    format: String,
    version: u32,
    radius_m: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    centre_m: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    hemisphere: Option<JsonHemisphere>,
    intrinsics: JsonIntrinsics,
    images: Vec<JsonImage>,
}

fn dvec3(a: [f64; 3]) -> DVec3 {
    DVec3::new(a[0], a[1], a[2])
}

/// Converts JSON intrinsics; `what` names them in errors.
fn intrinsics_from_json(j: &JsonIntrinsics, what: &str) -> Result<Intrinsics> {
    let focal = match (j.focal_px, j.pixel_scale_rad) {
        (Some(f), None) => f.pair(),
        (None, Some(s)) => {
            let s = s.pair();
            if !(s.x.is_finite() && s.y.is_finite() && s.x > 0.0 && s.y > 0.0) {
                return Err(NearfieldError::invalid(
                    format!("{what}: pixel_scale_rad"),
                    format!("({}, {}) must be finite and > 0", s.x, s.y),
                ));
            }
            DVec2::ONE / s
        }
        (Some(_), Some(_)) => {
            return Err(NearfieldError::invalid(
                format!("{what}: intrinsics"),
                "give focal_px or pixel_scale_rad, not both",
            ))
        }
        (None, None) => {
            return Err(NearfieldError::invalid(
                format!("{what}: intrinsics"),
                "focal_px or pixel_scale_rad is required",
            ))
        }
    };
    let principal = j.principal_px.map_or(
        DVec2::new(f64::from(j.width) / 2.0, f64::from(j.height) / 2.0),
        |[x, y]| DVec2::new(x, y),
    );
    let k = Intrinsics {
        width: j.width,
        height: j.height,
        principal_px: principal,
        focal_px: focal,
    };
    k.validate(what)?;
    Ok(k)
}

fn intrinsics_to_json(k: &Intrinsics) -> JsonIntrinsics {
    JsonIntrinsics {
        width: k.width,
        height: k.height,
        principal_px: Some([k.principal_px.x, k.principal_px.y]),
        focal_px: Some(OneOrTwo::Two([k.focal_px.x, k.focal_px.y])),
        pixel_scale_rad: None,
    }
}

// ---------------------------------------------------------------------------------------------
// Parsed manifests
// ---------------------------------------------------------------------------------------------

/// One image entry of a parsed manifest.
#[derive(Debug)]
pub struct ManifestEntry {
    /// The image file, resolved against the manifest's folder (absolute paths are kept).
    pub file: PathBuf,
    /// How messages name this image: `FILE [MANIFEST #INDEX]` with the file as written.
    pub name: String,
    /// Its camera, or why the entry is bad (bad pose, intrinsics override or metadata).
    pub camera: Result<Camera>,
}

/// A parsed manifest: sphere, shared intrinsics and its entries (files not yet opened).
#[derive(Debug)]
pub struct Manifest {
    /// The manifest file.
    pub path: PathBuf,
    /// The capture sphere.
    pub sphere: CaptureSphere,
    /// Intrinsics shared by its images.
    pub intrinsics: Intrinsics,
    /// The manifest-wide hemisphere tag, if any.
    pub hemisphere: Option<Hemisphere>,
    /// The images in file order.
    pub entries: Vec<ManifestEntry>,
}

/// Parses the bytes of a manifest (`path` names it in errors and resolves relative image paths).
/// Touches no file.
///
/// # Errors
/// [`NearfieldError::Format`] naming the manifest for malformed JSON (with line and column), a
/// missing or unknown field, a wrong `format`/`version`, a bad sphere or shared intrinsics, or more
/// than [`MAX_CAMERAS`] images. Problems of single images do not fail the parse: they are kept in
/// [`ManifestEntry::camera`].
pub fn parse_manifest(bytes: &[u8], path: &Path) -> Result<Manifest> {
    let ferr = |m: String| NearfieldError::format(path, m);
    let j: JsonManifest = serde_json::from_slice(bytes).map_err(|e| ferr(format!("manifest JSON: {e}")))?;
    if j.format != MANIFEST_FORMAT {
        return Err(ferr(format!(
            "\"format\" is \"{}\", expected \"{MANIFEST_FORMAT}\"",
            j.format
        )));
    }
    if j.version != MANIFEST_VERSION {
        return Err(ferr(format!(
            "\"version\" {} is not supported (this reader knows version {MANIFEST_VERSION})",
            j.version
        )));
    }
    let centre = dvec3(j.centre_m.unwrap_or([0.0; 3]));
    if !j.radius_m.is_finite() || j.radius_m <= 0.0 || !centre.is_finite() {
        return Err(ferr(format!(
            "capture sphere: radius_m {} must be finite and > 0, centre_m finite",
            j.radius_m
        )));
    }
    let sphere = CaptureSphere {
        centre_m: centre,
        radius_m: j.radius_m,
    };
    let intrinsics = intrinsics_from_json(&j.intrinsics, "shared intrinsics").map_err(|e| ferr(e.to_string()))?;
    if j.images.is_empty() {
        return Err(ferr("\"images\" is empty: a scan needs at least one image".into()));
    }
    if j.images.len() > MAX_CAMERAS {
        return Err(ferr(format!(
            "{} images; at most {MAX_CAMERAS} are accepted",
            j.images.len()
        )));
    }
    let hemisphere = j.hemisphere.map(Hemisphere::from);
    let dir = path.parent().unwrap_or(Path::new(""));
    let manifest_name = path
        .file_name()
        .map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
    let entries = j
        .images
        .iter()
        .enumerate()
        .map(|(i, im)| {
            let name = format!("{} [{manifest_name} #{i}]", im.file);
            let camera = entry_camera(im, &name, &sphere, hemisphere);
            ManifestEntry {
                file: dir.join(&im.file),
                name,
                camera,
            }
        })
        .collect();
    Ok(Manifest {
        path: path.to_path_buf(),
        sphere,
        intrinsics,
        hemisphere,
        entries,
    })
}

/// The camera of one manifest entry.
fn entry_camera(im: &JsonImage, name: &str, sphere: &CaptureSphere, hemisphere: Option<Hemisphere>) -> Result<Camera> {
    let bad = |m: String| NearfieldError::image(name, m);
    if im.file.trim().is_empty() {
        return Err(bad("\"file\" is empty".into()));
    }
    let label = im.label.clone().unwrap_or_else(|| im.file.clone());
    let angles = im.phi_deg.is_some() || im.theta_deg.is_some();
    let basis = im.position_m.is_some() || im.right.is_some() || im.down.is_some() || im.forward.is_some();
    let mut cam = match (angles, basis) {
        (true, true) => {
            return Err(bad(
                "give either phi_deg + theta_deg or position_m + right + down + forward, not both".into(),
            ))
        }
        (false, false) => {
            return Err(bad(
                "no pose: give phi_deg + theta_deg, or position_m + right + down + forward".into(),
            ))
        }
        (true, false) => {
            let (Some(phi), Some(theta)) = (im.phi_deg, im.theta_deg) else {
                return Err(bad("phi_deg and theta_deg must be given together".into()));
            };
            if !phi.is_finite() || !(0.0..=180.0).contains(&theta) {
                return Err(bad(format!(
                    "phi_deg {phi} must be finite and theta_deg {theta} within 0…180"
                )));
            }
            let d = direction_deg(phi, theta);
            Camera::on_sphere(sphere, d, hemisphere_of(d, hemisphere), label)
        }
        (false, true) => {
            let (Some(p), Some(r), Some(dn), Some(f)) = (im.position_m, im.right, im.down, im.forward) else {
                return Err(bad(
                    "a full pose needs all of position_m, right, down and forward".into()
                ));
            };
            let position = dvec3(p);
            let d = (position - sphere.centre_m).normalize_or_zero();
            let cam = Camera {
                position_m: position,
                right: dvec3(r),
                down: dvec3(dn),
                forward: dvec3(f),
                intrinsics: None,
                hemisphere: hemisphere_of(d, hemisphere),
                meta: ImageMeta::default(),
                label,
            };
            cam.validate().map_err(|_| {
                bad(
                    "right, down, forward must be finite unit vectors (to 1e-6), orthogonal and right-handed \
                     (right × down = forward); position_m finite"
                        .into(),
                )
            })?;
            let dist = (position - sphere.centre_m).length();
            if (dist - sphere.radius_m).abs() > POSITION_TOLERANCE * sphere.radius_m {
                return Err(bad(format!(
                    "position_m is {dist} m from the capture centre, but the sphere radius is {} m (tolerance {} %)",
                    sphere.radius_m,
                    POSITION_TOLERANCE * 100.0
                )));
            }
            cam
        }
    };
    if let Some(h) = im.hemisphere {
        cam.hemisphere = h.into();
    }
    if let Some(e) = im.exposure_s {
        if !e.is_finite() || e < 0.0 {
            return Err(bad(format!("exposure_s {e} must be finite and ≥ 0")));
        }
    }
    cam.meta = ImageMeta {
        exposure_s: im.exposure_s,
        overflow_count: im.overflow_count,
    };
    if let Some(k) = &im.intrinsics {
        cam.intrinsics = Some(intrinsics_from_json(k, name).map_err(|e| bad(e.to_string()))?);
    }
    Ok(cam)
}

/// The manifest's tag, else by direction (z ≤ 0, i.e. θ ≤ 90°: lower).
fn hemisphere_of(dir: DVec3, tag: Option<Hemisphere>) -> Hemisphere {
    tag.unwrap_or(if dir.z <= 0.0 {
        Hemisphere::Lower
    } else {
        Hemisphere::Upper
    })
}

/// Reads and parses a manifest file ([`parse_manifest`]).
///
/// # Errors
/// [`NearfieldError::Io`] when it cannot be read, [`NearfieldError::Format`] when it is larger than
/// [`MAX_MANIFEST_BYTES`], and those of [`parse_manifest`].
pub fn read_manifest(path: &Path) -> Result<Manifest> {
    // A refusal (not a regular file, too large) is a format error; anything else an I/O error.
    let bytes =
        crate::files::read_regular(path, MAX_MANIFEST_BYTES, "a scan manifest").map_err(|e| match e.kind() {
            std::io::ErrorKind::InvalidInput => NearfieldError::format(path, e.to_string()),
            _ => NearfieldError::io(path, e),
        })?;
    parse_manifest(&bytes, path)
}

// ---------------------------------------------------------------------------------------------
// The lazy image source
// ---------------------------------------------------------------------------------------------

/// Images read from files on demand: `image(i)` opens camera `i`'s file, decodes it and checks its
/// size and values against the camera's intrinsics ([`LuminanceImage::validate`]). Errors name the
/// image. Safe to call from several threads at once.
#[derive(Debug, Clone)]
pub struct FileSource {
    files: Vec<PathBuf>,
    names: Vec<String>,
    intrinsics: Vec<Intrinsics>,
}

impl FileSource {
    /// A source for `set`'s cameras reading `files[i]` for camera `i`; `names[i]` names it in errors.
    ///
    /// # Errors
    /// [`NearfieldError::InvalidArgument`] when the lengths differ from the camera count.
    pub fn new(set: &RayImageSet, files: Vec<PathBuf>, names: Vec<String>) -> Result<Self> {
        let n = set.cameras.len();
        if files.len() != n || names.len() != n {
            return Err(NearfieldError::invalid(
                "image files",
                format!("{} files and {} names for {n} cameras", files.len(), names.len()),
            ));
        }
        let intrinsics = (0..n).map(|i| *set.intrinsics_of(i)).collect();
        Ok(Self {
            files,
            names,
            intrinsics,
        })
    }

    /// The image files, one per camera.
    pub fn files(&self) -> &[PathBuf] {
        &self.files
    }

    /// The names used in messages, one per camera.
    pub fn names(&self) -> &[String] {
        &self.names
    }
}

/// Wraps an error of an image file as an error naming the image.
fn image_error(name: &str, e: NearfieldError) -> NearfieldError {
    match e {
        e @ NearfieldError::Image { .. } => e,
        e => NearfieldError::image(name, e.to_string()),
    }
}

impl ImageSource for FileSource {
    fn image(&self, index: usize) -> Result<LuminanceImage> {
        let (Some(path), Some(name), Some(k)) =
            (self.files.get(index), self.names.get(index), self.intrinsics.get(index))
        else {
            return Err(NearfieldError::invalid(
                "image index",
                format!("{index} is outside 0…{}", self.files.len()),
            ));
        };
        let img = read_image(path).map_err(|e| image_error(name, e))?;
        img.validate(name, k)?;
        Ok(img)
    }
    fn input_files(&self) -> Vec<PathBuf> {
        self.files.clone()
    }
}

// ---------------------------------------------------------------------------------------------
// Import
// ---------------------------------------------------------------------------------------------

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1.0)
}

fn same_sphere(a: &CaptureSphere, b: &CaptureSphere) -> bool {
    close(a.radius_m, b.radius_m)
        && close(a.centre_m.x, b.centre_m.x)
        && close(a.centre_m.y, b.centre_m.y)
        && close(a.centre_m.z, b.centre_m.z)
}

fn same_intrinsics(a: &Intrinsics, b: &Intrinsics) -> bool {
    a.width == b.width
        && a.height == b.height
        && close(a.principal_px.x, b.principal_px.x)
        && close(a.principal_px.y, b.principal_px.y)
        && close(a.focal_px.x, b.focal_px.x)
        && close(a.focal_px.y, b.focal_px.y)
}

/// Drops entry `i` with a warning under `skip_bad`, else returns the error.
fn reject(opts: &ImportOptions, report: &mut ImportReport, e: NearfieldError) -> Result<()> {
    if opts.skip_bad {
        report.warnings.push(format!("skipped {e}"));
        report.dropped += 1;
        Ok(())
    } else {
        Err(e)
    }
}

/// One image that passed its checks so far.
struct Candidate {
    camera: Camera,
    file: PathBuf,
    name: String,
}

/// Merges parsed manifests into a scan and checks every image: its file (exists, readable header,
/// size equal to its intrinsics, long enough; in parallel), its pixels when
/// [`ImportOptions::verify_pixels`], and duplicate poses. Bad images fail the import, or are dropped
/// with a warning under [`ImportOptions::skip_bad`].
///
/// # Errors
/// [`NearfieldError::Format`] naming both manifests when their spheres or shared intrinsics differ;
/// [`NearfieldError::Image`] naming the first bad image (without `skip_bad`);
/// [`NearfieldError::InvalidArgument`] when no manifest is given or no image is left.
pub fn assemble_scan(manifests: Vec<Manifest>, opts: &ImportOptions) -> Result<(Scan, ImportReport)> {
    let mut report = ImportReport::default();
    let Some(first) = manifests.first() else {
        return Err(NearfieldError::invalid("manifests", "no manifest given"));
    };
    let (sphere, intrinsics, first_path) = (first.sphere, first.intrinsics, first.path.clone());
    let total: usize = manifests.iter().map(|m| m.entries.len()).sum();
    if total > MAX_CAMERAS {
        return Err(NearfieldError::invalid(
            "manifests",
            format!("{total} images in all; at most {MAX_CAMERAS} are accepted"),
        ));
    }
    let mut candidates: Vec<Candidate> = Vec::with_capacity(total);
    for m in manifests {
        if !same_sphere(&m.sphere, &sphere) {
            return Err(NearfieldError::format(
                &m.path,
                format!(
                    "capture sphere (radius {} m, centre {:?}) differs from {}'s (radius {} m, centre {:?}); \
                     merged manifests must share it",
                    m.sphere.radius_m,
                    m.sphere.centre_m.to_array(),
                    first_path.display(),
                    sphere.radius_m,
                    sphere.centre_m.to_array()
                ),
            ));
        }
        if !same_intrinsics(&m.intrinsics, &intrinsics) {
            return Err(NearfieldError::format(
                &m.path,
                format!(
                    "shared intrinsics ({}) differ from {}'s ({}); merged manifests must share them",
                    describe(&m.intrinsics),
                    first_path.display(),
                    describe(&intrinsics)
                ),
            ));
        }
        report.info.push(format!(
            "{}: {} image(s){}",
            m.path.display(),
            m.entries.len(),
            m.hemisphere.map_or(String::new(), |h| format!(", {h:?} hemisphere"))
        ));
        for e in m.entries {
            match e.camera {
                Ok(camera) => candidates.push(Candidate {
                    camera,
                    file: e.file,
                    name: e.name,
                }),
                Err(err) => reject(opts, &mut report, err)?,
            }
        }
    }

    // Files: header checks in parallel, reported in image order.
    let checks: Vec<Result<()>> = candidates
        .par_iter()
        .map(|c| {
            let k = c.camera.intrinsics.as_ref().unwrap_or(&intrinsics);
            check_file(c, k, opts.verify_pixels)
        })
        .collect();
    let mut kept = Vec::with_capacity(candidates.len());
    for (c, check) in candidates.into_iter().zip(checks) {
        match check {
            Ok(()) => kept.push(c),
            Err(e) => reject(opts, &mut report, e)?,
        }
    }

    // Duplicate poses: same place (coincident_groups) and the same orientation.
    let set = RayImageSet {
        sphere,
        intrinsics,
        cameras: kept.iter().map(|c| c.camera.clone()).collect(),
    };
    let mut drop = vec![false; kept.len()];
    for group in set.coincident_groups(DUPLICATE_TOLERANCE_RAD) {
        let mut distinct: Vec<usize> = Vec::new();
        for &j in &group {
            let dup = distinct
                .iter()
                .copied()
                .find(|&k| same_orientation(&set.cameras[k], &set.cameras[j]));
            match dup {
                Some(k) => {
                    let e = NearfieldError::image(
                        &kept[j].name,
                        format!(
                            "duplicate pose: same position (within {DUPLICATE_TOLERANCE_RAD} rad) and orientation as {}",
                            kept[k].name
                        ),
                    );
                    reject(opts, &mut report, e)?;
                    drop[j] = true;
                }
                None => distinct.push(j),
            }
        }
        if distinct.len() > 1 {
            let d = set.cameras[distinct[0]].direction_from(sphere.centre_m);
            let names: Vec<&str> = distinct.iter().take(4).map(|&k| kept[k].name.as_str()).collect();
            report.info.push(format!(
                "{} cameras share the position at φ = {:.3}°, θ = {:.3}° with different orientations (e.g. \
                 meridian starts at a pole): {}{}",
                distinct.len(),
                d.y.atan2(d.x).to_degrees().rem_euclid(360.0),
                (-d.z).clamp(-1.0, 1.0).acos().to_degrees(),
                names.join(", "),
                if distinct.len() > 4 { ", …" } else { "" }
            ));
        }
    }
    let mut cameras = Vec::with_capacity(kept.len());
    let mut files = Vec::with_capacity(kept.len());
    let mut names = Vec::with_capacity(kept.len());
    for (c, d) in kept.into_iter().zip(drop) {
        if !d {
            cameras.push(c.camera);
            files.push(c.file);
            names.push(c.name);
        }
    }
    if cameras.is_empty() {
        return Err(NearfieldError::invalid(
            "manifests",
            format!("no usable image left ({} dropped)", report.dropped),
        ));
    }
    let set = RayImageSet {
        sphere,
        intrinsics,
        cameras,
    };
    set.validate()?;
    let source = FileSource::new(&set, files, names)?;
    Ok((
        Scan {
            set,
            source: Box::new(source),
        },
        report,
    ))
}

fn describe(k: &Intrinsics) -> String {
    format!(
        "{}×{} px, principal point ({}, {}), focal ({}, {}) px",
        k.width, k.height, k.principal_px.x, k.principal_px.y, k.focal_px.x, k.focal_px.y
    )
}

fn same_orientation(a: &Camera, b: &Camera) -> bool {
    let tol = DUPLICATE_TOLERANCE_RAD;
    (a.right - b.right).length() <= tol && (a.down - b.down).length() <= tol && (a.forward - b.forward).length() <= tol
}

/// Checks one image file against its intrinsics (header only, or all pixels).
fn check_file(c: &Candidate, k: &Intrinsics, pixels: bool) -> Result<()> {
    if pixels {
        let img = read_image(&c.file).map_err(|e| image_error(&c.name, e))?;
        return img.validate(&c.name, k);
    }
    let h = read_image_header(&c.file).map_err(|e| image_error(&c.name, e))?;
    if h.width != k.width || h.height != k.height {
        return Err(NearfieldError::image(
            &c.name,
            format!(
                "{}: size {}×{} px differs from its intrinsics' {}×{}",
                c.file.display(),
                h.width,
                h.height,
                k.width,
                k.height
            ),
        ));
    }
    Ok(())
}

/// Imports a scan from one or more manifests (e.g. one per hemisphere), with a report of dropped
/// images and facts found ([`assemble_scan`]). Images are read later, lazily, by the scan's
/// [`FileSource`].
///
/// # Errors
/// Those of [`read_manifest`] and [`assemble_scan`].
pub fn load_scan_with_report(manifests: &[PathBuf], opts: &ImportOptions) -> Result<(Scan, ImportReport)> {
    let parsed = manifests.iter().map(|p| read_manifest(p)).collect::<Result<Vec<_>>>()?;
    assemble_scan(parsed, opts)
}

/// Imports a scan from one or more manifests ([`load_scan_with_report`]); the warnings about dropped
/// images (only with [`ImportOptions::skip_bad`]) are written to stderr.
///
/// # Errors
/// Those of [`load_scan_with_report`].
pub fn load_scan(manifests: &[PathBuf], opts: &ImportOptions) -> Result<Scan> {
    let (scan, report) = load_scan_with_report(manifests, opts)?;
    for w in &report.warnings {
        eprintln!("lumiview: warning: {w}");
    }
    Ok(scan)
}

// ---------------------------------------------------------------------------------------------
// Export
// ---------------------------------------------------------------------------------------------

/// The manifest JSON of `set` with image `i` in `files[i]` (paths relative to the manifest): every
/// camera as a full pose (`position_m`, `right`, `down`, `forward`, exact to the last bit), its
/// hemisphere, label, metadata and intrinsics override.
fn manifest_json(set: &RayImageSet, files: &[String]) -> JsonManifest {
    let v = |d: DVec3| Some(d.to_array());
    JsonManifest {
        format: MANIFEST_FORMAT.to_string(),
        version: MANIFEST_VERSION,
        radius_m: set.sphere.radius_m,
        centre_m: Some(set.sphere.centre_m.to_array()),
        hemisphere: None,
        intrinsics: intrinsics_to_json(&set.intrinsics),
        images: set
            .cameras
            .iter()
            .zip(files)
            .map(|(c, f)| JsonImage {
                file: f.clone(),
                label: Some(c.label.clone()),
                phi_deg: None,
                theta_deg: None,
                position_m: v(c.position_m),
                right: v(c.right),
                down: v(c.down),
                forward: v(c.forward),
                hemisphere: Some(c.hemisphere.into()),
                exposure_s: c.meta.exposure_s,
                overflow_count: c.meta.overflow_count,
                intrinsics: c.intrinsics.as_ref().map(intrinsics_to_json),
            })
            .collect(),
    }
}

/// Writes `scan` to the folder `dir` (created if needed): `images/NNNNN.pf` per camera (in parallel,
/// each image checked against its intrinsics first) and then `manifest.json` describing them, so a
/// synthetic scan can be exported and imported again with [`load_scan`] (same cameras, same pixels).
/// `progress(done, total)` is called after each image, from worker threads. Existing files of the
/// same names are overwritten.
///
/// Returns the manifest's path.
///
/// # Errors
/// [`NearfieldError::Io`] naming the file that cannot be written; the image source's errors; an
/// [`NearfieldError::Image`] for an image whose size or values are invalid; the scan's own
/// validation errors.
pub fn write_scan(dir: &Path, scan: &Scan, progress: &(dyn Fn(usize, usize) + Sync)) -> Result<PathBuf> {
    scan.set.validate()?;
    let n = scan.set.cameras.len();
    let images = dir.join("images");
    std::fs::create_dir_all(&images).map_err(|e| NearfieldError::io(&images, e))?;
    let digits = n.saturating_sub(1).to_string().len().max(5);
    let files: Vec<String> = (0..n).map(|i| format!("images/{i:0digits$}.pf")).collect();
    let done = AtomicUsize::new(0);
    (0..n).into_par_iter().try_for_each(|i| -> Result<()> {
        let img = scan.source.image(i)?;
        img.validate(&scan.set.cameras[i].label, scan.set.intrinsics_of(i))?;
        write_pf(&dir.join(&files[i]), &img)?;
        progress(done.fetch_add(1, Ordering::Relaxed) + 1, n);
        Ok(())
    })?;
    let path = dir.join("manifest.json");
    let json = serde_json::to_vec_pretty(&manifest_json(&scan.set, &files))
        .map_err(|e| NearfieldError::invalid("manifest", format!("cannot encode JSON: {e}")))?;
    std::fs::write(&path, json).map_err(|e| NearfieldError::io(&path, e))?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn manifest(images: &str) -> String {
        format!(
            r#"{{"format": "lumiview-scan-manifest", "version": 1, "radius_m": 1.0,
                "intrinsics": {{"width": 4, "height": 3, "pixel_scale_rad": 0.01}},
                "images": [{images}]}}"#
        )
    }

    #[test]
    fn pixel_scale_gives_focal_and_default_principal_point() {
        let m = parse_manifest(
            manifest(r#"{"file": "a.pf", "phi_deg": 0, "theta_deg": 0}"#).as_bytes(),
            Path::new("/x/m.json"),
        )
        .unwrap();
        assert_eq!(m.intrinsics.focal_px, DVec2::splat(100.0));
        assert_eq!(m.intrinsics.principal_px, DVec2::new(2.0, 1.5));
        assert_eq!(m.entries[0].file, PathBuf::from("/x/a.pf"));
        let c = m.entries[0].camera.as_ref().unwrap();
        assert!((c.position_m - DVec3::new(0.0, 0.0, -1.0)).length() < 1e-12);
        assert_eq!(c.hemisphere, Hemisphere::Lower);
    }

    #[test]
    fn entry_problems_stay_with_the_entry() {
        let m = parse_manifest(
            manifest(
                r#"{"file": "a.pf", "phi_deg": 0},
                   {"file": "b.pf", "phi_deg": 0, "theta_deg": 200},
                   {"file": "c.pf", "position_m": [0,0,-1], "right": [1,0,0], "down": [0,1,0], "forward": [0,0,-1]},
                   {"file": "d.pf", "position_m": [0,0,-1000], "right": [1,0,0], "down": [0,1,0], "forward": [0,0,1]}"#,
            )
            .as_bytes(),
            Path::new("m.json"),
        )
        .unwrap();
        let errs: Vec<String> = m
            .entries
            .iter()
            .map(|e| e.camera.as_ref().unwrap_err().to_string())
            .collect();
        assert!(
            errs[0].contains("a.pf [m.json #0]") && errs[0].contains("together"),
            "{}",
            errs[0]
        );
        assert!(errs[1].contains("theta_deg 200"), "{}", errs[1]);
        assert!(errs[2].contains("right-handed"), "{}", errs[2]);
        assert!(errs[3].contains("1000 m from the capture centre"), "{}", errs[3]);
    }

    #[test]
    fn structural_errors_name_the_manifest() {
        let e = parse_manifest(b"{", Path::new("m.json")).unwrap_err().to_string();
        assert!(e.starts_with("m.json: manifest JSON"), "{e}");
        let e = parse_manifest(
            manifest(r#"{"file": "a.pf", "phi_deg": 0, "theta_deg": 0, "tilt": 3}"#).as_bytes(),
            Path::new("m.json"),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("unknown field `tilt`"), "{e}");
        let e = parse_manifest(manifest("").as_bytes(), Path::new("m.json"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("empty"), "{e}");
    }
}
