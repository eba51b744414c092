//! Uploading a pack: camera records, selection tables, chunk map and the tile pool within the
//! budget ([`NearfieldPass::upload`]).

use super::*;

impl NearfieldPass {
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
}
