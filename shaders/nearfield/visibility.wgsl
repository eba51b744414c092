// Near-field pass, visibility (see pass.wgsl for the whole): whether the proxy blocks the path from
// a surface point to a camera.

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
