//! Shared set-up of the GPU tests: one renderer per test, tests serialised (2 cores, one GPU),
//! CI=true turns a missing adapter into a failure.
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use lumiview::gpu::{ContextDesc, Renderer};
use lumiview::photometry::{self, LoadOptions, Photometry};

/// Serialises GPU tests within a test binary.
pub static GPU_LOCK: Mutex<()> = Mutex::new(());

/// Path of a test data file.
pub fn data(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(rel)
}

/// The BEGA downlight (rectangle 0.045 × 0.6 m).
pub fn bega() -> Arc<Photometry> {
    Arc::new(photometry::load(&data("misc/arnold-usd_bega_50804K3.ies"), &LoadOptions::default()).unwrap())
}

/// Counts wgpu / Vulkan validation messages (warnings and errors logged by wgpu-hal and wgpu-core).
struct CountingLogger;

static MESSAGES: Mutex<Vec<String>> = Mutex::new(Vec::new());

impl log::Log for CountingLogger {
    fn enabled(&self, m: &log::Metadata) -> bool {
        m.level() <= log::Level::Warn
    }
    fn log(&self, r: &log::Record) {
        let t = r.target();
        if r.level() <= log::Level::Warn && (t.starts_with("wgpu") || t.starts_with("naga")) {
            let text = format!("[{}] {}: {}", r.level(), t, r.args());
            eprintln!("{text}");
            MESSAGES.lock().unwrap_or_else(|e| e.into_inner()).push(text);
        }
    }
    fn flush(&self) {}
}

static LOGGER: CountingLogger = CountingLogger;

/// The validation messages logged so far (and clears them).
pub fn take_validation_messages() -> Vec<String> {
    std::mem::take(&mut *MESSAGES.lock().unwrap_or_else(|e| e.into_inner()))
}

/// Routes wgpu's log messages (and through them the validation layer's) to the counter.
pub fn install_logger() {
    if log::set_logger(&LOGGER).is_ok() {
        log::set_max_level(log::LevelFilter::Warn);
    }
}

/// Whether the tests run with the validation layer (LUMIVIEW_VALIDATION=1).
pub fn validation_on() -> bool {
    std::env::var("LUMIVIEW_VALIDATION").is_ok_and(|v| v == "1")
}

/// A renderer on the machine's Vulkan device, with validation when LUMIVIEW_VALIDATION=1. `None`
/// (with a printed reason) when there is no Vulkan device and CI is not set; a panic under CI.
pub fn renderer() -> Option<Renderer> {
    let validation = validation_on();
    install_logger();
    match Renderer::new(&ContextDesc {
        validation,
        ..ContextDesc::default()
    }) {
        Ok(r) => {
            if validation && !r.ctx.adapter.get_info().name.is_empty() {
                eprintln!("validation layer on for {}", r.ctx.caps.adapter_name);
            }
            Some(r)
        }
        Err(e) => {
            if std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "0") {
                panic!("CI=true and no usable Vulkan device: {e}");
            }
            eprintln!("SKIP: no usable Vulkan device ({e}); install mesa-vulkan-drivers (scripts/setup)");
            None
        }
    }
}

/// An OpenGL perspective projection (gluPerspective: right-handed, clip z in −w…w).
pub fn gl_perspective(fovy_rad: f32, aspect: f32, near: f32, far: f32) -> glam::Mat4 {
    let f = 1.0 / (fovy_rad / 2.0).tan();
    glam::Mat4::from_cols(
        glam::Vec4::new(f / aspect, 0.0, 0.0, 0.0),
        glam::Vec4::new(0.0, f, 0.0, 0.0),
        glam::Vec4::new(0.0, 0.0, (far + near) / (near - far), -1.0),
        glam::Vec4::new(0.0, 0.0, 2.0 * far * near / (near - far), 0.0),
    )
}

/// A right-handed view matrix (gluLookAt): world → eye, the eye looking down −Z.
pub fn look_at(eye: glam::Vec3, target: glam::Vec3, up: glam::Vec3) -> glam::Mat4 {
    let f = (target - eye).normalize();
    let s = f.cross(up).normalize();
    let u = s.cross(f);
    glam::Mat4::from_cols(
        glam::Vec4::new(s.x, u.x, -f.x, 0.0),
        glam::Vec4::new(s.y, u.y, -f.y, 0.0),
        glam::Vec4::new(s.z, u.z, -f.z, 0.0),
        glam::Vec4::new(-s.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
    )
}

/// The ASA 15M R2 luminaire (square opening 0.378 m).
pub fn asa() -> Arc<Photometry> {
    Arc::new(photometry::load(&data("misc/luxcore_ASA_15M_R2.ies"), &LoadOptions::default()).unwrap())
}

/// Asserts that no validation message was logged (with LUMIVIEW_VALIDATION=1 the Vulkan layer's
/// messages arrive here through wgpu's log hook).
pub fn assert_no_validation_messages() {
    let m = take_validation_messages();
    assert!(m.is_empty(), "{} validation message(s):\n{}", m.len(), m.join("\n"));
}
