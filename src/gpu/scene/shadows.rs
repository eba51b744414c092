//! Shadow maps of the scene pass: one cube per luminaire, its six faces squares of one shadow atlas
//! (a single `Depth32Float` texture, so no binding array is needed), rendered from the photometric
//! centre.
//!
//! Promises:
//! - Face `f` of luminaire `i` is atlas tile `6 i + f`, at column `tile % per_row`, row
//!   `tile / per_row`, `face_px` square; the faces follow [`CUBE_FORWARD`] (+X, −X, +Y, −Y, +Z, −Z)
//!   with the image axes [`CUBE_RIGHT`] and [`CUBE_UP`] (row 0 at the top). The shader gets these
//!   three tables as generated constants (`gpu::shaders`), so both sides use one definition.
//! - A face maps v = p − centre to clip (right·v, up·v, [`SHADOW_NEAR_M`], forward·v): a 90° square
//!   frustum with its near plane at [`SHADOW_NEAR_M`] and no far plane, depth
//!   `SHADOW_NEAR_M / (forward·v)` (reversed: nearer is greater, cleared to 0 = nothing).
//! - The layout fits the budget: the atlas is at most `budget_bytes` (4 bytes a texel) and at most
//!   the device's largest texture side (capped at 8192); the face size is the largest power of two
//!   up to `max_face_px` for which every face fits. A layout whose faces would be smaller than
//!   [`MIN_FACE_PX`] is an error naming the budget.

use glam::{Mat4, Vec3, Vec4};

use super::super::{Arg, GpuError};

/// The near plane of every shadow-map face, metres from the photometric centre: scene surfaces
/// nearer than this to a luminaire's centre cast no shadow.
pub const SHADOW_NEAR_M: f32 = 0.01;

/// A texel occludes when its surface is nearer than the receiver plane by more than this share of
/// the plane's distance along the texel's ray (depth and interpolation round-off).
pub const SHADOW_RELATIVE_BIAS: f32 = 2e-3;

/// A texel occludes a point b on a segment towards the opening when its surface lies nearer to the
/// centre than (1 + this)·|b − centre|: at b or at most this share behind it (surfaces far behind b
/// are not between b and the opening).
pub const SHADOW_REACH: f32 = 0.25;

/// The faces' axes (looking direction), in face order.
pub const CUBE_FORWARD: [Vec3; 6] = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
/// The faces' image right (+x in normalised device coordinates).
pub const CUBE_RIGHT: [Vec3; 6] = [Vec3::NEG_Z, Vec3::Z, Vec3::X, Vec3::X, Vec3::X, Vec3::NEG_X];
/// The faces' image up (+y in normalised device coordinates; image row 0 at the top).
pub const CUBE_UP: [Vec3; 6] = [Vec3::Y, Vec3::Y, Vec3::NEG_Z, Vec3::Z, Vec3::Y, Vec3::Y];

/// The smallest face size a layout may use, pixels.
pub const MIN_FACE_PX: u32 = 16;

/// Largest atlas side (pixels) used even where the device allows more.
pub const MAX_ATLAS_SIDE: u32 = 8192;

/// Where each luminaire's six faces lie in the shadow atlas.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ShadowLayout {
    /// Face side, pixels.
    pub face_px: u32,
    /// Faces per atlas row.
    pub per_row: u32,
    /// Atlas width, pixels.
    pub width: u32,
    /// Atlas height, pixels.
    pub height: u32,
}

impl ShadowLayout {
    /// The layout for `lights` luminaires within `budget_bytes` (4 bytes a texel), faces of at most
    /// `max_face_px`, an atlas side of at most `max_side` pixels.
    ///
    /// Errors: `InvalidArgument` (`Arg::BudgetBytes`) when the faces would be smaller than
    /// [`MIN_FACE_PX`].
    pub fn new(lights: usize, budget_bytes: u64, max_face_px: u32, max_side: u32) -> Result<Self, GpuError> {
        let faces = 6 * lights.max(1) as u64;
        let side_budget = ((budget_bytes / 4) as f64).sqrt() as u64;
        let side = side_budget.min(max_side.min(MAX_ATLAS_SIDE) as u64);
        let mut face = max_face_px.max(1).next_power_of_two();
        if face > max_face_px {
            face /= 2;
        }
        while face >= MIN_FACE_PX {
            let per_row = side / face as u64;
            if per_row > 0 && per_row * per_row >= faces {
                let rows = faces.div_ceil(per_row);
                return Ok(ShadowLayout {
                    face_px: face,
                    per_row: per_row.min(faces) as u32,
                    width: (per_row.min(faces) * face as u64) as u32,
                    height: (rows * face as u64) as u32,
                });
            }
            face /= 2;
        }
        Err(GpuError::invalid(
            Arg::BudgetBytes,
            format!(
                "{budget_bytes} bytes of shadow atlas (side ≤ {side} px) cannot hold {faces} cube faces of at least \
                 {MIN_FACE_PX} px: raise the budget or light the scene with fewer luminaires"
            ),
        ))
    }

    /// The top-left pixel of face `face` of luminaire `light`.
    pub fn face_origin(&self, light: usize, face: usize) -> (u32, u32) {
        let tile = (6 * light + face) as u32;
        (
            (tile % self.per_row) * self.face_px,
            (tile / self.per_row) * self.face_px,
        )
    }
}

/// World → wgpu clip space of cube face `face` around `centre` (see the module's promises).
pub fn face_clip_from_world(centre: Vec3, face: usize) -> Mat4 {
    let (f, r, u) = (CUBE_FORWARD[face], CUBE_RIGHT[face], CUBE_UP[face]);
    let rows = [
        r.extend(-r.dot(centre)),
        u.extend(-u.dot(centre)),
        Vec4::new(0.0, 0.0, 0.0, SHADOW_NEAR_M),
        f.extend(-f.dot(centre)),
    ];
    Mat4::from_cols(rows[0], rows[1], rows[2], rows[3]).transpose()
}

/// The face a direction falls on (as the shader's `cube_face`).
pub fn cube_face(d: Vec3) -> usize {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        if d.x >= 0.0 {
            0
        } else {
            1
        }
    } else if a.y >= a.z {
        if d.y >= 0.0 {
            2
        } else {
            3
        }
    } else if d.z >= 0.0 {
        4
    } else {
        5
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faces_are_right_handed_orthonormal_and_cover_their_directions() {
        for f in 0..6 {
            let (fw, r, u) = (CUBE_FORWARD[f], CUBE_RIGHT[f], CUBE_UP[f]);
            assert!(fw.dot(r).abs() < 1e-6 && fw.dot(u).abs() < 1e-6 && r.dot(u).abs() < 1e-6);
            assert_eq!(cube_face(fw), f);
            // A direction inside the face's frustum lands inside its square, at depth near/axis.
            let c = Vec3::new(0.5, 2.0, -1.0);
            let p = c + 3.0 * fw + 1.2 * r - 0.7 * u;
            let clip = face_clip_from_world(c, f) * p.extend(1.0);
            let ndc = clip.truncate() / clip.w;
            assert!(
                (ndc.x - 0.4).abs() < 1e-5 && (ndc.y + 0.7 / 3.0).abs() < 1e-5,
                "{f}: {ndc}"
            );
            assert!((ndc.z - SHADOW_NEAR_M / 3.0).abs() < 1e-7);
        }
    }

    #[test]
    fn layouts_fit_the_budget_and_shrink_faces_for_many_lights() {
        let l = ShadowLayout::new(6, 64 << 20, 512, 16384).unwrap();
        assert_eq!((l.face_px, l.per_row), (512, 8));
        assert_eq!((l.width, l.height), (4096, 5 * 512));
        let l = ShadowLayout::new(256, 64 << 20, 512, 16384).unwrap();
        assert_eq!(l.face_px, 64);
        assert!(u64::from(l.width) * u64::from(l.height) * 4 <= 64 << 20);
        assert!(u64::from(l.per_row) * u64::from(l.height / l.face_px) >= 6 * 256);
        assert_eq!(l.face_origin(1, 2), (8 * 64, 0));
        let e = ShadowLayout::new(100_000, 1 << 20, 512, 16384).unwrap_err();
        assert!(e.to_string().contains("budget_bytes"), "{e}");
    }
}
