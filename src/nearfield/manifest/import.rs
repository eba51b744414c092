//! Importing a scan: parsed manifests merged into one [`Scan`] (shared sphere and intrinsics), every
//! image's file checked (in parallel) and duplicate poses found; bad images fail the import or are
//! dropped with a warning. The images are read later, on demand, by a [`FileSource`].

use std::path::PathBuf;

use rayon::prelude::*;

use super::parse::{read_manifest, Manifest};
use super::DUPLICATE_TOLERANCE_RAD;
use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::images::{read_image, read_image_header};
use crate::nearfield::layout::MAX_CAMERAS;
use crate::nearfield::rayset::{Camera, CaptureSphere, ImageSource, Intrinsics, LuminanceImage, RayImageSet, Scan};

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
