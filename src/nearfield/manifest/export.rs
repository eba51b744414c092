//! Exporting a scan: its images written as `.pf` files and a manifest describing every camera as a
//! full pose, so that [`load_scan`](super::load_scan) reads the same cameras and pixels back.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;
use rayon::prelude::*;

use super::schema::{intrinsics_to_json, JsonImage, JsonManifest};
use super::{MANIFEST_FORMAT, MANIFEST_VERSION};
use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::images::write_pf;
use crate::nearfield::rayset::{RayImageSet, Scan};

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
/// synthetic scan can be exported and imported again with [`load_scan`](super::load_scan) (same
/// cameras, same pixels). `progress(done, total)` is called after each image, from worker threads.
/// Existing files of the same names are overwritten.
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
