//! Arbitrary bytes opened as an `.lvpack` store (`cargo fuzz run lvpack`): opening, verifying,
//! sampling and decoding never panic and never allocate from a size the file declares without
//! checking it against the file's length. Decoded luminances are finite and ≥ 0.
//!
//! Every input is tried twice: as it is (header, directory and checksums must reject it), and with
//! all checksums recomputed (so the mutations reach the section parsers and cross-checks).
#![no_main]

use libfuzzer_sys::fuzz_target;
use lumiview::nearfield::pack::{OpenOptions, Pack};

/// CRC-32/IEEE (as crc32fast computes it), bitwise: fuzz inputs are small.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 { (c >> 1) ^ 0xEDB8_8320 } else { c >> 1 };
        }
    }
    !c
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at.checked_add(4)?)?.try_into().ok()?))
}

fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at.checked_add(8)?)?.try_into().ok()?))
}

/// Recomputes the section CRCs in the directory, the directory CRC and the header CRC, where the
/// header's fields let it find them.
fn fix_checksums(b: &mut [u8]) {
    let (Some(dir), Some(count)) = (u64_at(b, 24), u32_at(b, 32)) else {
        return;
    };
    let dir = dir as usize;
    let Some(end) = (count as usize).checked_mul(48).and_then(|n| n.checked_add(dir)) else {
        return;
    };
    if dir < 64 || end > b.len() {
        return;
    }
    for e in (dir..end).step_by(48) {
        let (Some(off), Some(len)) = (u64_at(b, e + 24), u64_at(b, e + 32)) else {
            return;
        };
        let (off, len) = (off as usize, len as usize);
        if let Some(s) = off.checked_add(len).and_then(|stop| b.get(off..stop)) {
            let crc = crc32(s);
            b[e + 40..e + 44].copy_from_slice(&crc.to_le_bytes());
        }
    }
    let crc = crc32(&b[dir..end]);
    b[40..44].copy_from_slice(&crc.to_le_bytes());
    let crc = crc32(&b[..60]);
    b[60..64].copy_from_slice(&crc.to_le_bytes());
}

fn exercise(bytes: Vec<u8>) {
    let opts = OpenOptions {
        verify_pages: false,
        cache_bytes: 1 << 20,
    };
    let Ok(p) = Pack::from_bytes(bytes, &opts) else {
        return;
    };
    let _ = p.verify();
    for i in 0..p.image_count().min(8) {
        let e = p.images()[i];
        for (c, r) in [
            (0, 0),
            (e.width / 2, e.height / 2),
            (e.width.saturating_sub(1), e.height.saturating_sub(1)),
            (e.width, 0),
        ] {
            if let Ok(v) = p.sample(i, c, r) {
                assert!(v.is_finite() && v >= 0.0, "sample = {v}");
            }
        }
        // The output size is what the cameras declare (≤ 65536² px): keep the fuzzer's memory small.
        if u64::from(e.width) * u64::from(e.height) <= 1 << 20 {
            if let Ok(img) = p.decode_image(i) {
                assert!(img.data.iter().all(|v| v.is_finite() && *v >= 0.0));
            }
        }
    }
    for page in 0..p.page_count().min(4) {
        let _ = p.page_bytes(page);
    }
}

fuzz_target!(|data: &[u8]| {
    exercise(data.to_vec());
    if data.len() >= 64 && data.starts_with(b"LVPACK") {
        let mut fixed = data.to_vec();
        fix_checksums(&mut fixed);
        exercise(fixed);
    }
});
