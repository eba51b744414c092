//! `lumiview`: inspect photometric files, sample them, print luminance tables, write look-up
//! tables, photometric solids and polar plots. A thin layer over the library.

mod commands;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};

/// Command-line tool of lumiview: luminaire photometry and appearance.
#[derive(Parser, Debug)]
#[command(name = "lumiview", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// Options for reading a photometric file.
#[derive(Args, Debug, Clone)]
pub struct LoadArgs {
    /// Lamp tilt angle in degrees at which to apply the file's TILT table (default: the measured
    /// orientation, no factor).
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub tilt: Option<f64>,
    /// EULUMDAT lamp set to use, 1-based (sets are alternative equipment).
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub lamp_set: usize,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Summarise a photometric file: format, labels, type, symmetry, grid, lamps, maximum
    /// intensity (cd), integrated flux (lm), luminous opening (m).
    Info {
        /// IES (.ies) or EULUMDAT (.ldt) file.
        file: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
        #[command(flatten)]
        load: LoadArgs,
    },
    /// Luminous intensity in cd at directions given as C,GAMMA in degrees (lumiview's Type C frame).
    Sample {
        /// IES or EULUMDAT file.
        file: PathBuf,
        /// A direction `C,GAMMA` in degrees; repeat for more.
        #[arg(long = "at", value_name = "C,GAMMA", required = true, allow_hyphen_values = true)]
        at: Vec<String>,
        /// Print JSON: {"unit":"cd","samples":[{"c":..,"gamma":..,"cd":..}]}.
        #[arg(long)]
        json: bool,
        #[command(flatten)]
        load: LoadArgs,
    },
    /// Luminance table of the luminous opening in cd/m² (default: C 0–345 step 15, γ 65–85 step 5,
    /// the glare-rating grid).
    Luminance {
        /// IES or EULUMDAT file.
        file: PathBuf,
        /// Print JSON: {"unit":"cd/m2","c":[..],"gamma":[..],"table":[[..]]}, table[i][j] for
        /// gamma[i], c[j].
        #[arg(long)]
        json: bool,
        /// C angles as FROM:TO:STEP in degrees.
        #[arg(long, default_value = "0:345:15", value_name = "FROM:TO:STEP")]
        c: String,
        /// γ angles as FROM:TO:STEP in degrees.
        #[arg(long, default_value = "65:85:5", value_name = "FROM:TO:STEP")]
        gamma: String,
        #[command(flatten)]
        load: LoadArgs,
    },
    /// Write a look-up table for host lighting (EXR for float encodings, PNG for 8-bit).
    Lut(commands::LutArgs),
    /// Write the photometric solid (r ∝ I) as a mesh (.obj or .glb).
    Solid(commands::SolidArgs),
    /// Write the polar intensity diagram (C0–C180 and C90–C270 planes) as .svg or .png.
    Plot(commands::PlotArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Info { file, json, load } => commands::info(&file, json, &load),
        Command::Sample { file, at, json, load } => commands::sample(&file, &at, json, &load),
        Command::Luminance {
            file,
            json,
            c,
            gamma,
            load,
        } => commands::luminance(&file, json, &c, &gamma, &load),
        Command::Lut(args) => commands::lut(&args),
        Command::Solid(args) => commands::solid(&args),
        Command::Plot(args) => commands::plot(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("lumiview: error: {e}");
            ExitCode::FAILURE
        }
    }
}
