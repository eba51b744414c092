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
use lumiview::nearfield::scanfile::{detect, open_scan_of_kind};
use lumiview::nearfield::select::SelectionMode;
use lumiview::photometry::web::direction;

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
    /// looking at the photometric centre. γ = 0 is straight below (nadir).
    #[arg(
        long = "from",
        default_value = "30,60,2",
        allow_hyphen_values = true,
        value_name = "C,GAMMA,DIST"
    )]
    pub from: String,
    /// Eye position in the luminaire frame, metres: EX,EY,EZ, or EX,EY,EZ,TX,TY,TZ to look at the point
    /// T (default: the photometric centre, or a scan's capture centre). Overrides --from.
    #[arg(long, allow_hyphen_values = true, value_name = "EX,EY,EZ[,TX,TY,TZ]")]
    pub camera: Option<String>,
    /// Near-field selection: nearest, idw4 or continuous.
    #[arg(long, default_value = "continuous")]
    pub mode: String,
    /// Near-field proxy mesh (glTF 2.0, luminaire frame) for parallax-correct reprojection.
    #[arg(long, value_name = "FILE.glb")]
    pub proxy: Option<PathBuf>,
    /// GPU budget of a near-field scan in MiB (tiles beyond it are streamed per view).
    #[arg(long, default_value_t = 512)]
    pub budget_mib: u64,
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = 30.0)]
    pub fov: f32,
    /// Image size WxH in pixels.
    #[arg(long, default_value = "640x480")]
    pub size: String,
    /// Exposure in m²/cd for the PNG tone mapping (x = L · exposure, x / (1 + x)); default: 1 / the
    /// largest luminance seen from this direction, so the opening maps to about 0.5.
    #[arg(long)]
    pub exposure: Option<f32>,
    /// Draw the photometric-solid wireframe (radius 0.5 m at the maximum intensity).
    #[arg(long)]
    pub solid: bool,
    /// Draw the housing box (EULUMDAT luminaire dimensions).
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

fn parse_camera(s: &str) -> Result<(Vec3, Option<Vec3>), String> {
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

fn parse_mode(s: &str) -> Result<SelectionMode, String> {
    match s {
        "nearest" => Ok(SelectionMode::Nearest),
        "idw4" => Ok(SelectionMode::Idw4),
        "continuous" => Ok(SelectionMode::Continuous),
        _ => Err(format!("--mode '{s}': expected nearest, idw4 or continuous")),
    }
}

/// What was loaded: the luminance the PNG's default exposure is based on, and a description.
struct Loaded {
    /// Luminance (cd/m²) that maps to 0.5 by default; `None`: measure it from a first render.
    l_ref: Option<f64>,
    target: Vec3,
    what: String,
}

/// Runs `lumiview render`.
pub fn render(a: &RenderArgs) -> CliResult {
    let (c, g, dist) = parse_from(&a.from)?;
    let (w, h) = a
        .size
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)))
        .ok_or_else(|| format!("--size '{}': expected WxH", a.size))?;
    if !(a.fov.is_finite() && a.fov > 0.1 && a.fov < 179.0) {
        return Err(format!("--fov {}: expected 0.1…179 degrees", a.fov).into());
    }
    let camera = a.camera.as_deref().map(parse_camera).transpose()?;
    let mode = parse_mode(&a.mode)?;
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
    let mut r = Renderer::new(&ContextDesc::default())?;
    let loaded = match detect(&a.file)? {
        Some(kind) => {
            let (pack, cached) = open_scan_of_kind(&a.file, kind, None)?;
            let centre = pack.rayset().sphere.centre_m.as_vec3();
            let cameras = pack.image_count();
            let proxy = a.proxy.as_deref().map(load_gltf).transpose()?;
            let has_proxy = proxy.is_some();
            let opts = NearfieldOptions {
                budget_bytes: a.budget_mib.saturating_mul(1 << 20),
                ..NearfieldOptions::default()
            };
            let lum = r.add_pack(std::sync::Arc::new(pack), proxy, &opts)?;
            let inst = r.add_instance(lum, Mat4::IDENTITY)?;
            r.set_nearfield_settings(inst, NearfieldSettings { mode, proxy: has_proxy })?;
            Loaded {
                l_ref: None,
                target: centre,
                what: format!(
                    "near-field scan, {cameras} cameras, {} selection{}{}",
                    a.mode,
                    if has_proxy { " with proxy" } else { ", no proxy" },
                    cached.map_or(String::new(), |p| format!(" (packed into {})", p.display()))
                ),
            }
        }
        None => {
            if a.proxy.is_some() {
                return Err("--proxy applies to near-field scans only".into());
            }
            let p = std::sync::Arc::new(super::load(&a.file, &a.load)?);
            if p.opening.is_point() {
                eprintln!(
                    "lumiview: warning: {} declares no luminous opening: nothing to draw (overlays only)",
                    a.file.display()
                );
            }
            let lum = r.add_photometry(p.clone())?;
            r.add_instance(lum, Mat4::IDENTITY)?;
            let l_here = p.luminance(c, g).unwrap_or(0.0);
            Loaded {
                l_ref: Some(l_here),
                target: Vec3::ZERO,
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
    let (eye, target) = match camera {
        Some((e, t)) => (e, t.unwrap_or(loaded.target)),
        None => {
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
        projection: perspective(a.fov.to_radians(), w as f32 / h as f32, 0.01, 100.0),
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
    let l_ref = match (a.exposure, loaded.l_ref) {
        (Some(_), _) => None,
        (None, Some(l)) => Some(l),
        // A scan: the 99th percentile of the luminance in view, from a first render in cd/m².
        (None, None) if !exr => Some(percentile_luminance(&mut r, &cam, w, h, 0.99)?),
        (None, None) => None,
    };
    let exposure = a.exposure.unwrap_or(match l_ref {
        Some(l) if l > 0.0 => (1.0 / l) as f32,
        _ => 1e-3,
    });
    ro.exposure = exposure;
    r.render(&mut t, &cam, &ro)?;
    let px = t.read(&r.ctx, Attachment::Color)?;
    if exr {
        let f: Vec<f32> = px
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        exr::prelude::write_rgba_file(&a.output, w as usize, h as usize, |x, y| {
            let i = (y * w as usize + x) * 4;
            (f[i], f[i + 1], f[i + 2], f[i + 3])
        })
        .map_err(|e| format!("{}: {e}", a.output.display()))?;
    } else {
        let file = std::fs::File::create(&a.output).map_err(|e| format!("{}: {e}", a.output.display()))?;
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        let mut wr = enc.write_header().map_err(|e| format!("{}: {e}", a.output.display()))?;
        wr.write_image_data(&px)
            .map_err(|e| format!("{}: {e}", a.output.display()))?;
    }
    println!(
        "{}: {w}×{h}, eye ({:.3}, {:.3}, {:.3}) m looking at ({:.3}, {:.3}, {:.3}) m; {}; exposure {exposure:e} m²/cd; {} ({})",
        a.output.display(),
        eye.x,
        eye.y,
        eye.z,
        target.x,
        target.y,
        target.z,
        loaded.what,
        r.ctx.caps.adapter_name,
        if exr { "luminance, cd/m²" } else { "tone-mapped" }
    );
    Ok(())
}

/// The `q` quantile of the luminance (cd/m²) over the covered pixels of a render from `cam`.
fn percentile_luminance(
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

fn look_at(eye: Vec3, target: Vec3, up: Vec3) -> Mat4 {
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
fn perspective(fovy: f32, aspect: f32, near: f32, far: f32) -> Mat4 {
    let f = 1.0 / (fovy / 2.0).tan();
    Mat4::from_cols(
        Vec4::new(f / aspect, 0.0, 0.0, 0.0),
        Vec4::new(0.0, f, 0.0, 0.0),
        Vec4::new(0.0, 0.0, far / (near - far), -1.0),
        Vec4::new(0.0, 0.0, near * far / (near - far), 0.0),
    )
}
