//! Near-field scans (pure CPU): ray-image sets, importers, the synthetic goniophotometer, camera
//! layouts and the tiled `.lvpack` store.

pub mod error;
pub mod layout;
pub mod rayset;

pub use error::NearfieldError;
pub use rayset::{
    Camera, CaptureSphere, Hemisphere, ImageMeta, ImageSource, Intrinsics, LuminanceImage, RayImageSet, Scan,
};
