//! Images of a view: the GPU's render of every instance of a [`Renderer`], pinhole ([`render_view`])
//! and orthographic (the intensity Î(ω) = Σ L · p², [`ortho_intensity`]), and the exact ray-caster's
//! orthographic reference ([`reference_ortho_intensity`]). Render targets are kept by size and reused
//! (at most 8).

use glam::DVec3;

use super::views::View;
use super::EvalError;
use crate::gpu::{GpuError, HostCamera, RenderOptions, RenderTarget, Renderer, TargetDesc};
use crate::nearfield::synth::{render_ortho, Luminaire, OrthoView};

/// Renders luminance (cd/m²) of every instance in `r` from a pinhole view.
pub fn render_view(r: &mut Renderer, targets: &mut Vec<RenderTarget>, view: &View) -> Result<Vec<f32>, GpuError> {
    let k = &view.intrinsics;
    let near = 0.01f32;
    let far = (view.camera.position_m.length() + 3.0) as f32;
    let cam = HostCamera::from_pinhole(&view.camera, k, near, far);
    render_with(r, targets, &cam, k.width, k.height)
}

fn render_with(
    r: &mut Renderer,
    targets: &mut Vec<RenderTarget>,
    cam: &HostCamera,
    w: u32,
    h: u32,
) -> Result<Vec<f32>, GpuError> {
    let pos = match targets.iter().position(|t| t.desc.width == w && t.desc.height == h) {
        Some(p) => p,
        None => {
            targets.push(RenderTarget::new(&r.ctx, &TargetDesc::luminance(w, h))?);
            if targets.len() > 8 {
                targets.remove(0);
            }
            targets.len() - 1
        }
    };
    let t = &mut targets[pos];
    r.render(t, cam, &RenderOptions::default())?;
    t.read_luminance(&r.ctx)
}

/// The ray-caster's Σ T · p² over the pixels of [`ortho_intensity`]'s view (one ray through each pixel
/// centre, as the GPU rasterises them).
pub(crate) fn reference_ortho_intensity(
    lum: &dyn Luminaire,
    w: DVec3,
    centre: DVec3,
    rb: f64,
    px: u32,
) -> Result<f64, EvalError> {
    let size = px.max(8);
    let view = OrthoView {
        direction: w,
        centre_m: centre,
        pixel_m: 2.0 * rb / f64::from(size - 2),
        width: size,
        height: size,
    };
    let pixel = view.pixel_m;
    let img = render_ortho(lum, &view, 1)?;
    Ok(img.data.iter().map(|v| f64::from(*v)).sum::<f64>() * pixel * pixel)
}

/// Î(ω) = Σ L · p² over an orthographic render along −ω framing a sphere of radius `rb` with `px`
/// pixels a side (1 pixel of margin each side).
pub(crate) fn ortho_intensity(
    r: &mut Renderer,
    targets: &mut Vec<RenderTarget>,
    w: DVec3,
    centre: DVec3,
    rb: f64,
    px: u32,
) -> Result<f64, EvalError> {
    let size = px.max(8);
    let pixel = 2.0 * rb / f64::from(size - 2);
    let cam = HostCamera::from_ortho(w, centre, pixel, size, size, rb + 0.05);
    let img = render_with(r, targets, &cam, size, size)?;
    Ok(img.iter().map(|v| f64::from(*v)).sum::<f64>() * pixel * pixel)
}
