// Scene lighting's last step, drawn in the frame's render pass: a full-screen triangle that writes
// each pixel's lit colour (cs_lighting in shaders/scene/lighting.wgsl) with the depth of the surface
// the G-buffer pass found there, so the frame's depth test and R32F depth output are what drawing
// the scene's triangles would give. Pixels with no surface are left as they are.

@group(0) @binding(0) var lit: texture_2d<f32>;
@group(0) @binding(1) var surface_depth: texture_depth_2d;

@vertex
fn vs_composite(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let p = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(p * 2.0 - 1.0, 0.0, 1.0);
}

struct CompositeOut {
    @location(0) color: vec4<f32>,
    @location(1) depth_copy: vec4<f32>,
    @builtin(frag_depth) depth: f32,
};

struct CompositeColorOut {
    @location(0) color: vec4<f32>,
    @builtin(frag_depth) depth: f32,
};

// Entry points with the R32F depth output (targets with LUMI_DEPTH_R32F) ...
@fragment
fn fs_composite(@builtin(position) at: vec4<f32>) -> CompositeOut {
    let p = vec2<i32>(at.xy);
    let c = textureLoad(lit, p, 0);
    if (c.a == 0.0) {
        discard;
    }
    let d = textureLoad(surface_depth, p, 0);
    return CompositeOut(c, vec4<f32>(d, 0.0, 0.0, 1.0), d);
}

// ... and without it.
@fragment
fn fs_composite_color_only(@builtin(position) at: vec4<f32>) -> CompositeColorOut {
    let p = vec2<i32>(at.xy);
    let c = textureLoad(lit, p, 0);
    if (c.a == 0.0) {
        discard;
    }
    return CompositeColorOut(c, textureLoad(surface_depth, p, 0));
}
