// Near-field pass, fragment entry points (see pass.wgsl for the whole): shade, count a read of a
// missing chunk, and write colour (and depth) for each kind of draw.

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
