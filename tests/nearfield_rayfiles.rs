//! Ray files as light fields (`nearfield::raykde`, docs/rayfiles.md): the kernel estimate of the
//! real TM-25 files in tests/data/raysets and of rays forward-traced from a synthetic luminaire
//! whose intensity is known in closed form; kernels that shrink as rays are added; the proxy from
//! the ray origins; the `.lvpack` that stores it; renders from the default eye and from 5 cm to
//! 2 m that show the source; the estimate's far field against the rays binned by direction.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod gpu_common;

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::DVec3;
use lumiview::nearfield::binning::NearestDirection;
use lumiview::nearfield::pack::{write_pack, Pack, PackOptions, PackProxy};
use lumiview::nearfield::proxy::triangles_of;
use lumiview::nearfield::raykde::{estimate, estimate_frozen, KdeOptions, KdeScan, RayBatch};
use lumiview::nearfield::synth::emit::emit_rays;
use lumiview::nearfield::synth::luminaire;
use lumiview::nearfield::tm25::{encode, RayFile};
use lumiview::nearfield::NearfieldError;

const RAYSETS: [&str; 3] = [
    "rayfile_LERTDUW_S2WP_green_100k_20161013_IES_TM25.TM25RAY",
    "Cyl10k.1.tm25ray",
    "farfield.TM25ray",
];

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/raysets")
        .join(name)
}

fn kde(f: &RayFile) -> KdeScan {
    estimate(f, &KdeOptions::default(), &|_, _| {}).unwrap()
}

/// Each camera's intensity from its image, Σ L · A (cd).
fn camera_intensities(e: &KdeScan) -> Vec<f64> {
    let a = e.report.pixel_m * e.report.pixel_m;
    (0..e.scan.set.cameras.len())
        .map(|i| {
            e.scan
                .source
                .image(i)
                .unwrap()
                .data
                .iter()
                .map(|v| f64::from(*v))
                .sum::<f64>()
                * a
        })
        .collect()
}

#[test]
fn every_real_ray_file_becomes_a_plausible_estimate() {
    for name in RAYSETS {
        let f = RayFile::read(data(name)).unwrap();
        let e = kde(&f);
        let r = &e.report;
        assert!(r.cameras_lit > 0 && r.cameras >= 12, "{name}: {r:?}");
        assert!(
            r.angular_kernel_deg.median > 0.0 && r.spatial_kernel_m.median > 0.0,
            "{name}"
        );
        // The cameras' Voronoi quadrature of the estimate holds the rays' flux.
        let q = r.flux_from_images_lm / r.flux_lm;
        assert!((0.85..=1.15).contains(&q), "{name}: quadrature {q}");
        // The proxy encloses every ray origin (the hull grown outward): a ray from the origin crosses
        // the closed mesh an odd number of times.
        let mesh = &e.proxy.surfaces[0];
        let dir = DVec3::new(0.3141, 0.5926, 0.7431).normalize();
        for i in (0..f.len()).step_by(97) {
            let p = f.ray(i).unwrap().position_m;
            let mut crossings = 0;
            for t in mesh.indices.chunks_exact(3) {
                let (a, b, c) = (
                    mesh.positions[t[0] as usize],
                    mesh.positions[t[1] as usize],
                    mesh.positions[t[2] as usize],
                );
                let (e1, e2) = (b - a, c - a);
                let pv = dir.cross(e2);
                let det = e1.dot(pv);
                if det.abs() < 1e-30 {
                    continue;
                }
                let sv = p - a;
                let u = sv.dot(pv) / det;
                let q = sv.cross(e1);
                let v = dir.dot(q) / det;
                let tt = e2.dot(q) / det;
                if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && tt > 0.0 {
                    crossings += 1;
                }
            }
            assert!(
                crossings % 2 == 1,
                "{name}: origin {p} outside the proxy ({crossings} crossings)"
            );
        }
    }
}

#[test]
fn a_forward_traced_lambertian_disc_keeps_its_cosine_intensity() {
    // Rays from the synthetic disc (closed-form intensity I(γ) = L·A·cos γ below it): the
    // estimate's intensity at its lit cameras within 5 % (median) of the closed form.
    let lum = luminaire("disc").unwrap();
    let rays = emit_rays(lum.as_ref(), 60_000, 11, &|_| {}).unwrap();
    let f = RayFile::from_bytes(&rays.to_tm25("lumiview test").unwrap(), "disc.tm25ray").unwrap();
    let e = kde(&f);
    let got = camera_intensities(&e);
    let mut rel = Vec::new();
    for (i, cam) in e.scan.set.cameras.iter().enumerate() {
        let d = cam.direction_from(e.scan.set.sphere.centre_m);
        let want = lum.intensity_cd(d);
        if want > 0.2 * lum.intensity_cd(DVec3::NEG_Z) {
            rel.push((got[i] / want - 1.0).abs());
        }
    }
    rel.sort_by(f64::total_cmp);
    let median = rel[rel.len() / 2];
    assert!(
        rel.len() > 20 && median < 0.05,
        "{} cameras, median {median}",
        rel.len()
    );
    // The cameras' quadrature holds the disc's flux.
    let (omega, _) = NearestDirection::new(
        &e.scan
            .set
            .cameras
            .iter()
            .map(|c| c.direction_from(e.scan.set.sphere.centre_m))
            .collect::<Vec<_>>(),
    )
    .solid_angles();
    let flux: f64 = got.iter().zip(&omega).map(|(i, o)| i * o).sum();
    assert!((flux / lum.flux_lm() - 1.0).abs() < 0.06, "{flux} vs {}", lum.flux_lm());
}

/// Every `step`-th ray of a file as a new file.
fn subsample(f: &RayFile, step: usize) -> RayFile {
    let mut h = f.header().clone();
    let items = h.items_per_ray();
    let mut rec = Vec::with_capacity(f.len() / step * items);
    for i in (0..f.len()).step_by(step) {
        rec.extend_from_slice(f.record(i).unwrap());
    }
    h.ray_count = (rec.len() / items) as u64;
    RayFile::from_bytes(&encode(&h, &rec).unwrap(), "subsample.tm25ray").unwrap()
}

#[test]
fn kernels_shrink_as_rays_are_added() {
    // The measured LED with a tenth of its rays and with all of them: both widths narrower with
    // more rays (the rules give 10^(1/6) = 1.47× for the intensity and 10^(1/8) = 1.33× for the
    // spatial kernel).
    let full = RayFile::read(data(RAYSETS[0])).unwrap();
    let tenth = subsample(&full, 10);
    let (a, b) = (kde(&tenth).report, kde(&full).report);
    let ri = a.angular_kernel_deg.median / b.angular_kernel_deg.median;
    let rs = a.spatial_kernel_m.median / b.spatial_kernel_m.median;
    assert!(
        ri > 1.3,
        "intensity kernel {} → {} deg",
        a.angular_kernel_deg.median,
        b.angular_kernel_deg.median
    );
    assert!(
        rs > 1.15,
        "spatial kernel {} → {} m",
        a.spatial_kernel_m.median,
        b.spatial_kernel_m.median
    );
}

#[test]
fn a_pack_stores_the_proxy_and_its_kind() {
    let f = RayFile::read(data(RAYSETS[1])).unwrap();
    let e = kde(&f);
    let dir = std::env::temp_dir().join(format!("lumiview-rayfiles-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let tris = triangles_of(&e.proxy);
    let with = dir.join("with.lvpack");
    let opts = PackOptions {
        proxy: Some(PackProxy {
            triangles: tris.clone(),
            bound: true,
            source: "test".into(),
        }),
        ..PackOptions::default()
    };
    write_pack(&e.scan, &with, &opts, &|_, _| {}).unwrap();
    let p = Pack::open(&with).unwrap();
    let got = p.proxy().unwrap();
    assert_eq!(
        (got.triangles.len(), got.bound, got.source.as_str()),
        (tris.len(), true, "test")
    );
    assert_eq!(got.triangles, tris);
    assert_eq!(std::fs::read(&with).unwrap()[8], 2, "a pack with a proxy is version 2");
    // Without a proxy: version 1, as before.
    let without = dir.join("without.lvpack");
    write_pack(&e.scan, &without, &PackOptions::default(), &|_, _| {}).unwrap();
    assert_eq!(std::fs::read(&without).unwrap()[8], 1);
    assert!(Pack::open(&without).unwrap().proxy().is_none());
    // A flipped byte in the proxy section is found at open, naming it.
    let s = p.sections().iter().find(|s| s.name == "proxy").unwrap().clone();
    let mut bytes = std::fs::read(&with).unwrap();
    bytes[(s.offset + s.length / 2) as usize] ^= 0x40;
    let bad = dir.join("bad.lvpack");
    std::fs::write(&bad, &bytes).unwrap();
    match Pack::open(&bad) {
        Err(NearfieldError::Corrupt { section, .. }) => assert_eq!(section, "proxy"),
        other => panic!("{other:?}"),
    }
    let _ = std::fs::remove_dir_all(&dir);
}

fn lumiview(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_lumiview"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env(
            "LUMIVIEW_CACHE_DIR",
            std::env::temp_dir().join("lumiview-rayfiles-cache"),
        )
        .output()
        .unwrap()
}

#[test]
fn histogram_binning_says_when_it_is_speckle() {
    let out = lumiview(&[
        "rays2scan",
        data(RAYSETS[0]).to_str().unwrap(),
        "--method",
        "histogram",
        "--dry-run",
        "-o",
        "/tmp/x",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(e.contains("received no ray") && e.contains("--method kde"), "{e}");
    assert!(e.contains(RAYSETS[0]), "names the file: {e}");
}

fn lit_pixels(path: &Path) -> usize {
    let pm = tiny_skia::Pixmap::load_png(path).unwrap();
    pm.pixels().iter().filter(|p| p.red() > 20).count()
}

#[test]
fn every_ray_file_renders_its_source_from_the_default_eye_and_from_5_cm_to_2_m() {
    let _g = gpu_common::GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    if gpu_common::renderer().is_none() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("lumiview-rayrender-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for name in RAYSETS {
        let file = data(name);
        let f = RayFile::read(&file).unwrap();
        // The flux-weighted mean direction of the rays: where the source shows.
        let mut m = DVec3::ZERO;
        for i in 0..f.len() {
            let r = f.ray(i).unwrap();
            m += r.direction * r.luminous_lm.unwrap_or(0.0);
        }
        let m = m.normalize();
        // Frame the source: its proxy's radius, three times over, fills the field of view.
        let e = kde(&f);
        let c = e.scan.set.sphere.centre_m;
        let reach = e.proxy.surfaces[0]
            .positions
            .iter()
            .map(|p| (*p - c).length())
            .fold(0.0, f64::max);
        let out = dir.join("default.png");
        let o = lumiview(&[
            "render",
            file.to_str().unwrap(),
            "--exposure",
            "auto",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{name}: {}", String::from_utf8_lossy(&o.stderr));
        assert!(lit_pixels(&out) > 0, "{name}: nothing drawn from the default eye");
        for d in [0.05, 0.2, 2.0] {
            let eye = c + m * d;
            let cam = format!("{},{},{},{},{},{}", eye.x, eye.y, eye.z, c.x, c.y, c.z);
            let out = dir.join(format!("{d}.png"));
            let fov = format!("{}", (2.0 * (3.0 * reach / d).atan().to_degrees()).min(60.0));
            let fov = fov.as_str();
            let o = lumiview(&[
                "render",
                file.to_str().unwrap(),
                "--camera",
                &cam,
                "--fov",
                fov,
                "--exposure",
                "auto",
                "-o",
                out.to_str().unwrap(),
            ]);
            assert!(
                o.status.success(),
                "{name} at {d} m: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            assert!(lit_pixels(&out) > 0, "{name}: nothing drawn from {d} m");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_measured_led_far_field_matches_its_rays() {
    let _g = gpu_common::GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut r) = gpu_common::renderer() else { return };
    let f = RayFile::read(data(RAYSETS[0])).unwrap();
    let e = kde(&f);
    let tmp = std::env::temp_dir().join(format!("lumiview-led-{}.lvpack", std::process::id()));
    let c = lumiview::eval::rays::check_intensity(&mut r, &f, e, &tmp, 30.0, &|_| {}).unwrap();
    let _ = std::fs::remove_file(&tmp);
    // Measured (docs/rayfiles.md): bins median 8.7 % against their own 10.5 % noise; rings 1.5 %.
    assert!(c.median_rel < 0.12, "bins: median {}", c.median_rel);
    assert!(c.ring_median_rel < 0.05, "rings: median {}", c.ring_median_rel);
    gpu_common::assert_no_validation_messages();
}

#[test]
fn the_frozen_operator_on_the_estimates_own_rays_reproduces_it() {
    // The kernel-matched truth is the estimate's operator applied to other rays: applied to the
    // estimate's own rays (in two batches, each carrying half the flux twice over) it gives back
    // the estimate's images.
    let lum = luminaire("disc").unwrap();
    let rays = emit_rays(lum.as_ref(), 20_000, 5, &|_| {}).unwrap();
    let f = RayFile::from_bytes(&rays.to_tm25("lumiview test").unwrap(), "disc.tm25ray").unwrap();
    let keep = KdeOptions {
        keep_kernel_levels: true,
        ..KdeOptions::default()
    };
    let e = estimate(&f, &keep, &|_, _| {}).unwrap();
    // Without the kept levels the operator cannot be applied: an error, not level 0 everywhere.
    let mut none = || -> Result<Option<RayBatch>, NearfieldError> { Ok(None) };
    let err = estimate_frozen(&kde(&f), &mut none, &|_, _| {}).unwrap_err();
    assert!(err.to_string().contains("keep_kernel_levels"), "{err}");
    let batch: RayBatch = (0..rays.len())
        .map(|i| (rays.origins[i], rays.directions[i], rays.flux_lm[i] / 2.0))
        .collect();
    let mut left = 2;
    let mut next = || -> Result<Option<RayBatch>, NearfieldError> {
        left -= 1;
        Ok((left >= 0).then(|| batch.clone()))
    };
    let t = estimate_frozen(&e, &mut next, &|_, _| {}).unwrap();
    let (mut worst, mut total) = (0.0f64, 0.0f64);
    for i in 0..e.scan.set.cameras.len() {
        let a = e.scan.source.image(i).unwrap();
        let b = t.scan.source.image(i).unwrap();
        for (x, y) in a.data.iter().zip(&b.data) {
            worst = worst.max(f64::from((x - y).abs()));
            total = total.max(f64::from(*x));
        }
    }
    assert!(worst <= 1e-4 * total, "largest difference {worst} cd/m² of {total}");
    // The file stores fluxes as f32.
    assert!((t.report.flux_lm / e.report.flux_lm - 1.0).abs() < 1e-5);
}
