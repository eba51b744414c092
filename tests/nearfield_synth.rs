//! The synthetic goniophotometer against its exact ground truth: orthographic Σ L·ΔA against the
//! closed-form intensities, flux against ∫ I dω, pinhole renders against the projection of the
//! geometry, determinism, the reflector's energy balance, proxy meshes through a glTF reader, and the
//! `lumiview synth` command line.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::f64::consts::PI;
use std::process::Command;

use glam::{DVec2, DVec3};
use lumiview::nearfield::layout::{direction_deg, Layout};
use lumiview::nearfield::rayset::{Camera, CaptureSphere, Hemisphere, Intrinsics};
use lumiview::nearfield::synth::{
    luminaire, ortho_intensity, render_all, render_ortho, render_pinhole, synth_scan, Luminaire, OrthoView, Reflector,
    SynthOptions, NAMES,
};

/// Gauss–Legendre nodes and weights on [a, b].
fn gauss_legendre(n: usize, a: f64, b: f64) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 1..=n {
        let mut x = (PI * (i as f64 - 0.25) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        out.push((0.5 * (a + b) + 0.5 * (b - a) * x, 0.5 * (b - a) * w));
    }
    out
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// ∫ I dω over the sphere: Gauss–Legendre in μ = −cos γ… (64 nodes per hemisphere) × `nphi` φ steps.
fn integrate_intensity(lum: &dyn Luminaire, nphi: usize) -> f64 {
    let mut sum = 0.0;
    for (mu, w) in gauss_legendre(64, 0.0, 1.0)
        .into_iter()
        .chain(gauss_legendre(64, -1.0, 0.0))
    {
        let s = (1.0 - mu * mu).sqrt();
        for k in 0..nphi {
            let phi = 2.0 * PI * (k as f64 + 0.5) / nphi as f64;
            let d = DVec3::new(s * phi.cos(), s * phi.sin(), -mu);
            sum += w * (2.0 * PI / nphi as f64) * lum.intensity_cd(d);
        }
    }
    sum
}

#[test]
fn disc_orthographic_intensity_is_l_a_cos_gamma() {
    let disc = luminaire("disc").unwrap();
    let (l, a) = (10_000.0, PI * 0.01);
    for (c, g) in [(0.0, 0.0), (30.0, 20.0), (90.0, 45.0), (200.0, 60.0), (45.0, 80.0)] {
        let d = direction_deg(c, g);
        let exact = l * a * g.to_radians().cos();
        assert!(rel(disc.intensity_cd(d), exact) < 1e-12);
        let sum = ortho_intensity(disc.as_ref(), d, 0.5e-3, 2).unwrap();
        let e = rel(sum, exact);
        println!(
            "disc C {c}° γ {g}°: Σ L·ΔA {sum:.4} cd, exact {exact:.4} cd, error {:.4} %",
            100.0 * e
        );
        assert!(e < 1e-3, "C {c} γ {g}: {sum} vs {exact}");
    }
    // Nothing above the horizon: the back is black.
    assert_eq!(
        ortho_intensity(disc.as_ref(), direction_deg(0.0, 120.0), 1e-3, 1).unwrap(),
        0.0
    );
    assert_eq!(disc.intensity_cd(direction_deg(0.0, 120.0)), 0.0);
}

#[test]
fn disc_flux_is_pi_l_a_from_orthographic_renders() {
    let disc = luminaire("disc").unwrap();
    let exact = PI * 10_000.0 * PI * 0.01;
    assert!(rel(disc.flux_lm(), exact) < 1e-12);
    // Φ = 2π ∫₀¹ I(μ) dμ for an axially symmetric emitter (μ = cos γ); I from orthographic renders at
    // Gauss–Legendre nodes, each at a different C to exercise the azimuth too.
    let mut flux = 0.0;
    for (k, (mu, w)) in gauss_legendre(4, 0.0, 1.0).into_iter().enumerate() {
        let d = direction_deg(77.0 * k as f64, mu.acos().to_degrees());
        flux += 2.0 * PI * w * ortho_intensity(disc.as_ref(), d, 0.5e-3, 2).unwrap();
    }
    let e = rel(flux, exact);
    println!(
        "disc flux from renders {flux:.3} lm, exact {exact:.3} lm, error {:.4} %",
        100.0 * e
    );
    assert!(e < 1e-3);
}

#[test]
fn closed_form_flux_equals_the_integral_of_intensity() {
    for name in NAMES {
        let lum = luminaire(name).unwrap();
        if !lum.closed_form() {
            continue;
        }
        let integral = integrate_intensity(lum.as_ref(), 96);
        let e = rel(integral, lum.flux_lm());
        println!(
            "{name}: flux {:.4} lm, ∫ I dω {integral:.4} lm, {:.5} %",
            lum.flux_lm(),
            100.0 * e
        );
        assert!(e < 2e-4, "{name}: {} vs {integral}", lum.flux_lm());
    }
}

/// (luminaire, pixel (m), supersampling, directions as (C, γ) in degrees).
type Case = (&'static str, f64, u32, &'static [(f64, f64)]);

#[test]
fn orthographic_intensity_matches_closed_forms() {
    let cases: &[Case] = &[
        // Generic azimuths: edges cross the pixel grid obliquely (see the aligned-edge test).
        (
            "rect",
            0.5e-3,
            2,
            &[(0.0, 0.0), (20.0, 40.0), (110.0, 70.0), (30.0, 85.0)],
        ),
        ("cos1", 0.25e-3, 2, &[(0.0, 0.0), (45.0, 60.0)]),
        ("cos10", 0.25e-3, 2, &[(0.0, 0.0), (10.0, 15.0), (120.0, 40.0)]),
        ("cos100", 0.25e-3, 2, &[(0.0, 0.0), (0.0, 5.0), (300.0, 12.0)]),
        // Not at nadir: there the star's centre lies on the sample lattice and its 45° edges run
        // through samples, which all fall on one side (a bias of O(sub-sample), 0.1 % here).
        ("star-panel", 0.5e-3, 2, &[(7.0, 3.0), (20.0, 50.0), (135.0, 30.0)]),
        (
            "two-planes",
            0.25e-3,
            2,
            &[(0.0, 0.0), (0.0, 20.0), (45.0, 35.0), (100.0, 60.0)],
        ),
    ];
    for (name, pixel, ss, dirs) in cases {
        let lum = luminaire(name).unwrap();
        for &(c, g) in *dirs {
            let d = direction_deg(c, g);
            let exact = lum.intensity_cd(d);
            let sum = ortho_intensity(lum.as_ref(), d, *pixel, *ss).unwrap();
            let e = rel(sum, exact);
            println!(
                "{name} C {c}° γ {g}°: Σ L·ΔA {sum:.4} cd, exact {exact:.4} cd, {:.4} %",
                100.0 * e
            );
            assert!(e < 1e-3, "{name} C {c} γ {g}: {sum} vs {exact}");
        }
    }
}

#[test]
fn led_dots_intensity_from_windows_around_each_dot() {
    // 3 mm dots: render a 4 mm window around each (nothing else emits) at 20 µm pixels, 2 × 2 rays.
    let lum = luminaire("led-dots").unwrap();
    for (c, g) in [(0.0, 0.0), (60.0, 45.0), (170.0, 75.0)] {
        let d = direction_deg(c, g);
        let mut sum = 0.0;
        for j in 0..4 {
            for i in 0..8 {
                let centre = DVec3::new((i as f64 - 3.5) * 0.025, (j as f64 - 1.5) * 0.025, 0.0);
                let view = OrthoView {
                    direction: d,
                    centre_m: centre,
                    pixel_m: 20e-6,
                    width: 200,
                    height: 200,
                };
                let img = render_ortho(lum.as_ref(), &view, 2).unwrap();
                sum += img.data.iter().map(|&x| f64::from(x)).sum::<f64>() * view.pixel_area_m2();
            }
        }
        let exact = lum.intensity_cd(d);
        println!(
            "led-dots C {c}° γ {g}°: {sum:.4} vs {exact:.4} cd ({:.4} %)",
            100.0 * rel(sum, exact)
        );
        assert!(rel(sum, exact) < 1e-3, "C {c} γ {g}: {sum} vs {exact}");
    }
}

#[test]
fn aligned_thin_features_stay_within_one_subsample_per_edge() {
    // Point sampling of straight edges parallel to the pixel grid is off by less than one sub-sample
    // per edge crossing, with no averaging between rows: the worst case of a regular grid. Seen from
    // C90 the strips (along X) and the rectangle's long edges are parallel to the image rows.
    // Bound: |Σ − I| < L · (edges crossed per row) · (rows crossing) · sub².
    let sub = 0.25e-3 / 4.0;
    for (name, n_features, length) in [("strips", 5.0, 0.3), ("rect", 1.0, 0.6)] {
        let lum = luminaire(name).unwrap();
        let l = lum.max_luminance();
        for (c, g) in [(90.0, 30.0), (90.0, 70.0), (10.0, 60.0), (0.0, 0.0)] {
            let d = direction_deg(c, g);
            let exact = lum.intensity_cd(d);
            let sum = ortho_intensity(lum.as_ref(), d, 0.25e-3, 4).unwrap();
            let bound = l * n_features * (length / sub + 2.0) * sub * sub;
            println!(
                "{name} C {c}° γ {g}°: Σ L·ΔA {sum:.4} cd, exact {exact:.4} cd, {:+.4} % (bound {:.3} %)",
                100.0 * (sum - exact) / exact,
                100.0 * bound / exact
            );
            assert!((sum - exact).abs() < bound, "{name} C {c} γ {g}: {sum} vs {exact}");
        }
    }
}

#[test]
fn peak_intensity_with_a_refined_window() {
    // The 10⁶ cd/m² disc carries 99.8 % of the intensity and is only 5 mm across: integrate the
    // background on a coarse view and an 8 × 8-pixel window around the peak on a 40× finer one.
    let lum = luminaire("peak").unwrap();
    let peak = DVec3::new(0.03, 0.02, 0.0);
    for (c, g) in [(0.0, 0.0), (45.0, 30.0), (200.0, 60.0)] {
        let d = direction_deg(c, g);
        let coarse = OrthoView::framing(&lum.bounds(), d, 1e-3).unwrap();
        let img = render_ortho(lum.as_ref(), &coarse, 1).unwrap();
        let (right, down, _) = lumiview::nearfield::rayset::look_at_basis(-coarse.direction);
        let u = 0.5 * f64::from(coarse.width) + (peak - coarse.centre_m).dot(right) / coarse.pixel_m;
        let v = 0.5 * f64::from(coarse.height) + (peak - coarse.centre_m).dot(down) / coarse.pixel_m;
        let (c0, r0) = (u.floor() as i64 - 4, v.floor() as i64 - 4);
        let mut sum = 0.0;
        for row in 0..coarse.height as i64 {
            for col in 0..coarse.width as i64 {
                if (c0..c0 + 8).contains(&col) && (r0..r0 + 8).contains(&row) {
                    continue;
                }
                sum += f64::from(img.get(col as u32, row as u32)) * coarse.pixel_area_m2();
            }
        }
        let m = 40u32;
        let fine = OrthoView {
            direction: coarse.direction,
            centre_m: coarse.centre_m
                + right * ((c0 + 4) as f64 - 0.5 * f64::from(coarse.width)) * coarse.pixel_m
                + down * ((r0 + 4) as f64 - 0.5 * f64::from(coarse.height)) * coarse.pixel_m,
            pixel_m: coarse.pixel_m / f64::from(m),
            width: 8 * m,
            height: 8 * m,
        };
        let fimg = render_ortho(lum.as_ref(), &fine, 2).unwrap();
        sum += fimg.data.iter().map(|&x| f64::from(x)).sum::<f64>() * fine.pixel_area_m2();
        let exact = lum.intensity_cd(d);
        println!(
            "peak C {c}° γ {g}°: {sum:.5} vs {exact:.5} cd ({:.4} %)",
            100.0 * rel(sum, exact)
        );
        assert!(rel(sum, exact) < 1e-3, "C {c} γ {g}: {sum} vs {exact}");
    }
    assert!(lum.max_luminance() == 1.0e6);
}

fn small_intrinsics(w: u32, h: u32, f: f64) -> Intrinsics {
    Intrinsics {
        width: w,
        height: h,
        principal_px: DVec2::new(f64::from(w) / 2.0, f64::from(h) / 2.0),
        focal_px: DVec2::splat(f),
    }
}

/// Whether `p` is inside the closed polygon `poly`, and its distance to the polygon's edges.
fn inside_and_distance(poly: &[DVec2], p: DVec2) -> (bool, f64) {
    let mut inside = false;
    let mut dist = f64::INFINITY;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
        let ab = b - a;
        let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
        dist = dist.min((a + ab * t - p).length());
    }
    (inside, dist)
}

#[test]
fn pinhole_renders_see_the_disc_where_the_projection_says() {
    let disc = luminaire("disc").unwrap();
    let sphere = CaptureSphere {
        centre_m: DVec3::ZERO,
        radius_m: 1.117,
    };
    let k = small_intrinsics(160, 120, 500.0);
    for (c, g) in [(0.0, 0.0), (30.0, 35.0), (250.0, 70.0)] {
        let cam = Camera::on_sphere(&sphere, direction_deg(c, g), Hemisphere::Lower, "t".into());
        let img = render_pinhole(disc.as_ref(), &cam, &k, 1).unwrap();
        // The disc's rim projected through the pinhole (independent of the ray caster).
        let rim: Vec<DVec2> = (0..720)
            .map(|i| {
                let a = 2.0 * PI * i as f64 / 720.0;
                let p = DVec3::new(0.1 * a.cos(), 0.1 * a.sin(), 0.0);
                k.project(cam.to_camera(p - cam.position_m)).unwrap()
            })
            .collect();
        let mut checked = 0;
        for row in 0..k.height {
            for col in 0..k.width {
                let p = DVec2::new(f64::from(col) + 0.5, f64::from(row) + 0.5);
                let (inside, dist) = inside_and_distance(&rim, p);
                if dist < 0.05 {
                    continue; // on the rim: either value is right
                }
                let v = img.get(col, row);
                assert_eq!(
                    v,
                    if inside { 10_000.0 } else { 0.0 },
                    "C {c} γ {g} pixel ({col}, {row})"
                );
                checked += 1;
            }
        }
        assert!(checked > 19_000);
        let lit = img.data.iter().filter(|v| **v > 0.0).count();
        println!("C {c}° γ {g}°: {lit} lit pixels");
        assert!(lit > 100);
    }
    // From above (γ = 150°) the disc's back is black.
    let cam = Camera::on_sphere(&sphere, direction_deg(0.0, 150.0), Hemisphere::Upper, "up".into());
    let img = render_pinhole(disc.as_ref(), &cam, &k, 1).unwrap();
    assert!(img.data.iter().all(|v| *v == 0.0));
}

#[test]
fn supersampled_pinhole_pixels_average_the_subpixels() {
    let disc = luminaire("disc").unwrap();
    let sphere = CaptureSphere {
        centre_m: DVec3::ZERO,
        radius_m: 1.117,
    };
    let k = small_intrinsics(40, 30, 150.0);
    let cam = Camera::on_sphere(&sphere, direction_deg(10.0, 30.0), Hemisphere::Lower, "t".into());
    let img = render_pinhole(disc.as_ref(), &cam, &k, 3).unwrap();
    // The same pixel from 3× finer intrinsics, averaged over its 3 × 3 block.
    let k3 = Intrinsics {
        width: 120,
        height: 90,
        principal_px: k.principal_px * 3.0,
        focal_px: k.focal_px * 3.0,
    };
    let fine = render_pinhole(disc.as_ref(), &cam, &k3, 1).unwrap();
    let mut partial = 0;
    for row in 0..30 {
        for col in 0..40 {
            let mut s = 0.0;
            for b in 0..3 {
                for a in 0..3 {
                    s += f64::from(fine.get(3 * col + a, 3 * row + b));
                }
            }
            let v = f64::from(img.get(col, row));
            assert!((v - s / 9.0).abs() < 1e-2, "({col}, {row}): {v} vs {}", s / 9.0);
            if v > 0.0 && v < 10_000.0 {
                partial += 1;
            }
        }
    }
    assert!(partial > 10, "edge pixels are partial averages");
}

#[test]
fn scans_are_deterministic_for_a_seed_and_render_in_parallel() {
    let opts = SynthOptions {
        luminaire: "two-planes".into(),
        layout: Layout::Rigo {
            per_hemisphere: 12,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        },
        size: (64, 48),
        seed: 42,
        ..SynthOptions::default()
    };
    let a = synth_scan(&opts).unwrap();
    let b = synth_scan(&opts).unwrap();
    assert_eq!(a.set, b.set);
    let n = a.set.cameras.len();
    let imgs = render_all(a.source.as_ref(), n).unwrap();
    for (i, img) in imgs.iter().enumerate() {
        assert_eq!(*img, b.source.image(i).unwrap(), "image {i}");
        img.validate("synth", &a.set.intrinsics).unwrap();
    }
    // Lower-hemisphere cameras see light, the upper ones above the overlap see none.
    let lit = |i: usize| imgs[i].data.iter().any(|v| *v > 0.0);
    assert!((0..n).any(lit));
    for (i, cam) in a.set.cameras.iter().enumerate() {
        if cam.position_m.z > 0.06 {
            assert!(!lit(i), "camera {i} above the luminaire sees light");
        }
    }
    let c = synth_scan(&SynthOptions { seed: 43, ..opts }).unwrap();
    assert_ne!(a.set.cameras, c.set.cameras, "another seed, another jitter");
}

#[test]
fn default_intrinsics_frame_the_luminaire() {
    for name in ["rect", "reflector", "led-dots"] {
        let scan = synth_scan(&SynthOptions {
            luminaire: name.into(),
            layout: Layout::Fibonacci { count: 40 },
            size: (96, 80),
            ..SynthOptions::default()
        })
        .unwrap();
        let lum = luminaire(name).unwrap();
        for (i, cam) in scan.set.cameras.iter().enumerate() {
            let r = lumiview::nearfield::synth::pixel_bounds(&lum.bounds(), cam, &scan.set.intrinsics).unwrap();
            // The whole box projects inside the image (nothing clipped).
            assert!(
                r.col0 > 0 && r.row0 > 0 && r.col1 < 96 && r.row1 < 80,
                "{name} camera {i}: {r:?}"
            );
        }
    }
}

#[test]
fn reflector_energy_balance() {
    let r = Reflector::standard();
    let source = r.source_flux_lm();
    let b = r.forward_budget(1 << 16);
    let b2 = r.forward_budget(1 << 18);
    println!("reflector budget (2^16): {b:?}");
    println!("reflector budget (2^18): {b2:?}");
    assert!(rel(source, 4.0 * PI * PI * 25e-6 * 1e6) < 1e-12);
    let total = b.escaped_lm + b.mirror_absorbed_lm + b.returned_to_source_lm + b.trapped_lm;
    assert!(rel(total, source) < 1e-9);
    assert!(b.escaped_lm < source && b.escaped_lm > 0.85 * source);
    assert!(rel(b.escaped_lm, b2.escaped_lm) < 1e-3, "QMC converged");
    // Backward: flux from orthographic renders, 2π ∫ I(γ) sin γ dγ (the reflector is axially
    // symmetric), composite Gauss–Legendre with panels refined across the beam.
    let mut flux = 0.0;
    let edges = [0.0, 4.0, 8.0, 12.0, 16.0, 24.0, 35.0, 50.0, 70.0, 90.0];
    for w in edges.windows(2) {
        for (g, wt) in gauss_legendre(3, w[0], w[1]) {
            let d = direction_deg(0.0, g);
            let i = ortho_intensity(&r, d, 0.5e-3, 1).unwrap();
            flux += 2.0 * PI * wt.to_radians() * g.to_radians().sin() * i;
        }
    }
    let e = rel(flux, b2.escaped_lm);
    println!(
        "reflector: source {source:.2} lm, forward escaped {:.2} lm, backward ∫ I dω {flux:.2} lm ({:+.3} %)",
        b2.escaped_lm,
        100.0 * (flux - b2.escaped_lm) / b2.escaped_lm
    );
    assert!(e < 0.01, "{flux} vs {}", b2.escaped_lm);
    // On-axis: the aperture full of the source's image: ρ·L·π(R² − r²) + L·πr² (direct).
    let i0 = ortho_intensity(&r, -DVec3::Z, 0.25e-3, 2).unwrap();
    let expect = 0.9e6 * PI * (0.08f64.powi(2) - 0.005f64.powi(2)) + 1e6 * PI * 0.005f64.powi(2);
    println!("reflector I(0) {i0:.1} cd, aperture-filled estimate {expect:.1} cd");
    assert!(rel(i0, expect) < 2e-3);
}

#[test]
fn proxy_meshes_read_back_as_gltf() {
    let dir = std::env::temp_dir().join(format!("lumiview-synth-proxy-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for name in NAMES {
        let lum = luminaire(name).unwrap();
        let mesh = lum.proxy();
        let bytes = mesh.to_glb().unwrap();
        let g = gltf::Gltf::from_slice(&bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
        let m = g.meshes().next().unwrap();
        assert_eq!(m.primitives().len(), mesh.surfaces.len());
        let b = lum.bounds();
        let mut triangles = 0;
        for p in m.primitives() {
            let reader = p.reader(|_| g.blob.as_deref());
            for q in reader.read_positions().unwrap() {
                // glTF (x, y, z) = luminaire (x, z, −y). A disc's polygon has the disc's area, so
                // its vertices lie a little outside the circle: 0.02 % of the radius at 128 sides.
                let lp = DVec3::new(f64::from(q[0]), -f64::from(q[2]), f64::from(q[1]));
                let slack = DVec3::splat(1e-6 + 2.5e-4 * b.radius());
                assert!(
                    lp.cmpge(b.min - slack).all() && lp.cmple(b.max + slack).all(),
                    "{name}: vertex {lp} outside the bounds"
                );
            }
            for n in reader.read_normals().unwrap() {
                assert_eq!(n, [0.0, -1.0, 0.0], "{name}: emitting sides face nadir (−Y in glTF)");
            }
            triangles += reader.read_indices().unwrap().into_u32().count() / 3;
        }
        assert_eq!(triangles, mesh.triangle_count());
        let path = dir.join(format!("{name}.glb"));
        mesh.write_glb(&path).unwrap();
        gltf::Gltf::open(&path).unwrap();
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_names_and_options_are_errors_naming_the_argument() {
    let e = luminaire("lamp").unwrap_err().to_string();
    assert!(e.contains("luminaire") && e.contains("lamp"), "{e}");
    let base = SynthOptions {
        layout: Layout::Fibonacci { count: 3 },
        size: (16, 16),
        ..SynthOptions::default()
    };
    let e = synth_scan(&SynthOptions {
        radius_m: 0.1,
        ..base.clone()
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("radius"), "{e}");
    let e = synth_scan(&SynthOptions {
        supersample: 99,
        ..base.clone()
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("supersample"), "{e}");
    let e = synth_scan(&SynthOptions {
        layout: Layout::Grid {
            phi_steps: 0,
            theta_steps: 2,
        },
        ..base
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("grid"), "{e}");
}

fn lumiview(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_lumiview"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}

#[test]
fn cli_lists_renders_and_rejects() {
    let out = lumiview(&["synth", "--list", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v.as_array().unwrap().len(), NAMES.len());

    let dir = std::env::temp_dir().join(format!("lumiview-synth-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let pfm = dir.join("o.pfm");
    let out = lumiview(&[
        "synth",
        "disc",
        "--ortho",
        "0,30",
        "--pixel-mm",
        "1",
        "--supersample",
        "2",
        "-o",
        pfm.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("Σ L·ΔA") && text.contains("exact"), "{text}");
    let bytes = std::fs::read(&pfm).unwrap();
    assert!(bytes.starts_with(b"Pf\n"));

    let glb = dir.join("p.glb");
    let out = lumiview(&["synth", "two-planes", "--proxy", glb.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    gltf::Gltf::open(&glb).unwrap();

    let out = lumiview(&[
        "synth",
        "led-dots",
        "--layout",
        "fibonacci:8",
        "--size",
        "64x48",
        "--dry-run",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stdout).contains("images/s"));

    // A scan written as manifest + .pf images reads back with the same cameras and pixels.
    let scan_dir = dir.join("scan");
    let out = lumiview(&[
        "synth",
        "two-planes",
        "--layout",
        "rigo:6",
        "--size",
        "40x30",
        "--seed",
        "5",
        "-o",
        scan_dir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let back = lumiview::nearfield::manifest::load_scan(
        &[scan_dir.join("manifest.json")],
        &lumiview::nearfield::manifest::ImportOptions::default(),
    )
    .unwrap();
    let direct = synth_scan(&SynthOptions {
        luminaire: "two-planes".into(),
        layout: Layout::Rigo {
            per_hemisphere: 6,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        },
        size: (40, 30),
        seed: 5,
        ..SynthOptions::default()
    })
    .unwrap();
    assert_eq!(back.set.cameras.len(), direct.set.cameras.len());
    for i in 0..direct.set.cameras.len() {
        assert!((back.set.cameras[i].position_m - direct.set.cameras[i].position_m).length() < 1e-9);
        assert_eq!(
            back.source.image(i).unwrap().data,
            direct.source.image(i).unwrap().data,
            "image {i}"
        );
    }

    for (args, needle) in [
        (vec!["synth", "lamp"], "lamp"),
        (vec!["synth", "disc", "--layout", "spiral:3", "--dry-run"], "--layout"),
        (
            vec!["synth", "disc", "--size", "0x3", "--layout", "fibonacci:3", "--dry-run"],
            "--size",
        ),
        (
            vec![
                "synth",
                "disc",
                "--radius",
                "0.05",
                "--layout",
                "fibonacci:3",
                "--dry-run",
            ],
            "radius",
        ),
        (vec!["synth", "disc", "--ortho", "0,200", "-o", "x.pfm"], "--ortho"),
        (vec!["synth", "disc", "--dry-run"], "--layout"),
        (vec!["synth", "disc", "--proxy", "x.obj"], "--proxy"),
    ] {
        let out = lumiview(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains(needle), "{args:?}: {err}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
