//! `lumiview plot`: the polar intensity diagram (C0–C180 and C90–C270 planes) as SVG or PNG.

use std::path::PathBuf;

use clap::ValueEnum;
use lumiview::photometry::plot::{write_plot, PlotFormat, PlotOptions, PlotUnit, MAX_SIZE_PX, MIN_SIZE_PX};

use super::CliResult;
use crate::LoadArgs;

/// Unit of the diagram on the command line.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnitArg {
    /// Absolute intensity, cd.
    Cd,
    /// cd per 1000 lm of rated lamp flux (absolute photometry: of integrated luminaire flux).
    #[value(name = "cdklm", alias = "cd/klm")]
    CdKlm,
}

/// Arguments of `lumiview plot`.
#[derive(clap::Args, Debug)]
pub struct PlotArgs {
    /// IES or EULUMDAT file.
    pub file: PathBuf,
    /// Output file; the extension chooses the format: .svg or .png.
    #[arg(short, long, value_name = "OUTPUT")]
    pub output: PathBuf,
    /// Unit of the rings and curves.
    #[arg(long, value_enum, default_value_t = UnitArg::Cd)]
    pub unit: UnitArg,
    /// Image width in pixels (the height follows from the layout, about 1.15–1.2 × the width).
    #[arg(long, value_name = "PIXELS", default_value_t = 800)]
    pub size: u32,
    #[command(flatten)]
    pub load_args: LoadArgs,
}

/// Runs `lumiview plot`.
pub fn plot(args: &PlotArgs) -> CliResult {
    // Check what needs no file first, so a typo costs no parsing.
    PlotFormat::from_path(&args.output)?;
    if !(MIN_SIZE_PX..=MAX_SIZE_PX).contains(&args.size) {
        return Err(format!(
            "--size {}: must be within {MIN_SIZE_PX}…{MAX_SIZE_PX} pixels",
            args.size
        )
        .into());
    }
    let p = super::load(&args.file, &args.load_args)?;
    let opts = PlotOptions {
        unit: match args.unit {
            UnitArg::Cd => PlotUnit::Candela,
            UnitArg::CdKlm => PlotUnit::CandelaPerKilolumen,
        },
        size_px: args.size,
    };
    write_plot(&p, &opts, &args.output)?;
    Ok(())
}
