//! Helpers shared by the scene tests (tests/scene_reference.rs on the CPU, tests/gpu_scene.rs on the
//! GPU): a photometry from text, a scene of grey parts, the sample office, the floor. CPU only.

use std::sync::Arc;

use glam::DVec3;
use lumiview::photometry::{load_from_text, LoadOptions, Photometry};
use lumiview::scene::{Material, Scene, SceneParts};

/// A photometry read from file text.
pub fn photometry_text(text: &str, name: &str) -> Arc<Photometry> {
    Arc::new(load_from_text(text, name, &LoadOptions::default()).unwrap())
}

/// A scene of parts, each its triangles with one grey reflectance.
pub fn scene_of(parts: Vec<(Vec<[DVec3; 3]>, f64)>) -> Scene {
    let mut p = SceneParts::default();
    for (m, (tris, rho)) in parts.into_iter().enumerate() {
        p.material_of.extend(std::iter::repeat_n(m as u32, tris.len()));
        p.triangles.extend(tris);
        p.materials.push(Material::grey(rho));
    }
    Scene::new(p).unwrap()
}

/// The shipped sample office (`assets/scenes/office.glb`).
pub fn office() -> Scene {
    lumiview::scene::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/office.glb")).unwrap()
}

/// The floor y = 0 over ±`half` m, facing up.
pub fn floor(half: f64) -> Vec<[DVec3; 3]> {
    let c = |x: f64, z: f64| DVec3::new(x, 0.0, z);
    let (a, b, cc, d) = (c(-half, half), c(half, half), c(half, -half), c(-half, -half));
    vec![[a, b, cc], [a, cc, d]]
}
