//! `lumiview lut` (being written).

use std::path::PathBuf;

use super::CliResult;

/// Arguments of `lumiview lut`.
#[derive(clap::Args, Debug)]
pub struct LutArgs {
    /// IES or EULUMDAT file.
    pub file: PathBuf,
    /// Output file.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Runs `lumiview lut`.
pub fn lut(args: &LutArgs) -> CliResult {
    Err(format!("lumiview lut is not available yet ({})", args.file.display()).into())
}
