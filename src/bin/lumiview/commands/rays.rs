//! Subcommands on IES TM-25 ray files: `info` and `rays2scan`.

use std::path::Path;

use super::CliResult;

/// `lumiview info FILE.tm25ray`.
pub fn info_rayfile(file: &Path, _as_json: bool) -> CliResult {
    Err(format!("{}: TM-25 ray files are not supported yet", file.display()).into())
}
