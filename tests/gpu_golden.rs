//! Golden images of the far-field pass made on lavapipe (small RGBA8 tone-mapped renders): from
//! outside, from below, at a grazing angle, with the photometric-solid overlay, and an EULUMDAT
//! disc with luminous sides and its housing box, and an asymmetric side-lit EULUMDAT luminaire with
//! its housing from C0, C90, C180 and C270. Each view also checks a number: the tone-mapped
//! value of the pixel at the opening's centre equals Reinhard(L(C, γ) · exposure) for the direction
//! from the centre to the eye.
//!
//! Compared with a per-channel tolerance plus an outlier budget; failures write the actual image
//! and a difference image under target/golden-failures/. Bless after an intended change with
//! `LUMIVIEW_BLESS=1 cargo test --test gpu_golden` (on lavapipe, never on a developer's GPU).

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod gpu_common;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Mat4, Vec3};
use gpu_common::{asa, data, gl_perspective, look_at, renderer, GPU_LOCK};
use lumiview::gpu::farfield::tone_map;
use lumiview::gpu::{
    Attachment, ColorFormat, DepthFormat, DepthRange, HostCamera, Origin, OutputMode, Overlays, RenderOptions,
    RenderTarget, TargetDesc,
};
use lumiview::photometry::{self, LoadOptions, Photometry};
use tiny_skia::Pixmap;

const W: u32 = 97;
const H: u32 = 65;
const CHANNEL_TOLERANCE: u8 = 8;
const OUTLIER_BUDGET: f64 = 0.002;

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

fn srgb8(v: f64) -> u8 {
    let s = if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Camera at (C, γ) from the luminaire's centre at `distance_m`, looking at it, GL conventions.
fn camera_at(c_deg: f64, gamma_deg: f64, distance_m: f32) -> (HostCamera, [f64; 3]) {
    let d = photometry::web::direction(c_deg, gamma_deg);
    let eye = Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32) * distance_m;
    let up = if !(1.0..=179.0).contains(&gamma_deg) {
        Vec3::X
    } else {
        Vec3::Z
    };
    (
        HostCamera {
            view: look_at(eye, Vec3::ZERO, up),
            projection: gl_perspective(30f32.to_radians(), W as f32 / H as f32, 0.1, 20.0),
            depth_range: DepthRange::NegOneToOne,
            reversed_z: false,
            origin: Origin::TopLeft,
        },
        d,
    )
}

fn check(name: &str, p: Arc<Photometry>, c: f64, g: f64, dist: f32, overlays: Overlays, exposure: f32) {
    let Some(mut r) = renderer() else { return };
    let lum = r.add_photometry(p.clone()).unwrap();
    r.add_instance(lum, Mat4::IDENTITY).unwrap();
    let mut t = RenderTarget::new(
        &r.ctx,
        &TargetDesc {
            width: W,
            height: H,
            color: ColorFormat::Rgba8Srgb,
            depth: DepthFormat::None,
            exportable: true,
            semaphores: false,
        },
    )
    .unwrap();
    let (cam, d) = camera_at(c, g, dist);
    let opts = RenderOptions {
        output: OutputMode::ToneMapped,
        exposure,
        overlays,
        solid_radius_m: 0.4,
    };
    r.render(&mut t, &cam, &opts).unwrap();
    let px = t.read(&r.ctx, Attachment::Color).unwrap();
    // The number: centre pixel (an odd-sized image: its centre pixel's centre is the image centre).
    let (cx, cy) = (W / 2, H / 2);
    let centre = &px[((cy * W + cx) * 4) as usize..][..4];
    let l = p.luminance(c, g).unwrap_or(0.0);
    let want = srgb8(tone_map(l, exposure as f64));
    let is_line = overlays.solid && centre[0] > centre[2] + 60;
    assert!(
        is_line || ((centre[0] as i32 - want as i32).abs() <= 1 && centre[3] == 255),
        "{name}: centre pixel {centre:?}, predicted {want} for L({c}, {g}) = {l:.1} cd/m² (direction {d:?})"
    );
    if overlays.solid {
        let orange = px.chunks_exact(4).filter(|p| p[0] > 200 && p[2] < 120).count();
        assert!(orange > 30, "{name}: solid wireframe pixels {orange}");
    }
    let actual = Pixmap::from_vec(px, tiny_skia::IntSize::from_wh(W, H).unwrap()).unwrap();
    let golden_path = repo(&format!("tests/golden/farfield_{name}.png"));
    if std::env::var("LUMIVIEW_BLESS").is_ok_and(|v| v == "1") {
        actual.save_png(&golden_path).unwrap();
        eprintln!("blessed {}", golden_path.display());
        return;
    }
    let failures = repo("target/golden-failures");
    let save = |img: &Pixmap, suffix: &str| {
        std::fs::create_dir_all(&failures).unwrap();
        let p = failures.join(format!("farfield_{name}-{suffix}.png"));
        img.save_png(&p).unwrap();
        p
    };
    let golden = Pixmap::load_png(&golden_path).unwrap_or_else(|e| {
        let p = save(&actual, "actual");
        panic!("{}: {e}; the render is at {}", golden_path.display(), p.display())
    });
    assert_eq!((golden.width(), golden.height()), (W, H), "{name}: golden size");
    let mut diff = Pixmap::new(W, H).unwrap();
    let mut outliers = 0usize;
    for (i, (a, b)) in actual
        .data()
        .chunks_exact(4)
        .zip(golden.data().chunks_exact(4))
        .enumerate()
    {
        let m = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0);
        if m > CHANNEL_TOLERANCE {
            outliers += 1;
        }
        let v = m.saturating_mul(4);
        diff.data_mut()[i * 4..i * 4 + 4].copy_from_slice(&[v, v, v, 255]);
    }
    let budget = (OUTLIER_BUDGET * (W * H) as f64).ceil() as usize;
    if outliers > budget {
        let a = save(&actual, "actual");
        let dpath = save(&diff, "diff");
        panic!(
            "{name}: {outliers} pixels differ by more than {CHANNEL_TOLERANCE} (budget {budget}); see {} and {}",
            a.display(),
            dpath.display()
        );
    }
    gpu_common::assert_no_validation_messages();
}

#[test]
fn outside_oblique() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    check("outside", asa(), 30.0, 55.0, 2.0, Overlays::default(), 2e-4);
}

#[test]
fn from_below() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    check("below", asa(), 0.0, 0.0, 2.0, Overlays::default(), 2e-4);
}

#[test]
fn grazing() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    check("grazing", asa(), 60.0, 84.0, 1.5, Overlays::default(), 2e-4);
}

#[test]
fn with_solid_overlay() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    check(
        "solid",
        asa(),
        120.0,
        70.0,
        2.5,
        Overlays {
            solid: true,
            housing: false,
        },
        2e-4,
    );
}

#[test]
fn eulumdat_disc_with_sides_and_housing() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let p = Arc::new(
        photometry::load(
            &data("photometric-viewer/ldt/rectangular_luminaire_round_luminous_opening_with_heights.ldt"),
            &LoadOptions::default(),
        )
        .unwrap(),
    );
    assert!(p.luminaire_size_m.is_some());
    check(
        "ldt_housing",
        p,
        45.0,
        50.0,
        0.5,
        Overlays {
            solid: false,
            housing: true,
        },
        2e-4,
    );
}

/// The asymmetric side-lit EULUMDAT luminaire (tests/data/fixtures/side_lit.ldt: 600 mm long along
/// Y, 150 mm wide along X, side faces C0 60, C90 30, C180 0, C270 15 mm, housing 620 × 170 × 80 mm)
/// from C0, C90, C180 and C270 at γ 70°, with its housing: each view shows the face its C plane
/// names (docs/adr/0002), drawn by the far-field pass.
fn side_lit(c: f64) {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let p = Arc::new(photometry::load(&data("fixtures/side_lit.ldt"), &LoadOptions::default()).unwrap());
    check(
        &format!("side_lit_c{c}"),
        p,
        c,
        70.0,
        1.6,
        Overlays {
            solid: false,
            housing: true,
        },
        2e-4,
    );
}

#[test]
fn side_lit_from_c0() {
    side_lit(0.0);
}

#[test]
fn side_lit_from_c90() {
    side_lit(90.0);
}

#[test]
fn side_lit_from_c180() {
    side_lit(180.0);
}

#[test]
fn side_lit_from_c270() {
    side_lit(270.0);
}
