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
//
// The pass is assembled by src/gpu/shaders.rs, after the generated constants and
// shaders/common/common.wgsl, from these parts in this order (each uses only what comes before it):
// - pass.wgsl (this file): what a fragment does, the storage blocks and bindings, the pipeline
//   constants, the camera records;
// - sampling.wgsl: tiles read from the residency pool, a camera's bilinear sample;
// - visibility.wgsl: the proxy's BVH ray cast (does the proxy block a camera's path to P?);
// - vertex.wgsl: the vertex stages and the varyings that carry a raster polygon's cameras;
// - shade.wgsl: a fragment's luminance: camera selection in every mode (every branch on SELECTION
//   is there) and the blend;
// - fragment.wgsl: the fragment entry points and their outputs.

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
// (pool_word, sampling.wgsl) folds away, which matters on a software rasteriser that would run every
// case for every lane.
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

// The proxy has a hierarchy for the visibility test (src/nearfield/bvh.rs); a planar proxy has none
// (it cannot block the path from a point on it to a camera), and its pipelines leave the test out.
override VISIBILITY: bool = true;

// Continuous mode without a proxy, drawn as the triangle raster (src/nearfield/select/lit_bound/): each polygon
// covers one selection triangle's region (vertex attribute `tri`) and the fragment takes that
// triangle's weights directly, without the cell search.
override TRIANGLES: bool = false;

// Nearest mode without a proxy, drawn as the cell raster (src/nearfield/select/lit_bound/): each polygon covers
// (a little more than) one camera's Voronoi cell, `tri` naming the camera; the fragment runs the usual
// selection and is kept only where it picks that camera, so overlapping cells write each pixel once.
override CELLS: bool = false;

// The draw is the content box: the fragment writes the stand-in depth itself (entry points fs_box*).
// Proxy and polygon draws take the rasteriser's depth: the proxy's own, or the polygon's, which lies
// on the stand-in plane already (src/nearfield/select/lit_bound/), and write no frag_depth.
override BOX: bool = false;

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
