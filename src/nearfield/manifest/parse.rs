//! Parsing a manifest: the JSON checked into a [`Manifest`] (sphere, shared intrinsics) whose entries
//! each hold a camera or the reason the entry is bad; no image file is opened.

use std::path::{Path, PathBuf};

use glam::DVec3;

use super::schema::{dvec3, intrinsics_from_json, JsonImage, JsonManifest};
use super::{MANIFEST_FORMAT, MANIFEST_VERSION, MAX_MANIFEST_BYTES, POSITION_TOLERANCE};
use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::layout::{direction_deg, MAX_CAMERAS};
use crate::nearfield::rayset::{Camera, CaptureSphere, Hemisphere, ImageMeta, Intrinsics};

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

#[cfg(test)]
mod tests {
    use glam::DVec2;

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
