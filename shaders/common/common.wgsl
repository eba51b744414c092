// Shared by every pass: src/gpu/shaders.rs joins, in this order, the constants it generates from
// the Rust definitions (EMPTY, CAMERA_RECORD_VEC4S, QUADRATIC_ENTRIES), this file, and the pass's
// own file. Nothing here reads a pass's bindings.

const PI: f32 = 3.14159265358979;

// Reinhard tone mapping with an exposure (m²/cd): x = L · exposure, display value x / (1 + x).
fn reinhard(l: f32, exposure: f32) -> f32 {
    let x = max(l * exposure, 0.0);
    return x / (1.0 + x);
}

// The colour of a luminance (cd/m²): linear in RGB (alpha 1), or Reinhard-tone-mapped when
// `tone_mapped` (the draw's params.y == 1).
fn luminance_color(l: f32, exposure: f32, tone_mapped: bool) -> vec4<f32> {
    if (tone_mapped) {
        let t = reinhard(l, exposure);
        return vec4<f32>(t, t, t, 1.0);
    }
    return vec4<f32>(l, l, l, 1.0);
}

// Unit direction from the point p towards the eye, both in the luminaire frame: `eye` is the eye's
// position (w = 1, perspective) or the direction towards it (w = 0, orthographic).
fn towards_eye(eye: vec4<f32>, p: vec3<f32>) -> vec3<f32> {
    if (eye.w > 0.5) {
        return normalize(eye.xyz - p);
    }
    return normalize(eye.xyz);
}

// Colour and the fragment's window depth as a colour (the R32F depth output).
struct FsOut {
    @location(0) color: vec4<f32>,
    @location(1) depth: vec4<f32>,
};
