//! What every part of the selection tests uses: camera sets on one capture sphere (from a layout or
//! from directions), the default build, random unit directions, angles, and a triangle's corners and
//! edge values (u·(b×c), …: all ≥ 0 inside).

use std::f64::consts::TAU;

use glam::{DVec2, DVec3};

use lumiview::nearfield::layout::{cameras, Layout, SplitMix64};
use lumiview::nearfield::select::{Selection, SelectionMode, SelectionOptions};
use lumiview::nearfield::{Camera, CaptureSphere, Hemisphere, Intrinsics, RayImageSet};

pub(crate) const MODES: [SelectionMode; 3] = [SelectionMode::Nearest, SelectionMode::Idw4, SelectionMode::Continuous];

pub(crate) fn sphere() -> CaptureSphere {
    CaptureSphere {
        centre_m: DVec3::new(0.01, -0.02, 0.03),
        radius_m: 1.117,
    }
}

pub(crate) fn set_of(cameras: Vec<Camera>) -> RayImageSet {
    RayImageSet {
        sphere: sphere(),
        intrinsics: Intrinsics {
            width: 16,
            height: 16,
            principal_px: DVec2::splat(8.0),
            focal_px: DVec2::splat(16.0),
        },
        cameras,
    }
}

pub(crate) fn layout_set(layout: Layout, seed: u64) -> RayImageSet {
    set_of(cameras(&sphere(), &layout, seed).unwrap())
}

pub(crate) fn dirs_set(dirs: &[DVec3]) -> RayImageSet {
    let s = sphere();
    set_of(
        dirs.iter()
            .enumerate()
            .map(|(i, d)| Camera::on_sphere(&s, *d, Hemisphere::Lower, format!("cam {i}")))
            .collect(),
    )
}

pub(crate) fn build(set: &RayImageSet) -> Selection {
    Selection::build(set, &SelectionOptions::default()).unwrap()
}

pub(crate) fn random_unit(rng: &mut SplitMix64) -> DVec3 {
    let z = 2.0 * rng.next_f64() - 1.0;
    let a = TAU * rng.next_f64();
    let s = (1.0 - z * z).sqrt();
    DVec3::new(s * a.cos(), s * a.sin(), z)
}

pub(crate) fn angle(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

pub(crate) fn corners(sel: &Selection, t: usize) -> [DVec3; 3] {
    sel.triangles()[t].map(|v| sel.vertex_directions()[v as usize])
}

/// e = (u·(b×c), u·(c×a), u·(a×b)).
pub(crate) fn edge_values(sel: &Selection, t: usize, u: DVec3) -> [f64; 3] {
    let [a, b, c] = corners(sel, t);
    [u.dot(b.cross(c)), u.dot(c.cross(a)), u.dot(a.cross(b))]
}

pub(crate) fn min3(e: [f64; 3]) -> f64 {
    e[0].min(e[1]).min(e[2])
}
