//! A small neutral drawing leaf, pure CPU, used by the polar and isolux plots, the camera-coverage
//! pictures and the mesh writers. It depends on no other lumiview module.
//!
//! - [`text`]: text with the one bundled font (layout, measuring, fitting, drawing).
//! - [`colormap`]: colour maps from a value in 0…1 to sRGB (viridis, a light yellow-orange-brown).
//! - [`ticks`]: 1-2-5 steps, tick values over a range and tick labels.
//! - [`glb`]: the glTF 2.0 binary container.

pub mod colormap;
pub mod glb;
pub mod text;
pub mod ticks;
