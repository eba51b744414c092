//! `lumiview render`: a still of a luminaire's appearance, rendered on the GPU (Vulkan) exactly as a
//! host would get it: a PNG of the tone-mapped image, or an OpenEXR of luminance in cd/m².

use std::path::PathBuf;

use clap::Args;
use glam::{Mat4, Vec3, Vec4};
use lumiview::gpu::{
    Attachment, ColorFormat, ContextDesc, DepthFormat, DepthRange, HostCamera, Origin, OutputMode, Overlays,
    RenderOptions, RenderTarget, Renderer, TargetDesc,
};
use lumiview::photometry::web::direction;

use super::CliResult;
use crate::LoadArgs;

/// Arguments of `lumiview render`.
#[derive(Args, Debug)]
pub struct RenderArgs {
    /// IES or EULUMDAT file.
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
    let p = std::sync::Arc::new(super::load(&a.file, &a.load)?);
    if p.opening.is_point() {
        eprintln!(
            "lumiview: warning: {} declares no luminous opening: nothing to draw (overlays only)",
            a.file.display()
        );
    }
    let mut r = Renderer::new(&ContextDesc::default())?;
    let lum = r.add_photometry(p.clone())?;
    r.add_instance(lum, Mat4::IDENTITY)?;
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
    let d = direction(c, g);
    let eye = Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32) * dist as f32;
    let up = if !(1.0..=179.0).contains(&g) { Vec3::X } else { Vec3::Z };
    let cam = HostCamera {
        view: look_at(eye, up),
        projection: perspective(a.fov.to_radians(), w as f32 / h as f32, 0.01, 100.0),
        depth_range: DepthRange::ZeroToOne,
        reversed_z: false,
        origin: Origin::TopLeft,
    };
    let l_here = p.luminance(c, g).unwrap_or(0.0);
    let exposure = a
        .exposure
        .unwrap_or(if l_here > 0.0 { (1.0 / l_here) as f32 } else { 1e-3 });
    let ro = RenderOptions {
        output: if exr {
            OutputMode::Luminance
        } else {
            OutputMode::ToneMapped
        },
        exposure,
        overlays: Overlays {
            solid: a.solid,
            housing: a.housing,
        },
        solid_radius_m: 0.5,
    };
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
        "{}: {w}×{h} from C {c}° γ {g}° at {dist} m; L = {l_here:.1} cd/m² at the centre; exposure {exposure:e} m²/cd; {} ({})",
        a.output.display(),
        r.ctx.caps.adapter_name,
        if exr { "luminance, cd/m²" } else { "tone-mapped" }
    );
    Ok(())
}

fn look_at(eye: Vec3, up: Vec3) -> Mat4 {
    let f = (-eye).normalize();
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
