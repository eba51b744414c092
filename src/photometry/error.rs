//! Errors of the photometry module: every failure names the file, the line or field, and what was
//! expected.

use std::fmt;
use std::path::PathBuf;

/// An error while reading or interpreting a photometric file.
#[derive(Debug, thiserror::Error)]
pub enum PhotometryError {
    /// The file (or a TILT file it names) could not be read.
    #[error("{path}: cannot read file: {source}")]
    Io {
        /// The file that could not be read.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// The file's contents do not follow the format.
    #[error("{0}")]
    Parse(ParseError),
    /// An argument given by the caller is out of range (not a fault of the file).
    #[error("invalid argument `{name}`: {message}")]
    InvalidArgument {
        /// The argument's name.
        name: &'static str,
        /// What was wrong with it.
        message: String,
    },
}

impl From<ParseError> for PhotometryError {
    fn from(e: ParseError) -> Self {
        PhotometryError::Parse(e)
    }
}

/// Where in a file a parse error happened and what was expected there.
#[derive(Debug, Clone, PartialEq)]
pub struct ParseError {
    /// The file's name as given by the caller (or `<memory>` for in-memory text).
    pub file: String,
    /// 1-based line number, where one applies.
    pub line: Option<usize>,
    /// The field being read (e.g. `number of vertical angles`).
    pub field: String,
    /// What was expected and what was found.
    pub message: String,
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{}: {}: {}", self.file, line, self.field, self.message),
            None => write!(f, "{}: {}: {}", self.file, self.field, self.message),
        }
    }
}

impl std::error::Error for ParseError {}

/// Convenience constructor used by the parsers.
pub(crate) fn parse_error(
    file: &str,
    line: Option<usize>,
    field: impl Into<String>,
    message: impl Into<String>,
) -> ParseError {
    ParseError {
        file: file.to_string(),
        line,
        field: field.into(),
        message: message.into(),
    }
}
