//! The scene pass's luminaires as the shader reads them: one [`LightRecord`] per instance, the
//! intensity tables of their photometries in one atlas texture, and the per-tile lists of the
//! luminaires whose influence reaches a screen tile.
//!
//! Promises:
//! - Intensity tables are I(C, γ) in cd at [`INTENSITY_TABLE_W`] × [`INTENSITY_TABLE_H`] nodes (0.5°
//!   in C and γ, node-aligned like the far-field pass's luminance table), bilinear between nodes
//!   in the shader: exactly the web's own bilinear interpolation wherever its angles are
//!   multiples of 0.5°. One table per distinct photometry (shared by its instances), laid out in
//!   rows of at most [`MAX_TABLES_PER_ROW`] within an 8192-pixel atlas: at most
//!   [`MAX_INTENSITY_TABLES`] photometries per scene.
//! - A luminaire's influence radius is √(I_max / E_floor) plus its opening's half-diagonal: beyond
//!   it the luminaire adds less than the lux floor E_floor and is skipped (documented as the
//!   pass's only deliberate omission of light; `SceneSettings::lux_floor_lx`).
//! - The opening is cut into na × nb stratified points (at most [`MAX_OPENING_POINTS`], the grid
//!   closest to the opening's aspect ratio): flat rectangles and ellipses as they are; the vertical
//!   ellipses in their own plane; boxes, cylinders, ellipsoids and EULUMDAT shapes with sides by
//!   their horizontal footprint (rectangle or ellipse): their penumbrae take the footprint's size.
//! - Tiles: the screen is cut into [`TILE_PX`]-pixel squares; a luminaire is listed for every tile
//!   its influence sphere's screen rectangle touches (conservatively: the projected corners of the
//!   sphere's bounding box, the whole screen when a corner lies behind the eye).

use glam::{Mat3, Mat4, Vec3, Vec4};

use crate::photometry::{OpeningShape, Photometry};

/// Width of an intensity table: C from 0 to 360° in 0.5° steps.
pub const INTENSITY_TABLE_W: u32 = 721;
/// Height of an intensity table: γ from 0 to 180° in 0.5° steps.
pub const INTENSITY_TABLE_H: u32 = 361;
/// Tables per atlas row (8192 / 721).
pub const MAX_TABLES_PER_ROW: u32 = 11;
/// Most distinct photometries in one scene (11 × 22 tables in 8192²).
pub const MAX_INTENSITY_TABLES: usize = 242;
/// Most points an opening is cut into.
pub const MAX_OPENING_POINTS: u32 = 16;
/// Side of a screen tile, pixels.
pub const TILE_PX: u32 = 16;

/// Storage record of one luminaire (`Light` in shaders/scene/lighting.wgsl, which documents the
/// members; `gpu::shaders` tests the two layouts are one).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LightRecord {
    /// Photometric centre (world m), influence radius (m).
    pub centre: [f32; 4],
    /// Luminaire-from-world rotation, row 0.
    pub local_x: [f32; 4],
    /// Row 1.
    pub local_y: [f32; 4],
    /// Row 2.
    pub local_z: [f32; 4],
    /// Opening half-axis a (world m), points along it.
    pub axis_a: [f32; 4],
    /// Opening half-axis b (world m), points along it.
    pub axis_b: [f32; 4],
    /// Intensity table, first shadow face, elliptic opening, unused.
    pub tables: [u32; 4],
}

/// The intensity table of a photometry (cd, row-major over γ then C).
pub fn intensity_table(p: &Photometry) -> Vec<f32> {
    let mut out = Vec::with_capacity((INTENSITY_TABLE_W * INTENSITY_TABLE_H) as usize);
    for j in 0..INTENSITY_TABLE_H {
        for i in 0..INTENSITY_TABLE_W {
            let c = 360.0 * f64::from(i) / f64::from(INTENSITY_TABLE_W - 1);
            let g = 180.0 * f64::from(j) / f64::from(INTENSITY_TABLE_H - 1);
            let cd = p.intensity(c, g);
            out.push(if cd.is_finite() {
                cd.clamp(0.0, f64::from(f32::MAX)) as f32
            } else {
                0.0
            });
        }
    }
    out
}

/// The opening's half-axes in the luminaire frame and whether it is elliptic (see the module's
/// promises), zero for a point.
fn opening_axes(p: &Photometry) -> (Vec3, Vec3, bool) {
    let o = &p.opening;
    if o.is_point() {
        return (Vec3::ZERO, Vec3::ZERO, false);
    }
    let hx = Vec3::X * (o.size_x_m / 2.0) as f32;
    let hy = Vec3::Y * (o.size_y_m / 2.0) as f32;
    let hz = Vec3::Z * (o.height_m / 2.0) as f32;
    use OpeningShape as S;
    match o.shape {
        S::Point => (Vec3::ZERO, Vec3::ZERO, false),
        S::VerticalEllipseFacingC0 => (hy, hz, true),
        S::VerticalEllipseFacingC90 => (hx, hz, true),
        S::Ellipse | S::VerticalCylinder | S::Ellipsoid | S::DiscWithSides => (hx, hy, true),
        S::Rectangle
        | S::Box
        | S::RectangleWithSides
        | S::HorizontalCylinderAlongLength
        | S::HorizontalCylinderAlongWidth => (hx, hy, false),
    }
}

/// Points along the two half-axes of lengths `a_m`, `b_m`: the grid with at most
/// [`MAX_OPENING_POINTS`] points whose aspect ratio is closest to the opening's; (1, 1) for a point.
pub fn opening_grid(a_m: f32, b_m: f32) -> (u32, u32) {
    if a_m <= 0.0 && b_m <= 0.0 {
        return (1, 1);
    }
    let ratio = (a_m.max(1e-6) / b_m.max(1e-6)).ln();
    let mut best = (4, 4);
    let mut best_err = f32::MAX;
    let mut na = 1;
    while na <= MAX_OPENING_POINTS {
        let nb = MAX_OPENING_POINTS / na;
        let err = ((na as f32 / nb as f32).ln() - ratio).abs();
        if err < best_err {
            best = (na, nb);
            best_err = err;
        }
        na *= 2;
    }
    best
}

/// A luminaire placed in the world, as the pass lights with it.
#[derive(Debug, Clone, Copy)]
pub struct PlacedLight<'a> {
    /// Its photometry.
    pub photometry: &'a Photometry,
    /// Luminaire frame → world.
    pub model: Mat4,
    /// Its intensity table's index in the atlas.
    pub table: u32,
    /// The largest intensity of its table, cd.
    pub max_cd: f32,
}

/// The record of luminaire number `index` (its shadow faces start at `6 · index`).
pub fn light_record(light: &PlacedLight<'_>, index: usize, lux_floor_lx: f32) -> LightRecord {
    let m = light.model;
    let centre = m.transform_point3(Vec3::ZERO);
    let local_from_world = Mat3::from_mat4(m).inverse();
    let (a, b, ellipse) = opening_axes(light.photometry);
    let (a, b) = (m.transform_vector3(a), m.transform_vector3(b));
    let (na, nb) = opening_grid(a.length(), b.length());
    let radius = (light.max_cd.max(0.0) / lux_floor_lx).sqrt() + a.length() + b.length();
    let row = |i: usize| -> [f32; 4] {
        let r = local_from_world.row(i);
        [r.x, r.y, r.z, 0.0]
    };
    LightRecord {
        centre: [centre.x, centre.y, centre.z, radius],
        local_x: row(0),
        local_y: row(1),
        local_z: row(2),
        axis_a: [a.x, a.y, a.z, na as f32],
        axis_b: [b.x, b.y, b.z, nb as f32],
        tables: [light.table, 6 * index as u32, u32::from(ellipse), 0],
    }
}

/// The per-tile lists: `2 · tiles` words of (first, count) pairs, then the indices they point at.
pub fn tile_lists(clip_from_world: Mat4, width: u32, height: u32, lights: &[LightRecord]) -> (u32, u32, Vec<u32>) {
    let tiles_x = width.div_ceil(TILE_PX);
    let tiles_y = height.div_ceil(TILE_PX);
    let mut per_tile: Vec<Vec<u32>> = vec![Vec::new(); (tiles_x * tiles_y) as usize];
    for (i, l) in lights.iter().enumerate() {
        let c = Vec3::new(l.centre[0], l.centre[1], l.centre[2]);
        let r = l.centre[3];
        let Some((x0, y0, x1, y1)) = screen_rect(clip_from_world, c, r) else {
            continue;
        };
        let px = |v: f32, n: u32| -> f32 { v.clamp(0.0, n as f32 - 1e-3) };
        let (tx0, tx1) = (
            (px((x0 * 0.5 + 0.5) * width as f32, width) as u32) / TILE_PX,
            (px((x1 * 0.5 + 0.5) * width as f32, width) as u32) / TILE_PX,
        );
        let (ty0, ty1) = (
            (px((0.5 - y1 * 0.5) * height as f32, height) as u32) / TILE_PX,
            (px((0.5 - y0 * 0.5) * height as f32, height) as u32) / TILE_PX,
        );
        for ty in ty0..=ty1.min(tiles_y - 1) {
            for tx in tx0..=tx1.min(tiles_x - 1) {
                per_tile[(ty * tiles_x + tx) as usize].push(i as u32);
            }
        }
    }
    let header = 2 * per_tile.len();
    let mut words = vec![0u32; header];
    for (t, list) in per_tile.iter().enumerate() {
        words[2 * t] = words.len() as u32;
        words[2 * t + 1] = list.len() as u32;
        words.extend_from_slice(list);
    }
    (tiles_x, tiles_y, words)
}

/// The NDC rectangle (x0, y0, x1, y1) of the sphere, clipped to the screen; the whole screen when a
/// corner of its bounding box lies behind the eye; `None` when it is off screen.
fn screen_rect(clip_from_world: Mat4, c: Vec3, r: f32) -> Option<(f32, f32, f32, f32)> {
    let (mut x0, mut y0, mut x1, mut y1) = (f32::MAX, f32::MAX, f32::MIN, f32::MIN);
    for k in 0..8 {
        let o = Vec3::new(
            if k & 1 == 0 { -r } else { r },
            if k & 2 == 0 { -r } else { r },
            if k & 4 == 0 { -r } else { r },
        );
        let p: Vec4 = clip_from_world * (c + o).extend(1.0);
        if p.w.is_nan() || p.w <= 1e-6 {
            return Some((-1.0, -1.0, 1.0, 1.0));
        }
        let (x, y) = (p.x / p.w, p.y / p.w);
        x0 = x0.min(x);
        y0 = y0.min(y);
        x1 = x1.max(x);
        y1 = y1.max(y);
    }
    if x1 < -1.0 || y1 < -1.0 || x0 > 1.0 || y0 > 1.0 {
        return None;
    }
    Some((x0.max(-1.0), y0.max(-1.0), x1.min(1.0), y1.min(1.0)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn opening_grids_follow_the_aspect_ratio() {
        assert_eq!(opening_grid(0.0, 0.0), (1, 1));
        assert_eq!(opening_grid(0.6, 0.05), (16, 1));
        assert_eq!(opening_grid(0.2, 0.2), (4, 4));
        assert_eq!(opening_grid(0.1, 0.4), (2, 8));
    }

    #[test]
    fn tiles_list_the_lights_whose_sphere_they_touch() {
        // An orthographic top view of x, z in ±4 m on 64 × 64 px (4 × 4 tiles of 2 m).
        // NDC x = x/4, NDC y = −z/4 (looking down −Y, image up −Z).
        let clip = Mat4::from_cols(
            Vec4::new(0.25, 0.0, 0.0, 0.0),
            Vec4::new(0.0, 0.0, -0.05, 0.0),
            Vec4::new(0.0, -0.25, 0.0, 0.0),
            Vec4::new(0.0, 0.0, 0.5, 1.0),
        );
        let rec = |x: f32, z: f32, r: f32| LightRecord {
            centre: [x, 2.0, z, r],
            ..bytemuck::Zeroable::zeroed()
        };
        let (tx, ty, w) = tile_lists(
            clip,
            64,
            64,
            &[rec(-3.0, -3.0, 0.5), rec(0.0, 0.0, 100.0), rec(50.0, 0.0, 1.0)],
        );
        assert_eq!((tx, ty), (4, 4));
        let list = |t: usize| &w[w[2 * t] as usize..(w[2 * t] + w[2 * t + 1]) as usize];
        assert_eq!(list(0), &[0, 1], "top-left tile: the small light and the big one");
        assert_eq!(
            list(15),
            &[1],
            "bottom-right tile: the big one only; the far one nowhere"
        );
    }
}
