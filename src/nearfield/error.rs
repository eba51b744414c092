//! Errors of the near-field data layer. Every error names the file, image or argument it is about.

use std::path::PathBuf;

/// An error reading, converting, rendering or storing near-field data.
#[derive(Debug, thiserror::Error)]
pub enum NearfieldError {
    /// An I/O error on a named file.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A file whose contents are malformed (truncated, wrong magic, bad header field, ...).
    #[error("{path}: {message}")]
    Format {
        /// The file (or a description such as `manifest entry 12`).
        path: PathBuf,
        /// What is wrong, naming the field or offset.
        message: String,
    },
    /// An image inconsistent with its scan (wrong size, non-finite or negative luminance, duplicate pose).
    #[error("image {image}: {message}")]
    Image {
        /// The image's name (file name or index).
        image: String,
        /// What is wrong.
        message: String,
    },
    /// A corrupted section of a `.lvpack` file (checksum mismatch or out-of-range table entry).
    #[error("{path}: section '{section}' is corrupt: {message}")]
    Corrupt {
        /// The pack file.
        path: PathBuf,
        /// The section's name.
        section: String,
        /// What was detected.
        message: String,
    },
    /// A bad argument (layout parameters, camera counts, options).
    #[error("invalid argument '{name}': {message}")]
    InvalidArgument {
        /// The argument's name.
        name: String,
        /// Why it is rejected.
        message: String,
    },
    /// The data uses a feature that is deliberately not supported (e.g. TM-25 Stokes columns).
    #[error("{path}: unsupported: {message}")]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// What is not supported and why.
        message: String,
    },
}

impl NearfieldError {
    /// An I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }
    /// A format error in `path`.
    pub fn format(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Self::Format {
            path: path.into(),
            message: message.into(),
        }
    }
    /// An image error.
    pub fn image(image: impl Into<String>, message: impl Into<String>) -> Self {
        Self::Image {
            image: image.into(),
            message: message.into(),
        }
    }
    /// An invalid-argument error.
    pub fn invalid(name: impl Into<String>, message: impl Into<String>) -> Self {
        Self::InvalidArgument {
            name: name.into(),
            message: message.into(),
        }
    }
}

/// Result alias of the near-field layer.
pub type Result<T, E = NearfieldError> = std::result::Result<T, E>;
