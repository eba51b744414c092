//! The host's camera: view and projection matrices in the host's conventions, turned into wgpu clip
//! space so that the depth we write equals what the host's own depth buffer would hold.
//!
//! - `view` maps world → eye, `projection` eye → the host's clip space; both column-major like glm/GL.
//! - GL hosts (`DepthRange::NegOneToOne`) produce clip z in −w…w; wgpu clips to 0…w, so we use
//!   z' = (z + w)/2. The window depth wgpu then stores is (z_ndc + 1)/2, exactly GL's default
//!   `glDepthRange(0, 1)` window depth. Zero-to-one hosts pass through unchanged.
//! - Reversed-Z (near = 1, far = 0) only changes the depth test (GREATER) and the clear value (0).
//! - `Origin::BottomLeft` (GL's convention) flips clip y so that memory row 0 holds the bottom row
//!   of the image, as a GL texture's t = 0 row; `Origin::TopLeft` (Vulkan/D3D) puts the top row first.

use glam::{Mat4, Vec3, Vec4};

use super::{Arg, GpuError};

/// The host's clip-space depth range.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DepthRange {
    /// OpenGL: z_ndc in −1…1.
    NegOneToOne,
    /// Vulkan / D3D / `glClipControl(.., GL_ZERO_TO_ONE)`: z_ndc in 0…1.
    ZeroToOne,
}

/// Which image row the host treats as the first row in memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Origin {
    /// Memory row 0 is the top row (Vulkan, D3D, most image files).
    TopLeft,
    /// Memory row 0 is the bottom row (OpenGL textures and framebuffers).
    BottomLeft,
}

/// A camera as the host gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HostCamera {
    /// World → eye.
    pub view: Mat4,
    /// Eye → host clip space.
    pub projection: Mat4,
    /// The host's depth range.
    pub depth_range: DepthRange,
    /// Near maps to 1 and far to 0 (the depth test becomes GREATER).
    pub reversed_z: bool,
    /// Framebuffer origin.
    pub origin: Origin,
}

impl HostCamera {
    /// Checks the matrices (finite, invertible).
    pub fn validate(&self) -> Result<(), GpuError> {
        for (name, m) in [(Arg::View, self.view), (Arg::Projection, self.projection)] {
            if !m.is_finite() {
                return Err(GpuError::invalid(name, "matrix has a NaN or infinite element"));
            }
            let det = m.determinant();
            if !det.is_finite() || det.abs() < 1e-30 {
                return Err(GpuError::invalid(name, "matrix is singular"));
            }
        }
        Ok(())
    }

    /// The matrix from the host's clip space to wgpu's (depth-range remap and origin flip).
    pub fn clip_fixup(&self) -> Mat4 {
        let mut m = Mat4::IDENTITY;
        if self.depth_range == DepthRange::NegOneToOne {
            // z' = 0.5 z + 0.5 w
            m.z_axis = Vec4::new(0.0, 0.0, 0.5, 0.0);
            m.w_axis = Vec4::new(0.0, 0.0, 0.5, 1.0);
        }
        if self.origin == Origin::BottomLeft {
            m = Mat4::from_scale(Vec3::new(1.0, -1.0, 1.0)) * m;
        }
        m
    }

    /// wgpu clip space from world space.
    pub fn clip_from_world(&self) -> Mat4 {
        self.clip_fixup() * self.projection * self.view
    }

    /// True for an orthographic projection (the last row is (0, 0, 0, 1)).
    pub fn is_orthographic(&self) -> bool {
        let r = self.projection.row(3);
        r.x == 0.0 && r.y == 0.0 && r.z == 0.0
    }

    /// The eye in a frame whose transform to world is `model`: a point (w = 1) for perspective, the
    /// unit direction towards the eye (w = 0) for orthographic projections.
    pub fn eye_in(&self, model: Mat4) -> Vec4 {
        let local_from_eye = (self.view * model).inverse();
        if self.is_orthographic() {
            // The eye looks down −Z in eye space; the direction towards the eye is +Z.
            let d = local_from_eye.transform_vector3(Vec3::Z).normalize_or_zero();
            d.extend(0.0)
        } else {
            local_from_eye.transform_point3(Vec3::ZERO).extend(1.0)
        }
    }

    /// Whether drawing in a frame whose transform to world is `model` reverses the screen winding
    /// of triangles, compared with an unmirrored view: a triangle counter-clockwise as seen from the
    /// eye is then clockwise in wgpu's NDC. A y-flipping `Origin::BottomLeft`, a mirrored model or
    /// view (negative determinant) and a mirrored projection each reverse it; two reversals cancel.
    /// Hardware face culling must swap front and back when this is true.
    ///
    /// From the rows of the clip-from-local matrix (f64): near a point that projects to the
    /// image's centre, NDC (x, y) changes with a local offset δ as (r_x·δ, r_y·δ)/w, so a small
    /// triangle with normal m covers the signed area (r_x × r_y)·m / w² (times its own area): the
    /// winding is reversed where (r_x × r_y) points away from the eye. Perspective: the eye is a
    /// point and r_x × r_y lies along the central ray, parallel to (eye − p₀) for p₀ on that ray,
    /// so the sign is robust at any distance. Orthographic: depth grows away from the eye along
    /// r_z (unless `reversed_z`), so the winding is reversed where det[r_x; r_y; r_z] > 0.
    pub fn mirrors_winding(&self, model: Mat4) -> bool {
        self.mirrors_winding_of(model, self.clip_from_world() * model)
    }

    /// [`HostCamera::mirrors_winding`] for a draw whose clip-from-local matrix
    /// (`clip_from_world() · model`) the caller has already computed.
    pub fn mirrors_winding_of(&self, model: Mat4, clip_from_local: Mat4) -> bool {
        let c = clip_from_local.as_dmat4();
        let row = |i: usize| glam::DVec3::new(c.x_axis[i], c.y_axis[i], c.z_axis[i]);
        let (rx, ry, rz) = (row(0), row(1), row(2));
        let n = rx.cross(ry);
        if self.is_orthographic() {
            return (n.dot(rz) > 0.0) != self.reversed_z;
        }
        let eye = (self.view * model)
            .as_dmat4()
            .inverse()
            .transform_point3(glam::DVec3::ZERO);
        let p0 = c.inverse().project_point3(glam::DVec3::new(0.0, 0.0, 0.5));
        n.dot(eye - p0) < 0.0
    }

    /// The camera of a pinhole view given like a capture camera (position, OpenCV basis right /
    /// down / forward, intrinsics in pixels; luminaire frame = world), as a GL-convention host
    /// camera with a top-left origin, so that target row 0 is image row 0 and pixel (u, v) of the
    /// intrinsics is target pixel (u, v). Depth range `near_m`…`far_m`. The matrices:
    /// [`crate::nearfield::select::view::pinhole_view_projection`].
    pub fn from_pinhole(
        cam: &crate::nearfield::Camera,
        k: &crate::nearfield::Intrinsics,
        near_m: f32,
        far_m: f32,
    ) -> Self {
        let (view, projection) = crate::nearfield::select::view::pinhole_view_projection(cam, k, near_m, far_m);
        Self::gl_top_left(view, projection)
    }

    /// A GL-convention camera (clip z in −w…w, no reversed Z) with a top-left origin.
    fn gl_top_left(view: Mat4, projection: Mat4) -> Self {
        HostCamera {
            view,
            projection,
            depth_range: DepthRange::NegOneToOne,
            reversed_z: false,
            origin: Origin::TopLeft,
        }
    }

    /// An orthographic view like `synth::OrthoView`: looking along −`direction` at `centre_m`,
    /// `pixel_m` metres per pixel, `width` × `height` pixels, image axes from
    /// `rayset::look_at_basis(−direction)` (row 0 at the top), depth `±depth_m` around the centre;
    /// GL conventions and a top-left origin as [`HostCamera::from_pinhole`]. The matrices:
    /// [`crate::nearfield::select::view::ortho_view_projection`].
    pub fn from_ortho(
        direction: glam::DVec3,
        centre_m: glam::DVec3,
        pixel_m: f64,
        width: u32,
        height: u32,
        depth_m: f64,
    ) -> Self {
        let (view, projection) =
            crate::nearfield::select::view::ortho_view_projection(direction, centre_m, pixel_m, width, height, depth_m);
        Self::gl_top_left(view, projection)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gl_depth_becomes_gl_window_depth() {
        let f = 1.0 / 0.5f32.tan();
        let proj = Mat4::from_cols(
            Vec4::new(f, 0.0, 0.0, 0.0),
            Vec4::new(0.0, f, 0.0, 0.0),
            Vec4::new(0.0, 0.0, -10.1 / 9.9, -1.0),
            Vec4::new(0.0, 0.0, -2.0 / 9.9, 0.0),
        );
        let cam = HostCamera {
            view: Mat4::IDENTITY,
            projection: proj,
            depth_range: DepthRange::NegOneToOne,
            reversed_z: false,
            origin: Origin::BottomLeft,
        };
        let p = Vec4::new(0.3, 0.2, -2.0, 1.0);
        let gl = proj * p;
        let gl_window = 0.5 * gl.z / gl.w + 0.5;
        let ours = cam.clip_from_world() * p;
        assert!((ours.z / ours.w - gl_window).abs() < 1e-6);
        assert!(
            (ours.y / ours.w + gl.y / gl.w).abs() < 1e-6,
            "bottom-left origin flips y"
        );
        assert_eq!(cam.eye_in(Mat4::IDENTITY), Vec4::new(0.0, 0.0, 0.0, 1.0));
        let ortho = HostCamera {
            projection: Mat4::from_scale(Vec3::new(1.0, 1.0, -0.2)),
            ..cam
        };
        assert_eq!(ortho.eye_in(Mat4::IDENTITY), Vec4::new(0.0, 0.0, 1.0, 0.0));
    }

    /// A right-handed (`lh` false: looking down eye −Z) or left-handed (eye +Z) look-at view.
    fn look_at(eye: Vec3, target: Vec3, up: Vec3, lh: bool) -> Mat4 {
        let f = (target - eye).normalize();
        let (s, z) = if lh {
            (up.cross(f).normalize(), f)
        } else {
            (f.cross(up).normalize(), -f)
        };
        let u = z.cross(s);
        Mat4::from_cols(
            Vec4::new(s.x, u.x, z.x, 0.0),
            Vec4::new(s.y, u.y, z.y, 0.0),
            Vec4::new(s.z, u.z, z.z, 0.0),
            Vec4::new(-s.dot(eye), -u.dot(eye), -z.dot(eye), 1.0),
        )
    }

    /// Perspective projections: GL (right-handed, clip z −w…w), Vulkan (right-handed, 0…w) and
    /// D3D-style left-handed (0…w), fovy 1 rad, aspect 1.5, 0.1…100 m.
    fn perspective(kind: &str) -> Mat4 {
        let (f, a, n, far) = (1.0 / 0.5f32.tan(), 1.5f32, 0.1f32, 100.0f32);
        let (z, w) = match kind {
            "gl" => (
                Vec4::new(0.0, 0.0, (far + n) / (n - far), -1.0),
                Vec4::new(0.0, 0.0, 2.0 * far * n / (n - far), 0.0),
            ),
            "vk" => (
                Vec4::new(0.0, 0.0, far / (n - far), -1.0),
                Vec4::new(0.0, 0.0, n * far / (n - far), 0.0),
            ),
            _ => (
                Vec4::new(0.0, 0.0, far / (far - n), 1.0),
                Vec4::new(0.0, 0.0, -n * far / (far - n), 0.0),
            ),
        };
        Mat4::from_cols(Vec4::new(f / a, 0.0, 0.0, 0.0), Vec4::new(0.0, f, 0.0, 0.0), z, w)
    }

    /// A GL perspective camera at `eye` looking at the origin (+Z up).
    fn looking_at_origin(eye: Vec3, origin: Origin, depth_range: DepthRange) -> HostCamera {
        HostCamera {
            view: look_at(eye, Vec3::ZERO, Vec3::Z, false),
            projection: perspective("gl"),
            depth_range,
            reversed_z: false,
            origin,
        }
    }

    #[test]
    fn winding_reverses_with_each_mirror_and_not_with_two() {
        let mirror_x = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        for eye in [
            Vec3::new(0.3, -0.4, -2.0),
            Vec3::new(0.05, 0.02, 0.03),
            Vec3::new(3.0, 1.0, 0.5),
        ] {
            let gl_top = looking_at_origin(eye, Origin::TopLeft, DepthRange::NegOneToOne);
            let gl_bottom = HostCamera {
                origin: Origin::BottomLeft,
                ..gl_top
            };
            assert!(!gl_top.mirrors_winding(Mat4::IDENTITY), "eye {eye}");
            assert!(
                gl_bottom.mirrors_winding(Mat4::IDENTITY),
                "eye {eye}: BottomLeft flips y"
            );
            assert!(gl_top.mirrors_winding(mirror_x), "eye {eye}: a mirrored model");
            assert!(!gl_bottom.mirrors_winding(mirror_x), "eye {eye}: two mirrors cancel");
            // A Vulkan host's y-flipped 0…1 projection: upside down with TopLeft (mirrored), the
            // right way up with BottomLeft, whose flip undoes it (docs/ffi-conventions.md).
            let mut vk = perspective("vk");
            vk.y_axis.y = -vk.y_axis.y;
            let vk_top = HostCamera {
                projection: vk,
                depth_range: DepthRange::ZeroToOne,
                ..gl_top
            };
            let vk_bottom = HostCamera {
                origin: Origin::BottomLeft,
                ..vk_top
            };
            assert!(vk_top.mirrors_winding(Mat4::IDENTITY), "eye {eye}");
            assert!(!vk_bottom.mirrors_winding(Mat4::IDENTITY), "eye {eye}");
            let (a, b) = (vk_bottom.clip_from_world(), {
                let mut unflipped = vk;
                unflipped.y_axis.y = -unflipped.y_axis.y;
                HostCamera {
                    projection: unflipped,
                    ..vk_top
                }
                .clip_from_world()
            });
            assert!(a.abs_diff_eq(b, 1e-6), "flipped + BottomLeft = unflipped + TopLeft");
            // A left-handed view and projection (D3D's LookAtLH and PerspectiveFovLH) on the
            // right-handed luminaire frame: the image is a mirror image (eye x points left).
            let lh = HostCamera {
                view: look_at(eye, Vec3::ZERO, Vec3::Z, true),
                projection: perspective("lh"),
                depth_range: DepthRange::ZeroToOne,
                ..gl_top
            };
            assert!(
                lh.mirrors_winding(Mat4::IDENTITY),
                "eye {eye}: left-handed view + projection"
            );
            assert!(
                !HostCamera {
                    origin: Origin::BottomLeft,
                    ..lh
                }
                .mirrors_winding(Mat4::IDENTITY),
                "eye {eye}: left-handed, flipped back by BottomLeft"
            );
            // Orthographic.
            let ortho = HostCamera {
                projection: Mat4::from_cols(
                    Vec4::X,
                    Vec4::Y,
                    Vec4::new(0.0, 0.0, -2.0 / 9.9, 0.0),
                    Vec4::new(0.0, 0.0, -10.1 / 9.9, 1.0),
                ),
                ..gl_top
            };
            assert!(!ortho.mirrors_winding(Mat4::IDENTITY), "eye {eye}: orthographic");
            assert!(
                HostCamera {
                    origin: Origin::BottomLeft,
                    ..ortho
                }
                .mirrors_winding(Mat4::IDENTITY),
                "eye {eye}: orthographic, BottomLeft"
            );
        }
    }

    #[test]
    fn winding_holds_far_away_and_for_a_left_handed_orthographic_camera() {
        // 170 m away with a 1 cm near plane (f32 rounding made a measured triangle vanish there).
        let eye = Vec3::new(120.0, -90.0, -80.0);
        let n = 0.01f32;
        let (f, far) = (1.0 / 0.5f32.tan(), 1000.0f32);
        let projection = Mat4::from_cols(
            Vec4::new(f / 1.5, 0.0, 0.0, 0.0),
            Vec4::new(0.0, f, 0.0, 0.0),
            Vec4::new(0.0, 0.0, (far + n) / (n - far), -1.0),
            Vec4::new(0.0, 0.0, 2.0 * far * n / (n - far), 0.0),
        );
        let top = HostCamera {
            view: look_at(eye, Vec3::ZERO, Vec3::Z, false),
            projection,
            depth_range: DepthRange::NegOneToOne,
            reversed_z: false,
            origin: Origin::TopLeft,
        };
        assert!(!top.mirrors_winding(Mat4::IDENTITY));
        assert!(HostCamera {
            origin: Origin::BottomLeft,
            ..top
        }
        .mirrors_winding(Mat4::IDENTITY));
        // A left-handed orthographic camera (looking down eye +Z, depth 0…1): mirrored on the
        // right-handed luminaire frame, like the left-handed perspective one.
        let lh_ortho = HostCamera {
            view: look_at(Vec3::new(0.3, -0.4, -2.0), Vec3::ZERO, Vec3::Z, true),
            projection: Mat4::from_cols(
                Vec4::X,
                Vec4::Y,
                Vec4::new(0.0, 0.0, 1.0 / 9.9, 0.0),
                Vec4::new(0.0, 0.0, -0.1 / 9.9, 1.0),
            ),
            depth_range: DepthRange::ZeroToOne,
            reversed_z: false,
            origin: Origin::TopLeft,
        };
        assert!(lh_ortho.mirrors_winding(Mat4::IDENTITY));
        // Reversed Z flips which way depth grows, not the image.
        let rh_ortho_reversed = HostCamera {
            view: look_at(Vec3::new(0.3, -0.4, -2.0), Vec3::ZERO, Vec3::Z, false),
            projection: Mat4::from_cols(
                Vec4::X,
                Vec4::Y,
                Vec4::new(0.0, 0.0, 1.0 / 9.9, 0.0),
                Vec4::new(0.0, 0.0, 10.0 / 9.9, 1.0),
            ),
            depth_range: DepthRange::ZeroToOne,
            reversed_z: true,
            origin: Origin::TopLeft,
        };
        assert!(!rh_ortho_reversed.mirrors_winding(Mat4::IDENTITY));
    }

    #[test]
    fn clip_y_up_is_image_up_for_both_origins() {
        // A point above the view axis (eye-space +y) lands in the upper half of the image: NDC y > 0
        // in wgpu (row 0 at the top) with TopLeft, and mirrored into the rows near the bottom of
        // memory order with BottomLeft (NDC y < 0 in wgpu's clip space, row height − 1 side).
        let cam = looking_at_origin(Vec3::new(0.0, -3.0, 0.0), Origin::TopLeft, DepthRange::NegOneToOne);
        let above = cam.clip_from_world() * Vec4::new(0.0, 0.0, 0.5, 1.0); // world +Z is eye +y here
        assert!(above.y / above.w > 0.1, "{above}");
        let bottom = HostCamera {
            origin: Origin::BottomLeft,
            ..cam
        };
        let b = bottom.clip_from_world() * Vec4::new(0.0, 0.0, 0.5, 1.0);
        assert!(b.y / b.w < -0.1, "{b}");
    }
}
