//! Rendering a frame: the host's camera and render options.

use super::context::{lumi_context, with_context, ContextInner};
use super::target::target_in;
use super::{lumi_status, FfiError};
use crate::gpu::{Arg, DepthRange, GpuError, HostCamera, Origin, OutputMode, Overlays, RenderOptions};

/// Clip depth range: OpenGL's −1…1.
pub const LUMI_DEPTH_RANGE_NEG_ONE_TO_ONE: u32 = 0;
/// Clip depth range: 0…1 (Vulkan, D3D, `glClipControl(.., GL_ZERO_TO_ONE)`).
pub const LUMI_DEPTH_RANGE_ZERO_TO_ONE: u32 = 1;

/// Framebuffer origin: memory row 0 is the top row (Vulkan, D3D).
pub const LUMI_ORIGIN_TOP_LEFT: u32 = 0;
/// Framebuffer origin: memory row 0 is the bottom row (OpenGL).
pub const LUMI_ORIGIN_BOTTOM_LEFT: u32 = 1;

/// Output: linear luminance in cd/m² (float targets).
pub const LUMI_OUTPUT_LUMINANCE: u32 = 0;
/// Output: Reinhard with exposure, x = L · exposure, display value x / (1 + x).
pub const LUMI_OUTPUT_TONE_MAPPED: u32 = 1;

/// Overlay bit: photometric-solid wireframe (orange).
pub const LUMI_OVERLAY_SOLID: u32 = 1;
/// Overlay bit: housing box from the file's luminaire dimensions (blue), where it has them.
pub const LUMI_OVERLAY_HOUSING: u32 = 2;

/// The host's camera for one frame. Conventions, with a worked GL and Vulkan projection:
/// docs/ffi-conventions.md, "The camera".
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct lumi_camera {
    /// World → eye, column-major (glm / GL layout).
    pub view: [f32; 16],
    /// Eye → clip, column-major; clip +y is image up for either `origin` (GL's convention). A
    /// Vulkan projection with y flipped (`proj[1][1] *= -1`) is un-flipped, or passed with
    /// `LUMI_ORIGIN_BOTTOM_LEFT`, whose flip undoes it.
    pub projection: [f32; 16],
    /// `LUMI_DEPTH_RANGE_*`: the host's clip depth range; depth is written the way the host's own
    /// depth buffer would hold it (GL: window depth (z_ndc + 1)/2).
    pub depth_range: u32,
    /// The projection maps near to 1 and far to 0: depth test GREATER, depth cleared to 0 (not
    /// checked against the projection).
    pub reversed_z: bool,
    /// `LUMI_ORIGIN_*`: which image row is memory row 0 (the top for `TOP_LEFT`, the bottom for
    /// `BOTTOM_LEFT`); it mirrors the rows and changes nothing else.
    pub origin: u32,
}

/// Per-frame options.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct lumi_render_options {
    /// `LUMI_OUTPUT_*`. RGBA8 sRGB targets need `LUMI_OUTPUT_TONE_MAPPED`.
    pub output: u32,
    /// Exposure in m²/cd for tone mapping (> 0).
    pub exposure: f32,
    /// `LUMI_OVERLAY_*` bits.
    pub overlays: u32,
    /// Radius of the photometric solid at the maximum intensity, metres (> 0).
    pub solid_radius_m: f32,
}

/// A camera with identity matrices, GL depth range, no reversed Z, bottom-left origin (a GL host).
#[no_mangle]
pub extern "C" fn lumi_camera_default() -> lumi_camera {
    let id = glam::Mat4::IDENTITY.to_cols_array();
    lumi_camera {
        view: id,
        projection: id,
        depth_range: LUMI_DEPTH_RANGE_NEG_ONE_TO_ONE,
        reversed_z: false,
        origin: LUMI_ORIGIN_BOTTOM_LEFT,
    }
}

/// Default options: luminance output, exposure 0.001 m²/cd, no overlays, solid radius 0.5 m.
#[no_mangle]
pub extern "C" fn lumi_render_options_default() -> lumi_render_options {
    lumi_render_options {
        output: LUMI_OUTPUT_LUMINANCE,
        exposure: 1e-3,
        overlays: 0,
        solid_radius_m: 0.5,
    }
}

/// The host's camera: its enums checked here, its matrices once, by the frame (`gpu::FrameView`).
fn camera(c: &lumi_camera) -> Result<HostCamera, FfiError> {
    Ok(HostCamera {
        view: glam::Mat4::from_cols_array(&c.view),
        projection: glam::Mat4::from_cols_array(&c.projection),
        depth_range: match c.depth_range {
            LUMI_DEPTH_RANGE_NEG_ONE_TO_ONE => DepthRange::NegOneToOne,
            LUMI_DEPTH_RANGE_ZERO_TO_ONE => DepthRange::ZeroToOne,
            v => return Err(FfiError::invalid("camera.depth_range", format!("unknown value {v}"))),
        },
        reversed_z: c.reversed_z,
        origin: match c.origin {
            LUMI_ORIGIN_TOP_LEFT => Origin::TopLeft,
            LUMI_ORIGIN_BOTTOM_LEFT => Origin::BottomLeft,
            v => return Err(FfiError::invalid("camera.origin", format!("unknown value {v}"))),
        },
    })
}

/// A render error, naming the camera's and the options' fields as the C API spells them.
fn render_error(e: GpuError) -> FfiError {
    match e {
        GpuError::InvalidArgument { arg, message } => {
            let field = match arg {
                Arg::View => "camera.view",
                Arg::Projection => "camera.projection",
                Arg::Exposure => "options.exposure",
                Arg::SolidRadius => "options.solid_radius_m",
                Arg::Output => "options.output",
                other => other.name(),
            };
            FfiError::invalid(field, message)
        }
        other => other.into(),
    }
}

fn options(o: &lumi_render_options) -> Result<RenderOptions, FfiError> {
    if o.overlays & !(LUMI_OVERLAY_SOLID | LUMI_OVERLAY_HOUSING) != 0 {
        return Err(FfiError::invalid(
            "options.overlays",
            format!("unknown bits in {:#x}", o.overlays),
        ));
    }
    Ok(RenderOptions {
        output: match o.output {
            LUMI_OUTPUT_LUMINANCE => OutputMode::Luminance,
            LUMI_OUTPUT_TONE_MAPPED => OutputMode::ToneMapped,
            v => return Err(FfiError::invalid("options.output", format!("unknown value {v}"))),
        },
        exposure: o.exposure,
        overlays: Overlays {
            solid: o.overlays & LUMI_OVERLAY_SOLID != 0,
            housing: o.overlays & LUMI_OVERLAY_HOUSING != 0,
        },
        solid_radius_m: o.solid_radius_m,
    })
}

/// With a scene drawn and its inter-reflection on, every instance must be placed by a
/// rotation and a translation (photons are traced from it): the first that is not is
/// `INVALID_ARGUMENT` naming `instance` and its handle.
fn rigid_for_photons(renderer: &crate::gpu::Renderer, tag: u64) -> Result<(), FfiError> {
    if !renderer.has_scene() || !renderer.scene_settings().indirect {
        return Ok(());
    }
    for (id, lum, model) in renderer.instances() {
        let placed = crate::scene::SceneLuminaire {
            photometry: renderer.light_of(lum)?,
            scene_from_luminaire: model.as_dmat4(),
        };
        if let Err(why) = placed.check_placement() {
            let handle = super::handle::encode(tag, super::handle::Kind::Instance, id.0);
            return Err(FfiError::invalid(
                "instance",
                format!(
                    "{handle:#x}: {why} (the scene's inter-reflection traces photons from it; set \
                     lumi_scene_settings.indirect = false to draw it)"
                ),
            ));
        }
    }
    Ok(())
}

/// Renders every instance of the context into `target`, seen by `camera`.
///
/// Synchronisation (docs/interop.md): the call returns after the GPU finished; the exported images
/// are then released to `VK_QUEUE_FAMILY_EXTERNAL` in `VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL`.
/// The host must finish its reads of this target (glFinish or a fence) before the next
/// `lumi_render` into it; two targets used in turn avoid the stall.
///
/// - `camera`: required; its matrices finite and invertible.
/// - `options`: NULL for the defaults (`lumi_render_options_default()`: luminance output, which an
///   RGBA8 sRGB target refuses).
///
/// Errors: `LUMI_STATUS_NULL_POINTER` (`camera`), `LUMI_STATUS_INVALID_ARGUMENT` (a NaN, infinite
/// or singular matrix, an unknown enum value or overlay bit, an exposure or solid radius not > 0,
/// an output the target's format cannot hold, a stale handle, a near-field view needing more than
/// the luminaire's budget, with a scene's inter-reflection on an `instance` not placed by a rotation
/// and a translation), `LUMI_STATUS_GPU`, `LUMI_STATUS_DEVICE_LOST`,
/// `LUMI_STATUS_OUT_OF_MEMORY`; per case: docs/ffi-conventions.md, "Statuses by function".
///
/// # Safety
/// `ctx` is a live context; `camera` valid; `options` NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn lumi_render(
    ctx: *mut lumi_context,
    target: super::target::lumi_target,
    camera: *const lumi_camera,
    options: *const lumi_render_options,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_render", ctx, |c| {
            let Some(cam) = camera.as_ref() else {
                return Err(FfiError::null("camera"));
            };
            let cam = self::camera(cam)?;
            let o = match options.as_ref() {
                Some(o) => self::options(o)?,
                None => self::options(&lumi_render_options_default())?,
            };
            let ContextInner {
                renderer, targets, tag, ..
            } = c;
            rigid_for_photons(renderer, *tag)?;
            let t = target_in(*tag, targets, target)?;
            renderer.render(t, &cam, &o).map_err(render_error)
        })
    }
}
