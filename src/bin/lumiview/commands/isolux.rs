//! `lumiview isolux`: illuminance in lux on a horizontal floor plane H metres below the
//! luminaire's photometric centre, as an isolux diagram (.png, .svg) or a grid table (.csv,
//! columns `x_m,y_m,E_lx`). See docs/photometry.md, "Isolux diagram".

use std::path::{Path, PathBuf};

use lumiview::photometry::isolux::{IsoluxError, IsoluxGrid, IsoluxOptions};
use lumiview::photometry::plot::{write_isolux, IsoluxPlotOptions, MAX_SIZE_PX, MIN_SIZE_PX};

use super::{print_report, CliResult};

/// Arguments of `lumiview isolux`.
#[derive(clap::Args, Debug)]
pub struct IsoluxArgs {
    /// IES or EULUMDAT file.
    pub file: PathBuf,
    /// Output file; the extension chooses the format: .png or .svg (diagram) or .csv (grid).
    #[arg(short = 'o', long = "output", value_name = "OUTPUT")]
    pub output: PathBuf,
    /// Mounting height: distance from the photometric centre down to the floor plane, metres.
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub height: f64,
    /// Half-width of the square floor grid, metres (default: where E falls below 1 % of its
    /// maximum, plus 10 %, rounded up; between 0.5 and 10 × the height).
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub extent: Option<f64>,
    /// Grid spacing, metres (default: extent / 100, i.e. 201 × 201 points).
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub step: Option<f64>,
    /// Image width in pixels for .png and .svg (default 800; the height follows from the layout,
    /// about 1.2 × the width).
    #[arg(long, value_name = "PX")]
    pub size: Option<u32>,
    /// Draw only the isolux lines, without the false-colour fill and its colour bar.
    #[arg(long)]
    pub no_fill: bool,
    #[command(flatten)]
    pub load: crate::LoadArgs,
}

/// What the output file holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Output {
    /// The diagram (.png or .svg; the plot writer picks by extension).
    Diagram,
    /// The grid as CSV.
    Csv,
}

fn output_kind(path: &Path) -> Result<Output, String> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("png" | "svg") => Ok(Output::Diagram),
        Some("csv") => Ok(Output::Csv),
        _ => Err(format!(
            "{}: unsupported output format: the file name must end in .png, .svg or .csv",
            path.display()
        )),
    }
}

/// A length argument: finite and greater than 0.
fn positive_metres(arg: &str, value: f64) -> Result<f64, String> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(format!(
            "{arg} {value}: must be a finite number of metres greater than 0"
        ))
    }
}

/// Runs `lumiview isolux`.
pub fn isolux(args: &IsoluxArgs) -> CliResult {
    // Check what needs no file first, so a typo costs no parsing.
    let kind = output_kind(&args.output)?;
    let height_m = positive_metres("--height", args.height)?;
    let extent_m = args.extent.map(|v| positive_metres("--extent", v)).transpose()?;
    let step_m = args.step.map(|v| positive_metres("--step", v)).transpose()?;
    if kind == Output::Csv {
        for (given, name) in [(args.size.is_some(), "--size"), (args.no_fill, "--no-fill")] {
            if given {
                return Err(format!(
                    "{name} applies to the .png and .svg diagram; {} is the grid as CSV",
                    args.output.display()
                )
                .into());
            }
        }
    }
    let size = args.size.unwrap_or(800);
    if !(MIN_SIZE_PX..=MAX_SIZE_PX).contains(&size) {
        return Err(format!("--size {size}: must be within {MIN_SIZE_PX}…{MAX_SIZE_PX} pixels").into());
    }
    let p = super::load(&args.file, &args.load)?;
    let opts = IsoluxOptions {
        height_m,
        extent_m,
        step_m,
    };
    let grid = IsoluxGrid::new(&p, &opts).map_err(|e| match e {
        IsoluxError::Height { .. } => format!("--height: {e}"),
        IsoluxError::Extent { .. } => format!("--extent: {e}"),
        IsoluxError::Step { .. } | IsoluxError::TooManyPoints { .. } => format!("--step: {e}"),
        IsoluxError::StepExceedsExtent { .. } if extent_m.is_none() => {
            format!("--step: {e} (chosen automatically; give --extent to set it)")
        }
        IsoluxError::StepExceedsExtent { .. } => format!("--step, --extent: {e}"),
    })?;
    match kind {
        Output::Csv => std::fs::write(&args.output, grid.to_csv())
            .map_err(|e| format!("{}: cannot write file: {e}", args.output.display()))?,
        Output::Diagram => {
            let plot_opts = IsoluxPlotOptions {
                size_px: size,
                fill: !args.no_fill,
            };
            write_isolux(&p, &grid, &plot_opts, &args.output)?;
        }
    }
    let n = grid.points_per_side();
    let max = grid.max();
    let levels: Vec<String> = grid.levels().iter().map(|l| format!("{l}")).collect();
    let lit = if levels.is_empty() {
        "E = 0 lx everywhere: no light reaches the floor".to_string()
    } else {
        format!(
            "max. E {:.4} lx at ({}, {}) m; isolux lines at {} lx",
            max.e_lx,
            round_m(max.x_m),
            round_m(max.y_m),
            levels.join(", ")
        )
    };
    let mut out = String::new();
    outln!(
        out,
        "{}: {n} × {n} points, step {} m, ±{} m, floor {} m below {}; {lit}",
        args.output.display(),
        round_m(grid.step_m),
        round_m(grid.half_width_m()),
        round_m(height_m),
        p.source,
    );
    print_report(&out)
}

/// A length for the summary, rounded to a micrometre (0.21, not 0.21000000000000002).
fn round_m(v: f64) -> f64 {
    let r = (v * 1e6).round() / 1e6;
    if r == 0.0 {
        0.0
    } else {
        r
    }
}
