//! `lumiview solid` (being written).

use std::path::PathBuf;

use super::CliResult;

/// Arguments of `lumiview solid`.
#[derive(clap::Args, Debug)]
pub struct SolidArgs {
    /// IES or EULUMDAT file.
    pub file: PathBuf,
    /// Output file.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Runs `lumiview solid`.
pub fn solid(args: &SolidArgs) -> CliResult {
    Err(format!("lumiview solid is not available yet ({})", args.file.display()).into())
}
