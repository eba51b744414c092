//! `lumi_context`: the device, its luminaires, instances, targets and scenes.

use std::collections::BTreeMap;
use std::ffi::{c_char, c_void, CString};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use super::{
    boundary, lumi_status, write_out, FfiError, LUMI_ABI_VERSION, LUMI_STATUS_ABI_MISMATCH, LUMI_STATUS_POISONED,
};
use crate::gpu::{ContextDesc, LogLevel, RenderTarget, Renderer};

/// Log callback: `level` 0 = error, 1 = warning, 2 = info; `message` is NUL-terminated UTF-8 valid
/// only during the call. Called on whichever thread logs (including wgpu's), possibly concurrently:
/// it must be thread-safe and must not call back into lumiview.
pub type lumi_log_fn = Option<unsafe extern "C" fn(user: *mut c_void, level: u32, message: *const c_char)>;

/// How to create a context. Start from `lumi_context_desc_default()`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct lumi_context_desc {
    /// Must be `LUMI_ABI_VERSION` of the header the caller compiled against.
    pub abi_version: u32,
    /// Use the physical device whose `deviceUUID` equals `device_uuid` (the host's GPU).
    pub has_device_uuid: bool,
    /// The host's device UUID (`GL_DEVICE_UUID_EXT` or `VkPhysicalDeviceIDProperties::deviceUUID`).
    pub device_uuid: [u8; 16],
    /// Enable the Vulkan validation layer; messages go to `log`.
    pub validation: bool,
    /// Optional log callback (may be NULL).
    pub log: lumi_log_fn,
    /// Passed to `log` unchanged.
    pub log_user: *mut c_void,
}

/// What the context's device can do and who it is.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct lumi_device_caps {
    /// `VkPhysicalDeviceIDProperties::deviceUUID`; a GL host compares it with `GL_DEVICE_UUID_EXT`.
    pub device_uuid: [u8; 16],
    /// `driverUUID`; compare with `GL_DRIVER_UUID_EXT`.
    pub driver_uuid: [u8; 16],
    /// Adapter name, NUL-terminated UTF-8 (truncated to 255 bytes).
    pub adapter_name: [c_char; 256],
    /// Targets can be exported as opaque fds (`VK_KHR_external_memory_fd`).
    pub external_memory: bool,
    /// `VK_KHR_external_semaphore_fd` is available.
    pub external_semaphore: bool,
    /// The device is a software rasteriser (e.g. lavapipe).
    pub is_cpu: bool,
}

/// The state behind a `lumi_context*`.
pub struct ContextInner {
    /// The renderer.
    pub renderer: Renderer,
    /// Targets by handle.
    pub targets: BTreeMap<u64, RenderTarget>,
    /// Serial of the next target.
    pub next_target: u64,
    /// This context's tag, part of every handle it gives out (`ffi::handle`).
    pub tag: u64,
    /// Scenes by handle ([`super::scene`]).
    pub scenes: BTreeMap<u64, super::scene::SceneEntry>,
    /// Serial of the next scene.
    pub next_scene: u64,
    /// The handle of the scene `lumi_render` draws, if any (`lumi_context_set_scene`).
    pub active_scene: Option<u64>,
}

/// An opaque context. Create with `lumi_context_create`, destroy with `lumi_context_destroy`.
/// One thread at a time per context (calls are serialised by an internal lock; do not rely on
/// concurrency); different contexts are independent.
pub struct lumi_context {
    inner: Mutex<ContextInner>,
    poisoned: AtomicBool,
}

/// Send+Sync wrapper of the log callback's user pointer (the caller promised thread safety).
struct UserPtr(*mut c_void);
// SAFETY: the header documents that the log callback and its user pointer must be thread-safe.
unsafe impl Send for UserPtr {}
// SAFETY: as above.
unsafe impl Sync for UserPtr {}

/// Runs `f` on a context: checks NULL and poisoning, locks it, and poisons it on panic.
///
/// # Safety
/// `ctx` is NULL or a pointer returned by `lumi_context_create` and not yet destroyed.
pub(crate) unsafe fn with_context(
    name: &str,
    ctx: *const lumi_context,
    f: impl FnOnce(&mut ContextInner) -> Result<(), FfiError>,
) -> lumi_status {
    // SAFETY: per the caller's contract the pointer is NULL or a live context.
    let Some(c) = (unsafe { ctx.as_ref() }) else {
        return boundary(name, || {}, || Err(FfiError::null("ctx")));
    };
    if c.poisoned.load(Ordering::SeqCst) {
        return boundary(
            name,
            || {},
            || {
                Err(FfiError::new(
                    LUMI_STATUS_POISONED,
                    "the context panicked earlier; destroy it",
                ))
            },
        );
    }
    boundary(
        name,
        || c.poisoned.store(true, Ordering::SeqCst),
        || {
            let mut guard = c
                .inner
                .lock()
                .map_err(|_| FfiError::new(LUMI_STATUS_POISONED, "the context panicked earlier; destroy it"))?;
            f(&mut guard)
        },
    )
}

/// A context descriptor with defaults: `abi_version = LUMI_ABI_VERSION`, no device UUID (the first
/// discrete, integrated, then software Vulkan device), validation off, no log callback.
#[no_mangle]
pub extern "C" fn lumi_context_desc_default() -> lumi_context_desc {
    lumi_context_desc {
        abi_version: LUMI_ABI_VERSION,
        has_device_uuid: false,
        device_uuid: [0; 16],
        validation: false,
        log: None,
        log_user: std::ptr::null_mut(),
    }
}

/// Creates a context: opens a Vulkan device (with external memory where the driver has it) and
/// compiles the render passes.
///
/// - `desc`: may be NULL for the defaults.
/// - `out`: receives the new context (owned by the caller: free it with `lumi_context_destroy`);
///   written only on success.
///
/// Errors: `LUMI_STATUS_ABI_MISMATCH` (desc->abi_version differs), `LUMI_STATUS_NO_DEVICE`,
/// `LUMI_STATUS_UNSUPPORTED` (fewer than 16 storage buffers per shader stage), `LUMI_STATUS_GPU`,
/// `LUMI_STATUS_OUT_OF_MEMORY`, `LUMI_STATUS_NULL_POINTER` (out).
///
/// # Safety
/// `desc` is NULL or points to a valid descriptor; `out` points to writable storage.
#[no_mangle]
pub unsafe extern "C" fn lumi_context_create(
    desc: *const lumi_context_desc,
    out: *mut *mut lumi_context,
) -> lumi_status {
    boundary(
        "lumi_context_create",
        || {},
        || {
            if out.is_null() {
                return Err(FfiError::null("out"));
            }
            // SAFETY: NULL or a valid descriptor per the contract.
            let d = unsafe { desc.as_ref() }
                .copied()
                .unwrap_or_else(|| lumi_context_desc_default());
            if d.abi_version != LUMI_ABI_VERSION {
                return Err(FfiError::new(
                    LUMI_STATUS_ABI_MISMATCH,
                    format!(
                        "the caller was built against ABI {}, this library implements {LUMI_ABI_VERSION}",
                        d.abi_version
                    ),
                ));
            }
            let log = d.log.map(|cb| {
                let user = UserPtr(d.log_user);
                let sink: crate::gpu::LogSink = Arc::new(move |level: LogLevel, msg: &str| {
                    let lvl = match level {
                        LogLevel::Error => 0,
                        LogLevel::Warning => 1,
                        LogLevel::Info => 2,
                    };
                    let text = CString::new(msg.replace('\0', " ")).unwrap_or_default();
                    let u = &user;
                    // SAFETY: the host's callback, called with a NUL-terminated string valid for the call.
                    unsafe { cb(u.0, lvl, text.as_ptr()) };
                });
                sink
            });
            let renderer = Renderer::new(&ContextDesc {
                preferred_device_uuid: d.has_device_uuid.then_some(d.device_uuid),
                validation: d.validation,
                log,
            })?;
            let ctx = Box::new(lumi_context {
                inner: Mutex::new(ContextInner {
                    renderer,
                    targets: BTreeMap::new(),
                    next_target: 1,
                    tag: super::handle::new_context_tag(),
                    scenes: BTreeMap::new(),
                    next_scene: 1,
                    active_scene: None,
                }),
                poisoned: AtomicBool::new(false),
            });
            // SAFETY: checked non-NULL above.
            unsafe { write_out(out, Box::into_raw(ctx)) };
            Ok(())
        },
    )
}

/// Destroys a context and everything it owns (luminaires, instances, targets, scenes). Waits for
/// the GPU (not once a panic has poisoned the context).
/// NULL is ignored. Exported fds already handed out stay valid (the host owns them).
///
/// # Safety
/// `ctx` is NULL or a live context not used by another thread; it is invalid afterwards.
#[no_mangle]
pub unsafe extern "C" fn lumi_context_destroy(ctx: *mut lumi_context) {
    if ctx.is_null() {
        return;
    }
    let _ = boundary(
        "lumi_context_destroy",
        || {},
        || {
            // SAFETY: a pointer from lumi_context_create, destroyed once per the contract.
            let b = unsafe { Box::from_raw(ctx) };
            if let Ok(inner) = b.inner.lock() {
                let _ = inner.renderer.ctx.wait_idle();
            }
            drop(b);
            Ok(())
        },
    );
}

/// Reports what the context's device can do.
///
/// # Safety
/// `ctx` is a live context; `out` points to writable storage (written only on success).
#[no_mangle]
pub unsafe extern "C" fn lumi_context_caps(ctx: *const lumi_context, out: *mut lumi_device_caps) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_context_caps", ctx, |c| {
            if out.is_null() {
                return Err(FfiError::null("out"));
            }
            let caps = &c.renderer.ctx.caps;
            let mut name = [0 as c_char; 256];
            for (d, s) in name
                .iter_mut()
                .zip(caps.adapter_name.bytes().filter(|b| *b != 0).take(255))
            {
                *d = s as c_char;
            }
            write_out(
                out,
                lumi_device_caps {
                    device_uuid: caps.device_uuid,
                    driver_uuid: caps.driver_uuid,
                    adapter_name: name,
                    external_memory: caps.external_memory,
                    external_semaphore: caps.external_semaphore,
                    is_cpu: caps.is_cpu,
                },
            );
            Ok(())
        })
    }
}
