//! Integrity: a corrupted byte in every section found and named, any single byte change caught by
//! verify, truncated, foreign and future-version files refused.

use lumiview::nearfield::pack::tiles::entry_bytes;
use lumiview::nearfield::pack::{OpenOptions, Pack, PackOptions};
use lumiview::nearfield::{LuminanceImage, NearfieldError};

use crate::common::{disc_image, pack, scan, tmp};

/// Offsets of a byte inside each section plus header and directory, with the name to expect.
fn corruption_sites(bytes: &[u8]) -> Vec<(String, usize)> {
    let p = Pack::from_bytes(bytes.to_vec(), &OpenOptions::default()).unwrap();
    let mut sites = vec![("header".to_string(), 20usize)];
    for s in p.sections() {
        assert!(s.length > 0, "{s:?}");
        sites.push((s.name.clone(), (s.offset + s.length / 2) as usize));
        sites.push((s.name.clone(), (s.offset + s.length - 1) as usize));
    }
    let dir = p
        .sections()
        .iter()
        .map(|s| s.offset + s.length)
        .max()
        .unwrap()
        .next_multiple_of(8);
    sites.push(("directory".to_string(), dir as usize + 3));
    sites
}

#[test]
fn a_corrupted_byte_in_every_section_is_found_and_named() {
    let mut images: Vec<_> = (0..4).map(|i| disc_image(40, 32, i)).collect();
    images.push(LuminanceImage::zeros(40, 32));
    let opts = PackOptions {
        page_bytes: 40 * entry_bytes(8) as u64,
        ..PackOptions::default()
    };
    let (path, _) = pack(&scan(images), "corrupt.lvpack", &opts);
    let bytes = std::fs::read(&path).unwrap();
    let sites = corruption_sites(&bytes);
    let names: Vec<&str> = sites.iter().map(|(n, _)| n.as_str()).collect();
    for want in [
        "header",
        "directory",
        "metadata",
        "cameras",
        "images",
        "tile-tables",
        "page.0",
        "page.1",
    ] {
        assert!(names.contains(&want), "{want} missing from {names:?}");
    }
    for (name, at) in sites {
        let mut bad = bytes.clone();
        bad[at] ^= 0x10;
        // Small sections fail at open; pages on first access, or at open with eager verification.
        let eager = Pack::from_bytes(
            bad.clone(),
            &OpenOptions {
                verify_pages: true,
                ..OpenOptions::default()
            },
        );
        let lazy = Pack::from_bytes(bad.clone(), &OpenOptions::default());
        let err = match (eager, lazy) {
            (Err(e), Ok(p)) => {
                assert!(name.starts_with("page."), "{name} was not checked at open");
                let page: usize = name["page.".len()..].parse().unwrap();
                let e2 = p.page_bytes(page).unwrap_err();
                assert_eq!(e.to_string(), e2.to_string());
                assert!(p.verify().is_err());
                e
            }
            (Err(e), Err(_)) => e,
            (Ok(_), _) => panic!("byte {at} in {name} went unnoticed"),
        };
        match &err {
            NearfieldError::Corrupt { section, .. } => assert_eq!(section, &name, "byte {at}: {err}"),
            _ => panic!("byte {at} in {name}: not a Corrupt error: {err}"),
        }
        assert!(err.to_string().contains(&format!("'{name}'")), "{err}");
    }
    // And through the file API: open names the section, the page errors on first use.
    let mut bad = bytes.clone();
    let p = Pack::open(&path).unwrap();
    let page0 = p.page_section(0).unwrap().offset as usize;
    bad[page0 + 5] ^= 1;
    let path2 = tmp("corrupt-page.lvpack");
    std::fs::write(&path2, &bad).unwrap();
    let p2 = Pack::open(&path2).unwrap();
    let err = (0..5).map(|i| p2.decode_image(i)).find_map(|r| r.err()).unwrap();
    assert!(
        matches!(&err, NearfieldError::Corrupt { section, .. } if section == "page.0"),
        "{err}"
    );
}

#[test]
fn every_single_byte_change_anywhere_is_detected_by_verify() {
    let (path, _) = pack(
        &scan(vec![disc_image(12, 10, 3), disc_image(12, 10, 4)]),
        "every.lvpack",
        &PackOptions::default(),
    );
    let bytes = std::fs::read(&path).unwrap();
    assert!(bytes.len() > 4 * 4096);
    for at in 0..bytes.len() {
        let mut bad = bytes.clone();
        bad[at] ^= 0x01;
        let res = Pack::from_bytes(bad, &OpenOptions::default()).and_then(|p| p.verify());
        assert!(res.is_err(), "a change at byte {at} went unnoticed");
    }
}

#[test]
fn truncated_and_foreign_files_are_errors() {
    let (path, _) = pack(
        &scan(vec![disc_image(20, 20, 8)]),
        "trunc.lvpack",
        &PackOptions::default(),
    );
    let bytes = std::fs::read(&path).unwrap();
    for cut in (0..bytes.len()).step_by(97).chain([bytes.len() - 1, 63, 64, 65]) {
        let err = Pack::from_bytes(bytes[..cut].to_vec(), &OpenOptions::default()).unwrap_err();
        if cut >= 64 {
            assert!(err.to_string().contains("truncated"), "cut at {cut}: {err}");
        }
    }
    let mut extended = bytes.clone();
    extended.push(0);
    assert!(Pack::from_bytes(extended, &OpenOptions::default()).is_err());
    assert!(matches!(
        Pack::from_bytes(b"LVPACK but not really".to_vec(), &OpenOptions::default()),
        Err(NearfieldError::Format { .. })
    ));
    // A later version is reported as such.
    let mut v3 = bytes.clone();
    v3[8] = 3;
    let crc = crc32fast::hash(&v3[..60]);
    v3[60..64].copy_from_slice(&crc.to_le_bytes());
    assert!(matches!(
        Pack::from_bytes(v3, &OpenOptions::default()),
        Err(NearfieldError::Unsupported { .. })
    ));
    // A version-1 file relabelled 2 fails on its metadata's version, naming the section.
    let mut v2 = bytes.clone();
    v2[8] = 2;
    let crc = crc32fast::hash(&v2[..60]);
    v2[60..64].copy_from_slice(&crc.to_le_bytes());
    assert!(matches!(
        Pack::from_bytes(v2, &OpenOptions::default()),
        Err(NearfieldError::Corrupt { .. })
    ));
    assert!(matches!(
        Pack::open(&tmp("does-not-exist.lvpack")),
        Err(NearfieldError::Io { .. })
    ));
}
