//! A small neutral drawing leaf, pure CPU, used by the polar and isolux plots, the camera-coverage
//! pictures and the mesh writers: text with the one bundled font ([`text`]) and the glTF 2.0
//! binary container ([`glb`]). It depends on no other lumiview module.

pub mod glb;
pub mod text;
