//! The wgpu renderer (safe wgpu only): context, targets, passes, residency, readback. Filled in by
//! the GPU renderer issue; nothing here yet, so the crate builds without a GPU stack.
