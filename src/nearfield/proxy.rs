//! Proxy geometry for parallax-correct reprojection: a triangle mesh on the surfaces where a scanned
//! luminaire's luminance appears, in the luminaire frame (metres).
//!
//! glTF files use glTF's axes (+Y up, metres), as lumiview writes them (`photometry::solid`,
//! `synth::proxy`): a glTF position (X, Y, Z) is the luminaire-frame point (X, −Z, Y). Every mesh
//! primitive of every node of the default scene (or of all scenes' roots when none is default) is
//! taken with its node transforms; only triangle-list primitives are accepted.

use std::path::Path;

use glam::{DMat4, DVec3};

use super::error::{NearfieldError, Result};
use super::synth::ProxyMesh;

/// The triangles of a synthetic proxy mesh (luminaire frame, metres), three vertices each.
pub fn triangles_of(mesh: &ProxyMesh) -> Vec<[f32; 3]> {
    let mut out = Vec::new();
    for s in &mesh.surfaces {
        for &i in &s.indices {
            if let Some(p) = s.positions.get(i as usize) {
                out.push([p.x as f32, p.y as f32, p.z as f32]);
            }
        }
    }
    out
}

/// A triangle soup (luminaire frame, metres, three vertices per triangle) as a one-surface
/// [`ProxyMesh`] with face normals, for glTF export.
pub fn mesh_of_triangles(name: &str, surface: &str, triangles: &[[f32; 3]]) -> ProxyMesh {
    let mut s = super::synth::proxy::ProxySurface {
        name: surface.to_string(),
        ..Default::default()
    };
    for (t, tri) in triangles.chunks_exact(3).enumerate() {
        let [a, b, c] = [0, 1, 2].map(|k| DVec3::from(tri[k].map(f64::from)));
        let n = (b - a).cross(c - a).normalize_or(DVec3::Z);
        s.positions.extend([a, b, c]);
        s.normals.extend([n; 3]);
        s.indices.extend((0..3).map(|k| (3 * t + k) as u32));
    }
    let mut m = ProxyMesh::new(name);
    m.surfaces.push(s);
    m
}

/// Largest glTF file (and each buffer file it names) read as a proxy: 1 GiB.
pub const MAX_GLTF_BYTES: u64 = 1 << 30;

/// Loads a proxy mesh from a glTF 2.0 file (`.glb`, or `.gltf` with its buffers in files beside it
/// or embedded as base64 data URIs) as luminaire-frame triangles.
///
/// Errors: I/O ([`NearfieldError::Io`] naming the file), a file that is not glTF or has no
/// triangles, non-triangle primitives, buffers that are missing or too short, non-finite positions
/// ([`NearfieldError::Format`] naming the file and what is wrong).
pub fn load_gltf(path: &Path) -> Result<Vec<[f32; 3]>> {
    let bytes =
        crate::files::read_regular(path, MAX_GLTF_BYTES, "a glTF proxy").map_err(|e| NearfieldError::io(path, e))?;
    let bad = |m: String| NearfieldError::format(path, m);
    // gltf's own GLB parser underflows on a header length below 12: checked first.
    crate::draw::glb::check_header(&bytes).map_err(bad)?;
    let gltf = gltf::Gltf::from_slice(&bytes).map_err(|e| bad(format!("not a glTF 2.0 file: {e}")))?;
    let mut buffers: Vec<Vec<u8>> = Vec::new();
    for b in gltf.buffers() {
        let data = match b.source() {
            gltf::buffer::Source::Bin => gltf
                .blob
                .clone()
                .ok_or_else(|| bad("buffer refers to a GLB binary chunk the file lacks".into()))?,
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (_, b64) = rest
                        .split_once(";base64,")
                        .ok_or_else(|| bad(format!("data URI of buffer {} is not base64", b.index())))?;
                    decode_base64(b64).ok_or_else(|| bad(format!("buffer {} has bad base64", b.index())))?
                } else {
                    let file = path.parent().unwrap_or(Path::new(".")).join(uri);
                    crate::files::read_regular(&file, MAX_GLTF_BYTES, "a glTF buffer")
                        .map_err(|e| NearfieldError::io(&file, e))?
                }
            }
        };
        if data.len() < b.length() {
            return Err(bad(format!(
                "buffer {} holds {} bytes, fewer than the {} it declares",
                b.index(),
                data.len(),
                b.length()
            )));
        }
        buffers.push(data);
    }
    let mut out = Vec::new();
    let roots: Vec<gltf::Node> = match gltf.default_scene().or_else(|| gltf.scenes().next()) {
        Some(s) => s.nodes().collect(),
        None => gltf.nodes().collect(),
    };
    let mut stack: Vec<(gltf::Node, DMat4)> = roots.into_iter().map(|n| (n, DMat4::IDENTITY)).collect();
    let mut visited = 0usize;
    while let Some((node, parent)) = stack.pop() {
        visited += 1;
        if visited > 100_000 {
            return Err(bad("node hierarchy is too deep or cyclic".into()));
        }
        let m = node.transform().matrix();
        let local = DMat4::from_cols_array_2d(&m.map(|c| c.map(f64::from)));
        let world = parent * local;
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    return Err(bad(format!(
                        "mesh {} has a {:?} primitive; only triangle lists are supported",
                        mesh.index(),
                        prim.mode()
                    )));
                }
                let reader = prim.reader(|b| buffers.get(b.index()).map(|v| v.as_slice()));
                let pos: Vec<[f32; 3]> = reader
                    .read_positions()
                    .ok_or_else(|| bad(format!("mesh {} has no positions", mesh.index())))?
                    .collect();
                let indices: Vec<u32> = match reader.read_indices() {
                    Some(i) => i.into_u32().collect(),
                    None => (0..pos.len() as u32).collect(),
                };
                for i in indices {
                    let p = pos
                        .get(i as usize)
                        .ok_or_else(|| bad(format!("index {i} is beyond {} positions", pos.len())))?;
                    let g = world.transform_point3(DVec3::new(p[0].into(), p[1].into(), p[2].into()));
                    if !g.is_finite() {
                        return Err(bad("a position is not finite".into()));
                    }
                    out.push([g.x as f32, -g.z as f32, g.y as f32]);
                }
            }
        }
        for c in node.children() {
            stack.push((c, world));
        }
    }
    let whole = out.len() / 3 * 3;
    out.truncate(whole);
    if out.is_empty() {
        return Err(bad("no triangles in the default scene".into()));
    }
    Ok(out)
}

fn decode_base64(s: &str) -> Option<Vec<u8>> {
    let val = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        } as u32)
    };
    let bytes: Vec<u8> = s.bytes().filter(|c| !c.is_ascii_whitespace() && *c != b'=').collect();
    let mut out = Vec::with_capacity(bytes.len() * 3 / 4);
    for chunk in bytes.chunks(4) {
        let mut acc = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            acc |= val(c)? << (18 - 6 * k);
        }
        let n = chunk.len();
        if n < 2 {
            return None;
        }
        out.push((acc >> 16) as u8);
        if n > 2 {
            out.push((acc >> 8) as u8);
        }
        if n > 3 {
            out.push(acc as u8);
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn synthetic_proxy_round_trips_through_glb() {
        let lum = crate::nearfield::synth::luminaire("two-planes").unwrap();
        let mesh = lum.proxy();
        let direct = triangles_of(&mesh);
        let dir = std::env::temp_dir().join(format!("lumiview-proxy-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("two-planes.glb");
        mesh.write_glb(&f).unwrap();
        let loaded = load_gltf(&f).unwrap();
        assert_eq!(loaded.len(), direct.len());
        for (a, b) in loaded.iter().zip(&direct) {
            for k in 0..3 {
                assert!((a[k] - b[k]).abs() < 1e-6, "{a:?} vs {b:?}");
            }
        }
        std::fs::write(dir.join("bad.glb"), b"glTF garbage").unwrap();
        let e = load_gltf(&dir.join("bad.glb")).unwrap_err().to_string();
        assert!(e.contains("bad.glb"), "{e}");
        let e = load_gltf(&dir.join("missing.glb")).unwrap_err().to_string();
        assert!(e.contains("missing.glb"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn base64_decodes() {
        assert_eq!(decode_base64("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(decode_base64("AAEC").unwrap(), vec![0, 1, 2]);
        assert!(decode_base64("a$==").is_none());
    }
}
