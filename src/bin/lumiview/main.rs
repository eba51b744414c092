//! `lumiview`: inspect photometric files, sample them, print luminance tables, write look-up
//! tables, photometric solids and polar plots. A thin layer over the library.

mod commands;
mod interrupt;

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
    /// EULUMDAT lamp set to use, 1-based (sets are alternative equipment; default 1).
    #[arg(long, value_name = "N")]
    pub lamp_set: Option<usize>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Summarise a photometric file: format, labels, type, symmetry, grid, lamps, maximum
    /// intensity (cd) where the file stores it, flux (lm), beam and field angles, zonal lumens,
    /// DLOR/ULOR, CIE flux code, luminous opening (m), warnings. Several files or a folder: one
    /// CSV table (JSON lines with --json), continuing past a bad file.
    Info {
        /// IES (.ies) or EULUMDAT (.ldt) files or folders of them; a TM-25 ray file or .lvpack.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Print JSON instead of text (several files: one JSON object per line).
        #[arg(long)]
        json: bool,
        /// For an .lvpack: read every page and check its checksum (and that padding is zero).
        #[arg(long)]
        verify: bool,
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
    /// Several files or a folder: one CSV table `file,c_deg,gamma_deg,luminance_cd_m2,error` (JSON
    /// lines with --json), continuing past a bad file.
    Luminance {
        /// IES or EULUMDAT files, or folders of them.
        #[arg(required = true)]
        files: Vec<PathBuf>,
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
    /// Convert between IES LM-63-2019 and EULUMDAT, keeping the intensities (absolute, every C
    /// plane, the symmetry), the dimensions on their axes, lamp data and labels; what the target
    /// cannot keep is listed on stderr. Several files or a folder: into an output folder, one table.
    Convert(commands::ConvertArgs),
    /// Write a look-up table for host lighting (EXR for float encodings, PNG for 8-bit).
    Lut(commands::LutArgs),
    /// Write the photometric solid (r ∝ I) as a mesh (.obj or .glb).
    Solid(commands::SolidArgs),
    /// Write the polar intensity diagram (C0–C180 and C90–C270 planes) as .svg or .png.
    Plot(commands::PlotArgs),
    /// Write illuminance in lx on a floor plane --height metres below the luminaire: isolux diagram
    /// (.png or .svg: lines at 1-2-5 values, axes in m) or the grid as .csv (x_m,y_m,E_lx).
    Isolux(commands::IsoluxArgs),
    /// Render a still of the luminaire's appearance on the GPU (Vulkan): .png tone-mapped or .exr in cd/m².
    Render(commands::RenderArgs),
    /// A glTF scene lit by photometric luminaires (FILE@X,Y,Z[,YAW]): a view rendered on the GPU
    /// (.png tone-mapped, .exr cd/m²; direct light with shadow maps and inter-reflection), or with --grid H the
    /// illuminance in lx on the work plane y = H from the reference path tracer (.csv, or .png:
    /// false colour with isolux lines), printing Ē, Emin, Emax and U0 = Emin/Ē.
    Scene(commands::SceneArgs),
    /// Where a near-field scan's cameras sit and how well they cover the sphere: cameras per
    /// hemisphere, coincident positions, angle to the nearest camera (median, 95 %, max); -o writes
    /// a PNG (positions on equal-area discs, map of the nearest-camera angle).
    Cameras(commands::CamerasArgs),
    /// Bin an IES TM-25 ray file into the luminance images of a virtual near-field scan (cameras on
    /// a capture sphere) and write it as a scan (manifest + images); prints rays per camera and per
    /// lit pixel.
    Rays2scan(commands::Rays2scanArgs),
    /// Synthetic goniophotometer: analytic luminaires with exact photometry; write a scan, the proxy
    /// mesh or an orthographic ground-truth view (docs/synthetic.md).
    Synth(commands::SynthArgs),
    /// Store a near-field scan as a tiled .lvpack file (only tiles with signal, fp16 × per-tile
    /// scale within 0.05 %, pages ≤ 128 MiB): from scan manifests, --synth, a TM-25 ray file or
    /// another .lvpack.
    Pack(commands::PackArgs),
    /// The proxy mesh a scan renders with when it comes without one, reconstructed from its images
    /// (space carving; docs/proxy.md), written as .glb; --synth measures the reconstruction of
    /// synthetic luminaires against their true proxies (Chamfer table).
    Proxy(commands::ProxyArgs),
    /// Near-field quality harness: synthetic luminaires scanned, packed and rendered on the GPU in
    /// each selection mode, compared with the exact ray-caster (docs/quality-metrics.md); prints the
    /// table and writes the worst views as images.
    Eval(commands::EvalArgs),
    /// Ray-file convergence harness: rays forward-traced from synthetic luminaires at several
    /// counts, estimated, rendered on the GPU and compared with the kernel-matched truth and the
    /// exact ray-caster (docs/quality-metrics.md, "Ray files"); prints the table and the verdicts.
    EvalRays(commands::EvalRaysArgs),
}

/// Mesa's device-select Vulkan layer probes Wayland while the GPUs are listed and prints "error:
/// XDG_RUNTIME_DIR is invalid or not set in the environment" twice where there is no desktop
/// session (ssh, containers, CI). lumiview picks its adapter itself, so there the layer is
/// switched off (`NODEVICE_SELECT=1`); a value the user set wins.
fn quiet_vulkan_layers() {
    let session = std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).is_dir());
    if !session && std::env::var_os("NODEVICE_SELECT").is_none() {
        // Edition 2021: set before any thread exists (the first thing `main` does).
        std::env::set_var("NODEVICE_SELECT", "1");
    }
}

fn main() -> ExitCode {
    quiet_vulkan_layers();
    interrupt::install();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Info {
            files,
            json,
            verify,
            load,
        } => commands::info(&files, json, verify, &load),
        Command::Sample { file, at, json, load } => commands::sample(&file, &at, json, &load),
        Command::Luminance {
            files,
            json,
            c,
            gamma,
            load,
        } => commands::luminance(&files, json, &c, &gamma, &load),
        Command::Convert(args) => commands::convert(&args),
        Command::Lut(args) => commands::lut(&args),
        Command::Solid(args) => commands::solid(&args),
        Command::Plot(args) => commands::plot(&args),
        Command::Isolux(args) => commands::isolux(&args),
        Command::Render(args) => commands::render(&args),
        Command::Scene(args) => commands::scene(&args),
        Command::Cameras(args) => commands::cameras(&args),
        Command::Rays2scan(args) => commands::rays2scan(&args),
        Command::Synth(args) => commands::synth(&args),
        Command::Pack(args) => commands::pack(&args),
        Command::Proxy(args) => commands::proxy(&args),
        Command::Eval(args) => commands::eval(&args),
        Command::EvalRays(args) => commands::eval_rays(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("lumiview: error: {e}");
            ExitCode::FAILURE
        }
    }
}
