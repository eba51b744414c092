// Scene lighting's shadow maps: the scene's triangles rendered, depth only, into one face of a
// luminaire's cube in the shadow atlas (the viewport selects the face's square). The face matrix
// maps world to clip as (right·v, up·v, SHADOW_NEAR_M, forward·v) for v = p − centre, so the stored
// depth is SHADOW_NEAR_M / (distance along the face's axis): reversed, with no far plane.
// src/gpu/scene/shadows.rs builds the matrices; shaders/scene/lighting.wgsl reads the depths.

struct ShadowFace {
    clip_from_world: mat4x4<f32>,
};

@group(0) @binding(0) var<uniform> face: ShadowFace;

@vertex
fn vs_shadow(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return face.clip_from_world * vec4<f32>(position, 1.0);
}

// Clears one face's square (the viewport) to the far depth 0 before it is rendered again: a
// full-screen triangle at depth 0 drawn with the depth test off.
@vertex
fn vs_clear(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let p = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(p * 2.0 - 1.0, 0.0, 1.0);
}
