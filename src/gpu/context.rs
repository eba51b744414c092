//! The GPU context: a wgpu device on Vulkan (opened by `interop`), our own uncaptured-error handler,
//! error scopes around creation, device-loss reporting, and a log sink.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use super::GpuError;
use crate::interop::{self, DeviceCaps};

/// Severity of a log message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum LogLevel {
    /// Something failed.
    Error,
    /// Something unexpected that did not fail.
    Warning,
    /// Progress and facts.
    Info,
}

/// Where log messages go (the C API forwards them to the host's callback).
pub type LogSink = Arc<dyn Fn(LogLevel, &str) + Send + Sync>;

/// How to create a context.
#[derive(Clone, Default)]
pub struct ContextDesc {
    /// Pick the physical device with this `deviceUUID` (the host's GL/Vulkan device); an error if none has it.
    pub preferred_device_uuid: Option<[u8; 16]>,
    /// Enable the Vulkan validation layer (wgpu's debugging flags); messages go to the log sink.
    pub validation: bool,
    /// Log sink; `None` discards messages (errors still come back as statuses).
    pub log: Option<LogSink>,
}

impl std::fmt::Debug for ContextDesc {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ContextDesc")
            .field("preferred_device_uuid", &self.preferred_device_uuid)
            .field("validation", &self.validation)
            .field("log", &self.log.is_some())
            .finish()
    }
}

/// Errors wgpu reported outside an error scope, and device loss.
#[derive(Debug, Default)]
pub struct ErrorSink {
    errors: Mutex<Vec<String>>,
    lost: AtomicBool,
}

impl ErrorSink {
    /// Takes the uncaptured errors collected so far.
    pub fn take(&self) -> Vec<String> {
        self.errors
            .lock()
            .map(|mut v| std::mem::take(&mut *v))
            .unwrap_or_default()
    }
    /// True once the device was lost.
    pub fn is_lost(&self) -> bool {
        self.lost.load(Ordering::SeqCst)
    }
}

/// A wgpu device on Vulkan with lumiview's error handling.
pub struct GpuContext {
    /// Keeps the instance alive as long as the device.
    pub instance: wgpu::Instance,
    /// The adapter.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What the device can do and who it is.
    pub caps: DeviceCaps,
    /// Uncaptured errors and device loss.
    pub errors: Arc<ErrorSink>,
    log: Option<LogSink>,
}

impl std::fmt::Debug for GpuContext {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuContext")
            .field("caps", &self.caps)
            .finish_non_exhaustive()
    }
}

impl GpuContext {
    /// Opens the device described by `desc`.
    pub fn new(desc: &ContextDesc) -> Result<Self, GpuError> {
        let flags = if desc.validation {
            wgpu::InstanceFlags::debugging()
        } else {
            wgpu::InstanceFlags::empty()
        };
        let mut instance_desc = wgpu::InstanceDescriptor::new_without_display_handle();
        instance_desc.backends = wgpu::Backends::VULKAN;
        instance_desc.flags = flags;
        let instance = wgpu::Instance::new(instance_desc);
        let opened = interop::open_device(&instance, desc.preferred_device_uuid)?;
        let errors = Arc::new(ErrorSink::default());
        let sink = errors.clone();
        let log = desc.log.clone();
        let log_for_errors = log.clone();
        opened.device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            let text = e.to_string();
            if let Some(l) = &log_for_errors {
                l(LogLevel::Error, &format!("wgpu: {text}"));
            }
            if let Ok(mut v) = sink.errors.lock() {
                v.push(text);
            }
        }));
        let lost = errors.clone();
        let log_for_loss = log.clone();
        opened.device.set_device_lost_callback(move |reason, message| {
            lost.lost.store(true, Ordering::SeqCst);
            if let Some(l) = &log_for_loss {
                l(LogLevel::Error, &format!("device lost ({reason:?}): {message}"));
            }
        });
        let ctx = GpuContext {
            instance,
            adapter: opened.adapter,
            device: opened.device,
            queue: opened.queue,
            caps: opened.caps,
            errors,
            log,
        };
        ctx.log(
            LogLevel::Info,
            &format!(
                "lumiview: {} ({}), external memory {}, external semaphores {}",
                ctx.caps.adapter_name, ctx.caps.driver, ctx.caps.external_memory, ctx.caps.external_semaphore
            ),
        );
        Ok(ctx)
    }

    /// Sends a message to the log sink.
    pub fn log(&self, level: LogLevel, message: &str) {
        if let Some(l) = &self.log {
            l(level, message);
        }
    }

    /// Fails when the device was lost or wgpu reported errors outside a scope since the last check.
    pub fn check(&self) -> Result<(), GpuError> {
        if self.errors.is_lost() {
            return Err(GpuError::DeviceLost(
                "the GPU device was lost; destroy the context and create a new one".into(),
            ));
        }
        let errs = self.errors.take();
        if !errs.is_empty() {
            return Err(GpuError::Validation(errs.join("; ")));
        }
        Ok(())
    }

    /// Runs `f` inside validation and out-of-memory error scopes and turns a captured error into a
    /// [`GpuError`] naming `what`.
    pub fn scoped<T>(&self, what: &str, f: impl FnOnce() -> Result<T, GpuError>) -> Result<T, GpuError> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let result = f();
        let v = pollster::block_on(validation.pop());
        let o = pollster::block_on(oom.pop());
        if let Some(e) = v {
            return Err(GpuError::Validation(format!("{what}: {e}")));
        }
        if let Some(e) = o {
            return Err(GpuError::OutOfMemory(format!("{what}: {e}")));
        }
        result
    }

    /// Waits until the GPU finished all submitted work.
    pub fn wait_idle(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::DeviceLost(format!("waiting for the GPU: {e}")))?;
        self.check()
    }
}
