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

use super::GpuError;

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
        for (name, m) in [("view", self.view), ("projection", self.projection)] {
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

    /// The camera of a pinhole view given like a capture camera (position, OpenCV basis right /
    /// down / forward, intrinsics in pixels; luminaire frame = world), as a GL-convention host
    /// camera with a top-left origin, so that target row 0 is image row 0 and pixel (u, v) of the
    /// intrinsics is target pixel (u, v). Depth range `near_m`…`far_m`.
    pub fn from_pinhole(
        cam: &crate::nearfield::Camera,
        k: &crate::nearfield::Intrinsics,
        near_m: f32,
        far_m: f32,
    ) -> Self {
        let (r, d, f) = (cam.right.as_vec3(), cam.down.as_vec3(), cam.forward.as_vec3());
        let e = cam.position_m.as_vec3();
        let up = -d;
        // Eye space: x = right, y = up, z = −forward.
        let view = Mat4::from_cols(
            Vec4::new(r.x, up.x, -f.x, 0.0),
            Vec4::new(r.y, up.y, -f.y, 0.0),
            Vec4::new(r.z, up.z, -f.z, 0.0),
            Vec4::new(-r.dot(e), -up.dot(e), f.dot(e), 1.0),
        );
        let (w, h) = (k.width as f32, k.height as f32);
        let (fx, fy) = (k.focal_px.x as f32, k.focal_px.y as f32);
        let (cx, cy) = (k.principal_px.x as f32, k.principal_px.y as f32);
        let projection = Mat4::from_cols(
            Vec4::new(2.0 * fx / w, 0.0, 0.0, 0.0),
            Vec4::new(0.0, 2.0 * fy / h, 0.0, 0.0),
            Vec4::new(
                1.0 - 2.0 * cx / w,
                2.0 * cy / h - 1.0,
                (far_m + near_m) / (near_m - far_m),
                -1.0,
            ),
            Vec4::new(0.0, 0.0, 2.0 * far_m * near_m / (near_m - far_m), 0.0),
        );
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
    /// `rayset::look_at_basis(−direction)` (row 0 at the top), depth `±depth_m` around the centre.
    pub fn from_ortho(
        direction: glam::DVec3,
        centre_m: glam::DVec3,
        pixel_m: f64,
        width: u32,
        height: u32,
        depth_m: f64,
    ) -> Self {
        let (right, down, forward) = crate::nearfield::rayset::look_at_basis(-direction);
        let eye = centre_m - forward * (depth_m + 1.0);
        let cam = crate::nearfield::Camera {
            position_m: eye,
            right,
            down,
            forward,
            intrinsics: None,
            hemisphere: crate::nearfield::Hemisphere::Lower,
            meta: Default::default(),
            label: String::new(),
        };
        let k = crate::nearfield::Intrinsics {
            width,
            height,
            principal_px: glam::DVec2::new(f64::from(width) / 2.0, f64::from(height) / 2.0),
            focal_px: glam::DVec2::ONE,
        };
        let mut c = Self::from_pinhole(&cam, &k, 1.0, 2.0);
        let (hw, hh) = (0.5 * f64::from(width) * pixel_m, 0.5 * f64::from(height) * pixel_m);
        let (n, f) = (1.0f64, 1.0 + 2.0 * depth_m);
        c.projection = Mat4::from_cols(
            Vec4::new((1.0 / hw) as f32, 0.0, 0.0, 0.0),
            Vec4::new(0.0, (1.0 / hh) as f32, 0.0, 0.0),
            Vec4::new(0.0, 0.0, (-2.0 / (f - n)) as f32, 0.0),
            Vec4::new(0.0, 0.0, (-(f + n) / (f - n)) as f32, 1.0),
        );
        c
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
}
