// Far-field appearance pass: each instance of an IES/EULUMDAT luminaire drawn as its luminous
// opening, every fragment showing L(C, γ) = I / A_proj (cd/m²) for the direction from which the eye
// sees it, looked up in a node-aligned table (texel (i, j) at C = i·360/(W−1), γ = j·180/(H−1)).
// Also draws overlay lines (photometric-solid wireframe, housing box) with a constant colour.
//
// Outputs: location 0 = colour (linear cd/m² in RGB with alpha = coverage, or Reinhard-tone-mapped
// display value when params.y == 1), location 1 = the fragment's window depth in the host's own
// convention (the vertex stage remaps clip z for GL hosts), for hosts that sample depth as R32F.

struct Instance {
    // Luminaire frame -> wgpu clip space (host view · projection · model, with the host's depth range
    // and framebuffer origin folded in).
    clip_from_local: mat4x4<f32>,
    // Eye in the luminaire frame: xyz = position (w = 1) or direction towards the eye (w = 0, orthographic).
    eye_local: vec4<f32>,
    // x = exposure, y = mode (0 luminance, 1 tone mapped), z = luminance scale for lines, w = unused.
    params: vec4<f32>,
    // Overlay line colour (linear RGB in display units: multiplied by params.z in luminance mode).
    line_color: vec4<f32>,
};

@group(0) @binding(0) var<uniform> inst: Instance;
@group(1) @binding(0) var l_table: texture_2d<f32>;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) local_pos: vec3<f32>,
};

@vertex
fn vs_main(@location(0) pos: vec3<f32>) -> VsOut {
    var out: VsOut;
    out.clip = inst.clip_from_local * vec4<f32>(pos, 1.0);
    out.local_pos = pos;
    return out;
}

// Luminance (cd/m²) towards the unit direction d (luminaire frame), bilinear between table nodes,
// wrapping in C.
fn luminance_towards(d: vec3<f32>) -> f32 {
    let dims = vec2<i32>(textureDimensions(l_table));
    let gamma = acos(clamp(-d.z, -1.0, 1.0));
    var c = atan2(d.y, d.x);
    if (c < 0.0) {
        c = c + 2.0 * PI;
    }
    let u = c / (2.0 * PI) * f32(dims.x - 1);
    let v = gamma / PI * f32(dims.y - 1);
    let i0 = clamp(i32(floor(u)), 0, dims.x - 1);
    let j0 = clamp(i32(floor(v)), 0, dims.y - 1);
    let i1 = min(i0 + 1, dims.x - 1);
    let j1 = min(j0 + 1, dims.y - 1);
    let fu = clamp(u - f32(i0), 0.0, 1.0);
    let fv = clamp(v - f32(j0), 0.0, 1.0);
    let a = textureLoad(l_table, vec2<i32>(i0, j0), 0).r;
    let b = textureLoad(l_table, vec2<i32>(i1, j0), 0).r;
    let e = textureLoad(l_table, vec2<i32>(i0, j1), 0).r;
    let f = textureLoad(l_table, vec2<i32>(i1, j1), 0).r;
    return mix(mix(a, b, fu), mix(e, f, fu), fv);
}

fn opening_color(in: VsOut) -> vec4<f32> {
    let l = luminance_towards(towards_eye(inst.eye_local, in.local_pos));
    return luminance_color(l, inst.params.x, inst.params.y > 0.5);
}

fn line_color() -> vec4<f32> {
    if (inst.params.y > 0.5) {
        return vec4<f32>(inst.line_color.rgb, 1.0);
    }
    return vec4<f32>(inst.line_color.rgb * inst.params.z, 1.0);
}

// Entry points with the R32F depth output (targets with LUMI_DEPTH_R32F) ...
@fragment
fn fs_opening(in: VsOut) -> FsOut {
    return FsOut(opening_color(in), vec4<f32>(in.clip.z, 0.0, 0.0, 1.0));
}

@fragment
fn fs_line(in: VsOut) -> FsOut {
    return FsOut(line_color(), vec4<f32>(in.clip.z, 0.0, 0.0, 1.0));
}

// ... and without it (no unconsumed fragment outputs).
@fragment
fn fs_opening_color_only(in: VsOut) -> @location(0) vec4<f32> {
    return opening_color(in);
}

@fragment
fn fs_line_color_only(in: VsOut) -> @location(0) vec4<f32> {
    return line_color();
}
