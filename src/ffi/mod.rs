//! The C ABI (the only `extern "C"` code). Conventions (docs/ffi-conventions.md):
//!
//! - Every fallible function returns a `lumi_status` (numbers fixed forever, never reused).
//! - Out-parameters are written only on success.
//! - The last error's text is thread-local and *copied* into a caller buffer with
//!   [`lumi_last_error`]; it is never returned as a borrowed pointer.
//! - Every exported body runs inside `boundary` (catch_unwind): a panic becomes
//!   `LUMI_STATUS_PANIC` and poisons the context it happened in.
//! - Enums arrive as `uint32_t` and are converted with `TryFrom`; an unknown value is
//!   `LUMI_STATUS_INVALID_ARGUMENT`.
//! - Luminaires, instances, targets and scenes are `uint64_t` handles owned by their context: a
//!   stale or foreign handle is an error, never undefined behaviour; destroying the context frees
//!   them all.
//!
//! One file per C object: [`context`] (contexts, devices, logging), [`luminaire`] (loading and
//! querying luminaires), [`lut`] (host-lighting look-up tables), [`instance`] (instances, their
//! near-field settings and illuminance), [`target`] (render targets, export, read-back),
//! [`render`] (the camera, render options, `lumi_render`), [`scene`] (glTF scenes: loading, the
//! scene drawn and its lighting settings, illuminance by the reference path tracer); `handle`
//! encodes the handles.

#![allow(non_camel_case_types)]

pub mod context;
mod handle;
pub mod instance;
pub mod luminaire;
pub mod lut;
pub mod render;
pub mod scene;
pub mod target;

use std::cell::RefCell;
use std::ffi::{c_char, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

use crate::gpu::GpuError;
use crate::photometry::PhotometryError;

/// Status of a call: `LUMI_STATUS_OK` (0) or an error number. The numbers never change.
pub type lumi_status = u32;

/// Success.
pub const LUMI_STATUS_OK: lumi_status = 0;
/// An argument is out of range, an enum value unknown, or a handle stale or foreign.
pub const LUMI_STATUS_INVALID_ARGUMENT: lumi_status = 1;
/// A required pointer argument was NULL.
pub const LUMI_STATUS_NULL_POINTER: lumi_status = 2;
/// The device or driver lacks a capability (external memory, an exportable format, ...).
pub const LUMI_STATUS_UNSUPPORTED: lumi_status = 3;
/// A file could not be read.
pub const LUMI_STATUS_IO: lumi_status = 4;
/// A file is malformed.
pub const LUMI_STATUS_PARSE: lumi_status = 5;
/// A GPU validation or Vulkan error.
pub const LUMI_STATUS_GPU: lumi_status = 6;
/// The GPU device was lost: destroy the context and create a new one.
pub const LUMI_STATUS_DEVICE_LOST: lumi_status = 7;
/// Out of GPU or host memory.
pub const LUMI_STATUS_OUT_OF_MEMORY: lumi_status = 8;
/// A caller buffer is too small (the call says how large it must be).
pub const LUMI_STATUS_BUFFER_TOO_SMALL: lumi_status = 9;
/// A bug in lumiview panicked; the context is poisoned.
pub const LUMI_STATUS_PANIC: lumi_status = 10;
/// The context panicked earlier and refuses further work: destroy it.
pub const LUMI_STATUS_POISONED: lumi_status = 11;
/// The caller was compiled against a different ABI version.
pub const LUMI_STATUS_ABI_MISMATCH: lumi_status = 12;
/// No usable Vulkan device (or none with the requested UUID).
pub const LUMI_STATUS_NO_DEVICE: lumi_status = 13;

/// The ABI version of this header; pass it in `lumi_context_desc.abi_version`. History: 1 the first
/// release; 2 `lumi_luminaire_info` gained the near-field fields (`camera_count` … `budget_bytes`).
pub const LUMI_ABI_VERSION: u32 = 2;

/// An error crossing the boundary: a status and its text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FfiError {
    /// The status number.
    pub status: lumi_status,
    /// Human-readable text naming the argument or file.
    pub message: String,
}

impl FfiError {
    /// An error with a status.
    pub fn new(status: lumi_status, message: impl Into<String>) -> Self {
        FfiError {
            status,
            message: message.into(),
        }
    }
    /// `LUMI_STATUS_NULL_POINTER` naming the argument.
    pub fn null(arg: &str) -> Self {
        FfiError::new(LUMI_STATUS_NULL_POINTER, format!("argument '{arg}' is NULL"))
    }
    /// `LUMI_STATUS_INVALID_ARGUMENT` naming the argument.
    pub fn invalid(arg: &str, why: impl std::fmt::Display) -> Self {
        FfiError::new(LUMI_STATUS_INVALID_ARGUMENT, format!("invalid argument '{arg}': {why}"))
    }
}

impl From<GpuError> for FfiError {
    fn from(e: GpuError) -> Self {
        let status = match &e {
            GpuError::InvalidArgument { .. } => LUMI_STATUS_INVALID_ARGUMENT,
            GpuError::Unsupported(_) => LUMI_STATUS_UNSUPPORTED,
            GpuError::Validation(_) => LUMI_STATUS_GPU,
            GpuError::OutOfMemory(_) => LUMI_STATUS_OUT_OF_MEMORY,
            GpuError::DeviceLost(_) => LUMI_STATUS_DEVICE_LOST,
            GpuError::Interop(crate::interop::InteropError::NoAdapter(_)) => LUMI_STATUS_NO_DEVICE,
            GpuError::Interop(crate::interop::InteropError::Unsupported(_)) => LUMI_STATUS_UNSUPPORTED,
            GpuError::Interop(crate::interop::InteropError::Vulkan(_)) => LUMI_STATUS_GPU,
            GpuError::Interop(crate::interop::InteropError::OutOfMemory(_)) => LUMI_STATUS_OUT_OF_MEMORY,
            GpuError::Photometry(p) => photometry_status(p),
            GpuError::Nearfield(n) => nearfield_status(n),
        };
        FfiError::new(status, e.to_string())
    }
}

fn photometry_status(e: &PhotometryError) -> lumi_status {
    match e {
        PhotometryError::Io { source, .. } if source.kind() == std::io::ErrorKind::OutOfMemory => {
            LUMI_STATUS_OUT_OF_MEMORY
        }
        PhotometryError::Io { .. } => LUMI_STATUS_IO,
        PhotometryError::Parse(_) => LUMI_STATUS_PARSE,
        PhotometryError::InvalidArgument { .. } => LUMI_STATUS_INVALID_ARGUMENT,
    }
}

fn nearfield_status(e: &crate::nearfield::NearfieldError) -> lumi_status {
    use crate::nearfield::NearfieldError as N;
    match e {
        N::Io { source, .. } if source.kind() == std::io::ErrorKind::OutOfMemory => LUMI_STATUS_OUT_OF_MEMORY,
        N::Io { .. } => LUMI_STATUS_IO,
        N::InvalidArgument { .. } => LUMI_STATUS_INVALID_ARGUMENT,
        N::Unsupported { .. } => LUMI_STATUS_UNSUPPORTED,
        _ => LUMI_STATUS_PARSE,
    }
}

impl From<crate::nearfield::NearfieldError> for FfiError {
    fn from(e: crate::nearfield::NearfieldError) -> Self {
        FfiError::new(nearfield_status(&e), e.to_string())
    }
}

impl From<PhotometryError> for FfiError {
    fn from(e: PhotometryError) -> Self {
        FfiError::new(photometry_status(&e), e.to_string())
    }
}

thread_local! {
    static LAST_ERROR: RefCell<String> = const { RefCell::new(String::new()) };
}

/// Records `message` as this thread's last error.
pub(crate) fn set_last_error(message: &str) {
    LAST_ERROR.with(|e| {
        let mut e = e.borrow_mut();
        e.clear();
        e.push_str(message);
    });
}

fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic payload".to_string()
    }
}

/// Runs an exported function's body: converts errors to statuses (recording their text) and panics to
/// `LUMI_STATUS_PANIC`. `on_panic` runs after a panic (to poison the context).
pub(crate) fn boundary(name: &str, on_panic: impl FnOnce(), f: impl FnOnce() -> Result<(), FfiError>) -> lumi_status {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => LUMI_STATUS_OK,
        Ok(Err(e)) => {
            set_last_error(&format!("{name}: {}", e.message));
            e.status
        }
        Err(payload) => {
            on_panic();
            set_last_error(&format!(
                "{name}: internal error (panic): {}; the context is poisoned",
                panic_text(&*payload)
            ));
            LUMI_STATUS_PANIC
        }
    }
}

/// Copies this thread's last error text into `buffer` (snprintf semantics: at most `buffer_len − 1`
/// bytes and a NUL) and returns its full length in bytes without the NUL. With `buffer` NULL or
/// `buffer_len` 0 nothing is written (use it to query the length). The text is UTF-8 and names the
/// function and the argument or file at fault; an empty string when no call on this thread failed.
///
/// Thread safety: per thread; any thread may call it at any time.
///
/// # Safety
/// `buffer` is NULL or points to `buffer_len` writable bytes.
#[no_mangle]
pub unsafe extern "C" fn lumi_last_error(buffer: *mut c_char, buffer_len: usize) -> usize {
    let r = catch_unwind(|| {
        LAST_ERROR.with(|e| {
            let e = e.borrow();
            let bytes = e.as_bytes();
            if !buffer.is_null() && buffer_len > 0 {
                let n = bytes.len().min(buffer_len - 1);
                // SAFETY: the caller promises `buffer` points to `buffer_len` writable bytes; we write
                // n + 1 ≤ buffer_len bytes.
                unsafe {
                    std::ptr::copy_nonoverlapping(bytes.as_ptr(), buffer.cast::<u8>(), n);
                    *buffer.add(n) = 0;
                }
            }
            bytes.len()
        })
    });
    r.unwrap_or(0)
}

/// The library version packed as `major << 16 | minor << 8 | patch`.
#[no_mangle]
pub extern "C" fn lumi_version() -> u32 {
    let p = |s: &str| s.parse::<u32>().unwrap_or(0);
    (p(env!("CARGO_PKG_VERSION_MAJOR")) << 16)
        | (p(env!("CARGO_PKG_VERSION_MINOR")) << 8)
        | p(env!("CARGO_PKG_VERSION_PATCH"))
}

/// The ABI version this library implements (compare with `LUMI_ABI_VERSION` from the header).
#[no_mangle]
pub extern "C" fn lumi_abi_version() -> u32 {
    LUMI_ABI_VERSION
}

/// Reads a NUL-terminated UTF-8 path argument.
///
/// # Safety
/// `p` is NULL or points to a NUL-terminated string valid for the call.
pub(crate) unsafe fn path_arg(p: *const c_char, name: &str) -> Result<PathBuf, FfiError> {
    if p.is_null() {
        return Err(FfiError::null(name));
    }
    // SAFETY: non-NULL and NUL-terminated per the caller's contract.
    let s = unsafe { CStr::from_ptr(p) };
    let s = s
        .to_str()
        .map_err(|_| FfiError::invalid(name, "path is not valid UTF-8"))?;
    if s.is_empty() {
        return Err(FfiError::invalid(name, "path is empty"));
    }
    Ok(PathBuf::from(s))
}

/// Reads a column-major `float[16]` matrix argument.
///
/// # Safety
/// `m` is NULL or points to 16 readable floats.
pub(crate) unsafe fn mat_arg(m: *const f32, name: &str) -> Result<glam::Mat4, FfiError> {
    if m.is_null() {
        return Err(FfiError::null(name));
    }
    let mut a = [0f32; 16];
    // SAFETY: the caller promises 16 readable floats at `m`.
    unsafe { std::ptr::copy_nonoverlapping(m, a.as_mut_ptr(), 16) };
    if a.iter().any(|v| !v.is_finite()) {
        return Err(FfiError::invalid(name, "matrix has a NaN or infinite element"));
    }
    Ok(glam::Mat4::from_cols_array(&a))
}

/// Writes `v` through an out-pointer (already checked non-NULL).
///
/// # Safety
/// `out` is non-NULL, aligned and writable.
pub(crate) unsafe fn write_out<T>(out: *mut T, v: T) {
    // SAFETY: per the caller's contract.
    unsafe { out.write(v) };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn panic_becomes_a_status_with_text() {
        let mut poisoned = false;
        let s = boundary("lumi_test", || poisoned = true, || panic!("deliberate"));
        assert_eq!(s, LUMI_STATUS_PANIC);
        assert!(poisoned);
        let mut buf = [0 as c_char; 128];
        // SAFETY: a valid 128-byte buffer.
        let n = unsafe { lumi_last_error(buf.as_mut_ptr(), buf.len()) };
        // SAFETY: lumi_last_error NUL-terminated it.
        let text = unsafe { CStr::from_ptr(buf.as_ptr()) }.to_str().unwrap().to_string();
        assert!(text.contains("deliberate") && text.contains("lumi_test"), "{text}");
        assert_eq!(n, text.len());
        // Truncation keeps a NUL and reports the full length.
        let mut small = [1 as c_char; 5];
        // SAFETY: a valid 5-byte buffer.
        let n2 = unsafe { lumi_last_error(small.as_mut_ptr(), small.len()) };
        assert_eq!(n2, n);
        assert_eq!(small[4], 0);
        // SAFETY: NULL buffer queries the length.
        assert_eq!(unsafe { lumi_last_error(std::ptr::null_mut(), 0) }, n);
    }
}
