//! `lumiview scene`: a glTF scene lit by photometric luminaires and near-field scans (by their far
//! field, `nearfield::farfield`; the view draws a scan with its measured appearance). Without `--grid`, a view rendered
//! on the GPU (Vulkan) as a host would get it: the lit room in cd/m² (L = ρE/π, direct light with
//! shadow maps and inter-reflection from virtual point lights) with the luminaires' own appearance, as PNG (tone-mapped) or OpenEXR (cd/m²). With
//! `--grid H`, the illuminance in lx on the work plane y = H, computed by the reference path
//! tracer (direct light with visibility and every inter-reflection), as CSV or as a false-colour
//! plan with isolux lines; Ē, Emin, Emax and U0 are printed. Conventions: docs/scene-lighting.md.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use clap::Args;
use glam::Vec3;
use lumiview::gpu::nearfield::NearfieldOptions;
use lumiview::gpu::scene::SceneSettings;
use lumiview::gpu::{
    Attachment, ColorFormat, ContextDesc, DepthFormat, DepthRange, HostCamera, Origin, OutputMode, Overlays,
    RenderOptions, RenderTarget, Renderer, TargetDesc,
};
use lumiview::nearfield::farfield::{FarField, FarFieldOptions};
use lumiview::nearfield::pack::Pack;
use lumiview::photometry::Photometry;
use lumiview::scene::grid::{work_plane_grid, write_grid_csv, FloorRect};
use lumiview::scene::place::parse_luminaire_arg;
use lumiview::scene::plot::{fmt_lx, GridPlot, GridStats};
use lumiview::scene::{Scene, SceneLuminaire, TraceOptions, Tracer};
use lumiview::source::{self, Source, SourceKind, SourceOptions};

use super::render::{look_at, parse_camera, percentile_luminance, perspective, write_still, Still};
use super::CliResult;
use crate::LoadArgs;

/// Arguments of `lumiview scene`.
#[derive(Args, Debug)]
pub struct SceneArgs {
    /// glTF 2.0 scene (.glb, or .gltf with its buffers): metres, +Y up; surfaces are Lambertian
    /// with the base colour as reflectance. The sample office: assets/scenes/office.glb.
    pub scene: PathBuf,
    /// A luminaire placed in the scene: an IES or EULUMDAT file, or a near-field scan (.lvpack,
    /// manifest, TM-25 ray file) lighting by its far field estimated from its images, its
    /// photometric centre at X,Y,Z
    /// (scene metres), nadir along −Y, C0 along +X turned by YAW degrees about +Y (counter-clockwise
    /// seen from above). Repeat for more; the same file may be placed many times.
    #[arg(
        long = "luminaire",
        value_name = "FILE@X,Y,Z[,YAW]",
        required = true,
        allow_hyphen_values = true
    )]
    pub luminaires: Vec<String>,
    /// Output. A view: .png (tone-mapped, sRGB) or .exr (luminance in cd/m²). With --grid: .csv
    /// (x_m,y_m,z_m,E_lx) or .png (false-colour plan with isolux lines and the figures).
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Calculate the illuminance on the horizontal work plane y = H metres (e.g. 0.75 for desks)
    /// instead of rendering a view.
    #[arg(long, value_name = "H", allow_hyphen_values = true)]
    pub grid: Option<f64>,
    /// The grid's rectangle X0,Z0,X1,Z1 in scene metres (default: the scene's X–Z extent inset by
    /// --margin).
    #[arg(long = "grid-rect", value_name = "X0,Z0,X1,Z1", allow_hyphen_values = true)]
    pub grid_rect: Option<String>,
    /// Border left out of the default grid rectangle on every side, metres (a wall zone; EN
    /// 12464-1 uses 0.5 m).
    #[arg(long, value_name = "M", default_value_t = 0.0)]
    pub margin: f64,
    /// Largest distance between grid points, metres (cell centres; default 0.1, coarser where a
    /// large floor would need more than 20,000 points).
    #[arg(long, value_name = "M")]
    pub spacing: Option<f64>,
    /// Indirect paths per grid point (the standard error falls as 1/√N); 0 gives direct light only.
    #[arg(long, default_value_t = 512)]
    pub paths: usize,
    /// Direct light only (the same as --paths 0).
    #[arg(long)]
    pub direct_only: bool,
    /// Seed of the path tracer's random numbers.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Eye and target of the view in scene metres: EX,EY,EZ or EX,EY,EZ,TX,TY,TZ (default: from a
    /// corner of the scene's bounds at 55 % of its height, looking across it).
    #[arg(long, allow_hyphen_values = true, value_name = "EX,EY,EZ[,TX,TY,TZ]")]
    pub camera: Option<String>,
    /// Vertical field of view of the view, degrees.
    #[arg(long, default_value_t = 60.0)]
    pub fov: f32,
    /// Size of the view WxH in pixels.
    #[arg(long, default_value = "960x540")]
    pub size: String,
    /// PNG exposure in m²/cd (x = L · exposure, display x / (1 + x)), or `auto`: the view's median
    /// luminance shows as 25 % grey (the default).
    #[arg(long, value_name = "M2_PER_CD|auto", allow_hyphen_values = true)]
    pub exposure: Option<String>,
    /// Add a luminance scale bar in cd/m² below the PNG view.
    #[arg(long)]
    pub legend: bool,
    /// Render the view without shadows (every luminaire reaches every surface facing it).
    #[arg(long)]
    pub no_shadows: bool,
    /// Render the view without inter-reflection (direct light only).
    #[arg(long)]
    pub no_indirect: bool,
    /// Photons shot from the luminaires for the view's inter-reflection (each reflection leaves a
    /// virtual point light that every pixel gathers; docs/scene-lighting.md).
    #[arg(long, value_name = "N")]
    pub bounce_photons: Option<u32>,
    #[command(flatten)]
    pub load: LoadArgs,
}

/// A luminaire of the command line: its photometry (shared by placements of one file), matrix
/// and position.
struct Placed {
    /// What lights the scene (a scan's far field for a scan).
    photometry: Arc<Photometry>,
    /// The scan, drawn with its measured appearance in the view.
    pack: Option<Arc<Pack>>,
    matrix: glam::DMat4,
    position_m: glam::DVec3,
}

fn ext_of(path: &Path) -> Option<String> {
    path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase)
}

fn parse_rect(text: &str) -> Result<FloorRect, String> {
    let v: Vec<f64> = text
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--grid-rect '{text}': expected X0,Z0,X1,Z1 in metres"))?;
    match v[..] {
        [x0, z0, x1, z1] if v.iter().all(|x| x.is_finite()) && x1 > x0 && z1 > z0 => Ok(FloorRect {
            x_min_m: x0,
            x_max_m: x1,
            z_min_m: z0,
            z_max_m: z1,
        }),
        _ => Err(format!(
            "--grid-rect '{text}': expected four finite numbers X0,Z0,X1,Z1 with X1 > X0 and Z1 > Z0"
        )),
    }
}

/// Reads every `--luminaire`: each file once. A near-field scan (a pack, manifest or ray file)
/// lights by its far field, estimated from its images (`nearfield::farfield`, with a progress
/// bar and a line saying what it found); the view draws it with its measured appearance.
fn luminaires(args: &SceneArgs) -> Result<Vec<Placed>, Box<dyn std::error::Error>> {
    type Loaded = (Arc<Photometry>, Option<Arc<Pack>>);
    let mut loaded: HashMap<PathBuf, Loaded> = HashMap::new();
    let mut out = Vec::new();
    for text in &args.luminaires {
        let (file, at) = parse_luminaire_arg(text).map_err(|e| format!("--luminaire: {e}"))?;
        let (photometry, pack) = match loaded.get(&file) {
            Some(l) => l.clone(),
            None => {
                let kind = source::detect(&file)?;
                let l: Loaded = if kind == SourceKind::Photometry {
                    (Arc::new(super::load(&file, &args.load)?), None)
                } else {
                    let (p, pack) = scan_light(&file, kind)?;
                    (Arc::new(p), Some(Arc::new(pack)))
                };
                loaded.insert(file.clone(), l.clone());
                l
            }
        };
        out.push(Placed {
            photometry,
            pack,
            matrix: at.matrix(),
            position_m: glam::DVec3::new(at.x_m, at.y_m, at.z_m),
        });
    }
    Ok(out)
}

/// Opens the scan `file` (packing a manifest or ray file into the cache first) and estimates its
/// far field, with a progress bar; prints what it found and its warnings on stderr.
pub(super) fn scan_light(file: &Path, kind: SourceKind) -> Result<(Photometry, Pack), Box<dyn std::error::Error>> {
    let mut warnings = Vec::new();
    let Source::Scan { pack, .. } = source::open(file, kind, &SourceOptions::default(), &mut warnings)? else {
        return Err(format!("{}: opened as photometry, not as a scan", file.display()).into());
    };
    for w in &warnings {
        eprintln!("lumiview: warning: {w}");
    }
    let bar = super::proxy::bar(false, "far field");
    let ff = FarField::estimate(pack.rayset(), &pack, &FarFieldOptions::default(), &|f| {
        super::proxy::show_stage(&bar, "cameras", (f * 1000.0) as usize, 1000)
    })?;
    bar.finish_and_clear();
    for w in &ff.warnings {
        eprintln!("lumiview: warning: {w}");
    }
    let name = file.display().to_string();
    let p = ff.photometry(&name)?;
    let e = ff.extent_m;
    eprintln!(
        "lumiview: {name}: far field of the scan from {} cameras: {:.1} lm, kernel σ {:.2}°, luminous extent \
         {:.3} × {:.3} × {:.3} m (X × Y × Z)",
        ff.cameras_used, ff.flux_lm, ff.bandwidth_deg, e.x, e.y, e.z
    );
    Ok((p, pack))
}

/// Runs `lumiview scene`.
pub fn scene(args: &SceneArgs) -> CliResult {
    let ext = ext_of(&args.output);
    let grid_only = [
        (args.grid_rect.is_some(), "--grid-rect"),
        (args.spacing.is_some(), "--spacing"),
        (args.direct_only, "--direct-only"),
        (args.margin != 0.0, "--margin"),
    ];
    let view_only = [
        (args.camera.is_some(), "--camera"),
        (args.exposure.is_some(), "--exposure"),
        (args.legend, "--legend"),
        (args.no_shadows, "--no-shadows"),
        (args.no_indirect, "--no-indirect"),
        (args.bounce_photons.is_some(), "--bounce-photons"),
    ];
    if args.grid.is_some() {
        if !matches!(ext.as_deref(), Some("csv" | "png")) {
            return Err(format!(
                "{}: with --grid the output must end in .csv or .png",
                args.output.display()
            )
            .into());
        }
        if let Some((_, name)) = view_only.iter().find(|(given, _)| *given) {
            return Err(format!("{name} applies to a rendered view; --grid calculates illuminance").into());
        }
    } else {
        if !matches!(ext.as_deref(), Some("png" | "exr")) {
            return Err(format!(
                "{}: a view must end in .png or .exr (give --grid H for the illuminance grid as .csv or .png)",
                args.output.display()
            )
            .into());
        }
        if let Some((_, name)) = grid_only.iter().find(|(given, _)| *given) {
            return Err(format!("{name} applies to the illuminance grid (--grid H)").into());
        }
    }
    let inputs: Vec<PathBuf> = std::iter::once(args.scene.clone())
        .chain(
            args.luminaires
                .iter()
                .filter_map(|t| parse_luminaire_arg(t).ok().map(|(f, _)| f)),
        )
        .collect();
    lumiview::files::ensure_not_input(&args.output, inputs.iter().map(PathBuf::as_path))?;
    let scene = lumiview::scene::load(&args.scene)?;
    for w in scene.warnings() {
        eprintln!("lumiview: warning: {w}");
    }
    let placed = luminaires(args)?;
    match args.grid {
        Some(h) => grid(args, &scene, &placed, h),
        None => view(args, &scene, &placed),
    }
}

/// Default grid spacing, metres: 0.1, or coarser so the floor has at most 20,000 points.
fn default_spacing_m(rect: &FloorRect) -> f64 {
    let area = (rect.x_max_m - rect.x_min_m) * (rect.z_max_m - rect.z_min_m);
    0.1f64.max((area / 20_000.0).sqrt())
}

fn grid(args: &SceneArgs, scene: &Scene, placed: &[Placed], height_m: f64) -> CliResult {
    if !height_m.is_finite() {
        return Err(format!("--grid {height_m}: the work plane's height must be a finite number of metres").into());
    }
    let rect = match &args.grid_rect {
        Some(t) => parse_rect(t)?,
        None => FloorRect::of_bounds(&scene.bounds(), args.margin).map_err(|e| format!("--margin: {e}"))?,
    };
    let spacing_m = args.spacing.unwrap_or_else(|| default_spacing_m(&rect));
    let points = work_plane_grid(&rect, height_m, spacing_m).map_err(|e| format!("--spacing: {e}"))?;
    let (w, d) = (rect.x_max_m - rect.x_min_m, rect.z_max_m - rect.z_min_m);
    let (nx, nz) = ((w / spacing_m).ceil() as usize, (d / spacing_m).ceil() as usize);
    if nx * nz != points.len() {
        return Err(format!("internal: {} points for {nx} × {nz} cells", points.len()).into());
    }
    let lums: Vec<SceneLuminaire> = placed
        .iter()
        .map(|p| SceneLuminaire {
            photometry: p.photometry.clone(),
            scene_from_luminaire: p.matrix,
        })
        .collect();
    let tracer = Tracer::new(scene, &lums)?;
    let paths = if args.direct_only { 0 } else { args.paths };
    let opts = TraceOptions {
        paths_per_point: paths,
        seed: args.seed,
        ..TraceOptions::default()
    };
    // Each point's random numbers depend only on the seed and its index: the progress bar
    // changes nothing.
    let bar = indicatif::ProgressBar::new(points.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} points [{elapsed_precise}]")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message(if paths == 0 {
        "direct light".to_string()
    } else {
        format!("tracing {paths} paths per point")
    });
    let t = Instant::now();
    let results = tracer.illuminance_with_progress(&points, &opts, &|done| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    let seconds = t.elapsed().as_secs_f64();
    let e: Vec<f64> = results.iter().map(|r| r.total_lx).collect();
    let se_max = results.iter().map(|r| r.total_se_lx).fold(0.0, f64::max);
    let stats = GridStats::of(&e)?;
    let method = if paths == 0 {
        "direct light with visibility (no inter-reflection)".to_string()
    } else {
        format!(
            "direct light with visibility + every inter-reflection (reference path tracer, {paths} paths per point, \
             largest standard error {} lx)",
            fmt_lx(se_max)
        )
    };
    match ext_of(&args.output).as_deref() {
        Some("csv") => write_grid_csv(&args.output, &points, &e)?,
        _ => {
            let title = format!(
                "Illuminance E (lx) on the work plane y = {} m: {}",
                trim(height_m),
                args.scene.file_name().map_or_else(
                    || args.scene.display().to_string(),
                    |n| n.to_string_lossy().into_owned()
                )
            );
            let lum_names: Vec<String> = {
                let mut v: Vec<String> = placed.iter().map(|p| p.photometry.source.clone()).collect();
                v.dedup();
                v
            };
            let plot = GridPlot {
                rect,
                nx,
                nz,
                values_lx: &e,
                luminaires_xz_m: &placed.iter().map(|p| [p.position_m.x, p.position_m.z]).collect::<Vec<_>>(),
                title,
                caption: vec![
                    format!(
                        "plan view from above, x → right, z ↓ down, metres; {nx} × {nz} points every {} × {} m (cell centres); \
                         {} luminaires (○ with ×)",
                        trim(w / nx as f64),
                        trim(d / nz as f64),
                        placed.len()
                    ),
                    method.clone(),
                    format!("luminaires: {}", lum_names.join(", ")),
                ],
                width_px: 900,
            };
            let pm = plot.to_pixmap()?;
            let png = pm.encode_png().map_err(|e| format!("{}: {e}", args.output.display()))?;
            write_atomic(&args.output, &png)?;
        }
    }
    println!(
        "{}: work plane y = {} m, {nx} × {nz} points every ≤ {} m over x {}…{} m, z {}…{} m; Ē {} lx, Emin {} lx, \
         Emax {} lx, U0 = Emin/Ē {:.3}, Emin/Emax {:.3}; {method}; {:.1} s",
        args.output.display(),
        trim(height_m),
        trim(spacing_m),
        trim(rect.x_min_m),
        trim(rect.x_max_m),
        trim(rect.z_min_m),
        trim(rect.z_max_m),
        fmt_lx(stats.avg_lx),
        fmt_lx(stats.min_lx),
        fmt_lx(stats.max_lx),
        stats.u0,
        stats.min_over_max,
        seconds
    );
    Ok(())
}

/// A number of metres as written (0.75, not 0.75000000001).
fn trim(v: f64) -> String {
    lumiview::draw::ticks::trim_number(format!("{v:.4}"))
}

fn write_atomic(path: &Path, bytes: &[u8]) -> CliResult {
    use std::io::Write as _;
    let cannot = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    let (mut tmp, _) = lumiview::files::TempOutput::create(path).map_err(|e| cannot(&e))?;
    tmp.file()
        .ok_or_else(|| cannot(&"the temporary file is not open"))?
        .write_all(bytes)
        .map_err(|e| cannot(&e))?;
    tmp.commit().map_err(|e| cannot(&e))?;
    Ok(())
}

fn view(args: &SceneArgs, scene: &Scene, placed: &[Placed]) -> CliResult {
    let (w, h) = args
        .size
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)))
        .ok_or_else(|| format!("--size '{}': expected WxH", args.size))?;
    if !(args.fov.is_finite() && (1.0..170.0).contains(&args.fov)) {
        return Err(format!("--fov {}: expected 1…170 degrees", args.fov).into());
    }
    let exr = ext_of(&args.output).as_deref() == Some("exr");
    if exr && (args.exposure.is_some() || args.legend) {
        return Err(format!(
            "--exposure and --legend apply to .png views; {} is an OpenEXR of luminance in cd/m²",
            args.output.display()
        )
        .into());
    }
    if args.legend && w < 160 {
        return Err(format!("--legend needs a view at least 160 px wide (--size {})", args.size).into());
    }
    let exposure_arg = match args.exposure.as_deref() {
        None | Some("auto") => None,
        Some(t) => match t.trim().parse::<f32>() {
            Ok(v) if v.is_finite() && v > 0.0 => Some(v),
            _ => return Err(format!("--exposure `{t}`: expected a positive number in m²/cd or auto").into()),
        },
    };
    let b = scene.bounds();
    let size = b.size();
    let (eye, target) = match args.camera.as_deref().map(parse_camera).transpose()? {
        Some((e, t)) => (e, t.unwrap_or(b.min.as_vec3() + size.as_vec3() * 0.5)),
        None => (
            (b.min + size * glam::DVec3::new(0.08, 0.55, 0.92)).as_vec3(),
            (b.min + size * glam::DVec3::new(0.72, 0.3, 0.3)).as_vec3(),
        ),
    };
    if (target - eye).length() < 1e-6 {
        return Err("--camera: the eye and the point it looks at coincide".into());
    }
    let fwd = (target - eye).normalize();
    let up = if fwd.cross(Vec3::Y).length() < 0.02 {
        Vec3::Z
    } else {
        Vec3::Y
    };
    let reach = size.length().max(1.0) as f32 * 4.0;
    let cam = HostCamera {
        view: look_at(eye, target, up),
        projection: perspective(args.fov.to_radians(), w as f32 / h as f32, 0.01, reach),
        depth_range: DepthRange::ZeroToOne,
        reversed_z: false,
        origin: Origin::TopLeft,
    };
    let mut r = Renderer::new(&ContextDesc::default())?;
    r.set_scene(scene)?;
    if args.no_indirect && args.bounce_photons.is_some() {
        return Err("--bounce-photons and --no-indirect contradict each other".into());
    }
    let settings = SceneSettings {
        shadows: !args.no_shadows,
        indirect: !args.no_indirect,
        bounce_photons: args.bounce_photons.unwrap_or(SceneSettings::default().bounce_photons),
        ..SceneSettings::default()
    };
    r.set_scene_settings(settings)
        .map_err(|e| format!("--bounce-photons: {e}"))?;
    let mut ids: HashMap<*const Photometry, lumiview::gpu::LuminaireId> = HashMap::new();
    for p in placed {
        let key = Arc::as_ptr(&p.photometry);
        let lum = match ids.get(&key) {
            Some(&id) => id,
            None => {
                let id = match &p.pack {
                    None => r.add_photometry(p.photometry.clone())?,
                    Some(pack) => {
                        let (proxy, bound) = match pack.proxy() {
                            Some(pp) => (Some(pp.triangles.clone()), pp.bound),
                            None => (None, false),
                        };
                        let opts = NearfieldOptions {
                            proxy_is_bound: bound,
                            ..NearfieldOptions::default()
                        };
                        let id = r.add_pack(pack.clone(), proxy, &opts)?;
                        r.set_far_field(id, p.photometry.clone())?;
                        id
                    }
                };
                ids.insert(key, id);
                id
            }
        };
        r.add_instance(lum, p.matrix.as_mat4())?;
    }
    let (exposure, note) = match exposure_arg {
        Some(e) => (e, "as given"),
        None => {
            let median = percentile_luminance(&mut r, &cam, w, h, 0.5)?;
            // display x/(1 + x) = 0.25 at x = 1/3.
            let e = if median > 0.0 && (1.0 / (3.0 * median)).is_finite() {
                (1.0 / (3.0 * median)) as f32
            } else {
                1e-3
            };
            (e, "auto: the view's median luminance shows as 25 % grey")
        }
    };
    let mut t = RenderTarget::new(
        &r.ctx,
        &TargetDesc {
            width: w,
            height: h,
            color: if exr {
                ColorFormat::Rgba32Float
            } else {
                ColorFormat::Rgba8Srgb
            },
            depth: DepthFormat::None,
            exportable: false,
            semaphores: false,
        },
    )?;
    let ro = RenderOptions {
        output: if exr {
            OutputMode::Luminance
        } else {
            OutputMode::ToneMapped
        },
        exposure,
        overlays: Overlays::default(),
        solid_radius_m: 0.5,
    };
    r.render(&mut t, &cam, &ro)?;
    let px = t.read(&r.ctx, Attachment::Color)?;
    write_still(
        &args.output,
        px,
        (w, h),
        if exr {
            Still::Exr
        } else {
            Still::Png {
                transparent: false,
                legend_exposure: args.legend.then_some(exposure),
            }
        },
    )?;
    println!(
        "{}: {w}×{h}, eye ({:.2}, {:.2}, {:.2}) m looking at ({:.2}, {:.2}, {:.2}) m, fov {}°; {} triangles, {} \
         luminaires; direct light{}{}; {} ({})",
        args.output.display(),
        eye.x,
        eye.y,
        eye.z,
        target.x,
        target.y,
        target.z,
        args.fov,
        scene.triangles().len(),
        placed.len(),
        if args.no_shadows {
            " without shadows"
        } else {
            " with shadow maps"
        },
        if args.no_indirect {
            ", no inter-reflection".to_string()
        } else {
            format!(
                " + inter-reflection from {} photons ({} virtual point lights, every bounce)",
                settings.bounce_photons,
                r.scene_stats().vpls
            )
        },
        if exr {
            "luminance in cd/m²".to_string()
        } else {
            format!("exposure {exposure:e} m²/cd ({note})")
        },
        r.ctx.caps.adapter_name,
    );
    Ok(())
}
