//! Uploading a pack: camera records, selection tables, chunk map and the tile pool within the
//! budget ([`NearfieldPass::upload`]).

use std::sync::{Arc, Mutex};

use glam::DVec3;

use super::luminaire::NearfieldLuminaire;
use super::pass::NearfieldPass;
use super::records::{bounding_box, buffer_init, LumUniform, PoolLayout};
use super::{NearfieldOptions, MAX_PAGE_BYTES, MAX_POOL_PAGES};
use crate::gpu::context::GpuContext;
use crate::gpu::residency::{ChunkLayout, Residency, CHUNK_BYTES, EMPTY};
use crate::gpu::shaders::CAMERA_RECORD_VEC4S;
use crate::gpu::{Arg, GpuError};
use crate::nearfield::bvh::ProxyBvh;
use crate::nearfield::pack::Pack;
use crate::nearfield::select::lit_bound::LitDirections;
use crate::nearfield::select::view::content_radius_m;
use crate::nearfield::select::{Selection, SelectionGpu};

impl NearfieldPass {
    /// Uploads a pack: camera records, selection tables, chunk map, and the tile pool within
    /// `opts.budget_bytes` (the whole pack when it fits). `proxy` is a triangle list in the luminaire
    /// frame (m).
    ///
    /// The steps: check the inputs (`content_radius`); lay out the storage blocks on the CPU
    /// (`camera_records`, `selection_lists`, `geometry_block`, `check_binding_limits`,
    /// `luminaire_block`); create the fixed buffers (`FixedBuffers`); size and allocate the tile
    /// pool within the budget (`TilePool`); bind it all; upload every tile when the pool holds the
    /// whole pack (`NearfieldLuminaire::upload_all`).
    pub fn upload(
        &self,
        ctx: &GpuContext,
        pack: Arc<Pack>,
        proxy: Option<Vec<[f32; 3]>>,
        opts: &NearfieldOptions,
    ) -> Result<NearfieldLuminaire, GpuError> {
        let set = pack.rayset();
        let selection = Arc::new(Selection::build(set, &opts.selection)?);
        let chunks = ChunkLayout::new(&pack).map_err(|m| GpuError::invalid(Arg::Pack, m))?;
        let sphere = (set.sphere.centre_m, set.sphere.radius_m);
        let content = content_radius(&pack, sphere, proxy.as_deref(), opts)?;
        ctx.scoped("uploading a near-field luminaire", || {
            let cams = camera_records(&pack);
            let g = selection.gpu_data();
            let (lists, list_bases) = selection_lists(&g);
            let max_binding = ctx.device.limits().max_storage_buffer_binding_size.min(MAX_PAGE_BYTES);
            // A planar proxy cannot block itself: no hierarchy, and pipelines without the test.
            let bvh = proxy
                .as_deref()
                .filter(|p| !crate::nearfield::bvh::is_planar(p))
                .map(ProxyBvh::build)
                .transpose()?;
            let (geometry, bvh_bases, quad_base) = geometry_block(&g, bvh.as_ref());
            check_binding_limits(&cams, &geometry, &lists, max_binding)?;
            let lum_uniform = luminaire_block(&g, &chunks, sphere, content, list_bases, quad_base, bvh_bases, opts);
            let chunks_per_page = (max_binding / CHUNK_BYTES).max(1) as u32;
            let pool_layout = PoolLayout {
                tile_edge: pack.layout().tile_size,
                slot_words: chunks.slot_words,
                chunk_words: (CHUNK_BYTES / 4) as u32,
                page_chunks: chunks_per_page,
                table_per_chunk: chunks.entries_per_chunk,
                slots_per_chunk: chunks.slots_per_chunk,
            };
            let fixed = FixedBuffers::create(
                ctx,
                &lum_uniform,
                &cams,
                &geometry,
                &g.vertices,
                &lists,
                chunks.chunk_count() as usize,
                bounding_box(sphere.0, content),
                proxy.as_deref(),
            );
            let all = chunks.all_needed();
            let pool = TilePool::allocate(ctx, fixed.bytes(), all.len(), chunks_per_page, opts.budget_bytes)?;
            let gpu_bytes = fixed.bytes() + pool.bytes();
            let bind = self.bind_luminaire(ctx, &fixed, &pool);
            let fully_resident = pool.capacity as usize >= all.len();
            let lum = NearfieldLuminaire {
                pack: pack.clone(),
                selection: selection.clone(),
                sphere,
                content_radius_m: content,
                fully_resident: false,
                identity_map: false,
                residency: Mutex::new(Residency::new(chunks.chunk_count(), pool.capacity)),
                chunks,
                chunk_map: fixed.chunk_map,
                misses: fixed.misses,
                pages: pool.pages,
                chunks_per_page,
                pool_layout,
                lit: LitDirections::new(set, &pack, &selection, fully_resident)?,
                bounding_polygon: opts.bounding_polygon,
                has_bvh: bvh.is_some(),
                bind,
                bounds: fixed.bounds,
                proxy: fixed.proxy,
                gpu_bytes,
                budget_bytes: opts.budget_bytes,
                far_field: std::sync::OnceLock::new(),
            };
            if fully_resident {
                lum.upload_all(ctx, &all)
            } else {
                Ok(lum)
            }
        })
    }

    /// The luminaire's bind group: the fixed blocks at bindings 0–6, the pool's pages at 7… (the
    /// stand-in for each page the pool does not have).
    fn bind_luminaire(&self, ctx: &GpuContext, fixed: &FixedBuffers, pool: &TilePool) -> wgpu::BindGroup {
        let mut entries: Vec<wgpu::BindGroupEntry> = [
            &fixed.luminaire,
            &fixed.cameras,
            &fixed.geometry,
            &fixed.vertices,
            &fixed.lists,
            &fixed.chunk_map,
            &fixed.misses,
        ]
        .into_iter()
        .enumerate()
        .map(|(binding, b)| wgpu::BindGroupEntry {
            binding: binding as u32,
            resource: b.as_entire_binding(),
        })
        .collect();
        for b in 0..MAX_POOL_PAGES {
            entries.push(wgpu::BindGroupEntry {
                binding: 7 + b as u32,
                resource: pool.pages.get(b).unwrap_or(&pool.stand_in).as_entire_binding(),
            });
        }
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("near-field luminaire"),
            layout: &self.lum_layout,
            entries: &entries,
        })
    }
}

impl NearfieldLuminaire {
    /// Uploads every tile once (the pool holds the whole pack), in batches so staging memory stays
    /// bounded, and notes whether pack chunk c sits in pool chunk c for every chunk: the shader may
    /// then skip the chunk map (two of a footprint's four dependent reads).
    fn upload_all(self, ctx: &GpuContext, all: &[u32]) -> Result<NearfieldLuminaire, GpuError> {
        for batch in all.chunks(256) {
            self.make_resident_chunks(ctx, batch)?;
            ctx.queue.submit([]);
        }
        let identity_map = {
            let r = self.residency.lock().unwrap_or_else(|p| p.into_inner());
            all.len() == r.map.len() && r.map.iter().enumerate().all(|(c, &g)| g as usize == c)
        };
        Ok(NearfieldLuminaire {
            fully_resident: true,
            identity_map,
            ..self
        })
    }
}

/// Checks the options and the proxy; returns the content radius (m): the option's, else derived
/// from the cameras' tiles, grown to hold every proxy vertex.
fn content_radius(
    pack: &Pack,
    sphere: (DVec3, f64),
    proxy: Option<&[[f32; 3]]>,
    opts: &NearfieldOptions,
) -> Result<f64, GpuError> {
    let mut content = match opts.content_radius_m {
        Some(r) if r.is_finite() && r > 0.0 && r < sphere.1 => r,
        Some(r) => {
            return Err(GpuError::invalid(
                Arg::ContentRadius,
                format!("{r} must be finite, > 0 and below the capture radius {} m", sphere.1),
            ))
        }
        None => content_radius_m(pack),
    };
    if let Some(p) = proxy {
        if p.is_empty() || p.len() % 3 != 0 || p.iter().any(|v| !v.iter().all(|x| x.is_finite())) {
            return Err(GpuError::invalid(
                Arg::Proxy,
                "must be a non-empty list of finite triangles",
            ));
        }
        for v in p {
            let d = (glam::Vec3::from(*v).as_dvec3() - sphere.0).length();
            if d >= sphere.1 {
                return Err(GpuError::invalid(
                    Arg::Proxy,
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
        return Err(GpuError::invalid(Arg::BudgetBytes, "must be > 0"));
    }
    Ok(content)
}

/// The camera records, [`CAMERA_RECORD_VEC4S`] vec4 per camera (the shader's `camera()`): the
/// projection as one 3×4 matrix, the tile bounding box, the image size and table offset, the
/// position.
fn camera_records(pack: &Pack) -> Vec<[u32; 4]> {
    let set = pack.rayset();
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
    cams
}

/// The selection lists in one block, with the base of each: triangle offsets and items, nearest-1
/// offsets and items, nearest-4 offsets and items.
fn selection_lists(g: &SelectionGpu) -> (Vec<u32>, [u32; 6]) {
    let mut lists: Vec<u32> = Vec::new();
    let mut bases = [0u32; 6];
    for (base, v) in bases.iter_mut().zip([
        &g.tri_offsets,
        &g.tri_items,
        &g.near1_offsets,
        &g.near1_items,
        &g.near4_offsets,
        &g.near4_items,
    ]) {
        *base = lists.len() as u32;
        lists.extend_from_slice(v);
    }
    (lists, bases)
}

/// One block of vec4s: the selection triangles, the proxy's BVH for the visibility test
/// (src/nearfield/bvh.rs: nodes, then triangles) and the quadratic stencils
/// (src/nearfield/select/quadratic.rs). In one buffer, one binding fewer: lavapipe runs the pass
/// ~1.5× slower with a 17th storage buffer in the fragment stage. Returns the block, the BVH's
/// record (node base, triangle base, present, node count) and the stencils' base.
fn geometry_block(g: &SelectionGpu, bvh: Option<&ProxyBvh>) -> (Vec<[f32; 4]>, [u32; 4], u32) {
    let mut geometry = g.triangles.clone();
    let bvh_bases = match bvh {
        Some(b) => {
            let nodes = geometry.len() as u32;
            geometry.extend_from_slice(&b.nodes);
            let tris = geometry.len() as u32;
            geometry.extend_from_slice(&b.triangles);
            [nodes, tris, 1, (b.nodes.len() / 2) as u32]
        }
        None => [0; 4],
    };
    let quad_base = geometry.len() as u32;
    geometry.extend_from_slice(&g.quadratic);
    (geometry, bvh_bases, quad_base)
}

/// Each storage block must fit one binding (`max_binding` bytes).
fn check_binding_limits(
    cams: &[[u32; 4]],
    geometry: &[[f32; 4]],
    lists: &[u32],
    max_binding: u64,
) -> Result<(), GpuError> {
    for (what, bytes) in [
        ("camera records", std::mem::size_of_val(cams)),
        (
            "selection triangles, proxy BVH and stencils",
            std::mem::size_of_val(geometry),
        ),
        ("selection lists", std::mem::size_of_val(lists)),
    ] {
        if bytes as u64 > max_binding {
            return Err(GpuError::invalid(
                Arg::Scan,
                format!("its {what} need {bytes} bytes, above the {max_binding}-byte binding limit"),
            ));
        }
    }
    Ok(())
}

/// The luminaire's own block (the shader's `Lum`).
#[allow(clippy::too_many_arguments)]
fn luminaire_block(
    g: &SelectionGpu,
    chunks: &ChunkLayout,
    sphere: (DVec3, f64),
    content: f64,
    lists: [u32; 6],
    quad_base: u32,
    bvh: [u32; 4],
    opts: &NearfieldOptions,
) -> LumUniform {
    LumUniform {
        sphere: [sphere.0.x as f32, sphere.0.y as f32, sphere.0.z as f32, sphere.1 as f32],
        content: [sphere.0.x as f32, sphere.0.y as f32, sphere.0.z as f32, content as f32],
        grid: [g.n_phi, g.n_theta, chunks.table_chunks, 0],
        lists_a: [lists[0], lists[1], lists[2], lists[3]],
        lists_b: [lists[4], lists[5], quad_base, 0],
        bvh,
        // Visibility-test margin: 10⁻⁴ of the content radius (at least 1 µm); z: 1 when
        // the proxy only bounds the light (plain bilinear sampling).
        gap: [
            g.cos_max_gap,
            (1e-4 * content).max(1e-6) as f32,
            if opts.proxy_is_bound { 1.0 } else { 0.0 },
            0.0,
        ],
    }
}

/// The buffers of a luminaire other than its tile pool.
struct FixedBuffers {
    luminaire: wgpu::Buffer,
    cameras: wgpu::Buffer,
    geometry: wgpu::Buffer,
    vertices: wgpu::Buffer,
    lists: wgpu::Buffer,
    chunk_map: wgpu::Buffer,
    misses: wgpu::Buffer,
    bounds: (wgpu::Buffer, u32),
    proxy: Option<(wgpu::Buffer, u32)>,
}

impl FixedBuffers {
    #[allow(clippy::too_many_arguments)]
    fn create(
        ctx: &GpuContext,
        lum: &LumUniform,
        cams: &[[u32; 4]],
        geometry: &[[f32; 4]],
        vertices: &[[f32; 4]],
        lists: &[u32],
        map_len: usize,
        bounds: Vec<[f32; 3]>,
        proxy: Option<&[[f32; 3]]>,
    ) -> FixedBuffers {
        let storage = wgpu::BufferUsages::STORAGE;
        let vertex = wgpu::BufferUsages::VERTEX;
        FixedBuffers {
            luminaire: buffer_init(ctx, "near-field luminaire", bytemuck::bytes_of(lum), storage),
            cameras: buffer_init(ctx, "camera records", bytemuck::cast_slice(cams), storage),
            geometry: buffer_init(
                ctx,
                "selection triangles and proxy BVH",
                bytemuck::cast_slice(geometry),
                storage,
            ),
            vertices: buffer_init(ctx, "selection vertices", bytemuck::cast_slice(vertices), storage),
            lists: buffer_init(ctx, "selection lists", bytemuck::cast_slice(lists), storage),
            chunk_map: buffer_init(
                ctx,
                "chunk map",
                bytemuck::cast_slice(&vec![EMPTY; map_len.max(1)]),
                storage,
            ),
            misses: buffer_init(
                ctx,
                "near-field misses",
                &[0u8; 16],
                storage | wgpu::BufferUsages::COPY_SRC,
            ),
            bounds: (
                buffer_init(ctx, "content box", bytemuck::cast_slice(&bounds), vertex),
                bounds.len() as u32,
            ),
            proxy: proxy.map(|p| {
                (
                    buffer_init(ctx, "proxy mesh", bytemuck::cast_slice(p), vertex),
                    p.len() as u32,
                )
            }),
        }
    }

    /// Their bytes on the GPU.
    fn bytes(&self) -> u64 {
        [
            &self.luminaire,
            &self.cameras,
            &self.geometry,
            &self.vertices,
            &self.lists,
            &self.chunk_map,
            &self.misses,
            &self.bounds.0,
        ]
        .iter()
        .map(|b| b.size())
        .sum::<u64>()
            + self.proxy.as_ref().map_or(0, |p| p.0.size())
    }
}

/// A luminaire's tile pool: pages of `chunks_per_page` chunks, `capacity` chunks in all, plus one
/// 256-byte stand-in for the pool bindings without a page.
struct TilePool {
    pages: Vec<wgpu::Buffer>,
    stand_in: wgpu::Buffer,
    capacity: u32,
}

/// Bytes of the stand-in for unused pool bindings.
const STAND_IN_BYTES: u64 = 256;

impl TilePool {
    /// The largest pool the budget leaves after the `fixed` bytes (at most every one of the pack's
    /// `needed` chunks, at most [`MAX_POOL_PAGES`] pages). Errors: `BudgetBytes` when it leaves no
    /// room for one chunk.
    fn allocate(
        ctx: &GpuContext,
        fixed: u64,
        needed: usize,
        chunks_per_page: u32,
        budget_bytes: u64,
    ) -> Result<TilePool, GpuError> {
        let pool_budget = budget_bytes.saturating_sub(fixed + STAND_IN_BYTES);
        let capacity = (pool_budget / CHUNK_BYTES)
            .min(needed as u64)
            .min(MAX_POOL_PAGES as u64 * u64::from(chunks_per_page)) as u32;
        if capacity == 0 && needed > 0 {
            return Err(GpuError::invalid(
                Arg::BudgetBytes,
                format!(
                    "{budget_bytes} bytes leave no room for tiles: camera records and selection tables take {fixed}; give at least {}",
                    fixed + STAND_IN_BYTES + CHUNK_BYTES
                ),
            ));
        }
        let storage = wgpu::BufferUsages::STORAGE;
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
        let stand_in = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("near-field unused pool binding"),
            size: STAND_IN_BYTES,
            usage: storage,
            mapped_at_creation: false,
        });
        Ok(TilePool {
            pages,
            stand_in,
            capacity,
        })
    }

    /// Its bytes on the GPU, the stand-in included.
    fn bytes(&self) -> u64 {
        STAND_IN_BYTES + self.pages.iter().map(|p| p.size()).sum::<u64>()
    }
}
