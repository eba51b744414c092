//! Quadratic directional interpolation over a selection triangle and its three edge neighbours.
//!
//! Continuous selection blends the three cameras of the triangle around the view's sphere point with
//! their barycentric weights w: exact for a (log-)luminance that is linear over the triangle, off by
//! a second-order term otherwise. For barycentric coordinates, any quadratic f obeys
//!
//!   f(x) = Σ wₚ f(xₚ) − ½ Σ_{p<q} wₚ w_q κ_pq,
//!
//! with κ_pq the second difference of f along the edge pq (eᵀ H e for the edge vector e and the
//! Hessian H), for every x including points outside the triangle (negative coordinates). A vertex n
//! next to the triangle, with coordinates a, gives one equation a·f − f(n) = ½ (a₀a₁, a₁a₂, a₂a₀)·κ;
//! three of them give κ = K · (f₀, f₁, f₂, f(n₀), f(n₁), f(n₂)), a 3 × 6 matrix that depends on the
//! directions only and is computed here once per triangle. The three are chosen among the corners'
//! other neighbours for the smallest K: the vertices across the edges lie close to a conic through
//! the corners near the poles of a `rigo` layout, whose rows are small circles there. The shader samples the three neighbours' cameras at the same surface point and
//! subtracts ½ Σ wₚ w_q κ_pq from the blended log-luminance, which removes the interpolation's
//! second-order error (cos¹⁰⁰ across 0.85° camera spacing: 0.4 % → see docs/nearfield-rendering.md).

use glam::DVec3;

/// The stencil of one triangle: three vertices next to it and the rows of K (κ₀₁, κ₁₂, κ₂₀ from the
/// triangle's values then the neighbours').
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stencil {
    /// The three vertices (next to the triangle) whose values complete the stencil.
    pub neighbours: [u32; 3],
    /// κ = K · (f₀, f₁, f₂, f(n₀), f(n₁), f(n₂)).
    pub k: [[f64; 6]; 3],
}

/// Largest |K| entry: the fp16 storage error of the six samples (2⁻¹² relative) is amplified by
/// K in κ. Where the plain solution exceeds it (the six directions close to a conic, as on the
/// regular rows of a `rigo` layout near its poles) the system is regularised (Tikhonov, κ of least
/// norm along the poorly determined direction), which corrects less there instead of adding noise.
const MAX_K: f64 = 64.0;

/// Normalised barycentric coordinates of `x` in the triangle whose edge cross products are `cross`
/// ((b×c, c×a, a×b)), as the shader computes them (central projection).
fn coords(cross: &[DVec3; 3], x: DVec3) -> Option<[f64; 3]> {
    let e = [x.dot(cross[0]), x.dot(cross[1]), x.dot(cross[2])];
    let s = e[0] + e[1] + e[2];
    (s.abs() > 1e-300).then(|| [e[0] / s, e[1] / s, e[2] / s])
}

fn invert3(m: [[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let c = |r: usize, k: usize| {
        let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
        let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
        m[r1][k1] * m[r2][k2] - m[r1][k2] * m[r2][k1]
    };
    let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    let scale = m.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    if !(det.is_finite() && det.abs() > 1e-12 * scale.powi(3)) {
        return None;
    }
    let mut inv = [[0.0; 3]; 3];
    for (r, row) in inv.iter_mut().enumerate() {
        for (k, v) in row.iter_mut().enumerate() {
            // Adjugate: transpose of the cofactors.
            *v = c(k, r) / det;
        }
    }
    Some(inv)
}

/// The stencil of every triangle (`None` for a hole, a triangle next to a hole or the mesh's edge,
/// or a degenerate system). `tris` are vertex indices into `dirs`, `cross` their edge cross products.
pub fn stencils(dirs: &[DVec3], tris: &[[u32; 3]], cross: &[[DVec3; 3]], hole: &[bool]) -> Vec<Option<Stencil>> {
    // Per edge (low, high): how many non-hole triangles share it; per vertex: the vertices it shares
    // a non-hole edge with.
    let mut edges: std::collections::HashMap<(u32, u32), u8> = std::collections::HashMap::new();
    let mut ring: Vec<Vec<u32>> = vec![Vec::new(); dirs.len()];
    for (t, tri) in tris.iter().enumerate() {
        if hole[t] {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            ring[a as usize].push(b);
            ring[b as usize].push(a);
        }
    }
    for r in &mut ring {
        r.sort_unstable();
        r.dedup();
    }
    tris.iter()
        .enumerate()
        .map(|(t, tri)| {
            if hole[t] {
                return None;
            }
            // Every edge must have a neighbouring triangle (not at the mesh's edge or a hole's).
            for k in 0..3 {
                let (p, q) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
                if edges.get(&(p.min(q), p.max(q))).copied().unwrap_or(0) < 2 {
                    return None;
                }
            }
            // Candidates: the corners' other neighbours. Of every three, the best conditioned.
            let mut cand: Vec<u32> = tri
                .iter()
                .flat_map(|&v| ring[v as usize].iter().copied())
                .filter(|v| !tri.contains(v))
                .collect();
            cand.sort_unstable();
            cand.dedup();
            let coords_of: Vec<[f64; 3]> = cand
                .iter()
                .map(|&v| coords(&cross[t], dirs[v as usize]))
                .collect::<Option<_>>()?;
            let mut best: Option<(f64, Stencil)> = None;
            for i in 0..cand.len() {
                for j in i + 1..cand.len() {
                    for l in j + 1..cand.len() {
                        let pick = [i, j, l];
                        if let Some((big, st)) = solve(pick.map(|x| cand[x]), pick.map(|x| coords_of[x])) {
                            if best.as_ref().is_none_or(|(b, _)| big < *b) {
                                best = Some((big, st));
                            }
                        }
                    }
                }
            }
            best.map(|(_, st)| st)
        })
        .collect()
}

/// The stencil for neighbours `n` with barycentric coordinates `a`, and its largest |K| entry:
/// regularised until that is at most [`MAX_K`]; `None` when even that fails.
fn solve(neighbours: [u32; 3], a: [[f64; 3]; 3]) -> Option<(f64, Stencil)> {
    let m: [[f64; 3]; 3] = a.map(|c| [0.5 * c[0] * c[1], 0.5 * c[1] * c[2], 0.5 * c[2] * c[0]]);
    // κ = P (A f − f_n) with P = (MᵀM + λI)⁻¹ Mᵀ (M⁻¹ for λ = 0): K = [P A | −P].
    let mtm = |lambda: f64| {
        let mut r = [[0.0f64; 3]; 3];
        for (i, row) in r.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = (0..3).map(|q| m[q][i] * m[q][j]).sum::<f64>() + if i == j { lambda } else { 0.0 };
            }
        }
        r
    };
    let trace = (0..3).map(|i| mtm(0.0)[i][i]).sum::<f64>() / 3.0;
    let mut lambda = 0.0;
    let mut first = true;
    for _ in 0..40 {
        let inv = invert3(mtm(lambda))?;
        let mut pm = [[0.0f64; 3]; 3];
        for (r, row) in pm.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = (0..3).map(|i| inv[r][i] * m[j][i]).sum();
            }
        }
        let mut k = [[0.0f64; 6]; 3];
        for r in 0..3 {
            for j in 0..3 {
                k[r][j] = (0..3).map(|i| pm[r][i] * a[i][j]).sum();
                k[r][3 + j] = -pm[r][j];
            }
        }
        let big = k.iter().flatten().fold(0.0f64, |acc, v| acc.max(v.abs()));
        if big.is_finite() && big <= MAX_K {
            // A regularised solution ranks behind every exact one.
            let rank = if first { big } else { MAX_K + lambda / trace.max(1e-300) };
            return Some((rank, Stencil { neighbours, k }));
        }
        first = false;
        lambda = if lambda == 0.0 { 1e-4 * trace } else { 2.0 * lambda };
    }
    None
}

/// The quadratic correction −½ Σ_{p<q} wₚ w_q κ_pq for weights `w` of the triangle, values `f` at its
/// corners and `f_n` at its neighbours (the shader's formula, in f64).
pub fn correction(s: &Stencil, w: [f64; 3], f: [f64; 3], f_n: [f64; 3]) -> f64 {
    let v = [f[0], f[1], f[2], f_n[0], f_n[1], f_n[2]];
    let kappa: Vec<f64> =
        s.k.iter()
            .map(|row| row.iter().zip(&v).map(|(a, b)| a * b).sum())
            .collect();
    -0.5 * (w[0] * w[1] * kappa[0] + w[1] * w[2] * kappa[1] + w[2] * w[0] * kappa[2])
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// A small patch: a triangle and its three neighbours' vertices around the nadir.
    fn patch(h: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let d = |x: f64, y: f64| DVec3::new(x * h, y * h, -1.0).normalize();
        let dirs = vec![
            d(0.0, 0.0),
            d(1.0, 0.1),
            d(0.45, 0.9),
            d(1.2, 1.1),  // across edge 1–2
            d(-0.6, 0.8), // across edge 2–0
            d(0.5, -0.8), // across edge 0–1
        ];
        let tris = vec![[0, 1, 2], [1, 3, 2], [2, 4, 0], [0, 5, 1]];
        (dirs, tris)
    }

    fn crosses(dirs: &[DVec3], tris: &[[u32; 3]]) -> Vec<[DVec3; 3]> {
        tris.iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| dirs[i as usize]);
                [b.cross(c), c.cross(a), a.cross(b)]
            })
            .collect()
    }

    #[test]
    fn a_quadratic_in_the_coordinates_is_reproduced_exactly() {
        let (dirs, tris) = patch(0.02);
        let cross = crosses(&dirs, &tris);
        let s = stencils(&dirs, &tris, &cross, &[false; 4]);
        let st = s[0].unwrap();
        assert_eq!(st.neighbours, [3, 4, 5]);
        assert!(s[1].is_none(), "a triangle at the patch's edge has no stencil");
        // f = a quadratic in the triangle's own barycentric coordinates.
        let q = |c: [f64; 3]| 0.3 + 2.0 * c[0] - c[1] + 5.0 * c[0] * c[1] - 3.0 * c[1] * c[2] + 7.0 * c[2] * c[0];
        let f_at = |x: DVec3| q(coords(&cross[0], x).unwrap());
        let f = [0, 1, 2].map(|i| f_at(dirs[i]));
        let f_n = st.neighbours.map(|n| f_at(dirs[n as usize]));
        for w in [[0.2, 0.3, 0.5], [1.0 / 3.0; 3], [0.05, 0.9, 0.05]] {
            let x = (dirs[0] * w[0] + dirs[1] * w[1] + dirs[2] * w[2]).normalize();
            let c = coords(&cross[0], x).unwrap();
            let linear: f64 = (0..3).map(|i| c[i] * f[i]).sum();
            let exact = f_at(x);
            let quad = linear + correction(&st, c, f, f_n);
            assert!((quad - exact).abs() < 1e-9, "{w:?}: {quad} vs {exact}");
            assert!((linear - exact).abs() > 1e-3);
        }
    }

    #[test]
    fn a_cosine_lobe_interpolates_an_order_better() {
        // ln L of a cos¹⁰⁰ lobe tilted 20° from nadir, across 0.85° camera spacing.
        let (dirs, tris) = patch(0.0148);
        let axis = DVec3::new(20f64.to_radians().sin(), 0.0, -20f64.to_radians().cos());
        let f_at = |x: DVec3| 99.0 * x.dot(axis).ln();
        let rot = glam::DQuat::from_rotation_y(-20f64.to_radians());
        let dirs: Vec<DVec3> = dirs.iter().map(|d| rot * *d).collect();
        let cross = crosses(&dirs, &tris);
        let st = stencils(&dirs, &tris, &cross, &[false; 4])[0].unwrap();
        let f = [0, 1, 2].map(|i| f_at(dirs[i]));
        let f_n = st.neighbours.map(|n| f_at(dirs[n as usize]));
        let x = (dirs[0] + dirs[1] + dirs[2]).normalize();
        let c = coords(&cross[0], x).unwrap();
        let linear: f64 = (0..3).map(|i| c[i] * f[i]).sum();
        let quad = linear + correction(&st, c, f, f_n);
        let (el, eq) = ((linear - f_at(x)).abs(), (quad - f_at(x)).abs());
        assert!(el > 1e-3 && eq < 0.05 * el, "linear {el}, quadratic {eq}");
    }
}
