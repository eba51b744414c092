//! The far-field appearance pass: every instance of an IES/EULUMDAT luminaire drawn as its luminous
//! opening with L(C, γ) = I / A_proj looked up per fragment for the direction from which the eye
//! sees it; optional overlays (photometric-solid wireframe, housing box).

use std::collections::HashMap;
use std::sync::Arc;

use glam::Mat4;

use super::context::GpuContext;
use super::frame::{FrameView, Pass};
use super::slots::{DrawSlots, SLOT};
use super::target::{frame_color_targets, frame_depth_state, ColorFormat, DepthFormat, POSITION_LAYOUT};
use super::GpuError;
use crate::photometry::meshes;
use crate::photometry::Photometry;

/// Width of the luminance table: C from 0 to 360° in 0.5° steps, node-aligned.
pub const L_TABLE_WIDTH: u32 = 721;
/// Height of the luminance table: γ from 0 to 180° in 0.5° steps, node-aligned.
pub const L_TABLE_HEIGHT: u32 = 361;

/// The C and γ angles (degrees) of luminance-table texel (i, j).
pub fn l_table_angles(i: u32, j: u32) -> (f64, f64) {
    (
        360.0 * i as f64 / (L_TABLE_WIDTH - 1) as f64,
        180.0 * j as f64 / (L_TABLE_HEIGHT - 1) as f64,
    )
}

/// The luminance table of a luminaire (cd/m², row-major over γ then C); 0 where L is undefined
/// (zero projected area).
pub fn luminance_table(p: &Photometry) -> Vec<f32> {
    let mut out = Vec::with_capacity((L_TABLE_WIDTH * L_TABLE_HEIGHT) as usize);
    for j in 0..L_TABLE_HEIGHT {
        for i in 0..L_TABLE_WIDTH {
            let (c, g) = l_table_angles(i, j);
            let l = p.luminance(c, g).unwrap_or(0.0);
            out.push(if l.is_finite() {
                l.min(f32::MAX as f64) as f32
            } else {
                0.0
            });
        }
    }
    out
}

/// A luminaire's far-field data on the GPU; instances share it through an `Arc`.
#[derive(Debug)]
pub struct FarfieldLuminaire {
    /// The photometry it was made from.
    pub photometry: Arc<Photometry>,
    opening: Option<(wgpu::Buffer, u32)>,
    solid: Option<(wgpu::Buffer, u32)>,
    housing: Option<(wgpu::Buffer, u32)>,
    table_bind: wgpu::BindGroup,
}

fn vertex_buffer(ctx: &GpuContext, label: &str, v: &[[f32; 3]]) -> Option<(wgpu::Buffer, u32)> {
    if v.is_empty() {
        return None;
    }
    let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: std::mem::size_of_val(v) as u64,
        usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    ctx.queue.write_buffer(&buf, 0, bytemuck::cast_slice(v));
    Some((buf, v.len() as u32))
}

/// Uniform block of one draw (`Instance` in shaders/farfield.wgsl; `gpu::shaders` tests the two
/// layouts are one).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct InstanceUniform {
    /// Luminaire frame → wgpu clip space.
    pub clip_from_local: [[f32; 4]; 4],
    /// Eye in the luminaire frame (w = 1 point, w = 0 direction).
    pub eye_local: [f32; 4],
    /// exposure, mode, line luminance scale, unused.
    pub params: [f32; 4],
    /// Line colour.
    pub line_color: [f32; 4],
}

/// What a far-field pipeline is specialised for (one pipeline per key, cached).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct PipelineKey {
    color: ColorFormat,
    depth_copy: bool,
    reversed_z: bool,
    lines: bool,
}

/// Pipelines and shared layouts of the far-field pass.
#[derive(Debug)]
pub struct FarfieldPass {
    module: wgpu::ShaderModule,
    instance_layout: wgpu::BindGroupLayout,
    table_layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    pipelines: HashMap<PipelineKey, wgpu::RenderPipeline>,
    uniforms: DrawSlots,
}

impl FarfieldPass {
    /// Compiles the shader and creates the layouts.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        ctx.scoped("creating the far-field pass", || {
            let module = ctx.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("farfield.wgsl"),
                source: wgpu::ShaderSource::Wgsl(super::shaders::farfield().into()),
            });
            let instance_layout = ctx.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("far-field instance"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<InstanceUniform>() as u64),
                    },
                    count: None,
                }],
            });
            let table_layout = ctx.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("far-field luminance table"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                }],
            });
            let pipeline_layout = ctx.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("far-field"),
                bind_group_layouts: &[Some(&instance_layout), Some(&table_layout)],
                immediate_size: 0,
            });
            Ok(FarfieldPass {
                module,
                instance_layout,
                table_layout,
                pipeline_layout,
                pipelines: HashMap::new(),
                uniforms: DrawSlots::new("far-field instances", wgpu::BufferUsages::UNIFORM),
            })
        })
    }

    /// Uploads a luminaire: its luminance table, opening triangles, solid wireframe (unit radius) and
    /// housing box.
    pub fn upload(&self, ctx: &GpuContext, photometry: Arc<Photometry>) -> Result<FarfieldLuminaire, GpuError> {
        ctx.scoped("uploading a luminaire", || {
            let table = luminance_table(&photometry);
            let size = wgpu::Extent3d {
                width: L_TABLE_WIDTH,
                height: L_TABLE_HEIGHT,
                depth_or_array_layers: 1,
            };
            let tex = ctx.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("luminance table (cd/m²)"),
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::R32Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            ctx.queue.write_texture(
                tex.as_image_copy(),
                bytemuck::cast_slice(&table),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(L_TABLE_WIDTH * 4),
                    rows_per_image: None,
                },
                size,
            );
            let view = tex.create_view(&wgpu::TextureViewDescriptor::default());
            let table_bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("luminance table"),
                layout: &self.table_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&view),
                }],
            });
            let opening = vertex_buffer(
                ctx,
                "opening",
                &meshes::opening_triangles(&photometry.opening).positions,
            );
            let solid = vertex_buffer(ctx, "photometric solid", &meshes::solid_lines(&photometry.web, 1.0));
            let housing = photometry
                .luminaire_size_m
                .filter(|s| s.iter().all(|v| v.is_finite() && *v > 0.0))
                .and_then(|s| vertex_buffer(ctx, "housing", &meshes::housing_lines(s)));
            Ok(FarfieldLuminaire {
                photometry,
                opening,
                solid,
                housing,
                table_bind,
            })
        })
    }

    fn pipeline(&mut self, ctx: &GpuContext, key: PipelineKey) -> Result<wgpu::RenderPipeline, GpuError> {
        if let Some(p) = self.pipelines.get(&key) {
            return Ok(p.clone());
        }
        let p = ctx.scoped("creating a far-field pipeline", || {
            let targets = &frame_color_targets(key.color, key.depth_copy);
            Ok(ctx.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(if key.lines {
                    "far-field lines"
                } else {
                    "far-field opening"
                }),
                layout: Some(&self.pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &self.module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[Some(POSITION_LAYOUT)],
                },
                primitive: wgpu::PrimitiveState {
                    topology: if key.lines {
                        wgpu::PrimitiveTopology::LineList
                    } else {
                        wgpu::PrimitiveTopology::TriangleList
                    },
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: Some(frame_depth_state(key.reversed_z)),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &self.module,
                    entry_point: Some(match (key.lines, key.depth_copy) {
                        (false, true) => "fs_opening",
                        (true, true) => "fs_line",
                        (false, false) => "fs_opening_color_only",
                        (true, false) => "fs_line_color_only",
                    }),
                    compilation_options: Default::default(),
                    targets,
                }),
                multiview_mask: None,
                cache: None,
            }))
        })?;
        self.pipelines.insert(key, p.clone());
        Ok(p)
    }
}

impl Pass for FarfieldPass {
    /// A luminaire and its model matrix (luminaire frame → world, validated by the renderer).
    type Instance = (Arc<FarfieldLuminaire>, Mat4);
    type Prepared = FarfieldFrame;

    /// Prepares a frame: writes the draw uniforms and picks the pipelines for the target's formats.
    /// The draws happen in [`Pass::record`] inside the frame's render pass.
    fn prepare(
        &mut self,
        ctx: &GpuContext,
        view: &FrameView,
        instances: &[Self::Instance],
    ) -> Result<FarfieldFrame, GpuError> {
        let options = view.options();
        let mode = view.output_flag();
        let line_scale = 1.0 / options.exposure;
        let clip_from_world = view.clip_from_world();
        // Up to three draws per instance: opening, solid, housing.
        let mut slots: Vec<InstanceUniform> = Vec::with_capacity(instances.len() * 3);
        let mut draws: Vec<FarfieldDraw> = Vec::new();
        for (lum, model) in instances {
            let eye = view.camera().eye_in(*model);
            let base = InstanceUniform {
                clip_from_local: (clip_from_world * *model).to_cols_array_2d(),
                eye_local: eye.to_array(),
                params: [options.exposure, mode, line_scale, 0.0],
                line_color: [0.0; 4],
            };
            if let Some((buf, n)) = &lum.opening {
                draws.push((slots.len(), lum.table_bind.clone(), buf.clone(), *n, false));
                slots.push(base);
            }
            if options.overlays.solid {
                if let Some((buf, n)) = &lum.solid {
                    let scaled = *model * Mat4::from_scale(glam::Vec3::splat(options.solid_radius_m));
                    let mut u = base;
                    u.clip_from_local = (clip_from_world * scaled).to_cols_array_2d();
                    u.line_color = [1.0, 0.55, 0.1, 1.0];
                    draws.push((slots.len(), lum.table_bind.clone(), buf.clone(), *n, true));
                    slots.push(u);
                }
            }
            if options.overlays.housing {
                if let Some((buf, n)) = &lum.housing {
                    let mut u = base;
                    u.line_color = [0.2, 0.6, 1.0, 1.0];
                    draws.push((slots.len(), lum.table_bind.clone(), buf.clone(), *n, true));
                    slots.push(u);
                }
            }
        }
        if draws.is_empty() {
            return Ok(FarfieldFrame::default());
        }
        let key = |lines| PipelineKey {
            color: view.target().color,
            depth_copy: view.target().depth == DepthFormat::R32Float,
            reversed_z: view.camera().reversed_z,
            lines,
        };
        let tri_pipeline = self.pipeline(ctx, key(false))?;
        let line_pipeline = self.pipeline(ctx, key(true))?;
        let ubind = self.uniforms.write(ctx, &self.instance_layout, &slots);
        Ok(FarfieldFrame {
            draws,
            pipelines: Some((tri_pipeline, line_pipeline, ubind.clone())),
        })
    }

    fn record(&self, frame: &FarfieldFrame, pass: &mut wgpu::RenderPass<'_>) {
        let Some((tri, line, ubind)) = &frame.pipelines else {
            return;
        };
        for (slot, table, vb, count, lines) in &frame.draws {
            pass.set_pipeline(if *lines { line } else { tri });
            pass.set_bind_group(0, ubind, &[(*slot as u64 * SLOT) as u32]);
            pass.set_bind_group(1, table, &[]);
            pass.set_vertex_buffer(0, vb.slice(..));
            pass.draw(0..*count, 0..1);
        }
    }
}

/// One far-field draw: uniform slot, table bind group, vertex buffer, vertex count, lines or not.
type FarfieldDraw = (usize, wgpu::BindGroup, wgpu::Buffer, u32, bool);

/// One prepared frame of the far-field pass.
#[derive(Debug, Default)]
pub struct FarfieldFrame {
    draws: Vec<FarfieldDraw>,
    pipelines: Option<(wgpu::RenderPipeline, wgpu::RenderPipeline, wgpu::BindGroup)>,
}

/// Luminance (cd/m²) the far-field pass shows for a direction `d` (luminaire frame, towards the eye),
/// computed on the CPU the same way as the shader (bilinear between table nodes): for tests and hosts.
pub fn shader_luminance(table: &[f32], d: [f64; 3]) -> f64 {
    let gamma = (-d[2]).clamp(-1.0, 1.0).acos();
    let mut c = d[1].atan2(d[0]);
    if c < 0.0 {
        c += std::f64::consts::TAU;
    }
    let (w, h) = (L_TABLE_WIDTH as usize, L_TABLE_HEIGHT as usize);
    let u = c / std::f64::consts::TAU * (w - 1) as f64;
    let v = gamma / std::f64::consts::PI * (h - 1) as f64;
    let i0 = (u.floor() as usize).min(w - 1);
    let j0 = (v.floor() as usize).min(h - 1);
    let (i1, j1) = ((i0 + 1).min(w - 1), (j0 + 1).min(h - 1));
    let (fu, fv) = ((u - i0 as f64).clamp(0.0, 1.0), (v - j0 as f64).clamp(0.0, 1.0));
    let t = |i: usize, j: usize| table.get(j * w + i).copied().unwrap_or(0.0) as f64;
    let top = t(i0, j0) * (1.0 - fu) + t(i1, j0) * fu;
    let bottom = t(i0, j1) * (1.0 - fu) + t(i1, j1) * fu;
    top * (1.0 - fv) + bottom * fv
}

/// Reinhard tone mapping as the shader does it: x = L · exposure, x / (1 + x).
pub fn tone_map(l: f64, exposure: f64) -> f64 {
    let x = (l * exposure).max(0.0);
    x / (1.0 + x)
}
