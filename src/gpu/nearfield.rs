//! The near-field appearance pass: a scanned luminaire (`.lvpack`) drawn from the host's camera with
//! the luminance its capture cameras measured (shaders/nearfield.wgsl says what each fragment does).
//!
//! A [`NearfieldLuminaire`] holds on the GPU: the camera records, the selection tables
//! ([`Selection`]), a chunk map and a pool of residency chunks ([`super::residency`]) within a
//! budget, plus its bounding box and optional proxy mesh. When the whole pack fits the budget it is
//! uploaded once; otherwise each frame first makes resident every chunk of every camera the frame can
//! select (found on the CPU from the view, conservatively), so a frame never reads a tile that is not
//! there; a view that needs more than the budget is an error, never a partial image.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use glam::{DVec3, Mat4, Vec4};

use super::camera::HostCamera;
use super::context::GpuContext;
use super::farfield::{OutputMode, RenderOptions};
use super::residency::{ChunkLayout, Residency, Uploads, CHUNK_BYTES, EMPTY};
use super::shaders::CAMERA_RECORD_VEC4S;
use super::slots::{DrawSlots, SLOT};
use super::target::{frame_color_targets, frame_depth_state, ColorFormat, DepthFormat, TargetDesc, POSITION_LAYOUT};
use super::GpuError;
use crate::nearfield::bvh::ProxyBvh;
use crate::nearfield::pack::Pack;
use crate::nearfield::select::lit_bound::{LitDirections, PolygonKind, PolygonVertex, EMPTY_TRIANGLE};
use crate::nearfield::select::view::{content_radius_m, view_cells};
use crate::nearfield::select::{Selection, SelectionMode, SelectionOptions};

/// Pool pages a luminaire can bind (the shader declares this many).
pub const MAX_POOL_PAGES: usize = 8;

/// Largest pool page (lavapipe's storage-binding limit; also kind to real GPUs).
pub const MAX_PAGE_BYTES: u64 = 128 << 20;

/// Default GPU budget of one near-field luminaire (bytes).
pub const DEFAULT_BUDGET_BYTES: u64 = 512 << 20;

/// How a scan becomes a GPU luminaire.
#[derive(Debug, Clone, PartialEq)]
pub struct NearfieldOptions {
    /// GPU bytes this luminaire may hold: camera records, selection tables, chunk map and tile pool
    /// together. The pool gets what the rest leaves, at most [`MAX_POOL_PAGES`] × 128 MiB.
    pub budget_bytes: u64,
    /// Radius (m) of the ball around the capture centre that holds everything the cameras saw;
    /// `None` derives it from the cameras' tile bounding boxes (see [`content_radius_m`]).
    pub content_radius_m: Option<f64>,
    /// Selection-table options.
    pub selection: SelectionOptions,
    /// Without a proxy, draw the bounding polygon of the pixels that can be lit ([`crate::nearfield::select::lit_bound`])
    /// instead of the content ball's box where it applies. The image is the same either way (the
    /// tests compare them); only the work differs.
    pub bounding_polygon: bool,
    /// The proxy encloses the light rather than being its surface (a ray file's grown hull,
    /// `PackProxy::bound`): images are then sampled plainly, dark texels included. Otherwise, in
    /// proxy mode, the bilinear weights are renormalised over the texels that hold light, so a
    /// surface's edge is not darkened by the darkness beyond it in the capture.
    pub proxy_is_bound: bool,
}

impl Default for NearfieldOptions {
    fn default() -> Self {
        NearfieldOptions {
            budget_bytes: DEFAULT_BUDGET_BYTES,
            content_radius_m: None,
            selection: SelectionOptions::default(),
            bounding_polygon: true,
            proxy_is_bound: false,
        }
    }
}

/// Per-instance settings of a near-field luminaire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NearfieldSettings {
    /// Camera selection.
    pub mode: SelectionMode,
    /// Use the proxy mesh (when the luminaire has one) for parallax-correct reprojection.
    pub proxy: bool,
}

impl Default for NearfieldSettings {
    fn default() -> Self {
        NearfieldSettings {
            mode: SelectionMode::Continuous,
            proxy: true,
        }
    }
}

/// A scanned luminaire on the GPU; instances share it.
pub struct NearfieldLuminaire {
    /// The pack it reads from.
    pub pack: Arc<Pack>,
    /// The selection tables.
    pub selection: Arc<Selection>,
    /// Capture centre (m, luminaire frame) and radius (m).
    pub sphere: (DVec3, f64),
    /// Radius (m) of the content ball around the capture centre.
    pub content_radius_m: f64,
    /// Whether the whole pack is resident (no streaming).
    pub fully_resident: bool,
    /// Whether pack chunk c is pool chunk c (fully resident, every chunk in use): the shader skips
    /// the chunk map.
    identity_map: bool,
    chunks: ChunkLayout,
    residency: Mutex<Residency>,
    chunk_map: wgpu::Buffer,
    misses: wgpu::Buffer,
    pages: Vec<wgpu::Buffer>,
    chunks_per_page: u32,
    pool_layout: PoolLayout,
    /// The directions each camera's tile box covers, for the bounding polygon (bounding mode).
    lit: LitDirections,
    bounding_polygon: bool,
    /// Whether the proxy has a hierarchy for the visibility test (a planar one needs none).
    has_bvh: bool,
    bind: wgpu::BindGroup,
    bounds: (wgpu::Buffer, u32),
    proxy: Option<(wgpu::Buffer, u32)>,
    gpu_bytes: u64,
    budget_bytes: u64,
}

impl std::fmt::Debug for NearfieldLuminaire {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NearfieldLuminaire")
            .field("pack", &self.pack)
            .field("content_radius_m", &self.content_radius_m)
            .field("fully_resident", &self.fully_resident)
            .field("gpu_bytes", &self.gpu_bytes)
            .finish_non_exhaustive()
    }
}

/// Residency figures of a luminaire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ResidencyReport {
    /// Bytes of every GPU buffer the luminaire holds (never above the budget).
    pub gpu_bytes: u64,
    /// The budget it was created with.
    pub budget_bytes: u64,
    /// Chunks the pool can hold.
    pub capacity_chunks: u32,
    /// Chunks resident now.
    pub resident_chunks: u32,
    /// Chunks the whole pack has.
    pub total_chunks: u32,
    /// Chunks uploaded so far.
    pub uploads: u64,
    /// Chunks evicted so far.
    pub evictions: u64,
}

impl NearfieldLuminaire {
    /// Residency figures.
    pub fn residency(&self) -> ResidencyReport {
        let r = self.residency.lock().unwrap_or_else(|p| p.into_inner());
        ResidencyReport {
            gpu_bytes: self.gpu_bytes,
            budget_bytes: self.budget_bytes,
            capacity_chunks: r.capacity(),
            resident_chunks: r.resident() as u32,
            total_chunks: self.chunks.all_needed().len() as u32,
            uploads: r.uploads,
            evictions: r.evictions,
        }
    }

    /// Whether it has a proxy mesh.
    pub fn has_proxy(&self) -> bool {
        self.proxy.is_some()
    }

    /// Reads (and resets) the shader's count of reads of non-resident chunks. Waits for the GPU.
    pub fn take_misses(&self, ctx: &GpuContext) -> Result<u32, GpuError> {
        let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("near-field misses read-back"),
            size: 4,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(&self.misses, 0, &staging, 0, 4);
        enc.clear_buffer(&self.misses, 0, None);
        ctx.queue.submit([enc.finish()]);
        let slice = staging.slice(..);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        ctx.wait_idle()?;
        let v = {
            let data = slice
                .get_mapped_range()
                .map_err(|e| GpuError::DeviceLost(format!("reading the near-field miss counter: {e}")))?;
            u32::from_le_bytes([data[0], data[1], data[2], data[3]])
        };
        staging.unmap();
        Ok(v)
    }

    /// Cameras any pixel of a view from `eye` (luminaire frame: w = 1 a point, w = 0 the direction
    /// towards an orthographic eye) can select in `mode`: those listed in the selection cells that the
    /// view's lines through the content ball reach on the capture sphere (conservative). With
    /// `clip_from_local`, only the lines inside the view's frustum count: a close-up needs the
    /// cameras of the directions it shows, not of all the ball.
    pub fn cameras_for_view(&self, eye: Vec4, clip_from_local: Option<Mat4>, mode: SelectionMode) -> Vec<u32> {
        let cells = view_cells(
            &self.selection,
            self.sphere,
            self.content_radius_m,
            eye,
            clip_from_local,
        );
        self.selection.cameras_of_cells(mode, cells.into_iter())
    }

    /// Whether a view from `eye` (as in [`Self::cameras_for_view`]) without the proxy may draw the
    /// bounding polygon: it is enabled, and the eye is a point outside the content ball.
    fn polygon_applies(&self, eye: Vec4) -> bool {
        self.bounding_polygon
            && eye.w > 0.5
            && (eye.truncate().as_dvec3() - self.sphere.0).length() > 1.01 * self.content_radius_m
    }

    /// What the pass draws for an instance in `mode` without its proxy, seen from `eye` (luminaire
    /// frame, as in [`Self::cameras_for_view`]) through `clip_from_local` into a `viewport` of pixels:
    /// the bounding polygons ([`crate::nearfield::select::lit_bound`]) as a triangle list, and which kind they are;
    /// an empty list when no pixel can be lit; `None` where the pass draws the content ball's box.
    pub fn bounding_polygon(
        &self,
        eye: Vec4,
        clip_from_local: Mat4,
        mode: SelectionMode,
        viewport: (u32, u32),
    ) -> Option<(Vec<PolygonVertex>, PolygonKind)> {
        let applies = self.polygon_applies(eye);
        applies
            .then(|| self.view_geometry(eye, clip_from_local, mode, viewport, applies).1)
            .flatten()
    }

    /// The cameras a view can select, and (`polygon`: where it applies) its bounding polygons.
    #[allow(clippy::type_complexity)]
    fn view_geometry(
        &self,
        eye: Vec4,
        clip_from_local: Mat4,
        mode: SelectionMode,
        viewport: (u32, u32),
        polygon: bool,
    ) -> (Vec<u32>, Option<(Vec<PolygonVertex>, PolygonKind)>) {
        // Residency needs the cameras from the cell grid; the polygons the faster superset.
        let resident = if self.fully_resident {
            Vec::new()
        } else {
            self.cameras_for_view(eye, Some(clip_from_local), mode)
        };
        if !polygon {
            return (resident, None);
        }
        let Some((cams, tris)) = self
            .lit
            .selectable(&self.selection, eye.truncate(), self.content_radius_m, mode)
        else {
            return (resident, None);
        };
        // Continuous: the triangle raster; otherwise, or where it does not apply, the hull.
        if mode == SelectionMode::Continuous {
            let raster = self.lit.continuous_raster(
                &self.selection,
                &tris,
                clip_from_local,
                eye.truncate(),
                self.content_radius_m,
                viewport,
            );
            if let Some(r) = raster {
                return (resident, Some((r, PolygonKind::Triangles)));
            }
        }
        if mode == SelectionMode::Nearest {
            let raster =
                self.lit
                    .nearest_raster(&cams, clip_from_local, eye.truncate(), self.content_radius_m, viewport);
            if let Some(r) = raster {
                return (resident, Some((r, PolygonKind::Cells)));
            }
        }
        let hull = self.lit.bound(&cams, mode, clip_from_local, eye.truncate()).map(|p| {
            let v = p.into_iter().map(|pos| PolygonVertex {
                pos,
                tri: EMPTY_TRIANGLE,
            });
            (v.collect(), PolygonKind::Hull)
        });
        (resident, hull)
    }

    fn make_resident(&self, ctx: &GpuContext, cameras: &[u32]) -> Result<(), GpuError> {
        if self.fully_resident {
            return Ok(());
        }
        let needed = self.chunks.chunks_of(cameras.iter().copied());
        let mut r = self.residency.lock().unwrap_or_else(|p| p.into_inner());
        let uploads = r
            .make_resident(&needed)
            .map_err(|m| GpuError::invalid("budget_bytes", m))?;
        if uploads.is_empty() {
            return Ok(());
        }
        self.upload(ctx, uploads, &r.map)
    }
}

/// Storage block of one luminaire (`Lum` in shaders/nearfield.wgsl, which documents the members;
/// `gpu::shaders` tests the two layouts are one).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct LumUniform {
    pub(crate) sphere: [f32; 4],
    pub(crate) content: [f32; 4],
    pub(crate) grid: [u32; 4],
    pub(crate) lists_a: [u32; 4],
    pub(crate) lists_b: [u32; 4],
    pub(crate) gap: [f32; 4],
    pub(crate) bvh: [u32; 4],
}

/// Storage block of one draw (`Draw` in shaders/nearfield.wgsl; tested like [`LumUniform`]).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct DrawUniform {
    pub(crate) clip_from_local: [[f32; 4]; 4],
    pub(crate) eye_local: [f32; 4],
    pub(crate) params: [f32; 4],
}

/// The pool layout the shader divides by, given as pipeline constants (`TILE_EDGE` … in
/// shaders/nearfield.wgsl): lavapipe runs a division by a buffer value as one scalar division per lane,
/// a division by a constant as a multiply and a shift.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct PoolLayout {
    tile_edge: u32,
    slot_words: u32,
    chunk_words: u32,
    page_chunks: u32,
    table_per_chunk: u32,
    slots_per_chunk: u32,
}

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

    /// The shader's overridable constants for this pipeline (`override` in shaders/nearfield.wgsl;
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

const POLYGON_ATTRIBUTES: [wgpu::VertexAttribute; 2] = wgpu::vertex_attr_array![0 => Float32x3, 1 => Uint32];

/// [`PolygonVertex`]: position and selection triangle.
const POLYGON_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: std::mem::size_of::<PolygonVertex>() as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &POLYGON_ATTRIBUTES,
};

/// Pipelines and layouts of the near-field pass.
#[derive(Debug)]
pub struct NearfieldPass {
    module: wgpu::ShaderModule,
    draw_layout: wgpu::BindGroupLayout,
    lum_layout: wgpu::BindGroupLayout,
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

fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn buffer_init(ctx: &GpuContext, label: &str, bytes: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    let size = (bytes.len() as u64).max(16).div_ceil(4) * 4;
    let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: usage | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    if !bytes.is_empty() {
        let mut padded = bytes.to_vec();
        padded.resize(padded.len().div_ceil(4) * 4, 0);
        ctx.queue.write_buffer(&buf, 0, &padded);
    }
    buf
}

/// A box around the content ball (12 triangles, half-size = radius): bounding-mode geometry.
fn bounding_box(centre: DVec3, r: f64) -> Vec<[f32; 3]> {
    let c = centre.as_vec3();
    let r = r as f32;
    let v = |x: f32, y: f32, z: f32| [c.x + x * r, c.y + y * r, c.z + z * r];
    let corners = [
        v(-1.0, -1.0, -1.0),
        v(1.0, -1.0, -1.0),
        v(1.0, 1.0, -1.0),
        v(-1.0, 1.0, -1.0),
        v(-1.0, -1.0, 1.0),
        v(1.0, -1.0, 1.0),
        v(1.0, 1.0, 1.0),
        v(-1.0, 1.0, 1.0),
    ];
    // Outward-facing, counter-clockwise seen from outside.
    let quads = [
        [0, 3, 2, 1],
        [4, 5, 6, 7],
        [0, 1, 5, 4],
        [2, 3, 7, 6],
        [1, 2, 6, 5],
        [3, 0, 4, 7],
    ];
    let mut out = Vec::with_capacity(36);
    for q in quads {
        for t in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
            for i in t {
                out.push(corners[i]);
            }
        }
    }
    out
}

impl NearfieldPass {
    /// Compiles the shader and creates the layouts.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        ctx.scoped("creating the near-field pass", || {
            let module = ctx.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("nearfield.wgsl"),
                source: wgpu::ShaderSource::Wgsl(super::shaders::nearfield().into()),
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

    /// Uploads a pack: camera records, selection tables, chunk map, and the tile pool within
    /// `opts.budget_bytes` (the whole pack when it fits). `proxy` is a triangle list in the luminaire
    /// frame (m).
    pub fn upload(
        &self,
        ctx: &GpuContext,
        pack: Arc<Pack>,
        proxy: Option<Vec<[f32; 3]>>,
        opts: &NearfieldOptions,
    ) -> Result<NearfieldLuminaire, GpuError> {
        let set = pack.rayset();
        let selection = Arc::new(Selection::build(set, &opts.selection)?);
        let chunks = ChunkLayout::new(&pack).map_err(|m| GpuError::invalid("pack", m))?;
        let sphere = (set.sphere.centre_m, set.sphere.radius_m);
        let mut content = match opts.content_radius_m {
            Some(r) if r.is_finite() && r > 0.0 && r < sphere.1 => r,
            Some(r) => {
                return Err(GpuError::invalid(
                    "content_radius_m",
                    format!("{r} must be finite, > 0 and below the capture radius {} m", sphere.1),
                ))
            }
            None => content_radius_m(&pack),
        };
        if let Some(p) = &proxy {
            if p.is_empty() || p.len() % 3 != 0 || p.iter().any(|v| !v.iter().all(|x| x.is_finite())) {
                return Err(GpuError::invalid(
                    "proxy",
                    "must be a non-empty list of finite triangles",
                ));
            }
            for v in p {
                let d = (glam::Vec3::from(*v).as_dvec3() - sphere.0).length();
                if d >= sphere.1 {
                    return Err(GpuError::invalid(
                        "proxy",
                        format!(
                            "a vertex lies {d:.3} m from the capture centre, outside the capture sphere ({} m)",
                            sphere.1
                        ),
                    ));
                }
                content = content.max(d * 1.001);
            }
        }
        if opts.budget_bytes == 0 {
            return Err(GpuError::invalid("budget_bytes", "must be > 0"));
        }
        ctx.scoped("uploading a near-field luminaire", || {
            let storage = wgpu::BufferUsages::STORAGE;
            // Camera records.
            let layout = pack.layout();
            let mut cams: Vec<[u32; 4]> = Vec::with_capacity(set.cameras.len() * CAMERA_RECORD_VEC4S);
            for (i, (c, e)) in set.cameras.iter().zip(pack.images()).enumerate() {
                let k = set.intrinsics_of(i);
                let f = |v: f64| (v as f32).to_bits();
                let p = c.position_m;
                // The projection as one 3×4 matrix: (h.x, h.y, h.z) = M · x + t for a point x, M · v
                // for a direction; pixel = h.xy / h.z (see `Cam` in the shader).
                let rows = [
                    c.right * k.focal_px.x + c.forward * k.principal_px.x,
                    c.down * k.focal_px.y + c.forward * k.principal_px.y,
                    c.forward,
                ];
                for m in rows {
                    cams.push([f(m.x), f(m.y), f(m.z), f(-m.dot(p))]);
                }
                cams.push([e.bbox.x0, e.bbox.y0, e.bbox.w, e.bbox.h]);
                cams.push([e.width, e.height, e.table_offset as u32, 0]);
                cams.push([f(p.x), f(p.y), f(p.z), 0]);
                debug_assert_eq!(cams.len(), (i + 1) * CAMERA_RECORD_VEC4S);
            }
            let g = selection.gpu_data();
            let mut lists: Vec<u32> = Vec::new();
            let base = |v: &[u32], lists: &mut Vec<u32>| {
                let b = lists.len() as u32;
                lists.extend_from_slice(v);
                b
            };
            let tri_off = base(&g.tri_offsets, &mut lists);
            let tri_items = base(&g.tri_items, &mut lists);
            let n1_off = base(&g.near1_offsets, &mut lists);
            let n1_items = base(&g.near1_items, &mut lists);
            let n4_off = base(&g.near4_offsets, &mut lists);
            let n4_items = base(&g.near4_items, &mut lists);
            let max_binding = ctx.device.limits().max_storage_buffer_binding_size.min(MAX_PAGE_BYTES);
            // The proxy's BVH for the visibility test (src/nearfield/bvh.rs): nodes, then triangles,
            // after the selection triangles in the same buffer (one binding fewer: lavapipe runs the
            // pass ~1.5× slower with a 17th storage buffer in the fragment stage).
            // A planar proxy cannot block itself: no hierarchy, and pipelines without the test.
            let bvh = proxy
                .as_deref()
                .filter(|p| !crate::nearfield::bvh::is_planar(p))
                .map(ProxyBvh::build)
                .transpose()?;
            let mut geometry = g.triangles.clone();
            let bvh_bases = match &bvh {
                Some(b) => {
                    let nodes = geometry.len() as u32;
                    geometry.extend_from_slice(&b.nodes);
                    let tris = geometry.len() as u32;
                    geometry.extend_from_slice(&b.triangles);
                    [nodes, tris, 1, (b.nodes.len() / 2) as u32]
                }
                None => [0; 4],
            };
            // The quadratic stencils (src/nearfield/select/quadratic.rs), after them.
            let quad_base = geometry.len() as u32;
            geometry.extend_from_slice(&g.quadratic);
            for (what, bytes) in [
                ("camera records", cams.len() * 16),
                ("selection triangles, proxy BVH and stencils", geometry.len() * 16),
                ("selection lists", lists.len() * 4),
            ] {
                if bytes as u64 > max_binding {
                    return Err(GpuError::invalid(
                        "scan",
                        format!("its {what} need {bytes} bytes, above the {max_binding}-byte binding limit"),
                    ));
                }
            }
            let lum_uniform = LumUniform {
                sphere: [sphere.0.x as f32, sphere.0.y as f32, sphere.0.z as f32, sphere.1 as f32],
                content: [sphere.0.x as f32, sphere.0.y as f32, sphere.0.z as f32, content as f32],
                grid: [g.n_phi, g.n_theta, chunks.table_chunks, 0],
                lists_a: [tri_off, tri_items, n1_off, n1_items],
                lists_b: [n4_off, n4_items, quad_base, 0],
                bvh: bvh_bases,
                // Visibility-test margin: 10⁻⁴ of the content radius (at least 1 µm); z: 1 when
                // the proxy only bounds the light (plain bilinear sampling).
                gap: [
                    g.cos_max_gap,
                    (1e-4 * content).max(1e-6) as f32,
                    if opts.proxy_is_bound { 1.0 } else { 0.0 },
                    0.0,
                ],
            };
            let chunks_per_page = (max_binding / CHUNK_BYTES).max(1) as u32;
            let pool_layout = PoolLayout {
                tile_edge: layout.tile_size,
                slot_words: chunks.slot_words,
                chunk_words: (CHUNK_BYTES / 4) as u32,
                page_chunks: chunks_per_page,
                table_per_chunk: chunks.entries_per_chunk,
                slots_per_chunk: chunks.slots_per_chunk,
            };
            let ubuf = buffer_init(
                ctx,
                "near-field luminaire",
                bytemuck::bytes_of(&lum_uniform),
                wgpu::BufferUsages::STORAGE,
            );
            let cam_buf = buffer_init(ctx, "camera records", bytemuck::cast_slice(&cams), storage);
            let tri_buf = buffer_init(
                ctx,
                "selection triangles and proxy BVH",
                bytemuck::cast_slice(&geometry),
                storage,
            );
            let vert_buf = buffer_init(ctx, "selection vertices", bytemuck::cast_slice(&g.vertices), storage);
            let list_buf = buffer_init(ctx, "selection lists", bytemuck::cast_slice(&lists), storage);
            let map_len = chunks.chunk_count() as usize;
            let chunk_map = buffer_init(
                ctx,
                "chunk map",
                bytemuck::cast_slice(&vec![EMPTY; map_len.max(1)]),
                storage,
            );
            let misses = buffer_init(
                ctx,
                "near-field misses",
                &[0u8; 16],
                storage | wgpu::BufferUsages::COPY_SRC,
            );
            let bounds_v = bounding_box(sphere.0, content);
            let bounds = (
                buffer_init(ctx, "content box", bytemuck::cast_slice(&bounds_v), wgpu::BufferUsages::VERTEX),
                bounds_v.len() as u32,
            );
            let proxy_buf = proxy.as_ref().map(|p| {
                (
                    buffer_init(ctx, "proxy mesh", bytemuck::cast_slice(p), wgpu::BufferUsages::VERTEX),
                    p.len() as u32,
                )
            });
            let fixed: u64 = [
                &ubuf, &cam_buf, &tri_buf, &vert_buf, &list_buf, &chunk_map, &misses, &bounds.0,
            ]
                .iter()
                .map(|b| b.size())
                .sum::<u64>()
                + proxy_buf.as_ref().map_or(0, |p| p.0.size());
            // One 256-byte stand-in for unused pool bindings.
            let dummy_bytes = 256u64;
            let all = chunks.all_needed();
            let pool_budget = opts.budget_bytes.saturating_sub(fixed + dummy_bytes);
            let capacity = (pool_budget / CHUNK_BYTES)
                .min(all.len() as u64)
                .min(MAX_POOL_PAGES as u64 * u64::from(chunks_per_page)) as u32;
            if capacity == 0 && !all.is_empty() {
                return Err(GpuError::invalid(
                    "budget_bytes",
                    format!(
                        "{} bytes leave no room for tiles: camera records and selection tables take {fixed}; give at least {}",
                        opts.budget_bytes,
                        fixed + dummy_bytes + CHUNK_BYTES
                    ),
                ));
            }
            let mut pages = Vec::new();
            let mut left = u64::from(capacity);
            while left > 0 {
                let n = left.min(u64::from(chunks_per_page));
                pages.push(ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("near-field tile pool page"),
                    size: n * CHUNK_BYTES,
                    usage: storage | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }));
                left -= n;
            }
            let dummy = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("near-field unused pool binding"),
                size: dummy_bytes,
                usage: storage,
                mapped_at_creation: false,
            });
            let gpu_bytes = fixed + dummy_bytes + pages.iter().map(|p| p.size()).sum::<u64>();
            let mut entries = vec![
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: ubuf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: cam_buf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: tri_buf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: vert_buf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: list_buf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 5,
                    resource: chunk_map.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 6,
                    resource: misses.as_entire_binding(),
                },
            ];
            for b in 0..MAX_POOL_PAGES {
                entries.push(wgpu::BindGroupEntry {
                    binding: 7 + b as u32,
                    resource: pages.get(b).unwrap_or(&dummy).as_entire_binding(),
                });
            }

            let bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("near-field luminaire"),
                layout: &self.lum_layout,
                entries: &entries,
            });
            let fully_resident = capacity as usize >= all.len();
            let lum = NearfieldLuminaire {
                pack: pack.clone(),
                selection: selection.clone(),
                sphere,
                content_radius_m: content,
                fully_resident: false,
                identity_map: false,
                residency: Mutex::new(Residency::new(chunks.chunk_count(), capacity)),
                chunks,
                chunk_map,
                misses,
                pages,
                chunks_per_page,
                pool_layout,
                lit: LitDirections::new(set, &pack, &selection, fully_resident)?,
                bounding_polygon: opts.bounding_polygon,
                has_bvh: bvh.is_some(),
                bind,
                bounds,
                proxy: proxy_buf,
                gpu_bytes,
                budget_bytes: opts.budget_bytes,
            };
            if fully_resident {
                // Upload everything once, in batches so staging memory stays bounded.
                for batch in all.chunks(256) {
                    lum.make_resident_chunks(ctx, batch)?;
                    ctx.queue.submit([]);
                }
            }
            // Fully resident with every chunk id in use: pack chunk c sits in pool chunk c, and the
            // shader may skip the chunk map (two of a footprint's four dependent reads).
            let identity_map = fully_resident && {
                let r = lum.residency.lock().unwrap_or_else(|p| p.into_inner());
                all.len() == r.map.len() && r.map.iter().enumerate().all(|(c, &g)| g as usize == c)
            };
            Ok(NearfieldLuminaire {
                fully_resident,
                identity_map,
                ..lum
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

    /// Prepares a frame: makes resident what each luminaire's instances can select (all instances of
    /// a luminaire together) and writes the draw uniforms. The draws happen in [`NearfieldPass::draw`]
    /// inside the frame's render pass.
    pub fn prepare(
        &mut self,
        ctx: &GpuContext,
        target: &TargetDesc,
        camera: &HostCamera,
        options: &RenderOptions,
        instances: &[(Arc<NearfieldLuminaire>, Mat4, NearfieldSettings)],
    ) -> Result<NearfieldFrame, GpuError> {
        if instances.is_empty() {
            return Ok(NearfieldFrame::default());
        }
        let (color, depth, viewport) = (target.color, target.depth, (target.width, target.height));
        // Residency: the union over instances, per luminaire.
        let mut per_lum: Vec<(Arc<NearfieldLuminaire>, Vec<u32>)> = Vec::new();
        let mut slots: Vec<DrawUniform> = Vec::with_capacity(instances.len());
        let mut draws = Vec::with_capacity(instances.len());
        let clip_from_world = camera.clip_from_world();
        let mode_out = if options.output == OutputMode::ToneMapped {
            1.0
        } else {
            0.0
        };
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
                    let front = outside != camera.mirrors_winding(*model);
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

    /// Records a prepared frame's draws into the frame's render pass.
    pub fn draw(&self, frame: &NearfieldFrame, pass: &mut wgpu::RenderPass<'_>) {
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

impl NearfieldLuminaire {
    /// Writes the uploaded chunks into their pool pages and the new chunk map.
    fn upload(&self, ctx: &GpuContext, uploads: Uploads, map: &[u32]) -> Result<(), GpuError> {
        for (g, c) in uploads {
            let bytes = self.chunks.chunk_bytes(&self.pack, c)?;
            let page = (g / self.chunks_per_page) as usize;
            let off = u64::from(g % self.chunks_per_page) * CHUNK_BYTES;
            if !bytes.is_empty() {
                ctx.queue.write_buffer(&self.pages[page], off, &bytes);
            }
        }
        ctx.queue.write_buffer(&self.chunk_map, 0, bytemuck::cast_slice(map));
        Ok(())
    }

    fn make_resident_chunks(&self, ctx: &GpuContext, chunks: &[u32]) -> Result<(), GpuError> {
        let mut r = self.residency.lock().unwrap_or_else(|p| p.into_inner());
        // Keep what earlier batches uploaded: stamp them as needed too.
        let mut needed: Vec<u32> = r
            .map
            .iter()
            .enumerate()
            .filter(|(_, g)| **g != EMPTY)
            .map(|(c, _)| c as u32)
            .collect();
        needed.extend_from_slice(chunks);
        needed.sort_unstable();
        needed.dedup();
        let uploads = r
            .make_resident(&needed)
            .map_err(|m| GpuError::invalid("budget_bytes", m))?;
        self.upload(ctx, uploads, &r.map)
    }
}
