//! What every part of the C ABI tests uses: the thread's last error as text, a context (or a skip
//! printing why when there is no Vulkan device outside CI), test-data paths as C strings, and a
//! private temporary folder per test.

use std::ffi::{c_char, CStr, CString};
use std::path::{Path, PathBuf};
use std::ptr;

use lumiview::ffi::context::*;
use lumiview::ffi::*;

use crate::gpu_common::{self, data};

pub(crate) fn last_error() -> String {
    let mut buf = vec![0 as c_char; 1024];
    // SAFETY: a valid buffer of its length.
    unsafe { lumi_last_error(buf.as_mut_ptr(), buf.len()) };
    // SAFETY: NUL-terminated by lumi_last_error.
    unsafe { CStr::from_ptr(buf.as_ptr()) }.to_string_lossy().into_owned()
}

/// A context, or None (printing why) when there is no Vulkan device outside CI.
pub(crate) fn context() -> Option<*mut lumi_context> {
    let mut ctx: *mut lumi_context = ptr::null_mut();
    let mut desc = lumi_context_desc_default();
    desc.validation = gpu_common::validation_on();
    gpu_common::install_logger();
    // SAFETY: valid descriptor and out-pointer.
    let s = unsafe { lumi_context_create(&desc, &mut ctx) };
    if s != LUMI_STATUS_OK {
        if std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "0") {
            panic!("CI=true and lumi_context_create failed: {}", last_error());
        }
        eprintln!("SKIP: {}", last_error());
        return None;
    }
    Some(ctx)
}

pub(crate) fn cpath(rel: &str) -> CString {
    CString::new(data(rel).to_str().unwrap()).unwrap()
}

/// A private temporary folder for one test.
pub(crate) fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lumiview-ffi-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

pub(crate) fn cstr(p: &Path) -> CString {
    CString::new(p.to_str().unwrap()).unwrap()
}
