//! The bundled sample scenes, generated here: an office-sized room with furniture (shipped as
//! `assets/scenes/office.glb`), and the same room with tessellated statues (≥ 250 000 triangles)
//! for the benchmark.
//!
//! Promises:
//! - Coordinates are glTF's (metres, +Y up). The room spans x −3…3 m, y 0…3 m, z −2…2 m
//!   ([`OFFICE_BOUNDS_M`]); its floor, walls and ceiling face inwards, the furniture outwards.
//! - Reflectances (linear RGB factors, ρ_Y in brackets): ceiling 0.70 (0.70), walls
//!   0.52/0.50/0.46 (0.50), floor 0.25/0.19/0.14 (0.20), desks 0.45/0.35/0.25 (0.36), chairs
//!   0.30/0.32/0.40 (0.32), cabinet 0.50 (0.50), shelf 0.40/0.30/0.20 (0.31), statues 0.60 (0.60);
//!   the rug is white times a 2 × 2 checker texture ([`OFFICE_CHECKER_SRGB`], sampled nearest and
//!   repeated every 0.4 m: 0.2 m squares), the one textured surface.
//! - The furniture hangs under a group node with its own translation, chairs and the cabinet are
//!   turned by node rotations, and one desk mesh and one chair mesh are each used twice, so a
//!   loader must apply the node hierarchy. [`SampleScene::world_triangles`] computes the world
//!   triangles here, independently of any glTF reader, for tests to compare with.
//! - The documented luminaire layout [`OFFICE_LUMINAIRES`]: 2 × 3 luminaires 0.05 m below the
//!   ceiling, at x = −2, 0, 2 m and z = −1, 1 m, yaw 0 (C0 along +X).
//! - The output is deterministic: the same bytes on every run and platform (quarter-turn
//!   rotations written exactly, no transcendental functions in the shipped geometry).

use std::path::Path;

use glam::DVec3;
use serde_json::{json, Value};

use super::error::{Result, SceneError};
use super::place::Placement;
use crate::draw::glb::{Buffer, ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER};

/// The office room's extent, metres: (min, max) corners.
pub const OFFICE_BOUNDS_M: ([f64; 3], [f64; 3]) = ([-3.0, 0.0, -2.0], [3.0, 3.0, 2.0]);

/// The height of the office's ceiling, metres.
pub const OFFICE_CEILING_M: f64 = 3.0;

/// The office's luminaire layout: 2 × 3 at 0.05 m below the ceiling, yaw 0.
pub const OFFICE_LUMINAIRES: [Placement; 6] = {
    const fn at(x_m: f64, z_m: f64) -> Placement {
        Placement {
            x_m,
            y_m: OFFICE_CEILING_M - 0.05,
            z_m,
            yaw_deg: 0.0,
        }
    }
    [
        at(-2.0, -1.0),
        at(0.0, -1.0),
        at(2.0, -1.0),
        at(-2.0, 1.0),
        at(0.0, 1.0),
        at(2.0, 1.0),
    ]
};

/// The rug's checker texels (sRGB), left and right of the first row; the second row swaps them.
pub const OFFICE_CHECKER_SRGB: [[u8; 3]; 2] = [[150, 40, 40], [225, 215, 190]];

/// The rug: x from −1 to 1 m, z from −1.7 to −0.3 m, 5 mm above the floor; UV (0, 0) at its
/// (x −1, z −1.7) corner, u along +X and v along +Z, 2.5 per metre.
pub const OFFICE_RUG_M: ([f64; 2], [f64; 2], f64) = ([-1.0, -1.7], [1.0, -0.3], 0.005);

/// UV units per metre on the rug (the 2 × 2 texture repeats every 0.4 m).
pub const OFFICE_RUG_UV_PER_M: f64 = 2.5;

/// A material of a sample scene.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleMaterial {
    /// Name written to the glTF file.
    pub name: &'static str,
    /// Linear RGB base colour factor.
    pub base_color_factor: [f64; 3],
    /// Whether the rug's checker texture multiplies it.
    pub textured: bool,
}

/// A world-space triangle of a sample scene and its material index.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleTriangle {
    /// Vertices, metres.
    pub vertices: [DVec3; 3],
    /// Index into [`SampleScene::materials`].
    pub material: usize,
}

/// Part of a mesh with one material: indexed vertices with UVs.
#[derive(Debug, Clone, Default)]
struct Part {
    material: usize,
    positions: Vec<DVec3>,
    uvs: Vec<[f64; 2]>,
    indices: Vec<u32>,
}

impl Part {
    fn new(material: usize) -> Self {
        Part {
            material,
            ..Default::default()
        }
    }

    /// A quad a, b, c, d counter-clockwise seen from its front, with UVs.
    fn quad(&mut self, p: [DVec3; 4], uv: [[f64; 2]; 4]) {
        let base = self.positions.len() as u32;
        self.positions.extend(p);
        self.uvs.extend(uv);
        self.indices.extend([0, 1, 2, 0, 2, 3].map(|k| base + k));
    }

    /// A closed box, faces outward (or inward).
    fn add_box(&mut self, min: DVec3, max: DVec3, inward: bool) {
        for (_, corners) in box_faces(min, max, inward) {
            let uv = planar_uv(&corners);
            self.quad(corners, uv);
        }
    }

    fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
}

/// UVs of a rectangle's corners in metres along its first two edges.
fn planar_uv(c: &[DVec3; 4]) -> [[f64; 2]; 4] {
    let (w, h) = ((c[1] - c[0]).length(), (c[3] - c[0]).length());
    [[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]]
}

/// The six faces of a box as (outward axis ±1..±3, corners counter-clockwise seen from the side
/// the face faces: outside, or inside when `inward`).
fn box_faces(min: DVec3, max: DVec3, inward: bool) -> Vec<(i32, [DVec3; 4])> {
    let c = (min + max) / 2.0;
    let h = (max - min) / 2.0;
    let e = [DVec3::X, DVec3::Y, DVec3::Z];
    let mut out = Vec::new();
    for k in 0..3 {
        for s in [1.0, -1.0] {
            let facing = if inward { -s } else { s };
            let (ku, kv) = if facing > 0.0 {
                ((k + 1) % 3, (k + 2) % 3)
            } else {
                ((k + 2) % 3, (k + 1) % 3)
            };
            let fc = c + e[k] * s * h[k];
            let (u, v) = (e[ku] * h[ku], e[kv] * h[kv]);
            let axis = (k as i32 + 1) * if s > 0.0 { 1 } else { -1 };
            out.push((axis, [fc - u - v, fc + u - v, fc + u + v, fc - u + v]));
        }
    }
    out
}

/// The triangles of a closed axis-aligned box, faces outward or inward (for test scenes).
pub fn box_triangles(min: DVec3, max: DVec3, inward: bool) -> Vec<[DVec3; 3]> {
    box_faces(min, max, inward)
        .into_iter()
        .flat_map(|(_, q)| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect()
}

/// The triangles of a UV sphere with `rings` latitude bands and `segments` longitudes, faces
/// outward (or inward). `rings` ≥ 2, `segments` ≥ 3.
pub fn sphere_triangles(centre: DVec3, radius_m: f64, rings: u32, segments: u32, inward: bool) -> Vec<[DVec3; 3]> {
    let (rings, segments) = (rings.max(2), segments.max(3));
    let at = |i: u32, j: u32| {
        let theta = std::f64::consts::PI * f64::from(i) / f64::from(rings);
        let phi = std::f64::consts::TAU * f64::from(j % segments) / f64::from(segments);
        centre + radius_m * DVec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin())
    };
    let mut out = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            // Counter-clockwise seen from outside: a (upper) → b (lower) → c (lower, east).
            let mut tris = Vec::new();
            if i + 1 < rings {
                tris.push([a, b, c]);
            }
            if i > 0 {
                tris.push([a, c, d]);
            }
            for t in tris {
                out.push(if inward { [t[0], t[2], t[1]] } else { t });
            }
        }
    }
    out
}

/// A mesh: parts with one material each (one glTF primitive per part).
#[derive(Debug, Clone, Default)]
struct MeshDef {
    name: &'static str,
    parts: Vec<Part>,
}

/// A node: a translation, a turn about +Y by quarter turns, a mesh, children.
#[derive(Debug, Clone, Default)]
struct NodeDef {
    name: &'static str,
    translation: [f64; 3],
    quarter_turns: u32,
    mesh: Option<usize>,
    children: Vec<NodeDef>,
}

impl NodeDef {
    fn leaf(name: &'static str, mesh: usize, translation: [f64; 3], quarter_turns: u32) -> Self {
        NodeDef {
            name,
            translation,
            quarter_turns,
            mesh: Some(mesh),
            children: Vec::new(),
        }
    }

    /// The node's transform of a point: turn about +Y (counter-clockwise seen from above,
    /// (x, y, z) → (z, y, −x) per quarter turn), then translate.
    fn apply(&self, p: DVec3) -> DVec3 {
        let mut q = p;
        for _ in 0..self.quarter_turns % 4 {
            q = DVec3::new(q.z, q.y, -q.x);
        }
        q + DVec3::from(self.translation)
    }

    /// glTF's rotation quaternion (x, y, z, w) of the quarter turns, exact.
    fn rotation(&self) -> Option<[f64; 4]> {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        match self.quarter_turns % 4 {
            0 => None,
            1 => Some([0.0, h, 0.0, h]),
            2 => Some([0.0, 1.0, 0.0, 0.0]),
            _ => Some([0.0, h, 0.0, -h]),
        }
    }
}

/// A generated sample scene.
#[derive(Debug, Clone)]
pub struct SampleScene {
    materials: Vec<SampleMaterial>,
    meshes: Vec<MeshDef>,
    roots: Vec<NodeDef>,
}

const CEILING: usize = 0;
const WALLS: usize = 1;
const FLOOR: usize = 2;
const DESK: usize = 3;
const CHAIR: usize = 4;
const CABINET: usize = 5;
const SHELF: usize = 6;
const RUG: usize = 7;
const STATUE: usize = 8;

fn office_materials() -> Vec<SampleMaterial> {
    let m = |name, f: [f64; 3], textured| SampleMaterial {
        name,
        base_color_factor: f,
        textured,
    };
    vec![
        m("ceiling", [0.70, 0.70, 0.70], false),
        m("walls", [0.52, 0.50, 0.46], false),
        m("floor", [0.25, 0.19, 0.14], false),
        m("desk", [0.45, 0.35, 0.25], false),
        m("chair", [0.30, 0.32, 0.40], false),
        m("cabinet", [0.50, 0.50, 0.50], false),
        m("shelf", [0.40, 0.30, 0.20], false),
        m("rug", [1.0, 1.0, 1.0], true),
        m("statue", [0.60, 0.60, 0.60], false),
    ]
}

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

/// The office room with its furniture (see the module's promises).
pub fn office() -> SampleScene {
    let (lo, hi) = OFFICE_BOUNDS_M;
    let mut room = MeshDef {
        name: "room",
        parts: vec![Part::new(FLOOR), Part::new(WALLS), Part::new(CEILING)],
    };
    for (axis, corners) in box_faces(DVec3::from(lo), DVec3::from(hi), true) {
        let part = match axis {
            -2 => 0, // the face at −Y is the floor
            2 => 2,
            _ => 1,
        };
        let uv = planar_uv(&corners);
        room.parts[part].quad(corners, uv);
    }
    let mut desk = Part::new(DESK);
    desk.add_box(v(-0.8, 0.72, -0.4), v(0.8, 0.75, 0.4), false);
    for (x, z) in [(-0.72, -0.32), (0.72, -0.32), (-0.72, 0.32), (0.72, 0.32)] {
        desk.add_box(v(x - 0.025, 0.0, z - 0.025), v(x + 0.025, 0.72, z + 0.025), false);
    }
    let mut chair = Part::new(CHAIR);
    chair.add_box(v(-0.23, 0.42, -0.23), v(0.23, 0.47, 0.23), false);
    chair.add_box(v(-0.23, 0.47, 0.19), v(0.23, 0.92, 0.23), false);
    for (x, z) in [(-0.2, -0.2), (0.2, -0.2), (-0.2, 0.2), (0.2, 0.2)] {
        chair.add_box(v(x - 0.02, 0.0, z - 0.02), v(x + 0.02, 0.42, z + 0.02), false);
    }
    let mut cabinet = Part::new(CABINET);
    cabinet.add_box(v(-0.4, 0.0, -0.225), v(0.4, 2.0, 0.225), false);
    let mut shelf = Part::new(SHELF);
    shelf.add_box(v(-0.6, -0.015, -0.15), v(0.6, 0.015, 0.15), false);
    let mut rug = Part::new(RUG);
    let ([x0, z0], [x1, z1], y) = OFFICE_RUG_M;
    let k = OFFICE_RUG_UV_PER_M;
    // Facing +Y: (x0, z1) → (x1, z1) → (x1, z0) → (x0, z0) is counter-clockwise seen from above.
    rug.quad(
        [v(x0, y, z1), v(x1, y, z1), v(x1, y, z0), v(x0, y, z0)],
        [
            [0.0, (z1 - z0) * k],
            [(x1 - x0) * k, (z1 - z0) * k],
            [(x1 - x0) * k, 0.0],
            [0.0, 0.0],
        ],
    );
    // Rug coordinates relative to the node below (translation z −1.0).
    for p in &mut rug.positions {
        p.z += 1.0;
    }
    let meshes = vec![
        room,
        MeshDef {
            name: "desk",
            parts: vec![desk],
        },
        MeshDef {
            name: "chair",
            parts: vec![chair],
        },
        MeshDef {
            name: "cabinet",
            parts: vec![cabinet],
        },
        MeshDef {
            name: "shelf",
            parts: vec![shelf],
        },
        MeshDef {
            name: "rug",
            parts: vec![rug],
        },
    ];
    // The furniture group is moved by +0.25 m in z; its children's translations are relative.
    let furniture = NodeDef {
        name: "furniture",
        translation: [0.0, 0.0, 0.25],
        children: vec![
            NodeDef::leaf("desk 1", 1, [-1.5, 0.0, -0.25], 0),
            NodeDef::leaf("desk 2", 1, [1.5, 0.0, -0.25], 0),
            NodeDef::leaf("chair 1", 2, [-1.5, 0.0, 0.45], 0),
            NodeDef::leaf("chair 2", 2, [1.5, 0.0, -0.95], 2),
            NodeDef::leaf("cabinet", 3, [2.75, 0.0, -1.75], 1),
            NodeDef::leaf("shelf", 4, [-2.0, 1.6, -2.1], 0),
        ],
        ..Default::default()
    };
    let office = NodeDef {
        name: "office",
        children: vec![
            NodeDef {
                name: "room",
                mesh: Some(0),
                ..Default::default()
            },
            furniture,
            NodeDef::leaf("rug", 5, [0.0, 0.0, -1.0], 0),
        ],
        ..Default::default()
    };
    SampleScene {
        materials: office_materials(),
        meshes,
        roots: vec![office],
    }
}

/// The office with eight statues (a pedestal and a finely tessellated sphere each) standing
/// along its walls: 291 840 sphere triangles and the room's, for the benchmark's ≥ 250k-triangle
/// scene.
pub fn office_with_statues() -> SampleScene {
    let mut s = office();
    let mut statue = Part::new(STATUE);
    statue.add_box(v(-0.2, 0.0, -0.2), v(0.2, 0.6, 0.2), false);
    for t in sphere_triangles(v(0.0, 0.85, 0.0), 0.25, 96, 192, false) {
        let base = statue.positions.len() as u32;
        statue.positions.extend(t);
        statue.uvs.extend([[0.0; 2]; 3]);
        statue.indices.extend([base, base + 1, base + 2]);
    }
    s.meshes.push(MeshDef {
        name: "statue",
        parts: vec![statue],
    });
    let mesh = s.meshes.len() - 1;
    let spots = [
        [-2.6, -1.6],
        [-0.6, -1.6],
        [0.6, 1.6],
        [-2.6, 1.6],
        [2.6, 1.6],
        [-0.6, 1.6],
        [2.0, -0.9],
        [-2.6, 0.0],
    ];
    s.roots.push(NodeDef {
        name: "statues",
        children: spots
            .iter()
            .map(|&[x, z]| NodeDef::leaf("statue", mesh, [x, 0.0, z], 0))
            .collect(),
        ..Default::default()
    });
    s
}

impl SampleScene {
    /// The materials, in glTF order.
    pub fn materials(&self) -> &[SampleMaterial] {
        &self.materials
    }

    /// Every triangle in world space, computed from the node tree here (not through glTF), in the
    /// order a depth-first walk of the nodes writes them.
    pub fn world_triangles(&self) -> Vec<SampleTriangle> {
        fn walk(s: &SampleScene, n: &NodeDef, parent: &dyn Fn(DVec3) -> DVec3, out: &mut Vec<SampleTriangle>) {
            let world = |p: DVec3| parent(n.apply(p));
            if let Some(m) = n.mesh {
                for part in &s.meshes[m].parts {
                    for t in part.indices.chunks_exact(3) {
                        out.push(SampleTriangle {
                            vertices: [0, 1, 2].map(|k| world(part.positions[t[k] as usize])),
                            material: part.material,
                        });
                    }
                }
            }
            for c in &n.children {
                walk(s, c, &world, out);
            }
        }
        let mut out = Vec::new();
        for r in &self.roots {
            walk(self, r, &|p| p, &mut out);
        }
        out
    }

    /// Number of triangles in the scene (instances counted).
    pub fn triangle_count(&self) -> usize {
        fn count(s: &SampleScene, n: &NodeDef) -> usize {
            n.mesh
                .map_or(0, |m| s.meshes[m].parts.iter().map(Part::triangle_count).sum())
                + n.children.iter().map(|c| count(s, c)).sum::<usize>()
        }
        self.roots.iter().map(|r| count(self, r)).sum()
    }

    /// The scene as a GLB file.
    ///
    /// Errors (argument `sample scene`): the texture or the container cannot be encoded.
    pub fn to_glb(&self) -> Result<Vec<u8>> {
        let bad = |m: String| SceneError::invalid("sample scene", m);
        let mut buf = Buffer::new();
        let mut accessors: Vec<Value> = Vec::new();
        let mut meshes: Vec<Value> = Vec::new();
        for mesh in &self.meshes {
            let mut prims = Vec::new();
            for part in &mesh.parts {
                let textured = self.materials.get(part.material).is_some_and(|m| m.textured);
                let pos: Vec<[f32; 3]> = part.positions.iter().map(|p| p.as_vec3().to_array()).collect();
                let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
                for p in &pos {
                    for k in 0..3 {
                        lo[k] = lo[k].min(p[k]);
                        hi[k] = hi[k].max(p[k]);
                    }
                }
                let view = buf.push_view(&le_bytes(pos.iter().flatten().copied()), ARRAY_BUFFER);
                accessors.push(json!({"bufferView": view, "componentType": 5126, "count": pos.len(),
                    "type": "VEC3", "min": lo, "max": hi}));
                let mut attributes = json!({"POSITION": accessors.len() - 1});
                if textured {
                    let uv = part.uvs.iter().flat_map(|u| [u[0] as f32, u[1] as f32]);
                    let view = buf.push_view(&le_bytes(uv), ARRAY_BUFFER);
                    accessors.push(
                        json!({"bufferView": view, "componentType": 5126, "count": part.uvs.len(),
                        "type": "VEC2"}),
                    );
                    attributes["TEXCOORD_0"] = json!(accessors.len() - 1);
                }
                let ix: Vec<u8> = part.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
                let view = buf.push_view(&ix, ELEMENT_ARRAY_BUFFER);
                accessors.push(
                    json!({"bufferView": view, "componentType": 5125, "count": part.indices.len(),
                    "type": "SCALAR"}),
                );
                prims.push(json!({"attributes": attributes, "indices": accessors.len() - 1,
                    "material": part.material, "mode": 4}));
            }
            meshes.push(json!({"name": mesh.name, "primitives": prims}));
        }
        let mut nodes: Vec<Value> = Vec::new();
        fn push_node(n: &NodeDef, nodes: &mut Vec<Value>) -> usize {
            let i = nodes.len();
            nodes.push(json!({"name": n.name}));
            if n.translation != [0.0; 3] {
                nodes[i]["translation"] = json!(n.translation);
            }
            if let Some(q) = n.rotation() {
                nodes[i]["rotation"] = json!(q);
            }
            if let Some(m) = n.mesh {
                nodes[i]["mesh"] = json!(m);
            }
            let children: Vec<usize> = n.children.iter().map(|c| push_node(c, nodes)).collect();
            if !children.is_empty() {
                nodes[i]["children"] = json!(children);
            }
            i
        }
        let roots: Vec<usize> = self.roots.iter().map(|r| push_node(r, &mut nodes)).collect();
        let png = checker_png().map_err(bad)?;
        let image_view = buf.push_data(&png);
        let materials: Vec<Value> = self
            .materials
            .iter()
            .map(|m| {
                let f = m.base_color_factor;
                let mut pbr = json!({"baseColorFactor": [f[0], f[1], f[2], 1.0], "metallicFactor": 0.0,
                    "roughnessFactor": 1.0});
                if m.textured {
                    pbr["baseColorTexture"] = json!({"index": 0, "texCoord": 0});
                }
                json!({"name": m.name, "pbrMetallicRoughness": pbr})
            })
            .collect();
        let doc = json!({
            "asset": {"version": "2.0", "generator": "lumiview scene::sample"},
            "scene": 0,
            "scenes": [{"nodes": roots}],
            "nodes": nodes,
            "meshes": meshes,
            "materials": materials,
            "textures": [{"sampler": 0, "source": 0}],
            "samplers": [{"magFilter": 9728, "minFilter": 9728, "wrapS": 10497, "wrapT": 10497}],
            "images": [{"bufferView": image_view, "mimeType": "image/png"}],
            "accessors": accessors,
            "bufferViews": buf.views(),
            "buffers": [{"byteLength": buf.len()}],
        });
        buf.into_glb(&doc).map_err(bad)
    }

    /// Writes [`SampleScene::to_glb`] to `path` through a temporary file renamed into place.
    ///
    /// Errors: those of `to_glb`; I/O errors naming `path`.
    pub fn write_glb(&self, path: &Path) -> Result<()> {
        use std::io::Write as _;
        let bytes = self.to_glb()?;
        let io = |e| SceneError::io(path, e);
        let (mut out, _stale) = crate::files::TempOutput::create(path).map_err(io)?;
        let file = out
            .file()
            .ok_or_else(|| SceneError::invalid("output", "temporary file not open"))?;
        file.write_all(&bytes).map_err(io)?;
        out.commit().map_err(io)
    }
}

fn le_bytes(values: impl Iterator<Item = f32>) -> Vec<u8> {
    values.flat_map(f32::to_le_bytes).collect()
}

/// The rug's 2 × 2 checker as a PNG (RGB, 8 bits).
fn checker_png() -> std::result::Result<Vec<u8>, String> {
    let [a, b] = OFFICE_CHECKER_SRGB;
    let data: Vec<u8> = [a, b, b, a].concat();
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, 2, 2);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(|e| format!("checker PNG: {e}"))?;
    w.write_image_data(&data).map_err(|e| format!("checker PNG: {e}"))?;
    w.finish().map_err(|e| format!("checker PNG: {e}"))?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area_normal(t: &[DVec3; 3]) -> DVec3 {
        0.5 * (t[1] - t[0]).cross(t[2] - t[0])
    }

    #[test]
    fn boxes_and_spheres_are_closed_and_face_the_right_way() {
        let (lo, hi) = (v(-1.0, 0.0, -2.0), v(1.0, 3.0, 2.0));
        let centre = (lo + hi) / 2.0;
        for inward in [false, true] {
            let tris = box_triangles(lo, hi, inward);
            assert_eq!(tris.len(), 12);
            let sum: DVec3 = tris.iter().map(area_normal).sum();
            assert!(sum.length() < 1e-12, "closed: the area vectors cancel");
            for t in &tris {
                let out = area_normal(t).dot((t[0] + t[1] + t[2]) / 3.0 - centre) > 0.0;
                assert_eq!(out, !inward);
            }
            let total: f64 = tris.iter().map(|t| area_normal(t).length()).sum();
            assert!((total - 2.0 * (2.0 * 3.0 + 3.0 * 4.0 + 2.0 * 4.0)).abs() < 1e-12);
        }
        let s = sphere_triangles(v(1.0, 2.0, 3.0), 0.5, 8, 12, true);
        assert_eq!(s.len(), 12 * (2 * 8 - 2));
        assert!(s.iter().map(area_normal).sum::<DVec3>().length() < 1e-12);
        for t in &s {
            assert!(
                area_normal(t).dot((t[0] + t[1] + t[2]) / 3.0 - v(1.0, 2.0, 3.0)) < 0.0,
                "inward"
            );
        }
    }

    #[test]
    fn quarter_turns_match_the_quaternions() {
        for k in 0..4 {
            let n = NodeDef {
                quarter_turns: k,
                ..Default::default()
            };
            let q = n.rotation().map_or(glam::DQuat::IDENTITY, glam::DQuat::from_array);
            let want = glam::DQuat::from_rotation_y(f64::from(k) * std::f64::consts::FRAC_PI_2);
            for p in [DVec3::X, DVec3::Z, v(0.3, -1.0, 2.0)] {
                assert!((n.apply(p) - q * p).length() < 1e-12);
                assert!((n.apply(p) - want * p).length() < 1e-12);
            }
        }
    }

    #[test]
    fn the_office_stays_in_its_room_and_the_big_scene_is_big() {
        let s = office();
        let tris = s.world_triangles();
        assert_eq!(tris.len(), s.triangle_count());
        let (lo, hi) = OFFICE_BOUNDS_M;
        for t in &tris {
            for p in t.vertices {
                assert!(
                    p.cmpge(DVec3::from(lo) - 1e-12).all() && p.cmple(DVec3::from(hi) + 1e-12).all(),
                    "{p}"
                );
            }
        }
        // The cabinet (turned a quarter) stands against the wall x = 3: x from 2.525 to 2.975.
        let cab: Vec<_> = tris.iter().filter(|t| t.material == CABINET).collect();
        let xmax = cab
            .iter()
            .flat_map(|t| t.vertices)
            .map(|p| p.x)
            .fold(f64::MIN, f64::max);
        let zmin = cab
            .iter()
            .flat_map(|t| t.vertices)
            .map(|p| p.z)
            .fold(f64::MAX, f64::min);
        assert!(
            (xmax - 2.975).abs() < 1e-12 && (zmin + 1.9).abs() < 1e-12,
            "{xmax} {zmin}"
        );
        let big = office_with_statues();
        assert!(big.triangle_count() >= 250_000, "{}", big.triangle_count());
    }
}
