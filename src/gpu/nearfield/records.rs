//! The near-field pass's GPU-side layout: the storage blocks (`Draw`, `Lum` in
//! shaders/nearfield/pass.wgsl), the pool layout given as pipeline constants, the polygon vertex layout,
//! and buffer helpers.

use glam::DVec3;

use crate::gpu::context::GpuContext;
use crate::nearfield::select::lit_bound::PolygonVertex;

/// Storage block of one luminaire (`Lum` in shaders/nearfield/pass.wgsl, which documents the members;
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

/// Storage block of one draw (`Draw` in shaders/nearfield/pass.wgsl; tested like [`LumUniform`]).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct DrawUniform {
    pub(crate) clip_from_local: [[f32; 4]; 4],
    pub(crate) eye_local: [f32; 4],
    pub(crate) params: [f32; 4],
}

/// The pool layout the shader divides by, given as pipeline constants (`TILE_EDGE` … in
/// shaders/nearfield/pass.wgsl): lavapipe runs a division by a buffer value as one scalar division per lane,
/// a division by a constant as a multiply and a shift.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(super) struct PoolLayout {
    pub(super) tile_edge: u32,
    pub(super) slot_words: u32,
    pub(super) chunk_words: u32,
    pub(super) page_chunks: u32,
    pub(super) table_per_chunk: u32,
    pub(super) slots_per_chunk: u32,
}

const POLYGON_ATTRIBUTES: [wgpu::VertexAttribute; 2] = wgpu::vertex_attr_array![0 => Float32x3, 1 => Uint32];

/// [`PolygonVertex`]: position and selection triangle.
pub(super) const POLYGON_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: std::mem::size_of::<PolygonVertex>() as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &POLYGON_ATTRIBUTES,
};

pub(super) fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
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

pub(super) fn buffer_init(ctx: &GpuContext, label: &str, bytes: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
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
pub(super) fn bounding_box(centre: DVec3, r: f64) -> Vec<[f32; 3]> {
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
