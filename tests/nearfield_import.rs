//! Import of measured near-field scans: the image readers on hand-written bytes, errors that name
//! the file or image, the manifest's checks, `--skip-bad-images`, merging hemispheres, the
//! write → load round trip, and `lumiview cameras`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::{DVec2, DVec3};
use lumiview::nearfield::images::{decode_image, read_image, read_image_header, write_pf, ImageFormat, REC709_LUMA};
use lumiview::nearfield::layout::{cameras, Layout};
use lumiview::nearfield::manifest::{load_scan, load_scan_with_report, parse_manifest, write_scan, ImportOptions};
use lumiview::nearfield::rayset::MemorySource;
use lumiview::nearfield::{CaptureSphere, Hemisphere, Intrinsics, LuminanceImage, RayImageSet, Scan};

/// A fresh, empty scratch folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("nearfield_import")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn le(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn be(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_be_bytes()).collect()
}

/// A TechnoTeam luminance file written by hand (CR LF header, empty line, NUL, pixels).
fn pf_bytes(w: u32, h: u32, values: &[f32]) -> Vec<u8> {
    let mut b =
        format!("Typ=Pic98::TPlane<float>\r\nLines={h}\r\nColumns={w}\r\nFirstLine=0\r\nFirstColumn=0\r\n\r\n\0")
            .into_bytes();
    b.extend(le(values));
    b
}

fn err_text<T: std::fmt::Debug>(r: Result<T, lumiview::nearfield::NearfieldError>) -> String {
    r.unwrap_err().to_string()
}

// ---------------------------------------------------------------------------------------------
// Readers
// ---------------------------------------------------------------------------------------------

#[test]
fn pf_luminance_is_read_row_by_row() {
    let values = [0.0, 1.5, 2.0, 3.25, 1e6, 7.0];
    let img = decode_image(&pf_bytes(3, 2, &values), Path::new("a.pf")).unwrap();
    assert_eq!((img.width, img.height), (3, 2));
    assert_eq!(img.data, values);
    assert_eq!(img.get(2, 0), 2.0);
    assert_eq!(img.get(0, 1), 3.25);
    // A longer header (extra fields, `|` keys, LF only, no empty line before the NUL) does not
    // shift the pixels: they are the file's last bytes.
    let mut b = b"Typ=Pic98::TPlane<float>\n|Comment=a=b\nLines=2\nColumns=3\nExposureTime=0.01\n\0".to_vec();
    b.extend(le(&values));
    assert_eq!(decode_image(&b, Path::new("b.pf")).unwrap().data, values);
}

#[test]
fn pcf_colour_is_blue_green_red_and_becomes_luminance() {
    // Two pixels: pure red 10 and grey 4 (B, G, R order in the file).
    let mut b = b"Typ=Pic98::TPlane<Pic98::TRGBFloatPixel>\r\nLines=1\r\nColumns=2\r\n\r\n\0".to_vec();
    b.extend(le(&[0.0, 0.0, 10.0, 4.0, 4.0, 4.0]));
    let img = decode_image(&b, Path::new("c.pcf")).unwrap();
    assert!(
        (img.data[0] - (10.0 * REC709_LUMA[0]) as f32).abs() < 1e-5,
        "{:?}",
        img.data
    );
    assert!((img.data[1] - 4.0).abs() < 1e-5, "grey keeps its value: {:?}", img.data);
}

#[test]
fn pfm_both_endiannesses_with_rows_flipped() {
    // File rows bottom first: [1 2] is the bottom row, [3 4] the top.
    let mut little = b"Pf\n2 2\n-1.0\n".to_vec();
    little.extend(le(&[1.0, 2.0, 3.0, 4.0]));
    let img = decode_image(&little, Path::new("g.pfm")).unwrap();
    assert_eq!(img.data, vec![3.0, 4.0, 1.0, 2.0]);
    let mut big = b"Pf 2 2 1.0\n".to_vec();
    big.extend(be(&[1.0, 2.0, 3.0, 4.0]));
    assert_eq!(decode_image(&big, Path::new("g.pfm")).unwrap().data, img.data);
    // Colour, big-endian: R, G, B per pixel.
    let mut colour = b"PF\n1 1\n1\n".to_vec();
    colour.extend(be(&[0.0, 2.0, 0.0]));
    let c = decode_image(&colour, Path::new("c.pfm")).unwrap();
    assert!((c.data[0] - (2.0 * REC709_LUMA[1]) as f32).abs() < 1e-6);
}

fn write_exr(path: &Path, w: usize, h: usize, channels: &[(&str, Vec<f32>)]) {
    use exr::prelude::*;
    let list: Vec<AnyChannel<FlatSamples>> = channels
        .iter()
        .map(|(n, v)| AnyChannel::new(*n, FlatSamples::F32(v.clone())))
        .collect();
    let layer = Layer::new(
        (w, h),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(SmallVec::from_vec(list)),
    );
    Image::from_layer(layer).write().to_file(path).unwrap();
}

#[test]
fn exr_y_channel_or_rgb() {
    let dir = scratch("exr");
    let y = dir.join("y.exr");
    write_exr(&y, 3, 2, &[("Y", vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0])]);
    let img = read_image(&y).unwrap();
    assert_eq!((img.width, img.height), (3, 2));
    assert_eq!(img.data, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0], "row 0 is the top");
    let h = read_image_header(&y).unwrap();
    assert_eq!((h.format, h.width, h.height, h.channels), (ImageFormat::Exr, 3, 2, 1));
    let rgb = dir.join("rgb.exr");
    write_exr(
        &rgb,
        2,
        1,
        &[("R", vec![1.0, 5.0]), ("G", vec![1.0, 0.0]), ("B", vec![1.0, 0.0])],
    );
    let img = read_image(&rgb).unwrap();
    assert!((img.data[0] - 1.0).abs() < 1e-5 && (img.data[1] - (5.0 * REC709_LUMA[0]) as f32).abs() < 1e-5);
    let z = dir.join("z.exr");
    write_exr(&z, 1, 1, &[("Z", vec![1.0])]);
    let e = err_text(read_image(&z));
    assert!(e.contains("z.exr") && e.contains("expected a `Y` channel"), "{e}");
}

#[test]
fn truncated_and_garbage_files_are_errors_naming_the_file() {
    let dir = scratch("garbage");
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("short.pf", pf_bytes(4, 4, &[1.0; 15]), "truncated"),
        ("noend.pf", b"Typ=Pic98::TPlane<float>\r\nLines=4".to_vec(), "truncated"),
        (
            "nolines.pf",
            b"Typ=Pic98::TPlane<float>\r\nColumns=4\r\n\r\n\0".to_vec(),
            "Lines is missing",
        ),
        (
            "badcols.pf",
            b"Typ=Pic98::TPlane<float>\r\nLines=4\r\nColumns=x\r\n\r\n\0".to_vec(),
            "Columns=x",
        ),
        (
            "huge.pf",
            b"Typ=Pic98::TPlane<float>\r\nLines=100000\r\nColumns=1\r\n\r\n\0".to_vec(),
            "Lines=100000",
        ),
        (
            "typ.pf",
            b"Typ=Pic98::TPlane<double>\r\nLines=1\r\nColumns=1\r\n\r\n\0abcd".to_vec(),
            "Typ=",
        ),
        (
            "binary.pf",
            vec![0x89, 0x01, 0x02, 0x03, 0x04, b'\n', 0, 0],
            "control bytes",
        ),
        ("short.pfm", b"Pf\n4 4\n-1\n\0\0\0\0".to_vec(), "truncated"),
        ("scale.pfm", b"Pf\n1 1\n0\n\0\0\0\0".to_vec(), "scale"),
        ("size.pfm", b"Pf\n0 1\n-1\n\0\0\0\0".to_vec(), "width"),
        (
            "junk.exr",
            [0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0, 1, 2, 3].to_vec(),
            "OpenEXR",
        ),
        ("what.txt", b"hello".to_vec(), "not a luminance image"),
    ];
    for (name, bytes, want) in cases {
        let path = dir.join(name);
        std::fs::write(&path, &bytes).unwrap();
        let e = err_text(read_image(&path));
        assert!(e.contains(name) && e.contains(want), "{name}: {e}");
        // The header-only check finds the same problems without reading pixels.
        let e = err_text(read_image_header(&path));
        assert!(e.contains(name), "{name}: {e}");
        // Every prefix fails cleanly too (no panic).
        for cut in 0..bytes.len() {
            let _ = decode_image(&bytes[..cut], &path);
        }
    }
    let e = err_text(read_image(&dir.join("missing.pf")));
    assert!(e.contains("missing.pf"), "{e}");
}

// ---------------------------------------------------------------------------------------------
// Manifests
// ---------------------------------------------------------------------------------------------

const W: u32 = 4;
const H: u32 = 3;

fn image(fill: f32) -> LuminanceImage {
    LuminanceImage {
        width: W,
        height: H,
        data: (0..W * H).map(|i| fill + i as f32).collect(),
    }
}

fn manifest_text(images: &[String], extra: &str) -> String {
    format!(
        r#"{{
  "format": "lumiview-scan-manifest",
  "version": 1,
  "radius_m": 1.117,
  {extra}
  "intrinsics": {{"width": {W}, "height": {H}, "principal_px": [2.0, 1.5], "focal_px": 40}},
  "images": [{}]
}}"#,
        images.join(",\n    ")
    )
}

fn entry(file: &str, phi: f64, theta: f64) -> String {
    format!(r#"{{"file": "{file}", "phi_deg": {phi}, "theta_deg": {theta}, "exposure_s": 0.02}}"#)
}

#[test]
fn a_good_manifest_loads_lazily() {
    let dir = scratch("good");
    for (i, name) in ["a.pf", "b.pf"].iter().enumerate() {
        write_pf(&dir.join(name), &image(i as f32)).unwrap();
    }
    let m = dir.join("scan.json");
    std::fs::write(
        &m,
        manifest_text(&[entry("a.pf", 0.0, 30.0), entry("b.pf", 90.0, 120.0)], ""),
    )
    .unwrap();
    let scan = load_scan(&[m], &ImportOptions::default()).unwrap();
    assert_eq!(scan.set.cameras.len(), 2);
    let c = &scan.set.cameras[1];
    assert_eq!(c.hemisphere, Hemisphere::Upper);
    assert_eq!(c.meta.exposure_s, Some(0.02));
    assert_eq!(c.label, "b.pf");
    assert!((c.position_m.length() - 1.117).abs() < 1e-12);
    assert!(
        (c.forward + c.position_m.normalize()).length() < 1e-12,
        "looks at the centre"
    );
    assert_eq!(scan.set.intrinsics.focal_px, DVec2::splat(40.0));
    // Images are opened only now; deleting one after the import shows it.
    assert_eq!(scan.source.image(0).unwrap(), image(0.0));
    std::fs::remove_file(dir.join("b.pf")).unwrap();
    let e = err_text(scan.source.image(1));
    assert!(e.contains("b.pf [scan.json #1]"), "{e}");
}

/// Writes a manifest whose image `bad` is broken in the way `make` says, and returns the import's
/// error text (without --skip-bad-images) and, with it, the files that survive.
fn bad_case(name: &str, make: impl Fn(&Path) -> Vec<String>, verify: bool) -> (String, Vec<String>) {
    let dir = scratch(name);
    let entries = make(&dir);
    let m = dir.join("scan.json");
    std::fs::write(&m, manifest_text(&entries, "")).unwrap();
    let strict = ImportOptions {
        skip_bad: false,
        verify_pixels: verify,
    };
    let e = match load_scan_with_report(std::slice::from_ref(&m), &strict) {
        Ok(_) => "no error".to_string(),
        Err(e) => e.to_string(),
    };
    let lenient = ImportOptions {
        skip_bad: true,
        verify_pixels: verify,
    };
    let (scan, report) = load_scan_with_report(&[m], &lenient).unwrap();
    assert_eq!(report.dropped, report.warnings.len());
    let kept = scan.set.cameras.iter().map(|c| c.label.clone()).collect();
    (e, kept)
}

#[test]
fn manifest_errors_name_the_image_and_skip_drops_it() {
    // Missing file.
    let (e, kept) = bad_case(
        "missing",
        |d| {
            write_pf(&d.join("ok.pf"), &image(1.0)).unwrap();
            vec![entry("ok.pf", 0.0, 10.0), entry("gone.pf", 0.0, 20.0)]
        },
        false,
    );
    assert!(
        e.contains("gone.pf [scan.json #1]") && e.contains("No such file"),
        "{e}"
    );
    assert_eq!(kept, ["ok.pf"]);
    // Wrong size (header check, no pixels read).
    let (e, kept) = bad_case(
        "size",
        |d| {
            write_pf(&d.join("ok.pf"), &image(1.0)).unwrap();
            write_pf(&d.join("big.pf"), &LuminanceImage::zeros(5, 3)).unwrap();
            vec![entry("big.pf", 0.0, 10.0), entry("ok.pf", 0.0, 20.0)]
        },
        false,
    );
    assert!(e.contains("big.pf [scan.json #0]") && e.contains("5×3"), "{e}");
    assert_eq!(kept, ["ok.pf"]);
    // Truncated file.
    let (e, _) = bad_case(
        "truncated",
        |d| {
            let mut b = pf_bytes(W, H, &image(0.0).data);
            b.truncate(b.len() - 4);
            std::fs::write(d.join("cut.pf"), b).unwrap();
            write_pf(&d.join("ok.pf"), &image(1.0)).unwrap();
            vec![entry("cut.pf", 0.0, 10.0), entry("ok.pf", 0.0, 20.0)]
        },
        false,
    );
    assert!(e.contains("cut.pf [scan.json #0]") && e.contains("truncated"), "{e}");
    // NaN and negative pixels: found when the image is read (here: --verify-images).
    for (case, value, want) in [("nan", f32::NAN, "NaN"), ("negative", -0.5, "-0.5")] {
        let (e, kept) = bad_case(
            case,
            |d| {
                let mut img = image(1.0);
                img.data[5] = value;
                write_pf(&d.join("bad.pf"), &img).unwrap();
                write_pf(&d.join("ok.pf"), &image(1.0)).unwrap();
                vec![entry("ok.pf", 0.0, 10.0), entry("bad.pf", 0.0, 20.0)]
            },
            true,
        );
        assert!(
            e.contains("bad.pf [scan.json #1]") && e.contains(want) && e.contains("(col 1, row 1)"),
            "{e}"
        );
        assert_eq!(kept, ["ok.pf"]);
    }
    // Duplicate pose: both images named.
    let (e, kept) = bad_case(
        "duplicate",
        |d| {
            write_pf(&d.join("one.pf"), &image(1.0)).unwrap();
            write_pf(&d.join("two.pf"), &image(2.0)).unwrap();
            vec![entry("one.pf", 30.0, 45.0), entry("two.pf", 30.0 + 1e-9, 45.0)]
        },
        false,
    );
    assert!(
        e.contains("two.pf [scan.json #1]") && e.contains("duplicate pose") && e.contains("one.pf [scan.json #0]"),
        "{e}"
    );
    assert_eq!(kept, ["one.pf"]);
    // A bad pose in the manifest.
    let (e, kept) = bad_case(
        "pose",
        |d| {
            write_pf(&d.join("ok.pf"), &image(1.0)).unwrap();
            vec![entry("ok.pf", 0.0, 10.0), entry("ok.pf", 0.0, 190.0)]
        },
        false,
    );
    assert!(e.contains("ok.pf [scan.json #1]") && e.contains("theta_deg 190"), "{e}");
    assert_eq!(kept, ["ok.pf"]);
}

#[test]
fn bad_pixels_without_verification_fail_when_the_image_is_read() {
    let dir = scratch("lazy_nan");
    let mut img = image(1.0);
    img.data[0] = f32::INFINITY;
    write_pf(&dir.join("inf.pf"), &img).unwrap();
    let m = dir.join("scan.json");
    std::fs::write(&m, manifest_text(&[entry("inf.pf", 0.0, 30.0)], "")).unwrap();
    let scan = load_scan(&[m], &ImportOptions::default()).unwrap();
    let e = err_text(scan.source.image(0));
    assert!(e.contains("inf.pf [scan.json #0]") && e.contains("inf"), "{e}");
}

fn basis_entry(file: &str, right: DVec3, down: DVec3) -> String {
    let forward = right.cross(down);
    let p = -forward * 1.117;
    format!(
        r#"{{"file": "{file}", "position_m": [{}, {}, {}], "right": [{}, {}, {}], "down": [{}, {}, {}], "forward": [{}, {}, {}]}}"#,
        p.x, p.y, p.z, right.x, right.y, right.z, down.x, down.y, down.z, forward.x, forward.y, forward.z
    )
}

#[test]
fn coincident_pole_cameras_with_different_rotations_are_fine() {
    let dir = scratch("pole");
    for n in ["p0.pf", "p1.pf", "e.pf"] {
        write_pf(&dir.join(n), &image(1.0)).unwrap();
    }
    // Two cameras at the nadir looking up (+Z), rotated 90° about the optical axis.
    let entries = [
        basis_entry("p0.pf", DVec3::X, DVec3::NEG_Y),
        basis_entry("p1.pf", DVec3::Y, DVec3::X),
        entry("e.pf", 0.0, 90.0),
    ];
    let m = dir.join("scan.json");
    std::fs::write(&m, manifest_text(&entries, "")).unwrap();
    let (scan, report) = load_scan_with_report(&[m], &ImportOptions::default()).unwrap();
    assert_eq!(scan.set.cameras.len(), 3);
    assert!(report.warnings.is_empty());
    assert!(
        report
            .info
            .iter()
            .any(|i| i.contains("2 cameras share the position") && i.contains("p1.pf")),
        "{:?}",
        report.info
    );
}

#[test]
fn hemispheres_merge_when_sphere_and_intrinsics_agree() {
    let dir = scratch("merge");
    for n in ["l.pf", "u.pf"] {
        write_pf(&dir.join(n), &image(1.0)).unwrap();
    }
    let lower = dir.join("lower.json");
    let upper = dir.join("upper.json");
    // Tags win over the direction: the lower scan reaches 2° past the equator.
    std::fs::write(
        &lower,
        manifest_text(&[entry("l.pf", 0.0, 92.0)], r#""hemisphere": "lower","#),
    )
    .unwrap();
    std::fs::write(
        &upper,
        manifest_text(&[entry("u.pf", 0.0, 88.0)], r#""hemisphere": "upper","#),
    )
    .unwrap();
    let scan = load_scan(&[lower.clone(), upper.clone()], &ImportOptions::default()).unwrap();
    let h: Vec<Hemisphere> = scan.set.cameras.iter().map(|c| c.hemisphere).collect();
    assert_eq!(h, [Hemisphere::Lower, Hemisphere::Upper]);
    assert_eq!(scan.source.image(1).unwrap(), image(1.0));
    // A different sphere or different intrinsics: an error naming both manifests.
    let other = dir.join("other.json");
    std::fs::write(
        &other,
        manifest_text(&[entry("u.pf", 0.0, 88.0)], r#""centre_m": [0, 0, 0.01],"#),
    )
    .unwrap();
    let e = err_text(load_scan(&[lower.clone(), other.clone()], &ImportOptions::default()));
    assert!(
        e.contains("other.json") && e.contains("lower.json") && e.contains("sphere"),
        "{e}"
    );
    let text = manifest_text(&[entry("u.pf", 0.0, 88.0)], "").replace("\"focal_px\": 40", "\"focal_px\": 41");
    std::fs::write(&other, text).unwrap();
    let e = err_text(load_scan(&[lower, other], &ImportOptions::default()));
    assert!(
        e.contains("other.json") && e.contains("lower.json") && e.contains("intrinsics"),
        "{e}"
    );
}

#[test]
fn structural_manifest_errors_name_the_manifest() {
    let dir = scratch("structural");
    let m = dir.join("broken.json");
    for (text, want) in [
        ("{\"format\": \"lumiview-scan-manifest\"", "EOF"),
        (
            r#"{"format": "x", "version": 1, "radius_m": 1, "intrinsics": {"width": 1, "height": 1, "focal_px": 1}, "images": []}"#,
            "\"format\"",
        ),
        (
            r#"{"format": "lumiview-scan-manifest", "version": 2, "radius_m": 1, "intrinsics": {"width": 1, "height": 1, "focal_px": 1}, "images": []}"#,
            "version",
        ),
        (
            r#"{"format": "lumiview-scan-manifest", "version": 1, "radius_m": -1, "intrinsics": {"width": 1, "height": 1, "focal_px": 1}, "images": []}"#,
            "radius_m",
        ),
        (
            r#"{"format": "lumiview-scan-manifest", "version": 1, "radius_m": 1, "intrinsics": {"width": 1, "height": 1}, "images": []}"#,
            "focal_px or pixel_scale_rad",
        ),
        (
            r#"{"format": "lumiview-scan-manifest", "version": 1, "radius_m": 1, "intrinsics": {"width": 0, "height": 1, "focal_px": 1}, "images": []}"#,
            "size",
        ),
    ] {
        std::fs::write(&m, text).unwrap();
        let e = err_text(load_scan(std::slice::from_ref(&m), &ImportOptions::default()));
        assert!(e.contains("broken.json") && e.contains(want), "{text}: {e}");
    }
    let e = err_text(load_scan(&[dir.join("absent.json")], &ImportOptions::default()));
    assert!(e.contains("absent.json"), "{e}");
}

// ---------------------------------------------------------------------------------------------
// Round trip and the `cameras` command
// ---------------------------------------------------------------------------------------------

fn synthetic_scan() -> Scan {
    let sphere = CaptureSphere {
        centre_m: DVec3::new(0.01, -0.02, 0.03),
        radius_m: 1.117,
    };
    let mut cams = cameras(&sphere, &Layout::Fibonacci { count: 24 }, 0).unwrap();
    cams[3].meta.exposure_s = Some(0.125);
    cams[3].meta.overflow_count = Some(7);
    cams[5].intrinsics = Some(Intrinsics {
        width: 5,
        height: 2,
        principal_px: DVec2::new(2.5, 1.0),
        focal_px: DVec2::new(30.0, 31.0),
    });
    cams[6].hemisphere = Hemisphere::Upper;
    let intrinsics = Intrinsics {
        width: W,
        height: H,
        principal_px: DVec2::new(2.0, 1.5),
        focal_px: DVec2::splat(1.0 / 0.004),
    };
    let images = cams
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let k = c.intrinsics.unwrap_or(intrinsics);
            LuminanceImage {
                width: k.width,
                height: k.height,
                data: (0..k.width * k.height)
                    .map(|p| (i as f32 * 0.37 + p as f32).powf(1.7) * 1e3)
                    .collect(),
            }
        })
        .collect();
    Scan {
        set: RayImageSet {
            sphere,
            intrinsics,
            cameras: cams,
        },
        source: Box::new(MemorySource { images }),
    }
}

/// Equal, or neighbouring doubles.
fn within_one_ulp(a: f64, b: f64) -> bool {
    a == b || (a.signum() == b.signum() && a.to_bits().abs_diff(b.to_bits()) <= 1)
}

#[test]
fn write_scan_then_load_scan_gives_the_same_cameras_and_pixels() {
    let dir = scratch("round_trip");
    let scan = synthetic_scan();
    let calls = std::sync::atomic::AtomicUsize::new(0);
    let manifest = write_scan(&dir, &scan, &|done, total| {
        assert!(done >= 1 && done <= total && total == 24);
        calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    })
    .unwrap();
    assert_eq!(calls.into_inner(), 24);
    let back = load_scan(&[manifest], &ImportOptions::default()).unwrap();
    // Everything but the pose vectors is identical; the pose vectors are written with every digit
    // (shortest round-trip form) but serde_json's default float parser may land one ulp off (its
    // `float_roundtrip` feature makes it exact).
    assert_eq!(back.set.sphere, scan.set.sphere);
    assert_eq!(back.set.intrinsics, scan.set.intrinsics);
    assert_eq!(back.set.cameras.len(), scan.set.cameras.len());
    for (a, b) in back.set.cameras.iter().zip(&scan.set.cameras) {
        for (u, v) in [
            (a.position_m, b.position_m),
            (a.right, b.right),
            (a.down, b.down),
            (a.forward, b.forward),
        ] {
            for k in 0..3 {
                assert!(within_one_ulp(u[k], v[k]), "{}: {u} vs {v}", b.label);
            }
        }
        assert_eq!(
            (&a.label, a.hemisphere, a.meta, a.intrinsics),
            (&b.label, b.hemisphere, b.meta, b.intrinsics)
        );
    }
    for i in 0..scan.set.cameras.len() {
        assert_eq!(
            back.source.image(i).unwrap(),
            scan.source.image(i).unwrap(),
            "image {i}"
        );
    }
}

#[test]
fn cameras_command_prints_stats_and_writes_a_png() {
    let dir = scratch("cameras_cli");
    let manifest = write_scan(&dir, &synthetic_scan(), &|_, _| {}).unwrap();
    let png = dir.join("cams.png");
    let out = Command::new(env!("CARGO_BIN_EXE_lumiview"))
        .args([
            "cameras",
            manifest.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
            "--size",
            "800",
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("cameras            24"), "{stdout}");
    assert!(stdout.contains("nearest camera     median"), "{stdout}");
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    let out = Command::new(env!("CARGO_BIN_EXE_lumiview"))
        .args(["cameras", manifest.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["cameras"], 24);
    assert!(v["nearest_camera_deg"]["max"].as_f64().unwrap() > v["nearest_camera_deg"]["median"].as_f64().unwrap());
    // A missing image names it.
    std::fs::remove_file(dir.join("images/00002.pf")).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_lumiview"))
        .args(["cameras", manifest.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("images/00002.pf [manifest.json #2]"),
        "{stderr}"
    );
    let out = Command::new(env!("CARGO_BIN_EXE_lumiview"))
        .args(["cameras", manifest.to_str().unwrap(), "--skip-bad-images"])
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("cameras            23"));
    assert!(String::from_utf8_lossy(&out.stderr).contains("warning"));
}

#[test]
fn the_documented_manifest_example_parses() {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/formats.md")).unwrap();
    let section = &doc[doc.find("## Scan manifest").unwrap()..];
    let start = section.find("```json\n").unwrap() + "```json\n".len();
    let json = &section[start..start + section[start..].find("```").unwrap()];
    let m = parse_manifest(json.as_bytes(), Path::new("/scan/lower.json")).unwrap();
    assert_eq!(m.entries.len(), 4);
    assert_eq!(m.entries[3].file, Path::new("/scan/lower/00003.pcf"));
    let cams: Vec<_> = m.entries.iter().map(|e| e.camera.as_ref().unwrap().clone()).collect();
    assert!(cams.iter().all(|c| c.hemisphere == Hemisphere::Lower));
    assert!((m.intrinsics.focal_px.x - 1.0 / 0.000436).abs() < 1e-9);
    // Images 0 and 2: same place, different orientation.
    assert!((cams[0].position_m - cams[2].position_m).length() < 1e-12);
    assert!((cams[0].right - cams[2].right).length() > 0.5);
    assert_eq!(cams[3].intrinsics.unwrap().focal_px, DVec2::new(2293.1, 2292.7));
}
