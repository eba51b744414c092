//! The GPU form of a [`Selection`]: flat arrays of 4-byte little-endian words, the contract with the
//! near-field shader (`shaders/nearfield/shade.wgsl`). The layout is documented in the module docs of
//! [`super`].

use super::Selection;

/// The camera word of a hole triangle (all three of its entries).
pub const HOLE_CAMERA: u32 = 0xFFFF_FFFF;

/// The selection tables as the GPU reads them (see the module docs of [`super`] for the layout).
/// `Vec<[f32; 4]>` and `Vec<u32>` cast to bytes with `bytemuck::cast_slice`.
#[derive(Debug, Clone, PartialEq)]
pub struct SelectionGpu {
    /// 3 entries per triangle (a, b, c): `[(b×c).xyz, camera(a)]`, `[(c×a).xyz, camera(b)]`,
    /// `[(a×b).xyz, camera(c)]`, cameras bit-cast (`f32::from_bits`), [`HOLE_CAMERA`] for a hole.
    pub triangles: Vec<[f32; 4]>,
    /// Per vertex `[d.xyz, camera]` (camera bit-cast).
    pub vertices: Vec<[f32; 4]>,
    /// Triangle-list offsets (cells + 1).
    pub tri_offsets: Vec<u32>,
    /// Triangle lists (triangle indices).
    pub tri_items: Vec<u32>,
    /// Nearest (k = 1) list offsets (cells + 1).
    pub near1_offsets: Vec<u32>,
    /// Nearest (k = 1) lists (vertex indices).
    pub near1_items: Vec<u32>,
    /// 4-nearest list offsets (cells + 1).
    pub near4_offsets: Vec<u32>,
    /// 4-nearest lists (vertex indices).
    pub near4_items: Vec<u32>,
    /// Grid columns (φ).
    pub n_phi: u32,
    /// Grid rows (θ).
    pub n_theta: u32,
    /// cos(max gap): Nearest/Idw4 skip vertices with u · d below it.
    pub cos_max_gap: f32,
    /// [`QUADRATIC_ENTRIES`] entries per triangle: `[camera(n₀), camera(n₁), camera(n₂), 1]` (bit-cast;
    /// 0 in the last word: no stencil), then the rows of K ([`super::quadratic`]) as two entries each
    /// (the triangle's three coefficients, then the neighbours', w = 0).
    pub quadratic: Vec<[f32; 4]>,
}

/// Entries of [`SelectionGpu::quadratic`] per triangle.
pub const QUADRATIC_ENTRIES: usize = 7;

impl SelectionGpu {
    /// Bytes of all arrays plus the three scalars (12 bytes).
    pub fn byte_size(&self) -> u64 {
        let words = self.tri_offsets.len()
            + self.tri_items.len()
            + self.near1_offsets.len()
            + self.near1_items.len()
            + self.near4_offsets.len()
            + self.near4_items.len();
        16 * (self.triangles.len() + self.vertices.len() + self.quadratic.len()) as u64 + 4 * words as u64 + 12
    }
}

impl Selection {
    /// The tables in GPU form.
    pub fn gpu_data(&self) -> SelectionGpu {
        let mut triangles = Vec::with_capacity(3 * self.tris.len());
        for ((tri, cross), &hole) in self.tris.iter().zip(&self.cross).zip(&self.hole) {
            for (&v, n) in tri.iter().zip(cross) {
                let cam = if hole {
                    HOLE_CAMERA
                } else {
                    self.vertex_camera[v as usize]
                };
                triangles.push([n.x as f32, n.y as f32, n.z as f32, f32::from_bits(cam)]);
            }
        }
        let vertices = self
            .dirs
            .iter()
            .zip(&self.vertex_camera)
            .map(|(d, &c)| [d.x as f32, d.y as f32, d.z as f32, f32::from_bits(c)])
            .collect();
        let mut quadratic = Vec::with_capacity(QUADRATIC_ENTRIES * self.tris.len());
        for t in 0..self.tris.len() {
            match self.stencil(t) {
                Some(st) => {
                    let cam = st.neighbours.map(|v| f32::from_bits(self.vertex_camera[v as usize]));
                    quadratic.push([cam[0], cam[1], cam[2], f32::from_bits(1)]);
                    for row in &st.k {
                        let r = row.map(|v| v as f32);
                        quadratic.push([r[0], r[1], r[2], 0.0]);
                        quadratic.push([r[3], r[4], r[5], 0.0]);
                    }
                }
                None => quadratic.extend(std::iter::repeat_n([0.0; 4], QUADRATIC_ENTRIES)),
            }
        }
        SelectionGpu {
            triangles,
            vertices,
            tri_offsets: self.tri_cells.offsets.clone(),
            tri_items: self.tri_cells.items.clone(),
            near1_offsets: self.near1.offsets.clone(),
            near1_items: self.near1.items.clone(),
            near4_offsets: self.near4.offsets.clone(),
            near4_items: self.near4.items.clone(),
            n_phi: self.grid.n_phi,
            n_theta: self.grid.n_theta,
            cos_max_gap: self.cos_max_gap as f32,
            quadratic,
        }
    }

    /// Bytes of [`Self::gpu_data`] ([`SelectionGpu::byte_size`]) without building it.
    pub fn gpu_bytes(&self) -> u64 {
        let words = [&self.tri_cells, &self.near1, &self.near4]
            .iter()
            .map(|c| c.offsets.len() + c.items.len())
            .sum::<usize>();
        16 * ((3 + QUADRATIC_ENTRIES) * self.tris.len() + self.dirs.len()) as u64 + 4 * words as u64 + 12
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use glam::{DVec2, DVec3};

    use super::super::{SelectionMode, SelectionOptions};
    use super::*;
    use crate::nearfield::rayset::{Camera, CaptureSphere, Hemisphere, Intrinsics, RayImageSet};

    /// A query on the GPU arrays alone, as the shader does it (in f64 here): Continuous.
    fn gpu_continuous(g: &SelectionGpu, sel: &Selection, u: DVec3) -> Vec<(u32, f64)> {
        let cell = sel.cell_of(u);
        let (a, b) = (g.tri_offsets[cell] as usize, g.tri_offsets[cell + 1] as usize);
        let mut best = (-2.0f64, u32::MAX, [0.0f64; 3]);
        for &t in &g.tri_items[a..b] {
            let e: Vec<f64> = (0..3)
                .map(|k| {
                    let r = g.triangles[3 * t as usize + k];
                    u.dot(DVec3::new(r[0].into(), r[1].into(), r[2].into()))
                })
                .collect();
            let m = e[0].min(e[1]).min(e[2]);
            if m > best.0 {
                best = (m, t, [e[0], e[1], e[2]]);
                if m >= 0.0 {
                    break;
                }
            }
        }
        if best.1 == u32::MAX || g.triangles[3 * best.1 as usize][3].to_bits() == HOLE_CAMERA {
            return vec![];
        }
        let e = best.2.map(|x| x.max(0.0));
        let s = e[0] + e[1] + e[2];
        (0..3)
            .filter(|&k| e[k] > 0.0)
            .map(|k| (g.triangles[3 * best.1 as usize + k][3].to_bits(), e[k] / s))
            .collect()
    }

    #[test]
    fn gpu_arrays_follow_the_layout_and_reproduce_the_queries() {
        let sphere = CaptureSphere {
            centre_m: DVec3::ZERO,
            radius_m: 1.0,
        };
        let mut cameras = Vec::new();
        let n = 300;
        for i in 0..n {
            // Fibonacci directions restricted to z < 0.3: the top cap is a hole.
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            if z > 0.3 {
                continue;
            }
            let r = (1.0 - z * z).sqrt();
            let a = 2.399_963_229_728_653 * i as f64;
            let d = DVec3::new(r * a.cos(), r * a.sin(), z);
            cameras.push(Camera::on_sphere(&sphere, d, Hemisphere::Lower, format!("c{i}")));
        }
        let set = RayImageSet {
            sphere,
            intrinsics: Intrinsics {
                width: 4,
                height: 4,
                principal_px: DVec2::splat(2.0),
                focal_px: DVec2::splat(4.0),
            },
            cameras,
        };
        let sel = Selection::build(&set, &SelectionOptions::default()).unwrap();
        let g = sel.gpu_data();
        assert_eq!(g.byte_size(), sel.gpu_bytes());
        assert_eq!(g.triangles.len(), 3 * sel.triangles().len());
        assert_eq!(g.vertices.len(), sel.vertex_directions().len());
        assert_eq!(g.tri_offsets.len(), sel.cells() + 1);
        assert_eq!(g.near4_offsets.len(), sel.cells() + 1);
        assert_eq!((g.n_phi, g.n_theta), sel.grid());
        assert_eq!(*g.tri_offsets.last().unwrap() as usize, g.tri_items.len());
        assert!(sel.stats().holes > 0 && sel.stats().holes < sel.triangles().len() / 4);
        for (t, tri) in sel.triangles().iter().enumerate() {
            let d = tri.map(|v| sel.vertex_directions()[v as usize]);
            let want = [d[1].cross(d[2]), d[2].cross(d[0]), d[0].cross(d[1])];
            for k in 0..3 {
                let r = g.triangles[3 * t + k];
                assert!((DVec3::new(r[0].into(), r[1].into(), r[2].into()) - want[k]).length() < 1e-6);
                let cam = r[3].to_bits();
                if sel.is_hole(t) {
                    assert_eq!(cam, HOLE_CAMERA);
                } else {
                    assert_eq!(cam, sel.vertex_camera()[tri[k] as usize]);
                }
            }
        }
        for (v, r) in g.vertices.iter().enumerate() {
            assert_eq!(r[3].to_bits(), sel.vertex_camera()[v]);
        }
        // The arrays alone reproduce the CPU query (up to the f32 rounding of the cross products).
        let mut rng = crate::nearfield::layout::SplitMix64::new(5);
        let mut holes = 0;
        for _ in 0..5000 {
            let u = DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, rng.next_f64() - 0.5).normalize();
            let cpu = sel.select(SelectionMode::Continuous, u);
            let gpu = gpu_continuous(&g, &sel, u);
            holes += usize::from(cpu.is_empty());
            assert_eq!(cpu.is_empty(), gpu.is_empty(), "{u}");
            for (cam, w) in gpu {
                assert!((cpu.weight_of(cam) - w).abs() < 1e-4, "{u}");
            }
        }
        assert!(holes > 100, "the top cap is a hole: {holes}");
        assert!(holes < 2500, "the rest is measured: {holes}");
        assert_eq!(sel.stats().folded, 0);
    }
}
