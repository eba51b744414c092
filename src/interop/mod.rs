//! Vulkan external memory: the only module allowed to use `ash` or `wgpu::hal`. Filled in by the
//! GPU renderer issue.
