// Near-field pass, sampling (see pass.wgsl for the whole): reading a camera's tiles from the pool
// of residency chunks (src/gpu/residency.rs), the bilinear footprint, and a camera's luminance at a
// point or along a direction.

// The pool chunk of pack chunk `c` (EMPTY: not resident).
fn pool_chunk(c: u32) -> u32 {
    if (IDENTITY_MAP) {
        return c;
    }
    return chunk_map[c];
}

fn pool_word(chunk: u32, word: u32) -> u32 {
    if (POOL_PAGES == 1u) {
        return pool0[chunk * CHUNK_WORDS + word];
    }
    let page = chunk / PAGE_CHUNKS;
    let i = (chunk % PAGE_CHUNKS) * CHUNK_WORDS + word;
    switch page {
        case 0u: { return pool0[i]; }
        case 1u: { return pool1[i]; }
        case 2u: { return pool2[i]; }
        case 3u: { return pool3[i]; }
        case 4u: { return pool4[i]; }
        case 5u: { return pool5[i]; }
        case 6u: { return pool6[i]; }
        default: { return pool7[i]; }
    }
}

// Set by footprint() when a read needed a chunk that is not resident (the fragment then counts once
// in `misses`; the CPU makes every chunk a frame can read resident, and the tests assert 0).
var<private> missed: bool = false;
// The largest spatial spread of a footprint sampled so far in this fragment (see sample_camera).
var<private> spread: f32 = 0.0;

// Floor division by the tile edge (also left of the image, where col < 0).
fn tile_of(x: i32) -> i32 {
    let t = i32(TILE_EDGE);
    return select((x + 1) / t - 1, x / t, x >= 0);
}

// Stored luminance (cd/m²) of the bilinear footprint of texels (x0, y0), (x0 + 1, y0), (x0, y0 + 1),
// (x0 + 1, y0 + 1) of a camera; 0 outside the image, outside the camera's tile box, where no tile is
// kept, or (setting `missed`) where a chunk is not resident.
//
// The whole footprint lies in the GPU slot of the tile holding (x0, y0) (src/gpu/residency.rs): the
// tile's own values, then its apron (the 2T + 1 values right of and below it, f32). So a footprint
// costs one tile-table entry and one header; the tile is clamped into the camera's tile box, since a
// footprint starting just left of or above the box reaches into its first tile (the texels outside
// the box are dark). The pack's tables point tiles without light next to lit ones at apron-only slots.
//
// Written without early returns: every lane runs the same straight line of loads and selects. On a
// SIMD rasteriser (lavapipe) the nested early-return version cost 1.7× the frame time, as divergent
// branches run both sides for every lane anyway.
fn footprint(cam: Cam, x0: i32, y0: i32) -> vec4<f32> {
    let t = i32(TILE_EDGE);
    let has_box = cam.bbox.z > 0u && cam.bbox.w > 0u;
    let bx = clamp(tile_of(x0) - i32(cam.bbox.x), 0, max(i32(cam.bbox.z) - 1, 0));
    let by = clamp(tile_of(y0) - i32(cam.bbox.y), 0, max(i32(cam.bbox.w) - 1, 0));
    // (x0, y0) relative to that tile: −1…T − 1 where the footprint meets it.
    let lx = x0 - (i32(cam.bbox.x) + bx) * t;
    let ly = y0 - (i32(cam.bbox.y) + by) * t;
    let near = has_box && lx >= -1 && lx < t && ly >= -1 && ly < t;
    let entry = cam.table + u32(by) * cam.bbox.z + u32(bx);
    let tchunk = pool_chunk(entry / TABLE_PER_CHUNK);
    let t_ok = tchunk != EMPTY;
    let slot = pool_word(select(0u, tchunk, t_ok), entry % TABLE_PER_CHUNK);
    let has_tile = near && t_ok && slot != EMPTY;
    let sl = select(0u, slot, has_tile);
    let per = SLOTS_PER_CHUNK;
    let schunk = pool_chunk(lum.grid.z + sl / per);
    let s_ok = schunk != EMPTY;
    let sc = select(0u, schunk, s_ok);
    let base = (sl % per) * SLOT_WORDS;
    let scale = bitcast<f32>(pool_word(sc, base));
    // The header: > 0 an fp16 tile's scale (its apron ends the slot), else an f32 tile (two slots,
    // the apron after its T² values).
    let half = scale > 0.0;
    let apron = select(1u + TILE_EDGE * TILE_EDGE, SLOT_WORDS - 2u * TILE_EDGE - 1u, half);
    let ok = has_tile && s_ok;
    missed = missed || (near && !t_ok) || (has_tile && !s_ok);
    var v = vec4<f32>(0.0);
    for (var j = 0u; j < 4u; j = j + 1u) {
        let dx = i32(j & 1u);
        let dy = i32(j >> 1u);
        let x = lx + dx;
        let y = ly + dy;
        let in_image = u32(x0 + dx) < cam.size.x && u32(y0 + dy) < cam.size.y;
        let reach = x >= 0 && y >= 0;
        let inner = x < t && y < t;
        let k = u32(y * t + x);
        // Apron order: the column right of the tile (rows 0…T), then the row below (columns 0…T − 1).
        let a = select(u32(t + 1 + x), u32(y), x == t);
        let w = select(apron + a, 1u + select(k, k / 2u, half), inner);
        let word = pool_word(sc, base + select(0u, w, ok && reach));
        let pair = unpack2x16float(word);
        let value = select(bitcast<f32>(word), select(pair.x, pair.y, (k & 1u) == 1u) * scale, inner && half);
        v[j] = select(0.0, value, ok && reach && in_image);
    }
    return v;
}

// Bilinear luminance at pixel coordinates (x, y) (pixel centres at +0.5). With `lit_only` (proxy
// mode) the weights are renormalised over the texels that hold light: the proxy says where the surface
// is and the images say its luminance, so a fragment near the surface's edge is not darkened by the
// dark texels beyond the edge in the capture (plain bilinear would darken a band half a capture pixel
// wide all around every silhouette, a bias in the intensity Σ L·ΔA). All four dark gives 0.
fn sample_camera(cam: Cam, px: vec2<f32>, lit_only: bool) -> f32 {
    let s = px - vec2<f32>(0.5, 0.5);
    let f0 = floor(s);
    let f = s - f0;
    let i = vec2<i32>(f0);
    let t = footprint(cam, i.x, i.y);
    let w = vec4<f32>((1.0 - f.x) * (1.0 - f.y), f.x * (1.0 - f.y), (1.0 - f.x) * f.y, f.x * f.y);
    let l = dot(w, t);
    // Spatial spread of the footprint in log luminance: Σ wᵢ·|ln tᵢ − ln l| (dark texels count as
    // 10⁻³ l). About half the log step per pixel on a smooth gradient (a steep cosⁿ flank: 0.1), and
    // far more across an edge or a spot under a pixel; continuous in the weights.
    if (l > 0.0) {
        let dev = dot(w, abs(log(max(t, vec4<f32>(1e-3 * l))) - vec4<f32>(log(l))));
        spread = max(spread, dev);
    }
    if (!lit_only) {
        return l;
    }
    let lit = dot(w, select(vec4<f32>(0.0), vec4<f32>(1.0), t > vec4<f32>(0.0)));
    if (lit <= 0.0) {
        return 0.0;
    }
    return l / lit;
}

// Luminance seen by camera `ci` at surface point p (proxy mode) or along direction v (bounding mode).
fn camera_luminance(ci: u32, p: vec3<f32>, v: vec3<f32>, proxy: bool) -> f32 {
    return luminance_of(camera(ci), p, v, proxy);
}

fn luminance_of(cam: Cam, p: vec3<f32>, v: vec3<f32>, proxy: bool) -> f32 {
    // A point (w = 1) in proxy mode, a direction (w = 0) without.
    let x = select(vec4<f32>(v, 0.0), vec4<f32>(p, 1.0), proxy);
    let h = vec3<f32>(dot(cam.m0, x), dot(cam.m1, x), dot(cam.m2, x));
    if (h.z <= 0.0) {
        return 0.0;
    }
    // A proxy that only bounds the light (lum.gap.z = 1) is sampled plainly: its dark texels are
    // the estimate's own darkness, not the space beyond a surface's edge.
    return sample_camera(cam, h.xy / h.z, proxy && lum.gap.z < 0.5);
}
