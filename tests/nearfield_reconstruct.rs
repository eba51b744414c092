//! The proxy reconstructed from a scan (issue 17): its distance to the true proxy on synthetic
//! luminaires, the guard that drops a proxy that would hide light, and the path from a manifest to
//! a pack that stores it. Small images (128 × 128 px) keep this fast; `lumiview proxy --synth all`
//! measures the full table (docs/proxy.md).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;

use lumiview::nearfield::layout::Layout;
use lumiview::nearfield::manifest::write_scan;
use lumiview::nearfield::pack::{write_pack, Pack, PackOptions};
use lumiview::nearfield::proxy::triangles_of;
use lumiview::nearfield::reconstruct::{
    chamfer, reconstruct, reconstruct_refined, scan_proxy, window_intrinsics, FineImages, ReconstructOptions,
    CAPTURE_SUPERSAMPLE, MIN_COVERAGE, PROXY_IS_BOUND,
};
use lumiview::nearfield::scanfile::{scan_from_file_with_warnings, ScanFileKind};
use lumiview::nearfield::synth::{self, synth_scan, SynthOptions};

fn opts(luminaire: &str, per_hemisphere: usize, supersample: u32) -> SynthOptions {
    SynthOptions {
        luminaire: luminaire.into(),
        layout: Layout::Rigo {
            per_hemisphere,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        },
        size: (128, 128),
        supersample,
        ..SynthOptions::default()
    }
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lumiview-reconstruct-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Chamfer distance (mm) to the true proxy within half the limit (1 % of the bounding
/// diameter or two capture-pixel footprints), the flat parts collapsed onto their middle and put on
/// the plane the images agree on, and nearly all lit pixels explained, at rigo:300 (the default
/// layout of `lumiview proxy --synth`), 128 × 128 px. Measured (this set-up, 2026-11-27): disc mean
/// 0.13 mm, p95 0.14 mm (limit 5.57); two-planes 0.24 / 0.41 mm (limit 6.66; 0.26 / 0.90 before
/// thin parts' rims stopped collapsing inwards); star-panel 0.07 / 0.07 mm (limit 8.92); coverage
/// 0.995–1.000. Before the flat-part step (docs/proxy.md, step 5): disc 0.52 / 1.27
/// mm, two-planes 0.69 / 1.96 mm.
#[test]
fn reconstruction_is_near_the_true_proxy() {
    for (name, max_mean_mm) in [("disc", 0.3), ("two-planes", 0.5), ("star-panel", 0.5)] {
        let scan = synth_scan(&opts(name, 300, 3)).unwrap();
        let mut warnings = Vec::new();
        let rec = scan_proxy(&scan, name, &|_, _, _| {}, &mut warnings)
            .unwrap()
            .unwrap_or_else(|| panic!("{name}: no proxy: {warnings:?}"));
        assert!(warnings.is_empty(), "{name}: {warnings:?}");
        let lum = synth::luminaire(name).unwrap();
        let c = chamfer(&rec.mesh.soup(), &triangles_of(&lum.proxy()), 50_000);
        let limit_mm = limit_mm(&scan, 2.0 * lum.bounds().radius() * 1e3);
        let (mean_mm, p95_mm) = (c.mean_m * 1e3, c.p95_m * 1e3);
        eprintln!(
            "{name}: mean {mean_mm:.2} mm, p95 {p95_mm:.2} mm (limit {limit_mm:.2}), coverage {:.3}, {} triangles",
            rec.report.coverage, rec.report.triangles
        );
        assert!(
            p95_mm <= 0.25 * limit_mm,
            "{name}: p95 {p95_mm:.2} mm above a quarter of the limit {limit_mm:.2} mm"
        );
        assert!(rec.report.collapsed_vertices > 0, "{name}: nothing collapsed");
        // Put on the plane the images agree on: most of the mesh's vertices in flat parts.
        let flat: usize = rec.report.flat_parts.iter().map(|f| f.vertices + f.absorbed).sum();
        assert!(
            2 * flat > rec.mesh.vertices.len(),
            "{name}: {flat} of {} vertices in flat parts",
            rec.mesh.vertices.len()
        );
        assert!(
            mean_mm <= max_mean_mm,
            "{name}: mean {mean_mm:.2} mm above {max_mean_mm} mm"
        );
        assert!(rec.report.coverage > 0.95, "{name}: coverage {}", rec.report.coverage);
        // Stored as a surface proxy that says where it came from.
        let p = rec.to_pack_proxy();
        assert!(
            p.bound == PROXY_IS_BOUND && p.source.starts_with("reconstructed"),
            "{p:?}"
        );
        assert_eq!(p.triangles.len(), 3 * rec.report.triangles);
    }
}

/// Beams and small features (docs/proxy.md, steps 2 and 4): `cos100` is seen lit only within 29°
/// of its axis, and the cameras beyond see its front dark; its carved lens, a double cone 1.8
/// radii thick, goes onto the plane of its rim along the beam's axis. `led-dots`' 3 mm dots are
/// missed by point-sampled cameras below 6° of their plane; the scan is carved again with a 30°
/// grazing tolerance. Both within half the limit, with nearly all the light explained, at
/// rigo:300, 128 × 128 px. Measured (this set-up, 2026-11-27): cos100 mean 0.13 mm, p95 0.16 mm
/// (limit 2.77), 374 of 544 cameras carving (the others see its front from outside the beam);
/// led-dots 0.05 / 0.18 mm (limit 3.81), carved at 30°; coverage 1.000.
#[test]
fn beams_and_small_features_get_a_proxy() {
    // led-dots at 256 px: its 3 mm dots are then about three capture pixels across, what the
    // redrawing needs to tell their area (at 128 px, 1.6 pixels across, they come out 39 % large:
    // docs/proxy.md, known limits).
    for (name, grazing_deg, px) in [("cos100", 1.0, 128), ("led-dots", 30.0, 256)] {
        let scan = synth_scan(&SynthOptions {
            size: (px, px),
            ..opts(name, 300, 3)
        })
        .unwrap();
        let mut warnings = Vec::new();
        let rec = scan_proxy(&scan, name, &|_, _, _| {}, &mut warnings)
            .unwrap()
            .unwrap_or_else(|| panic!("{name}: no proxy: {warnings:?}"));
        let lum = synth::luminaire(name).unwrap();
        let c = chamfer(&rec.mesh.soup(), &triangles_of(&lum.proxy()), 50_000);
        let limit_mm = limit_mm(&scan, 2.0 * lum.bounds().radius() * 1e3);
        let (mean_mm, p95_mm) = (c.mean_m * 1e3, c.p95_m * 1e3);
        let r = &rec.report;
        eprintln!(
            "{name}: mean {mean_mm:.2} mm, p95 {p95_mm:.2} mm (limit {limit_mm:.2}), coverage {:.3}, grazing {:.0}°, {} of {} cameras, {} triangles",
            r.coverage, r.grazing_deg, r.cameras_used, r.cameras_read, r.triangles
        );
        assert!(
            p95_mm <= 0.5 * limit_mm,
            "{name}: p95 {p95_mm:.2} mm above half the limit {limit_mm:.2} mm"
        );
        assert!(r.coverage > 0.95, "{name}: coverage {}", r.coverage);
        assert!(
            (r.grazing_deg - grazing_deg).abs() < 1e-9,
            "{name}: grazing {}°",
            r.grazing_deg
        );
        if name == "led-dots" {
            // Each dot redrawn from the images (docs/proxy.md, step 5): a polygon on both sheets,
            // of the dot's area; the mesh is nothing else, so half its area is the dots'.
            let redrawn: usize = r.flat_parts.iter().map(|f| f.redrawn).sum();
            let ratio = rec.mesh.area() / 2.0 / (32.0 * std::f64::consts::PI * 1.5e-3f64.powi(2));
            eprintln!("led-dots: {redrawn} dots redrawn, area {ratio:.4} of the dots'");
            assert_eq!(redrawn, 32);
            assert!(
                (ratio - 1.0).abs() < DOTS_AREA_TOLERANCE,
                "area {ratio:.4} of the dots'"
            );
        }
    }
}

/// The dots' area after redrawing, measured 0.4 % large here (rigo:300, 256 px; the rendered flux,
/// which the contract asks within 1 %, follows it: docs/proxy.md); crumpled and followed vertex by
/// vertex it was 3–28 % too large.
const DOTS_AREA_TOLERANCE: f64 = 0.01;

/// The known limit at a sparse layout (docs/proxy.md): at rigo:150 the disc keeps part of a
/// floating lens bottom in front of it (measured mean 0.82 mm, max 16.8 mm; before the flat-part
/// step 1.60 mm and 25 mm: the uniform disc gives the luminance test little to tell the lens from
/// the disc by). Held so that it cannot quietly get worse, and so that a fix shows here.
#[test]
fn a_sparse_layout_leaves_a_bounded_lens_under_the_disc() {
    let o = opts("disc", 150, 3);
    let scan = synth_scan(&o).unwrap();
    let mut warnings = Vec::new();
    let rec = scan_proxy(&scan, "disc", &|_, _, _| {}, &mut warnings)
        .unwrap()
        .unwrap();
    let lum = synth::luminaire("disc").unwrap();
    let c = chamfer(&rec.mesh.soup(), &triangles_of(&lum.proxy()), 50_000);
    let (mean_mm, max_mm) = (c.mean_m * 1e3, c.max_m * 1e3);
    eprintln!("disc at rigo:150: mean {mean_mm:.2} mm, max {max_mm:.2} mm");
    assert!(
        mean_mm <= 1.2 && max_mm <= 22.0,
        "mean {mean_mm:.2} mm, max {max_mm:.2} mm"
    );
}

/// The mirror: the lamp's light moves over `reflector`'s mirror with the view, so no surface holds
/// it still; the mesh explains little of the light (measured 4.2 % here, 8.4 % at rigo:300,
/// 256 px) and is dropped with a warning rather than stored (a surface proxy would hide the light).
#[test]
fn a_proxy_that_hides_the_light_is_dropped() {
    let scan = synth_scan(&opts("reflector", 150, 3)).unwrap();
    let mut warnings = Vec::new();
    let rec = scan_proxy(&scan, "reflector", &|_, _, _| {}, &mut warnings).unwrap();
    assert!(rec.is_none());
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].starts_with("reflector: ") && warnings[0].contains("lit pixels"),
        "{warnings:?}"
    );
}

/// `peak`: a 10⁶ cd/m² spot on a 1 cd/m² background, 10⁻⁶ of the spot, below the masks' default
/// threshold (10⁻⁴ of each image's maximum): every camera that sees the spot sees the background
/// dark and carves it (the mesh explained 15 % of the light). The masks made again above each
/// image's noise recover the background, also under Gaussian noise of 0.05 cd/m² (negative pixels
/// included, as a dark-corrected camera gives them): 6 σ = 0.3 cd/m² lies below the background and
/// far above 10⁻⁷ of the spot, so a mask made at 10⁻⁷ without looking at the noise would light
/// every pixel.
#[test]
fn a_dim_background_beside_a_bright_spot_is_found_above_the_noise() {
    let scan = synth_scan(&opts("peak", 150, 3)).unwrap();
    let noisy = |i: usize| {
        scan.source.image(i).map(|mut img| {
            for (k, v) in img.data.iter_mut().enumerate() {
                *v += 0.05 * normal((i as u64) << 32 | k as u64);
            }
            img
        })
    };
    let rec = reconstruct(&scan.set, &noisy, &ReconstructOptions::default(), &|_, _, _| {}).unwrap();
    let lum = synth::luminaire("peak").unwrap();
    let c = chamfer(&rec.mesh.soup(), &triangles_of(&lum.proxy()), 50_000);
    let r = &rec.report;
    let limit_mm = limit_mm(&scan, 2.0 * lum.bounds().radius() * 1e3);
    eprintln!(
        "noisy peak: mean {:.2} mm, p95 {:.2} mm (limit {limit_mm:.2}), coverage {:.3}, masks at {:e}, {} of {} cameras above their noise",
        c.mean_m * 1e3,
        c.p95_m * 1e3,
        r.coverage,
        r.lit_relative,
        r.noise_floored,
        r.cameras_read
    );
    assert!(r.coverage >= MIN_COVERAGE, "coverage {}", r.coverage);
    assert_eq!(r.lit_relative, ReconstructOptions::default().deep_relative);
    assert!(
        r.noise_floored * 2 > r.cameras_read,
        "{} of {}",
        r.noise_floored,
        r.cameras_read
    );
    assert!(c.p95_m * 1e3 <= 0.5 * limit_mm, "p95 {:.2} mm", c.p95_m * 1e3);
}

/// led-dots (300,000 cd/m²) under Gaussian noise of 600 cd/m², 0.2 % of the dots' luminance: the
/// noise lies far above the masks' 10⁻⁴ of the images' maximum (30 cd/m²) and the redrawing's
/// floor of 10⁻³. The masks are made above each image's noise (made at 10⁻⁴ alone they lit the
/// noise, and the proxy was the whole content ball, 5 × 10⁴ times the dots' area, after 5 min),
/// and the dots are still redrawn with their area, each camera's floor there above its own noise
/// (without it the noise joined the dots' light to the grid's border: none redrawn, and the
/// crumpled dots 5 times their area). Measured: 32 redrawn, area 1.0054.
#[test]
fn led_dots_under_noise_are_redrawn_with_their_area() {
    let scan = synth_scan(&SynthOptions {
        size: (256, 256),
        ..opts("led-dots", 300, 3)
    })
    .unwrap();
    let noisy = |i: usize| {
        scan.source.image(i).map(|mut img| {
            for (k, v) in img.data.iter_mut().enumerate() {
                *v += 600.0 * normal((i as u64) << 32 | k as u64);
            }
            img
        })
    };
    let rec = reconstruct(&scan.set, &noisy, &ReconstructOptions::default(), &|_, _, _| {}).unwrap();
    let r = &rec.report;
    let redrawn: usize = r.flat_parts.iter().map(|f| f.redrawn).sum();
    let ratio = rec.mesh.area() / 2.0 / (32.0 * std::f64::consts::PI * 1.5e-3f64.powi(2));
    eprintln!(
        "noisy led-dots: {redrawn} dots redrawn, area {ratio:.4} of the dots', coverage {:.3}, {} of {} cameras above their noise",
        r.coverage, r.noise_floored, r.cameras_read
    );
    assert!(r.coverage >= MIN_COVERAGE, "coverage {}", r.coverage);
    assert!(
        r.noise_floored * 2 > r.cameras_read,
        "{} of {}",
        r.noise_floored,
        r.cameras_read
    );
    assert_eq!(redrawn, 32);
    assert!(
        (ratio - 1.0).abs() < DOTS_AREA_TOLERANCE,
        "area {ratio:.4} of the dots'"
    );
}

/// `strips`' five 1 mm strips, 300 mm long, carve to lenses about as thick as they are wide (cells
/// of 1.54 mm, captures of 256 px): each is a line, whose plane the cameras' light gives
/// (docs/proxy.md, step 5), and each is redrawn whole as a flat band. Refined from images of 1024
/// px (0.38 mm pixels, a strip 2.6 pixels across), as a real scan's reconstruction reads its own
/// images, the bands come out 1 mm wide and at the strips' depth. Measured (2026-11-27): 5 bands,
/// area 1.011 of the strips', every triangle within 2.7° of the strips' plane (the roll about a
/// band's axis, fitted to its edges), every vertex within 0.029 mm of it (with a budget of 2²²
/// pixels, 16 refinement cameras, tried in session 27: 4.8°, area 1.022). Before lines were found,
/// each strip was flattened onto a plane standing on edge (its lens' widest section): rendered with
/// that proxy, the strips lost 92 % of their flux. At 128 px (strips a third of a pixel wide) the
/// five lenses carve into one part (docs/proxy.md, known limits).
#[test]
fn strips_are_redrawn_as_flat_bands_of_their_width() {
    let scan = synth_scan(&SynthOptions {
        size: (256, 256),
        ..opts("strips", 300, 3)
    })
    .unwrap();
    let mut fine_set = scan.set.clone();
    let (w, h) = (1024, 1024);
    let k = synth::framing_intrinsics(
        synth::luminaire("strips").unwrap().as_ref(),
        w,
        h,
        fine_set.sphere.radius_m,
    )
    .unwrap();
    fine_set.intrinsics = k;
    let lum = synth::luminaire("strips").unwrap();
    let window = |i: usize, crop: [u32; 4]| {
        let k = window_intrinsics(fine_set.intrinsics_of(i), crop);
        synth::render_pinhole(lum.as_ref(), &fine_set.cameras[i], &k, CAPTURE_SUPERSAMPLE)
    };
    let fine = FineImages {
        set: &fine_set,
        window: &window,
    };
    let rec = reconstruct_refined(
        &scan.set,
        &|i| scan.source.image(i),
        Some(fine),
        &ReconstructOptions::default(),
        &|_, _, _| {},
    )
    .unwrap();
    let r = &rec.report;
    let redrawn: usize = r.flat_parts.iter().map(|f| f.redrawn).sum();
    let ratio = rec.mesh.area() / 2.0 / (5.0 * 1e-3 * 0.3);
    let (mut tilt, mut depth) = (0.0f64, 0.0f64);
    for t in &rec.mesh.triangles {
        let [a, b, c] = t.map(|i| rec.mesh.vertices[i as usize]);
        let n = (b - a).cross(c - a).normalize();
        tilt = tilt.max(n.z.abs().min(1.0).acos().to_degrees());
        depth = depth.max(a.z.abs()).max(b.z.abs()).max(c.z.abs());
    }
    eprintln!(
        "strips: {redrawn} bands, area {ratio:.4} of the strips', tilt {tilt:.3}°, depth {:.3} mm, {} triangles",
        depth * 1e3,
        r.triangles
    );
    assert_eq!(redrawn, 5);
    assert!((ratio - 1.0).abs() < 0.02, "area {ratio:.4} of the strips'");
    assert!(tilt < 5.0, "a triangle {tilt:.3}° from the strips' plane");
    assert!(depth < 0.05e-3, "a vertex {:.3} mm from the strips' plane", depth * 1e3);
}

/// From images of 1024 px (0.38 mm pixels) carving itself breaks `strips`' strips into pieces
/// (cells of 1.53 mm: a pixel beside a strip sees part of each cell over its edge dark); each piece
/// that is a line is extended along the strip while the light goes on, the copies are merged and
/// what lies under a band is dropped, so each strip is one band with no gap, as `lumiview pack`
/// stores it. Measured (2026-11-27): 14 pieces, every strip's middle covered from end to end, area
/// 1.02 of the strips', every vertex within 0.15 mm of their plane. Before the extension each
/// piece's band ended with the piece, and the strips rendered with black gaps.
#[test]
fn strips_carved_into_pieces_are_one_band_each() {
    let scan = synth_scan(&SynthOptions {
        size: (1024, 1024),
        ..opts("strips", 300, 3)
    })
    .unwrap();
    let mut warnings = Vec::new();
    let rec = scan_proxy(&scan, "strips", &|_, _, _| {}, &mut warnings)
        .unwrap()
        .unwrap_or_else(|| panic!("no proxy: {warnings:?}"));
    let m = &rec.mesh;
    let covers = |x: f64, y: f64| {
        m.triangles.iter().any(|t| {
            let [a, b, c] = t.map(|i| m.vertices[i as usize]);
            let s = |p: glam::DVec3, q: glam::DVec3| (q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x);
            let (d0, d1, d2) = (s(a, b), s(b, c), s(c, a));
            (d0 >= 0.0 && d1 >= 0.0 && d2 >= 0.0) || (d0 <= 0.0 && d1 <= 0.0 && d2 <= 0.0)
        })
    };
    let mut gaps = Vec::new();
    for k in 0..5 {
        let y = (k as f64 - 2.0) * 0.02;
        for i in 0..150 {
            let x = -0.149 + 0.002 * i as f64;
            if !covers(x, y) {
                gaps.push((x, y));
            }
        }
    }
    let ratio = m.area() / 2.0 / (5.0 * 1e-3 * 0.3);
    let depth = m.vertices.iter().map(|v| v.z.abs()).fold(0.0, f64::max);
    eprintln!(
        "strips at 1024 px: {} pieces, {} of 750 middle points uncovered, area {ratio:.4} of the strips', depth {:.3} mm",
        rec.report.flat_parts.len(),
        gaps.len(),
        depth * 1e3
    );
    assert!(gaps.is_empty(), "middle points uncovered (m): {gaps:?}");
    assert!((ratio - 1.0).abs() < 0.05, "area {ratio:.4} of the strips'");
    assert!(depth < 0.3e-3, "a vertex {:.3} mm from the strips' plane", depth * 1e3);
}

/// A standard normal number from `key` (splitmix64 and Box–Muller).
fn normal(key: u64) -> f32 {
    let mix = |z: u64| (lumiview::scene::sampling::splitmix64(z) >> 11) as f64 / (1u64 << 53) as f64;
    let (u, v) = (mix(2 * key).max(1e-300), mix(2 * key + 1));
    ((-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()) as f32
}

/// The Chamfer limit of docs/proxy.md: the larger of 1 % of the luminaire's bounding diameter and
/// two capture-pixel footprints at the centre (mm).
fn limit_mm(scan: &lumiview::nearfield::Scan, diam_mm: f64) -> f64 {
    let k = scan.set.intrinsics_of(0);
    let footprint_mm = scan.set.sphere.radius_m / k.focal_px.x.max(k.focal_px.y) * 1e3;
    (0.01 * diam_mm).max(2.0 * footprint_mm)
}

/// A manifest comes without a mesh: loading it as `render` and `lumi_luminaire_load` do gives the
/// reconstructed proxy, and a pack written with it stores and reads it back.
#[test]
fn a_manifest_gets_a_reconstructed_proxy_in_its_pack() {
    let dir = tmp("manifest");
    let scan = synth_scan(&opts("disc", 150, 1)).unwrap();
    let manifest = write_scan(&dir, &scan, &|_, _| {}).unwrap();
    let mut warnings = Vec::new();
    let (scan, desc, proxy) = scan_from_file_with_warnings(&manifest, ScanFileKind::Manifest, &mut warnings).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let proxy = proxy.expect("a reconstructed proxy");
    assert!(
        proxy.bound == PROXY_IS_BOUND && proxy.source.starts_with("reconstructed"),
        "{}",
        proxy.source
    );
    let path = dir.join("disc.lvpack");
    write_pack(
        &scan,
        &path,
        &PackOptions {
            source: desc,
            proxy: Some(proxy.clone()),
            ..PackOptions::default()
        },
        &|_, _| {},
    )
    .unwrap();
    assert_eq!(Pack::open(&path).unwrap().proxy(), Some(&proxy));
    let _ = std::fs::remove_dir_all(&dir);
}
