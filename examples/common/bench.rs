//! What the benchmarks (examples/bench_*.rs) share: the trivial passes every frame is measured
//! against, a plain render target of a frame's size, and the median of timed runs.

use std::error::Error;
use std::time::Instant;

use lumiview::gpu::Renderer;

/// The examples' error type.
pub type Res<T> = std::result::Result<T, Box<dyn Error>>;

/// A full-screen triangle that writes a constant: the floor every per-pixel pass pays.
pub struct Trivial {
    pipeline: wgpu::RenderPipeline,
}

const TRIVIAL_WGSL: &str = r#"
@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let p = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(p * 2.0 - 1.0, 0.5, 1.0);
}
@fragment
fn fs() -> @location(0) vec4<f32> {
    return vec4<f32>(1000.0, 1000.0, 1000.0, 1.0);
}
"#;

impl Trivial {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("trivial"),
            source: wgpu::ShaderSource::Wgsl(TRIVIAL_WGSL.into()),
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("trivial"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: wgpu::TextureFormat::Rgba32Float,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        Trivial { pipeline }
    }

    pub fn frame(&self, r: &Renderer, view: &wgpu::TextureView) -> Res<()> {
        let mut enc = r.ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("trivial"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.draw(0..3, 0..1);
        }
        r.ctx.queue.submit([enc.finish()]);
        r.ctx.wait_idle()?;
        Ok(())
    }
}

/// A compute pass that writes a constant into every pixel of a storage texture of the frame's size:
/// the "trivial pass" of the near-field notes (measured there at 7–13 ms at 640×360 on lavapipe).
pub struct TrivialCompute {
    pipeline: wgpu::ComputePipeline,
    bind: wgpu::BindGroup,
    size: (u32, u32),
}

const TRIVIAL_COMPUTE_WGSL: &str = r#"
@group(0) @binding(0) var out: texture_storage_2d<rgba32float, write>;
@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(out);
    if (id.x < size.x && id.y < size.y) {
        textureStore(out, vec2<i32>(id.xy), vec4<f32>(1000.0, 1000.0, 1000.0, 1.0));
    }
}
"#;

impl TrivialCompute {
    pub fn new(device: &wgpu::Device, w: u32, h: u32) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("trivial compute"),
            source: wgpu::ShaderSource::Wgsl(TRIVIAL_COMPUTE_WGSL.into()),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("trivial compute"),
            layout: None,
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        let tex = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("trivial compute target"),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::STORAGE_BINDING,
            view_formats: &[],
        });
        let view = tex.create_view(&Default::default());
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("trivial compute"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&view),
            }],
        });
        TrivialCompute {
            pipeline,
            bind,
            size: (w, h),
        }
    }

    pub fn frame(&self, r: &Renderer) -> Res<()> {
        let mut enc = r.ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind, &[]);
            pass.dispatch_workgroups(self.size.0.div_ceil(8), self.size.1.div_ceil(8), 1);
        }
        r.ctx.queue.submit([enc.finish()]);
        r.ctx.wait_idle()?;
        Ok(())
    }
}

/// The median of `runs` timed calls of `f` (after one untimed warm-up), ms, and every timing.
pub fn median_ms(mut f: impl FnMut() -> Res<()>, runs: usize) -> Res<(f64, Vec<f64>)> {
    f()?; // warm-up: pipelines, residency, caches
    let mut t = Vec::with_capacity(runs);
    for _ in 0..runs {
        let s = Instant::now();
        f()?;
        t.push(s.elapsed().as_secs_f64() * 1e3);
    }
    let mut sorted = t.clone();
    sorted.sort_by(f64::total_cmp);
    Ok((sorted[sorted.len() / 2], t))
}

/// A plain RGBA32F render target of `w` × `h` for [`Trivial`].
pub fn plain_target(r: &Renderer, w: u32, h: u32) -> wgpu::TextureView {
    r.ctx
        .device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some("trivial target"),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        })
        .create_view(&Default::default())
}

/// The median of `v` (not empty).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}
