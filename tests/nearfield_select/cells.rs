//! The cell lists: conservative at cell borders and for a cell computed in fp32 as the GPU does,
//! covering every query in a cell, and the cells a view keeps with its frustum.

use std::f64::consts::{PI, TAU};

use glam::{DVec2, DVec3};

use lumiview::nearfield::layout::{Layout, SplitMix64};
use lumiview::nearfield::select::SelectionMode;
use lumiview::nearfield::{Camera, Intrinsics};

use crate::common::{build, edge_values, layout_set, min3, random_unit, sphere, MODES};

/// The cell a GPU computes in fp32 (the shader's formula).
fn cell_of_f32(u: DVec3, n_phi: u32, n_theta: u32) -> usize {
    let u = u.as_vec3();
    let mut phi = u.y.atan2(u.x);
    if phi < 0.0 {
        phi += 2.0 * std::f32::consts::PI;
    }
    let theta = u.z.clamp(-1.0, 1.0).acos();
    let i = ((phi / (2.0 * std::f32::consts::PI) * n_phi as f32).floor() as u32).min(n_phi - 1);
    let j = ((theta / std::f32::consts::PI * n_theta as f32).floor() as u32).min(n_theta - 1);
    (j * n_phi + i) as usize
}

#[test]
fn cell_lists_are_conservative_at_cell_borders_and_for_an_fp32_cell() {
    let sel = build(&layout_set(
        Layout::Rigo {
            per_hemisphere: 800,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        },
        2,
    ));
    let (np, nt) = sel.grid();
    let dirs = sel.vertex_directions();
    let cos_gap = sel.max_gap_rad().min(PI).cos();
    let mut rng = SplitMix64::new(31);
    let mut moved = 0;
    for k in 0..20_000 {
        // Points on (or within 10⁻⁷ rad of) cell borders, near the poles too.
        let i = (rng.next_u64() % u64::from(np)) as f64;
        let j = (rng.next_u64() % u64::from(nt)) as f64;
        let jitter = |r: &mut SplitMix64| (r.next_f64() - 0.5) * 2e-7;
        let (phi, theta) = if k % 2 == 0 {
            (
                i * TAU / f64::from(np) + jitter(&mut rng),
                (j + rng.next_f64()) * PI / f64::from(nt),
            )
        } else {
            (
                (i + rng.next_f64()) * TAU / f64::from(np),
                j * PI / f64::from(nt) + jitter(&mut rng),
            )
        };
        let u = DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
        for cell in [sel.cell_of(u), cell_of_f32(u, np, nt)] {
            moved += usize::from(cell != sel.cell_of(u));
            let tris = sel.cell_candidates(SelectionMode::Continuous, cell);
            assert!(
                tris.iter().any(|&t| min3(edge_values(&sel, t as usize, u)) >= -1e-12),
                "no containing triangle in cell {cell} for {u}"
            );
            let mut by_dot: Vec<(f64, u32)> = (0..dirs.len() as u32).map(|v| (u.dot(dirs[v as usize]), v)).collect();
            by_dot.sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
            let near1 = sel.cell_candidates(SelectionMode::Nearest, cell);
            let near4 = sel.cell_candidates(SelectionMode::Idw4, cell);
            assert!(near1.contains(&by_dot[0].1), "nearest missing from cell {cell} for {u}");
            for p in by_dot.iter().take(4).filter(|p| p.0 >= cos_gap) {
                assert!(near4.contains(&p.1), "4-nearest missing from cell {cell} for {u}");
            }
        }
    }
    assert!(moved > 100, "the fp32 cell differs from the f64 one in {moved} cases");
}

#[test]
fn cameras_of_cells_cover_every_query_in_them() {
    let sel = build(&layout_set(Layout::Fibonacci { count: 800 }, 0));
    let mut rng = SplitMix64::new(17);
    for _ in 0..3000 {
        let u = random_unit(&mut rng);
        let cell = sel.cell_of(u);
        for mode in MODES {
            let cams = sel.cameras_of_cells(mode, [cell, cell + 1].into_iter());
            assert!(cams.windows(2).all(|w| w[0] < w[1]), "sorted, unique");
            for &(c, _) in sel.select(mode, u).iter() {
                assert!(cams.binary_search(&c).is_ok(), "{mode:?} {u}: camera {c}");
            }
        }
    }
}

/// The cells a view needs (`view_cells`, residency's input): with the view's frustum, a close-up
/// keeps far fewer cells than the whole content ball and still every cell that a pixel's line through
/// the content ball reaches (perspective from inside and outside the capture sphere, orthographic; a
/// wide view keeps the ball's set). This catches wrong planes, signs and frames; that the slack of
/// two sample spacings suffices is argued in `view_cells` (a boundary line's cell is usually also
/// marked from a sample inside, so a test could not tell a slightly short slack).
#[test]
fn view_cells_with_the_frustum_keep_every_pixels_cell_and_drop_the_rest() {
    use glam::Vec4;
    use lumiview::nearfield::select::view::{ortho_view_projection, pinhole_view_projection, view_cells};
    let set = layout_set(
        Layout::Rigo {
            per_hemisphere: 2000,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        },
        5,
    );
    let sel = build(&set);
    let s = sphere();
    let (c, r, rc) = (s.centre_m, s.radius_m, 0.15);
    // The line's cell on the capture sphere: its first intersection, as residency takes it.
    let cell_of_line = |p: DVec3, v: DVec3| -> Option<usize> {
        let os = p - c;
        let b = os.dot(v);
        let disc = b * b - (os.length_squared() - r * r);
        (disc >= 0.0).then(|| sel.cell_of((p + (-b - disc.sqrt()) * v - c).normalize()))
    };
    let through_ball = |p: DVec3, v: DVec3| (c - p).cross(v).length() <= rc;
    // (eye, target, vertical field of view in degrees (0: orthographic, 45 × 30 mm), how many times
    // fewer cells the frustum must keep: from inside the capture sphere a close-up's lines through the
    // ball spread over much of the sphere, from outside over a cap a few cells wide)
    let views = [
        (DVec3::new(0.25, 0.1, -0.3), DVec3::new(0.05, 0.03, 0.0), 4.0, 8.0),
        (DVec3::new(-0.6, 0.8, -1.2), DVec3::new(-0.04, 0.06, 0.0), 2.0, 1.5),
        (DVec3::new(0.5, -0.2, -1.0), DVec3::new(0.07, 0.0, 0.0), 0.0, 1.5),
        (DVec3::new(0.8, 0.6, -1.6), DVec3::ZERO, 60.0, 1.0),
    ];
    for (eye, target, fov, fewer) in views {
        // GL matrices (clip z in −w…w; the frustum's side planes and the unprojected lines below
        // do not depend on the depth range) and the eye: a point, or the direction towards it.
        let ((view, projection), eye4) = if fov > 0.0 {
            let cam = Camera::looking_at(eye, target, "eye");
            let f = 100.0 / (0.5 * f64::to_radians(fov)).tan();
            let k = Intrinsics {
                width: 300,
                height: 200,
                principal_px: DVec2::new(150.0, 100.0),
                focal_px: DVec2::splat(f),
            };
            (pinhole_view_projection(&cam, &k, 0.01, 10.0), eye.as_vec3().extend(1.0))
        } else {
            let towards_eye = (eye - target).normalize();
            (
                ortho_view_projection(towards_eye, target, 1e-4, 450, 300, 2.0),
                towards_eye.as_vec3().extend(0.0),
            )
        };
        let clip = projection * view;
        let all = view_cells(&sel, (c, r), rc, eye4, None);
        let kept = view_cells(&sel, (c, r), rc, eye4, Some(clip));
        if fewer > 1.0 {
            assert!(
                kept.len() as f64 * fewer < all.len() as f64,
                "eye {eye}: {} of {} cells kept",
                kept.len(),
                all.len()
            );
        } else {
            assert_eq!(kept.len(), all.len(), "a wide view needs the whole ball");
        }
        let kept_set: std::collections::HashSet<usize> = kept.iter().copied().collect();
        let inv = clip.inverse();
        let n = 120;
        let mut lines = 0;
        for i in 0..=n {
            for j in 0..=n {
                let ndc = |z: f32| {
                    let (x, y) = (2.0 * i as f32 / n as f32 - 1.0, 2.0 * j as f32 / n as f32 - 1.0);
                    let h = inv * Vec4::new(x, y, z, 1.0);
                    (h.truncate() / h.w).as_dvec3()
                };
                let (p0, p1) = (ndc(0.2), ndc(0.9));
                let v = (p1 - p0).normalize();
                if !through_ball(p0, v) {
                    continue;
                }
                let Some(cell) = cell_of_line(p0, v) else { continue };
                lines += 1;
                assert!(
                    kept_set.contains(&cell),
                    "eye {eye}: pixel ({i}, {j})'s cell {cell} dropped"
                );
            }
        }
        assert!(lines > 100, "eye {eye}: only {lines} pixel lines meet the content ball");
    }
}
