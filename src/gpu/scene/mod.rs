//! The scene lighting pass (issue 20): a loaded [`Scene`] drawn from the host's camera and lit by
//! every luminaire instance of the renderer (a far-field file's photometry, or a near-field scan's
//! far field, `nearfield::farfield`): direct light (absolute candela from each
//! photometric web, inverse square, cos i, visibility from cube shadow maps with penumbrae sized by
//! the luminous opening) plus inter-reflection from virtual point lights (`scene::vpl`). It writes
//! L = ρ·E/π (cd/m², Lambertian) and depth into the frame's target, before the far-field and
//! near-field passes, so the luminaires' own appearance composites over the lit room through the
//! one depth test.
//!
//! Each pixel is lit once: `prepare` submits a G-buffer pass (the surface each pixel sees:
//! position, normal of the side seen, reflectance, depth) and a compute pass that lights it
//! (`cs_lighting`); the frame's render pass then draws a full-screen triangle that writes the lit
//! colours with their surfaces' depth (shaders/scene/composite.wgsl). Frames of more than
//! [`SceneSettings::deferred_max_pixels`] pixels are lit per fragment as the triangles are drawn
//! instead (the same lighting functions; no per-pixel images).
//!
//! Promises:
//! - [`ScenePass::set_scene`] uploads the scene once: world-space triangles, their geometric
//!   normals (surfaces are two-sided: the side the eye sees is the side lit, as the reference's
//!   calculation points take the normal of the receiving side), the material's linear RGB base
//!   colour factor and UVs per vertex, and the base-colour textures in one sRGB atlas
//!   ([`TextureAtlas`]) sampled per fragment as `scene::texture` samples them (for |uv| ≤ 2²⁰).
//! - Each frame lights with every instance ([`Pass::prepare`]'s instances: photometry and model
//!   matrix; a scan lights as its far field from its luminous extent). Direct illuminance is the
//!   reference's direct estimator (`scene::reference`) with fixed stratified points on the opening
//!   instead of random ones and shadow-map visibility instead of shadow rays:
//!   shaders/scene/lighting.wgsl says how.
//! - Shadow maps ([`shadows`]) are rendered inside `prepare`, in their own render pass submitted
//!   before the frame's (queue order makes them visible to it). A luminaire's faces are rendered
//!   again when its centre moved, at most [`SceneSettings::shadow_updates_per_frame`] luminaires a
//!   frame (round robin); a new scene, layout or number of luminaires renders all.
//! - Virtual point lights are made on the CPU when the scene, an instance or the photon count
//!   changes, and gathered by every pixel.
//! - Light culling: each luminaire has an influence radius where its light falls below
//!   [`SceneSettings::lux_floor_lx`]; each 16-pixel screen tile lists the luminaires whose
//!   influence sphere covers it ([`lights`]), and pixels loop over their tile's list only.
//! - Memory: the vertex buffer (48 bytes a vertex, three per triangle) must fit the device's
//!   largest buffer; the shadow atlas stays within [`SceneSettings::shadow_budget_bytes`]; the
//!   intensity atlas holds up to [`lights::MAX_INTENSITY_TABLES`] photometries (1 MiB each); the
//!   tile lists, luminaire records and VPLs are storage buffers; lists larger than the device's
//!   binding limit (lavapipe: 128 MiB; every luminaire in every tile reaches it near a thousand
//!   luminaires at 4K) are an error that names the lux floor; the compute lighting's per-pixel
//!   images take [`SURFACE_BYTES_PER_PIXEL`] a pixel of the frame, kept while frames keep their size.

pub mod lights;
pub mod shadows;

use std::collections::HashMap;
use std::sync::Arc;

use glam::{Mat4, Vec3};

use super::context::GpuContext;
use super::frame::{FrameView, Pass};
use super::slots::{DrawSlots, SLOT};
use super::target::{frame_color_targets, frame_depth_state, ColorFormat, DepthFormat};
use super::{Arg, GpuError};
use crate::photometry::Photometry;
use crate::scene::bvh::Bvh;
use crate::scene::vpl::{EmissionTable, VplOptions, VplSet};
use crate::scene::{Scene, SceneLuminaire};
use bytemuck::Zeroable as _;
use lights::{
    LightRecord, PlacedLight, INTENSITY_TABLE_H, INTENSITY_TABLE_W, MAX_INTENSITY_TABLES, MAX_TABLES_PER_ROW,
};
use shadows::{face_clip_from_world, ShadowLayout, MIN_FACE_PX};

/// How the scene pass lights.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneSettings {
    /// The illuminance below which a luminaire's light is left out (its influence radius is where
    /// I_max / r² falls to it), lx.
    pub lux_floor_lx: f32,
    /// Visibility from shadow maps (false: every luminaire reaches every point facing it).
    pub shadows: bool,
    /// Most bytes of the shadow atlas (4 a texel).
    pub shadow_budget_bytes: u64,
    /// Largest cube face, pixels (faces shrink by powers of two to fit the budget).
    pub max_face_px: u32,
    /// Inter-reflection from virtual point lights (`scene::vpl`: photons shot from the
    /// luminaires on the CPU, every reflection gathered per pixel, all bounces).
    pub indirect: bool,
    /// Photons shot from all luminaires together (each leaves a VPL per reflection: about 1.7–2×
    /// as many VPLs in the office), 1…[`MAX_BOUNCE_PHOTONS`].
    pub bounce_photons: u32,
    /// Distance below which a VPL's 1/r² is held, metres (finite, ≥ 0).
    pub vpl_clamp_m: f32,
    /// Most luminaires whose shadow maps are rendered again in one frame after they moved (≥ 1);
    /// the others keep their old maps until a later frame's turn. A new scene, shadow layout or
    /// atlas renders every luminaire at once.
    pub shadow_updates_per_frame: u32,
    /// Frames of up to this many pixels are lit once per pixel in a compute pass over the surface
    /// each pixel sees (a G-buffer of [`SURFACE_BYTES_PER_PIXEL`] a pixel, kept between frames of
    /// one size); larger frames, and frames whose images the device has no memory for, are lit
    /// per fragment as they are drawn (no per-pixel buffers, but every fragment the depth test
    /// later hides is lit too). 0: always per fragment.
    pub deferred_max_pixels: u64,
}

/// GPU memory a pixel of the compute lighting's buffers takes: the surface (position, reflectance:
/// 16 bytes), its normal and reflectance (16), its depth (4) and its lit colour (16), bytes.
pub const SURFACE_BYTES_PER_PIXEL: u64 = 52;

/// Most photons [`SceneSettings::bounce_photons`] may ask for.
pub const MAX_BOUNCE_PHOTONS: u32 = 1 << 16;

impl Default for SceneSettings {
    fn default() -> Self {
        SceneSettings {
            lux_floor_lx: 0.1,
            shadows: true,
            shadow_budget_bytes: 64 << 20,
            max_face_px: 512,
            indirect: true,
            bounce_photons: 256,
            vpl_clamp_m: 0.25,
            shadow_updates_per_frame: 32,
            deferred_max_pixels: 1 << 24,
        }
    }
}

impl SceneSettings {
    /// Checks the settings.
    ///
    /// Errors: `InvalidArgument` naming `lux_floor_lx` (finite, > 0), `budget_bytes` (> 0) or
    /// `max_face_px` (≥ 16).
    pub fn validate(&self) -> Result<(), GpuError> {
        if !self.lux_floor_lx.is_finite() || self.lux_floor_lx <= 0.0 {
            return Err(GpuError::invalid(
                Arg::LuxFloor,
                format!("{} must be finite and > 0", self.lux_floor_lx),
            ));
        }
        if self.shadow_budget_bytes == 0 {
            return Err(GpuError::invalid(Arg::BudgetBytes, "the shadow budget must be > 0"));
        }
        if !(1..=MAX_BOUNCE_PHOTONS).contains(&self.bounce_photons) {
            return Err(GpuError::invalid(
                Arg::BouncePhotons,
                format!("{} must be within 1…{MAX_BOUNCE_PHOTONS}", self.bounce_photons),
            ));
        }
        if !(self.vpl_clamp_m.is_finite() && self.vpl_clamp_m >= 0.0) {
            return Err(GpuError::invalid(
                Arg::VplClamp,
                format!("{} m must be finite and ≥ 0", self.vpl_clamp_m),
            ));
        }
        if self.shadow_updates_per_frame == 0 {
            return Err(GpuError::invalid(
                Arg::ShadowUpdates,
                "at least one luminaire's shadows must be updated per frame",
            ));
        }
        if !(MIN_FACE_PX..=shadows::MAX_ATLAS_SIDE).contains(&self.max_face_px) {
            return Err(GpuError::invalid(
                Arg::FacePx,
                format!(
                    "{} must be at least {MIN_FACE_PX} and at most {}",
                    self.max_face_px,
                    shadows::MAX_ATLAS_SIDE
                ),
            ));
        }
        Ok(())
    }
}

/// Uniform block of a frame (`SceneFrame` in shaders/scene/lighting.wgsl; `gpu::shaders` tests the
/// two layouts are one).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SceneFrameUniform {
    /// World → wgpu clip space.
    pub clip_from_world: [[f32; 4]; 4],
    /// The eye (w = 1) or the direction towards it (w = 0).
    pub eye: [f32; 4],
    /// Exposure, mode, lux floor, unused.
    pub params: [f32; 4],
    /// Tile size, tiles across, tiles down, luminaires.
    pub tiles: [u32; 4],
    /// Intensity tables per row, shadow faces per row, face size, shadows on.
    pub atlas: [u32; 4],
    /// Virtual point lights gathered (0: no inter-reflection), unused × 3.
    pub indirect: [u32; 4],
}

/// Uniform block of one shadow face (`ShadowFace` in shaders/scene/shadow.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadowFaceUniform {
    /// World → wgpu clip space of the face.
    pub clip_from_world: [[f32; 4]; 4],
}

/// Floats per vertex: position, normal, linear RGB reflectance (the base colour factor), texture
/// coordinates, and the texture record + 1 (0: untextured) as an exact small float.
const VERTEX_FLOATS: usize = 12;

const SCENE_ATTRIBUTES: [wgpu::VertexAttribute; 5] = wgpu::vertex_attr_array![
    0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Float32x2, 4 => Float32
];
const SCENE_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: (VERTEX_FLOATS * 4) as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &SCENE_ATTRIBUTES,
};
const SHADOW_ATTRIBUTES: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![0 => Float32x3];
const SHADOW_VERTEX_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: (VERTEX_FLOATS * 4) as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &SHADOW_ATTRIBUTES,
};

/// Where a material's base-colour texture lies in the texture atlas and how it is sampled
/// (`TextureRecord` in shaders/scene/lighting.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TextureRecord {
    /// Atlas x, y of the image's top-left texel; its width and height in texels.
    pub rect: [u32; 4],
    /// Wrap in s and t (0 repeat, 1 clamp to edge, 2 mirrored repeat), filter (0 nearest, 1
    /// linear), unused.
    pub mode: [u32; 4],
}

/// The base-colour textures of a scene packed for the GPU: one sRGB atlas (RGBA8) and a record
/// per textured material.
#[derive(Debug, Clone, PartialEq)]
pub struct TextureAtlas {
    /// Atlas width and height, texels.
    pub size: (u32, u32),
    /// RGBA8 sRGB texels, row-major.
    pub texels: Vec<u8>,
    /// Per material: its record's index, or `None` without a texture.
    pub record_of_material: Vec<Option<u32>>,
    /// The records.
    pub records: Vec<TextureRecord>,
    /// Images stored at a lower resolution to fit (image index, the divisor).
    pub reduced: Vec<(usize, u32)>,
}

/// An image at 1/`k` of its resolution in each direction (box average of each k × k block in
/// linear light, encoded back to sRGB), as RGBA8 rows.
fn reduced_rgba(img: &crate::scene::texture::Image, k: u32) -> (u32, u32, Vec<u8>) {
    let (w, h) = (img.width().div_ceil(k), img.height().div_ceil(k));
    let nearest = crate::scene::texture::TextureRef {
        image: 0,
        tex_coord: 0,
        wrap_s: crate::scene::texture::Wrap::ClampToEdge,
        wrap_t: crate::scene::texture::Wrap::ClampToEdge,
        filter: crate::scene::texture::Filter::Nearest,
    };
    let encode = crate::scene::texture::linear_to_srgb8;
    let mut out = Vec::with_capacity((w * h * 4) as usize);
    for j in 0..h {
        for i in 0..w {
            let mut sum = [0.0f64; 3];
            let mut n = 0.0;
            for y in (j * k)..((j + 1) * k).min(img.height()) {
                for x in (i * k)..((i + 1) * k).min(img.width()) {
                    let u = (f64::from(x) + 0.5) / f64::from(img.width());
                    let v = (f64::from(y) + 0.5) / f64::from(img.height());
                    let t = img.sample_linear(u, v, &nearest);
                    (0..3).for_each(|c| sum[c] += t[c]);
                    n += 1.0;
                }
            }
            out.extend_from_slice(&[encode(sum[0] / n), encode(sum[1] / n), encode(sum[2] / n), 255]);
        }
    }
    (w, h, out)
}

impl TextureAtlas {
    /// Packs the images that `scene`'s materials use as base colour into shelves of an atlas at
    /// most `max_side` texels wide and high; images are halved (box average in linear light) until
    /// all fit.
    ///
    /// Errors: `InvalidArgument` (`Arg::Scene`) when even 1 × 1 texel images would not fit (more
    /// images than the atlas has texels); `OutOfMemory` when the atlas cannot be allocated.
    pub fn of(scene: &Scene, max_side: u32) -> Result<TextureAtlas, GpuError> {
        let used: Vec<usize> = {
            let mut v: Vec<usize> = scene
                .materials()
                .iter()
                .filter_map(|m| m.base_color_texture.as_ref().map(|t| t.image))
                .filter(|&i| i < scene.images().len())
                .collect();
            v.sort_unstable();
            v.dedup();
            v
        };
        let side = max_side.clamp(1, shadows::MAX_ATLAS_SIDE);
        // Shelf packing at divisor k for every image; k doubles until it fits.
        let mut k = 1u32;
        let (size, places) = loop {
            if k > 1 << 24 {
                return Err(GpuError::invalid(
                    Arg::Scene,
                    format!("{} texture images do not fit a {side} × {side} atlas", used.len()),
                ));
            }
            let mut places = Vec::with_capacity(used.len());
            let (mut x, mut y, mut shelf, mut width) = (0u32, 0u32, 0u32, 1u32);
            let mut fits = true;
            for &i in &used {
                let img = &scene.images()[i];
                let (w, h) = (img.width().div_ceil(k), img.height().div_ceil(k));
                if w > side || h > side {
                    fits = false;
                    break;
                }
                if x + w > side {
                    y += shelf;
                    x = 0;
                    shelf = 0;
                }
                places.push((x, y, w, h));
                x += w;
                shelf = shelf.max(h);
                width = width.max(x);
            }
            if fits && y + shelf <= side {
                break ((width, (y + shelf).max(1)), places);
            }
            k *= 2;
        };
        let n = size.0 as usize * size.1 as usize * 4;
        let mut texels = crate::files::try_vec::<u8>(n, "the scene's texture atlas")
            .map_err(|e| GpuError::OutOfMemory(e.to_string()))?;
        texels.resize(n, 0);
        let mut reduced = Vec::new();
        for (&i, &(x, y, w, _)) in used.iter().zip(&places) {
            if k > 1 {
                reduced.push((i, k));
            }
            let (_, h, rows) = reduced_rgba(&scene.images()[i], k);
            for r in 0..h {
                let src = &rows[(r * w * 4) as usize..((r + 1) * w * 4) as usize];
                let o = (((y + r) * size.0 + x) * 4) as usize;
                texels[o..o + src.len()].copy_from_slice(src);
            }
        }
        let mut records = Vec::new();
        let record_of_material = scene
            .materials()
            .iter()
            .map(|m| {
                let t = m.base_color_texture.as_ref()?;
                let slot = used.iter().position(|&i| i == t.image)?;
                let (x, y, w, h) = places[slot];
                let wrap = |w: crate::scene::texture::Wrap| match w {
                    crate::scene::texture::Wrap::Repeat => 0,
                    crate::scene::texture::Wrap::ClampToEdge => 1,
                    crate::scene::texture::Wrap::MirroredRepeat => 2,
                };
                records.push(TextureRecord {
                    rect: [x, y, w, h],
                    mode: [
                        wrap(t.wrap_s),
                        wrap(t.wrap_t),
                        u32::from(t.filter == crate::scene::texture::Filter::Linear),
                        0,
                    ],
                });
                Some(records.len() as u32 - 1)
            })
            .collect();
        Ok(TextureAtlas {
            size,
            texels,
            record_of_material,
            records,
            reduced,
        })
    }
}

/// The vertices of a scene as the pass draws them (see the module's promises), with `atlas`'s
/// record of each textured material.
pub fn scene_vertices(scene: &Scene, atlas: &TextureAtlas) -> Vec<f32> {
    let mut out = Vec::with_capacity(scene.triangles().len() * 3 * VERTEX_FLOATS);
    for (t, (tri, m)) in scene.triangles().iter().zip(scene.material_of()).enumerate() {
        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero().as_vec3();
        let material = scene.materials().get(*m as usize);
        let rho = material.map_or([1.0; 3], |m| m.base_color_factor.map(|c| c as f32));
        let record = atlas
            .record_of_material
            .get(*m as usize)
            .copied()
            .flatten()
            .map_or(0.0, |r| (r + 1) as f32);
        let uvs = scene.uvs().get(t).copied().unwrap_or([[0.0; 2]; 3]);
        for (v, uv) in tri.iter().zip(uvs) {
            let p = v.as_vec3();
            out.extend_from_slice(&[
                p.x, p.y, p.z, n.x, n.y, n.z, rho[0], rho[1], rho[2], uv[0], uv[1], record,
            ]);
        }
    }
    out
}

/// A scene on the GPU.
#[derive(Debug)]
struct SceneMesh {
    vertices: wgpu::Buffer,
    count: u32,
    generation: u64,
    /// The base-colour texture atlas (sRGB) and its records.
    textures: wgpu::TextureView,
    texture_records: wgpu::Buffer,
    /// Images stored at a lower resolution to fit the atlas.
    reduced_textures: usize,
}

/// The intensity tables of the photometries of the last frame.
#[derive(Debug)]
struct IntensityAtlas {
    /// Held, so that an address is never reused for another photometry while it is compared.
    photometries: Vec<Arc<Photometry>>,
    view: wgpu::TextureView,
    per_row: u32,
    max_cd: Vec<f32>,
}

/// The shadow maps of the last frame and what they were rendered for.
#[derive(Debug)]
struct ShadowCache {
    /// Scene generation, layout and number of luminaires the atlas was made for.
    key: (u64, ShadowLayout, usize),
    view: wgpu::TextureView,
    /// Per luminaire (index in the frame's list), the centre its faces were rendered from.
    rendered: Vec<Option<[u32; 3]>>,
}

/// What the scene pass used for its last frame (for benchmarks and reports).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SceneStats {
    /// Luminaires lighting the scene.
    pub luminaires: usize,
    /// Virtual point lights gathered per pixel (0: no inter-reflection).
    pub vpls: u32,
    /// Side of each shadow cube face, pixels (0: no shadows).
    pub shadow_face_px: u32,
    /// Frames that rendered shadow maps since the pass was made.
    pub shadow_renders: u64,
    /// Luminaires whose six faces were rendered, summed over those frames.
    pub shadow_lights_rendered: u64,
    /// Luminaires whose shadow maps were left for a later frame (moved, beyond the per-frame
    /// budget) in the last frame.
    pub shadows_pending: usize,
    /// Base-colour images of the scene stored at a lower resolution to fit the texture atlas.
    pub reduced_textures: usize,
    /// Times the virtual point lights were made since the pass was made.
    pub vpl_generations: u64,
}

/// One virtual point light as the shader reads it (`Vpl` in shaders/scene/lighting.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VplRecord {
    /// Position, world metres (w unused).
    pub position: [f32; 4],
    /// Unit normal of the lit side (w unused).
    pub normal: [f32; 4],
    /// Reflected flux per channel, lm (w unused).
    pub flux: [f32; 4],
}

/// The VPLs of the last frame and what they were made for.
#[derive(Debug)]
struct VplCache {
    /// Scene generation, each instance's photometry address and matrix bits, photons (the clamp
    /// is a uniform: changing it needs no new VPLs).
    key: (u64, Vec<(usize, [u32; 16])>, u32),
    buffer: wgpu::Buffer,
    count: u32,
    /// Held, so that an address in the key is never reused for another photometry.
    _photometries: Vec<Arc<Photometry>>,
}

/// What a scene pipeline drawing into the frame is specialised for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct PipelineKey {
    color: ColorFormat,
    depth_copy: bool,
    reversed_z: bool,
    /// The composite of the compute lighting's pixels (true) or the scene's triangles lit per
    /// fragment (false).
    deferred: bool,
}

/// Format of the compute lighting's surface buffers and of its lit colours.
const SURFACE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// `NO_SURFACE` in shaders/scene/lighting.wgsl: the clear value of a pixel's normal where no
/// surface is.
const NO_SURFACE: f64 = 2.0;

/// The compute lighting's per-pixel buffers for frames of one size (`fs_surface`, `cs_lighting`
/// and shaders/scene/composite.wgsl say what each holds).
#[derive(Debug)]
struct SurfaceBuffers {
    size: (u32, u32),
    surface: wgpu::TextureView,
    facing: wgpu::TextureView,
    depth: wgpu::TextureView,
    /// `cs_lighting`'s group 1: surface, facing, lit colour.
    lighting_bind: wgpu::BindGroup,
    /// The composite's group 0: lit colour, depth.
    composite_bind: wgpu::BindGroup,
}

/// Pipelines, layouts and the uploaded scene of the scene lighting pass.
#[derive(Debug)]
pub struct ScenePass {
    module: wgpu::ShaderModule,
    frame_layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    pipelines: HashMap<PipelineKey, wgpu::RenderPipeline>,
    composite_module: wgpu::ShaderModule,
    composite_layout: wgpu::BindGroupLayout,
    composite_pipeline_layout: wgpu::PipelineLayout,
    lighting_layout: wgpu::BindGroupLayout,
    /// The G-buffer pass, for forward depth (index 0) and reversed depth (index 1).
    surface_pipelines: [wgpu::RenderPipeline; 2],
    lighting_pipeline: wgpu::ComputePipeline,
    surfaces: Option<SurfaceBuffers>,
    face_layout: wgpu::BindGroupLayout,
    shadow_pipeline: wgpu::RenderPipeline,
    /// Clears a face's square to the far depth (before it is rendered again).
    clear_pipeline: wgpu::RenderPipeline,
    /// Where the next frame's round of shadow updates starts.
    shadow_cursor: usize,
    faces: DrawSlots,
    mesh: Option<SceneMesh>,
    settings: SceneSettings,
    tables: Option<IntensityAtlas>,
    shadows: Option<ShadowCache>,
    placeholder_depth: wgpu::TextureView,
    placeholder_table: wgpu::TextureView,
    generations: u64,
    /// The scene on the CPU (photons are traced through it) and its hierarchy, built on first use.
    cpu: Option<(Arc<Scene>, Option<Arc<Bvh>>)>,
    /// Emission tables of the photometries seen, kept while they are.
    emission: Vec<(Arc<Photometry>, Arc<EmissionTable>)>,
    vpls: Option<VplCache>,
    /// A one-VPL zero buffer bound when there is no inter-reflection.
    no_vpls: wgpu::Buffer,
    stats: SceneStats,
}

fn texture_entry(binding: u32, sample_type: wgpu::TextureSampleType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

fn storage_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn texture(ctx: &GpuContext, label: &str, w: u32, h: u32, format: wgpu::TextureFormat) -> wgpu::Texture {
    ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_DST
            | if format == wgpu::TextureFormat::Depth32Float {
                wgpu::TextureUsages::RENDER_ATTACHMENT
            } else {
                wgpu::TextureUsages::empty()
            },
        view_formats: &[],
    })
}

/// A pipeline that writes only Depth32Float (the shadow atlas): `entry` of `module`, no culling,
/// depth written where `compare` passes.
fn depth_only_pipeline(
    ctx: &GpuContext,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
    buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
    compare: wgpu::CompareFunction,
) -> wgpu::RenderPipeline {
    ctx.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            buffers,
        },
        primitive: wgpu::PrimitiveState {
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: wgpu::TextureFormat::Depth32Float,
            depth_write_enabled: Some(true),
            depth_compare: Some(compare),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        }),
        multisample: wgpu::MultisampleState::default(),
        fragment: None,
        multiview_mask: None,
        cache: None,
    })
}

/// The G-buffer pass of the compute lighting: the scene's triangles with the frame's depth test
/// (`reversed_z`: nearer is greater), each pixel's nearest surface written by `fs_surface`.
fn surface_pipeline(
    ctx: &GpuContext,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    reversed_z: bool,
) -> wgpu::RenderPipeline {
    let target = Some(wgpu::ColorTargetState {
        format: SURFACE_FORMAT,
        blend: None,
        write_mask: wgpu::ColorWrites::ALL,
    });
    ctx.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("scene surfaces"),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_scene"),
            compilation_options: Default::default(),
            buffers: &[Some(SCENE_LAYOUT)],
        },
        primitive: wgpu::PrimitiveState {
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(frame_depth_state(reversed_z)),
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some("fs_surface"),
            compilation_options: Default::default(),
            targets: &[target.clone(), target],
        }),
        multiview_mask: None,
        cache: None,
    })
}

fn storage_buffer(ctx: &GpuContext, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: (bytes.len() as u64).max(16).next_multiple_of(4),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::UNIFORM,
        mapped_at_creation: false,
    });
    if !bytes.is_empty() {
        ctx.queue.write_buffer(&buf, 0, bytes);
    }
    buf
}

impl ScenePass {
    /// Compiles the shaders and creates the layouts; no scene yet.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        ctx.scoped("creating the scene pass", || {
            let module = ctx.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("scene/lighting.wgsl"),
                source: wgpu::ShaderSource::Wgsl(super::shaders::scene().into()),
            });
            let shadow_module = ctx.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("scene/shadow.wgsl"),
                source: wgpu::ShaderSource::Wgsl(super::shaders::scene_shadow().into()),
            });
            let frame_layout = ctx.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("scene frame"),
                entries: &[
                    wgpu::BindGroupLayoutEntry {
                        binding: 0,
                        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE,
                        ty: wgpu::BindingType::Buffer {
                            ty: wgpu::BufferBindingType::Uniform,
                            has_dynamic_offset: false,
                            min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<SceneFrameUniform>() as u64),
                        },
                        count: None,
                    },
                    storage_entry(1),
                    storage_entry(2),
                    texture_entry(3, wgpu::TextureSampleType::Float { filterable: false }),
                    texture_entry(4, wgpu::TextureSampleType::Depth),
                    storage_entry(5),
                    texture_entry(6, wgpu::TextureSampleType::Float { filterable: false }),
                    storage_entry(7),
                ],
            });
            let pipeline_layout = ctx.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("scene"),
                bind_group_layouts: &[Some(&frame_layout)],
                immediate_size: 0,
            });
            let unfilterable = wgpu::TextureSampleType::Float { filterable: false };
            let lighting_layout = ctx.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("scene lighting surfaces"),
                entries: &[
                    texture_entry(0, unfilterable),
                    texture_entry(1, unfilterable),
                    wgpu::BindGroupLayoutEntry {
                        binding: 2,
                        visibility: wgpu::ShaderStages::COMPUTE,
                        ty: wgpu::BindingType::StorageTexture {
                            access: wgpu::StorageTextureAccess::WriteOnly,
                            format: SURFACE_FORMAT,
                            view_dimension: wgpu::TextureViewDimension::D2,
                        },
                        count: None,
                    },
                ],
            });
            let lighting_pipeline_layout = ctx.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("scene lighting"),
                bind_group_layouts: &[Some(&frame_layout), Some(&lighting_layout)],
                immediate_size: 0,
            });
            let lighting_pipeline = ctx.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("scene lighting"),
                layout: Some(&lighting_pipeline_layout),
                module: &module,
                entry_point: Some("cs_lighting"),
                compilation_options: Default::default(),
                cache: None,
            });
            let surface_pipelines =
                [false, true].map(|reversed_z| surface_pipeline(ctx, &pipeline_layout, &module, reversed_z));
            let composite_module = ctx.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("scene/composite.wgsl"),
                source: wgpu::ShaderSource::Wgsl(super::shaders::scene_composite().into()),
            });
            let composite_layout = ctx.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("scene composite"),
                entries: &[
                    texture_entry(0, unfilterable),
                    texture_entry(1, wgpu::TextureSampleType::Depth),
                ],
            });
            let composite_pipeline_layout = ctx.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("scene composite"),
                bind_group_layouts: &[Some(&composite_layout)],
                immediate_size: 0,
            });
            let face_layout = ctx.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("shadow face"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<ShadowFaceUniform>() as u64),
                    },
                    count: None,
                }],
            });
            let shadow_layout = ctx.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("scene shadows"),
                bind_group_layouts: &[Some(&face_layout)],
                immediate_size: 0,
            });
            // Faces: the scene's depth, nearest kept (reversed depth). Clear: a face's square reset
            // to the far depth 0 whatever it held.
            let shadow_pipeline = depth_only_pipeline(
                ctx,
                "scene shadow faces",
                &shadow_layout,
                &shadow_module,
                "vs_shadow",
                &[Some(SHADOW_VERTEX_LAYOUT)],
                wgpu::CompareFunction::Greater,
            );
            let clear_pipeline = depth_only_pipeline(
                ctx,
                "scene shadow face clear",
                &shadow_layout,
                &shadow_module,
                "vs_clear",
                &[],
                wgpu::CompareFunction::Always,
            );
            let placeholder_depth = texture(ctx, "no shadow maps", 1, 1, wgpu::TextureFormat::Depth32Float)
                .create_view(&wgpu::TextureViewDescriptor::default());
            let placeholder_table = texture(ctx, "no intensity tables", 1, 1, wgpu::TextureFormat::R32Float)
                .create_view(&wgpu::TextureViewDescriptor::default());
            Ok(ScenePass {
                module,
                frame_layout,
                pipeline_layout,
                pipelines: HashMap::new(),
                composite_module,
                composite_layout,
                composite_pipeline_layout,
                lighting_layout,
                surface_pipelines,
                lighting_pipeline,
                surfaces: None,
                face_layout,
                shadow_pipeline,
                clear_pipeline,
                shadow_cursor: 0,
                faces: DrawSlots::new("shadow faces", wgpu::BufferUsages::UNIFORM),
                mesh: None,
                settings: SceneSettings::default(),
                tables: None,
                shadows: None,
                placeholder_depth,
                placeholder_table,
                generations: 0,
                cpu: None,
                emission: Vec::new(),
                vpls: None,
                no_vpls: storage_buffer(ctx, "no VPLs", bytemuck::bytes_of(&VplRecord::zeroed())),
                stats: SceneStats::default(),
            })
        })
    }

    /// Uploads `scene` (replacing any earlier one) and keeps it, with its hierarchy `bvh` if given
    /// (photons for inter-reflection are traced through them; the hierarchy is built on first use
    /// otherwise).
    ///
    /// Errors: `InvalidArgument` (`Arg::Scene`) for a scene with no triangles or one whose vertices
    /// do not fit the device's largest buffer; what creating the buffer reports.
    pub fn set_scene(&mut self, ctx: &GpuContext, scene: Arc<Scene>, bvh: Option<Arc<Bvh>>) -> Result<(), GpuError> {
        let bytes = scene.triangles().len() as u64 * 3 * (VERTEX_FLOATS as u64) * 4;
        if bytes == 0 {
            return Err(GpuError::invalid(Arg::Scene, "the scene has no triangles"));
        }
        let max = ctx.device.limits().max_buffer_size;
        if bytes > max {
            return Err(GpuError::invalid(
                Arg::Scene,
                format!(
                    "{} triangles need {bytes} bytes of vertices; the device's largest buffer is {max} bytes",
                    scene.triangles().len()
                ),
            ));
        }
        if let Some(b) = &bvh {
            if b.triangle_count() != scene.triangles().len() {
                return Err(GpuError::invalid(
                    Arg::Scene,
                    format!(
                        "the hierarchy given has {} triangles, the scene {}: it was built for another scene",
                        b.triangle_count(),
                        scene.triangles().len()
                    ),
                ));
            }
        }
        let atlas = TextureAtlas::of(&scene, ctx.device.limits().max_texture_dimension_2d)?;
        let vertices = scene_vertices(&scene, &atlas);
        let (buf, texture, records) = ctx.scoped("uploading a scene", || {
            let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("scene vertices"),
                size: bytes,
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            ctx.queue.write_buffer(&buf, 0, bytemuck::cast_slice(&vertices));
            let (w, h) = atlas.size;
            let tex = texture(ctx, "scene textures (sRGB)", w, h, wgpu::TextureFormat::Rgba8UnormSrgb);
            ctx.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &tex,
                    mip_level: 0,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::All,
                },
                &atlas.texels,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(w * 4),
                    rows_per_image: None,
                },
                wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
            );
            let records = if atlas.records.is_empty() {
                vec![TextureRecord::zeroed()]
            } else {
                atlas.records.clone()
            };
            let records = storage_buffer(ctx, "scene texture records", bytemuck::cast_slice(&records));
            Ok((buf, tex.create_view(&wgpu::TextureViewDescriptor::default()), records))
        })?;
        self.generations += 1;
        self.mesh = Some(SceneMesh {
            vertices: buf,
            count: (vertices.len() / VERTEX_FLOATS) as u32,
            generation: self.generations,
            textures: texture,
            texture_records: records,
            reduced_textures: atlas.reduced.len(),
        });
        self.shadows = None;
        self.vpls = None;
        self.cpu = Some((scene, bvh));
        Ok(())
    }

    /// Removes the scene: frames draw no room (the per-pixel lighting images are freed too).
    pub fn clear_scene(&mut self) {
        self.mesh = None;
        self.shadows = None;
        self.tables = None;
        self.vpls = None;
        self.cpu = None;
        self.emission.clear();
        self.surfaces = None;
    }

    /// The virtual point lights of `instances` (made again when the scene, a luminaire or the
    /// settings changed; an empty set without a scene or with indirect light off): the count
    /// uploaded.
    ///
    /// Errors: `InvalidArgument` (`Arg::Instance`) for an instance whose model matrix scales,
    /// shears or mirrors (photons need a rotation and a translation); what uploading reports.
    fn virtual_lights(&mut self, ctx: &GpuContext, instances: &[(Arc<Photometry>, Mat4)]) -> Result<u32, GpuError> {
        let settings = self.settings;
        let (Some(mesh), Some((scene, bvh))) = (&self.mesh, &mut self.cpu) else {
            return Ok(0);
        };
        if !settings.indirect || instances.is_empty() {
            return Ok(0);
        }
        let key = (
            mesh.generation,
            instances
                .iter()
                .map(|(l, m)| (Arc::as_ptr(l) as usize, m.to_cols_array().map(f32::to_bits)))
                .collect::<Vec<_>>(),
            settings.bounce_photons,
        );
        if let Some(v) = &self.vpls {
            if v.key == key {
                return Ok(v.count);
            }
        }
        let scene = scene.clone();
        let bvh = bvh.get_or_insert_with(|| Arc::new(Bvh::build(&scene))).clone();
        // Emission tables: kept for the photometries still in use, made for new ones.
        self.emission
            .retain(|(p, _)| instances.iter().any(|(l, _)| Arc::ptr_eq(p, l)));
        let mut tables = Vec::with_capacity(instances.len());
        let mut luminaires = Vec::with_capacity(instances.len());
        for (lum, model) in instances {
            let table = match self.emission.iter().find(|(p, _)| Arc::ptr_eq(p, lum)) {
                Some((_, t)) => t.clone(),
                None => {
                    let t = Arc::new(EmissionTable::of(lum));
                    self.emission.push((lum.clone(), t.clone()));
                    t
                }
            };
            tables.push(table);
            luminaires.push(SceneLuminaire {
                photometry: lum.clone(),
                scene_from_luminaire: model.as_dmat4(),
            });
        }
        let opts = VplOptions {
            photons: settings.bounce_photons as usize,
            clamp_m: f64::from(settings.vpl_clamp_m),
            ..VplOptions::default()
        };
        let set = VplSet::generate_with(&scene, &bvh, &luminaires, &tables, &opts).map_err(|e| {
            GpuError::invalid(
                Arg::Instance,
                format!("inter-reflection (`luminaires[i]` is the i-th instance in creation order): {e}"),
            )
        })?;
        let records: Vec<VplRecord> = set
            .vpls
            .iter()
            .map(|v| VplRecord {
                position: [v.position_m.x as f32, v.position_m.y as f32, v.position_m.z as f32, 0.0],
                normal: [v.normal.x as f32, v.normal.y as f32, v.normal.z as f32, 0.0],
                flux: [
                    v.flux_rgb_lm[0] as f32,
                    v.flux_rgb_lm[1] as f32,
                    v.flux_rgb_lm[2] as f32,
                    0.0,
                ],
            })
            .collect();
        let max_binding = ctx.device.limits().max_storage_buffer_binding_size;
        let bytes = std::mem::size_of_val(records.as_slice()) as u64;
        if bytes > max_binding {
            return Err(GpuError::invalid(
                Arg::BouncePhotons,
                format!(
                    "{} photons left {} virtual point lights ({bytes} bytes), more than the device's {max_binding} a \
                     binding: ask for fewer",
                    settings.bounce_photons,
                    records.len()
                ),
            ));
        }
        let count = records.len() as u32;
        let buffer = ctx.scoped("uploading virtual point lights", || {
            Ok(storage_buffer(ctx, "scene VPLs", bytemuck::cast_slice(&records)))
        })?;
        self.stats.vpl_generations += 1;
        self.vpls = Some(VplCache {
            key,
            buffer,
            count,
            _photometries: instances.iter().map(|(l, _)| l.clone()).collect(),
        });
        Ok(count)
    }

    /// What the last frame used.
    pub fn stats(&self) -> SceneStats {
        self.stats
    }

    /// Whether a scene is loaded.
    pub fn has_scene(&self) -> bool {
        self.mesh.is_some()
    }

    /// The lighting settings.
    pub fn settings(&self) -> SceneSettings {
        self.settings
    }

    /// Sets the lighting settings (checked by [`SceneSettings::validate`]).
    pub fn set_settings(&mut self, settings: SceneSettings) -> Result<(), GpuError> {
        settings.validate()?;
        self.settings = settings;
        Ok(())
    }

    /// The intensity atlas for the photometries of `instances` (rebuilt when they change) and each
    /// instance's table index.
    fn intensity_tables(
        &mut self,
        ctx: &GpuContext,
        instances: &[(Arc<Photometry>, Mat4)],
    ) -> Result<Vec<u32>, GpuError> {
        let mut distinct: Vec<Arc<Photometry>> = Vec::new();
        let mut index = Vec::with_capacity(instances.len());
        for (lum, _) in instances {
            let i = distinct.iter().position(|p| Arc::ptr_eq(p, lum)).unwrap_or_else(|| {
                distinct.push(lum.clone());
                distinct.len() - 1
            });
            index.push(i as u32);
        }
        if distinct.len() > MAX_INTENSITY_TABLES {
            return Err(GpuError::invalid(
                Arg::Luminaire,
                format!(
                    "the scene is lit by {} distinct photometries; the intensity atlas holds {MAX_INTENSITY_TABLES}",
                    distinct.len()
                ),
            ));
        }
        if self.tables.as_ref().is_some_and(|t| {
            t.photometries.len() == distinct.len()
                && t.photometries.iter().zip(&distinct).all(|(a, b)| Arc::ptr_eq(a, b))
        }) {
            return Ok(index);
        }
        // As many tables a row and rows as the device's largest 2D texture holds (8192 on
        // lavapipe; 2048 on the smallest devices wgpu supports: 2 × 5 tables).
        let max_side = ctx.device.limits().max_texture_dimension_2d;
        let fit_row = (max_side / INTENSITY_TABLE_W).min(MAX_TABLES_PER_ROW);
        let fit_rows = max_side / INTENSITY_TABLE_H;
        if distinct.len() as u64 > u64::from(fit_row) * u64::from(fit_rows) {
            return Err(GpuError::invalid(
                Arg::Luminaire,
                format!(
                    "the scene is lit by {} distinct photometries; this device's {max_side}-texel textures hold {} \
                     intensity tables",
                    distinct.len(),
                    fit_row * fit_rows
                ),
            ));
        }
        let per_row = (distinct.len() as u32).clamp(1, fit_row);
        let rows = (distinct.len() as u32).div_ceil(per_row).max(1);
        let (w, h) = (per_row * INTENSITY_TABLE_W, rows * INTENSITY_TABLE_H);
        let mut max_cd = vec![0.0f32; distinct.len()];
        let view = ctx.scoped("uploading intensity tables", || {
            let tex = texture(ctx, "intensity tables (cd)", w, h, wgpu::TextureFormat::R32Float);
            for (t, photometry) in distinct.iter().enumerate() {
                let table = lights::intensity_table(photometry);
                max_cd[t] = table.iter().copied().fold(0.0, f32::max);
                let (col, row) = (t as u32 % per_row, t as u32 / per_row);
                ctx.queue.write_texture(
                    wgpu::TexelCopyTextureInfo {
                        texture: &tex,
                        mip_level: 0,
                        origin: wgpu::Origin3d {
                            x: col * INTENSITY_TABLE_W,
                            y: row * INTENSITY_TABLE_H,
                            z: 0,
                        },
                        aspect: wgpu::TextureAspect::All,
                    },
                    bytemuck::cast_slice(&table),
                    wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(INTENSITY_TABLE_W * 4),
                        rows_per_image: None,
                    },
                    wgpu::Extent3d {
                        width: INTENSITY_TABLE_W,
                        height: INTENSITY_TABLE_H,
                        depth_or_array_layers: 1,
                    },
                );
            }
            Ok(tex.create_view(&wgpu::TextureViewDescriptor::default()))
        })?;
        self.tables = Some(IntensityAtlas {
            photometries: distinct,
            view,
            per_row,
            max_cd,
        });
        Ok(index)
    }

    /// Renders the shadow maps of `records`: all of them into a new atlas when the scene or the
    /// layout changed; otherwise only those of luminaires whose centre moved since their faces were
    /// rendered, at most `SceneSettings::shadow_updates_per_frame` of them (lowest index first; the
    /// rest keep their old faces until a later frame).
    fn shadow_maps(&mut self, ctx: &GpuContext, records: &[LightRecord], layout: ShadowLayout) -> Result<(), GpuError> {
        let Some(mesh) = &self.mesh else {
            return Ok(());
        };
        let centres: Vec<[u32; 3]> = records
            .iter()
            .map(|r| [r.centre[0].to_bits(), r.centre[1].to_bits(), r.centre[2].to_bits()])
            .collect();
        // A new number of luminaires renders all: luminaires are slots by their place in the
        // list, which shifts when one is added or removed.
        let key = (mesh.generation, layout, records.len());
        let fresh = !self.shadows.as_ref().is_some_and(|s| s.key == key);
        let rendered: Vec<Option<[u32; 3]>> = match &self.shadows {
            Some(s) if !fresh => s.rendered.clone(),
            _ => Vec::new(),
        };
        // Round robin from where the last frame stopped, so that none waits forever.
        let n = records.len();
        let cursor = self.shadow_cursor % n.max(1);
        let stale: Vec<usize> = (0..n)
            .map(|k| (cursor + k) % n)
            .filter(|&i| rendered.get(i).copied().flatten() != Some(centres[i]))
            .collect();
        let budget = if fresh {
            usize::MAX
        } else {
            self.settings.shadow_updates_per_frame as usize
        };
        let now: Vec<usize> = stale.iter().copied().take(budget).collect();
        if let Some(&last) = now.last() {
            self.shadow_cursor = (last + 1) % n.max(1);
        }
        self.stats.shadows_pending = stale.len() - now.len();
        if now.is_empty() {
            return Ok(());
        }
        let mut faces = Vec::with_capacity(now.len() * 6);
        for &i in &now {
            let c = Vec3::from_array(records[i].centre[..3].try_into().unwrap_or([0.0; 3]));
            for f in 0..6 {
                faces.push(ShadowFaceUniform {
                    clip_from_world: face_clip_from_world(c, f).to_cols_array_2d(),
                });
            }
        }
        let view = match (&self.shadows, fresh) {
            (Some(s), false) => s.view.clone(),
            _ => texture(
                ctx,
                "shadow atlas",
                layout.width,
                layout.height,
                wgpu::TextureFormat::Depth32Float,
            )
            .create_view(&wgpu::TextureViewDescriptor::default()),
        };
        ctx.scoped("rendering shadow maps", || {
            let bind = self.faces.write(ctx, &self.face_layout, &faces).clone();
            let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("scene shadow maps"),
            });
            {
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("scene shadow maps"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &view,
                        depth_ops: Some(wgpu::Operations {
                            load: if fresh {
                                wgpu::LoadOp::Clear(0.0)
                            } else {
                                wgpu::LoadOp::Load
                            },
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                for (k, &light) in now.iter().enumerate() {
                    for f in 0..6 {
                        let (x, y) = layout.face_origin(light, f);
                        let s = layout.face_px;
                        pass.set_viewport(x as f32, y as f32, s as f32, s as f32, 0.0, 1.0);
                        pass.set_scissor_rect(x, y, s, s);
                        pass.set_bind_group(0, &bind, &[((6 * k + f) as u64 * SLOT) as u32]);
                        if !fresh {
                            pass.set_pipeline(&self.clear_pipeline);
                            pass.draw(0..3, 0..1);
                        }
                        pass.set_pipeline(&self.shadow_pipeline);
                        pass.set_vertex_buffer(0, mesh.vertices.slice(..));
                        pass.draw(0..mesh.count, 0..1);
                    }
                }
            }
            ctx.queue.submit([enc.finish()]);
            Ok(())
        })?;
        let mut rendered = rendered;
        rendered.resize(records.len(), None);
        rendered.truncate(records.len());
        for &i in &now {
            rendered[i] = Some(centres[i]);
        }
        self.stats.shadow_renders += 1;
        self.stats.shadow_lights_rendered += now.len() as u64;
        self.shadows = Some(ShadowCache { key, view, rendered });
        Ok(())
    }

    /// The compute lighting's buffers for frames of `width` × `height` pixels (made again when the
    /// size changed).
    fn surface_buffers(&mut self, ctx: &GpuContext, width: u32, height: u32) -> Result<(), GpuError> {
        if self.surfaces.as_ref().is_some_and(|b| b.size == (width, height)) {
            return Ok(());
        }
        // The old buffers go first: two frame sizes' worth need not fit at once.
        self.surfaces = None;
        let made = ctx.scoped("making the scene lighting's per-pixel buffers", || {
            let make = |label: &str, format: wgpu::TextureFormat, usage: wgpu::TextureUsages| {
                ctx.device
                    .create_texture(&wgpu::TextureDescriptor {
                        label: Some(label),
                        size: wgpu::Extent3d {
                            width,
                            height,
                            depth_or_array_layers: 1,
                        },
                        mip_level_count: 1,
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D2,
                        format,
                        usage: usage | wgpu::TextureUsages::TEXTURE_BINDING,
                        view_formats: &[],
                    })
                    .create_view(&wgpu::TextureViewDescriptor::default())
            };
            let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
            let surface = make("scene surfaces", SURFACE_FORMAT, attachment);
            let facing = make("scene surface normals", SURFACE_FORMAT, attachment);
            let depth = make("scene surface depth", wgpu::TextureFormat::Depth32Float, attachment);
            let lit = make("scene lit colour", SURFACE_FORMAT, wgpu::TextureUsages::STORAGE_BINDING);
            let lighting_bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("scene lighting surfaces"),
                layout: &self.lighting_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&surface),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&facing),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::TextureView(&lit),
                    },
                ],
            });
            let composite_bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("scene composite"),
                layout: &self.composite_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&lit),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&depth),
                    },
                ],
            });
            Ok(SurfaceBuffers {
                size: (width, height),
                surface,
                facing,
                depth,
                lighting_bind,
                composite_bind,
            })
        })?;
        self.surfaces = Some(made);
        Ok(())
    }

    fn pipeline(&mut self, ctx: &GpuContext, key: PipelineKey) -> Result<wgpu::RenderPipeline, GpuError> {
        if let Some(p) = self.pipelines.get(&key) {
            return Ok(p.clone());
        }
        let p = ctx.scoped("creating a scene pipeline", || {
            let targets = &frame_color_targets(key.color, key.depth_copy);
            // The compute lighting's composite (a full-screen triangle), or the triangles lit per
            // fragment; the entry with the R32F depth output when the target has one.
            let (label, layout, module, vs, buffers, fs) = if key.deferred {
                (
                    "scene composite",
                    &self.composite_pipeline_layout,
                    &self.composite_module,
                    "vs_composite",
                    &[][..],
                    ["fs_composite", "fs_composite_color_only"],
                )
            } else {
                (
                    "scene lighting",
                    &self.pipeline_layout,
                    &self.module,
                    "vs_scene",
                    &[Some(SCENE_LAYOUT)][..],
                    ["fs_scene", "fs_scene_color_only"],
                )
            };
            Ok(ctx.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState {
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: Some(frame_depth_state(key.reversed_z)),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module,
                    entry_point: Some(fs[usize::from(!key.depth_copy)]),
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

impl Pass for ScenePass {
    /// A luminaire's photometry lighting the scene (a far-field file's, or a scan's far field) and
    /// its model matrix (luminaire frame → world).
    type Instance = (Arc<Photometry>, Mat4);
    type Prepared = SceneFrame;

    /// Prepares a frame: intensity tables, luminaire records, shadow maps (rendered and submitted
    /// here when they changed), tile lists for the view, the frame's bindings.
    fn prepare(
        &mut self,
        ctx: &GpuContext,
        view: &FrameView,
        instances: &[Self::Instance],
    ) -> Result<SceneFrame, GpuError> {
        if self.mesh.is_none() {
            return Ok(SceneFrame::default());
        }
        let settings = self.settings;
        let table_of = self.intensity_tables(ctx, instances)?;
        let (per_row, max_cd) = match &self.tables {
            Some(t) => (t.per_row, t.max_cd.clone()),
            None => (1, Vec::new()),
        };
        let records: Vec<LightRecord> = instances
            .iter()
            .zip(&table_of)
            .enumerate()
            .map(|(i, ((lum, model), t))| {
                let placed = PlacedLight {
                    photometry: lum,
                    model: *model,
                    table: *t,
                    max_cd: max_cd.get(*t as usize).copied().unwrap_or(0.0),
                };
                lights::light_record(&placed, i, settings.lux_floor_lx)
            })
            .collect();
        let shadows_on = settings.shadows && !records.is_empty();
        self.stats.shadows_pending = 0;
        let layout = if shadows_on {
            let max_side = ctx.device.limits().max_texture_dimension_2d;
            let layout = ShadowLayout::new(
                records.len(),
                settings.shadow_budget_bytes,
                settings.max_face_px,
                max_side,
            )?;
            self.shadow_maps(ctx, &records, layout)?;
            Some(layout)
        } else {
            None
        };
        let target = view.target();
        let clip_from_world = view.clip_from_world();
        let (tiles_x, tiles_y, lists) = lights::tile_lists(clip_from_world, target.width, target.height, &records);
        let max_binding = ctx.device.limits().max_storage_buffer_binding_size;
        if 4 * lists.len() as u64 > max_binding {
            return Err(GpuError::invalid(
                Arg::Luminaire,
                format!(
                    "the per-tile light lists of {} luminaires at {}×{} take {} bytes, more than the device's {} \
                     a binding: raise the lux floor (SceneSettings::lux_floor_lx, now {} lx) or use fewer luminaires",
                    records.len(),
                    target.width,
                    target.height,
                    4 * lists.len(),
                    max_binding,
                    settings.lux_floor_lx
                ),
            ));
        }
        let vpl_count = self.virtual_lights(ctx, instances)?;
        self.stats.luminaires = records.len();
        self.stats.reduced_textures = self.mesh.as_ref().map_or(0, |m| m.reduced_textures);
        self.stats.vpls = vpl_count;
        self.stats.shadow_face_px = layout.map_or(0, |l| l.face_px);
        let options = view.options();
        let uniform = SceneFrameUniform {
            clip_from_world: clip_from_world.to_cols_array_2d(),
            eye: view.camera().eye_in(Mat4::IDENTITY).to_array(),
            params: [
                options.exposure,
                view.output_flag(),
                settings.lux_floor_lx,
                settings.vpl_clamp_m * settings.vpl_clamp_m,
            ],
            tiles: [lights::TILE_PX, tiles_x, tiles_y, records.len() as u32],
            atlas: [
                per_row,
                layout.map_or(1, |l| l.per_row),
                layout.map_or(1, |l| l.face_px),
                u32::from(layout.is_some()),
            ],
            indirect: [vpl_count, 0, 0, 0],
        };
        // Lit once per pixel when the frame's per-pixel images fit; a device out of memory for
        // them lights per fragment instead (the same frame, slower).
        let deferred = u64::from(target.width) * u64::from(target.height) <= settings.deferred_max_pixels
            && match self.surface_buffers(ctx, target.width, target.height) {
                Ok(()) => true,
                Err(GpuError::OutOfMemory(_)) => false,
                Err(e) => return Err(e),
            };
        let key = PipelineKey {
            color: target.color,
            depth_copy: target.depth == DepthFormat::R32Float,
            reversed_z: view.camera().reversed_z,
            deferred,
        };
        let pipeline = self.pipeline(ctx, key)?;
        let Some(mesh) = &self.mesh else {
            return Ok(SceneFrame::default());
        };
        let bind = ctx.scoped("binding a scene frame", || {
            let frame_buf = storage_buffer(ctx, "scene frame", bytemuck::bytes_of(&uniform));
            let lights_buf = storage_buffer(ctx, "scene luminaires", bytemuck::cast_slice(&records));
            let lists_buf = storage_buffer(ctx, "scene tile lists", bytemuck::cast_slice(&lists));
            let tables = self.tables.as_ref().map_or(&self.placeholder_table, |t| &t.view);
            let shadow = match (&self.shadows, layout) {
                (Some(s), Some(_)) => &s.view,
                _ => &self.placeholder_depth,
            };
            Ok(ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("scene frame"),
                layout: &self.frame_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: frame_buf.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: lights_buf.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: lists_buf.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: wgpu::BindingResource::TextureView(tables),
                    },
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: wgpu::BindingResource::TextureView(shadow),
                    },
                    wgpu::BindGroupEntry {
                        binding: 5,
                        resource: match (&self.vpls, vpl_count) {
                            (Some(v), 1..) => v.buffer.as_entire_binding(),
                            _ => self.no_vpls.as_entire_binding(),
                        },
                    },
                    wgpu::BindGroupEntry {
                        binding: 6,
                        resource: wgpu::BindingResource::TextureView(&mesh.textures),
                    },
                    wgpu::BindGroupEntry {
                        binding: 7,
                        resource: mesh.texture_records.as_entire_binding(),
                    },
                ],
            }))
        })?;
        let Some(mesh) = &self.mesh else {
            return Ok(SceneFrame::default());
        };
        let Some(surfaces) = self.surfaces.as_ref().filter(|_| deferred) else {
            return Ok(SceneFrame {
                draw: Some(SceneDraw {
                    pipeline,
                    bind,
                    vertices: Some(mesh.vertices.clone()),
                    count: mesh.count,
                }),
            });
        };
        // The compute lighting: each pixel's surface (the G-buffer pass), then its light, submitted
        // now so that the frame's render pass composites it.
        ctx.scoped("lighting the scene", || {
            let far = if key.reversed_z { 0.0 } else { 1.0 };
            let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("scene lighting"),
            });
            {
                let clear = |c: wgpu::Color| wgpu::Operations {
                    load: wgpu::LoadOp::Clear(c),
                    store: wgpu::StoreOp::Store,
                };
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("scene surfaces"),
                    color_attachments: &[
                        Some(wgpu::RenderPassColorAttachment {
                            view: &surfaces.surface,
                            depth_slice: None,
                            resolve_target: None,
                            ops: clear(wgpu::Color::TRANSPARENT),
                        }),
                        Some(wgpu::RenderPassColorAttachment {
                            view: &surfaces.facing,
                            depth_slice: None,
                            resolve_target: None,
                            ops: clear(wgpu::Color {
                                r: NO_SURFACE,
                                g: 0.0,
                                b: 0.0,
                                a: 0.0,
                            }),
                        }),
                    ],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &surfaces.depth,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(far),
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(&self.surface_pipelines[usize::from(key.reversed_z)]);
                pass.set_bind_group(0, &bind, &[]);
                pass.set_vertex_buffer(0, mesh.vertices.slice(..));
                pass.draw(0..mesh.count, 0..1);
            }
            {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("scene lighting"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(&self.lighting_pipeline);
                pass.set_bind_group(0, &bind, &[]);
                pass.set_bind_group(1, &surfaces.lighting_bind, &[]);
                pass.dispatch_workgroups(target.width.div_ceil(8), target.height.div_ceil(8), 1);
            }
            ctx.queue.submit([enc.finish()]);
            Ok(())
        })?;
        Ok(SceneFrame {
            draw: Some(SceneDraw {
                pipeline,
                bind: surfaces.composite_bind.clone(),
                vertices: None,
                count: 3,
            }),
        })
    }

    fn record(&self, frame: &SceneFrame, pass: &mut wgpu::RenderPass<'_>) {
        let Some(d) = &frame.draw else {
            return;
        };
        pass.set_pipeline(&d.pipeline);
        pass.set_bind_group(0, &d.bind, &[]);
        if let Some(v) = &d.vertices {
            pass.set_vertex_buffer(0, v.slice(..));
        }
        pass.draw(0..d.count, 0..1);
    }
}

/// The scene's one draw of a frame: its triangles lit per fragment (with their vertices), or the
/// compute lighting's composite (a full-screen triangle, no vertex buffer).
#[derive(Debug)]
struct SceneDraw {
    pipeline: wgpu::RenderPipeline,
    bind: wgpu::BindGroup,
    vertices: Option<wgpu::Buffer>,
    count: u32,
}

/// One prepared frame of the scene pass (empty without a scene).
#[derive(Debug, Default)]
pub struct SceneFrame {
    draw: Option<SceneDraw>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::texture::{Filter, Image, TextureRef, Wrap};
    use crate::scene::{Material, SceneParts};
    use glam::DVec3;

    /// A scene of one triangle per image, each image `w × h` of one sRGB code per texel row.
    fn textured(sizes: &[(u32, u32)]) -> Scene {
        let mut p = SceneParts::default();
        for (k, &(w, h)) in sizes.iter().enumerate() {
            let texels = (0..w * h).map(|t| [(t / w) as u8, k as u8, 7]).collect();
            p.images.push(Image::from_srgb(w, h, texels).unwrap());
            p.materials.push(Material {
                base_color_factor: [1.0; 3],
                base_color_texture: Some(TextureRef {
                    image: k,
                    tex_coord: 0,
                    wrap_s: Wrap::MirroredRepeat,
                    wrap_t: Wrap::ClampToEdge,
                    filter: Filter::Linear,
                }),
            });
            p.triangles.push([DVec3::ZERO, DVec3::X, DVec3::Z]);
            p.material_of.push(k as u32);
            p.uvs.push([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
        }
        p.materials.push(Material::grey(0.5));
        p.triangles.push([DVec3::ZERO, DVec3::X, DVec3::Y]);
        p.material_of.push(sizes.len() as u32);
        p.uvs.push([[0.0; 2]; 3]);
        Scene::new(p).unwrap()
    }

    #[test]
    fn the_texture_atlas_holds_every_image_once_and_in_place() {
        let scene = textured(&[(5, 3), (2, 2), (7, 4)]);
        let a = TextureAtlas::of(&scene, 8).unwrap();
        assert!(a.reduced.is_empty());
        assert_eq!(a.records.len(), 3);
        assert_eq!(a.record_of_material, vec![Some(0), Some(1), Some(2), None]);
        assert!(a.size.0 <= 8 && a.size.1 <= 8);
        let rects: Vec<[u32; 4]> = a.records.iter().map(|r| r.rect).collect();
        for (k, r) in rects.iter().enumerate() {
            assert!(
                r[0] + r[2] <= a.size.0 && r[1] + r[3] <= a.size.1,
                "{r:?} in {:?}",
                a.size
            );
            for o in &rects[k + 1..] {
                let apart = r[0] + r[2] <= o[0] || o[0] + o[2] <= r[0] || r[1] + r[3] <= o[1] || o[1] + o[3] <= r[1];
                assert!(apart, "{r:?} overlaps {o:?}");
            }
            // Texel (x, y) of image k is (y, k, 7).
            for y in 0..r[3] {
                for x in 0..r[2] {
                    let i = (((r[1] + y) * a.size.0 + r[0] + x) * 4) as usize;
                    assert_eq!(&a.texels[i..i + 4], &[y as u8, k as u8, 7, 255]);
                }
            }
        }
        assert_eq!(a.records[0].mode, [2, 1, 1, 0]);
        // The vertices carry each material's record + 1 (0: untextured) and the UVs.
        let v = scene_vertices(&scene, &a);
        assert_eq!(v.len(), 4 * 3 * VERTEX_FLOATS);
        assert_eq!(v[VERTEX_FLOATS - 1], 1.0);
        assert_eq!(v[3 * VERTEX_FLOATS + VERTEX_FLOATS - 1], 2.0);
        assert_eq!(v[9 * VERTEX_FLOATS + VERTEX_FLOATS - 1], 0.0);
        assert_eq!(&v[VERTEX_FLOATS + 9..VERTEX_FLOATS + 11], &[1.0, 0.0]);
    }

    #[test]
    fn images_too_large_for_the_atlas_are_halved_until_they_fit() {
        let scene = textured(&[(16, 16), (16, 8)]);
        let a = TextureAtlas::of(&scene, 16).unwrap();
        assert_eq!(a.reduced, vec![(0, 2), (1, 2)]);
        assert_eq!(a.records[0].rect[2..], [8, 8]);
        assert_eq!(a.records[1].rect[2..], [8, 4]);
        // A 2 × 2 block of rows 0 and 1 (codes 0 and 1) averages in linear light.
        let want = {
            let lin = |c: u8| crate::scene::texture::srgb_to_linear(c);
            let m = (lin(0) + lin(1)) / 2.0;
            let s = if m <= 0.003_130_8 {
                12.92 * m
            } else {
                1.055 * m.powf(1.0 / 2.4) - 0.055
            };
            (s * 255.0).round() as u8
        };
        let r = a.records[0].rect;
        assert_eq!(a.texels[((r[1] * a.size.0 + r[0]) * 4) as usize], want);
        // More images than a 1 × 1 atlas has texels: an error, not a loop.
        assert!(TextureAtlas::of(&scene, 1).is_err());
    }
}
