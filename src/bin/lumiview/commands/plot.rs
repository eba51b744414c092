//! `lumiview plot` (being written).

use std::path::PathBuf;

use super::CliResult;

/// Arguments of `lumiview plot`.
#[derive(clap::Args, Debug)]
pub struct PlotArgs {
    /// IES or EULUMDAT file.
    pub file: PathBuf,
    /// Output file.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Runs `lumiview plot`.
pub fn plot(args: &PlotArgs) -> CliResult {
    Err(format!("lumiview plot is not available yet ({})", args.file.display()).into())
}
