// Near-field appearance pass: the measured luminance of a scanned luminaire (a `.lvpack` of capture
// images on a capture sphere), seen from the host's camera.
//
// Per fragment (luminaire frame, metres):
// 1. The fragment lies on the luminaire's proxy mesh (proxy mode: P is the surface point) or on a box
//    around the content ball (bounding mode). v = unit view direction, from the eye into the scene.
// 2. Q = the first point where the line P + t·v meets the capture sphere (t < 0: between the eye and
//    the luminaire, or behind the eye when the eye is inside the sphere); u = unit(Q − centre). A camera
//    at Q sees P along exactly the eye's line.
// 3. Cameras around u are selected (nearest, idw4 or continuous barycentric weights over the spherical
//    Delaunay triangulation; `src/nearfield/select/` builds the tables and documents them).
// 4. In proxy mode a camera whose path to P the proxy blocks is left out (BVH ray cast, see shade()).
//    Each selected camera is sampled (bilinear over pixel centres; in proxy mode over the lit texels
//    only, see sample_camera) where it sees the same point: the projection of P (proxy mode) or,
//    without a proxy, the view direction v rotated into its frame (the "infinite-depth billboard").
// 5. The blend (continuous: weighted geometric mean where every camera sees light, see shade())
//    gives the luminance (cd/m²), written as linear luminance or tone mapped; depth is the proxy's,
//    or the stand-in plane through the content centre facing the eye (bounding mode).
//
// Tiles are read from a pool of fixed-size chunks (residency: `src/gpu/residency.rs`): the pack's
// tile tables and tile slots (each with an apron: the values right of and below the tile) are cut
// into chunks; `chunk_map` maps a pack chunk to its GPU chunk (or
// EMPTY when not resident). The CPU makes every chunk a frame can read resident before the frame; a
// read of a missing chunk returns 0, and the fragment counts once in `misses` (tests assert 0).

struct Draw {
    // Luminaire frame -> wgpu clip space (host view · projection · model, depth range folded in).
    clip_from_local: mat4x4<f32>,
    // Eye in the luminaire frame: xyz = position (w = 1) or direction towards the eye (w = 0, orthographic).
    eye_local: vec4<f32>,
    // x = exposure (m²/cd), y = output (0 luminance, 1 tone mapped), z, w unused.
    params: vec4<f32>,
};

struct Lum {
    // Capture sphere: centre xyz (m), radius (m).
    sphere: vec4<f32>,
    // Content ball: centre xyz (m), radius (m).
    content: vec4<f32>,
    // n_phi, n_theta, number of table chunks (the slot chunks follow them in chunk_map), unused.
    grid: vec4<u32>,
    // Word offsets in `lists`: triangle offsets, triangle items, nearest offsets, nearest items.
    lists_a: vec4<u32>,
    // idw4 offsets, idw4 items, first entry of the quadratic stencils in `tris` (7 per triangle,
    // src/nearfield/select/gpu.rs), unused.
    lists_b: vec4<u32>,
    // x = cos(max gap) for nearest/idw4, y = visibility-test margin (m), z = 1 when the proxy only
    // bounds the light (images sampled plainly), w unused.
    gap: vec4<f32>,
    // The proxy's BVH in `tris` (src/nearfield/bvh.rs): x = first node word (2 per node), y = first
    // triangle word (3 per triangle), z = 1 when there is one, w = number of nodes.
    bvh: vec4<u32>,
};

// The per-draw and per-luminaire blocks are read-only storage, not uniform buffers: lavapipe (Mesa
// 22.3) "inlines" uniforms a shader branches on, recompiling the shader for every draw and never
// freeing the old variant (~4 MB per frame, found by the C examples under LeakSanitizer), which also
// cost half the frame time.
@group(0) @binding(0) var<storage, read> draw: Draw;

@group(1) @binding(0) var<storage, read> lum: Lum;
// The camera records, CAMERA_RECORD_VEC4S × vec4<u32> each: see camera() below.
@group(1) @binding(1) var<storage, read> cameras: array<vec4<u32>>;
// 3 × vec4 per triangle: (b×c, camera a), (c×a, camera b), (a×b, camera c); camera bits EMPTY = hole.
// Followed by the proxy's BVH (see Lum.bvh).
@group(1) @binding(2) var<storage, read> tris: array<vec4<f32>>;
// Per vertex: unit direction, camera bits.
@group(1) @binding(3) var<storage, read> verts: array<vec4<f32>>;
// The three CSR cell tables, concatenated (offsets at lum.lists_*).
@group(1) @binding(4) var<storage, read> lists: array<u32>;
// Pack chunk -> GPU chunk (EMPTY: not resident): table chunks first, then slot chunks.
@group(1) @binding(5) var<storage, read> chunk_map: array<u32>;
@group(1) @binding(6) var<storage, read_write> misses: array<atomic<u32>>;
@group(1) @binding(7) var<storage, read> pool0: array<u32>;
@group(1) @binding(8) var<storage, read> pool1: array<u32>;
@group(1) @binding(9) var<storage, read> pool2: array<u32>;
@group(1) @binding(10) var<storage, read> pool3: array<u32>;
@group(1) @binding(11) var<storage, read> pool4: array<u32>;
@group(1) @binding(12) var<storage, read> pool5: array<u32>;
@group(1) @binding(13) var<storage, read> pool6: array<u32>;
@group(1) @binding(14) var<storage, read> pool7: array<u32>;


// Pool pages bound (1…8), fixed per pipeline: with one page (any pool up to 128 MiB) the page switch
// below folds away, which matters on a software rasteriser that would run every case for every lane.
override POOL_PAGES: u32 = 8u;

// Set when the whole pack is resident with pack chunk c in pool chunk c: the chunk map is skipped.
override IDENTITY_MAP: bool = false;

// The pool's layout (the luminaire's; `src/gpu/residency.rs`): tile edge T (px), words per tile slot,
// words per chunk, chunks per pool page, tile-table entries per table chunk, slots per slot chunk.
// Pipeline constants because the fetch divides by them: a division by a constant is a multiply and a
// shift, by a value read from a buffer a SIMD rasteriser runs as one scalar division per lane.
override TILE_EDGE: u32 = 8u;
override SLOT_WORDS: u32 = 33u;
override CHUNK_WORDS: u32 = 16384u;
override PAGE_CHUNKS: u32 = 2048u;
override TABLE_PER_CHUNK: u32 = 16384u;
override SLOTS_PER_CHUNK: u32 = 496u;

// The instance's selection (0 nearest, 1 idw4, 2 continuous) and whether it draws its proxy (else the
// bounding box, with the pipeline culling the faces that do not apply: back faces from outside the
// box, front faces from inside). Pipeline constants rather than per-draw data: a software rasteriser
// runs every case of a branch for every lane, so the selection's camera loop has a fixed count per
// pipeline (1, 4 or 3 cameras) and the other modes fold away.
override SELECTION: u32 = 2u;
override PROXY: bool = false;

// The proxy has a hierarchy for the visibility test (src/nearfield/bvh.rs); a planar proxy has none
// (it cannot block the path from a point on it to a camera), and its pipelines leave the test out.
override VISIBILITY: bool = true;

// Continuous mode without a proxy, drawn as the triangle raster (src/nearfield/select/lit_bound.rs): each polygon
// covers one selection triangle's region (vertex attribute `tri`) and the fragment takes that
// triangle's weights directly, without the cell search.
override TRIANGLES: bool = false;

// Nearest mode without a proxy, drawn as the cell raster (src/nearfield/select/lit_bound.rs): each polygon covers
// (a little more than) one camera's Voronoi cell, `tri` naming the camera; the fragment runs the usual
// selection and is kept only where it picks that camera, so overlapping cells write each pixel once.
override CELLS: bool = false;

// The draw is the content box: the fragment writes the stand-in depth itself (entry points fs_box*).
// Proxy and polygon draws take the rasteriser's depth: the proxy's own, or the polygon's, which lies
// on the stand-in plane already (src/nearfield/select/lit_bound.rs), and write no frag_depth.
override BOX: bool = false;

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

struct Cam {
    // Projection rows: (h.x, h.y, h.z) = M · x + t for a point x (luminaire frame, m), M · v for a
    // direction v; the pixel (pixel centres at +0.5) is h.xy / h.z, in front of the camera when h.z > 0.
    // M = (fx · right + cx · forward, fy · down + cy · forward, forward), t = −M · position.
    m0: vec4<f32>,
    m1: vec4<f32>,
    m2: vec4<f32>,
    size: vec2<u32>,
    table: u32,
    bbox: vec4<u32>,
};

// Per camera CAMERA_RECORD_VEC4S (6) × vec4<u32> (written by `NearfieldPass::upload`): the
// three projection rows (f32 bits) | tile box x0, y0, w, h (tiles) | width, height, table offset,
// unused | position xyz (f32 bits; the visibility test), unused.
fn camera(i: u32) -> Cam {
    var cam: Cam;
    let r = CAMERA_RECORD_VEC4S * i;
    cam.m0 = bitcast<vec4<f32>>(cameras[r]);
    cam.m1 = bitcast<vec4<f32>>(cameras[r + 1u]);
    cam.m2 = bitcast<vec4<f32>>(cameras[r + 2u]);
    cam.bbox = cameras[r + 3u];
    let e = cameras[r + 4u];
    cam.size = e.xy;
    cam.table = e.z;
    return cam;
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

fn cell_of(u: vec3<f32>) -> u32 {
    var phi = atan2(u.y, u.x);
    if (phi < 0.0) {
        phi = phi + 2.0 * PI;
    }
    let theta = acos(clamp(u.z, -1.0, 1.0));
    let np = lum.grid.x;
    let nt = lum.grid.y;
    let i = min(u32(floor(phi / (2.0 * PI) * f32(np))), np - 1u);
    let j = min(u32(floor(theta / PI * f32(nt))), nt - 1u);
    return j * np + i;
}

struct Selected {
    cam: vec4<u32>,
    w: vec4<f32>,
    // Continuous: the triangle, else EMPTY.
    tri: u32,
};

fn select_continuous(u: vec3<f32>, cell: u32) -> Selected {
    var out: Selected;
    out.cam = vec4<u32>(EMPTY);
    out.w = vec4<f32>(0.0);
    out.tri = EMPTY;
    let start = lists[lum.lists_a.x + cell];
    let end = lists[lum.lists_a.x + cell + 1u];
    var best = -2.0;
    var best_e = vec3<f32>(0.0);
    var best_t = EMPTY;
    for (var k = start; k < end; k = k + 1u) {
        let t = lists[lum.lists_a.y + k];
        let e = vec3<f32>(dot(u, tris[3u * t].xyz), dot(u, tris[3u * t + 1u].xyz), dot(u, tris[3u * t + 2u].xyz));
        let m = min(e.x, min(e.y, e.z));
        if (m > best) {
            best = m;
            best_e = e;
            best_t = t;
            if (m >= 0.0) {
                break;
            }
        }
    }
    if (best_t == EMPTY) {
        return out;
    }
    let ca = bitcast<u32>(tris[3u * best_t].w);
    if (ca == EMPTY) {
        return out;
    }
    let e = max(best_e, vec3<f32>(0.0));
    let s = e.x + e.y + e.z;
    if (s <= 0.0) {
        return out;
    }
    out.cam = vec4<u32>(ca, bitcast<u32>(tris[3u * best_t + 1u].w), bitcast<u32>(tris[3u * best_t + 2u].w), EMPTY);
    out.w = vec4<f32>(e / s, 0.0);
    out.tri = best_t;
    return out;
}

// The continuous weights of triangle t at u (as select_continuous), or nothing (cam.x = EMPTY) when u
// lies outside t by more than a hair of tolerance: that line belongs to the neighbouring triangle,
// whose polygon covers it too (the polygons overlap a little, so no line falls between two).
fn select_in_triangle(u: vec3<f32>, t: u32) -> Selected {
    var out: Selected;
    out.cam = vec4<u32>(EMPTY);
    out.w = vec4<f32>(0.0);
    out.tri = EMPTY;
    let a = tris[3u * t];
    let b = tris[3u * t + 1u];
    let c = tris[3u * t + 2u];
    let e = vec3<f32>(dot(u, a.xyz), dot(u, b.xyz), dot(u, c.xyz));
    let s = abs(e.x) + abs(e.y) + abs(e.z);
    if (min(e.x, min(e.y, e.z)) < -1e-5 * s) {
        return out;
    }
    let ep = max(e, vec3<f32>(0.0));
    let sum = ep.x + ep.y + ep.z;
    if (sum <= 0.0) {
        return out;
    }
    out.cam = vec4<u32>(bitcast<u32>(a.w), bitcast<u32>(b.w), bitcast<u32>(c.w), EMPTY);
    out.w = vec4<f32>(ep / sum, 0.0);
    out.tri = t;
    return out;
}

// Nearest (k = 1) or inverse-distance over the 4 nearest (k = 4), great-circle distances.
fn select_nearest(u: vec3<f32>, cell: u32, k4: bool) -> Selected {
    var out: Selected;
    out.cam = vec4<u32>(EMPTY);
    out.w = vec4<f32>(0.0);
    out.tri = EMPTY;
    var off = lum.lists_a.z;
    var items = lum.lists_a.w;
    if (k4) {
        off = lum.lists_b.x;
        items = lum.lists_b.y;
    }
    let start = lists[off + cell];
    let end = lists[off + cell + 1u];
    if (!k4) {
        // The largest cosine within the gap; the earlier list entry wins a tie (as below).
        var best = -2.0;
        var id = EMPTY;
        for (var k = start; k < end; k = k + 1u) {
            let v = verts[lists[items + k]];
            let c = dot(u, v.xyz);
            if (c >= lum.gap.x && c > best) {
                best = c;
                id = bitcast<u32>(v.w);
            }
        }
        out.cam = vec4<u32>(id, EMPTY, EMPTY, EMPTY);
        out.w = vec4<f32>(select(1.0, 0.0, id == EMPTY), 0.0, 0.0, 0.0);
        return out;
    }
    // Largest cosines first.
    var cs = vec4<f32>(-2.0);
    var ids = vec4<u32>(EMPTY);
    var vid = vec4<u32>(0u);
    for (var k = start; k < end; k = k + 1u) {
        let vi = lists[items + k];
        let v = verts[vi];
        let c = dot(u, v.xyz);
        if (c < lum.gap.x) {
            continue;
        }
        let id = bitcast<u32>(v.w);
        if (c > cs.x) {
            cs = vec4<f32>(c, cs.xyz);
            ids = vec4<u32>(id, ids.xyz);
            vid = vec4<u32>(vi, vid.xyz);
        } else if (c > cs.y) {
            cs = vec4<f32>(cs.x, c, cs.yz);
            ids = vec4<u32>(ids.x, id, ids.yz);
            vid = vec4<u32>(vid.x, vi, vid.yz);
        } else if (c > cs.z) {
            cs = vec4<f32>(cs.xy, c, cs.z);
            ids = vec4<u32>(ids.xy, id, ids.z);
            vid = vec4<u32>(vid.xy, vi, vid.z);
        } else if (c > cs.w) {
            cs.w = c;
            ids.w = id;
            vid.w = vi;
        }
    }
    if (ids.x == EMPTY) {
        return out;
    }
    var w = vec4<f32>(0.0);
    for (var i = 0u; i < 4u; i = i + 1u) {
        if (ids[i] != EMPTY) {
            // Great-circle angle from the chord, 2·asin(|u − d| / 2): accurate for small angles, where
            // fp32 acos(u · d) is not (acos of 1 − 2⁻²⁴ is already 3.5·10⁻⁴ rad).
            let a = 2.0 * asin(min(0.5 * length(u - verts[vid[i]].xyz), 1.0));
            if (a < 1e-7) {
                out.cam = vec4<u32>(ids[i], EMPTY, EMPTY, EMPTY);
                out.w = vec4<f32>(1.0, 0.0, 0.0, 0.0);
                return out;
            }
            w[i] = 1.0 / a;
        }
    }
    out.cam = ids;
    out.w = w / (w.x + w.y + w.z + w.w);
    return out;
}

// Is the segment from `origin` to `dest` blocked by the proxy (its BVH, src/nearfield/bvh.rs)? Parameters
// within `lum.gap.y` (metres, over the segment's length) of either end do not count, so the surface
// P lies on does not block itself.
fn occluded(origin: vec3<f32>, dest: vec3<f32>) -> bool {
    if (lum.bvh.z == 0u) {
        return false;
    }
    let nodes = lum.bvh.x;
    let toff = lum.bvh.y;
    var d = dest - origin;
    let len = length(d);
    if (len <= 0.0) {
        return false;
    }
    let eps = lum.gap.y / len;
    // No zero components: the slab test divides by them.
    d = select(d, vec3<f32>(1e-20), abs(d) < vec3<f32>(1e-20));
    let inv = 1.0 / d;
    // Preorder with escape indices: no stack (see src/nearfield/bvh.rs).
    var n = 0u;
    loop {
        if (n >= lum.bvh.w) {
            break;
        }
        let a = tris[nodes + 2u * n];
        let b = tris[nodes + 2u * n + 1u];
        let t0 = (a.xyz - origin) * inv;
        let t1 = (b.xyz - origin) * inv;
        let lo = min(t0, t1);
        let hi = max(t0, t1);
        let tmin = max(max(max(lo.x, lo.y), lo.z), eps);
        let tmax = min(min(min(hi.x, hi.y), hi.z), 1.0 - eps);
        let first = bitcast<u32>(a.w);
        let count = bitcast<u32>(b.w);
        if (tmin > tmax) {
            // Missed: skip the subtree (a leaf's is itself).
            n = select(first, n + 1u, count > 0u);
            continue;
        }
        for (var j = first; j < first + count; j = j + 1u) {
            let v0 = tris[toff + 3u * j].xyz;
            let e1 = tris[toff + 3u * j + 1u].xyz;
            let e2 = tris[toff + 3u * j + 2u].xyz;
            // Möller–Trumbore.
            let pv = cross(d, e2);
            let det = dot(e1, pv);
            if (abs(det) < 1e-20) {
                continue;
            }
            let idet = 1.0 / det;
            let sv = origin - v0;
            let u = dot(sv, pv) * idet;
            let q = cross(sv, e1);
            let w = dot(d, q) * idet;
            let t = dot(e2, q) * idet;
            if (u >= 0.0 && w >= 0.0 && u + w <= 1.0 && t > eps && t < 1.0 - eps) {
                return true;
            }
        }
        n = n + 1u;
    }
    return false;
}

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) local_pos: vec3<f32>,
    // The selection triangle of the triangle raster (TRIANGLES), the camera of the cell raster
    // (CELLS), else EMPTY.
    @location(1) @interpolate(flat) tri: u32,
    // The raster polygon's cameras (TRIANGLES: the triangle's three; CELLS: the cell's, first), as
    // flat varyings: the vertex stage reads their records once per vertex instead of every fragment
    // once per pixel. Projection rows, then (tile box x0 | y0 << 16, w | h << 16, table offset,
    // width − 1 | (height − 1) << 16).
    @location(2) @interpolate(flat) a0: vec4<f32>,
    @location(3) @interpolate(flat) a1: vec4<f32>,
    @location(4) @interpolate(flat) a2: vec4<f32>,
    @location(5) @interpolate(flat) b0: vec4<f32>,
    @location(6) @interpolate(flat) b1: vec4<f32>,
    @location(7) @interpolate(flat) b2: vec4<f32>,
    @location(8) @interpolate(flat) c0: vec4<f32>,
    @location(9) @interpolate(flat) c1: vec4<f32>,
    @location(10) @interpolate(flat) c2: vec4<f32>,
    @location(11) @interpolate(flat) am: vec4<u32>,
    @location(12) @interpolate(flat) bm: vec4<u32>,
    @location(13) @interpolate(flat) cm: vec4<u32>,
};

// A camera record packed for the varyings.
fn packed_meta(ci: u32) -> vec4<u32> {
    let bb = cameras[CAMERA_RECORD_VEC4S * ci + 3u];
    let e = cameras[CAMERA_RECORD_VEC4S * ci + 4u];
    return vec4<u32>(bb.x | (bb.y << 16u), bb.z | (bb.w << 16u), e.z, (e.x - 1u) | ((e.y - 1u) << 16u));
}

fn unpacked(r0: vec4<f32>, r1: vec4<f32>, r2: vec4<f32>, m: vec4<u32>) -> Cam {
    var cam: Cam;
    cam.m0 = r0;
    cam.m1 = r1;
    cam.m2 = r2;
    cam.bbox = vec4<u32>(m.x & 0xFFFFu, m.x >> 16u, m.y & 0xFFFFu, m.y >> 16u);
    cam.table = m.z;
    cam.size = vec2<u32>((m.w & 0xFFFFu) + 1u, (m.w >> 16u) + 1u);
    return cam;
}

// Camera k (0, 1, 2) of the polygon's varyings.
fn varying_camera(in: VsOut, k: u32) -> Cam {
    let r0 = select(select(in.a0, in.b0, k == 1u), in.c0, k == 2u);
    let r1 = select(select(in.a1, in.b1, k == 1u), in.c1, k == 2u);
    let r2 = select(select(in.a2, in.b2, k == 1u), in.c2, k == 2u);
    let m = select(select(in.am, in.bm, k == 1u), in.cm, k == 2u);
    return unpacked(r0, r1, r2, m);
}

@vertex
fn vs_main(@location(0) pos: vec3<f32>) -> VsOut {
    var out: VsOut;
    out.clip = draw.clip_from_local * vec4<f32>(pos, 1.0);
    out.local_pos = pos;
    out.tri = EMPTY;
    return out;
}

// The frame's bounding polygons (src/nearfield/select/lit_bound.rs): a point and its selection triangle (or cell
// camera), with the records of the cameras it draws.
@vertex
fn vs_polygon(@location(0) pos: vec3<f32>, @location(1) tri: u32) -> VsOut {
    var out: VsOut;
    out.clip = draw.clip_from_local * vec4<f32>(pos, 1.0);
    out.local_pos = pos;
    out.tri = tri;
    var ca = tri;
    var cb = tri;
    var cc = tri;
    if (TRIANGLES) {
        ca = bitcast<u32>(tris[3u * tri].w);
        cb = bitcast<u32>(tris[3u * tri + 1u].w);
        cc = bitcast<u32>(tris[3u * tri + 2u].w);
    }
    out.a0 = bitcast<vec4<f32>>(cameras[CAMERA_RECORD_VEC4S * ca]);
    out.a1 = bitcast<vec4<f32>>(cameras[CAMERA_RECORD_VEC4S * ca + 1u]);
    out.a2 = bitcast<vec4<f32>>(cameras[CAMERA_RECORD_VEC4S * ca + 2u]);
    out.am = packed_meta(ca);
    out.b0 = bitcast<vec4<f32>>(cameras[CAMERA_RECORD_VEC4S * cb]);
    out.b1 = bitcast<vec4<f32>>(cameras[CAMERA_RECORD_VEC4S * cb + 1u]);
    out.b2 = bitcast<vec4<f32>>(cameras[CAMERA_RECORD_VEC4S * cb + 2u]);
    out.bm = packed_meta(cb);
    out.c0 = bitcast<vec4<f32>>(cameras[CAMERA_RECORD_VEC4S * cc]);
    out.c1 = bitcast<vec4<f32>>(cameras[CAMERA_RECORD_VEC4S * cc + 1u]);
    out.c2 = bitcast<vec4<f32>>(cameras[CAMERA_RECORD_VEC4S * cc + 2u]);
    out.cm = packed_meta(cc);
    return out;
}

struct Shaded {
    l: f32,
    // Whether anything is drawn (bounding mode discards where no camera sees light).
    keep: bool,
    // Window depth of the stand-in plane (bounding mode), or the rasterised depth.
    depth: f32,
};

fn shade(in: VsOut) -> Shaded {
    var out: Shaded;
    out.keep = false;
    out.l = 0.0;
    out.depth = in.clip.z;
    let proxy = PROXY;
    let p = in.local_pos;
    let v = -towards_eye(draw.eye_local, p);
    let s = lum.sphere.xyz;
    let r = lum.sphere.w;
    // The line must pass through the content ball (bounding mode draws a box around it).
    let oc = p - lum.content.xyz;
    let bc = dot(oc, v);
    let dc = dot(oc, oc) - bc * bc;
    if (!proxy && dc > lum.content.w * lum.content.w) {
        return out;
    }
    // First intersection of the line with the capture sphere.
    let os = p - s;
    let b = dot(os, v);
    let disc = b * b - (dot(os, os) - r * r);
    if (disc < 0.0) {
        return out;
    }
    let t = -b - sqrt(disc);
    let q = p + t * v;
    let u = normalize(q - s);
    var sel: Selected;
    if (TRIANGLES) {
        sel = select_in_triangle(u, in.tri);
        if (sel.cam.x == EMPTY) {
            return out;
        }
    } else if (SELECTION == SELECTION_CONTINUOUS) {
        sel = select_continuous(u, cell_of(u));
    } else {
        sel = select_nearest(u, cell_of(u), SELECTION == SELECTION_IDW4);
        if (CELLS && sel.cam.x != in.tri) {
            return out;
        }
    }
    // Cameras the mode can select: 1 (nearest), 4 (idw4), 3 (continuous).
    let n_cams = select(select(3u, 4u, SELECTION == SELECTION_IDW4), 1u, SELECTION == SELECTION_NEAREST);
    // The point on the line closest to the content centre (bounding mode samples along v only).
    let pc = p - bc * v;
    // Proxy mode: a camera whose straight path to P is blocked by the proxy sees something else there
    // and does not vote; the others' weights are renormalised (all blocked: all vote, as without the
    // test). Then continuous mode blends log luminance (a weighted geometric mean) where the voting
    // cameras see light of similar size: luminance varies with direction multiplicatively (cosⁿ lobes,
    // highlights), and interpolating its logarithm across the camera spacing keeps the relative error
    // small where a linear blend of a peaked distribution is off by many percent; for a diffuse surface
    // both are exact. Where they disagree by far more than a lobe changes over a camera spacing, they
    // see different detail (a spot under a capture pixel caught by one camera and missed by the next, a
    // silhouette), and a geometric mean would lose its light (a 10⁶ cd/m² spot seen by one camera of
    // three: 100 cd/m² instead of 3·10⁵): there the blend turns linear, smoothly from a ratio of 8 to
    // one of 64 between the largest and smallest sample, and wholly where a camera sees no light. It
    // also turns linear where a camera's own footprint spans an edge (its spatial spread, see
    // sample_camera, from 0.2 to 0.5): the cameras then disagree because each samples the edge at
    // other points, not because the luminance changes with direction, and a geometric mean of such
    // samples loses light (peak's flux error 0.96 → 0.65 %). With the proxy, a camera none of whose
    // footprint texels holds light where others see it lit has not sampled the surface there (a dot
    // under a capture pixel at a grazing angle falls between its samples): it does not vote, as a
    // blocked camera does not (led-dots flux error 1.6 → 0.2 %). In nearest/idw4 (the reference's
    // methods) the blend is linear.
    var l = 0.0;
    var log_l = 0.0;
    var wsum = 0.0;
    var all_lit = true;
    var l_min = 3.0e38;
    var l_max = 0.0;
    var l_lit = 0.0;
    var w_lit = 0.0;
    // Per selected camera: ln L where it votes with light (the quadratic correction's corners).
    var lf = vec4<f32>(0.0);
    var n_lit = 0u;
    // (Written as plain loops: lavapipe ran the pass 1.6× slower, in every mode, with this in a
    // helper function returning a struct.)
    var blocked = vec4<bool>(false);
    if (PROXY && VISIBILITY && lum.bvh.z != 0u) {
        var n_blocked = 0u;
        var n_valid = 0u;
        for (var i = 0u; i < n_cams; i = i + 1u) {
            if (sel.cam[i] != EMPTY && sel.w[i] > 0.0) {
                n_valid = n_valid + 1u;
                blocked[i] = occluded(p, bitcast<vec3<f32>>(cameras[CAMERA_RECORD_VEC4S * sel.cam[i] + 5u].xyz));
                n_blocked = n_blocked + select(0u, 1u, blocked[i]);
            }
        }
        if (n_blocked == n_valid) {
            blocked = vec4<bool>(false);
        }
    }
    for (var i = 0u; i < n_cams; i = i + 1u) {
        if (sel.cam[i] != EMPTY && sel.w[i] > 0.0 && !blocked[i]) {
            var li: f32;
            if (TRIANGLES || CELLS) {
                li = luminance_of(varying_camera(in, i), p, v, proxy);
            } else {
                li = camera_luminance(sel.cam[i], p, v, proxy);
            }
            l = l + sel.w[i] * li;
            wsum = wsum + sel.w[i];
            if (li > 0.0) {
                lf[i] = log(li);
                n_lit = n_lit + 1u;
                log_l = log_l + sel.w[i] * lf[i];
                l_lit = l_lit + sel.w[i] * li;
                w_lit = w_lit + sel.w[i];
                l_min = min(l_min, li);
                l_max = max(l_max, li);
            } else {
                all_lit = false;
            }
        }
    }
    // A surface proxy: a camera that sampled no light where another sees it does not vote. A
    // bounding proxy (lum.gap.z = 1, a ray file's hull): darkness is the estimate's own, it votes.
    if (PROXY && SELECTION == SELECTION_CONTINUOUS && w_lit > 0.0 && lum.gap.z < 0.5) {
        l = l_lit;
        wsum = w_lit;
        all_lit = true;
    }
    if (wsum > 0.0) {
        l = l / wsum;
        if (SELECTION == SELECTION_CONTINUOUS && all_lit && l > 0.0) {
            // ln 8 … ln 64.
            let t = max(smoothstep(2.0794415, 4.1588831, log(l_max / l_min)), smoothstep(0.2, 0.5, spread));
            var mean_log = log_l / wsum;
            // Quadratic directional interpolation (src/nearfield/select/quadratic.rs), with the proxy
            // (without it each camera samples another point of the surface, and the differences are
            // not directional): where the three corners vote with light, the three cameras across the
            // triangle's edges are sampled at the same point, and −½ Σ wₚ w_q κ_pq (κ from the six values through the triangle's stencil)
            // corrects the blend's second-order error. Only inside the log regime, and only where the
            // neighbours see light within 8× of the corners and no footprint of the six spans an edge
            // (spread under 0.15): there the cameras differ by where they sample, not by direction.
            // Corners that agree within the storage's quantisation (a diffuse surface) have nothing
            // to correct, and skip the three extra samples.
            if (PROXY && spread < 0.15 && n_lit == 3u && sel.tri != EMPTY && wsum > 0.0
                && l_max > 1.002 * l_min && l_max <= 8.0 * l_min) {
                let qb = lum.lists_b.z + QUADRATIC_ENTRIES * sel.tri;
                let q0 = bitcast<vec4<u32>>(tris[qb]);
                if (q0.w == 1u) {
                    var fnb = vec3<f32>(0.0);
                    var ok = true;
                    var lo = l_min;
                    var hi = l_max;
                    for (var k = 0u; k < 3u; k = k + 1u) {
                        let cn = q0[k];
                        var ln = 0.0;
                        if (!(PROXY && VISIBILITY && lum.bvh.z != 0u
                            && occluded(p, bitcast<vec3<f32>>(cameras[CAMERA_RECORD_VEC4S * cn + 5u].xyz)))) {
                            ln = camera_luminance(cn, p, v, proxy);
                        }
                        ok = ok && ln > 0.0;
                        fnb[k] = log(max(ln, 1e-30));
                        lo = min(lo, ln);
                        hi = max(hi, ln);
                    }
                    if (ok && hi <= 8.0 * lo && spread < 0.15) {
                        let fv = lf.xyz;
                        let k0 = dot(tris[qb + 1u].xyz, fv) + dot(tris[qb + 2u].xyz, fnb);
                        let k1 = dot(tris[qb + 3u].xyz, fv) + dot(tris[qb + 4u].xyz, fnb);
                        let k2 = dot(tris[qb + 5u].xyz, fv) + dot(tris[qb + 6u].xyz, fnb);
                        let w = sel.w.xyz / wsum;
                        let corr = -0.5 * (w.x * w.y * k0 + w.y * w.z * k1 + w.z * w.x * k2);
                        // Corrections under the storage's quantisation (2⁻¹¹) are its noise, not a
                        // curvature: faded out below it.
                        let keep = smoothstep(0.00024, 0.00049, abs(corr));
                        mean_log = mean_log + keep * clamp(corr, -0.5, 0.5);
                    }
                }
            }
            l = mix(exp(mean_log), l, t);
        }
    }
    out.l = l;
    if (proxy) {
        out.keep = true;
    } else {
        out.keep = l > 0.0;
    }
    if (BOX) {
        // Stand-in depth: the plane through the content centre facing the eye.
        let n = towards_eye(draw.eye_local, lum.content.xyz);
        let dn = dot(v, n);
        var x = pc;
        if (abs(dn) > 1e-6) {
            x = p + (dot(lum.content.xyz - p, n) / dn) * v;
        }
        let c = draw.clip_from_local * vec4<f32>(x, 1.0);
        out.depth = clamp(c.z / c.w, 0.0, 1.0);
    }
    return out;
}

fn color_of(l: f32) -> vec4<f32> {
    return luminance_color(l, draw.params.x, draw.params.y > 0.5);
}

struct FsOutColor {
    @location(0) color: vec4<f32>,
};

struct FsBoxOut {
    @location(0) color: vec4<f32>,
    @location(1) depth: vec4<f32>,
    @builtin(frag_depth) frag_depth: f32,
};

struct FsBoxOutColor {
    @location(0) color: vec4<f32>,
    @builtin(frag_depth) frag_depth: f32,
};

// Shades, counts a read of a missing chunk, and discards what is not drawn.
fn shade_kept(in: VsOut) -> Shaded {
    let s = shade(in);
    if (missed) {
        atomicAdd(&misses[0], 1u);
    }
    if (!s.keep) {
        discard;
    }
    return s;
}

// With the host's depth as a colour attachment (depth copy) or without; the rasteriser's depth.
@fragment
fn fs_main(in: VsOut) -> FsOut {
    let s = shade_kept(in);
    return FsOut(color_of(s.l), vec4<f32>(s.depth, 0.0, 0.0, 1.0));
}

@fragment
fn fs_main_color_only(in: VsOut) -> FsOutColor {
    let s = shade_kept(in);
    return FsOutColor(color_of(s.l));
}

// The content box: the stand-in depth written by the fragment.
@fragment
fn fs_box(in: VsOut) -> FsBoxOut {
    let s = shade_kept(in);
    return FsBoxOut(color_of(s.l), vec4<f32>(s.depth, 0.0, 0.0, 1.0), s.depth);
}

@fragment
fn fs_box_color_only(in: VsOut) -> FsBoxOutColor {
    let s = shade_kept(in);
    return FsBoxOutColor(color_of(s.l), s.depth);
}
