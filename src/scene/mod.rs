//! Scene lighting's pure-CPU foundation (issue 20): glTF scenes, luminaires placed in them, ray
//! queries, and the reference path tracer that gives illuminance per bounce. No wgpu, no unsafe.
//!
//! - [`mod@load`]: a glTF 2.0 scene → [`Scene`] (world-space triangles in metres, +Y up, diffuse
//!   materials with base-colour textures), hostile files as errors.
//! - [`model`]: the [`Scene`] and its reflectance at a point (RGB and the scalar ρ_Y).
//! - [`texture`]: PNG base-colour textures and their sampling.
//! - [`place`]: `@X,Y,Z[,YAW]` → the luminaire-frame → scene matrix.
//! - [`bvh`]: the hierarchy for closest-hit and shadow queries.
//! - [`emitter`]: photometric luminaires as point or area sources.
//! - [`mod@reference`]: the path tracer ([`illuminance`], [`PerBounce`]).
//! - [`grid`]: work-plane grids and their CSV.
//! - [`plot`]: the grid as a plan view in false colour with isolux lines and the report figures.
//! - [`vpl`]: inter-reflection by virtual point lights shot from the luminaires (the GPU's bounce).
//! - [`sampling`]: the random numbers (PCG32) and direction sampling.
//! - [`sample`]: the generated sample scenes (the office shipped as `assets/scenes/office.glb`).
//!
//! Conventions and measured accuracy: docs/scene-lighting.md.

pub mod bvh;
pub mod emitter;
pub mod error;
pub mod grid;
pub mod load;
pub mod model;
pub mod place;
pub mod plot;
pub mod reference;
pub mod sample;
pub mod sampling;
pub mod texture;
pub mod vpl;

pub use emitter::SceneLuminaire;
pub use error::SceneError;
pub use load::{load, load_from_slice};
pub use model::{Aabb, Material, Scene, SceneParts};
pub use place::{placement, Placement};
pub use reference::{illuminance, PerBounce, SurfacePoint, TraceOptions, Tracer};
