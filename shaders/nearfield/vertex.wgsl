// Near-field pass, vertex stages (see pass.wgsl for the whole): the proxy or box, and the frame's
// bounding polygons with the records of their cameras as flat varyings.

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

// The frame's bounding polygons (src/nearfield/select/lit_bound/): a point and its selection triangle (or cell
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
