//! A scene as the lighting computations see it: world-space triangles in metres (glTF's axes, +Y
//! up), each with a diffuse material, and the reflectance at any point of any triangle.
//!
//! Promises:
//! - Every [`Scene`] holds at least one triangle, at most [`MAX_TRIANGLES`]; every vertex is
//!   finite; every triangle's material exists; its bounds contain every vertex.
//! - A material's diffuse reflectance ρ is its linear RGB base-colour factor times its base-colour
//!   texture (sRGB-decoded) at the point's UV, each channel in 0…1. Photometric computations use
//!   the luminance-weighted scalar ρ_Y = 0.2126 R + 0.7152 G + 0.0722 B ([`luminance_y`], the Y row
//!   of linear sRGB/Rec. 709), so a grey of ρ is ρ in both.
//! - Surfaces are two-sided for the lighting: a surface reflects on the side light reaches, and
//!   occludes from both sides, whatever its winding or glTF's `doubleSided` (which only says whether
//!   a renderer may cull back faces).

use glam::DVec3;

use super::error::{Result, SceneError};
use super::texture::{Image, TextureRef};

/// Most triangles a scene may have.
pub const MAX_TRIANGLES: usize = 8_000_000;

/// The luminance-weighted scalar of a linear RGB reflectance (Rec. 709 / sRGB primaries, D65):
/// 0.2126 R + 0.7152 G + 0.0722 B.
pub fn luminance_y(rgb: [f64; 3]) -> f64 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

/// An axis-aligned box, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: DVec3,
    /// Largest corner.
    pub max: DVec3,
}

impl Aabb {
    /// The empty box (grows from nothing).
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::INFINITY,
        max: DVec3::NEG_INFINITY,
    };

    /// The box grown to hold `p`.
    pub fn grow(self, p: DVec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// The smallest box holding both.
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Extent along each axis (negative for the empty box).
    pub fn size(&self) -> DVec3 {
        self.max - self.min
    }

    /// Half the surface area (the SAH cost's measure); 0 for the empty box.
    pub fn half_area(&self) -> f64 {
        let d = self.size();
        if d.min_element() < 0.0 {
            return 0.0;
        }
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// A diffuse material.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Linear RGB base-colour factor, each channel in 0…1 (glTF `baseColorFactor` without alpha).
    pub base_color_factor: [f64; 3],
    /// The base-colour texture, multiplied into the factor where present.
    pub base_color_texture: Option<TextureRef>,
}

impl Material {
    /// An untextured grey of reflectance `rho` (clamped to 0…1).
    pub fn grey(rho: f64) -> Self {
        Material {
            base_color_factor: [rho.clamp(0.0, 1.0); 3],
            base_color_texture: None,
        }
    }
}

/// A scene's triangles and materials (see the module's promises).
#[derive(Debug, Clone)]
pub struct Scene {
    triangles: Vec<[DVec3; 3]>,
    material_of: Vec<u32>,
    uvs: Vec<[[f32; 2]; 3]>,
    materials: Vec<Material>,
    images: Vec<Image>,
    bounds: Aabb,
    warnings: Vec<String>,
}

/// The parts a [`Scene`] is made of, checked by [`Scene::new`].
#[derive(Debug, Clone, Default)]
pub struct SceneParts {
    /// World-space triangles, metres, +Y up.
    pub triangles: Vec<[DVec3; 3]>,
    /// Each triangle's index into `materials`.
    pub material_of: Vec<u32>,
    /// Each triangle's vertex UVs (the set its material's texture reads); may be empty when no
    /// material has a texture.
    pub uvs: Vec<[[f32; 2]; 3]>,
    /// The materials.
    pub materials: Vec<Material>,
    /// The images the materials' textures refer to.
    pub images: Vec<Image>,
    /// Non-fatal findings of whoever made the parts (a loader's unsupported features).
    pub warnings: Vec<String>,
}

impl Scene {
    /// Checks `parts` and makes the scene.
    ///
    /// Errors (argument `scene`): no triangles or more than [`MAX_TRIANGLES`]; lengths of
    /// `material_of` or `uvs` that do not match; a non-finite vertex; a material or image index out
    /// of range; a non-finite or out-of-range factor.
    pub fn new(parts: SceneParts) -> Result<Self> {
        let bad = |m: String| SceneError::invalid("scene", m);
        let SceneParts {
            triangles,
            material_of,
            mut uvs,
            materials,
            images,
            warnings,
        } = parts;
        let n = triangles.len();
        if n == 0 {
            return Err(bad("no triangles".into()));
        }
        if n > MAX_TRIANGLES {
            return Err(bad(format!("{n} triangles; at most {MAX_TRIANGLES} are supported")));
        }
        if material_of.len() != n {
            return Err(bad(format!("{} material indices for {n} triangles", material_of.len())));
        }
        let textured = materials.iter().any(|m| m.base_color_texture.is_some());
        if uvs.is_empty() && !textured {
            uvs = vec![[[0.0; 2]; 3]; n];
        }
        if uvs.len() != n {
            return Err(bad(format!("{} UV triples for {n} triangles", uvs.len())));
        }
        for (i, m) in materials.iter().enumerate() {
            if !m.base_color_factor.iter().all(|c| (0.0..=1.0).contains(c)) {
                return Err(bad(format!(
                    "material {i}: base colour factor {:?} is not within 0…1",
                    m.base_color_factor
                )));
            }
            if let Some(t) = &m.base_color_texture {
                if t.image >= images.len() {
                    return Err(bad(format!("material {i}: image {} of {}", t.image, images.len())));
                }
            }
        }
        let mut bounds = Aabb::EMPTY;
        for (t, (tri, &m)) in triangles.iter().zip(&material_of).enumerate() {
            if !tri.iter().all(|v| v.is_finite()) {
                return Err(bad(format!("triangle {t} has a vertex that is not finite")));
            }
            if m as usize >= materials.len() {
                return Err(bad(format!("triangle {t}: material {m} of {}", materials.len())));
            }
            for v in tri {
                bounds = bounds.grow(*v);
            }
        }
        Ok(Scene {
            triangles,
            material_of,
            uvs,
            materials,
            images,
            bounds,
            warnings,
        })
    }

    /// The triangles, world space, metres.
    pub fn triangles(&self) -> &[[DVec3; 3]] {
        &self.triangles
    }

    /// Each triangle's material index.
    pub fn material_of(&self) -> &[u32] {
        &self.material_of
    }

    /// Each triangle's vertex UVs.
    pub fn uvs(&self) -> &[[[f32; 2]; 3]] {
        &self.uvs
    }

    /// The materials.
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// The decoded images.
    pub fn images(&self) -> &[Image] {
        &self.images
    }

    /// The box holding every vertex.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Non-fatal findings of the loader (unsupported image formats, defaults applied).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// The linear RGB diffuse reflectance of triangle `tri` at barycentric coordinates (`b1`,
    /// `b2`) (the point v0 + b1 (v1 − v0) + b2 (v2 − v0)). `tri` must be a triangle of the scene.
    pub fn reflectance_rgb(&self, tri: usize, b1: f64, b2: f64) -> [f64; 3] {
        let m = &self.materials[self.material_of[tri] as usize];
        let Some(t) = &m.base_color_texture else {
            return m.base_color_factor;
        };
        let [a, b, c] = self.uvs[tri].map(|p| p.map(f64::from));
        let b0 = 1.0 - b1 - b2;
        let u = b0 * a[0] + b1 * b[0] + b2 * c[0];
        let v = b0 * a[1] + b1 * b[1] + b2 * c[1];
        let texel = self.images[t.image].sample_linear(u, v, t);
        std::array::from_fn(|k| m.base_color_factor[k] * texel[k])
    }

    /// The scalar reflectance ρ_Y ([`luminance_y`] of [`Scene::reflectance_rgb`]).
    pub fn reflectance_y(&self, tri: usize, b1: f64, b2: f64) -> f64 {
        luminance_y(self.reflectance_rgb(tri, b1, b2))
    }

    /// The total area of the triangles, m².
    pub fn area_m2(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length())
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::texture::{Filter, Wrap};

    fn one_triangle() -> SceneParts {
        SceneParts {
            triangles: vec![[DVec3::ZERO, DVec3::X, DVec3::Z]],
            material_of: vec![0],
            materials: vec![Material::grey(0.5)],
            ..Default::default()
        }
    }

    #[test]
    fn a_scene_checks_its_parts() {
        let s = Scene::new(one_triangle()).unwrap();
        assert_eq!(s.bounds().max, DVec3::new(1.0, 0.0, 1.0));
        assert!((s.area_m2() - 0.5).abs() < 1e-15);
        assert_eq!(s.reflectance_y(0, 0.2, 0.3), 0.5);
        let mut p = one_triangle();
        p.material_of = vec![1];
        assert!(Scene::new(p).unwrap_err().to_string().contains("material 1 of 1"));
        let mut p = one_triangle();
        p.triangles[0][1].y = f64::NAN;
        assert!(Scene::new(p).unwrap_err().to_string().contains("not finite"));
        let mut p = one_triangle();
        p.materials[0].base_color_factor[2] = 1.5;
        assert!(Scene::new(p).is_err());
        assert!(Scene::new(SceneParts::default())
            .unwrap_err()
            .to_string()
            .contains("no triangles"));
    }

    #[test]
    fn texture_times_factor_at_the_barycentric_uv() {
        let mut p = one_triangle();
        // 2 × 1 image: left texel sRGB 255 (linear 1), right 0; nearest.
        p.images = vec![Image::from_srgb(2, 1, vec![[255; 3], [0; 3]]).unwrap()];
        p.materials[0].base_color_texture = Some(TextureRef {
            image: 0,
            tex_coord: 0,
            wrap_s: Wrap::ClampToEdge,
            wrap_t: Wrap::ClampToEdge,
            filter: Filter::Nearest,
        });
        p.materials[0].base_color_factor = [0.8, 0.4, 0.2];
        p.uvs = vec![[[0.0, 0.5], [1.0, 0.5], [0.0, 0.5]]];
        let s = Scene::new(p).unwrap();
        assert_eq!(s.reflectance_rgb(0, 0.1, 0.5), [0.8, 0.4, 0.2], "u = 0.1: left texel");
        assert_eq!(s.reflectance_rgb(0, 0.9, 0.05), [0.0; 3], "u = 0.9: right texel");
        let y = s.reflectance_y(0, 0.1, 0.1);
        assert!((y - (0.2126 * 0.8 + 0.7152 * 0.4 + 0.0722 * 0.2)).abs() < 1e-15);
    }
}
