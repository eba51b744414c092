//! Near-field scans (pure CPU): ray-image sets, importers, the synthetic goniophotometer, camera
//! layouts and the tiled `.lvpack` store.

pub mod binning;
pub mod bvh;
pub mod coverage;
pub mod error;
pub mod farfield;
pub mod images;
pub mod layout;
pub mod manifest;
pub mod pack;
pub mod proxy;
pub mod raykde;
pub mod rayset;
pub mod reconstruct;
pub mod scanfile;
pub mod select;
pub mod synth;
pub mod tm25;

pub use error::NearfieldError;
pub use rayset::{
    Camera, CaptureSphere, Hemisphere, ImageMeta, ImageSource, Intrinsics, LuminanceImage, RayImageSet, Scan,
};
