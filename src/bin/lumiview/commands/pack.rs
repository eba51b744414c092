//! Subcommands on `.lvpack` near-field stores: `info`, `pack`, `cameras`.

use std::path::Path;

use super::CliResult;

/// `lumiview info FILE.lvpack`.
pub fn info_pack(file: &Path, _as_json: bool) -> CliResult {
    Err(format!("{}: .lvpack files are not supported yet", file.display()).into())
}
