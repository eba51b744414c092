//! IES TM-25 ray files: the three real files in `tests/data/raysets/` (header fields, sums), hand-built
//! files that must fail with a clear error, binning into a virtual scan with flux conservation, and
//! the `info` / `rays2scan` command line.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::f64::consts::PI;
use std::path::Path;
use std::process::Command;

use glam::DVec3;
use lumiview::nearfield::binning::{bin_rays, BinningOptions};
use lumiview::nearfield::layout::{Layout, SplitMix64};
use lumiview::nearfield::tm25::{
    encode, CreationMethod, LuminousSource, RayFile, SpectralKind, SpectralTable, Tm25Flags, Tm25Header,
};
use lumiview::nearfield::NearfieldError;

const LED: &str = "tests/data/raysets/rayfile_LERTDUW_S2WP_green_100k_20161013_IES_TM25.TM25RAY";
const CYL: &str = "tests/data/raysets/Cyl10k.1.tm25ray";
const FAR: &str = "tests/data/raysets/farfield.TM25ray";

fn data(p: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs())
}

#[test]
fn measured_led_header_and_sums() {
    let f = RayFile::read(data(LED)).unwrap();
    let h = f.header();
    println!("{h:#?}\nwarnings {:?}", f.warnings());
    assert_eq!(h.version, 2013);
    assert_eq!(h.creation_method, CreationMethod::Measured);
    assert_eq!(h.luminous_flux_lm, Some(337.0));
    assert!(close(h.radiant_flux_w.unwrap(), 0.693_790_6, 1e-6));
    assert_eq!(h.ray_count, 100_000);
    assert_eq!(h.date, "2016-10-13 14:07:45");
    assert_eq!(h.ray_start_position, 0);
    assert_eq!(h.spectral, SpectralKind::Table);
    assert_eq!(h.single_wavelength_nm, None);
    assert_eq!((h.min_wavelength_nm, h.max_wavelength_nm), (Some(450.0), Some(620.0)));
    assert_eq!(
        h.flags,
        Tm25Flags {
            luminous_flux: true,
            ..Tm25Flags::default()
        }
    );
    assert!(h.description.entries().iter().all(|(_, v)| v.is_empty()));
    assert_eq!(h.spectral_tables.len(), 1);
    let t = &h.spectral_tables[0];
    assert_eq!(t.wavelengths_nm.len(), 86);
    assert_eq!((t.wavelengths_nm[0], t.wavelengths_nm[85]), (450.0, 620.0));
    assert_eq!(t.peak_nm(), Some(520.0));
    // 36288 + 4 + 86·8 = 36980, padded to a multiple of 32.
    assert_eq!(h.ray_data_offset, 36_992);
    assert_eq!(h.items_per_ray(), 7);
    assert_eq!(f.len(), 100_000);
    assert!(f.warnings().is_empty(), "{:?}", f.warnings());
    assert_eq!(f.luminous_source(), &LuminousSource::Column);

    // The header flux equals the sum of the ray fluxes (every ray carries 0.00337 lm).
    let s = f.stats();
    println!("{s:#?}");
    let sum = s.luminous_sum_lm.unwrap();
    assert!(close(sum, 337.0, 1e-6), "{sum}");
    assert!(close(s.flux_range.0, 0.00337, 1e-6) && close(s.flux_range.1, 0.00337, 1e-6));
    // The spectral table's luminous efficacy agrees with the header's Φv/Φe within 0.1 %: V(λ) and
    // the table are read right.
    let k_table = t.luminous_efficacy().unwrap();
    let k_header = 337.0 / h.radiant_flux_w.unwrap();
    assert!(close(k_table, k_header, 1e-3), "{k_table} vs {k_header}");
    // A 6 × 6 mm LED emitting upwards, roughly Lambertian (mean cosine 2/3).
    assert!(s.bbox_min_m.x > -0.0030 && s.bbox_max_m.x < 0.0030);
    assert!(s.bbox_min_m.z > -0.0012 && s.bbox_max_m.z < 0.000_021);
    assert!(s.upward_fraction > 0.999);
    assert!((s.mean_direction.z - 0.6957).abs() < 1e-3, "{}", s.mean_direction);
    let first = f.ray(0).unwrap();
    assert!((first.position_m - DVec3::new(-0.000_981_4, 0.000_284_6, 0.000_02)).length() < 1e-7);
    assert!((first.direction - DVec3::new(0.209_407, -0.424_003, 0.881_119)).length() < 1e-5);
    assert_eq!(first.luminous_lm.map(|v| (v * 1e5).round()), Some(337.0));
}

#[test]
fn simulated_cylinder_header() {
    let f = RayFile::read(data(CYL)).unwrap();
    let h = f.header();
    println!("{h:#?}\nwarnings {:?}", f.warnings());
    assert_eq!(h.version, 2013);
    assert_eq!(h.creation_method, CreationMethod::Simulated);
    assert_eq!(h.luminous_flux_lm, Some(1.0));
    assert_eq!(h.radiant_flux_w, Some(0.0));
    assert_eq!(h.ray_count, 10_000);
    assert_eq!(h.date, "");
    assert_eq!(h.spectral, SpectralKind::None);
    assert_eq!(h.description.ray_file_creator, "LightTools 8.7.0 ");
    assert_eq!(h.ray_data_offset, 36_288);
    assert_eq!(h.column_names(), ["x", "y", "z", "kx", "ky", "kz", "luminous flux"]);
    // Here the header flux (1 lm) is not the sum of the rays (10,000 lm): said in a warning.
    let s = f.stats();
    assert!(close(s.luminous_sum_lm.unwrap(), 10_000.0, 1e-6));
    assert!(f
        .warnings()
        .iter()
        .any(|w| w.contains("sum to") && w.contains("states 1 lm")));
    // A 20 mm cylinder on z = 0…20 mm emitting in all directions.
    assert!(s.bbox_max_m.z < 0.020 && s.bbox_min_m.z > 0.0 && s.max_radius_m < 0.02);
    assert!((s.upward_fraction - 0.5).abs() < 0.01);
}

#[test]
fn point_source_radiant_flux_at_one_wavelength() {
    let f = RayFile::read(data(FAR)).unwrap();
    let h = f.header();
    println!("{h:#?}\nwarnings {:?}", f.warnings());
    assert_eq!(h.luminous_flux_lm, None);
    assert_eq!(h.radiant_flux_w, Some(1.0));
    assert_eq!(h.date, "2025-02-24T15:22:34+0100");
    assert_eq!(h.spectral, SpectralKind::SingleWavelength);
    assert_eq!(h.single_wavelength_nm, Some(500.0));
    assert_eq!((h.min_wavelength_nm, h.max_wavelength_nm), (None, None));
    assert_eq!(
        h.flags,
        Tm25Flags {
            radiant_flux: true,
            ..Tm25Flags::default()
        }
    );
    // Radiant flux only and no header luminous flux: 683 lm/W × V(500 nm) = 683 × 0.323.
    match f.luminous_source() {
        LuminousSource::SingleWavelength { nm, lm_per_w } => {
            assert_eq!(*nm, 500.0);
            assert!((lm_per_w - 220.609).abs() < 1e-9);
        }
        o => panic!("{o:?}"),
    }
    let r = f.ray(0).unwrap();
    assert_eq!(r.position_m, DVec3::ZERO);
    assert_eq!(r.wavelength_nm, Some(500.0));
    assert!(close(r.luminous_lm.unwrap(), r.radiant_w.unwrap() * 220.609, 1e-12));
    let s = f.stats();
    assert_eq!(s.max_radius_m, 0.0);
    // The ray fluxes are weights: they sum to 31,350 W against the header's 1 W.
    assert!(
        close(s.radiant_sum_w.unwrap(), 31_350.14, 1e-5),
        "{:?}",
        s.radiant_sum_w
    );
    assert!(f.warnings().iter().any(|w| w.contains("radiant fluxes sum to")));
}

/// A minimal valid file: one ray per entry of `rays` (x y z kx ky kz Φv).
fn minimal(rays: &[[f32; 7]]) -> Vec<u8> {
    let h = Tm25Header {
        luminous_flux_lm: Some(1.0),
        date: "2024-01-02T03:04:05Z".into(),
        ..Tm25Header::default()
    };
    encode(&h, &rays.concat()).unwrap()
}

const TWO: [[f32; 7]; 2] = [
    [0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.5],
    [1.0, 0.0, 0.0, 0.6, 0.0, -0.8, 0.5],
];

fn err(bytes: &[u8]) -> String {
    RayFile::from_bytes(bytes, "hand.tm25ray").unwrap_err().to_string()
}

#[test]
fn minimal_file_reads() {
    let b = minimal(&TWO);
    assert_eq!(b.len(), 36_288 + 2 * 28);
    let f = RayFile::from_bytes(&b, "hand.tm25ray").unwrap();
    assert_eq!(f.len(), 2);
    assert_eq!(f.header().date, "2024-01-02T03:04:05Z");
    let r: Vec<_> = f.rays().collect();
    assert_eq!(r[1].position_m, DVec3::new(0.001, 0.0, 0.0));
    assert!((r[1].direction - DVec3::new(0.6, 0.0, -0.8)).length() < 1e-7);
    assert_eq!(r[1].luminous_lm, Some(0.5));
    assert_eq!(r[1].radiant_w, None);
    // The same bytes through a file on disk.
    let dir = std::env::temp_dir().join(format!("lumiview-tm25-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("two.tm25ray");
    std::fs::write(&p, &b).unwrap();
    let g = RayFile::read(&p).unwrap();
    assert_eq!(g.record(1), f.record(1));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn truncated_files_name_the_block() {
    let b = minimal(&TWO);
    let cases = [
        (0, "not a TM-25"),
        (3, "not a TM-25"),
        (100, "file header"),
        (270, "known-data flags"),
        (1000, "description block"),
        (36_288 + 27, "declares 2 rays"),
        (b.len() - 1, "truncated or the ray count is wrong"),
    ];
    for (n, want) in cases {
        let e = err(&b[..n]);
        assert!(e.starts_with("hand.tm25ray: "), "{e}");
        assert!(e.contains(want), "{n} bytes: {e}");
    }
    let mut bad = b.clone();
    bad[0] = b'X';
    assert!(err(&bad).contains("expected \"TM25\""));
    // Bytes after the last ray: the layout does not match the data.
    let mut long = b.clone();
    long.extend_from_slice(&[0; 28]);
    let e = err(&long);
    assert!(e.contains("28 bytes follow the last of 2 rays"), "{e}");
}

#[test]
fn stokes_and_tristimulus_are_unsupported() {
    for (offset, word) in [(256 + 20, "Stokes"), (256 + 24, "tristimulus")] {
        let mut b = minimal(&TWO);
        b[offset..offset + 4].copy_from_slice(&1i32.to_le_bytes());
        let e = RayFile::from_bytes(&b, "pol.tm25ray").unwrap_err();
        assert!(matches!(e, NearfieldError::Unsupported { .. }), "{e:?}");
        let m = e.to_string();
        assert!(m.starts_with("pol.tm25ray: unsupported:") && m.contains(word), "{m}");
    }
}

#[test]
fn counts_larger_than_the_file_fail_before_allocating() {
    let mut b = minimal(&TWO);
    for count in [3u64, 1 << 40, u64::MAX] {
        b[20..28].copy_from_slice(&count.to_le_bytes());
        let e = err(&b);
        assert!(e.contains(&format!("{count} rays")), "{e}");
    }
    // A spectral table or column-label count far beyond the file.
    let mut b = minimal(&TWO);
    b[60..64].copy_from_slice(&3i32.to_le_bytes());
    b[76..80].copy_from_slice(&1i32.to_le_bytes());
    b[36_288..36_292].copy_from_slice(&i32::MAX.to_le_bytes());
    let e = err(&b);
    assert!(e.contains("spectral table 1") && e.contains("truncated"), "{e}");
    let mut b = minimal(&TWO);
    b[80..84].copy_from_slice(&1_000_000i32.to_le_bytes());
    let e = err(&b);
    assert!(e.contains("additional column labels"), "{e}");
}

#[test]
fn bad_rays_name_the_ray() {
    let cases: [(usize, f32, &str); 5] = [
        (4, f32::NAN, "ray 1: direction (0.6, NaN, -0.8) is not finite"),
        (0, f32::INFINITY, "ray 1: position (inf, 0, 0) mm is not finite"),
        (6, -1.0, "ray 1: luminous flux -1 lm must be finite and ≥ 0"),
        (6, f32::NAN, "ray 1: luminous flux NaN lm"),
        (3, 0.0, "ray 1: direction"),
    ];
    for (col, v, want) in cases {
        let mut rays = TWO;
        rays[1][col] = v;
        if want == "ray 1: direction" {
            rays[1][3..6].copy_from_slice(&[0.0, 0.0, 0.0]);
        }
        let e = err(&minimal(&rays));
        assert!(e.starts_with("hand.tm25ray: ") && e.contains(want), "{e}");
    }
    let mut rays = TWO;
    rays[1][3..6].copy_from_slice(&[0.0, 0.0, 0.0]);
    assert!(err(&minimal(&rays)).contains("zero length"));
}

#[test]
fn header_consistency_errors() {
    let set = |off: usize, v: i32| {
        let mut b = minimal(&TWO);
        b[off..off + 4].copy_from_slice(&v.to_le_bytes());
        err(&b)
    };
    assert!(set(4, 1999).contains("version"));
    assert!(set(60, 7).contains("spectral data identifier (offset 60) is 7"));
    assert!(set(60, 3).contains("needs spectral tables"));
    assert!(set(256, 0).contains("position and direction flags"));
    assert!(set(264 + 8, 0).contains("neither the radiant flux flag"));
    assert!(set(264 + 4, 2).contains("wavelength flag (offset 268) is 2"));
    assert!(set(60, 2).contains("wavelength flag (offset 268) is 0"));
    assert!(set(284, 1).contains("spectrum index flag"));
    let mut b = minimal(&TWO);
    b[12..16].copy_from_slice(&(-5.0f32).to_le_bytes());
    assert!(err(&b).contains("total luminous flux (offset 12) is -5"));
    let mut b = minimal(&TWO);
    b[64..68].copy_from_slice(&f32::NAN.to_le_bytes());
    b[60..64].copy_from_slice(&1i32.to_le_bytes());
    assert!(err(&b).contains("single wavelength"));
    // A start-position field holding something else than a code: warned, offset computed.
    let mut b = minimal(&TWO);
    b[56..60].copy_from_slice(&36_288i32.to_le_bytes());
    let f = RayFile::from_bytes(&b, "hand.tm25ray").unwrap();
    assert!(
        f.warnings()[0].contains("equals the computed ray data offset"),
        "{:?}",
        f.warnings()
    );
}

#[test]
fn additional_columns_shift_the_ray_data() {
    let h = Tm25Header {
        additional_columns: vec!["phase (rad)".into(), "e-field".into()],
        additional_text: "created by a test".into(),
        spectral: SpectralKind::Table,
        spectral_tables: vec![SpectralTable {
            wavelengths_nm: vec![500.0, 555.0, 600.0],
            weights: vec![0.5, 1.0, 0.5],
        }],
        ..Tm25Header::default()
    };
    let b = encode(&h, &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 0.25, -3.0]).unwrap();
    let f = RayFile::from_bytes(&b, "extra.tm25ray").unwrap();
    assert_eq!(f.header().ray_data_offset, 36_288 + 32 + 2 * 512 + 96);
    assert_eq!(f.header().additional_columns, ["phase (rad)", "e-field"]);
    assert_eq!(f.header().additional_text, "created by a test");
    assert_eq!(
        (f.additional(0, 0), f.additional(0, 1), f.additional(0, 2)),
        (Some(0.25), Some(-3.0), None)
    );
    assert_eq!(f.ray(0).unwrap().luminous_lm, Some(2.0));
}

/// Mutated and cut copies of a valid file: errors or values, never a panic.
#[test]
fn mutations_never_panic() {
    let base = {
        let h = Tm25Header {
            spectral: SpectralKind::Table,
            spectral_tables: vec![SpectralTable {
                wavelengths_nm: vec![500.0, 600.0],
                weights: vec![1.0, 1.0],
            }],
            additional_columns: vec!["a".into()],
            ..Tm25Header::default()
        };
        encode(&h, &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 5.0].repeat(3)).unwrap()
    };
    let mut rng = SplitMix64::new(42);
    let hot: Vec<usize> = (0..92).chain(256..292).chain(36_288..base.len()).collect();
    for _ in 0..4000 {
        let mut b = base.clone();
        for _ in 0..1 + rng.next_u64() % 4 {
            let at = hot[(rng.next_u64() % hot.len() as u64) as usize];
            b[at] = match rng.next_u64() % 4 {
                0 => 0xFF,
                1 => 0,
                2 => 0x7F,
                _ => rng.next_u64() as u8,
            };
        }
        let cut = if rng.next_u64().is_multiple_of(5) {
            (rng.next_u64() % b.len() as u64) as usize
        } else {
            b.len()
        };
        if let Ok(f) = RayFile::from_bytes(&b[..cut], "m") {
            for r in f.rays() {
                assert!(r.position_m.is_finite() && (r.direction.length() - 1.0).abs() < 1e-9);
            }
            let _ = f.stats();
        }
    }
}

#[test]
fn binning_the_led_conserves_flux() {
    let f = RayFile::read(data(LED)).unwrap();
    let opts = BinningOptions {
        layout: Layout::Fibonacci { count: 1000 },
        width: 64,
        height: 64,
        ..BinningOptions::default()
    };
    let b = bin_rays(&f, &opts).unwrap();
    let r = &b.report;
    println!(
        "LED, fibonacci:1000, 64×64, auto fov {:.4}°: used {}/{} rays, behind {}, outside {}; flux rays {:.6} lm, \
         images {:.6} lm; cameras with rays {}, zero {}; rays/camera max {}; lit px {}, rays per lit px mean {:.3} \
         median {} max {}; Ω {:.5}…{:.5} sr (4π/N = {:.5})",
        r.fov_deg,
        r.rays_used,
        r.rays_total,
        r.rays_behind,
        r.rays_outside_image,
        r.flux_total_lm,
        r.flux_from_images_lm,
        1000 - r.cameras_with_zero_rays,
        r.cameras_with_zero_rays,
        r.rays_per_camera.iter().max().unwrap(),
        r.lit_pixels,
        r.rays_per_lit_pixel_mean,
        r.rays_per_lit_pixel_median,
        r.rays_per_lit_pixel_max,
        r.solid_angle_sr.iter().copied().fold(f64::INFINITY, f64::min),
        r.solid_angle_sr.iter().copied().fold(0.0, f64::max),
        4.0 * PI / 1000.0
    );
    assert_eq!(r.rays_used, 100_000, "auto fov keeps every ray");
    // Σ over cameras and pixels of L·A·Ω equals the file's luminous flux (header 337 lm) within 1 %.
    let header = f.header().luminous_flux_lm.unwrap();
    assert!(
        close(r.flux_from_images_lm, header, 0.01),
        "{} vs {header}",
        r.flux_from_images_lm
    );
    assert!(close(r.flux_from_images_lm, r.flux_total_lm, 1e-5));
    let omega_sum: f64 = r.solid_angle_sr.iter().sum();
    assert!(close(omega_sum, 4.0 * PI, 1e-9));
    // An upward LED: the lower half of a uniform layout sees (almost) nothing; a few cameras just
    // below the equator catch the 0.06 % of rays that leave below the horizon.
    assert!(
        (450..=500).contains(&r.cameras_with_zero_rays),
        "{}",
        r.cameras_with_zero_rays
    );
    assert!(r.rays_per_lit_pixel_mean > 1.0 && r.rays_per_lit_pixel_mean < 10.0);
    // Recompute the images' flux independently through the scan's own images.
    let mut sum = 0.0;
    for (i, om) in r.solid_angle_sr.iter().enumerate() {
        let img = b.scan.source.image(i).unwrap();
        img.validate(&format!("cam {i}"), &b.scan.set.intrinsics).unwrap();
        sum += img.data.iter().map(|v| *v as f64).sum::<f64>() * r.pixel_area_m2 * om;
    }
    assert!(close(sum, 337.0, 0.01));

    // A field of view narrower than the LED loses rays outside the images, and says so.
    let narrow = bin_rays(
        &f,
        &BinningOptions {
            fov_deg: Some(0.2),
            ..opts.clone()
        },
    )
    .unwrap();
    let n = &narrow.report;
    assert!(n.rays_outside_image > 0);
    assert_eq!(n.rays_used + n.rays_outside_image + n.rays_behind, n.rays_total);
    assert!(close(n.flux_used_lm + n.flux_outside_image_lm, 337.0, 1e-5));
    assert!(close(n.flux_from_images_lm, n.flux_used_lm, 1e-5));
    println!(
        "LED, fov 0.2°: {} rays outside the image ({:.3} lm), {:.3} lm binned",
        n.rays_outside_image, n.flux_outside_image_lm, n.flux_from_images_lm
    );
}

/// An isotropic point source (rays on a Fibonacci lattice, equal flux) seen by every camera with the
/// same intensity Φ/4π: checks the Voronoi solid angles camera by camera.
#[test]
fn isotropic_source_gives_equal_intensity_everywhere() {
    let m = 200_000usize;
    let golden = PI * (3.0 - 5f64.sqrt());
    let mut rec = Vec::with_capacity(7 * m);
    for i in 0..m {
        let z = 1.0 - (2.0 * i as f64 + 1.0) / m as f64;
        let r = (1.0 - z * z).sqrt();
        let a = golden * i as f64;
        rec.extend_from_slice(&[
            0.0,
            0.0,
            0.0,
            (r * a.cos()) as f32,
            (r * a.sin()) as f32,
            z as f32,
            1e-3,
        ]);
    }
    let b = encode(&Tm25Header::default(), &rec).unwrap();
    let f = RayFile::from_bytes(&b, "iso").unwrap();
    for layout in [
        Layout::Fibonacci { count: 200 },
        Layout::Grid {
            phi_steps: 24,
            theta_steps: 13,
        },
    ] {
        let out = bin_rays(
            &f,
            &BinningOptions {
                layout,
                width: 8,
                height: 8,
                fov_deg: Some(1.0),
                ..BinningOptions::default()
            },
        )
        .unwrap();
        let r = &out.report;
        let want = 200.0 / (4.0 * PI);
        let mut worst = 0.0f64;
        for (i, om) in r.solid_angle_sr.iter().enumerate() {
            let img = out.scan.source.image(i).unwrap();
            let intensity = img.data.iter().map(|v| *v as f64).sum::<f64>() * r.pixel_area_m2;
            worst = worst.max((intensity / want - 1.0).abs());
            assert!(*om > 0.0);
        }
        println!("{layout:?}: worst camera intensity error {:.3} %", 100.0 * worst);
        assert!(worst < 0.02, "{worst}");
        assert!(close(r.flux_from_images_lm, 200.0, 1e-5));
    }
}

#[test]
fn radiant_only_without_spectrum_cannot_be_binned() {
    let h = Tm25Header {
        flags: Tm25Flags {
            radiant_flux: true,
            ..Tm25Flags::default()
        },
        ..Tm25Header::default()
    };
    let f = RayFile::from_bytes(&encode(&h, &TWO.concat()).unwrap(), "w.tm25ray").unwrap();
    assert_eq!(f.luminous_source(), &LuminousSource::Unavailable);
    assert_eq!(f.ray(0).unwrap().luminous_lm, None);
    let e = bin_rays(&f, &BinningOptions::default()).unwrap_err().to_string();
    assert!(
        e.starts_with("w.tm25ray: unsupported:") && e.contains("radiant flux only"),
        "{e}"
    );
}

fn lumiview(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_lumiview"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}

#[test]
fn cli_info_on_a_ray_file() {
    let out = lumiview(&["info", LED, "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["format"], "IES TM-25");
    assert_eq!(v["header"]["ray_count"], 100_000);
    assert_eq!(v["header"]["spectral_identifier"], 3);
    assert_eq!(v["header"]["creation_method"], "measured");
    assert_eq!(v["flags"]["luminous flux"], true);
    assert_eq!(v["spectral_tables"][0]["points"], 86);
    assert_eq!(v["luminous_flux_rule"]["key"], "column");
    assert!(
        v["ray_flux_vs_header"]["luminous_relative_difference"]
            .as_f64()
            .unwrap()
            .abs()
            < 1e-6
    );
    assert_eq!(v["description"].as_array().unwrap().len(), 9);
    let text = String::from_utf8(lumiview(&["info", FAR]).stdout).unwrap();
    for want in [
        "IES TM-25",
        "single wavelength",
        "V(500 nm) = 220.609 lm/W",
        "bounding box",
        "× the header's",
    ] {
        assert!(text.contains(want), "missing `{want}` in:\n{text}");
    }
    let bad = lumiview(&["info", "tests/data/raysets/missing.tm25ray"]);
    assert!(!bad.status.success());
}

#[test]
fn cli_rays2scan_reports() {
    let out = lumiview(&[
        "rays2scan",
        LED,
        "--method",
        "histogram",
        "-o",
        "target/rays2scan-test/scan.json",
        "--layout",
        "grid:12,7",
        "--size",
        "16x16",
        "--fov",
        "1",
        "--dry-run",
        "--json",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["cameras"], 12 * 5 + 2);
    assert_eq!(v["manifest"], serde_json::Value::Null);
    assert_eq!(v["rays"]["total"], 100_000);
    let used = v["flux_lm"]["from_images"].as_f64().unwrap();
    let binned = v["flux_lm"]["used"].as_f64().unwrap();
    assert!(close(used, binned, 1e-5));
    assert!(v["rays"]["per_lit_pixel_median"].as_f64().unwrap() >= 1.0);
    let bad = lumiview(&[
        "rays2scan",
        LED,
        "--method",
        "histogram",
        "-o",
        "x",
        "--layout",
        "hex:4",
        "--dry-run",
    ]);
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--layout `hex:4`"));
}

/// `rays2scan` writes a scan that `manifest::load_scan` reads back with the same cameras and pixels;
/// its flux (Σ L·A·Ω with the solid angles recomputed from the loaded cameras) is the LED's.
#[test]
fn cli_rays2scan_writes_a_loadable_scan() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("rays2scan-led");
    let _ = std::fs::remove_dir_all(&dir);
    let json_path = dir.join("scan.json");
    let out = lumiview(&[
        "rays2scan",
        LED,
        "--method",
        "histogram",
        "-o",
        json_path.to_str().unwrap(),
        "--layout",
        "fibonacci:150",
        "--size",
        "24x24",
        "--json",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["manifest"], json_path.display().to_string());
    assert!(json_path.is_file() && !dir.join("manifest.json").exists());
    let scan = lumiview::nearfield::manifest::load_scan(
        std::slice::from_ref(&json_path),
        &lumiview::nearfield::manifest::ImportOptions::default(),
    )
    .unwrap();
    assert_eq!(scan.set.cameras.len(), 150);
    let k = &scan.set.intrinsics;
    assert_eq!((k.width, k.height), (24, 24));
    let r_s = scan.set.sphere.radius_m;
    let area = (r_s / k.focal_px.x) * (r_s / k.focal_px.y);
    let dirs: Vec<DVec3> = scan
        .set
        .cameras
        .iter()
        .map(|c| c.direction_from(scan.set.sphere.centre_m))
        .collect();
    let (omega, exact) = lumiview::nearfield::binning::NearestDirection::new(&dirs).solid_angles();
    assert!(exact);
    let mut flux = 0.0;
    for (i, om) in omega.iter().enumerate() {
        let img = scan.source.image(i).unwrap();
        flux += img.data.iter().map(|v| *v as f64).sum::<f64>() * area * om;
    }
    assert!(close(flux, 337.0, 1e-4), "{flux}");
    assert!(close(flux, v["flux_lm"]["from_images"].as_f64().unwrap(), 1e-5));
}
