//! Reading a luminance image file of any supported format: the format detected by content (else by
//! extension), the whole image ([`read_image`]) or only its header ([`read_image_header`]); only
//! regular files of bounded size are opened.

use std::io::Read;
use std::path::Path;

use super::openexr::{exr_channels, exr_header, exr_size, parse_exr, ExrChannels};
use super::pf::{parse_pf, parse_pf_header};
use super::pfm::{parse_pfm, parse_pfm_header};
use super::{fmt_err, MAX_PIXELS, PF_MAX_HEADER};
use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::rayset::LuminanceImage;

/// OpenEXR's magic number.
const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// The kind of a luminance image file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ImageFormat {
    /// TechnoTeam `.pf` (luminance) or `.pcf` (colour); the header's `Typ` tells which.
    TechnoTeam,
    /// Portable float map (`Pf` grey, `PF` colour).
    Pfm,
    /// OpenEXR.
    Exr,
}

impl ImageFormat {
    /// The format named by a file's extension (`.pf`, `.pcf`, `.pfm`, `.exr`, any case).
    pub fn from_extension(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "pf" | "pcf" => Some(Self::TechnoTeam),
            "pfm" => Some(Self::Pfm),
            "exr" => Some(Self::Exr),
            _ => None,
        }
    }

    /// The format recognised from the first bytes of a file, if any.
    pub fn sniff(head: &[u8]) -> Option<Self> {
        if head.starts_with(&EXR_MAGIC) {
            Some(Self::Exr)
        } else if head.len() >= 3
            && (head.starts_with(b"PF") || head.starts_with(b"Pf"))
            && head[2].is_ascii_whitespace()
        {
            Some(Self::Pfm)
        } else if head.starts_with(b"Typ=") || head.starts_with(b"|Typ=") {
            Some(Self::TechnoTeam)
        } else {
            None
        }
    }

    /// The format of a file: by content when recognised, else by extension (so a damaged file gets
    /// the error of the reader its name asks for).
    pub fn detect(path: &Path, head: &[u8]) -> Result<Self> {
        Self::sniff(head).or_else(|| Self::from_extension(path)).ok_or_else(|| {
            NearfieldError::format(
                path,
                "not a luminance image: expected a TechnoTeam .pf/.pcf (starts with `Typ=`), a PFM (`Pf`/`PF`) \
                 or an OpenEXR file",
            )
        })
    }

    /// A short name for messages.
    pub fn name(&self) -> &'static str {
        match self {
            Self::TechnoTeam => "TechnoTeam .pf/.pcf",
            Self::Pfm => "PFM",
            Self::Exr => "OpenEXR",
        }
    }
}

/// What a file's header says, read without its pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImageHeader {
    /// The file's format.
    pub format: ImageFormat,
    /// Width (columns), pixels.
    pub width: u32,
    /// Height (rows), pixels.
    pub height: u32,
    /// Channels stored per pixel (1 luminance, 3 colour).
    pub channels: u8,
}

/// Decodes the bytes of a luminance image file; `path` picks the format when the content does not
/// ([`ImageFormat::detect`]) and names the file in errors.
pub fn decode_image(bytes: &[u8], path: &Path) -> Result<LuminanceImage> {
    match ImageFormat::detect(path, bytes)? {
        ImageFormat::TechnoTeam => parse_pf(bytes, path),
        ImageFormat::Pfm => parse_pfm(bytes, path),
        ImageFormat::Exr => parse_exr(bytes, path),
    }
}

/// Reads a luminance image file (`.pf`, `.pcf`, `.pfm`, `.exr`).
///
/// # Errors
/// [`NearfieldError::Io`] when the file cannot be read; [`NearfieldError::Format`] (naming the file
/// and what is wrong: not a regular file, truncated, header field missing or bad, size too large,
/// unknown type) or
/// [`NearfieldError::Unsupported`] (camera raw `.pus` images) otherwise. Pixel values are not checked
/// here (see [`LuminanceImage::validate`]).
pub fn read_image(path: &Path) -> Result<LuminanceImage> {
    let io = |e| NearfieldError::io(path, e);
    let file = open_regular(path)?;
    let len = file.metadata().map_err(io)?.len();
    // Up to MAX_FILE_BYTES (3 GiB): a failed allocation is an error, not an abort.
    let mut bytes = crate::files::try_vec(len as usize, "reading it").map_err(io)?;
    file.take(MAX_FILE_BYTES).read_to_end(&mut bytes).map_err(io)?;
    decode_image(&bytes, path)
}

/// Largest image file read: the pixels of [`MAX_PIXELS`] colour pixels plus a header.
const MAX_FILE_BYTES: u64 = MAX_PIXELS * 12 + PF_MAX_HEADER as u64;

/// Opens a regular file of at most [`MAX_FILE_BYTES`] (not a device, FIFO or folder, which could
/// block or never end).
fn open_regular(path: &Path) -> Result<std::fs::File> {
    // A refusal (not a regular file, too large) is a format error; anything else an I/O error.
    crate::files::open_regular(path, MAX_FILE_BYTES, "a luminance image")
        .map(|(f, _)| f)
        .map_err(|e| match e.kind() {
            std::io::ErrorKind::InvalidInput => fmt_err(path, e.to_string()),
            _ => NearfieldError::io(path, e),
        })
}

/// Reads only the header of a luminance image file: its format and size, and checks that the file is
/// long enough for the pixels it declares (`.pf`, `.pcf`, `.pfm`; OpenEXR headers are read and their
/// channels checked). Reads at most [`PF_MAX_HEADER`] bytes for `.pf` / PFM.
///
/// # Errors
/// As [`read_image`], for what the header shows.
pub fn read_image_header(path: &Path) -> Result<ImageHeader> {
    let io = |e| NearfieldError::io(path, e);
    let file = open_regular(path)?;
    let len = file.metadata().map_err(io)?.len();
    let mut head = Vec::with_capacity(PF_MAX_HEADER.min(len as usize));
    file.take(PF_MAX_HEADER as u64).read_to_end(&mut head).map_err(io)?;
    match ImageFormat::detect(path, &head)? {
        ImageFormat::TechnoTeam => {
            let h = parse_pf_header(&head, len, path)?;
            Ok(ImageHeader {
                format: ImageFormat::TechnoTeam,
                width: h.width,
                height: h.height,
                channels: if h.colour { 3 } else { 1 },
            })
        }
        ImageFormat::Pfm => {
            let h = parse_pfm_header(&head, len, path)?;
            Ok(ImageHeader {
                format: ImageFormat::Pfm,
                width: h.width,
                height: h.height,
                channels: if h.colour { 3 } else { 1 },
            })
        }
        ImageFormat::Exr => {
            let file = open_regular(path)?;
            let meta = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                exr::meta::MetaData::read_from_buffered(std::io::BufReader::new(file), false)
            }))
            .map_err(|_| fmt_err(path, "OpenEXR: the header reader failed on malformed data"))?
            .map_err(|e| fmt_err(path, format!("OpenEXR: {e}")))?;
            let header = exr_header(&meta, path)?;
            let (width, height) = exr_size(header, path)?;
            let channels = match exr_channels(header, path)? {
                ExrChannels::Y => 1,
                ExrChannels::Rgb(_) => 3,
            };
            Ok(ImageHeader {
                format: ImageFormat::Exr,
                width,
                height,
                channels,
            })
        }
    }
}
