//! Proxy meshes: triangles on the surfaces where a luminaire's luminance appears (its emitting planes,
//! the reflector's aperture), for parallax-correct reprojection of near-field images. Written as glTF
//! 2.0 binary (GLB) by hand, in the axes of `photometry::solid` (Y up: (x, y, z) → (x, z, −y)), one
//! mesh primitive per named surface, front faces (counter-clockwise) on the emitting side.

use std::path::Path;

use glam::DVec3;
use serde_json::json;

use crate::draw::glb;
use crate::nearfield::error::{NearfieldError, Result};
use crate::photometry::solid::to_gltf_axes;

/// One named surface of a proxy mesh (luminaire frame, metres).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ProxySurface {
    /// Name (e.g. `front tile 3`, `back plane`, `aperture`).
    pub name: String,
    /// Vertex positions (m, luminaire frame).
    pub positions: Vec<DVec3>,
    /// Unit normals per vertex, pointing to the side the light leaves.
    pub normals: Vec<DVec3>,
    /// Triangles (three vertex indices each), counter-clockwise seen from the emitting side.
    pub indices: Vec<u32>,
}

/// A luminaire's proxy geometry: named surfaces.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ProxyMesh {
    /// The luminaire's name.
    pub name: String,
    /// The surfaces.
    pub surfaces: Vec<ProxySurface>,
}

impl ProxyMesh {
    /// An empty mesh for luminaire `name`.
    pub fn new(name: &str) -> Self {
        Self {
            name: name.to_string(),
            surfaces: Vec::new(),
        }
    }

    /// Adds the rectangle [x0, x1] × [y0, y1] in the plane z, facing down (−Z).
    pub fn add_rect(&mut self, name: &str, x0: f64, x1: f64, y0: f64, y1: f64, z: f64) {
        self.surfaces.push(ProxySurface {
            name: name.to_string(),
            positions: vec![
                DVec3::new(x0, y0, z),
                DVec3::new(x0, y1, z),
                DVec3::new(x1, y1, z),
                DVec3::new(x1, y0, z),
            ],
            normals: vec![DVec3::NEG_Z; 4],
            // (p1 − p0) × (p2 − p0) points along −Z for this order.
            indices: vec![0, 1, 2, 0, 2, 3],
        });
    }

    /// Adds a disc centred at `centre` in the plane z = centre.z, facing down (−Z): a regular polygon
    /// of `segments` ≥ 3 sides with the disc's area (its vertices a little outside the circle, its
    /// edges' midpoints a little inside). An inscribed polygon would lose area, and with it light: the
    /// renderer draws only where the proxy is, so a 32-gon's 0.64 % shortfall is a 0.64 % flux error.
    pub fn add_disc(&mut self, name: &str, centre: DVec3, radius: f64, segments: u32) {
        let n = segments.max(3);
        let step = std::f64::consts::TAU / f64::from(n);
        // Polygon area n/2·R²·sin(2π/n) = π r².
        let r_vertex = radius * (std::f64::consts::TAU / (f64::from(n) * step.sin())).sqrt();
        let mut positions = vec![centre];
        for k in 0..n {
            let a = step * f64::from(k);
            positions.push(centre + DVec3::new(r_vertex * a.cos(), r_vertex * a.sin(), 0.0));
        }
        let mut indices = Vec::with_capacity(3 * n as usize);
        for k in 0..n {
            let (a, b) = (1 + k, 1 + (k + 1) % n);
            indices.extend_from_slice(&[0, b, a]);
        }
        self.surfaces.push(ProxySurface {
            name: name.to_string(),
            normals: vec![DVec3::NEG_Z; positions.len()],
            positions,
            indices,
        });
    }

    /// Total number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.surfaces.iter().map(|s| s.indices.len() / 3).sum()
    }

    /// The glTF 2.0 binary: one buffer; per surface a POSITION (with min/max), NORMAL and u32 index
    /// accessor and a triangle primitive; one mesh, one node, one scene. `asset.extras` states the
    /// luminaire and the frame.
    ///
    /// Errors: a surface whose indices point past its vertices, or a mesh over 4 GiB.
    pub fn to_glb(&self) -> Result<Vec<u8>> {
        let bad = |m: String| NearfieldError::invalid("proxy mesh", m);
        let mut buf = glb::Buffer::new();
        let mut accessors = Vec::new();
        let mut primitives = Vec::new();
        for s in &self.surfaces {
            if s.positions.len() != s.normals.len() || s.indices.len() % 3 != 0 {
                return Err(bad(format!(
                    "surface '{}': positions, normals and triangles do not match",
                    s.name
                )));
            }
            if let Some(i) = s.indices.iter().find(|&&i| i as usize >= s.positions.len()) {
                return Err(bad(format!("surface '{}': index {i} past its vertices", s.name)));
            }
            let pos: Vec<[f32; 3]> = s
                .positions
                .iter()
                .map(|p| to_gltf_axes([p.x as f32, p.y as f32, p.z as f32]))
                .collect();
            let nrm: Vec<[f32; 3]> = s
                .normals
                .iter()
                .map(|p| to_gltf_axes([p.x as f32, p.y as f32, p.z as f32]))
                .collect();
            let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
            for p in &pos {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            let bytes = |v: &[[f32; 3]]| v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
            let pv = buf.push_view(&bytes(&pos), glb::ARRAY_BUFFER);
            let nv = buf.push_view(&bytes(&nrm), glb::ARRAY_BUFFER);
            let idx: Vec<u8> = s.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
            let iv = buf.push_view(&idx, glb::ELEMENT_ARRAY_BUFFER);
            let a0 = accessors.len();
            accessors.push(
                json!({"bufferView": pv, "componentType": 5126, "count": pos.len(), "type": "VEC3",
                "min": lo, "max": hi}),
            );
            accessors.push(json!({"bufferView": nv, "componentType": 5126, "count": nrm.len(), "type": "VEC3"}));
            accessors
                .push(json!({"bufferView": iv, "componentType": 5125, "count": s.indices.len(), "type": "SCALAR"}));
            primitives.push(json!({
                "attributes": {"POSITION": a0, "NORMAL": a0 + 1},
                "indices": a0 + 2,
                "mode": 4,
                "extras": {"surface": s.name},
            }));
        }
        let doc = json!({
            "asset": {
                "version": "2.0",
                "generator": "lumiview synth",
                "extras": {
                    "luminaire": self.name,
                    "kind": "near-field proxy: surfaces where the luminance appears",
                    "unit": "m",
                    "frame": "glTF Y up; lumiview luminaire frame (Z up) rotated by -90 deg about X: \
                              (x, y, z) -> (x, z, -y); nadir along -Y, C0 along +X, C90 along -Z",
                },
            },
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0, "name": self.name}],
            "meshes": [{"name": self.name, "primitives": primitives}],
            "accessors": accessors,
            "bufferViews": buf.views(),
            "buffers": [{"byteLength": buf.len()}],
        });
        buf.into_glb(&doc).map_err(bad)
    }

    /// Writes [`ProxyMesh::to_glb`] to `path`.
    ///
    /// Errors: as `to_glb`, or an I/O error naming `path`.
    pub fn write_glb(&self, path: &Path) -> Result<()> {
        let bytes = self.to_glb()?;
        std::fs::write(path, bytes).map_err(|e| NearfieldError::io(path, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_disc_polygon_has_the_disc_area() {
        for n in [3u32, 8, 32, 128] {
            let mut m = ProxyMesh::new("t");
            m.add_disc("d", DVec3::new(0.3, -0.2, 0.0), 0.0015, n);
            let s = &m.surfaces[0];
            let area: f64 = s
                .indices
                .chunks(3)
                .map(|t| {
                    let p = |k: usize| s.positions[t[k] as usize];
                    0.5 * (p(1) - p(0)).cross(p(2) - p(0)).length()
                })
                .sum();
            let disc = std::f64::consts::PI * 0.0015 * 0.0015;
            assert!((area / disc - 1.0).abs() < 1e-12, "{n} segments: {area} vs {disc}");
        }
    }

    #[test]
    fn rect_and_disc_face_down() {
        let mut m = ProxyMesh::new("t");
        m.add_rect("r", -1.0, 1.0, -0.5, 0.5, 0.0);
        m.add_disc("d", DVec3::new(0.0, 0.0, 0.1), 0.2, 16);
        assert_eq!(m.triangle_count(), 2 + 16);
        for s in &m.surfaces {
            for t in s.indices.chunks(3) {
                let (a, b, c) = (
                    s.positions[t[0] as usize],
                    s.positions[t[1] as usize],
                    s.positions[t[2] as usize],
                );
                assert!((b - a).cross(c - a).z < 0.0, "{}", s.name);
            }
        }
        let glb = m.to_glb().unwrap();
        assert_eq!(&glb[..4], b"glTF");
        assert_eq!(glb.len() % 4, 0);
    }

    #[test]
    fn bad_indices_are_errors() {
        let mut m = ProxyMesh::new("t");
        m.add_rect("r", 0.0, 1.0, 0.0, 1.0, 0.0);
        m.surfaces[0].indices[2] = 9;
        assert!(m.to_glb().is_err());
    }
}
