//! Render targets: a colour image (linear cd/m² as RGBA16F/RGBA32F, or tone-mapped RGBA8 sRGB), an
//! optional depth output a host can use (an R32F copy a GL host can sample, or the D32F attachment
//! itself), an internal D32F depth buffer, export of each as an opaque fd, and read-back.

use std::os::fd::OwnedFd;

use super::context::GpuContext;
use super::{Arg, GpuError};
use crate::interop::{ExportInfo, ExportableImage, ExportableSemaphore};

/// The two semaphores of a target synchronised on the GPU.
#[derive(Debug)]
pub struct TargetSemaphores {
    /// Signalled by each frame's submission; the host waits on it before reading.
    pub render_done: ExportableSemaphore,
    /// Signalled by the host after its reads; the next frame waits on it before writing.
    pub host_done: ExportableSemaphore,
}

/// Colour formats of a target.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ColorFormat {
    /// Linear luminance in cd/m², half float (overflows above 65,504 cd/m²: use RGBA32F for bare LEDs).
    Rgba16Float,
    /// Linear luminance in cd/m², float.
    Rgba32Float,
    /// Reinhard-tone-mapped display values, sRGB-encoded 8-bit.
    Rgba8Srgb,
}

impl ColorFormat {
    /// The wgpu format.
    pub fn wgpu(self) -> wgpu::TextureFormat {
        match self {
            ColorFormat::Rgba16Float => wgpu::TextureFormat::Rgba16Float,
            ColorFormat::Rgba32Float => wgpu::TextureFormat::Rgba32Float,
            ColorFormat::Rgba8Srgb => wgpu::TextureFormat::Rgba8UnormSrgb,
        }
    }
    /// Bytes per pixel.
    pub fn bytes_per_pixel(self) -> u32 {
        match self {
            ColorFormat::Rgba16Float => 8,
            ColorFormat::Rgba32Float => 16,
            ColorFormat::Rgba8Srgb => 4,
        }
    }
    /// The GL internal format a GL host imports it with.
    pub fn gl_internal_format(self) -> u32 {
        match self {
            ColorFormat::Rgba16Float => 0x881A, // GL_RGBA16F
            ColorFormat::Rgba32Float => 0x8814, // GL_RGBA32F
            ColorFormat::Rgba8Srgb => 0x8C43,   // GL_SRGB8_ALPHA8
        }
    }
}

/// Depth outputs of a target.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DepthFormat {
    /// No depth output (an internal depth buffer is still used).
    None,
    /// An R32F colour image holding the window depth in the host's convention (GL hosts sample it).
    R32Float,
    /// The D32F depth attachment itself (Vulkan hosts can use it as a depth image).
    Depth32Float,
}

impl DepthFormat {
    /// The GL internal format of the exported depth image, 0 when there is none.
    pub fn gl_internal_format(self) -> u32 {
        match self {
            DepthFormat::None => 0,
            DepthFormat::R32Float => 0x822E,     // GL_R32F
            DepthFormat::Depth32Float => 0x8CAC, // GL_DEPTH_COMPONENT32F
        }
    }
    /// Bytes per pixel of the exported/read-back depth.
    pub fn bytes_per_pixel(self) -> u32 {
        match self {
            DepthFormat::None => 0,
            _ => 4,
        }
    }
}

/// Which image of a target.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Attachment {
    /// The colour image.
    Color,
    /// The depth output (R32F copy or D32F attachment).
    Depth,
}

/// How to create a target.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TargetDesc {
    /// Width in pixels (1…16384).
    pub width: u32,
    /// Height in pixels (1…16384).
    pub height: u32,
    /// Colour format.
    pub color: ColorFormat,
    /// Depth output.
    pub depth: DepthFormat,
    /// Create exportable images (requires external memory); otherwise plain textures (read-back only).
    pub exportable: bool,
    /// Synchronise with the host through two exported semaphores instead of waiting on the CPU
    /// (requires `VK_KHR_external_semaphore_fd`; docs/interop.md).
    pub semaphores: bool,
}

impl TargetDesc {
    /// An offscreen target for measurements and stills: luminance in cd/m² (RGBA32F), no depth, not
    /// exported.
    pub fn luminance(width: u32, height: u32) -> Self {
        TargetDesc {
            width,
            height,
            color: ColorFormat::Rgba32Float,
            depth: DepthFormat::None,
            exportable: false,
            semaphores: false,
        }
    }
}

/// The colour attachments of a frame into a target: its colour format, plus the R32F depth copy when
/// the target has one (`depth_copy`). Every pass drawing into a frame uses these.
pub(crate) fn frame_color_targets(color: ColorFormat, depth_copy: bool) -> Vec<Option<wgpu::ColorTargetState>> {
    let mut t = vec![Some(wgpu::ColorTargetState {
        format: color.wgpu(),
        blend: None,
        write_mask: wgpu::ColorWrites::ALL,
    })];
    if depth_copy {
        t.push(Some(wgpu::ColorTargetState {
            format: wgpu::TextureFormat::R32Float,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        }));
    }
    t
}

/// The depth test of a frame's draws: Depth32Float, written, nearer wins (greater for reversed Z).
pub(crate) fn frame_depth_state(reversed_z: bool) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: wgpu::TextureFormat::Depth32Float,
        depth_write_enabled: Some(true),
        depth_compare: Some(if reversed_z {
            wgpu::CompareFunction::Greater
        } else {
            wgpu::CompareFunction::Less
        }),
        stencil: wgpu::StencilState::default(),
        bias: wgpu::DepthBiasState::default(),
    }
}

/// Vertex attributes of the passes' meshes: one `vec3<f32>` position (m, luminaire frame).
pub(crate) const POSITION_ATTRIBUTES: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![0 => Float32x3];

/// Vertex buffer layout of the passes' meshes (tightly packed positions).
pub(crate) const POSITION_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: 12,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &POSITION_ATTRIBUTES,
};

/// Largest target side in pixels.
pub const MAX_TARGET_SIZE: u32 = 16384;

/// A texture that may be exportable.
#[derive(Debug)]
pub(crate) enum Image {
    Exportable(ExportableImage),
    Plain(wgpu::Texture),
}

impl Image {
    pub(crate) fn texture(&self) -> &wgpu::Texture {
        match self {
            Image::Exportable(e) => &e.texture,
            Image::Plain(t) => t,
        }
    }
}

/// A render target.
#[derive(Debug)]
pub struct RenderTarget {
    /// How it was created.
    pub desc: TargetDesc,
    pub(crate) color: Image,
    pub(crate) depth_copy: Option<Image>,
    pub(crate) depth: Image,
    /// Number of frames rendered into it.
    pub frames: u64,
    /// GPU-side synchronisation with the host, when asked for.
    pub semaphores: Option<TargetSemaphores>,
}

impl RenderTarget {
    /// Creates a target.
    pub fn new(ctx: &GpuContext, desc: &TargetDesc) -> Result<Self, GpuError> {
        if desc.width == 0 || desc.height == 0 || desc.width > MAX_TARGET_SIZE || desc.height > MAX_TARGET_SIZE {
            return Err(GpuError::invalid(
                Arg::Size,
                format!("{}×{} is outside 1…{MAX_TARGET_SIZE}", desc.width, desc.height),
            ));
        }
        if desc.semaphores && !desc.exportable {
            return Err(GpuError::invalid(
                Arg::Semaphores,
                "semaphores synchronise exported images: set exportable too",
            ));
        }
        if desc.semaphores && !ctx.caps.external_semaphore {
            return Err(GpuError::Unsupported(format!(
                "the device ({}) has no VK_KHR_external_semaphore_fd: use the CPU-wait contract (semaphores = false)",
                ctx.caps.adapter_name
            )));
        }
        if desc.exportable && !ctx.caps.external_memory {
            return Err(GpuError::Unsupported(format!(
                "the device ({}) has no VK_KHR_external_memory_fd: create the target with exportable = false and use read-back",
                ctx.caps.adapter_name
            )));
        }
        ctx.scoped("creating a render target", || {
            let make = |label: &str, format: wgpu::TextureFormat, export: bool| -> Result<Image, GpuError> {
                if export {
                    Ok(Image::Exportable(ExportableImage::new(
                        &ctx.adapter,
                        &ctx.device,
                        label,
                        desc.width,
                        desc.height,
                        format,
                    )?))
                } else {
                    Ok(Image::Plain(ctx.device.create_texture(&wgpu::TextureDescriptor {
                        label: Some(label),
                        size: wgpu::Extent3d {
                            width: desc.width,
                            height: desc.height,
                            depth_or_array_layers: 1,
                        },
                        mip_level_count: 1,
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D2,
                        format,
                        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                            | wgpu::TextureUsages::COPY_SRC
                            | wgpu::TextureUsages::TEXTURE_BINDING,
                        view_formats: &[],
                    })))
                }
            };
            let color = make("lumiview colour", desc.color.wgpu(), desc.exportable)?;
            let depth_copy = match desc.depth {
                DepthFormat::R32Float => Some(make(
                    "lumiview depth (R32F)",
                    wgpu::TextureFormat::R32Float,
                    desc.exportable,
                )?),
                _ => None,
            };
            let depth = make(
                "lumiview depth (D32F)",
                wgpu::TextureFormat::Depth32Float,
                desc.exportable && desc.depth == DepthFormat::Depth32Float,
            )?;
            let semaphores = if desc.semaphores {
                Some(TargetSemaphores {
                    render_done: ExportableSemaphore::new(&ctx.adapter, &ctx.device)?,
                    host_done: ExportableSemaphore::new(&ctx.adapter, &ctx.device)?,
                })
            } else {
                None
            };
            Ok(RenderTarget {
                desc: *desc,
                color,
                depth_copy,
                depth,
                frames: 0,
                semaphores,
            })
        })
    }

    /// The image behind `which`.
    pub(crate) fn image(&self, which: Attachment) -> Result<&Image, GpuError> {
        match which {
            Attachment::Color => Ok(&self.color),
            Attachment::Depth => match self.desc.depth {
                DepthFormat::None => Err(GpuError::invalid(
                    Arg::Attachment,
                    "the target has no depth output (created with depth format NONE)",
                )),
                DepthFormat::R32Float => self
                    .depth_copy
                    .as_ref()
                    .ok_or_else(|| GpuError::invalid(Arg::Attachment, "missing depth copy")),
                DepthFormat::Depth32Float => Ok(&self.depth),
            },
        }
    }

    /// The exportable images (those released to the host after each frame).
    pub(crate) fn exportables_mut(&mut self) -> Vec<&mut ExportableImage> {
        let mut v = Vec::new();
        if let Image::Exportable(e) = &mut self.color {
            v.push(e);
        }
        if let Some(Image::Exportable(e)) = &mut self.depth_copy {
            v.push(e);
        }
        if let Image::Exportable(e) = &mut self.depth {
            v.push(e);
        }
        v
    }

    /// Exports `which` as a new opaque fd (owned by the caller) with what a host needs to import it.
    pub fn export(&self, ctx: &GpuContext, which: Attachment) -> Result<(OwnedFd, ExportInfo), GpuError> {
        match self.image(which)? {
            Image::Exportable(e) => Ok((e.export_fd(&ctx.device)?, e.info)),
            Image::Plain(_) => Err(GpuError::Unsupported(
                "the target was created with exportable = false".into(),
            )),
        }
    }

    /// Exports the target's semaphores as new opaque fds (render_done, host_done), owned by the caller.
    pub fn export_semaphores(&self) -> Result<(OwnedFd, OwnedFd), GpuError> {
        let s = self
            .semaphores
            .as_ref()
            .ok_or_else(|| GpuError::invalid(Arg::Target, "the target was created without semaphores"))?;
        Ok((s.render_done.export_fd()?, s.host_done.export_fd()?))
    }

    /// Bytes per pixel of `which` as read back.
    pub fn bytes_per_pixel(&self, which: Attachment) -> u32 {
        match which {
            Attachment::Color => self.desc.color.bytes_per_pixel(),
            Attachment::Depth => self.desc.depth.bytes_per_pixel(),
        }
    }

    /// The luminance (cd/m², the R channel) of an RGBA32F colour target, in the row order of
    /// [`RenderTarget::read`].
    ///
    /// Errors: another colour format, or those of [`RenderTarget::read`].
    pub fn read_luminance(&mut self, ctx: &GpuContext) -> Result<Vec<f32>, GpuError> {
        if self.desc.color != ColorFormat::Rgba32Float {
            return Err(GpuError::invalid(
                Arg::Target,
                "luminance read-back needs an RGBA32F colour target",
            ));
        }
        let px = self.read(ctx, Attachment::Color)?;
        Ok(px
            .chunks_exact(16)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect())
    }

    /// Reads `which` back into memory: rows of `width · bytes_per_pixel` bytes, memory row 0 first
    /// (the same row order as the exported image). Fails before the first render.
    pub fn read(&mut self, ctx: &GpuContext, which: Attachment) -> Result<Vec<u8>, GpuError> {
        if self.frames == 0 {
            return Err(GpuError::invalid(
                Arg::Target,
                "nothing has been rendered into the target yet",
            ));
        }
        let bpp = self.bytes_per_pixel(which);
        let (w, h) = (self.desc.width, self.desc.height);
        let row = w * bpp;
        let padded = row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let family = ctx.caps.queue_family;
        let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lumiview read-back"),
            size: padded as u64 * h as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let image = self.image(which)?;
        let texture = image.texture().clone();
        let mut cbs = Vec::new();
        if let Image::Exportable(e) = image {
            cbs.extend(e.encode_acquire(&ctx.device, family));
        }
        let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("read-back"),
        });
        let is_depth = texture.format().is_depth_stencil_format();
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: if is_depth {
                    wgpu::TextureAspect::DepthOnly
                } else {
                    wgpu::TextureAspect::All
                },
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        // Return wgpu's tracker to the attachment state the release barrier starts from: an empty
        // pass that loads and stores the image.
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        {
            let _pass = if is_depth {
                enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("restore attachment state"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &view,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
            } else {
                enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("restore attachment state"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
            };
        }
        cbs.push(enc.finish());
        if let Image::Exportable(e) = image {
            cbs.push(e.encode_release(&ctx.device, family));
        }
        ctx.scoped("reading a target back", || {
            ctx.queue.submit(cbs);
            Ok(())
        })?;
        let slice = buffer.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        ctx.wait_idle()?;
        rx.recv()
            .map_err(|_| GpuError::DeviceLost("read-back mapping was dropped".into()))?
            .map_err(|e| GpuError::DeviceLost(format!("mapping the read-back buffer: {e}")))?;
        let data = slice
            .get_mapped_range()
            .map_err(|e| GpuError::DeviceLost(format!("reading the mapped read-back buffer: {e}")))?;
        let mut out = Vec::with_capacity(row as usize * h as usize);
        for r in 0..h as usize {
            let start = r * padded as usize;
            out.extend_from_slice(&data[start..start + row as usize]);
        }
        drop(data);
        buffer.unmap();
        Ok(out)
    }
}
