//! Reading primitives: bytes from a slice or a file, front to back, every length checked against the
//! file size before it is read or allocated; little-endian fields and UTF-32 text.

use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;

use crate::nearfield::error::{NearfieldError, Result};

/// Bytes from a slice or a file, read front to back, every length checked against the file size
/// before it is read or allocated.
pub(super) struct Input<'a> {
    pub(super) src: Src<'a>,
    pub(super) len: u64,
    pub(super) pos: u64,
    pub(super) path: &'a Path,
}

pub(super) enum Src<'a> {
    Bytes(&'a [u8]),
    File(BufReader<File>),
}

impl Input<'_> {
    pub(super) fn remaining(&self) -> u64 {
        self.len.saturating_sub(self.pos)
    }

    pub(super) fn ensure(&self, n: u64, what: &str) -> Result<()> {
        if n > self.remaining() {
            return Err(NearfieldError::format(
                self.path,
                format!(
                    "truncated in the {what}: it needs {n} bytes at offset {}, but the file ends after {} more \
                     (file size {} bytes)",
                    self.pos,
                    self.remaining(),
                    self.len
                ),
            ));
        }
        Ok(())
    }

    pub(super) fn take(&mut self, n: u64, what: &str) -> Result<Vec<u8>> {
        self.ensure(n, what)?;
        let out = match &mut self.src {
            Src::Bytes(b) => {
                // In range: pos + n ≤ len = b.len().
                let (s, e) = (self.pos as usize, (self.pos + n) as usize);
                b.get(s..e).map(<[u8]>::to_vec).unwrap_or_default()
            }
            Src::File(r) => {
                let mut v = vec![0u8; n as usize];
                r.read_exact(&mut v).map_err(|e| NearfieldError::io(self.path, e))?;
                v
            }
        };
        self.pos += n;
        Ok(out)
    }

    /// `count` little-endian f32 (the caller has checked that they fit).
    pub(super) fn take_f32s(&mut self, count: usize, what: &str) -> Result<Vec<f32>> {
        let bytes = (count as u64).saturating_mul(4);
        self.ensure(bytes, what)?;
        // As large as the file (gigabytes for 10⁸ rays): a failed allocation is an error, not an abort.
        let mut out =
            crate::files::try_vec(count, &format!("the {what}")).map_err(|e| NearfieldError::io(self.path, e))?;
        let conv = |c: &[u8]| f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        match &mut self.src {
            Src::Bytes(b) => {
                let (s, e) = (self.pos as usize, (self.pos + bytes) as usize);
                out.extend(b.get(s..e).unwrap_or_default().chunks_exact(4).map(conv));
            }
            Src::File(r) => {
                const CHUNK: usize = 1 << 20;
                let mut buf = vec![0u8; CHUNK];
                let mut left = bytes as usize;
                while left > 0 {
                    let n = left.min(CHUNK);
                    let chunk = &mut buf[..n];
                    r.read_exact(chunk).map_err(|e| NearfieldError::io(self.path, e))?;
                    out.extend(chunk.chunks_exact(4).map(conv));
                    left -= n;
                }
            }
        }
        self.pos += bytes;
        Ok(out)
    }
}

pub(super) fn le_i32(b: &[u8], at: usize) -> i32 {
    i32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}
pub(super) fn le_f32(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

/// A NaN-for-unknown float as an option.
pub(super) fn known(v: f32) -> Option<f64> {
    (!v.is_nan()).then_some(v as f64)
}

/// UTF-32LE up to the first NUL; invalid code points become U+FFFD (and a warning).
pub(super) fn decode_utf32(bytes: &[u8], what: &str, warnings: &mut Vec<String>) -> String {
    let mut s = String::new();
    let mut bad = 0usize;
    for c in bytes.chunks_exact(4) {
        let u = u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        if u == 0 {
            break;
        }
        match char::from_u32(u) {
            Some(ch) => s.push(ch),
            None => {
                bad += 1;
                s.push(char::REPLACEMENT_CHARACTER);
            }
        }
    }
    if bad > 0 {
        warnings.push(format!("{what}: {bad} invalid UTF-32 code unit(s) replaced by U+FFFD"));
    }
    s
}
