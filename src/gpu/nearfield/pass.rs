//! The near-field pass: pipelines (one per [`PipelineKey`]), a frame's draws, and drawing them.

use std::collections::HashMap;
use std::sync::Arc;

use glam::Mat4;

use super::luminaire::NearfieldLuminaire;
use super::records::{storage_entry, DrawUniform, LumUniform, PoolLayout, POLYGON_LAYOUT};
use super::{NearfieldSettings, MAX_POOL_PAGES};
use crate::gpu::context::GpuContext;
use crate::gpu::frame::{FrameView, Pass};
use crate::gpu::slots::{DrawSlots, SLOT};
use crate::gpu::target::{frame_color_targets, frame_depth_state, ColorFormat, DepthFormat, POSITION_LAYOUT};
use crate::gpu::GpuError;
use crate::nearfield::select::lit_bound::{PolygonKind, PolygonVertex};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct PipelineKey {
    /// The luminaire's pool layout.
    pool_layout: PoolLayout,
    color: ColorFormat,
    depth_copy: bool,
    reversed_z: bool,
    /// The shader's `POOL_PAGES`: 1 for a pool in one page (the page switch folds away), else
    /// [`MAX_POOL_PAGES`].
    pool_pages: u32,
    /// The shader's `IDENTITY_MAP`.
    identity_map: bool,
    /// The shader's `SELECTION` (0 nearest, 1 idw4, 2 continuous).
    selection: u32,
    /// The shader's `PROXY`.
    proxy: bool,
    /// The shader's `VISIBILITY`: the luminaire's proxy has a hierarchy (it is not planar).
    visibility: bool,
    /// Faces culled: none for a proxy, back faces of the bounding box from outside it, front faces
    /// from inside.
    cull: Option<wgpu::Face>,
    /// Drawing the frame's polygons (vertex layout [`POLYGON_LAYOUT`], entry `vs_polygon`), of
    /// this kind (the shader's `TRIANGLES` and `CELLS`).
    polygon: Option<PolygonKind>,
}

impl PipelineKey {
    /// Drawing the content box (the fragment writes the stand-in depth).
    fn is_box(&self) -> bool {
        !self.proxy && self.polygon.is_none()
    }

    /// The shader's overridable constants for this pipeline (`override` in shaders/nearfield/;
    /// `gpu::shaders` tests that the names are exactly the shader's).
    fn constants(&self) -> [(&'static str, f64); 14] {
        let flag = |b: bool| f64::from(u8::from(b));
        [
            ("POOL_PAGES", f64::from(self.pool_pages)),
            ("IDENTITY_MAP", flag(self.identity_map)),
            ("SELECTION", f64::from(self.selection)),
            ("PROXY", flag(self.proxy)),
            ("VISIBILITY", flag(self.visibility)),
            ("TRIANGLES", flag(self.polygon == Some(PolygonKind::Triangles))),
            ("CELLS", flag(self.polygon == Some(PolygonKind::Cells))),
            ("BOX", flag(self.is_box())),
            ("TILE_EDGE", f64::from(self.pool_layout.tile_edge)),
            ("SLOT_WORDS", f64::from(self.pool_layout.slot_words)),
            ("CHUNK_WORDS", f64::from(self.pool_layout.chunk_words)),
            ("PAGE_CHUNKS", f64::from(self.pool_layout.page_chunks)),
            ("TABLE_PER_CHUNK", f64::from(self.pool_layout.table_per_chunk)),
            ("SLOTS_PER_CHUNK", f64::from(self.pool_layout.slots_per_chunk)),
        ]
    }
}

/// The names of the near-field pipeline's constants (for `gpu::shaders`' tests).
#[cfg(test)]
pub(crate) fn pipeline_constant_names() -> Vec<&'static str> {
    let key = PipelineKey {
        pool_layout: PoolLayout {
            tile_edge: 8,
            slot_words: 33,
            chunk_words: 16384,
            page_chunks: 2048,
            table_per_chunk: 16384,
            slots_per_chunk: 496,
        },
        color: ColorFormat::Rgba32Float,
        depth_copy: false,
        reversed_z: false,
        pool_pages: 1,
        identity_map: false,
        selection: 2,
        proxy: false,
        visibility: false,
        cull: None,
        polygon: None,
    };
    key.constants().iter().map(|(n, _)| *n).collect()
}

/// Pipelines and layouts of the near-field pass.
#[derive(Debug)]
pub struct NearfieldPass {
    module: wgpu::ShaderModule,
    draw_layout: wgpu::BindGroupLayout,
    pub(super) lum_layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    pipelines: HashMap<PipelineKey, wgpu::RenderPipeline>,
    uniforms: DrawSlots,
    /// This frame's bounding polygons (luminaire frames, m), with the buffer's capacity in vertices.
    polygons: Option<(wgpu::Buffer, u64)>,
}

/// What a draw rasterises.
#[derive(Debug, Clone, Copy)]
enum DrawGeometry {
    /// The luminaire's proxy mesh.
    Proxy,
    /// The box around the content ball.
    Box,
    /// Vertices `first..first + count` of the frame's bounding polygons ([`crate::nearfield::select::lit_bound`]).
    Polygon { first: u32, count: u32, kind: PolygonKind },
}

/// One prepared frame of the pass: draws whose uniforms are written.
#[derive(Debug, Default)]
pub struct NearfieldFrame {
    /// Uniform slot, luminaire, geometry, pipeline.
    draws: Vec<(usize, Arc<NearfieldLuminaire>, DrawGeometry, wgpu::RenderPipeline)>,
}

impl NearfieldPass {
    /// Compiles the shader and creates the layouts.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        ctx.scoped("creating the near-field pass", || {
            let module = ctx.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("shaders/nearfield/"),
                source: wgpu::ShaderSource::Wgsl(crate::gpu::shaders::nearfield().into()),
            });
            let draw_layout = ctx.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("near-field draw"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: true },
                        has_dynamic_offset: true,
                        min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<DrawUniform>() as u64),
                    },
                    count: None,
                }],
            });
            let mut entries = vec![wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: true },
                    has_dynamic_offset: false,
                    min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<LumUniform>() as u64),
                },
                count: None,
            }];
            for b in 1..=5 {
                let mut e = storage_entry(b, true);
                // The polygon vertex stage reads the camera records and triangles (flat varyings).
                if b <= 2 {
                    e.visibility = wgpu::ShaderStages::VERTEX_FRAGMENT;
                }
                entries.push(e);
            }
            entries.push(storage_entry(6, false));
            for b in 0..MAX_POOL_PAGES as u32 {
                entries.push(storage_entry(7 + b, true));
            }

            let lum_layout = ctx.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("near-field luminaire"),
                entries: &entries,
            });
            let pipeline_layout = ctx.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("near-field"),
                bind_group_layouts: &[Some(&draw_layout), Some(&lum_layout)],
                immediate_size: 0,
            });
            Ok(NearfieldPass {
                module,
                draw_layout,
                lum_layout,
                pipeline_layout,
                pipelines: HashMap::new(),
                uniforms: DrawSlots::new("near-field draws", wgpu::BufferUsages::STORAGE),
                polygons: None,
            })
        })
    }
    fn pipeline(&mut self, ctx: &GpuContext, key: PipelineKey) -> Result<wgpu::RenderPipeline, GpuError> {
        if let Some(p) = self.pipelines.get(&key) {
            return Ok(p.clone());
        }
        let constants = key.constants();
        let p = ctx.scoped("creating a near-field pipeline", || {
            let targets = &frame_color_targets(key.color, key.depth_copy);
            Ok(ctx.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("near-field"),
                layout: Some(&self.pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &self.module,
                    entry_point: Some(if key.polygon.is_some() { "vs_polygon" } else { "vs_main" }),
                    // The same constants for both stages (the polygon vertex stage reads TRIANGLES).
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &constants,
                        ..Default::default()
                    },
                    buffers: &[Some(if key.polygon.is_some() {
                        POLYGON_LAYOUT
                    } else {
                        POSITION_LAYOUT
                    })],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    cull_mode: key.cull,
                    ..Default::default()
                },
                depth_stencil: Some(frame_depth_state(key.reversed_z)),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &self.module,
                    entry_point: Some(match (key.depth_copy, key.is_box()) {
                        (true, false) => "fs_main",
                        (false, false) => "fs_main_color_only",
                        (true, true) => "fs_box",
                        (false, true) => "fs_box_color_only",
                    }),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &constants,
                        ..Default::default()
                    },
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

impl Pass for NearfieldPass {
    /// A scanned luminaire, its model matrix (luminaire frame → world, validated by the renderer)
    /// and the instance's settings.
    type Instance = (Arc<NearfieldLuminaire>, Mat4, NearfieldSettings);
    type Prepared = NearfieldFrame;

    /// Prepares a frame: makes resident what each luminaire's instances can select (all instances of
    /// a luminaire together) and writes the draw uniforms. The draws happen in [`Pass::record`]
    /// inside the frame's render pass.
    fn prepare(
        &mut self,
        ctx: &GpuContext,
        view: &FrameView,
        instances: &[Self::Instance],
    ) -> Result<NearfieldFrame, GpuError> {
        let (target, camera, options) = (view.target(), view.camera(), view.options());
        if instances.is_empty() {
            return Ok(NearfieldFrame::default());
        }
        let (color, depth, viewport) = (target.color, target.depth, (target.width, target.height));
        // Residency: the union over instances, per luminaire.
        let mut per_lum: Vec<(Arc<NearfieldLuminaire>, Vec<u32>)> = Vec::new();
        let mut slots: Vec<DrawUniform> = Vec::with_capacity(instances.len());
        let mut draws = Vec::with_capacity(instances.len());
        let clip_from_world = view.clip_from_world();
        let mode_out = view.output_flag();
        let mut polygons: Vec<PolygonVertex> = Vec::new();
        for (lum, model, settings) in instances {
            let eye = camera.eye_in(*model);
            let clip_from_local = clip_from_world * *model;
            let proxy = settings.proxy && lum.proxy.is_some();
            let polygon_view = !proxy && lum.polygon_applies(eye);
            let (cams, bound) = if !lum.fully_resident || polygon_view {
                lum.view_geometry(eye, clip_from_local, settings.mode, viewport, polygon_view)
            } else {
                (Vec::new(), None)
            };
            if !lum.fully_resident {
                match per_lum.iter_mut().find(|(l, _)| Arc::ptr_eq(l, lum)) {
                    Some((_, v)) => v.extend(cams),
                    None => per_lum.push((lum.clone(), cams)),
                }
            }
            let outside = if eye.w > 0.5 {
                let e = eye.truncate().as_dvec3() - lum.sphere.0;
                e.abs().max_element() > lum.content_radius_m
            } else {
                true
            };
            let mode = settings.mode.index();
            let (geometry, cull) = match (proxy, bound, outside) {
                (true, _, _) => (DrawGeometry::Proxy, None),
                // No selectable camera has light in the view.
                (false, Some((p, _)), _) if p.is_empty() => continue,
                (false, Some((p, kind)), _) => {
                    let first = polygons.len() as u32;
                    polygons.extend_from_slice(&p);
                    (
                        DrawGeometry::Polygon {
                            first,
                            count: p.len() as u32,
                            kind,
                        },
                        None,
                    )
                }
                // The box mesh is counter-clockwise from outside: from outside draw its front
                // faces, from inside its back faces, swapped when the host's camera (a y-flipping
                // BottomLeft origin) or the model mirrors the winding.
                (false, None, outside) => {
                    let front = outside != camera.mirrors_winding_of(*model, clip_from_local);
                    let cull = if front { wgpu::Face::Back } else { wgpu::Face::Front };
                    (DrawGeometry::Box, Some(cull))
                }
            };
            draws.push((slots.len(), lum.clone(), geometry, mode, cull));
            slots.push(DrawUniform {
                clip_from_local: clip_from_local.to_cols_array_2d(),
                eye_local: eye.to_array(),
                params: [options.exposure, mode_out, 0.0, 0.0],
            });
        }
        for (lum, mut cams) in per_lum {
            cams.sort_unstable();
            cams.dedup();
            lum.make_resident(ctx, &cams)?;
        }
        self.uniforms.write(ctx, &self.draw_layout, &slots);
        if !polygons.is_empty() {
            let n = polygons.len() as u64;
            if self.polygons.as_ref().is_none_or(|(_, cap)| *cap < n) {
                let cap = n.next_power_of_two().max(256);
                let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("near-field bounding polygons"),
                    size: cap * std::mem::size_of::<PolygonVertex>() as u64,
                    usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                self.polygons = Some((buffer, cap));
            }
            if let Some((b, _)) = &self.polygons {
                ctx.queue.write_buffer(b, 0, bytemuck::cast_slice(&polygons));
            }
        }
        let mut with_pipelines = Vec::with_capacity(draws.len());
        for (slot, lum, geometry, selection, cull) in draws {
            let proxy = matches!(geometry, DrawGeometry::Proxy);
            let polygon = match geometry {
                DrawGeometry::Polygon { kind, .. } => Some(kind),
                _ => None,
            };
            let pipeline = self.pipeline(
                ctx,
                PipelineKey {
                    color,
                    depth_copy: depth == DepthFormat::R32Float,
                    reversed_z: camera.reversed_z,
                    pool_pages: if lum.pages.len() <= 1 { 1 } else { MAX_POOL_PAGES as u32 },
                    identity_map: lum.identity_map,
                    pool_layout: lum.pool_layout,
                    selection,
                    proxy,
                    visibility: lum.has_bvh,
                    cull,
                    polygon,
                },
            )?;
            with_pipelines.push((slot, lum, geometry, pipeline));
        }
        Ok(NearfieldFrame { draws: with_pipelines })
    }

    fn record(&self, frame: &NearfieldFrame, pass: &mut wgpu::RenderPass<'_>) {
        let Some(ubind) = self.uniforms.bind_group() else {
            return;
        };
        for (slot, lum, geometry, pipeline) in &frame.draws {
            let (vb, range) = match (geometry, &lum.proxy, &self.polygons) {
                (DrawGeometry::Proxy, Some(p), _) => (&p.0, 0..p.1),
                (DrawGeometry::Polygon { first, count, .. }, _, Some((b, _))) => (b, *first..*first + *count),
                _ => (&lum.bounds.0, 0..lum.bounds.1),
            };
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, ubind, &[(*slot as u64 * SLOT) as u32]);
            pass.set_bind_group(1, &lum.bind, &[]);
            pass.set_vertex_buffer(0, vb.slice(..));
            pass.draw(range, 0..1);
        }
    }
}
