//! Where a [`Pack`]'s bytes come from (a file read with positioned reads, or memory) and the
//! bounded cache of its verified pages: a page is read and checked against its CRC32 when first
//! needed, kept while the cache's budget allows (least recently used dropped first), and a damaged
//! page is remembered so that every later use fails at once.

use std::fs::File;
use std::ops::Deref;
use std::sync::{Arc, PoisonError};

use super::Pack;
use crate::nearfield::error::{NearfieldError, Result};

/// The verified bytes of one pool page (shared; cheap to clone).
#[derive(Clone)]
pub struct PageBytes(pub(super) Arc<Vec<u8>>);

impl Deref for PageBytes {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        &self.0
    }
}

impl AsRef<[u8]> for PageBytes {
    fn as_ref(&self) -> &[u8] {
        &self.0
    }
}

impl std::fmt::Debug for PageBytes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "PageBytes({} bytes)", self.0.len())
    }
}

/// Where the bytes come from.
pub(super) enum Backing {
    File(File),
    Memory(Vec<u8>),
}

impl Backing {
    pub(super) fn read_exact_at(&self, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
        match self {
            Backing::Memory(m) => {
                let src = usize::try_from(offset)
                    .ok()
                    .and_then(|o| m.get(o..o.checked_add(buf.len())?))
                    .ok_or_else(|| std::io::Error::from(std::io::ErrorKind::UnexpectedEof))?;
                buf.copy_from_slice(src);
                Ok(())
            }
            Backing::File(f) => read_exact_at(f, buf, offset),
        }
    }
}

#[cfg(unix)]
fn read_exact_at(f: &File, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(f, buf, offset)
}

#[cfg(windows)]
fn read_exact_at(f: &File, mut buf: &mut [u8], mut offset: u64) -> std::io::Result<()> {
    use std::os::windows::fs::FileExt;
    while !buf.is_empty() {
        match f.seek_read(buf, offset)? {
            0 => return Err(std::io::ErrorKind::UnexpectedEof.into()),
            n => {
                buf = &mut buf[n..];
                offset += n as u64;
            }
        }
    }
    Ok(())
}

#[cfg(not(any(unix, windows)))]
fn read_exact_at(_: &File, _: &mut [u8], _: u64) -> std::io::Result<()> {
    Err(std::io::Error::new(
        std::io::ErrorKind::Unsupported,
        "positioned reads are not available",
    ))
}

/// Pages read so far.
pub(super) struct PageCache {
    pub(super) pages: Vec<Option<(PageBytes, u64)>>,
    /// Pages found damaged (the error's message): a damaged page is read and checked once, then
    /// every later use fails at once (a render asks for its tiles thousands of times).
    pub(super) bad: Vec<Option<String>>,
    pub(super) bytes: u64,
    pub(super) tick: u64,
}

impl Pack {
    /// The verified bytes of page `index` (read and checked against its CRC32 the first time, then
    /// cached within [`OpenOptions::cache_bytes`](super::OpenOptions::cache_bytes)).
    pub fn page_bytes(&self, index: usize) -> Result<PageBytes> {
        let sec = self
            .pages
            .get(index)
            .ok_or_else(|| NearfieldError::invalid("page", format!("{index} is outside 0…{}", self.pages.len())))?;
        {
            let mut c = self.cache.lock().unwrap_or_else(PoisonError::into_inner);
            c.tick += 1;
            let tick = c.tick;
            if let Some(Some((p, used))) = c.pages.get_mut(index) {
                *used = tick;
                return Ok(p.clone());
            }
            if let Some(Some(m)) = c.bad.get(index) {
                return Err(self.corrupt(&sec.name, m.clone()));
            }
        }
        // Read outside the lock so other threads keep sampling cached pages.
        let mut buf = vec![0u8; sec.length as usize];
        self.backing
            .read_exact_at(&mut buf, sec.offset)
            .map_err(|e| NearfieldError::io(&self.path, e))?;
        let crc = crc32fast::hash(&buf);
        if crc != sec.crc32 {
            let m = format!("checksum mismatch (stored {:08x}, computed {crc:08x})", sec.crc32);
            if let Some(slot) = self
                .cache
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .bad
                .get_mut(index)
            {
                *slot = Some(m.clone());
            }
            return Err(self.corrupt(&sec.name, m));
        }
        let page = PageBytes(Arc::new(buf));
        let mut c = self.cache.lock().unwrap_or_else(PoisonError::into_inner);
        c.tick += 1;
        let tick = c.tick;
        if let Some(slot) = c.pages.get_mut(index) {
            if slot.is_none() {
                *slot = Some((page.clone(), tick));
                c.bytes += sec.length;
            }
        }
        while c.bytes > self.cache_budget {
            let victim = c
                .pages
                .iter()
                .enumerate()
                .filter(|(i, p)| *i != index && p.is_some())
                .min_by_key(|(_, p)| p.as_ref().map_or(u64::MAX, |(_, t)| *t))
                .map(|(i, _)| i);
            match victim {
                Some(v) => {
                    if let Some((p, _)) = c.pages[v].take() {
                        c.bytes -= p.len() as u64;
                    }
                }
                None => break,
            }
        }
        Ok(page)
    }
}
