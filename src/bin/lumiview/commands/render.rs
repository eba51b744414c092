//! `lumiview render`: a still of a luminaire's appearance, rendered on the GPU (Vulkan) exactly as a
//! host would get it: a PNG of the tone-mapped image, or an OpenEXR of luminance in cd/m². The input
//! is far-field photometry (IES, EULUMDAT: the luminous opening) or a near-field scan (`.lvpack`, a
//! scan manifest or a TM-25 ray file: the measured appearance, with a selection mode and an optional
//! glTF proxy).

use std::path::PathBuf;

use clap::Args;
use glam::{Mat4, Vec3, Vec4};
use lumiview::gpu::nearfield::{NearfieldOptions, NearfieldSettings};
use lumiview::gpu::{
    Attachment, ColorFormat, ContextDesc, DepthFormat, DepthRange, HostCamera, Origin, OutputMode, Overlays,
    RenderOptions, RenderTarget, Renderer, TargetDesc,
};
use lumiview::nearfield::proxy::load_gltf;
use lumiview::nearfield::select::SelectionMode;
use lumiview::photometry::web::direction;
use lumiview::source::{self, Source, SourceKind, SourceOptions};

use super::CliResult;
use crate::LoadArgs;

/// Arguments of `lumiview render`.
#[derive(Args, Debug)]
pub struct RenderArgs {
    /// IES or EULUMDAT file, or a near-field scan: .lvpack, scan manifest (.json) or TM-25 ray file
    /// (the last two are packed once into the scan cache, see docs/formats.md).
    pub file: PathBuf,
    /// Output: .png (Reinhard tone-mapped, sRGB) or .exr (luminance in cd/m², RGBA32F).
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Eye position as photometric angles and distance: C,GAMMA,DIST (degrees, degrees, metres),
    /// looking at the photometric centre. γ = 0 is straight below (nadir). Default: 30,60,2 for a
    /// photometric file; for a scan, from the direction its brightest camera looks from, so far
    /// that what the cameras saw fills about half the field of view (at least 2 cm).
    #[arg(long = "from", allow_hyphen_values = true, value_name = "C,GAMMA,DIST")]
    pub from: Option<String>,
    /// Eye position in the luminaire frame, metres: EX,EY,EZ, or EX,EY,EZ,TX,TY,TZ to look at the point
    /// T (default: the photometric centre, or a scan's capture centre). Overrides --from.
    #[arg(long, allow_hyphen_values = true, value_name = "EX,EY,EZ[,TX,TY,TZ]")]
    pub camera: Option<String>,
    /// Near-field selection: nearest, idw4 or continuous.
    #[arg(long, default_value = "continuous")]
    pub mode: String,
    /// Draw a scan without any proxy mesh, not even the one its .lvpack stores.
    #[arg(long)]
    pub no_proxy: bool,
    /// Near-field proxy mesh (glTF 2.0, luminaire frame) for parallax-correct reprojection
    /// (default: the one the scan's .lvpack stores, e.g. a ray file's hull of its ray origins).
    #[arg(long, value_name = "FILE.glb")]
    pub proxy: Option<PathBuf>,
    /// GPU budget of a near-field scan in MiB (tiles beyond it are streamed per view).
    #[arg(long, default_value_t = 512)]
    pub budget_mib: u64,
    /// Vertical field of view in degrees (default 30; from a scan's default eye, narrower where
    /// the source is so small that 2 cm away it would fill less than half of 30°).
    #[arg(long)]
    pub fov: Option<f32>,
    /// Image size WxH in pixels.
    #[arg(long, default_value = "640x480")]
    pub size: String,
    /// Exposure in m²/cd for the PNG tone mapping (x = L · exposure, display x / (1 + x), then
    /// sRGB), so stills of different luminaires compare: the default 1e-3 shows 1000 cd/m² as 50 %
    /// grey. `auto` exposes each view for itself (1 / the luminance seen, or a scan's 99th
    /// percentile).
    #[arg(long, value_name = "M2_PER_CD|auto", allow_hyphen_values = true)]
    pub exposure: Option<String>,
    /// Keep the PNG's alpha channel (coverage: transparent where there is no luminaire); the
    /// default is an opaque black background, the luminance of empty space.
    #[arg(long)]
    pub transparent: bool,
    /// Add a luminance scale bar in cd/m² below the PNG (what each grey level means at this
    /// exposure).
    #[arg(long)]
    pub legend: bool,
    /// Draw the photometric-solid wireframe (radius 0.5 m at the maximum intensity; far-field
    /// files only).
    #[arg(long)]
    pub solid: bool,
    /// Draw the housing box (EULUMDAT luminaire dimensions; IES files have none).
    #[arg(long)]
    pub housing: bool,
    #[command(flatten)]
    pub load: LoadArgs,
}

fn parse_from(s: &str) -> Result<(f64, f64, f64), String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--from '{s}': expected C,GAMMA,DIST"))?;
    match v[..] {
        [c, g, d] if c.is_finite() && (0.0..=180.0).contains(&g) && d.is_finite() && d > 0.0 => Ok((c, g, d)),
        _ => Err(format!(
            "--from '{s}': expected C,GAMMA,DIST with γ in 0…180 and DIST > 0"
        )),
    }
}

/// `--camera EX,EY,EZ[,TX,TY,TZ]` (metres): the eye and, if given, the point it looks at.
pub(super) fn parse_camera(s: &str) -> Result<(Vec3, Option<Vec3>), String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|t| t.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--camera '{s}': expected EX,EY,EZ or EX,EY,EZ,TX,TY,TZ in metres"))?;
    if v.iter().any(|x| !x.is_finite()) {
        return Err(format!("--camera '{s}': values must be finite"));
    }
    match v[..] {
        [x, y, z] => Ok((Vec3::new(x, y, z), None)),
        [x, y, z, a, b, c] => Ok((Vec3::new(x, y, z), Some(Vec3::new(a, b, c)))),
        _ => Err(format!("--camera '{s}': expected 3 or 6 numbers")),
    }
}

/// The default exposure of a PNG still, m²/cd: 1000 cd/m² shows as 50 % grey.
const DEFAULT_EXPOSURE: f32 = 1e-3;

/// `--exposure`: a positive finite value in m²/cd, or `auto` (`None`).
fn parse_exposure(s: &str) -> Result<Option<f32>, String> {
    if s.eq_ignore_ascii_case("auto") {
        return Ok(None);
    }
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(Some(v)),
        _ => Err(format!(
            "--exposure `{s}`: expected a positive number in m²/cd (e.g. 1e-3: 1000 cd/m² shows as 50 % grey) or auto"
        )),
    }
}

fn parse_mode(s: &str) -> Result<SelectionMode, String> {
    SelectionMode::from_name(s).ok_or_else(|| {
        let names: Vec<&str> = SelectionMode::ALL.iter().map(|m| m.name()).collect();
        let (last, rest) = names.split_last().unwrap_or((&"", &[]));
        format!("--mode '{s}': expected {} or {last}", rest.join(", "))
    })
}

/// What was loaded: the luminance the PNG's default exposure is based on, and a description.
struct Loaded {
    /// Luminance (cd/m²) that maps to 0.5 by default; `None`: measure it from a first render.
    l_ref: Option<f64>,
    target: Vec3,
    /// The eye when neither --from nor --camera is given (scans), else `None` (30,60,2).
    default_eye: Option<Vec3>,
    /// The field of view with that eye when --fov is not given and 30° would not frame it.
    default_fov: Option<f32>,
    what: String,
}

/// Runs `lumiview render`.
pub fn render(a: &RenderArgs) -> CliResult {
    let (c, g, dist) = parse_from(a.from.as_deref().unwrap_or("30,60,2"))?;
    if a.no_proxy && a.proxy.is_some() {
        return Err("--no-proxy and --proxy contradict each other".into());
    }
    let (w, h) = a
        .size
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)))
        .ok_or_else(|| format!("--size '{}': expected WxH", a.size))?;
    let fov_given = a.fov.unwrap_or(30.0);
    if !(fov_given.is_finite() && (1e-4..179.0).contains(&fov_given)) {
        return Err(format!("--fov {fov_given}: expected 0.0001…179 degrees").into());
    }
    let camera = a.camera.as_deref().map(parse_camera).transpose()?;
    let mode = parse_mode(&a.mode)?;
    let exposure_arg = match &a.exposure {
        Some(e) => parse_exposure(e)?,
        None => Some(DEFAULT_EXPOSURE),
    };
    let ext = a
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let exr = match ext.as_deref() {
        Some("png") => false,
        Some("exr") => true,
        _ => return Err(format!("{}: the output must end in .png or .exr", a.output.display()).into()),
    };
    lumiview::files::ensure_not_input(&a.output, [a.file.as_path()])?;
    if a.legend && w < 160 {
        return Err(format!("--legend needs a still at least 160 px wide (--size {})", a.size).into());
    }
    if exr {
        for (given, name) in [
            (a.transparent, "--transparent"),
            (a.legend, "--legend"),
            (a.exposure.is_some(), "--exposure"),
        ] {
            if given {
                return Err(format!(
                    "{name} applies to .png stills; {} is an OpenEXR of luminance in cd/m² (no tone mapping, alpha = \
                     coverage)",
                    a.output.display()
                )
                .into());
            }
        }
    }
    // Read and check the input before starting the GPU: options that do not apply are errors.
    let kind = source::detect(&a.file)?;
    if kind == SourceKind::Manifest && a.output.exists() {
        // Never write over one of the scan's images (read the manifest only when that could be).
        let m = lumiview::nearfield::manifest::read_manifest(&a.file)?;
        lumiview::files::ensure_not_input(&a.output, m.entries.iter().map(|e| e.file.as_path()))?;
    }
    let photometry = if kind.is_scan() {
        for (given, name) in [
            (a.solid, "--solid"),
            (a.housing, "--housing"),
            (a.load.tilt.is_some(), "--tilt"),
            (a.load.lamp_set.is_some(), "--lamp-set"),
        ] {
            if given {
                return Err(format!(
                    "{name} applies to photometric files (IES, EULUMDAT); {} is a near-field scan",
                    a.file.display()
                )
                .into());
            }
        }
        None
    } else {
        if a.proxy.is_some() || a.no_proxy {
            return Err(format!(
                "--proxy / --no-proxy apply to near-field scans; {} is a photometric file",
                a.file.display()
            )
            .into());
        }
        let p = std::sync::Arc::new(super::load(&a.file, &a.load)?);
        if a.housing && p.luminaire_size_m.is_none() {
            return Err(format!(
                "--housing: {} gives no luminaire (housing) dimensions{}",
                a.file.display(),
                if matches!(p.format, lumiview::photometry::FileFormat::Ies(_)) {
                    " (IES files have none; EULUMDAT files do)"
                } else {
                    " (its luminaire length is 0)"
                }
            )
            .into());
        }
        if p.opening.is_point() {
            eprintln!(
                "lumiview: warning: {} declares no luminous opening: nothing to draw (overlays only)",
                a.file.display()
            );
        }
        Some(p)
    };
    let mut r = Renderer::new(&ContextDesc::default())?;
    let loaded = match photometry {
        None => {
            let mut warnings = Vec::new();
            // A manifest or ray file is packed into the cache on its first use: say so, as it can
            // take a minute (the proxy reconstructed, the light field estimated).
            let first_use = match kind {
                SourceKind::Manifest => Some("reconstructing its proxy from the images"),
                SourceKind::RayFile => Some("estimating its light field from the rays"),
                _ => None,
            };
            if let Some(what) = first_use {
                let dir = lumiview::nearfield::scanfile::default_cache_dir();
                if lumiview::nearfield::scanfile::cache_path(&a.file, &dir).is_ok_and(|p| !p.exists()) {
                    eprintln!(
                        "lumiview: {}: packing into the scan cache {} once ({what}) …",
                        a.file.display(),
                        dir.display()
                    );
                }
            }
            let Source::Scan { pack, cached } = source::open(&a.file, kind, &SourceOptions::default(), &mut warnings)?
            else {
                return Err(format!("{}: opened as photometry, not as a scan", a.file.display()).into());
            };
            for w in &warnings {
                eprintln!("lumiview: warning: {w}");
            }
            let centre = pack.rayset().sphere.centre_m.as_vec3();
            let cameras = pack.image_count();
            // The user's mesh, else the pack's own (a ray file's grown hull bounds the light).
            let (proxy, bound, proxy_what) = if a.no_proxy {
                (None, false, String::new())
            } else if let Some(path) = a.proxy.as_deref() {
                (Some(load_gltf(path)?), false, format!(" with proxy {}", path.display()))
            } else if let Some(p) = pack.proxy() {
                (
                    Some(p.triangles.clone()),
                    p.bound,
                    format!(" with the scan's proxy ({})", p.source),
                )
            } else {
                (None, false, String::new())
            };
            let has_proxy = proxy.is_some();
            // Where the eye goes by default: the direction the brightest camera looks from, far
            // enough that what the cameras saw (the proxy, else their content) fills about half
            // the field of view.
            let reach = pack
                .proxy()
                .map(|p| {
                    let c = pack.rayset().sphere.centre_m;
                    p.triangles
                        .iter()
                        .map(|v| (glam::DVec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2])) - c).length())
                        .fold(0.0, f64::max)
                })
                .unwrap_or_else(|| lumiview::nearfield::select::view::content_radius_m(&pack));
            let half = f64::from(fov_given).to_radians() / 2.0;
            let eye_distance = (2.0 * reach / half.tan()).max(0.02);
            // A source too small to fill half the view from 2 cm gets a narrower view instead.
            let default_fov = (a.fov.is_none() && 2.0 * reach / half.tan() < 0.02)
                .then(|| (2.0 * (2.0 * reach / 0.02).atan()).to_degrees().max(1e-3) as f32);
            let brightest = pack
                .images()
                .iter()
                .enumerate()
                .max_by(|x, y| {
                    let w = |e: &lumiview::nearfield::pack::ImageEntry| f64::from(e.max_cd_m2) * f64::from(e.tiles);
                    w(x.1).total_cmp(&w(y.1))
                })
                .map(|(i, _)| pack.rayset().cameras[i].direction_from(pack.rayset().sphere.centre_m));
            let opts = NearfieldOptions {
                budget_bytes: a.budget_mib.saturating_mul(1 << 20),
                proxy_is_bound: bound,
                ..NearfieldOptions::default()
            };
            let lum = r.add_pack(std::sync::Arc::new(pack), proxy, &opts)?;
            let inst = r.add_instance(lum, Mat4::IDENTITY)?;
            r.set_nearfield_settings(inst, NearfieldSettings { mode, proxy: has_proxy })?;
            Loaded {
                l_ref: None,
                target: centre,
                default_eye: brightest.map(|d| centre + d.as_vec3() * eye_distance as f32),
                default_fov,
                what: format!(
                    "near-field scan, {cameras} cameras, {} selection{}{}",
                    a.mode,
                    if has_proxy { proxy_what.as_str() } else { ", no proxy" },
                    cached.map_or(String::new(), |p| format!(" (packed into {})", p.display()))
                ),
            }
        }
        Some(p) => {
            let lum = r.add_photometry(p.clone())?;
            r.add_instance(lum, Mat4::IDENTITY)?;
            let l_here = p.luminance(c, g).unwrap_or(0.0);
            Loaded {
                l_ref: Some(l_here),
                target: Vec3::ZERO,
                default_eye: None,
                default_fov: None,
                what: format!("far-field, L = {l_here:.1} cd/m² at the centre"),
            }
        }
    };
    let color = if exr {
        ColorFormat::Rgba32Float
    } else {
        ColorFormat::Rgba8Srgb
    };
    let mut t = RenderTarget::new(
        &r.ctx,
        &TargetDesc {
            width: w,
            height: h,
            color,
            depth: DepthFormat::None,
            exportable: false,
            semaphores: false,
        },
    )?;
    let mut fov = fov_given;
    let (eye, target) = match (camera, loaded.default_eye) {
        (Some((e, t)), _) => (e, t.unwrap_or(loaded.target)),
        (None, Some(e)) if a.from.is_none() => {
            fov = loaded.default_fov.unwrap_or(fov);
            (e, loaded.target)
        }
        (None, _) => {
            let d = direction(c, g);
            (
                loaded.target + Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32) * dist as f32,
                loaded.target,
            )
        }
    };
    let fwd = target - eye;
    if fwd.length() < 1e-6 {
        return Err("--camera: the eye and the point it looks at coincide".into());
    }
    let up = if fwd.normalize().cross(Vec3::Z).length() < 0.02 {
        Vec3::X
    } else {
        Vec3::Z
    };
    let cam = HostCamera {
        view: look_at(eye, target, up),
        projection: perspective(
            fov.to_radians(),
            w as f32 / h as f32,
            (0.1 * fwd.length()).min(0.01),
            100.0,
        ),
        depth_range: DepthRange::ZeroToOne,
        reversed_z: false,
        origin: Origin::TopLeft,
    };
    let mut ro = RenderOptions {
        output: if exr {
            OutputMode::Luminance
        } else {
            OutputMode::ToneMapped
        },
        exposure: 1.0,
        overlays: Overlays {
            solid: a.solid,
            housing: a.housing,
        },
        solid_radius_m: 0.5,
    };
    let (exposure, exposure_note) = match exposure_arg {
        Some(e) => (
            e,
            if a.exposure.is_none() {
                "default: 1000 cd/m² shows as 50 % grey"
            } else {
                "as given"
            },
        ),
        None => {
            let l_ref = match loaded.l_ref {
                Some(l) => l,
                // A scan: the 99th percentile of the luminance in view, from a first render.
                None => percentile_luminance(&mut r, &cam, w, h, 0.99)?,
            };
            let e = if l_ref > 0.0 && (1.0 / l_ref).is_finite() && (1.0 / l_ref) < f64::from(f32::MAX) {
                (1.0 / l_ref) as f32
            } else {
                1e-3
            };
            (e, "auto: this view's luminance shows as 50 % grey")
        }
    };
    ro.exposure = exposure;
    r.render(&mut t, &cam, &ro)?;
    let px = t.read(&r.ctx, Attachment::Color)?;
    write_still(
        &a.output,
        px,
        (w, h),
        if exr {
            Still::Exr
        } else {
            Still::Png {
                transparent: a.transparent,
                legend_exposure: a.legend.then_some(exposure),
            }
        },
    )?;
    println!(
        "{}: {w}×{h}, eye ({:.3}, {:.3}, {:.3}) m looking at ({:.3}, {:.3}, {:.3}) m, fov {fov}°; {}; {}; {} ({})",
        a.output.display(),
        eye.x,
        eye.y,
        eye.z,
        target.x,
        target.y,
        target.z,
        loaded.what,
        if exr {
            "no exposure (luminance file)".to_string()
        } else {
            format!("exposure {exposure:e} m²/cd ({exposure_note})")
        },
        r.ctx.caps.adapter_name,
        if exr {
            "luminance, cd/m²"
        } else if a.transparent {
            "tone-mapped, alpha = coverage"
        } else {
            "tone-mapped on black"
        }
    );
    Ok(())
}

/// What a still is written as.
pub(super) enum Still {
    /// OpenEXR of the RGBA32F target (luminance in cd/m², alpha = coverage).
    Exr,
    /// PNG of the RGBA8 sRGB target: opaque on black unless `transparent`; with a luminance scale
    /// bar below at `legend_exposure` (m²/cd).
    Png {
        transparent: bool,
        legend_exposure: Option<f32>,
    },
}

/// Writes the target's pixels `px` (`w` × `h`, rows from the top) to `path` as `kind`, under a
/// temporary name renamed into place: a failed or interrupted render keeps the previous still.
pub(super) fn write_still(path: &std::path::Path, px: Vec<u8>, (w, h): (u32, u32), kind: Still) -> CliResult {
    let cannot = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    let (mut tmp, _) = lumiview::files::TempOutput::create(path).map_err(|e| cannot(&e))?;
    match kind {
        Still::Exr => {
            let f: Vec<f32> = px
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect();
            exr::prelude::write_rgba_file(tmp.path(), w as usize, h as usize, |x, y| {
                let i = (y * w as usize + x) * 4;
                (f[i], f[i + 1], f[i + 2], f[i + 3])
            })
            .map_err(|e| cannot(&e))?;
        }
        Still::Png {
            transparent,
            legend_exposure,
        } => {
            let mut px = px;
            if !transparent {
                // The colour is premultiplied by coverage: over black it stays as it is.
                for p in px.chunks_exact_mut(4) {
                    p[3] = 255;
                }
            }
            let (px, h_out) = match legend_exposure {
                Some(exposure) => {
                    let legend = luminance_legend(w, exposure, transparent)?;
                    let lh = legend.len() as u32 / (4 * w);
                    ([px, legend].concat(), h + lh)
                }
                None => (px, h),
            };
            let file = tmp
                .take_file()
                .ok_or_else(|| cannot(&"the temporary file is not open"))?;
            let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h_out);
            enc.set_color(png::ColorType::Rgba);
            enc.set_depth(png::BitDepth::Eight);
            let mut wr = enc.write_header().map_err(|e| cannot(&e))?;
            wr.write_image_data(&px).map_err(|e| cannot(&e))?;
            wr.finish().map_err(|e| cannot(&e))?;
        }
    }
    tmp.commit().map_err(|e| cannot(&e))?;
    Ok(())
}

/// The scale bar under a `--legend` still: luminance in cd/m² from where the tone map leaves
/// black (display 2 %) to where it saturates (98 %), in the still's own colours, as RGBA rows
/// `width` wide.
fn luminance_legend(width: u32, exposure: f32, transparent: bool) -> Result<Vec<u8>, Box<dyn std::error::Error>> {
    use lumiview::gpu::farfield::tone_map;
    use lumiview::photometry::plot::legend::ScaleBar;
    let e = f64::from(exposure);
    let srgb8 = lumiview::scene::texture::linear_to_srgb8;
    let colour = |l: f64| {
        let g = srgb8(tone_map(l, e));
        [g, g, g]
    };
    // display d = x / (1 + x): d = 0.02 at x = 0.0204, d = 0.98 at x = 49.
    let bar = ScaleBar {
        width_px: width.max(160),
        min: 0.0204 / e,
        max: 49.0 / e,
        // Short enough for a 360 px still (the exposure is 1 / the 50 % grey luminance).
        caption: format!(
            "luminance in cd/m² (50 % grey at {:.2e}{})",
            1.0 / e,
            if transparent { "" } else { "; black: no light" }
        ),
        colour_of: &colour,
    };
    let pm = bar.to_pixmap()?;
    if pm.width() != width {
        return Err(format!("--legend needs a still at least 160 px wide (this one is {width} px)").into());
    }
    Ok(pm.data().to_vec())
}

/// The `q` quantile of the luminance (cd/m²) over the covered pixels of a render from `cam`.
pub(super) fn percentile_luminance(
    r: &mut Renderer,
    cam: &HostCamera,
    w: u32,
    h: u32,
    q: f64,
) -> Result<f64, Box<dyn std::error::Error>> {
    let mut t = RenderTarget::new(&r.ctx, &TargetDesc::luminance(w, h))?;
    r.render(&mut t, cam, &RenderOptions::default())?;
    let mut l: Vec<f32> = t
        .read_luminance(&r.ctx)?
        .into_iter()
        .filter(|v| *v > 0.0 && v.is_finite())
        .collect();
    if l.is_empty() {
        return Ok(0.0);
    }
    l.sort_by(f32::total_cmp);
    let k = ((q * l.len() as f64) as usize).min(l.len() - 1);
    Ok(f64::from(l[k]))
}

pub(super) fn look_at(eye: Vec3, target: Vec3, up: Vec3) -> Mat4 {
    let f = (target - eye).normalize();
    let s = f.cross(up).normalize();
    let u = s.cross(f);
    Mat4::from_cols(
        Vec4::new(s.x, u.x, -f.x, 0.0),
        Vec4::new(s.y, u.y, -f.y, 0.0),
        Vec4::new(s.z, u.z, -f.z, 0.0),
        Vec4::new(-s.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
    )
}

/// A right-handed perspective projection with clip depth 0…1.
pub(super) fn perspective(fovy: f32, aspect: f32, near: f32, far: f32) -> Mat4 {
    let f = 1.0 / (fovy / 2.0).tan();
    Mat4::from_cols(
        Vec4::new(f / aspect, 0.0, 0.0, 0.0),
        Vec4::new(0.0, f, 0.0, 0.0),
        Vec4::new(0.0, 0.0, far / (near - far), -1.0),
        Vec4::new(0.0, 0.0, near * far / (near - far), 0.0),
    )
}
