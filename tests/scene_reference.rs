//! The scene-lighting CPU layer (issue 20) against independent references: the reference path
//! tracer's direct term against E = I(γ)·cos³γ / h² written here from the photometric angles alone
//! (and `photometry::isolux`), exact shadows of an occluder, the penumbra of a linear luminaire
//! against similar triangles, inter-reflection inside closed diffuse enclosures against the
//! integrating-sphere balance, and the glTF loader against the sample generator's own geometry and
//! hostile files. CPU only.
//!
//! Measured figures are printed (`--nocapture`) and quoted in docs/scene-lighting.md.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod scene_common;

use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use scene_common::{floor, office, photometry_text, scene_of};

use glam::DVec3;
use lumiview::draw::glb::{Buffer, ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER};
use lumiview::photometry::isolux::illuminance_lx;
use lumiview::photometry::{load, LoadOptions, LuminousOpening, Photometry};
use lumiview::scene::grid::{grid_csv, work_plane_grid, FloorRect};
use lumiview::scene::sample::{self, box_triangles, sphere_triangles, OFFICE_BOUNDS_M, OFFICE_CHECKER_SRGB};
use lumiview::scene::{placement, PerBounce, SceneLuminaire, SurfacePoint, TraceOptions, Tracer};
use serde_json::json;

const BEGA: &str = "tests/data/misc/arnold-usd_bega_50804K3.ies";
const OFFICE_GLB: &str = "assets/scenes/office.glb";

/// A synthetic point luminaire with no symmetry: five C planes (0–360°), γ 0–90°.
const ASYMMETRIC_IES: &str = "IESNA:LM-63-2002\n[TEST] asymmetric point source\nTILT=NONE\n\
1 -1 1 5 5 1 2 0 0 0\n1 1 10\n0 22.5 45 67.5 90\n0 90 180 270 360\n\
1000 900 700 400 100\n1000 760 600 300 50\n1000 500 350 150 20\n1000 650 500 250 40\n1000 900 700 400 100\n";

/// An isotropic 1000 cd point source over the whole sphere: Φ = 4π · 1000 lm.
const ISOTROPIC_IES: &str = "IESNA:LM-63-2002\n[TEST] isotropic\nTILT=NONE\n\
1 -1 1 3 1 1 2 0 0 0\n1 1 10\n0 90 180\n0\n1000 1000 1000\n";

/// A linear luminaire: opening 1.2 m along X (IES length) × 0.1 m along Y (width), I = 1000 cd ·
/// cos γ below.
const LINEAR_IES: &str = "IESNA:LM-63-2002\n[TEST] linear 1.2 m\nTILT=NONE\n\
1 -1 1 5 1 1 2 0.1 1.2 0\n1 1 30\n0 22.5 45 67.5 90\n0\n1000 923.8795 707.1068 382.6834 0\n";

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn up(x: f64, y: f64, z: f64) -> SurfacePoint {
    SurfacePoint {
        position_m: DVec3::new(x, y, z),
        normal: DVec3::Y,
    }
}

fn direct_only(area_samples: usize, direct_estimates: usize) -> TraceOptions {
    TraceOptions {
        paths_per_point: 0,
        direct_estimates,
        area_samples,
        ..TraceOptions::default()
    }
}

/// The reference of a luminaire hanging `h` m above the horizontal receiver at scene offset (dx,
/// dz), C0 along +X turned by `yaw_deg` about +Y (counter-clockwise from above): C from the
/// horizontal offset's components along C0 = (cos ψ, 0, −sin ψ) and C90 = (−sin ψ, 0, −cos ψ),
/// tan γ = r / h, E = I(C, γ) · cos³γ / h².
fn point_reference_lx(p: &Photometry, h: f64, yaw_deg: f64, dx: f64, dz: f64) -> f64 {
    let psi = yaw_deg.to_radians();
    let (c0, c90) = ((psi.cos(), -psi.sin()), (-psi.sin(), -psi.cos()));
    let (along0, along90) = (dx * c0.0 + dz * c0.1, dx * c90.0 + dz * c90.1);
    let mut c = along90.atan2(along0).to_degrees();
    if c < 0.0 {
        c += 360.0;
    }
    let gamma = (dx.hypot(dz) / h).atan();
    p.intensity(c, gamma.to_degrees()) * gamma.cos().powi(3) / (h * h)
}

/// Same offsets in the floor frame of `photometry::isolux` (x along C0, y along C90).
fn isolux_lx(p: &Photometry, h: f64, yaw_deg: f64, dx: f64, dz: f64) -> f64 {
    let psi = yaw_deg.to_radians();
    let x = dx * psi.cos() - dz * psi.sin();
    let y = -dx * psi.sin() - dz * psi.cos();
    illuminance_lx(p, h, x, y)
}

const PROBES: [(f64, f64); 8] = [
    (0.0, 0.0),
    (0.8, 0.0),
    (0.0, -1.3),
    (-1.7, 0.4),
    (1.1, 1.9),
    (-2.5, -2.2),
    (3.0, -0.5),
    (0.3, 4.0),
];

#[test]
fn direct_light_on_an_open_plane_is_i_cos3_over_h2() {
    let plane = scene_of(vec![(floor(50.0), 0.0)]);
    let asym = photometry_text(ASYMMETRIC_IES, "asymmetric.ies");
    let bega = Arc::new(load(&repo(BEGA), &LoadOptions::default()).unwrap());
    let mut bega_point = (*bega).clone();
    bega_point.opening = LuminousOpening::point();
    let bega_point = Arc::new(bega_point);
    assert!(!bega.opening.is_point(), "the BEGA file has a 0.6 m opening");
    // (photometry, height, yaw, tolerance): point sources are exact; the BEGA opening (0.6 m) as an
    // area source at 16 m, far enough for the point formula (its near field shifts E by 0.6 % at
    // 8 m and 0.4 % at 12 m; 6.5 % at 1.2 m, as the next test measures).
    let cases = [
        (&asym, 2.5, 0.0, 1e-9),
        (&asym, 3.0, 30.0, 1e-9),
        (&asym, 2.0, -115.0, 1e-9),
        (&bega_point, 2.8, 0.0, 1e-9),
        (&bega_point, 2.8, 90.0, 1e-9),
        (&bega, 16.0, 20.0, 5e-3),
    ];
    for (p, h, yaw, tol) in cases {
        let lum = SceneLuminaire {
            photometry: (*p).clone(),
            scene_from_luminaire: placement(0.0, h, 0.0, yaw),
        };
        let points: Vec<SurfacePoint> = PROBES.iter().map(|&(x, z)| up(x * h / 2.5, 0.0, z * h / 2.5)).collect();
        let got = lumiview::scene::illuminance(&plane, &[lum], &points, &direct_only(256, 4)).unwrap();
        let mut worst = 0.0f64;
        for (pt, r) in points.iter().zip(&got) {
            let (dx, dz) = (pt.position_m.x, pt.position_m.z);
            let want = point_reference_lx(p, h, yaw, dx, dz);
            let iso = isolux_lx(p, h, yaw, dx, dz);
            assert!(want > 0.0, "{} at ({dx}, {dz}) must be lit", p.source);
            assert!((iso - want).abs() <= 1e-9 * want, "isolux {iso} vs reference {want}");
            let rel = (r.direct_lx - want).abs() / want;
            worst = worst.max(rel);
            assert!(
                rel <= tol,
                "{} h {h} yaw {yaw} at ({dx}, {dz}): {} lx vs I cos³γ / h² = {want} lx ({rel:.2e})",
                p.source,
                r.direct_lx
            );
            assert!(r.bounces_lx.is_empty() && r.total_lx == r.direct_lx);
        }
        eprintln!(
            "open plane: {} h {h} m yaw {yaw}°: worst relative error {worst:.2e}",
            p.source
        );
    }
}

/// The direction-dependent intensity from an opening point towards a scene vector `v` (from the
/// point to the receiver), for a luminaire hanging nadir down with C0 turned by `yaw_deg`.
fn intensity_towards(p: &Photometry, yaw_deg: f64, v: DVec3) -> f64 {
    let psi = yaw_deg.to_radians();
    let c0 = DVec3::new(psi.cos(), 0.0, -psi.sin());
    let c90 = DVec3::new(-psi.sin(), 0.0, -psi.cos());
    let (a0, a90) = (v.dot(c0), v.dot(c90));
    let mut c = a90.atan2(a0).to_degrees();
    if c < 0.0 {
        c += 360.0;
    }
    let gamma = a0.hypot(a90).atan2(-v.y).to_degrees();
    p.intensity(c, gamma)
}

#[test]
fn an_area_source_is_its_opening_integral() {
    // The BEGA 50804K3's flat 0.045 × 0.6 m opening close to the plane (1.2 m): the path tracer's
    // area source against a 9 × 600 midpoint integral over the opening, each element carrying
    // I(its direction) / N — written here from the opening's extents and the placement
    // convention, not through the library's emitter.
    let bega = Arc::new(load(&repo(BEGA), &LoadOptions::default()).unwrap());
    let (l, w) = (bega.opening.size_x_m, bega.opening.size_y_m);
    assert_eq!((l, w), (0.045, 0.6));
    let (h, yaw) = (1.2, 35.0);
    let psi = f64::to_radians(yaw);
    let (ax, ay) = (
        DVec3::new(psi.cos(), 0.0, -psi.sin()),
        DVec3::new(-psi.sin(), 0.0, -psi.cos()),
    );
    let centre = DVec3::new(0.2, h, -0.1);
    let plane = scene_of(vec![(floor(50.0), 0.0)]);
    let lum = SceneLuminaire {
        photometry: bega.clone(),
        scene_from_luminaire: placement(centre.x, centre.y, centre.z, yaw),
    };
    let points: Vec<SurfacePoint> = PROBES
        .iter()
        .map(|&(x, z)| up(0.2 + 0.4 * x, 0.0, -0.1 + 0.4 * z))
        .collect();
    let got = lumiview::scene::illuminance(&plane, &[lum], &points, &direct_only(1024, 8)).unwrap();
    let (nx, ny) = (9, 600);
    let mut worst = (0.0f64, 0.0f64);
    for (pt, r) in points.iter().zip(&got) {
        let x = pt.position_m;
        let mut sum = 0.0;
        for i in 0..nx {
            for j in 0..ny {
                let s = centre
                    + ax * (l * ((i as f64 + 0.5) / nx as f64 - 0.5))
                    + ay * (w * ((j as f64 + 0.5) / ny as f64 - 0.5));
                let v = x - s;
                sum += intensity_towards(&bega, yaw, v) * (-v.y) / v.length().powi(3);
            }
        }
        let want = sum / (nx * ny) as f64;
        let far = point_reference_lx(&bega, h, yaw, x.x - centre.x, x.z - centre.z);
        let rel = (r.direct_lx - want).abs() / want;
        worst = (worst.0.max(rel), worst.1.max((far - want).abs() / want));
        assert!(
            rel < 2e-3,
            "at {x}: {} lx vs the opening integral {want} lx ({rel:.2e})",
            r.direct_lx
        );
        assert!(
            r.direct_se_lx < 2e-3 * want,
            "standard error {} of {want}",
            r.direct_se_lx
        );
    }
    eprintln!(
        "area source (BEGA 0.045 × 0.6 m at 1.2 m): worst relative error against the opening integral {:.2e}; \
         the point formula is off by up to {:.1} % there",
        worst.0,
        100.0 * worst.1
    );
}

#[test]
fn an_occluder_casts_an_exact_shadow_and_nothing_else() {
    // A 1 × 0.2 × 1 m slab from y 0.8 to 1.0 under a point luminaire at 2.5 m.
    let slab = box_triangles(DVec3::new(-0.5, 0.8, -0.5), DVec3::new(0.5, 1.0, 0.5), false);
    let scene = scene_of(vec![(floor(20.0), 0.0), (slab, 0.0)]);
    let p = photometry_text(ASYMMETRIC_IES, "asymmetric.ies");
    let lum = SceneLuminaire {
        photometry: p.clone(),
        scene_from_luminaire: placement(0.0, 2.5, 0.0, 40.0),
    };
    // The segment from (x, 0, z) to the luminaire crosses y = 0.8 at 0.68 (x, z) and y = 1 at
    // 0.6 (x, z): inside the slab's ±0.5 for |x|, |z| < 0.73 — umbra; outside it beyond 0.84.
    let umbra = [(0.0, 0.0), (0.3, -0.2), (0.6, 0.6), (-0.7, 0.1), (0.2, -0.72)];
    let lit = [(0.9, 0.0), (-1.2, 0.3), (0.0, 1.5), (2.0, -2.0), (-0.86, -0.86)];
    let mut points: Vec<SurfacePoint> = umbra.iter().chain(&lit).map(|&(x, z)| up(x, 0.0, z)).collect();
    points.push(up(0.1, 1.0, -0.2)); // on the slab's top, 1.5 m below the luminaire
    let tracer = Tracer::new(&scene, &[lum]).unwrap();
    let got = tracer.illuminance(&points, &direct_only(1, 1)).unwrap();
    for (i, &(x, z)) in umbra.iter().enumerate() {
        assert_eq!(got[i].direct_lx, 0.0, "umbra at ({x}, {z})");
    }
    for (k, &(x, z)) in lit.iter().enumerate() {
        let want = point_reference_lx(&p, 2.5, 40.0, x, z);
        let e = got[umbra.len() + k].direct_lx;
        assert!((e - want).abs() <= 1e-12 * want, "lit at ({x}, {z}): {e} vs {want}");
    }
    let top = got.last().unwrap().direct_lx;
    let want = point_reference_lx(&p, 1.5, 40.0, 0.1, -0.2);
    assert!((top - want).abs() <= 1e-12 * want, "slab top: {top} vs {want}");
}

/// A hierarchy built once serves tracers with other luminaires (`Tracer::with_bvh`, what the C API's
/// scene keeps): the same numbers as `Tracer::new`, bit for bit; one built over another scene is
/// refused, and so is a matrix that scales.
#[test]
fn a_prebuilt_hierarchy_traces_like_a_fresh_one() {
    let scene = office();
    let bvh = Arc::new(lumiview::scene::bvh::Bvh::build(&scene));
    let p = photometry_text(LINEAR_IES, "linear.ies");
    let points: Vec<SurfacePoint> = [(0.0, 0.0), (0.5, 1.2), (-2.5, 1.5)]
        .iter()
        .map(|&(x, z)| up(x, 0.0, z))
        .collect();
    let opts = TraceOptions {
        paths_per_point: 16,
        ..TraceOptions::default()
    };
    for yaw in [0.0, 60.0] {
        let lum = SceneLuminaire {
            photometry: p.clone(),
            scene_from_luminaire: placement(0.2, 2.5, -0.1, yaw),
        };
        let fresh = Tracer::new(&scene, std::slice::from_ref(&lum)).unwrap();
        let shared = Tracer::with_bvh(&scene, bvh.clone(), std::slice::from_ref(&lum)).unwrap();
        let (a, b) = (
            fresh.illuminance(&points, &opts).unwrap(),
            shared.illuminance(&points, &opts).unwrap(),
        );
        assert_eq!(a, b, "yaw {yaw}");
        assert!(
            a.iter().all(|r| r.total_lx > r.direct_lx) && a[0].direct_lx > 0.0,
            "{a:?}"
        );
    }
    let other = scene_of(vec![(floor(5.0), 0.3)]);
    let e = Tracer::with_bvh(&other, bvh.clone(), &[]).unwrap_err().to_string();
    assert!(e.contains("'bvh'") && e.contains("302 triangles"), "{e}");
    let scaled = SceneLuminaire {
        photometry: p,
        scene_from_luminaire: placement(0.0, 2.5, 0.0, 0.0) * glam::DMat4::from_scale(DVec3::splat(2.0)),
    };
    let e = Tracer::with_bvh(&scene, bvh, &[scaled]).unwrap_err().to_string();
    assert!(e.contains("luminaires[0]") && e.contains("scales or shears"), "{e}");
}

/// Visible fraction of the luminaire along the floor line z = 0 under a half-plane occluder
/// (x ≥ 0, at `h_plate` m) for a luminaire at `h` m: E with the plate / E without it.
fn visible_fraction(p: &Arc<Photometry>, h: f64, h_plate: f64, xs: &[f64], opts: &TraceOptions) -> Vec<f64> {
    let plate = {
        let c = |x: f64, z: f64| DVec3::new(x, h_plate, z);
        vec![
            [c(0.0, -5.0), c(0.0, 5.0), c(5.0, 5.0)],
            [c(0.0, -5.0), c(5.0, 5.0), c(5.0, -5.0)],
        ]
    };
    let lum = SceneLuminaire {
        photometry: p.clone(),
        scene_from_luminaire: placement(0.0, h, 0.0, 0.0),
    };
    let points: Vec<SurfacePoint> = xs.iter().map(|&x| up(x, 0.0, 0.0)).collect();
    let open = scene_of(vec![(floor(10.0), 0.0)]);
    let shaded = scene_of(vec![(floor(10.0), 0.0), (plate, 0.0)]);
    // The same seed draws the same points on the opening in both scenes: the ratio is the
    // visible share of the sampled intensity, exactly.
    let e0 = lumiview::scene::illuminance(&open, std::slice::from_ref(&lum), &points, opts).unwrap();
    let e1 = lumiview::scene::illuminance(&shaded, &[lum], &points, opts).unwrap();
    e0.iter().zip(&e1).map(|(a, b)| b.direct_lx / a.direct_lx).collect()
}

/// The width between the last fully lit and the first fully shadowed point, m.
fn penumbra_width(xs: &[f64], f: &[f64]) -> (f64, f64) {
    let lit_end = xs
        .iter()
        .zip(f)
        .filter(|(_, f)| **f >= 1.0 - 1e-12)
        .map(|(x, _)| *x)
        .fold(f64::MIN, f64::max);
    let dark_start = xs
        .iter()
        .zip(f)
        .filter(|(_, f)| **f <= 1e-12)
        .map(|(x, _)| *x)
        .fold(f64::MAX, f64::min);
    (lit_end, dark_start)
}

#[test]
fn a_linear_luminaire_casts_the_penumbra_of_similar_triangles() {
    let (h, h_plate) = (2.5, 1.0);
    let linear = photometry_text(LINEAR_IES, "linear.ies");
    assert_eq!(
        (linear.opening.size_x_m, linear.opening.size_y_m),
        (1.2, 0.1),
        "IES length along X"
    );
    let step = 0.005;
    let xs: Vec<f64> = (0..=240).map(|i| -0.6 + step * i as f64).collect();
    let opts = TraceOptions {
        seed: 7,
        ..direct_only(1024, 8)
    };
    let f = visible_fraction(&linear, h, h_plate, &xs, &opts);
    // Similar triangles: the edge at x = 0, height h_plate, seen from the luminaire's ends
    // (x = ±0.6 at height h) throws the shadow boundaries to x = ∓0.6 · h_plate / (h − h_plate).
    let predicted = 1.2 * h_plate / (h - h_plate);
    let (lit_end, dark_start) = penumbra_width(&xs, &f);
    let width = dark_start - lit_end;
    let rel = (width - predicted) / predicted;
    eprintln!(
        "penumbra of a 1.2 m linear luminaire: fully lit to x = {lit_end:.3} m, fully dark from {dark_start:.3} m: \
         width {width:.3} m vs {predicted:.3} m predicted ({:+.1} %); visible share at the edge's foot {:.3}",
        100.0 * rel,
        f[120]
    );
    assert!(rel.abs() < 0.03, "penumbra width {width} vs {predicted}");
    assert!(
        (f[120] - 0.5).abs() < 0.02,
        "half the luminaire is seen below the edge: {}",
        f[120]
    );
    assert!(
        f.windows(2).all(|w| w[1] <= w[0] + 0.02),
        "the light fades monotonically into the shadow"
    );
    // The same luminaire as a point: a hard shadow at x = 0.
    let mut point = (*linear).clone();
    point.opening = LuminousOpening::point();
    let f = visible_fraction(&Arc::new(point), h, h_plate, &xs, &opts);
    let (lit_end, dark_start) = penumbra_width(&xs, &f);
    assert!(
        lit_end <= 1e-9 && dark_start >= -1e-9 && dark_start - lit_end <= step + 1e-12,
        "a point source's shadow edge lies at x = 0: lit to {lit_end}, dark from {dark_start}"
    );
}

/// Calculation points on each inside face of the box, one uniformly placed in each cell of an
/// n × n grid (jittered: unbiased for area means), with inward normals, and each point's share of
/// the box's area (the weights sum to 1).
fn box_wall_points(lo: DVec3, hi: DVec3, n: usize) -> (Vec<SurfacePoint>, Vec<f64>) {
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut jitter = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut out = Vec::new();
    let mut weights = Vec::new();
    let d = hi - lo;
    let total = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
    for axis in 0..3 {
        for (side, normal_sign) in [(lo[axis], 1.0), (hi[axis], -1.0)] {
            let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
            weights.extend(std::iter::repeat_n(d[a] * d[b] / total / (n * n) as f64, n * n));
            for i in 0..n {
                for j in 0..n {
                    let mut p = DVec3::ZERO;
                    p[axis] = side;
                    p[a] = lo[a] + (i as f64 + jitter()) / n as f64 * (hi[a] - lo[a]);
                    p[b] = lo[b] + (j as f64 + jitter()) / n as f64 * (hi[b] - lo[b]);
                    let mut normal = DVec3::ZERO;
                    normal[axis] = normal_sign;
                    out.push(SurfacePoint { position_m: p, normal });
                }
            }
        }
    }
    (out, weights)
}

struct Means {
    direct: f64,
    bounces: Vec<f64>,
    total: f64,
    total_se: f64,
}

/// Weighted means over the points (weights summing to 1) and the standard error of the total's.
fn means(r: &[PerBounce], w: &[f64], depth: usize) -> Means {
    let mean = |f: &dyn Fn(&PerBounce) -> f64| r.iter().zip(w).map(|(p, w)| w * f(p)).sum::<f64>();
    Means {
        direct: mean(&|p| p.direct_lx),
        bounces: (0..depth)
            .map(|k| mean(&|p| p.bounces_lx.get(k).copied().unwrap_or(0.0)))
            .collect(),
        total: mean(&|p| p.total_lx),
        total_se: r
            .iter()
            .zip(w)
            .map(|(p, w)| (w * p.total_se_lx).powi(2))
            .sum::<f64>()
            .sqrt(),
    }
}

#[test]
fn inter_reflection_in_a_closed_box_balances_like_an_integrating_sphere() {
    // Inside any closed enclosure of uniform reflectance ρ and area A with a source of flux Φ,
    // every reflection keeps ρ of the light inside: the area-mean of bounce k is ρᵏ Φ / A and the
    // mean total Φ / (A (1 − ρ)). A 3 × 2 × 2.5 m box, the isotropic source off-centre.
    let (lo, hi) = (DVec3::new(-1.5, 0.0, -1.0), DVec3::new(1.5, 2.0, 1.5));
    let area = 2.0 * (3.0 * 2.0 + 2.0 * 2.5 + 3.0 * 2.5);
    let iso = photometry_text(ISOTROPIC_IES, "isotropic.ies");
    let flux = iso.flux_lm();
    assert!((flux - 4000.0 * PI).abs() < 1e-6 * flux);
    // Points: 16 × 16 per face, jittered, weighted by area; the direct term's check below
    // measures what the points' placement costs.
    let (points, weights) = box_wall_points(lo, hi, 16);
    for (rho, paths) in [(0.5, 128), (0.8, 128)] {
        let scene = scene_of(vec![(box_triangles(lo, hi, true), rho)]);
        assert!((scene.area_m2() - area).abs() < 1e-12);
        let lum = SceneLuminaire {
            photometry: iso.clone(),
            scene_from_luminaire: placement(0.3, 1.2, 0.1, 0.0),
        };
        let opts = TraceOptions {
            paths_per_point: paths,
            seed: 11,
            ..TraceOptions::default()
        };
        let t0 = std::time::Instant::now();
        let r = lumiview::scene::illuminance(&scene, &[lum], &points, &opts).unwrap();
        let m = means(&r, &weights, 3);
        let e_direct = flux / area;
        let rel = |got: f64, want: f64| (got - want) / want;
        let quad_err = rel(m.direct, e_direct);
        let want_total = flux / (area * (1.0 - rho));
        eprintln!(
            "closed box ρ = {rho}: {} points × {paths} paths in {:.1} s; mean direct {:+.3} %, bounce 1 {:+.2} %, \
             bounce 2 {:+.2} %, bounce 3 {:+.2} %, total {:+.2} % (standard error {:.2} %)",
            points.len(),
            t0.elapsed().as_secs_f64(),
            100.0 * quad_err,
            100.0 * rel(m.bounces[0], rho * e_direct),
            100.0 * rel(m.bounces[1], rho * rho * e_direct),
            100.0 * rel(m.bounces[2], rho.powi(3) * e_direct),
            100.0 * rel(m.total, want_total),
            100.0 * m.total_se / want_total
        );
        assert!(
            quad_err.abs() < 2e-3,
            "the points' mean direct term {} vs Φ/A {e_direct}",
            m.direct
        );
        // Four standard errors plus the points' quadrature error.
        let tol = 4.0 * m.total_se / want_total + 2e-3;
        assert!(
            rel(m.total, want_total).abs() < tol,
            "mean total {} vs Φ/(A(1−ρ)) {want_total}",
            m.total
        );
        for (k, tol) in [(0, 0.01), (1, 0.015), (2, 0.02)] {
            let want = rho.powi(k as i32 + 1) * e_direct;
            assert!(
                rel(m.bounces[k], want).abs() < tol,
                "bounce {}: {} vs ρ^{} Φ/A = {want}",
                k + 1,
                m.bounces[k],
                k + 1
            );
        }
    }
}

#[test]
fn inside_a_tessellated_sphere_the_indirect_light_is_the_same_everywhere() {
    // A sphere (the polyhedron of 96 × 48 bands, inward) of ρ = 0.6 with the isotropic source at
    // its centre: at every point the indirect illuminance is Φ ρ / (A (1 − ρ)), A the
    // polyhedron's area (exact for a true sphere; the facets make it nearly so).
    let (c, r, rho) = (DVec3::new(0.0, 2.0, 0.0), 1.5, 0.6);
    let scene = scene_of(vec![(sphere_triangles(c, r, 48, 96, true), rho)]);
    let area = scene.area_m2();
    let iso = photometry_text(ISOTROPIC_IES, "isotropic.ies");
    let flux = iso.flux_lm();
    let lum = SceneLuminaire {
        photometry: iso,
        scene_from_luminaire: placement(c.x, c.y, c.z, 0.0),
    };
    // Points on the facets where rays from the centre meet them, facing the centre.
    let tracer = Tracer::new(&scene, std::slice::from_ref(&lum)).unwrap();
    let dirs = [
        DVec3::X,
        DVec3::NEG_Y,
        DVec3::new(0.3, 0.8, -0.5),
        DVec3::new(-0.7, 0.1, 0.7),
        DVec3::new(0.0, -0.6, -0.8),
        DVec3::new(-0.2, 0.95, 0.1),
    ];
    let points: Vec<SurfacePoint> = dirs
        .iter()
        .map(|d| {
            let d = d.normalize();
            let hit = tracer.bvh().closest_hit(c, d, 2.0 * r).unwrap();
            let t = scene.triangles()[hit.triangle];
            SurfacePoint {
                position_m: c + d * hit.t,
                normal: (t[1] - t[0]).cross(t[2] - t[0]).normalize(),
            }
        })
        .collect();
    assert!(
        points.iter().all(|p| p.normal.dot(c - p.position_m) > 0.0),
        "inward facets"
    );
    let opts = TraceOptions {
        paths_per_point: 6000,
        seed: 5,
        ..TraceOptions::default()
    };
    let res = tracer.illuminance(&points, &opts).unwrap();
    let want = flux * rho / (area * (1.0 - rho));
    let mut worst = 0.0f64;
    for (p, e) in points.iter().zip(&res) {
        let se = e.total_se_lx;
        let rel = (e.indirect_lx() - want) / want;
        worst = worst.max(rel.abs());
        assert!(
            rel.abs() < 4.0 * se / want + 0.01,
            "indirect at {}: {} lx vs Φρ/(A(1−ρ)) = {want} lx (se {se})",
            p.position_m,
            e.indirect_lx()
        );
    }
    eprintln!(
        "tessellated sphere ρ = {rho}: indirect within {:.2} % of Φρ/(A(1−ρ)) at {} points (standard error ≈ {:.2} %)",
        100.0 * worst,
        points.len(),
        100.0 * res[0].total_se_lx / want
    );
}

#[test]
fn the_shipped_office_is_what_the_generator_makes_and_loads_back() {
    let generated = sample::office().to_glb().unwrap();
    let path = repo(OFFICE_GLB);
    if std::env::var("LUMIVIEW_BLESS").is_ok_and(|v| v == "1") {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        sample::office().write_glb(&path).unwrap();
        eprintln!("blessed {}", path.display());
    }
    let shipped = std::fs::read(&path).unwrap_or_default();
    assert!(
        shipped == generated,
        "{} differs from scene::sample::office(); regenerate it with LUMIVIEW_BLESS=1 cargo test --test \
         scene_reference the_shipped_office",
        path.display()
    );

    let scene = lumiview::scene::load(&path).unwrap();
    assert!(scene.warnings().is_empty(), "{:?}", scene.warnings());
    let office = sample::office();
    let want = office.world_triangles();
    assert_eq!(scene.triangles().len(), want.len());
    for (i, (got, w)) in scene.triangles().iter().zip(&want).enumerate() {
        for k in 0..3 {
            assert!(
                (got[k] - w.vertices[k]).length() < 1e-5,
                "triangle {i}: {:?} vs {:?}",
                got,
                w.vertices
            );
        }
        assert_eq!(scene.material_of()[i] as usize, w.material);
    }
    assert_eq!(scene.materials().len(), office.materials().len());
    for (m, w) in scene.materials().iter().zip(office.materials()) {
        for k in 0..3 {
            assert!(
                (m.base_color_factor[k] - w.base_color_factor[k]).abs() < 1e-6,
                "{}",
                w.name
            );
        }
        assert_eq!(m.base_color_texture.is_some(), w.textured, "{}", w.name);
    }
    let b = scene.bounds();
    let (lo, hi) = OFFICE_BOUNDS_M;
    assert!((b.min - DVec3::from(lo)).length() < 1e-6 && (b.max - DVec3::from(hi)).length() < 1e-6);

    // The rug's checker: cast down onto it and read the reflectance. Square (i, j) of 0.2 m from
    // the rug's corner (x −1, z −1.7) shows texel (i mod 2, j mod 2): the first colour where they
    // are equal, the second otherwise; sRGB decoded with IEC 61966-2-1.
    let srgb = |c: u8| {
        let c = f64::from(c) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let tracer = Tracer::new(&scene, &[]).unwrap();
    for (i, j) in [(3, 1), (4, 1), (5, 2), (6, 5), (2, 4)] {
        let (x, z) = (-1.0 + 0.2 * (i as f64 + 0.5), -1.7 + 0.2 * (j as f64 + 0.5));
        let hit = tracer
            .bvh()
            .closest_hit(DVec3::new(x, 1.0, z), DVec3::NEG_Y, 10.0)
            .unwrap();
        assert!((hit.t - 0.995).abs() < 1e-9, "the rug lies 5 mm above the floor");
        let texel = OFFICE_CHECKER_SRGB[usize::from(i % 2 != j % 2)];
        let rgb = scene.reflectance_rgb(hit.triangle, hit.b1, hit.b2);
        for k in 0..3 {
            assert!(
                (rgb[k] - srgb(texel[k])).abs() < 1e-12,
                "square ({i}, {j}): {rgb:?} vs {texel:?}"
            );
        }
    }
}

#[test]
fn the_office_work_plane_under_its_documented_layout() {
    // The shipped office, its six documented luminaires (the asymmetric point source, so each is
    // seen or not), a plane at 0.3 m (under the desks and chairs) inside a 0.5 m border. Direct
    // light at every grid point: the sum of I cos³γ / h² (written here) over the luminaires it
    // sees — some subset of the six, all of them where nothing stands between.
    let scene = office();
    let p = photometry_text(ASYMMETRIC_IES, "asymmetric.ies");
    let lums: Vec<SceneLuminaire> = sample::OFFICE_LUMINAIRES
        .iter()
        .map(|pl| SceneLuminaire {
            photometry: p.clone(),
            scene_from_luminaire: pl.matrix(),
        })
        .collect();
    let rect = FloorRect::of_bounds(&scene.bounds(), 0.5).unwrap();
    let grid = work_plane_grid(&rect, 0.3, 0.25).unwrap();
    assert_eq!(grid.len(), 20 * 12);
    let opts = TraceOptions {
        paths_per_point: 16,
        ..TraceOptions::default()
    };
    let r = lumiview::scene::illuminance(&scene, &lums, &grid, &opts).unwrap();
    let (mut unshadowed, mut partly, mut dark) = (0, 0, 0);
    for (g, e) in grid.iter().zip(&r) {
        let x = g.position_m;
        let each: Vec<f64> = sample::OFFICE_LUMINAIRES
            .iter()
            .map(|pl| point_reference_lx(&p, pl.y_m - x.y, pl.yaw_deg, x.x - pl.x_m, x.z - pl.z_m))
            .collect();
        let subset = (0..1u32 << each.len()).find(|mask| {
            let sum: f64 = (0..each.len()).filter(|i| mask & (1 << i) != 0).map(|i| each[i]).sum();
            (e.direct_lx - sum).abs() <= 1e-12 * sum.max(1.0)
        });
        match subset {
            Some(0b11_1111) => unshadowed += 1,
            Some(0) => dark += 1,
            Some(_) => partly += 1,
            None => panic!("at {x}: {} lx is no sum of the luminaires' {each:?}", e.direct_lx),
        }
        assert!(
            e.total_lx > e.direct_lx && !e.bounces_lx.is_empty(),
            "the room reflects light onto {x}"
        );
    }
    assert!(
        unshadowed > 0 && partly > 0 && dark > 0,
        "{unshadowed} unshadowed, {partly} partly, {dark} in full shadow"
    );
    let e: Vec<f64> = r.iter().map(|p| p.total_lx).collect();
    let (min, max) = e.iter().fold((f64::MAX, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    let avg = e.iter().sum::<f64>() / e.len() as f64;
    eprintln!(
        "office plane at 0.3 m (asymmetric point source × 6): {unshadowed} of {} points see all six, {partly} \
         some, {dark} none; total E min {min:.0} / avg {avg:.0} / max {max:.0} lx, U0 {:.2}, indirect {:.0} % of the average",
        grid.len(),
        min / avg,
        100.0 * r.iter().map(PerBounce::indirect_lx).sum::<f64>() / e.len() as f64 / avg
    );
    let csv = grid_csv(&grid, &e).unwrap();
    assert!(
        csv.starts_with("x_m,y_m,z_m,E_lx\n-2.3750,0.3000,-1.3750,"),
        "{}",
        &csv[..60]
    );
    assert_eq!(csv.lines().count(), grid.len() + 1);
}

#[test]
fn the_big_scene_traces_like_brute_force() {
    let big = sample::office_with_statues();
    let bytes = big.to_glb().unwrap();
    let scene = lumiview::scene::load_from_slice(&bytes, Path::new("statues.glb"), None).unwrap();
    assert!(scene.triangles().len() >= 250_000, "{}", scene.triangles().len());
    assert_eq!(scene.triangles().len(), big.triangle_count());
    let t0 = std::time::Instant::now();
    let tracer = Tracer::new(&scene, &[]).unwrap();
    let build_s = t0.elapsed().as_secs_f64();
    let tris = scene.triangles();
    let brute = |o: DVec3, d: DVec3| {
        let mut best = f64::INFINITY;
        for t in tris {
            // Möller–Trumbore, written out again here.
            let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
            let p = d.cross(e2);
            let det = e1.dot(p);
            if det == 0.0 {
                continue;
            }
            let s = o - t[0];
            let u = s.dot(p) / det;
            let q = s.cross(e1);
            let v = d.dot(q) / det;
            let tt = e2.dot(q) / det;
            if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && tt > 0.0 && tt < best {
                best = tt;
            }
        }
        best
    };
    let mut k = 0u64;
    for i in 0..40 {
        k = k.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let a = (k >> 11) as f64 / (1u64 << 53) as f64 * std::f64::consts::TAU;
        let z = ((k >> 20) & 0xFFFF) as f64 / 65535.0 * 2.0 - 1.0;
        let d = DVec3::new((1.0 - z * z).sqrt() * a.cos(), z, (1.0 - z * z).sqrt() * a.sin());
        let o = DVec3::new(-2.0 + 0.1 * i as f64, 0.9, -1.5 + 0.07 * i as f64);
        let want = brute(o, d);
        let got = tracer
            .bvh()
            .closest_hit(o, d, f64::INFINITY)
            .map_or(f64::INFINITY, |h| h.t);
        assert!((got - want).abs() <= 1e-9 * want.max(1.0), "ray {i}: {got} vs {want}");
    }
    eprintln!(
        "statues scene: {} triangles, BVH of {} nodes, depth {}, built in {build_s:.2} s",
        tris.len(),
        tracer.bvh().node_count(),
        tracer.bvh().depth()
    );
}

/// A one-triangle glTF document and its buffer, for the hostile-input variants.
fn triangle_gltf(positions: &[[f32; 3]], indices: &[u32]) -> (serde_json::Value, Buffer) {
    let mut buf = Buffer::new();
    let pos: Vec<u8> = positions.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    let ix: Vec<u8> = indices.iter().flat_map(|x| x.to_le_bytes()).collect();
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for p in positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let pv = buf.push_view(&pos, ARRAY_BUFFER);
    let iv = buf.push_view(&ix, ELEMENT_ARRAY_BUFFER);
    let doc = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0]}}],
        "accessors": [
            {"bufferView": pv, "componentType": 5126, "count": positions.len(), "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": iv, "componentType": 5125, "count": indices.len(), "type": "SCALAR"},
        ],
        "bufferViews": buf.views(),
        "buffers": [{"byteLength": buf.len()}],
    });
    (doc, buf)
}

const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];

fn glb(doc: &serde_json::Value, buf: Buffer) -> Vec<u8> {
    buf.into_glb(doc).unwrap()
}

fn load_err(bytes: &[u8], name: &str) -> String {
    let e = lumiview::scene::load_from_slice(bytes, Path::new(name), None)
        .err()
        .unwrap_or_else(|| panic!("{name} loaded"))
        .to_string();
    assert!(e.contains(name), "the error names the file: {e}");
    e
}

#[test]
fn hostile_gltf_files_are_errors_not_panics() {
    let (doc, buf) = triangle_gltf(&TRI, &[0, 1, 2]);
    let good = glb(&doc, buf);
    let s = lumiview::scene::load_from_slice(&good, Path::new("good.glb"), None).unwrap();
    assert_eq!(s.triangles().len(), 1);
    assert!((s.reflectance_y(0, 0.3, 0.3) - 0.5).abs() < 1e-7);

    let e = load_err(&good[..good.len() - 9], "cut.glb");
    assert!(e.contains("truncated"), "{e}");
    let e = load_err(&good[..10], "header.glb");
    assert!(e.contains("truncated"), "{e}");
    let mut liar = good.clone();
    liar[8..12].copy_from_slice(&3u32.to_le_bytes());
    let e = load_err(&liar, "liar.glb");
    assert!(e.contains("says 3 bytes"), "{e}");
    let e = load_err(b"solid cube\nfacet normal 0 0 1\n", "cube.stl");
    assert!(e.contains("not a glTF 2.0 file"), "{e}");

    let (doc, buf) = triangle_gltf(&TRI, &[0, 1, 7]);
    let e = load_err(&glb(&doc, buf), "index.glb");
    assert!(e.contains("index 2 is 7, beyond its 3 vertices"), "{e}");

    let (doc, buf) = triangle_gltf(&[[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 0.0, 1.0]], &[0, 1, 2]);
    let e = load_err(&glb(&doc, buf), "nan.glb");
    assert!(e.contains("position 1") && e.contains("not finite"), "{e}");

    let (mut doc, buf) = triangle_gltf(&TRI, &[0, 1, 2]);
    doc["accessors"][0]["count"] = json!(4_000_000_000u64);
    let e = load_err(&glb(&doc, buf), "count.glb");
    assert!(e.contains("4000000000 elements") && e.contains("do not fit"), "{e}");

    let (mut doc, buf) = triangle_gltf(&TRI, &[0, 1, 2]);
    doc["bufferViews"][1]["byteOffset"] = json!(1u64 << 40);
    let e = load_err(&glb(&doc, buf), "view.glb");
    assert!(e.contains("lies beyond buffer 0"), "{e}");

    let (mut doc, buf) = triangle_gltf(&TRI, &[0, 1, 2]);
    doc["bufferViews"][0]["byteStride"] = json!(4);
    let e = load_err(&glb(&doc, buf), "stride.glb");
    assert!(e.contains("stride 4 is shorter"), "{e}");

    let (mut doc, buf) = triangle_gltf(&TRI, &[0, 1, 2]);
    doc["accessors"][0]["componentType"] = json!(5121);
    let e = load_err(&glb(&doc, buf), "quantized.glb");
    assert!(e.contains("only FLOAT VEC3"), "{e}");

    let (mut doc, buf) = triangle_gltf(&TRI, &[0, 1, 2]);
    doc["nodes"] = json!([{"mesh": 0, "children": [1]}, {"children": [0]}]);
    let e = load_err(&glb(&doc, buf), "cycle.glb");
    assert!(e.contains("reached twice"), "{e}");

    // Each transform finite in f32, their product not in f64.
    let (mut doc, buf) = triangle_gltf(&TRI, &[0, 1, 2]);
    let big = json!([3e38, 3e38, 3e38]);
    doc["nodes"] = json!([{"children": [1], "scale": big}, {"children": [2], "scale": big},
        {"children": [3], "scale": big}, {"children": [4], "scale": big}, {"children": [5], "scale": big},
        {"children": [6], "scale": big}, {"children": [7], "scale": big}, {"children": [8], "scale": big},
        {"children": [9], "scale": big}, {"mesh": 0, "scale": big}]);
    let e = load_err(&glb(&doc, buf), "huge.glb");
    assert!(e.contains("node 8: its transform is not finite"), "{e}");

    // One mesh of a million vertices used by 100 nodes: 10⁸ vertex reads, over the budget
    // (MAX_VERTICES_READ), refused before the reads take minutes.
    let mut many = vec![[0.0f32; 3]; 1_000_000];
    many[..3].copy_from_slice(&TRI);
    let (mut doc, buf) = triangle_gltf(&many, &[0, 1, 2]);
    doc["scenes"] = json!([{"nodes": (0..100).collect::<Vec<u32>>()}]);
    doc["nodes"] = json!((0..100).map(|_| json!({"mesh": 0})).collect::<Vec<_>>());
    let e = load_err(&glb(&doc, buf), "instances.glb");
    assert!(e.contains("vertices together"), "{e}");

    let (mut doc, buf) = triangle_gltf(&TRI, &[0, 1, 2]);
    doc["buffers"][0]["byteLength"] = json!(buf.len() + 100);
    let e = load_err(&glb(&doc, buf), "short.glb");
    assert!(e.contains("fewer than the"), "{e}");

    // A .gltf naming a buffer file that is not there: an I/O error naming that file.
    let dir = std::env::temp_dir().join(format!("lumiview-scene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (mut doc, buf) = triangle_gltf(&TRI, &[0, 1, 2]);
    doc["buffers"][0]["uri"] = json!("missing%20data.bin");
    let _ = buf;
    let gltf_path = dir.join("external.gltf");
    std::fs::write(&gltf_path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let e = lumiview::scene::load(&gltf_path).unwrap_err().to_string();
    assert!(e.contains("missing data.bin"), "{e}");
    doc["buffers"][0]["uri"] = json!("https://example.com/data.bin");
    std::fs::write(&gltf_path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let e = lumiview::scene::load(&gltf_path).unwrap_err().to_string();
    assert!(e.contains("not a relative file name"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn embedded_buffers_load_and_jpeg_textures_fall_back_to_their_factor() {
    // A .gltf with its buffer as a base64 data URI, a JPEG-signed image as the base colour
    // texture, and a primitive without a material.
    let (mut doc, buf) = triangle_gltf(&TRI, &[0, 1, 2]);
    let mut bin = glb(&doc, buf);
    let json_len = u32::from_le_bytes(bin[12..16].try_into().unwrap()) as usize;
    let bin = bin.split_off(20 + json_len + 8);
    let b64 = base64(&bin);
    doc["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{b64}"));
    let jpeg = base64(&[0xFF, 0xD8, 0xFF, 0xE0, 0, 0x10, b'J', b'F', b'I', b'F']);
    doc["images"] = json!([{"uri": format!("data:image/jpeg;base64,{jpeg}")}]);
    doc["textures"] = json!([{"source": 0}]);
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = json!([0.2, 0.4, 0.6, 1.0]);
    let prim = doc["meshes"][0]["primitives"][0].clone();
    let mut bare = prim.clone();
    bare.as_object_mut().unwrap().remove("material");
    doc["meshes"][0]["primitives"] = json!([prim, bare]);
    let text = serde_json::to_vec(&doc).unwrap();
    let s = lumiview::scene::load_from_slice(&text, Path::new("embedded.gltf"), None).unwrap();
    assert_eq!(s.triangles().len(), 2);
    let w = s.warnings().join("\n");
    assert!(w.contains("JPEG") && w.contains("factor alone"), "{w}");
    assert!(w.contains("default material is white"), "{w}");
    assert_eq!(s.reflectance_rgb(0, 0.2, 0.2), [0.2f32, 0.4, 0.6].map(f64::from));
    assert!((s.reflectance_y(1, 0.2, 0.2) - 1.0).abs() < 1e-12);
}

fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in bytes.chunks(3) {
        let n =
            (u32::from(c[0]) << 16) | (u32::from(*c.get(1).unwrap_or(&0)) << 8) | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// The office's three documented layouts for inter-reflection (docs/scene-lighting.md): the
/// 1.2 m linear downlight in `OFFICE_LUMINAIRES`; six BEGA 50804K3 up/down lights as pendants at
/// 2.4 m; three asymmetric point luminaires 0.6 m from the x = −3 m wall at 2.7 m.
fn bounce_layouts() -> Vec<(&'static str, Vec<SceneLuminaire>)> {
    let linear = photometry_text(LINEAR_IES, "linear.ies");
    let asym = photometry_text(ASYMMETRIC_IES, "asymmetric.ies");
    let bega = Arc::new(load(Path::new(BEGA), &LoadOptions::default()).unwrap());
    let at = |p: &Arc<Photometry>, m: glam::DMat4| SceneLuminaire {
        photometry: p.clone(),
        scene_from_luminaire: m,
    };
    vec![
        (
            "linear downlights (OFFICE_LUMINAIRES)",
            sample::OFFICE_LUMINAIRES
                .iter()
                .map(|p| at(&linear, p.matrix()))
                .collect(),
        ),
        (
            "BEGA up/down pendants at 2.4 m",
            [-2.0, 0.0, 2.0]
                .iter()
                .flat_map(|&x| [-1.0, 1.0].map(|z| at(&bega, placement(x, 2.4, z, 0.0))))
                .collect(),
        ),
        (
            "asymmetric, along the x = −3 m wall",
            [-1.2, 0.0, 1.2]
                .iter()
                .map(|&z| at(&asym, placement(-2.4, 2.7, z, 0.0)))
                .collect(),
        ),
    ]
}

#[test]
fn the_vpl_bounce_matches_the_path_tracer_on_the_work_plane() {
    // The GPU's inter-reflection (scene::vpl with SceneSettings' defaults: 256 photons, clamp
    // 0.25 m) added to the exact direct term, against the path tracer's total with every bounce,
    // on the work plane at 0.75 m inside EN 12464-1's 0.5 m wall zone (0.25 m grid, 240 points).
    // tests/gpu_scene.rs checks the GPU gathers these VPLs as this CPU mirror does.
    use lumiview::scene::bvh::Bvh;
    use lumiview::scene::vpl::{VplOptions, VplSet};
    let scene = office();
    let bvh = Bvh::build(&scene);
    let rect = FloorRect::of_bounds(&scene.bounds(), 0.5).unwrap();
    let points = work_plane_grid(&rect, 0.75, 0.25).unwrap();
    assert_eq!(points.len(), 240);
    let quantiles = |mut e: Vec<f64>| {
        e.sort_by(f64::total_cmp);
        (e[e.len() / 2], e[e.len() * 95 / 100])
    };
    for (name, lums) in bounce_layouts() {
        let tracer = Tracer::new(&scene, &lums).unwrap();
        let reference = tracer
            .illuminance(
                &points,
                &TraceOptions {
                    paths_per_point: 1024,
                    seed: 11,
                    ..TraceOptions::default()
                },
            )
            .unwrap();
        let vpls = VplSet::generate(&scene, &bvh, &lums, &VplOptions::default()).unwrap();
        let (mut with, mut without, mut se) = (Vec::new(), Vec::new(), 0.0f64);
        for (p, r) in points.iter().zip(&reference) {
            let total = r.direct_lx + vpls.illuminance_lx(p.position_m, p.normal);
            with.push((total / r.total_lx - 1.0).abs());
            without.push((r.direct_lx / r.total_lx - 1.0).abs());
            se = se.max(r.total_se_lx / r.total_lx);
        }
        let (med, p95) = quantiles(with);
        let (dmed, dp95) = quantiles(without);
        let share = reference.iter().map(|r| r.indirect_lx() / r.total_lx).sum::<f64>() / points.len() as f64;
        println!(
            "| {name} | {} | {:.0} % | {:.1} % / {:.1} % | {:.1} % / {:.1} % | {:.1} % |",
            vpls.vpls.len(),
            100.0 * share,
            100.0 * med,
            100.0 * p95,
            100.0 * dmed,
            100.0 * dp95,
            100.0 * se
        );
        assert!(med < 0.05 && p95 < 0.15, "{name}: median {med}, p95 {p95}");
    }
}
