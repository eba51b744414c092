//! Render targets: create, destroy, export as opaque fds, read back.

use std::collections::BTreeMap;
use std::os::fd::IntoRawFd;

use super::context::{lumi_context, with_context, ContextInner};
use super::{lumi_status, write_out, FfiError, LUMI_STATUS_BUFFER_TOO_SMALL};
use crate::gpu::{Attachment, ColorFormat, DepthFormat, RenderTarget, TargetDesc};

/// Handle of a render target, owned by its context (0 is never a valid handle).
pub type lumi_target = u64;

/// Colour format: linear cd/m² in RGBA16F (alpha = coverage, premultiplied).
pub const LUMI_COLOR_RGBA16F: u32 = 0;
/// Colour format: linear cd/m² in RGBA32F.
pub const LUMI_COLOR_RGBA32F: u32 = 1;
/// Colour format: Reinhard-tone-mapped display values, RGBA8 sRGB.
pub const LUMI_COLOR_RGBA8_SRGB: u32 = 2;

/// Depth output: none.
pub const LUMI_DEPTH_NONE: u32 = 0;
/// Depth output: R32F colour image with the window depth in the host's convention (GL hosts sample it).
pub const LUMI_DEPTH_R32F: u32 = 1;
/// Depth output: the D32F depth attachment itself (Vulkan hosts).
pub const LUMI_DEPTH_D32F: u32 = 2;

/// Attachment selector: the colour image.
pub const LUMI_ATTACHMENT_COLOR: u32 = 0;
/// Attachment selector: the depth output.
pub const LUMI_ATTACHMENT_DEPTH: u32 = 1;

/// `GL_OPTIMAL_TILING_EXT`, the GL tiling every exported image uses.
pub const LUMI_GL_OPTIMAL_TILING_EXT: u32 = 0x9584;
/// `GL_LAYOUT_SHADER_READ_ONLY_EXT`, the GL layout matching the release layout.
pub const LUMI_GL_LAYOUT_SHADER_READ_ONLY_EXT: u32 = 0x9591;

/// How to create a target. Start from `lumi_target_desc_default()`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct lumi_target_desc {
    /// Width in pixels, 1…16384.
    pub width: u32,
    /// Height in pixels, 1…16384.
    pub height: u32,
    /// One of `LUMI_COLOR_*`.
    pub color_format: u32,
    /// One of `LUMI_DEPTH_*`.
    pub depth_format: u32,
    /// Create exportable images (needs `external_memory` in `lumi_device_caps`); false gives
    /// read-back-only targets.
    pub exportable: bool,
    /// Synchronise with the host on the GPU through two exported semaphores (needs
    /// `external_semaphore` in `lumi_device_caps`; `LUMI_STATUS_UNSUPPORTED` otherwise) and
    /// `exportable` (`LUMI_STATUS_INVALID_ARGUMENT` otherwise). Then `lumi_render` returns
    /// without waiting: see `lumi_target_export_semaphores`.
    pub semaphores: bool,
}

/// Everything a host needs to import one exported image.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct lumi_export {
    /// A new opaque fd owned by the caller: a successful `glImportMemoryFdEXT` or Vulkan import
    /// takes ownership of it; otherwise the caller must `close()` it.
    pub fd: i32,
    /// Allocation size in bytes (the `size` argument of `glImportMemoryFdEXT`, `allocationSize` in Vulkan).
    pub allocation_size: u64,
    /// `VkFormat` of the image.
    pub vk_format: i32,
    /// GL internal format for `glTextureStorageMem2DEXT` (e.g. `GL_RGBA16F`, `GL_R32F`).
    pub gl_internal_format: u32,
    /// `VkImageTiling` (always `VK_IMAGE_TILING_OPTIMAL` = 0).
    pub vk_tiling: i32,
    /// `GL_TEXTURE_TILING_EXT` value (always `GL_OPTIMAL_TILING_EXT`).
    pub gl_tiling: u32,
    /// The allocation is dedicated to the image (`GL_DEDICATED_MEMORY_OBJECT_EXT` = GL_TRUE;
    /// Vulkan hosts chain `VkMemoryDedicatedAllocateInfo`).
    pub dedicated: bool,
    /// `VkImageLayout` the image is in after `lumi_render` returns (released to
    /// `VK_QUEUE_FAMILY_EXTERNAL`): `VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL`.
    pub vk_layout: i32,
    /// The matching GL layout (`GL_LAYOUT_SHADER_READ_ONLY_EXT`).
    pub gl_layout: u32,
    /// `VkImageUsageFlags` the image was created with (a Vulkan host creates its image with the same).
    pub vk_usage: u32,
    /// `memoryTypeIndex` of the exported allocation; a Vulkan host allocates its import with the same
    /// index (VUID-VkMemoryAllocateInfo-allocationSize-01742). GL hosts ignore it.
    pub vk_memory_type_index: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The exporting device's UUID (compare with `GL_DEVICE_UUID_EXT` before importing).
    pub device_uuid: [u8; 16],
    /// The exporting driver's UUID (compare with `GL_DRIVER_UUID_EXT`).
    pub driver_uuid: [u8; 16],
}

/// A default target: 1280 × 720, RGBA32F (half float overflows above 65,504 cd/m², which many
/// luminaires exceed), R32F depth, exportable.
#[no_mangle]
pub extern "C" fn lumi_target_desc_default() -> lumi_target_desc {
    lumi_target_desc {
        width: 1280,
        height: 720,
        color_format: LUMI_COLOR_RGBA32F,
        depth_format: LUMI_DEPTH_R32F,
        exportable: true,
        semaphores: false,
    }
}

fn color_format(v: u32) -> Result<ColorFormat, FfiError> {
    match v {
        LUMI_COLOR_RGBA16F => Ok(ColorFormat::Rgba16Float),
        LUMI_COLOR_RGBA32F => Ok(ColorFormat::Rgba32Float),
        LUMI_COLOR_RGBA8_SRGB => Ok(ColorFormat::Rgba8Srgb),
        v => Err(FfiError::invalid("desc.color_format", format!("unknown value {v}"))),
    }
}

fn depth_format(v: u32) -> Result<DepthFormat, FfiError> {
    match v {
        LUMI_DEPTH_NONE => Ok(DepthFormat::None),
        LUMI_DEPTH_R32F => Ok(DepthFormat::R32Float),
        LUMI_DEPTH_D32F => Ok(DepthFormat::Depth32Float),
        v => Err(FfiError::invalid("desc.depth_format", format!("unknown value {v}"))),
    }
}

pub(crate) fn attachment(v: u32) -> Result<Attachment, FfiError> {
    match v {
        LUMI_ATTACHMENT_COLOR => Ok(Attachment::Color),
        LUMI_ATTACHMENT_DEPTH => Ok(Attachment::Depth),
        v => Err(FfiError::invalid("attachment", format!("unknown value {v}"))),
    }
}

/// The target `t` of a context, given as its tag and target map so that the caller may borrow the
/// renderer beside it; the handle is checked and looked up once.
pub(crate) fn target_in(
    tag: u64,
    targets: &mut BTreeMap<u64, RenderTarget>,
    t: lumi_target,
) -> Result<&mut RenderTarget, FfiError> {
    check_target(tag, t)?;
    targets.get_mut(&t).ok_or_else(|| gone(t))
}

/// The target `t` of a context, read-only ([`target_in`]).
fn target_ref(c: &ContextInner, t: lumi_target) -> Result<&RenderTarget, FfiError> {
    check_target(c.tag, t)?;
    c.targets.get(&t).ok_or_else(|| gone(t))
}

/// Checks that `t` is a target handle of the context tagged `tag` (the map is keyed by the whole
/// handle).
fn check_target(tag: u64, t: lumi_target) -> Result<(), FfiError> {
    super::handle::decode(tag, super::handle::Kind::Target, t, "target").map(|_| ())
}

/// A target handle of this context that names no live target.
fn gone(t: lumi_target) -> FfiError {
    FfiError::invalid("target", format!("no target with handle {t:#x} (destroyed?)"))
}

/// Creates a render target. `out` is written only on success.
///
/// Errors: `LUMI_STATUS_NULL_POINTER` (`desc`, `out`), `LUMI_STATUS_INVALID_ARGUMENT` (size,
/// unknown format, `semaphores` without `exportable`), `LUMI_STATUS_UNSUPPORTED` (exportable
/// without external memory, semaphores without external semaphores, or a format the driver cannot
/// export), `LUMI_STATUS_GPU`, `LUMI_STATUS_OUT_OF_MEMORY`.
///
/// # Safety
/// `ctx` is a live context; `desc` valid; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn lumi_target_create(
    ctx: *mut lumi_context,
    desc: *const lumi_target_desc,
    out: *mut lumi_target,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_target_create", ctx, |c| {
            let Some(d) = desc.as_ref() else {
                return Err(FfiError::null("desc"));
            };
            if out.is_null() {
                return Err(FfiError::null("out"));
            }
            let td = TargetDesc {
                width: d.width,
                height: d.height,
                color: color_format(d.color_format)?,
                depth: depth_format(d.depth_format)?,
                exportable: d.exportable,
                semaphores: d.semaphores,
            };
            let t = RenderTarget::new(&c.renderer.ctx, &td)?;
            let id = super::handle::encode(c.tag, super::handle::Kind::Target, c.next_target);
            c.next_target += 1;
            c.targets.insert(id, t);
            write_out(out, id);
            Ok(())
        })
    }
}

/// Frees a target (waits for the GPU). Handle 0 is ignored; a stale handle is an error. Memory a
/// host imported stays valid until the host releases its import. The target is freed even when
/// the wait reports an error an earlier call left (`LUMI_STATUS_GPU`, `LUMI_STATUS_DEVICE_LOST`),
/// which is then returned.
///
/// # Safety
/// `ctx` is a live context.
#[no_mangle]
pub unsafe extern "C" fn lumi_target_destroy(ctx: *mut lumi_context, target: lumi_target) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_target_destroy", ctx, |c| {
            if target == 0 {
                return Ok(());
            }
            target_ref(c, target)?;
            // The target goes whatever the wait reports (an earlier call's GPU error, a lost
            // device): the handle is stale afterwards either way, and the error is returned.
            let waited = c.renderer.ctx.wait_idle();
            c.targets.remove(&target);
            waited.map_err(FfiError::from)
        })
    }
}

/// Exports one image of a target as a new opaque fd plus what the host needs to import it.
/// Each call returns a new fd (the caller owns it). The memory row 0 is the image row the host's
/// `origin` (in `lumi_camera`) names as first: the top row for `LUMI_ORIGIN_TOP_LEFT`, the bottom
/// row for `LUMI_ORIGIN_BOTTOM_LEFT`. Allowed before the first render; the image holds a frame
/// once a `lumi_render` into the target has returned.
///
/// Errors: `LUMI_STATUS_NULL_POINTER` (`out`), `LUMI_STATUS_INVALID_ARGUMENT` (unknown `which`,
/// `LUMI_ATTACHMENT_DEPTH` of a `LUMI_DEPTH_NONE` target, a stale handle),
/// `LUMI_STATUS_UNSUPPORTED` (a target created with `exportable = false`), `LUMI_STATUS_GPU`.
///
/// # Safety
/// `ctx` is a live context; `out` writable (written only on success).
#[no_mangle]
pub unsafe extern "C" fn lumi_target_export(
    ctx: *mut lumi_context,
    target: lumi_target,
    which: u32,
    out: *mut lumi_export,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_target_export", ctx, |c| {
            if out.is_null() {
                return Err(FfiError::null("out"));
            }
            let which = attachment(which)?;
            let caps = c.renderer.ctx.caps.clone();
            let t = target_ref(c, target)?;
            let gl_internal_format = match which {
                Attachment::Color => t.desc.color.gl_internal_format(),
                Attachment::Depth => t.desc.depth.gl_internal_format(),
            };
            let (fd, info) = t.export(&c.renderer.ctx, which)?;
            write_out(
                out,
                lumi_export {
                    fd: fd.into_raw_fd(),
                    allocation_size: info.allocation_size,
                    vk_format: info.vk_format,
                    gl_internal_format,
                    vk_tiling: info.vk_tiling,
                    gl_tiling: LUMI_GL_OPTIMAL_TILING_EXT,
                    dedicated: info.dedicated,
                    vk_layout: info.vk_layout,
                    gl_layout: LUMI_GL_LAYOUT_SHADER_READ_ONLY_EXT,
                    vk_usage: info.vk_usage,
                    vk_memory_type_index: info.memory_type_index,
                    width: info.width,
                    height: info.height,
                    device_uuid: caps.device_uuid,
                    driver_uuid: caps.driver_uuid,
                },
            );
            Ok(())
        })
    }
}

/// Reads one image of a target back into `buffer` for hosts without interop: rows of
/// `width × bytes-per-pixel` bytes (RGBA16F 8, RGBA32F 16, RGBA8 4, depth 4), memory row 0 first,
/// little-endian. `written` receives the byte count (or, on `LUMI_STATUS_BUFFER_TOO_SMALL`, the size
/// needed). With `buffer` NULL only `written` is written, the size (a size query, allowed before
/// any render).
///
/// Errors: `LUMI_STATUS_NULL_POINTER` (`written`), `LUMI_STATUS_INVALID_ARGUMENT` (unknown
/// `which`, a stale, foreign or wrong-kind handle, `LUMI_ATTACHMENT_DEPTH` of a `LUMI_DEPTH_NONE`
/// target, or no `lumi_render` into the target yet), `LUMI_STATUS_BUFFER_TOO_SMALL`,
/// `LUMI_STATUS_GPU`. On a target with semaphores call it only while the host holds no read in
/// flight (it does not wait on `host_done`).
///
/// # Safety
/// `ctx` is a live context; `buffer` NULL or `buffer_len` writable bytes; `written` writable.
#[no_mangle]
pub unsafe extern "C" fn lumi_target_read_pixels(
    ctx: *mut lumi_context,
    target: lumi_target,
    which: u32,
    buffer: *mut u8,
    buffer_len: usize,
    written: *mut usize,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_target_read_pixels", ctx, |c| {
            if written.is_null() {
                return Err(FfiError::null("written"));
            }
            let which = attachment(which)?;
            let ContextInner {
                renderer, targets, tag, ..
            } = c;
            let t = target_in(*tag, targets, target)?;
            let need = t.desc.width as usize * t.desc.height as usize * t.bytes_per_pixel(which) as usize;
            if which == Attachment::Depth && t.desc.depth == DepthFormat::None {
                return Err(FfiError::invalid("which", "the target has no depth output"));
            }
            if buffer.is_null() {
                write_out(written, need);
                return Ok(());
            }
            if buffer_len < need {
                write_out(written, need);
                return Err(FfiError::new(
                    LUMI_STATUS_BUFFER_TOO_SMALL,
                    format!("buffer_len {buffer_len} < {need} bytes needed"),
                ));
            }
            let data = t.read(&renderer.ctx, which)?;
            std::ptr::copy_nonoverlapping(data.as_ptr(), buffer, data.len());
            write_out(written, data.len());
            Ok(())
        })
    }
}

/// Exports a target's two semaphores (created with `desc.semaphores = true`) as new opaque fds owned
/// by the caller (a successful `glImportSemaphoreFdEXT` / `vkImportSemaphoreFdKHR` takes them).
///
/// Contract per frame: `lumi_render` submits a frame that signals `render_done`; the host waits on
/// `render_done` (GL: `glWaitSemaphoreEXT` with source layout `GL_LAYOUT_SHADER_READ_ONLY_EXT`) before
/// reading, and signals `host_done` (GL: `glSignalSemaphoreEXT`, destination layout
/// `GL_LAYOUT_SHADER_READ_ONLY_EXT`) after its reads, exactly once per frame; every `lumi_render`
/// after the first waits on `host_done` on the GPU. Neither side waits on the CPU.
///
/// # Safety
/// `ctx` is a live context; `render_done_fd` and `host_done_fd` writable (written only on success).
#[no_mangle]
pub unsafe extern "C" fn lumi_target_export_semaphores(
    ctx: *mut lumi_context,
    target: lumi_target,
    render_done_fd: *mut i32,
    host_done_fd: *mut i32,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_target_export_semaphores", ctx, |c| {
            if render_done_fd.is_null() {
                return Err(FfiError::null("render_done_fd"));
            }
            if host_done_fd.is_null() {
                return Err(FfiError::null("host_done_fd"));
            }
            let t = target_ref(c, target)?;
            let (a, b) = t.export_semaphores()?;
            write_out(render_done_fd, a.into_raw_fd());
            write_out(host_done_fd, b.into_raw_fd());
            Ok(())
        })
    }
}
