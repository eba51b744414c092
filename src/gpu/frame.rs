//! One frame: what the host asks for (camera, render options), validated once against the target,
//! and the sequence that records every pass into one render pass of that target.
//!
//! A pass ([`Pass`]: the scene lighting pass, the far-field pass, the near-field pass) prepares its draws for a
//! [`FrameView`] (uploads, uniforms, pipelines) and records them into the frame's render pass;
//! [`render`] clears the target, records the prepared passes in order, hands the exported images to
//! the host and submits. A `FrameView` exists only validated, so no pass checks the camera or the
//! options again.

use glam::Mat4;

use super::camera::HostCamera;
use super::context::GpuContext;
use super::target::{ColorFormat, RenderTarget, TargetDesc};
use super::{Arg, GpuError};

/// Overlays drawn on top of the appearance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Overlays {
    /// The photometric-solid wireframe.
    pub solid: bool,
    /// The housing box (where the file gives luminaire dimensions).
    pub housing: bool,
}

/// What the colour output holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputMode {
    /// Linear luminance in cd/m² (float targets only).
    Luminance,
    /// Reinhard with exposure: x = L · exposure, display value x / (1 + x).
    ToneMapped,
}

/// Per-frame render options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderOptions {
    /// Output mode (RGBA8 sRGB targets require `ToneMapped`).
    pub output: OutputMode,
    /// Exposure in m²/cd for tone mapping (x = L · exposure); also scales overlay colours in
    /// luminance mode (an overlay of display value v is written as v / exposure cd/m²).
    pub exposure: f32,
    /// Overlays.
    pub overlays: Overlays,
    /// Radius of the photometric solid at the maximum intensity, metres.
    pub solid_radius_m: f32,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            output: OutputMode::Luminance,
            exposure: 1e-3,
            overlays: Overlays::default(),
            solid_radius_m: 0.5,
        }
    }
}

impl RenderOptions {
    /// Checks the options against a target's formats.
    pub fn validate(&self, target: &TargetDesc) -> Result<(), GpuError> {
        if !self.exposure.is_finite() || self.exposure <= 0.0 {
            return Err(GpuError::invalid(
                Arg::Exposure,
                format!("{} must be finite and > 0", self.exposure),
            ));
        }
        if !self.solid_radius_m.is_finite() || self.solid_radius_m <= 0.0 {
            return Err(GpuError::invalid(
                Arg::SolidRadius,
                format!("{} must be finite and > 0", self.solid_radius_m),
            ));
        }
        if self.output == OutputMode::Luminance && target.color == ColorFormat::Rgba8Srgb {
            return Err(GpuError::invalid(
                Arg::Output,
                "an RGBA8 sRGB target cannot hold luminance in cd/m²: use the tone-mapped output or a float target",
            ));
        }
        Ok(())
    }
}

/// A frame's view, validated once: the host's camera (finite, invertible matrices), the render
/// options (checked against the target's formats) and the target's description, with the
/// clip-from-world matrix every pass uses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameView {
    camera: HostCamera,
    options: RenderOptions,
    target: TargetDesc,
    clip_from_world: Mat4,
}

impl FrameView {
    /// Validates `camera` and `options` for a target described by `target`.
    ///
    /// Errors: `InvalidArgument` naming the matrix (`Arg::View`, `Arg::Projection`) or the option.
    pub fn new(camera: &HostCamera, options: &RenderOptions, target: &TargetDesc) -> Result<Self, GpuError> {
        camera.validate()?;
        options.validate(target)?;
        Ok(FrameView {
            camera: *camera,
            options: *options,
            target: *target,
            clip_from_world: camera.clip_from_world(),
        })
    }

    /// The host's camera.
    pub fn camera(&self) -> &HostCamera {
        &self.camera
    }

    /// The render options.
    pub fn options(&self) -> &RenderOptions {
        &self.options
    }

    /// The target's size and formats.
    pub fn target(&self) -> &TargetDesc {
        &self.target
    }

    /// wgpu clip space from world space ([`HostCamera::clip_from_world`]).
    pub fn clip_from_world(&self) -> Mat4 {
        self.clip_from_world
    }

    /// The shader's output-mode flag: 1 for tone-mapped output, 0 for luminance in cd/m².
    pub fn output_flag(&self) -> f32 {
        match self.options.output {
            OutputMode::ToneMapped => 1.0,
            OutputMode::Luminance => 0.0,
        }
    }
}

/// A pass of the frame: it prepares its draws of a frame's instances, then records them into the
/// frame's render pass. Every pass draws into the same target with the same depth test.
pub trait Pass {
    /// What the renderer hands the pass for each instance it draws.
    type Instance;
    /// The pass's draws of one frame, ready to record.
    type Prepared;
    /// Prepares a frame: residency, uniforms, pipelines for the target's formats. Work that needs
    /// its own render passes (the scene pass's shadow maps) is encoded and submitted here: the
    /// queue runs it before the frame's render pass.
    fn prepare(
        &mut self,
        ctx: &GpuContext,
        view: &FrameView,
        instances: &[Self::Instance],
    ) -> Result<Self::Prepared, GpuError>;
    /// Records prepared draws into the frame's render pass.
    fn record(&self, prepared: &Self::Prepared, pass: &mut wgpu::RenderPass<'_>);
}

/// A pass with its prepared draws: what [`render`] records.
pub trait Recording {
    /// Records the draws into the frame's render pass.
    fn record(&self, pass: &mut wgpu::RenderPass<'_>);
}

/// A pass borrowed with the frame it prepared ([`prepare`]).
pub struct Prepared<'p, P: Pass> {
    pass: &'p P,
    frame: P::Prepared,
}

impl<P: Pass> Recording for Prepared<'_, P> {
    fn record(&self, pass: &mut wgpu::RenderPass<'_>) {
        self.pass.record(&self.frame, pass);
    }
}

/// Prepares `pass` for a frame and keeps it with its draws, ready for [`render`].
pub fn prepare<'p, P: Pass>(
    pass: &'p mut P,
    ctx: &GpuContext,
    view: &FrameView,
    instances: &[P::Instance],
) -> Result<Prepared<'p, P>, GpuError> {
    let frame = pass.prepare(ctx, view, instances)?;
    Ok(Prepared { pass, frame })
}

/// Records one frame into `target`: acquires the exported images, clears colour (transparent),
/// depth copy and depth (far), records every prepared pass in order into one render pass, releases
/// the images to the host, submits, and waits for the GPU (or signals the target's semaphores).
///
/// Errors: `InvalidArgument` (`Arg::Target`) when `target` is not the one `view` was made for (its
/// size or formats differ), and what submitting reports.
pub fn render(
    ctx: &GpuContext,
    target: &mut RenderTarget,
    view: &FrameView,
    passes: &[&dyn Recording],
) -> Result<(), GpuError> {
    if target.desc != view.target {
        return Err(GpuError::invalid(
            Arg::Target,
            "the frame was prepared for a target of another size or format",
        ));
    }
    let far = if view.camera.reversed_z { 0.0 } else { 1.0 };
    let color_view = target
        .color
        .texture()
        .create_view(&wgpu::TextureViewDescriptor::default());
    let depth_copy_view = target
        .depth_copy
        .as_ref()
        .map(|d| d.texture().create_view(&wgpu::TextureViewDescriptor::default()));
    let depth_view = target
        .depth
        .texture()
        .create_view(&wgpu::TextureViewDescriptor::default());
    let family = ctx.caps.queue_family;
    let mut cbs: Vec<wgpu::CommandBuffer> = Vec::new();
    for e in target.exportables_mut() {
        cbs.extend(e.encode_acquire(&ctx.device, family));
    }
    let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("lumiview frame"),
    });
    {
        let mut color_attachments = vec![Some(wgpu::RenderPassColorAttachment {
            view: &color_view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                store: wgpu::StoreOp::Store,
            },
        })];
        if let Some(v) = &depth_copy_view {
            color_attachments.push(Some(wgpu::RenderPassColorAttachment {
                view: v,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: far,
                        g: 0.0,
                        b: 0.0,
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            }));
        }
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("luminaire appearance"),
            color_attachments: &color_attachments,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(far as f32),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        for p in passes {
            p.record(&mut pass);
        }
    }
    cbs.push(enc.finish());
    for e in target.exportables_mut() {
        cbs.push(e.encode_release(&ctx.device, family));
    }
    if let Some(sem) = &target.semaphores {
        // GPU-side contract: wait for the host's reads of the previous frame, signal this one's end.
        if target.frames > 0 {
            sem.host_done.wait_on_next_submit(&ctx.queue);
        }
        sem.render_done.signal_on_next_submit(&ctx.queue);
    }
    ctx.scoped("rendering a frame", || {
        ctx.queue.submit(cbs);
        Ok(())
    })?;
    if target.semaphores.is_some() {
        let _ = ctx.device.poll(wgpu::PollType::Poll);
        ctx.check()?;
    } else {
        ctx.wait_idle()?;
    }
    for e in target.exportables_mut() {
        e.mark_released();
    }
    target.frames += 1;
    Ok(())
}
