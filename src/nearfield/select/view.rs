//! The geometry of a view of a scan, on the CPU (the near-field pass uses it to cull and to make
//! tiles resident): the content ball around the capture centre holding everything the cameras saw
//! ([`content_radius_m`]), the cells of the selection grid that a view's lines through that ball
//! reach on the capture sphere ([`view_cells`]), and the GL-convention view and projection matrices
//! of a camera given like a capture camera ([`pinhole_view_projection`], [`ortho_view_projection`]).

use glam::{DVec3, Mat4, Vec4};

use super::Selection;
use crate::nearfield::pack::Pack;
use crate::nearfield::{Camera, Hemisphere, Intrinsics};

/// The view (world → eye: x = right, y = up, z = −forward) and GL projection (eye → clip, clip z
/// in −w…w, `near_m`…`far_m`) of a pinhole camera given like a capture camera (position, OpenCV
/// basis right / down / forward, intrinsics in pixels; luminaire frame = world), such that with a
/// top-left origin target row 0 is image row 0 and pixel (u, v) of the intrinsics is target pixel
/// (u, v).
pub fn pinhole_view_projection(cam: &Camera, k: &Intrinsics, near_m: f32, far_m: f32) -> (Mat4, Mat4) {
    let (r, d, f) = (cam.right.as_vec3(), cam.down.as_vec3(), cam.forward.as_vec3());
    let e = cam.position_m.as_vec3();
    let up = -d;
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
    (view, projection)
}

/// The view and GL orthographic projection of a view like `synth::OrthoView`: looking along
/// −`direction` at `centre_m`, `pixel_m` metres per pixel, `width` × `height` pixels, image axes
/// from `rayset::look_at_basis(−direction)` (row 0 at the top with a top-left origin), depth
/// `±depth_m` around the centre.
pub fn ortho_view_projection(
    direction: DVec3,
    centre_m: DVec3,
    pixel_m: f64,
    width: u32,
    height: u32,
    depth_m: f64,
) -> (Mat4, Mat4) {
    let (right, down, forward) = crate::nearfield::rayset::look_at_basis(-direction);
    let eye = centre_m - forward * (depth_m + 1.0);
    let cam = Camera {
        position_m: eye,
        right,
        down,
        forward,
        intrinsics: None,
        hemisphere: Hemisphere::Lower,
        meta: Default::default(),
        label: String::new(),
    };
    let k = Intrinsics {
        width,
        height,
        principal_px: glam::DVec2::new(f64::from(width) / 2.0, f64::from(height) / 2.0),
        focal_px: glam::DVec2::ONE,
    };
    let (view, _) = pinhole_view_projection(&cam, &k, 1.0, 2.0);
    let (hw, hh) = (0.5 * f64::from(width) * pixel_m, 0.5 * f64::from(height) * pixel_m);
    let (n, f) = (1.0f64, 1.0 + 2.0 * depth_m);
    let projection = Mat4::from_cols(
        Vec4::new((1.0 / hw) as f32, 0.0, 0.0, 0.0),
        Vec4::new(0.0, (1.0 / hh) as f32, 0.0, 0.0),
        Vec4::new(0.0, 0.0, (-2.0 / (f - n)) as f32, 0.0),
        Vec4::new(0.0, 0.0, (-(f + n) / (f - n)) as f32, 1.0),
    );
    (view, projection)
}

/// Radius (m) of a ball around the capture centre holding everything the pack's cameras saw: the
/// largest `D · tan α` over cameras, where D is the camera's distance from the centre and α the
/// largest angle from its optical axis to a corner of its kept tiles' bounding box (a point at
/// distance r from the centre is seen at tan α = r / D by the cameras looking across it), plus 2 %.
pub fn content_radius_m(pack: &Pack) -> f64 {
    let set = pack.rayset();
    let t = f64::from(pack.layout().tile_size);
    let mut r: f64 = 0.0;
    for (i, (cam, e)) in set.cameras.iter().zip(pack.images()).enumerate() {
        if e.bbox.w == 0 || e.bbox.h == 0 {
            continue;
        }
        let k = set.intrinsics_of(i);
        let d = (cam.position_m - set.sphere.centre_m).length();
        let (x0, y0) = (f64::from(e.bbox.x0) * t, f64::from(e.bbox.y0) * t);
        let (x1, y1) = (x0 + f64::from(e.bbox.w) * t, y0 + f64::from(e.bbox.h) * t);
        for (u, v) in [(x0, y0), (x1, y0), (x0, y1), (x1, y1)] {
            let ray = k.ray_camera(u, v);
            let tan = (ray.x * ray.x + ray.y * ray.y).sqrt();
            r = r.max(d * tan);
        }
    }
    (r * 1.02).min(set.sphere.radius_m * 0.999)
}

/// The cells of `sel`'s grid that the lines of a view through the content ball reach on the capture
/// sphere (first intersection of each line). Lines are sampled so that neighbouring samples land at
/// most `step` apart on the sphere, and every cell within `step` of a sample is taken. With
/// `clip_from_local`, a sample counts only where its line is inside the view's frustum (the four
/// side planes) or within twice the sample spacing of it, so that every line the view shows still
/// has a counted sample within `step`.
pub fn view_cells(
    sel: &Selection,
    sphere: (DVec3, f64),
    content_radius_m: f64,
    eye: Vec4,
    clip_from_local: Option<Mat4>,
) -> Vec<usize> {
    let (s, r) = sphere;
    let rc = content_radius_m.max(1e-6);
    let (n_phi, n_theta) = sel.grid();
    let cells = n_phi as usize * n_theta as usize;
    let cell_rad = std::f64::consts::PI / f64::from(n_theta);
    let step = 0.5 * cell_rad;
    let mut mark = vec![false; cells];
    let cos_i = (1.0 - (rc / r).min(0.995).powi(2)).sqrt();
    let add = |q: DVec3, mark: &mut Vec<bool>| {
        let u = (q - s).normalize_or_zero();
        sel.for_each_cell_near(u, step + 1e-4, |c| mark[c] = true);
    };
    let e = eye.truncate().as_dvec3();
    let first_hit = |p: DVec3, v: DVec3| -> Option<DVec3> {
        let os = p - s;
        let b = os.dot(v);
        let disc = b * b - (os.length_squared() - r * r);
        (disc >= 0.0).then(|| p + (-b - disc.sqrt()) * v)
    };
    // The frustum's side planes (x = ±w, y = ±w in clip space), as (normal, offset) with a unit
    // normal pointing inwards: for a perspective view they pass through the eye.
    let planes: Vec<(DVec3, f64)> = clip_from_local
        .map(|m| {
            let row = |i: usize| m.row(i).as_dvec4();
            [row(3) + row(0), row(3) - row(0), row(3) + row(1), row(3) - row(1)]
                .into_iter()
                .filter_map(|p| {
                    let n = p.truncate();
                    let len = n.length();
                    (len > 0.0 && len.is_finite()).then(|| (n / len, p.w / len))
                })
                .collect()
        })
        .unwrap_or_default();
    if eye.w > 0.5 {
        let to_c = s - e;
        let dist = to_c.length();
        if dist <= rc * 1.0001 {
            return (0..cells).collect();
        }
        let axis = to_c / dist;
        let beta = (rc / dist).min(1.0).asin();
        let amp = (dist + r) / (r * cos_i);
        let n_r = ((beta * amp / step).ceil() as usize).clamp(1, 4096);
        let (bx, by) = orthonormal(axis);
        // A direction is in view where it is on the inner side of every side plane through the eye;
        // a plane that misses the eye (a projection translated in clip x or y without w) is left
        // out, which only keeps more.
        let through_eye: Vec<DVec3> = planes
            .iter()
            .filter(|(n, w)| (n.dot(e) + w).abs() <= 1e-4)
            .map(|(n, _)| *n)
            .collect();
        for k in 0..=n_r {
            let a = beta * k as f64 / n_r as f64;
            let n_a = ((std::f64::consts::TAU * a.sin() * amp / step).ceil() as usize).clamp(1, 65_536);
            // Directions: a sample's neighbours are at most this far away (radians; step / amp
            // unless the counts were clamped), and a line within twice that of the frustum counts.
            let spacing = (step / amp)
                .max(beta / n_r as f64)
                .max(std::f64::consts::TAU * a.sin() / n_a as f64);
            let slack = (2.0 * spacing).min(1.0).sin();
            for m in 0..n_a {
                let phi = std::f64::consts::TAU * m as f64 / n_a as f64;
                let d = axis * a.cos() + (bx * phi.cos() + by * phi.sin()) * a.sin();
                if !through_eye.iter().all(|n| n.dot(d) >= -slack) {
                    continue;
                }
                if let Some(q) = first_hit(e, d) {
                    add(q, &mut mark);
                }
            }
        }
    } else {
        let v = -e.normalize_or_zero();
        let (bx, by) = orthonormal(v);
        let spacing = step * r * cos_i;
        let n = ((rc / spacing).ceil() as i64).clamp(1, 4096);
        // Parallel lines: a sample's neighbours are rc / n apart (m).
        let slack = 2.0 * rc / n as f64;
        let in_view = |p: DVec3| planes.iter().all(|(nrm, w)| nrm.dot(p) + w >= -slack);
        for i in -n..=n {
            for j in -n..=n {
                let (x, y) = (i as f64 * rc / n as f64, j as f64 * rc / n as f64);
                if x * x + y * y > rc * rc * (1.0 + 2.0 / n as f64) {
                    continue;
                }
                let p = s + bx * x + by * y;
                if !in_view(p) {
                    continue;
                }
                if let Some(q) = first_hit(p, v) {
                    add(q, &mut mark);
                }
            }
        }
    }
    mark.iter().enumerate().filter(|(_, m)| **m).map(|(i, _)| i).collect()
}

/// Two unit vectors orthogonal to the unit vector `a` and to each other (a right-handed frame
/// (x, y, a) up to sign).
pub(crate) fn orthonormal(a: DVec3) -> (DVec3, DVec3) {
    let t = if a.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let x = a.cross(t).normalize();
    (x, a.cross(x))
}
