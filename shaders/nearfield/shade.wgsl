// Near-field pass, shading (see pass.wgsl for the whole): a fragment's luminance. The selection
// modes live here, all of them: the SELECTION constant, each mode's camera selection over the cell
// tables (src/nearfield/select/ builds them), and every branch on SELECTION in the blend.

// The instance's selection (0 nearest, 1 idw4, 2 continuous) and whether it draws its proxy (else the
// bounding box, with the pipeline culling the faces that do not apply: back faces from outside the
// box, front faces from inside). Pipeline constants rather than per-draw data: a software rasteriser
// runs every case of a branch for every lane, so the selection's camera loop has a fixed count per
// pipeline (1, 4 or 3 cameras) and the other modes fold away.
override SELECTION: u32 = 2u;
override PROXY: bool = false;

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
    // methods) the blend is linear, and so it is over a proxy that only bounds the light (lum.gap.z =
    // 1, a ray file's hull): its cameras' images do not sample one surface point, so they differ by
    // where the light lies, not by direction, and a geometric mean of them loses light between the
    // cameras (a 10,000-ray cylinder's intensity read 5.5 % low midway between two cameras 12° apart,
    // 0.8 % at the cameras); linear weights summing to one keep the intensity the cameras hold.
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
        if (SELECTION == SELECTION_CONTINUOUS && all_lit && l > 0.0 && lum.gap.z < 0.5) {
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
