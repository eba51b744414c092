//! Luminaires, instances and frames: the scene a host builds through the C API.
//!
//! A luminaire is loaded once (its data uploaded once); instances refer to it with their own model
//! matrix (luminaire frame → world, metres). Ids are never reused within a renderer, so a stale id
//! is an error, never another object.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use glam::Mat4;

use super::camera::HostCamera;
use super::context::{ContextDesc, GpuContext};
use super::farfield::{FarfieldLuminaire, FarfieldPass};
use super::frame::{self, FrameView, RenderOptions};
use super::nearfield::{NearfieldLuminaire, NearfieldOptions, NearfieldPass, NearfieldSettings};
use super::scene::{ScenePass, SceneSettings};
use super::target::RenderTarget;
use super::{Arg, GpuError};
use crate::nearfield::pack::Pack;
use crate::photometry::{self, LoadOptions, Photometry};

/// Identifies a luminaire in a renderer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct LuminaireId(pub u64);

/// Identifies an instance in a renderer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct InstanceId(pub u64);

/// A luminaire the renderer can draw.
#[derive(Debug)]
pub enum Luminaire {
    /// Far-field photometry (IES / EULUMDAT) drawn as its luminous opening.
    Farfield(Arc<FarfieldLuminaire>),
    /// A near-field scan drawn with its measured luminance.
    Nearfield(Arc<NearfieldLuminaire>),
}

impl Luminaire {
    /// The far-field photometry, if that is what it is.
    pub fn photometry(&self) -> Option<&Arc<Photometry>> {
        match self {
            Luminaire::Farfield(f) => Some(&f.photometry),
            Luminaire::Nearfield(_) => None,
        }
    }
}

#[derive(Debug)]
struct Instance {
    luminaire: LuminaireId,
    model: Mat4,
    nearfield: NearfieldSettings,
}

/// The renderer: a GPU context, the passes, luminaires and instances.
#[derive(Debug)]
pub struct Renderer {
    /// The GPU context.
    pub ctx: GpuContext,
    farfield: FarfieldPass,
    nearfield: NearfieldPass,
    scene: ScenePass,
    luminaires: BTreeMap<LuminaireId, Luminaire>,
    instances: BTreeMap<InstanceId, Instance>,
    next_id: u64,
}

impl Renderer {
    /// Opens a device and compiles the passes.
    pub fn new(desc: &ContextDesc) -> Result<Self, GpuError> {
        let ctx = GpuContext::new(desc)?;
        let farfield = FarfieldPass::new(&ctx)?;
        let nearfield = NearfieldPass::new(&ctx)?;
        let scene = ScenePass::new(&ctx)?;
        Ok(Renderer {
            ctx,
            farfield,
            nearfield,
            scene,
            luminaires: BTreeMap::new(),
            instances: BTreeMap::new(),
            next_id: 1,
        })
    }

    fn next(&mut self) -> u64 {
        let id = self.next_id;
        self.next_id += 1;
        id
    }

    /// Loads a luminaire from a file (format detected: IES, EULUMDAT).
    pub fn load_luminaire(&mut self, path: &Path, opts: &LoadOptions) -> Result<LuminaireId, GpuError> {
        let p = photometry::load(path, opts)?;
        self.add_photometry(Arc::new(p))
    }

    /// Adds far-field photometry as a luminaire.
    pub fn add_photometry(&mut self, p: Arc<Photometry>) -> Result<LuminaireId, GpuError> {
        let lum = self.farfield.upload(&self.ctx, p)?;
        let id = LuminaireId(self.next());
        self.luminaires.insert(id, Luminaire::Farfield(Arc::new(lum)));
        Ok(id)
    }

    /// Adds a near-field scan (an open `.lvpack`) as a luminaire, with an optional proxy mesh
    /// (triangle list in the luminaire frame, metres).
    pub fn add_pack(
        &mut self,
        pack: Arc<Pack>,
        proxy: Option<Vec<[f32; 3]>>,
        opts: &NearfieldOptions,
    ) -> Result<LuminaireId, GpuError> {
        let lum = self.nearfield.upload(&self.ctx, pack, proxy, opts)?;
        let id = LuminaireId(self.next());
        self.luminaires.insert(id, Luminaire::Nearfield(Arc::new(lum)));
        Ok(id)
    }

    /// Sets an instance's near-field settings (selection mode, proxy use); ignored by far-field
    /// luminaires.
    pub fn set_nearfield_settings(&mut self, id: InstanceId, settings: NearfieldSettings) -> Result<(), GpuError> {
        let inst = self
            .instances
            .get_mut(&id)
            .ok_or_else(|| GpuError::invalid(Arg::Instance, format!("no instance with id {}", id.0)))?;
        inst.nearfield = settings;
        Ok(())
    }

    /// A luminaire by id.
    pub fn luminaire(&self, id: LuminaireId) -> Result<&Luminaire, GpuError> {
        self.luminaires
            .get(&id)
            .ok_or_else(|| GpuError::invalid(Arg::Luminaire, format!("no luminaire with id {}", id.0)))
    }

    /// Removes a luminaire and every instance of it.
    pub fn remove_luminaire(&mut self, id: LuminaireId) -> Result<(), GpuError> {
        self.luminaires
            .remove(&id)
            .ok_or_else(|| GpuError::invalid(Arg::Luminaire, format!("no luminaire with id {}", id.0)))?;
        self.instances.retain(|_, i| i.luminaire != id);
        Ok(())
    }

    /// Adds an instance of a luminaire with a model matrix (luminaire frame → world).
    pub fn add_instance(&mut self, luminaire: LuminaireId, model: Mat4) -> Result<InstanceId, GpuError> {
        self.luminaire(luminaire)?;
        check_model(&model)?;
        let id = InstanceId(self.next());
        self.instances.insert(
            id,
            Instance {
                luminaire,
                model,
                nearfield: NearfieldSettings::default(),
            },
        );
        Ok(id)
    }

    /// Whether an instance exists.
    pub fn has_instance(&self, id: InstanceId) -> bool {
        self.instances.contains_key(&id)
    }

    /// Sets an instance's model matrix.
    pub fn set_transform(&mut self, id: InstanceId, model: Mat4) -> Result<(), GpuError> {
        check_model(&model)?;
        let inst = self.instances.get_mut(&id).ok_or_else(|| {
            GpuError::invalid(
                Arg::Instance,
                format!("no instance with id {} (destroyed, or its luminaire was)", id.0),
            )
        })?;
        inst.model = model;
        Ok(())
    }

    /// Every instance as (id, luminaire, model matrix), in id order.
    pub fn instances(&self) -> impl Iterator<Item = (InstanceId, LuminaireId, Mat4)> + '_ {
        self.instances.iter().map(|(id, i)| (*id, i.luminaire, i.model))
    }

    /// An instance's luminaire and model matrix.
    pub fn instance(&self, id: InstanceId) -> Result<(LuminaireId, Mat4), GpuError> {
        self.instances
            .get(&id)
            .map(|i| (i.luminaire, i.model))
            .ok_or_else(|| GpuError::invalid(Arg::Instance, format!("no instance with id {}", id.0)))
    }

    /// Illuminance in lux at a world point on a surface with unit normal `normal` from one instance,
    /// by the inverse-square law E = I(d) · max(0, cos i) / r², where d is the direction from the
    /// instance's photometric centre to the point in its luminaire frame, r the distance in metres and
    /// i the angle between the normal and the direction back to the luminaire. The far-field
    /// approximation (the host's shaders evaluate the same formula from the look-up tables).
    pub fn illuminance(&self, id: InstanceId, point: glam::Vec3, normal: glam::Vec3) -> Result<f64, GpuError> {
        let (lum, model) = self.instance(id)?;
        if !point.is_finite() || !normal.is_finite() || normal.length_squared() < 1e-12 {
            return Err(GpuError::invalid(
                Arg::PointNormal,
                "must be finite with a non-zero normal",
            ));
        }
        let p = self.light_of(lum)?;
        let centre = model.transform_point3(glam::Vec3::ZERO).as_dvec3();
        let to_point = point.as_dvec3() - centre;
        let r2 = to_point.length_squared();
        if r2 < 1e-12 {
            return Err(GpuError::invalid(
                Arg::Point,
                "coincides with the luminaire's photometric centre",
            ));
        }
        let local = model.inverse().as_dmat4().transform_vector3(to_point).normalize();
        let cd = p.web.sample_dir([local.x, local.y, local.z]);
        let cos_i = (-to_point.normalize()).dot(normal.as_dvec3().normalize()).max(0.0);
        Ok(cd * cos_i / r2)
    }

    /// Loads a scene for the scene lighting pass (replacing any earlier one): from then on every
    /// frame draws it lit by every instance (a scan by its far field), before the luminaires' own
    /// appearance.
    pub fn set_scene(&mut self, scene: &crate::scene::Scene) -> Result<(), GpuError> {
        self.scene.set_scene(&self.ctx, Arc::new(scene.clone()), None)
    }

    /// [`Renderer::set_scene`] sharing the caller's scene and, when it has one, its ray-query
    /// hierarchy (photons for inter-reflection are traced through it; built on first use
    /// otherwise).
    pub fn set_scene_shared(
        &mut self,
        scene: Arc<crate::scene::Scene>,
        bvh: Option<Arc<crate::scene::bvh::Bvh>>,
    ) -> Result<(), GpuError> {
        self.scene.set_scene(&self.ctx, scene, bvh)
    }

    /// How the scene is lit (the settings last set).
    pub fn scene_settings(&self) -> SceneSettings {
        self.scene.settings()
    }

    /// Whether a scene is set.
    pub fn has_scene(&self) -> bool {
        self.scene.has_scene()
    }

    /// What the scene pass used for its last frame: luminaires, virtual point lights, shadow
    /// face size, and how often shadows and VPLs were made.
    pub fn scene_stats(&self) -> crate::gpu::scene::SceneStats {
        self.scene.stats()
    }

    /// What lights the scene: every instance's photometry and model matrix, in instance order (a
    /// near-field scan's far field, [`NearfieldLuminaire::far_field`], estimated on first use). Empty
    /// without a scene.
    ///
    /// Errors: a scan whose far field cannot be estimated (its images cannot be read).
    pub fn scene_lights(&self) -> Result<Vec<(Arc<Photometry>, Mat4)>, GpuError> {
        if !self.scene.has_scene() {
            return Ok(Vec::new());
        }
        let mut out = Vec::with_capacity(self.instances.len());
        for inst in self.instances.values() {
            if self.luminaires.contains_key(&inst.luminaire) {
                out.push((self.light_of(inst.luminaire)?, inst.model));
            }
        }
        Ok(out)
    }

    /// Gives a near-field luminaire the far field it lights a scene with (one the caller estimated
    /// already, so it is not estimated again); a far-field luminaire keeps its own photometry.
    ///
    /// Errors: an unknown id; a far-field luminaire; a scan whose far field is set or estimated
    /// already.
    pub fn set_far_field(&self, id: LuminaireId, p: Arc<Photometry>) -> Result<(), GpuError> {
        match self.luminaire(id)? {
            Luminaire::Farfield(_) => Err(GpuError::invalid(
                Arg::Luminaire,
                "a far-field luminaire lights with its own photometry",
            )),
            Luminaire::Nearfield(n) => n.set_far_field(p),
        }
    }

    /// The photometry a luminaire lights a scene with: a far-field file's own, or a scan's far
    /// field ([`NearfieldLuminaire::far_field`], estimated on first use and kept).
    ///
    /// Errors: an unknown id; a scan whose far field cannot be estimated.
    pub fn light_of(&self, id: LuminaireId) -> Result<Arc<Photometry>, GpuError> {
        match self.luminaire(id)? {
            Luminaire::Farfield(f) => Ok(f.photometry.clone()),
            Luminaire::Nearfield(n) => n.far_field(&self.ctx),
        }
    }

    /// Removes the scene.
    pub fn clear_scene(&mut self) {
        self.scene.clear_scene();
    }

    /// Sets how the scene is lit (lux floor, shadows, shadow budget).
    pub fn set_scene_settings(&mut self, settings: SceneSettings) -> Result<(), GpuError> {
        self.scene.set_settings(settings)
    }

    /// Removes an instance.
    pub fn remove_instance(&mut self, id: InstanceId) -> Result<(), GpuError> {
        self.instances
            .remove(&id)
            .map(|_| ())
            .ok_or_else(|| GpuError::invalid(Arg::Instance, format!("no instance with id {}", id.0)))
    }

    /// Renders every instance into `target`.
    pub fn render(
        &mut self,
        target: &mut RenderTarget,
        camera: &HostCamera,
        options: &RenderOptions,
    ) -> Result<(), GpuError> {
        let view = FrameView::new(camera, options, &target.desc)?;
        self.ctx.check()?;
        let mut far: Vec<(Arc<FarfieldLuminaire>, Mat4)> = Vec::with_capacity(self.instances.len());
        let mut near: Vec<(Arc<NearfieldLuminaire>, Mat4, NearfieldSettings)> = Vec::new();
        for inst in self.instances.values() {
            match self.luminaires.get(&inst.luminaire) {
                Some(Luminaire::Farfield(f)) => far.push((f.clone(), inst.model)),
                Some(Luminaire::Nearfield(n)) => near.push((n.clone(), inst.model, inst.nearfield)),
                None => {}
            }
        }
        let lights = self.scene_lights()?;
        let scene = frame::prepare(&mut self.scene, &self.ctx, &view, &lights)?;
        let far = frame::prepare(&mut self.farfield, &self.ctx, &view, &far)?;
        let near = frame::prepare(&mut self.nearfield, &self.ctx, &view, &near)?;
        frame::render(&self.ctx, target, &view, &[&scene, &far, &near])
    }
}

fn check_model(m: &Mat4) -> Result<(), GpuError> {
    if !m.is_finite() {
        return Err(GpuError::invalid(Arg::Model, "matrix has a NaN or infinite element"));
    }
    if m.determinant().abs() < 1e-30 {
        return Err(GpuError::invalid(Arg::Model, "matrix is singular"));
    }
    Ok(())
}
