// Scene lighting pass (issue 20; docs/scene-lighting.md, "The GPU pass" and "Inter-reflection"):
// the scene's triangles drawn from the host's camera into the surface each pixel sees (fs_surface),
// each pixel then lit once (cs_lighting; or each fragment as it is drawn, fs_scene, for frames
// too large for the per-pixel images) by every photometric luminaire whose influence sphere reaches
// it (the pixel's screen tile lists them), with visibility from the luminaires' cube shadow maps,
// plus the inter-reflected light of the virtual point lights (scene::vpl), reflectance from the
// base colour and its texture. Output: L = ρ·E/π per RGB channel (Lambertian; the luminance Y of
// the colour is ρ_Y·E/π in cd/m²), or its Reinhard-tone-mapped display value; plus the R32F depth
// (shaders/scene/composite.wgsl writes the compute lighting's pixels into the frame).
//
// Direct illuminance of one luminaire at x (normal n, turned towards the eye): its opening is cut
// into na × nb stratified points s_k (the midpoints of the cells of its parameterisation, uniform
// in area; fewer where the opening looks small from x, OPENING_POINT_RAD; one point, the
// photometric centre, when it has no area); each carries I(x − s_k)/N:
//   E = Σ_k I(x − s_k)/N · max(0, n·(s_k − x)) / |s_k − x|³ · V_k.
// V_k comes from the cube shadow map rendered from the photometric centre c (depth along the face
// axis, reversed and infinite: depth = SHADOW_NEAR_M / distance along the axis), PCSS-like:
//   1. blocker search: points b on the segments x → s_k towards at most SEARCH_GRID² of the
//      opening's points (at SEARCH_AT of their length) are looked up; a texel
//      occludes b when its surface lies nearer to c than (1 + SHADOW_REACH)·|b − c| and nearer
//      than the receiver plane (through x, normal n) along the texel centre's own ray (so the
//      receiver's plane never shadows itself);
//   2. with d_b the mean distance of the blockers found and d_r = |x − c|, the segment x → s_k is
//      taken to cross the blockers at b_k = x + (s_k − x)(1 − d_b/d_r): V_k = 0 when b_k's texel
//      occludes. For one planar blocker parallel to the receiver this is exact (similar triangles);
//      a point source (s = c) gets the hard shadow of x's own texel.

struct SceneFrame {
    // World -> wgpu clip space (the host's view · projection with its depth range and origin).
    clip_from_world: mat4x4<f32>,
    // xyz = the eye (w = 1) or the direction towards it (w = 0, orthographic).
    eye: vec4<f32>,
    // x = exposure (m²/cd), y = mode (0 luminance, 1 tone mapped), z = lux floor, w = the VPL
    // clamp distance squared (m²).
    params: vec4<f32>,
    // x = tile size (px), y = tiles across, z = tiles down, w = number of luminaires.
    tiles: vec4<u32>,
    // x = intensity tables per atlas row, y = shadow faces per atlas row, z = face size (px),
    // w = 1 with shadows, 0 without.
    atlas: vec4<u32>,
    // x = virtual point lights gathered (0: no inter-reflection); yzw unused.
    indirect: vec4<u32>,
};

// A virtual point light (scene::vpl): a point of a surface that reflects `flux` (lm per channel)
// to the side its normal faces, as a Lambertian emitter.
struct Vpl {
    position: vec4<f32>,
    normal: vec4<f32>,
    flux: vec4<f32>,
};

struct Light {
    // xyz = photometric centre (world m), w = influence radius (m).
    centre: vec4<f32>,
    // Rows of the luminaire-from-world rotation (xyz; w unused).
    local_x: vec4<f32>,
    local_y: vec4<f32>,
    local_z: vec4<f32>,
    // Opening half-axes in world metres (xyz); w = stratified points along the axis.
    axis_a: vec4<f32>,
    axis_b: vec4<f32>,
    // x = intensity table, y = first of its six shadow faces, z = 1 for an elliptic opening, w = unused.
    tables: vec4<u32>,
};

@group(0) @binding(0) var<uniform> frame: SceneFrame;
@group(0) @binding(1) var<storage, read> lights: array<Light>;
// Per screen tile (row-major) a pair (first, count) into the indices after the pairs.
@group(0) @binding(2) var<storage, read> tile_lists: array<u32>;
// I(C, γ) in cd, one INTENSITY_TABLE_W × INTENSITY_TABLE_H table per photometry, node-aligned
// (texel (i, j) at C = i·360/(W−1), γ = j·180/(H−1)).
@group(0) @binding(3) var intensity_atlas: texture_2d<f32>;
// Six faces per luminaire (CUBE_FORWARD order), face size frame.atlas.z.
@group(0) @binding(4) var shadow_atlas: texture_depth_2d;
// frame.indirect.x of them (the buffer holds at least one).
@group(0) @binding(5) var<storage, read> vpls: array<Vpl>;
// The scene's base-colour textures (sRGB, read as linear), one rectangle each.
@group(0) @binding(6) var textures: texture_2d<f32>;
@group(0) @binding(7) var<storage, read> texture_records: array<TextureRecord>;

// Where a material's texture lies in `textures` and how it is sampled (gpu::scene::TextureRecord).
struct TextureRecord {
    // x, y of its top-left texel; width, height.
    rect: vec4<u32>,
    // Wrap s, wrap t (0 repeat, 1 clamp to edge, 2 mirrored repeat), filter (0 nearest, 1 linear).
    mode: vec4<u32>,
};

struct VsIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) reflectance: vec3<f32>,
    @location(3) uv: vec2<f32>,
    @location(4) texture: f32,
};

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) reflectance: vec3<f32>,
    @location(3) uv: vec2<f32>,
    // The texture record + 1 (0: none).
    @location(4) @interpolate(flat) texture: u32,
};

@vertex
fn vs_scene(v: VsIn) -> VsOut {
    var out: VsOut;
    out.clip = frame.clip_from_world * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.reflectance = v.reflectance;
    out.uv = v.uv;
    out.texture = u32(v.texture + 0.5);
    return out;
}

// Intensity (cd) of table `table` towards the direction d of the luminaire frame, bilinear between
// the table's nodes, wrapping in C.
fn intensity_cd(table: u32, d: vec3<f32>) -> f32 {
    let w = i32(INTENSITY_TABLE_W);
    let h = i32(INTENSITY_TABLE_H);
    let per_row = frame.atlas.x;
    let origin = vec2<i32>(i32(table % per_row) * w, i32(table / per_row) * h);
    let gamma = atan2(length(d.xy), -d.z);
    var c = atan2(d.y, d.x);
    if (c < 0.0) {
        c = c + 2.0 * PI;
    }
    let u = c / (2.0 * PI) * f32(w - 1);
    let v = gamma / PI * f32(h - 1);
    let i0 = clamp(i32(floor(u)), 0, w - 1);
    let j0 = clamp(i32(floor(v)), 0, h - 1);
    let i1 = min(i0 + 1, w - 1);
    let j1 = min(j0 + 1, h - 1);
    let fu = clamp(u - f32(i0), 0.0, 1.0);
    let fv = clamp(v - f32(j0), 0.0, 1.0);
    let a = textureLoad(intensity_atlas, origin + vec2<i32>(i0, j0), 0).r;
    let b = textureLoad(intensity_atlas, origin + vec2<i32>(i1, j0), 0).r;
    let e = textureLoad(intensity_atlas, origin + vec2<i32>(i0, j1), 0).r;
    let f = textureLoad(intensity_atlas, origin + vec2<i32>(i1, j1), 0).r;
    return mix(mix(a, b, fu), mix(e, f, fu), fv);
}

// The cube face a direction falls on (CUBE_FORWARD order: +X, −X, +Y, −Y, +Z, −Z).
fn cube_face(d: vec3<f32>) -> u32 {
    let a = abs(d);
    if (a.x >= a.y && a.x >= a.z) {
        return select(1u, 0u, d.x >= 0.0);
    }
    if (a.y >= a.z) {
        return select(3u, 2u, d.y >= 0.0);
    }
    return select(5u, 4u, d.z >= 0.0);
}

// Whether the shadow map of `light` holds a surface that blocks the point b (on a segment from the
// receiver x towards the opening): the surface seen from the centre c through b lies nearer to c
// than b's own distance times (1 + SHADOW_REACH) (at b, or a little behind it) and than x, and nearer than the
// receiver plane (through x, normal n) along the same texel's ray (so the receiver's own plane
// never shadows itself, and surfaces beyond it do not count). Returns that surface's distance from
// c (m), or −1 when it does not block (or nothing was drawn there).
fn occluder_m(light: Light, b: vec3<f32>, x: vec3<f32>, n: vec3<f32>) -> f32 {
    let d = b - light.centre.xyz;
    let face = cube_face(d);
    let forward = CUBE_FORWARD[face];
    let right = CUBE_RIGHT[face];
    let up = CUBE_UP[face];
    let fd = dot(forward, d);
    let size = i32(frame.atlas.z);
    let s = f32(size);
    let ndc = vec2<f32>(dot(right, d), dot(up, d)) / fd;
    let px = clamp(i32(floor((ndc.x * 0.5 + 0.5) * s)), 0, size - 1);
    let py = clamp(i32(floor((0.5 - ndc.y * 0.5) * s)), 0, size - 1);
    let tile = light.tables.y + face;
    let per_row = frame.atlas.y;
    let origin = vec2<i32>(i32(tile % per_row) * size, i32(tile / per_row) * size);
    let depth = textureLoad(shadow_atlas, origin + vec2<i32>(px, py), 0);
    if (depth <= 0.0) {
        return -1.0;
    }
    let along_m = SHADOW_NEAR_M / depth;
    // The texel centre's ray, with a unit component along the face's axis.
    let cx = (f32(px) + 0.5) / s * 2.0 - 1.0;
    let cy = 1.0 - (f32(py) + 0.5) / s * 2.0;
    let ray = forward + cx * right + cy * up;
    let surface_m = along_m * length(ray);
    // Nothing farther from the centre than the receiver lies on a segment from it to the opening
    // (up to the opening's own size): a surface beyond x (the floor past a cabinet's foot, seen
    // through the nearest search point) does not block.
    if (surface_m > min(length(d) * (1.0 + SHADOW_REACH), length(x - light.centre.xyz))) {
        return -1.0;
    }
    let denom = dot(n, ray);
    if (denom >= 0.0) {
        return surface_m;
    }
    let plane_m = dot(n, x - light.centre.xyz) / denom;
    if (along_m < plane_m * (1.0 - SHADOW_RELATIVE_BIAS)) {
        return surface_m;
    }
    return -1.0;
}

// The k-th stratified point of the opening (world) on an na × nb grid, k < na·nb.
fn opening_point(light: Light, k: u32, na: u32, nb: u32) -> vec3<f32> {
    var s = (f32(k % na) + 0.5) / f32(na) * 2.0 - 1.0;
    var t = (f32(k / na) + 0.5) / f32(nb) * 2.0 - 1.0;
    if (light.tables.z == 1u && (s != 0.0 || t != 0.0)) {
        // Shirley–Chiu concentric map from the square to the disc (area-preserving).
        let q = PI / 4.0;
        var r: f32;
        var phi: f32;
        if (abs(s) > abs(t)) {
            r = s;
            phi = q * (t / s);
        } else {
            r = t;
            phi = 2.0 * q - q * (s / t);
        }
        s = r * cos(phi);
        t = r * sin(phi);
    }
    return light.centre.xyz + s * light.axis_a.xyz + t * light.axis_b.xyz;
}

// The largest angle (radians) between neighbouring opening points seen from the receiver: a
// 1.2 m opening keeps its 16 points out to 3.75 m, a 0.6 m one has 3 at 10 m and 1 beyond 30 m.
// Sampling the opening at this resolution changes the unshadowed illuminance by less than 0.1 %
// and a penumbra by less than the angle's share of its width.
const OPENING_POINT_RAD: f32 = 0.02;

// Where along each segment from the receiver to an opening point the blockers are looked for. The
// nearest, 1/32 of the way, finds a blocker just in front of the receiver (the foot of a low box):
// a texel counts up to (1 + SHADOW_REACH) times the point's distance from the centre.
const SEARCH_AT = array<f32, 5>(0.03125, 0.125, 0.25, 0.5, 0.75);

// Opening points per axis the blocker search looks towards.
const SEARCH_GRID: u32 = 3u;

// Direct illuminance (lx) at x (normal n facing the side lit) from one luminaire.
fn light_lx(light: Light, x: vec3<f32>, n: vec3<f32>) -> f32 {
    let c = light.centre.xyz;
    let d_r = length(x - c);
    if (d_r > light.centre.w || d_r <= 0.0) {
        return 0.0;
    }
    // Fewer points for an opening that looks small from x: no two neighbours more than
    // OPENING_POINT_RAD apart as seen from x along either axis (at most the light's own grid).
    let na = clamp(u32(ceil(2.0 * length(light.axis_a.xyz) / (d_r * OPENING_POINT_RAD))), 1u, u32(light.axis_a.w));
    let nb = clamp(u32(ceil(2.0 * length(light.axis_b.xyz) / (d_r * OPENING_POINT_RAD))), 1u, u32(light.axis_b.w));
    let count = na * nb;
    let shadows = frame.atlas.w == 1u;
    // 1. Blocker search.
    var blockers = 0.0;
    var blocker_sum_m = 0.0;
    // The search looks towards at most 3 × 3 points of the opening (its coarser stratification):
    // the blocker depth varies slowly across an opening, the visibility test below uses every point.
    let sa = min(na, SEARCH_GRID);
    let sb = min(nb, SEARCH_GRID);
    if (shadows) {
        for (var k = 0u; k < sa * sb; k = k + 1u) {
            let s = opening_point(light, k, sa, sb);
            for (var j = 0u; j < 5u; j = j + 1u) {
                let b = x + (s - x) * SEARCH_AT[j];
                let o = occluder_m(light, b, x, n);
                if (o > 0.0) {
                    blockers = blockers + 1.0;
                    blocker_sum_m = blocker_sum_m + o;
                }
            }
        }
    }
    let lambda = clamp(1.0 - blocker_sum_m / max(blockers, 1.0) / d_r, 0.0, 1.0);
    // 2. Each point's intensity, incidence, distance and visibility.
    var e = 0.0;
    for (var k = 0u; k < count; k = k + 1u) {
        let s = opening_point(light, k, na, nb);
        let to_s = s - x;
        let r2 = dot(to_s, to_s);
        let cos_i = dot(n, to_s) * inverseSqrt(r2);
        if (cos_i <= 0.0) {
            continue;
        }
        if (blockers > 0.0) {
            let b = x + to_s * lambda;
            if (occluder_m(light, b, x, n) > 0.0) {
                continue;
            }
        }
        let d = -to_s;
        let local = vec3<f32>(dot(light.local_x.xyz, d), dot(light.local_y.xyz, d), dot(light.local_z.xyz, d));
        e = e + intensity_cd(light.tables.x, local) * cos_i / r2;
    }
    return e / f32(count);
}

// Direct illuminance (lx) at x with normal n from every luminaire listed for the screen tile of
// the fragment at `frag` (framebuffer pixels).
fn direct_lx(frag: vec2<f32>, x: vec3<f32>, n: vec3<f32>) -> f32 {
    let tile_px = f32(frame.tiles.x);
    let tx = min(u32(frag.x / tile_px), frame.tiles.y - 1u);
    let ty = min(u32(frag.y / tile_px), frame.tiles.z - 1u);
    let tile = ty * frame.tiles.y + tx;
    let first = tile_lists[2u * tile];
    let count = tile_lists[2u * tile + 1u];
    var e = 0.0;
    for (var i = 0u; i < count; i = i + 1u) {
        e = e + light_lx(lights[tile_lists[first + i]], x, n);
    }
    return e;
}

// Inter-reflected illuminance (lx per channel) at x with normal n: every VPL at y (normal n_y,
// flux Φ) gives Φ cos θ_y cos θ_x / (π · max(r², clamp²)), without visibility (scene::vpl).
fn indirect_lx(x: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let clamp2 = frame.params.w;
    var e = vec3<f32>(0.0);
    for (var i = 0u; i < frame.indirect.x; i = i + 1u) {
        let v = vpls[i];
        let d = x - v.position.xyz;
        let r2 = dot(d, d);
        if (r2 <= 0.0) {
            continue;
        }
        let inv_r = inverseSqrt(r2);
        let cos_v = dot(v.normal.xyz, d) * inv_r;
        let cos_x = -dot(n, d) * inv_r;
        if (cos_v <= 0.0 || cos_x <= 0.0) {
            continue;
        }
        e = e + v.flux.xyz * (cos_v * cos_x / (PI * max(r2, clamp2)));
    }
    return e;
}

// A texel index in 0…n−1 of the (possibly outside) index i under wrap mode `mode`.
fn wrap_texel(i: i32, n: i32, mode: u32) -> i32 {
    if (mode == 1u) {
        return clamp(i, 0, n - 1);
    }
    if (mode == 2u) {
        let m = ((i % (2 * n)) + 2 * n) % (2 * n);
        return select(2 * n - 1 - m, m, m < n);
    }
    return ((i % n) + n) % n;
}

// The linear RGB of texture record r at uv, as scene::texture samples it (⌊u·w⌋ for nearest; the
// four texels around u·w − ½ for linear; glTF's wrap modes).
fn texture_rgb(r: TextureRecord, uv_in: vec2<f32>) -> vec3<f32> {
    let far = 1048576.0;
    let uv = clamp(uv_in, vec2<f32>(-far), vec2<f32>(far));
    let origin = vec2<i32>(r.rect.xy);
    let n = vec2<i32>(r.rect.zw);
    let p = uv * vec2<f32>(n) - 0.5;
    if (r.mode.z == 0u) {
        let i = wrap_texel(i32(floor(p.x + 0.5)), n.x, r.mode.x);
        let j = wrap_texel(i32(floor(p.y + 0.5)), n.y, r.mode.y);
        return textureLoad(textures, origin + vec2<i32>(i, j), 0).rgb;
    }
    let f = floor(p);
    let t = p - f;
    let i0 = wrap_texel(i32(f.x), n.x, r.mode.x);
    let i1 = wrap_texel(i32(f.x) + 1, n.x, r.mode.x);
    let j0 = wrap_texel(i32(f.y), n.y, r.mode.y);
    let j1 = wrap_texel(i32(f.y) + 1, n.y, r.mode.y);
    let a = textureLoad(textures, origin + vec2<i32>(i0, j0), 0).rgb;
    let b = textureLoad(textures, origin + vec2<i32>(i1, j0), 0).rgb;
    let c = textureLoad(textures, origin + vec2<i32>(i0, j1), 0).rgb;
    let d = textureLoad(textures, origin + vec2<i32>(i1, j1), 0).rgb;
    return mix(mix(a, b, t.x), mix(c, d, t.x), t.y);
}

// Unit normal n as two numbers (octahedral map: n / (|x| + |y| + |z|), the lower half folded out),
// exact to about 1e-7 in f32.
fn octahedral(n: vec3<f32>) -> vec2<f32> {
    let p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if (n.z >= 0.0) {
        return p;
    }
    return (1.0 - abs(p.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
}

// The unit normal of octahedral(n).
fn from_octahedral(e: vec2<f32>) -> vec3<f32> {
    var v = vec3<f32>(e, 1.0 - abs(e.x) - abs(e.y));
    let t = max(-v.z, 0.0);
    v.x = v.x + select(t, -t, v.x >= 0.0);
    v.y = v.y + select(t, -t, v.y >= 0.0);
    return normalize(v);
}

// The surface each pixel sees, written by the G-buffer pass (fs_surface) and lit by cs_lighting:
// `surface` = (world position m, ρ_b), `facing` = (octahedral normal of the side seen, ρ_r, ρ_g);
// a pixel with no surface keeps the clear value facing.x = NO_SURFACE.
struct SurfaceOut {
    @location(0) surface: vec4<f32>,
    @location(1) facing: vec4<f32>,
};

const NO_SURFACE: f32 = 2.0;

// The fragment's unit normal turned towards the eye (two-sided: the side seen is the side lit).
fn seen_normal(in: VsOut) -> vec3<f32> {
    var to_eye = frame.eye.xyz;
    if (frame.eye.w > 0.5) {
        to_eye = frame.eye.xyz - in.world;
    }
    let n = normalize(in.normal);
    return select(n, -n, dot(n, to_eye) < 0.0);
}

// The fragment's reflectance per channel: base colour × texture.
fn reflectance(in: VsOut) -> vec3<f32> {
    if (in.texture > 0u) {
        return in.reflectance * texture_rgb(texture_records[in.texture - 1u], in.uv);
    }
    return in.reflectance;
}

// The colour of a surface point x (normal n towards the eye, reflectance rho) seen by the pixel
// whose centre is `frag` (framebuffer pixels): L = ρ·E/π per channel, E direct (the pixel's
// tile's luminaires) plus inter-reflected, or its tone-mapped value.
fn lit_color(frag: vec2<f32>, x: vec3<f32>, n: vec3<f32>, rho: vec3<f32>) -> vec4<f32> {
    let e = vec3<f32>(direct_lx(frag, x, n)) + indirect_lx(x, n);
    let l = rho * (e / PI);
    if (frame.params.y > 0.5) {
        let exposure = frame.params.x;
        return vec4<f32>(reinhard(l.r, exposure), reinhard(l.g, exposure), reinhard(l.b, exposure), 1.0);
    }
    return vec4<f32>(l, 1.0);
}

// The G-buffer pass's fragment: the surface, its normal and its reflectance.
@fragment
fn fs_surface(in: VsOut) -> SurfaceOut {
    let n = seen_normal(in);
    let rho = reflectance(in);
    return SurfaceOut(vec4<f32>(in.world, rho.b), vec4<f32>(octahedral(n), rho.r, rho.g));
}

// Lighting per fragment as the scene's triangles are drawn (frames larger than
// SceneSettings::deferred_max_pixels): with the R32F depth output (targets with LUMI_DEPTH_R32F) ...
@fragment
fn fs_scene(in: VsOut) -> FsOut {
    return FsOut(lit_color(in.clip.xy, in.world, seen_normal(in), reflectance(in)), vec4<f32>(in.clip.z, 0.0, 0.0, 1.0));
}

// ... and without it.
@fragment
fn fs_scene_color_only(in: VsOut) -> @location(0) vec4<f32> {
    return lit_color(in.clip.xy, in.world, seen_normal(in), reflectance(in));
}

@group(1) @binding(0) var surfaces: texture_2d<f32>;
@group(1) @binding(1) var facings: texture_2d<f32>;
// The lit colour of every pixel (alpha 0 where no surface is), drawn into the frame by
// shaders/scene/composite.wgsl.
@group(1) @binding(2) var lit: texture_storage_2d<rgba32float, write>;

// Lighting, once per pixel, of the surface it sees (a compute pass: fragments the depth test hid
// cost nothing, and the work runs on every compute unit, where a data-centre GPU runs fragment
// shaders on a few of them only).
@compute @workgroup_size(8, 8)
fn cs_lighting(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(lit);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let p = vec2<i32>(id.xy);
    let s = textureLoad(surfaces, p, 0);
    let f = textureLoad(facings, p, 0);
    if (f.x > 1.5) {
        textureStore(lit, p, vec4<f32>(0.0));
        return;
    }
    // The pixel's centre, as a fragment's position would be.
    let frag = vec2<f32>(id.xy) + vec2<f32>(0.5);
    textureStore(lit, p, lit_color(frag, s.xyz, from_octahedral(f.xy), vec3<f32>(f.z, f.w, s.w)));
}
