//! The photometric solid: the closed surface r(d) = scale · I(d) / I_max around the photometric
//! centre, as an indexed triangle mesh with smooth normals, and its OBJ and glTF 2.0 (GLB) forms.
//!
//! Layout (lumiview's luminaire frame: right-handed, Z up, nadir γ = 0 along −Z, C0 along +X):
//! vertex 0 is the nadir pole, then `gamma_steps − 1` rings at γ_j = 180°·j/G (j = 1 … G − 1),
//! each with `c_steps` vertices at C_i = 360°·i/N (i = 0 … N − 1), vertex `1 + (j − 1)·N + i`;
//! the last vertex is the zenith pole. One vertex per pole, so no triangle degenerates
//! topologically there; the mesh is closed (every edge in exactly two triangles) and wound
//! counter-clockwise seen from outside. A pole's radius uses the mean of I over C at that γ.
//!
//! glTF is +Y up: positions and normals are rotated by −90° about X, (x, y, z) → (x, z, −y), so
//! the nadir points down (−Y), C0 stays +X and C90 goes to −Z. OBJ stays in the luminaire frame.

use serde_json::json;

use crate::draw::glb;

use super::error::PhotometryError;
use super::lut::c_mean;
use super::web::{direction, PhotometricWeb};

/// Largest accepted `c_steps` or `gamma_steps`.
pub const MAX_SOLID_STEPS: usize = 16384;

/// Largest accepted `c_steps · gamma_steps` (about that many vertices).
pub const MAX_SOLID_CELLS: usize = 1 << 22;

/// Largest accepted scale, metres.
pub const MAX_SOLID_SCALE_M: f64 = 1e6;

/// Resolution and size of a photometric solid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolidOptions {
    /// Vertices per ring (C steps of 360°/N), ≥ 3.
    pub c_steps: usize,
    /// γ intervals between the poles (steps of 180°/G), ≥ 2.
    pub gamma_steps: usize,
    /// Radius in metres at the web's maximum intensity.
    pub scale_m: f64,
}

impl Default for SolidOptions {
    /// 72 × 36 (5° steps), scale 1 m.
    fn default() -> Self {
        SolidOptions {
            c_steps: 72,
            gamma_steps: 36,
            scale_m: 1.0,
        }
    }
}

/// An indexed triangle mesh of the photometric solid in the luminaire frame (metres).
#[derive(Debug, Clone, PartialEq)]
pub struct PhotometricSolid {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    indices: Vec<u32>,
    max_cd: f64,
    options: SolidOptions,
}

fn invalid(name: &'static str, message: impl Into<String>) -> PhotometryError {
    PhotometryError::InvalidArgument {
        name,
        message: message.into(),
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// To f32, with −0 turned into +0 (vertices at the origin print as `0`, not `-0`).
fn to_f32(a: [f64; 3]) -> [f32; 3] {
    a.map(|x| x as f32 + 0.0)
}

/// Converts a point or vector from lumiview's Z-up luminaire frame to glTF's Y-up frame: a −90°
/// rotation about X, (x, y, z) → (x, z, −y). Nadir (0, 0, −1) → (0, −1, 0).
pub fn to_gltf_axes(p: [f32; 3]) -> [f32; 3] {
    [p[0], p[2], -p[1]]
}

impl PhotometricSolid {
    /// Builds the solid: each vertex at `scale_m · I(C, γ) / I_max` along its direction, where
    /// I_max is the web's maximum ([`PhotometricWeb::max_intensity`]). Normals are the normalised,
    /// area-weighted sums of the adjacent faces' normals; where that sum vanishes (e.g. around
    /// vertices at the origin) the radial direction is used, so no normal is NaN.
    ///
    /// Errors: `c_steps` < 3, `gamma_steps` < 2, either above 16384 or their product above 2²²,
    /// a scale that is not finite and positive (or above 10⁶ m), or an all-zero web.
    pub fn new(web: &PhotometricWeb, options: &SolidOptions) -> Result<Self, PhotometryError> {
        let (nc, ng, scale) = (options.c_steps, options.gamma_steps, options.scale_m);
        if !(3..=MAX_SOLID_STEPS).contains(&nc) {
            return Err(invalid("c_steps", format!("{nc}: expected 3…{MAX_SOLID_STEPS}")));
        }
        if !(2..=MAX_SOLID_STEPS).contains(&ng) {
            return Err(invalid("gamma_steps", format!("{ng}: expected 2…{MAX_SOLID_STEPS}")));
        }
        if nc * ng > MAX_SOLID_CELLS {
            return Err(invalid(
                "resolution",
                format!("{nc} × {ng} = {} cells: at most {MAX_SOLID_CELLS}", nc * ng),
            ));
        }
        if !(scale.is_finite() && scale > 0.0 && scale <= MAX_SOLID_SCALE_M) {
            return Err(invalid(
                "scale",
                format!("{scale} m: expected a finite value in (0, {MAX_SOLID_SCALE_M}]"),
            ));
        }
        let (max_cd, _, _) = web.max_intensity();
        if max_cd.is_nan() || max_cd <= 0.0 {
            return Err(invalid(
                "web",
                "every intensity is zero: the photometric solid is empty",
            ));
        }
        let vertex_count = 2 + nc * (ng - 1);
        let mut dirs: Vec<[f64; 3]> = Vec::with_capacity(vertex_count);
        let mut pos: Vec<[f64; 3]> = Vec::with_capacity(vertex_count);
        let mut push = |d: [f64; 3], i_cd: f64| {
            // I / I_max ≤ 1 stays finite even for a subnormal maximum.
            let r = scale * (i_cd / max_cd);
            dirs.push(d);
            pos.push([r * d[0], r * d[1], r * d[2]]);
        };
        push([0.0, 0.0, -1.0], c_mean(web, 0.0));
        for j in 1..ng {
            let g = 180.0 * j as f64 / ng as f64;
            for i in 0..nc {
                let c = 360.0 * i as f64 / nc as f64;
                push(direction(c, g), web.sample(c, g));
            }
        }
        push([0.0, 0.0, 1.0], c_mean(web, 180.0));

        // Vertex count ≤ 2 + 2²² fits u32.
        let ring = |j: usize, i: usize| (1 + (j - 1) * nc + i % nc) as u32;
        let top = (vertex_count - 1) as u32;
        let mut indices: Vec<u32> = Vec::with_capacity(6 * nc * (ng - 1));
        for i in 0..nc {
            // Nadir fan: seen from below (outside), counter-clockwise.
            indices.extend_from_slice(&[0, ring(1, i + 1), ring(1, i)]);
        }
        for j in 1..ng - 1 {
            for i in 0..nc {
                let (a, b) = (ring(j, i), ring(j, i + 1));
                let (c, d) = (ring(j + 1, i + 1), ring(j + 1, i));
                indices.extend_from_slice(&[a, b, c, a, c, d]);
            }
        }
        for i in 0..nc {
            indices.extend_from_slice(&[top, ring(ng - 1, i), ring(ng - 1, i + 1)]);
        }

        let mut acc = vec![[0.0_f64; 3]; vertex_count];
        for t in indices.chunks_exact(3) {
            let (a, b, c) = (t[0] as usize, t[1] as usize, t[2] as usize);
            let n = cross(sub(pos[b], pos[a]), sub(pos[c], pos[a]));
            for v in [a, b, c] {
                for (s, x) in acc[v].iter_mut().zip(n) {
                    *s += x;
                }
            }
        }
        // Below this length (relative to scale²) a face-normal sum is rounding noise.
        let tiny = 1e-14 * scale * scale;
        let normals = acc
            .iter()
            .zip(&dirs)
            .map(|(n, d)| {
                let len = norm(*n);
                if len > tiny && len.is_finite() {
                    to_f32([n[0] / len, n[1] / len, n[2] / len])
                } else {
                    to_f32(*d)
                }
            })
            .collect();
        Ok(PhotometricSolid {
            positions: pos.into_iter().map(to_f32).collect(),
            normals,
            indices,
            max_cd,
            options: *options,
        })
    }

    /// Vertex positions in metres, luminaire frame.
    pub fn positions(&self) -> &[[f32; 3]] {
        &self.positions
    }

    /// Unit vertex normals, luminaire frame, pointing out of the solid.
    pub fn normals(&self) -> &[[f32; 3]] {
        &self.normals
    }

    /// Triangle vertex indices, three per triangle, counter-clockwise seen from outside.
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }

    /// Number of vertices: 2 + c_steps · (gamma_steps − 1).
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles: 2 · c_steps · (gamma_steps − 1).
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// The intensity (cd) that maps to radius `scale_m`: the web's maximum.
    pub fn max_cd(&self) -> f64 {
        self.max_cd
    }

    /// The options the solid was built with.
    pub fn options(&self) -> &SolidOptions {
        &self.options
    }

    /// Type C angles (C, γ) in degrees of vertex `k` (C = 0 at the poles), or `None` past the end.
    pub fn vertex_angles(&self, k: usize) -> Option<(f64, f64)> {
        let (nc, ng) = (self.options.c_steps, self.options.gamma_steps);
        let n = self.positions.len();
        if k >= n {
            None
        } else if k == 0 {
            Some((0.0, 0.0))
        } else if k == n - 1 {
            Some((0.0, 180.0))
        } else {
            let (j, i) = ((k - 1) / nc + 1, (k - 1) % nc);
            Some((360.0 * i as f64 / nc as f64, 180.0 * j as f64 / ng as f64))
        }
    }

    /// Axis-aligned bounds (min, max) of the positions, luminaire frame.
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        bounds_of(self.positions.iter().copied())
    }

    /// Wavefront OBJ text: comment header, `v`, `vn`, then `f a//a b//b c//c` lines (1-based), in
    /// the luminaire frame (Z up; tell importers "Z up, Y forward").
    pub fn to_obj(&self) -> String {
        use std::fmt::Write;
        let mut s = String::with_capacity(self.positions.len() * 64 + self.indices.len() * 8);
        let o = &self.options;
        // Writing to a String cannot fail.
        let _ = writeln!(
            s,
            "# lumiview photometric solid: r = {} m * I / {} cd",
            o.scale_m, self.max_cd
        );
        let _ = writeln!(
            s,
            "# luminaire frame, metres: Z up, nadir (gamma 0) along -Z, C0 along +X, C90 along +Y"
        );
        let _ = writeln!(
            s,
            "# {} C steps x {} gamma steps, {} vertices, {} triangles",
            o.c_steps,
            o.gamma_steps,
            self.vertex_count(),
            self.triangle_count()
        );
        let _ = writeln!(s, "o photometric_solid");
        for p in &self.positions {
            let _ = writeln!(s, "v {} {} {}", p[0], p[1], p[2]);
        }
        for n in &self.normals {
            let _ = writeln!(s, "vn {} {} {}", n[0], n[1], n[2]);
        }
        for t in self.indices.chunks_exact(3) {
            let (a, b, c) = (t[0] + 1, t[1] + 1, t[2] + 1);
            let _ = writeln!(s, "f {a}//{a} {b}//{b} {c}//{c}");
        }
        s
    }

    /// A glTF 2.0 binary (GLB): one buffer, one mesh with one triangle primitive (POSITION with
    /// min/max, NORMAL, u32 indices), one node, one scene; positions and normals rotated into
    /// glTF's Y-up frame with [`to_gltf_axes`]. `asset.extras` records max_cd, scale and frame.
    ///
    /// Errors: a mesh too large for a GLB (over 4 GiB).
    pub fn to_glb(&self) -> Result<Vec<u8>, PhotometryError> {
        let pos: Vec<[f32; 3]> = self.positions.iter().map(|&p| to_gltf_axes(p)).collect();
        let nrm: Vec<[f32; 3]> = self.normals.iter().map(|&n| to_gltf_axes(n)).collect();
        let (min, max) = bounds_of(pos.iter().copied());
        let bytes = |v: &[[f32; 3]]| v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
        let mut buf = glb::Buffer::new();
        buf.push_view(&bytes(&pos), glb::ARRAY_BUFFER);
        buf.push_view(&bytes(&nrm), glb::ARRAY_BUFFER);
        let idx: Vec<u8> = self.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        buf.push_view(&idx, glb::ELEMENT_ARRAY_BUFFER);
        let o = &self.options;
        let doc = json!({
            "asset": {
                "version": "2.0",
                "generator": "lumiview",
                "extras": {
                    "max_cd": self.max_cd,
                    "scale_m": o.scale_m,
                    "c_steps": o.c_steps,
                    "gamma_steps": o.gamma_steps,
                    "frame": "glTF Y up; lumiview luminaire frame (Z up) rotated by -90 deg about X: \
                              (x, y, z) -> (x, z, -y); nadir along -Y, C0 along +X, C90 along -Z",
                },
            },
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0, "name": "photometric solid"}],
            "meshes": [{
                "name": "photometric solid",
                "primitives": [{
                    "attributes": {"POSITION": 0, "NORMAL": 1},
                    "indices": 2,
                    "mode": 4,
                }],
            }],
            "accessors": [
                {
                    "bufferView": 0,
                    "componentType": 5126,
                    "count": pos.len(),
                    "type": "VEC3",
                    "min": [min[0], min[1], min[2]],
                    "max": [max[0], max[1], max[2]],
                },
                {
                    "bufferView": 1,
                    "componentType": 5126,
                    "count": nrm.len(),
                    "type": "VEC3",
                },
                {
                    "bufferView": 2,
                    "componentType": 5125,
                    "count": self.indices.len(),
                    "type": "SCALAR",
                },
            ],
            "bufferViews": buf.views(),
            "buffers": [{"byteLength": buf.len()}],
        });
        buf.into_glb(&doc).map_err(|m| invalid("solid", m))
    }
}

fn bounds_of(points: impl Iterator<Item = [f32; 3]>) -> ([f32; 3], [f32; 3]) {
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    let mut any = false;
    for p in points {
        any = true;
        for k in 0..3 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k]);
        }
    }
    if any {
        (min, max)
    } else {
        ([0.0; 3], [0.0; 3])
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;

    fn web(values: impl Fn(f64, f64) -> f64) -> PhotometricWeb {
        let c: Vec<f64> = (0..=24).map(|i| i as f64 * 15.0).collect();
        let g: Vec<f64> = (0..=36).map(|i| i as f64 * 5.0).collect();
        let mut cd = Vec::new();
        for &ci in &c {
            for &gi in &g {
                cd.push(values(ci, gi));
            }
        }
        PhotometricWeb::from_grid(c, g, cd).unwrap()
    }

    #[test]
    fn isotropic_is_a_closed_outward_sphere() {
        let w = web(|_, _| 100.0);
        let s = PhotometricSolid::new(
            &w,
            &SolidOptions {
                c_steps: 12,
                gamma_steps: 6,
                scale_m: 2.0,
            },
        )
        .unwrap();
        assert_eq!(s.vertex_count(), 2 + 12 * 5);
        assert_eq!(s.triangle_count(), 2 * 12 * 5);
        for (p, n) in s.positions().iter().zip(s.normals()) {
            let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            assert!((r - 2.0).abs() < 1e-5);
            let d = (p[0] * n[0] + p[1] * n[1] + p[2] * n[2]) / r;
            assert!(d > 0.95, "{d}");
        }
        let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
        for t in s.indices().chunks_exact(3) {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                assert!(edges.insert((a, b), 1).is_none(), "directed edge used twice");
            }
        }
        for &(a, b) in edges.keys() {
            assert!(edges.contains_key(&(b, a)), "edge without its twin");
        }
    }

    #[test]
    fn downlight_normals_are_finite() {
        let w = web(|_, g| if g <= 60.0 { 500.0 * g.to_radians().cos() } else { 0.0 });
        let s = PhotometricSolid::new(&w, &SolidOptions::default()).unwrap();
        for n in s.normals() {
            assert!(n.iter().all(|x| x.is_finite()));
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            assert!((len - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn bad_options_and_zero_web_are_errors() {
        let w = web(|_, _| 1.0);
        for (c, g, s) in [
            (2, 4, 1.0),
            (4, 1, 1.0),
            (20_000, 4, 1.0),
            (4096, 4096, 1.0),
            (8, 8, 0.0),
            (8, 8, f64::NAN),
            (8, 8, -1.0),
        ] {
            let o = SolidOptions {
                c_steps: c,
                gamma_steps: g,
                scale_m: s,
            };
            assert!(PhotometricSolid::new(&w, &o).is_err(), "{c} {g} {s}");
        }
        let z = web(|_, _| 0.0);
        assert!(PhotometricSolid::new(&z, &SolidOptions::default()).is_err());
    }

    #[test]
    fn extreme_maxima_stay_finite() {
        for peak in [1e-310, 1e-30, 1e15] {
            let w = web(|c, g| peak * (1.0 + (c.to_radians().cos() * g.to_radians().sin())).max(0.0) / 2.0);
            let s = PhotometricSolid::new(&w, &SolidOptions::default()).unwrap();
            assert!(
                s.positions().iter().chain(s.normals()).flatten().all(|x| x.is_finite()),
                "{peak}"
            );
            let r_max = s
                .positions()
                .iter()
                .map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt())
                .fold(0.0, f32::max);
            assert!(r_max > 0.9 && r_max <= 1.0 + 1e-6, "{peak}: {r_max}");
        }
    }

    #[test]
    fn gltf_axes_put_nadir_down() {
        assert_eq!(to_gltf_axes([0.0, 0.0, -1.0]), [0.0, -1.0, 0.0]);
        assert_eq!(to_gltf_axes([1.0, 0.0, 0.0]), [1.0, 0.0, 0.0]);
        assert_eq!(to_gltf_axes([0.0, 1.0, 0.0]), [0.0, 0.0, -1.0]);
    }
}
