//! Errors of scene lighting's CPU layer. Every error names the file or the argument it is about.

use std::path::PathBuf;

/// An error loading a scene, placing a luminaire or computing illuminance.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// An I/O error on a named file (the scene, a buffer or image file it names, an output).
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A file whose contents are malformed or unsupported (not glTF, an index out of range, a
    /// non-finite position, a buffer too short, ...).
    #[error("{path}: {message}")]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the glTF object (`accessor 3`, `mesh 1 primitive 0`, ...).
        message: String,
    },
    /// A bad argument (a placement, a grid, options, a luminaire's matrix).
    #[error("invalid argument '{name}': {message}")]
    InvalidArgument {
        /// The argument's name.
        name: String,
        /// Why it is rejected.
        message: String,
    },
}

impl SceneError {
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

    /// An invalid-argument error.
    pub fn invalid(name: impl Into<String>, message: impl Into<String>) -> Self {
        Self::InvalidArgument {
            name: name.into(),
            message: message.into(),
        }
    }
}

/// Result alias of the scene layer.
pub type Result<T, E = SceneError> = std::result::Result<T, E>;
