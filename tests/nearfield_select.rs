//! Camera selection (`lumiview::nearfield::select`): the spherical Delaunay triangulation (empty
//! circumcaps, Euler, closed and tiling the sphere), merged pole duplicates, holes over unmeasured
//! regions, cocircular layouts, a brute-force cross-check of all three modes on ≥ 20,000 random
//! directions, conservative cell lists under an fp32 cell computation, continuity of the Continuous
//! weights (and the jumps of Nearest), exactness for linear data, the 56,000-camera build, and bad input.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::{BTreeMap, HashMap};
use std::f64::consts::{PI, TAU};
use std::time::Instant;

use glam::{DVec2, DVec3};

use lumiview::nearfield::layout::{cameras, direction_deg, Layout, SplitMix64};
use lumiview::nearfield::select::{Selection, SelectionMode, SelectionOptions, Weights};
use lumiview::nearfield::{Camera, CaptureSphere, Hemisphere, Intrinsics, NearfieldError, RayImageSet};

const MODES: [SelectionMode; 3] = [SelectionMode::Nearest, SelectionMode::Idw4, SelectionMode::Continuous];

fn sphere() -> CaptureSphere {
    CaptureSphere {
        centre_m: DVec3::new(0.01, -0.02, 0.03),
        radius_m: 1.117,
    }
}

fn set_of(cameras: Vec<Camera>) -> RayImageSet {
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

fn layout_set(layout: Layout, seed: u64) -> RayImageSet {
    set_of(cameras(&sphere(), &layout, seed).unwrap())
}

fn dirs_set(dirs: &[DVec3]) -> RayImageSet {
    let s = sphere();
    set_of(
        dirs.iter()
            .enumerate()
            .map(|(i, d)| Camera::on_sphere(&s, *d, Hemisphere::Lower, format!("cam {i}")))
            .collect(),
    )
}

fn build(set: &RayImageSet) -> Selection {
    Selection::build(set, &SelectionOptions::default()).unwrap()
}

fn random_unit(rng: &mut SplitMix64) -> DVec3 {
    let z = 2.0 * rng.next_f64() - 1.0;
    let a = TAU * rng.next_f64();
    let s = (1.0 - z * z).sqrt();
    DVec3::new(s * a.cos(), s * a.sin(), z)
}

fn angle(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

fn corners(sel: &Selection, t: usize) -> [DVec3; 3] {
    sel.triangles()[t].map(|v| sel.vertex_directions()[v as usize])
}

/// e = (u·(b×c), u·(c×a), u·(a×b)).
fn edge_values(sel: &Selection, t: usize, u: DVec3) -> [f64; 3] {
    let [a, b, c] = corners(sel, t);
    [u.dot(b.cross(c)), u.dot(c.cross(a)), u.dot(a.cross(b))]
}

fn min3(e: [f64; 3]) -> f64 {
    e[0].min(e[1]).min(e[2])
}

/// Barycentric weights of `u` in triangle `t` as a dense camera map (computed independently).
fn triangle_weights(sel: &Selection, t: usize, u: DVec3) -> BTreeMap<u32, f64> {
    let e = edge_values(sel, t, u).map(|x| x.max(0.0));
    let s: f64 = e.iter().sum();
    let mut m = BTreeMap::new();
    for (&x, &v) in e.iter().zip(&sel.triangles()[t]) {
        if x > 0.0 {
            m.insert(sel.vertex_camera()[v as usize], x / s);
        }
    }
    m
}

fn dense(w: &Weights) -> BTreeMap<u32, f64> {
    w.iter().map(|&(c, x)| (c, x)).collect()
}

fn l1_change(a: &BTreeMap<u32, f64>, b: &BTreeMap<u32, f64>) -> f64 {
    let mut keys: Vec<u32> = a.keys().chain(b.keys()).copied().collect();
    keys.sort_unstable();
    keys.dedup();
    keys.iter()
        .map(|k| (a.get(k).copied().unwrap_or(0.0) - b.get(k).copied().unwrap_or(0.0)).abs())
        .sum()
}

fn camera_to_vertex(sel: &Selection) -> HashMap<u32, usize> {
    sel.vertex_camera().iter().enumerate().map(|(v, &c)| (c, v)).collect()
}

/// Solid angle of the spherical triangle (a, b, c) (Van Oosterom–Strackee).
fn solid_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let num = a.dot(b.cross(c));
    let den = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
    2.0 * num.atan2(den)
}

/// The structural checks of a triangulation: Euler, every vertex used, every edge shared by two
/// triangles (in opposite directions, the folded ones turned back first), det > 0, and (for a scan
/// around the centre) the triangles tile the sphere: their solid angles sum to 4π.
fn check_structure(sel: &Selection, tiles_sphere: bool) {
    let (v, t) = (sel.vertex_directions().len(), sel.triangles().len());
    assert_eq!(t, 2 * v - 4, "Euler");
    let mut used = vec![false; v];
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    for (k, tri) in sel.triangles().iter().enumerate() {
        let mut tri = *tri;
        if sel.is_folded(k) {
            assert!(sel.is_hole(k), "a folded triangle is a hole");
            tri.swap(1, 2);
        }
        for k in 0..3 {
            used[tri[k] as usize] = true;
            *edges.entry((tri[k], tri[(k + 1) % 3])).or_default() += 1;
        }
    }
    assert!(used.iter().all(|u| *u), "every vertex used");
    for (&(a, b), &n) in &edges {
        assert_eq!(n, 1);
        assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}-{b}");
    }
    if tiles_sphere {
        assert_eq!(sel.stats().folded, 0);
    }
    for k in 0..t {
        let [a, b, c] = corners(sel, k);
        assert!(
            a.dot(b.cross(c)) > 0.0,
            "triangle {k} is counter-clockwise seen from outside"
        );
    }
    if tiles_sphere {
        let total: f64 = (0..t)
            .map(|k| {
                let [a, b, c] = corners(sel, k);
                solid_angle(a, b, c)
            })
            .sum();
        assert!((total - 4.0 * PI).abs() < 1e-9, "solid angles sum to {total}");
    }
}

/// No vertex strictly inside the circumcap of any non-hole triangle (tolerance 1e-9 rad).
fn check_delaunay(sel: &Selection) -> usize {
    let dirs = sel.vertex_directions();
    let mut checked = 0;
    for (t, tri) in sel.triangles().iter().enumerate() {
        if sel.is_hole(t) {
            continue;
        }
        let (n, r) = sel.circumcap(t).unwrap();
        for (v, d) in dirs.iter().enumerate() {
            if tri.contains(&(v as u32)) {
                assert!((angle(n, *d) - r).abs() < 1e-9, "vertex on its own circumcircle");
                continue;
            }
            let a = angle(n, *d);
            assert!(
                a >= r - 1e-9,
                "vertex {v} inside the circumcap of triangle {t}: {a} < {r}"
            );
        }
        checked += 1;
    }
    checked
}

#[test]
fn delaunay_property_euler_and_every_vertex_used() {
    let sets = [
        ("fibonacci 1000", layout_set(Layout::Fibonacci { count: 1000 }, 0)),
        (
            "rigo jitter 0.5°",
            layout_set(
                Layout::Rigo {
                    per_hemisphere: 400,
                    overlap_deg: 2.0,
                    jitter_deg: 0.5,
                },
                11,
            ),
        ),
        (
            "rigo jitter 0.05°",
            layout_set(
                Layout::Rigo {
                    per_hemisphere: 600,
                    overlap_deg: 5.0,
                    jitter_deg: 0.05,
                },
                12,
            ),
        ),
        (
            "grid (cocircular)",
            layout_set(
                Layout::Grid {
                    phi_steps: 30,
                    theta_steps: 17,
                },
                0,
            ),
        ),
    ];
    for (name, set) in &sets {
        let sel = build(set);
        check_structure(&sel, true);
        let checked = check_delaunay(&sel);
        let s = sel.stats();
        assert_eq!(s.holes, 0, "{name}: a scan around the centre has no holes");
        assert_eq!(checked, sel.triangles().len(), "{name}");
        println!("{name}: {s}");
    }
    // Random points (jittered fibonacci): generic positions.
    let mut rng = SplitMix64::new(77);
    let dirs: Vec<DVec3> = (0..700).map(|_| random_unit(&mut rng)).collect();
    let sel = build(&dirs_set(&dirs));
    check_structure(&sel, true);
    check_delaunay(&sel);
}

#[test]
fn full_rigo_merges_pole_duplicates_and_has_no_holes() {
    let set = layout_set(
        Layout::Rigo {
            per_hemisphere: 500,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        },
        3,
    );
    let sel = build(&set);
    let s = sel.stats();
    assert_eq!(s.cameras, set.cameras.len());
    assert!(s.vertices < s.cameras, "{s}");
    assert_eq!(s.merged_groups, 2, "one group per pole");
    assert_eq!((s.holes, s.folded), (0, 0), "{s}");
    check_structure(&sel, true);
    // Each pole is one vertex whose camera is the lowest index among the cameras there.
    let c = set.sphere.centre_m;
    for pole in [-DVec3::Z, DVec3::Z] {
        let at_pole: Vec<usize> = (0..set.cameras.len())
            .filter(|&i| set.cameras[i].direction_from(c).dot(pole) > 1.0 - 1e-12)
            .collect();
        assert!(at_pole.len() > 3);
        let vs: Vec<usize> = (0..s.vertices)
            .filter(|&v| sel.vertex_directions()[v].dot(pole) > 1.0 - 1e-12)
            .collect();
        assert_eq!(vs.len(), 1);
        assert_eq!(sel.vertex_camera()[vs[0]] as usize, at_pole[0]);
        assert_eq!(s.cameras - s.vertices, 2 * (at_pole.len() - 1));
        // Selecting at the pole returns that camera.
        for mode in MODES {
            let w = sel.select(mode, pole);
            assert!((w.weight_of(at_pole[0] as u32) - 1.0).abs() < 1e-9, "{mode:?}: {w:?}");
        }
    }
}

#[test]
fn lower_hemisphere_only_leaves_the_upper_cap_a_hole() {
    // Lower-hemisphere cameras (θ < 90° + overlap, z < 0 mostly: nadir is −Z): the zenith (+Z) is
    // unmeasured.
    let full = layout_set(
        Layout::Rigo {
            per_hemisphere: 500,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        },
        5,
    );
    let lower: Vec<Camera> = full
        .cameras
        .iter()
        .filter(|c| c.hemisphere == Hemisphere::Lower)
        .cloned()
        .collect();
    let set = set_of(lower);
    let sel = build(&set);
    let s = sel.stats();
    println!("{s}");
    assert!(s.holes > 0 && s.folded == 0, "{s}");
    check_structure(&sel, true);
    // The holes are exactly the triangles over the upper cap: their circumcentres near +Z, and every
    // triangle whose circumcentre is near +Z a hole.
    for t in 0..s.triangles {
        let (n, _) = sel.circumcap(t).unwrap();
        assert_eq!(sel.is_hole(t), n.z > 0.9, "triangle {t}: centre {n}");
    }
    for mode in MODES {
        assert!(sel.select(mode, DVec3::Z).is_empty(), "{mode:?} at the zenith");
    }
    assert!(sel.find_triangle(DVec3::Z).is_some_and(|t| sel.is_hole(t)));
    let top = sel.cell_of(DVec3::Z);
    assert!(sel
        .cameras_of_cells(SelectionMode::Continuous, [top].into_iter())
        .is_empty());
    assert!(sel
        .cameras_of_cells(SelectionMode::Nearest, [top].into_iter())
        .is_empty());
    let mut rng = SplitMix64::new(8);
    let (mut above, mut below) = (0, 0);
    for _ in 0..5000 {
        let u = random_unit(&mut rng);
        if u.z > 0.5 {
            above += 1;
            for mode in MODES {
                assert!(sel.select(mode, u).is_empty(), "{mode:?} at {u}");
            }
        } else if u.z < -0.05 {
            below += 1;
            for mode in MODES {
                let w = sel.select(mode, u);
                assert!(!w.is_empty(), "{mode:?} at {u}");
                assert!((w.iter().map(|p| p.1).sum::<f64>() - 1.0).abs() < 1e-12);
            }
        }
    }
    assert!(above > 500 && below > 1500);
}

#[test]
fn a_cap_only_scan_folds_the_far_side_and_stays_right_inside() {
    // Only a 60° cap around nadir: the convex hull of the directions misses the centre. The far side
    // is folded (documented): the measured cap is still covered once and exactly.
    let n = 4000;
    let dirs: Vec<DVec3> = (0..n)
        .filter_map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let a = 2.399_963_229_728_653 * i as f64;
            let r = (1.0 - z * z).sqrt();
            (z < -0.5).then(|| DVec3::new(r * a.cos(), r * a.sin(), z))
        })
        .collect();
    let sel = build(&dirs_set(&dirs));
    let s = sel.stats();
    println!("{s}");
    assert!(s.folded > 0 && s.holes >= s.folded, "{s}");
    check_structure(&sel, false);
    let mut rng = SplitMix64::new(4);
    for _ in 0..5000 {
        let u = random_unit(&mut rng);
        let w = sel.select(SelectionMode::Continuous, u);
        if u.z < -0.55 {
            let t = sel.find_triangle(u).unwrap();
            assert!(!sel.is_hole(t) && min3(edge_values(&sel, t, u)) >= -1e-12, "{u}");
            assert!(!w.is_empty());
        } else if u.z > -0.3 {
            for mode in MODES {
                assert!(sel.select(mode, u).is_empty(), "{mode:?} at {u}");
            }
        }
    }
}

#[test]
fn grid_layout_with_cocircular_points_builds_and_queries() {
    let set = layout_set(
        Layout::Grid {
            phi_steps: 24,
            theta_steps: 13,
        },
        0,
    );
    let sel = build(&set);
    let s = sel.stats();
    assert_eq!(s.vertices, 24 * 11 + 2);
    assert_eq!(s.holes, 0);
    check_structure(&sel, true);
    let mut rng = SplitMix64::new(21);
    for _ in 0..5000 {
        let u = random_unit(&mut rng);
        for mode in MODES {
            let w = sel.select(mode, u);
            assert!(!w.is_empty(), "{mode:?} {u}");
            assert!((w.iter().map(|p| p.1).sum::<f64>() - 1.0).abs() < 1e-12);
        }
        let t = sel.find_triangle(u).unwrap();
        assert!(min3(edge_values(&sel, t, u)) >= -1e-12);
    }
    // Exactly at grid points, and on the (cocircular) quad diagonals' circles.
    for j in 1..12 {
        for i in 0..24 {
            let u = direction_deg(15.0 * i as f64, 15.0 * j as f64);
            let w = sel.select(SelectionMode::Continuous, u);
            assert!(w.iter().any(|p| (p.1 - 1.0).abs() < 1e-9), "{u}: {w:?}");
        }
    }
}

/// Brute-force check of all three modes at `u`.
fn cross_check(sel: &Selection, cam_vertex: &HashMap<u32, usize>, u: DVec3) {
    let dirs = sel.vertex_directions();
    let cos_gap = sel.max_gap_rad().min(PI).cos();
    let mut by_dot: Vec<(f64, usize)> = dirs.iter().enumerate().map(|(v, d)| (u.dot(*d), v)).collect();
    by_dot.sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
    // Nearest.
    let w = sel.select(SelectionMode::Nearest, u);
    if by_dot[0].0 >= cos_gap {
        assert_eq!(w.len(), 1);
        let v = cam_vertex[&w.as_slice()[0].0];
        assert!(u.dot(dirs[v]) >= by_dot[0].0 - 1e-12, "nearest at {u}");
    } else {
        assert!(w.is_empty());
    }
    // Idw4: the same set as the brute-force 4 nearest within the gap (ties at the 4th place allowed).
    let w = sel.select(SelectionMode::Idw4, u);
    if by_dot[0].0 >= cos_gap && angle(u, dirs[by_dot[0].1]) < 1e-7 {
        // At a camera: that camera alone.
        assert_eq!(w.len(), 1);
        assert_eq!(w.as_slice()[0].1, 1.0);
        assert!(u.dot(dirs[cam_vertex[&w.as_slice()[0].0]]) >= by_dot[0].0 - 1e-12);
        return cross_check_continuous(sel, u);
    }
    let want: Vec<usize> = by_dot.iter().take(4).filter(|p| p.0 >= cos_gap).map(|p| p.1).collect();
    assert_eq!(w.len(), want.len(), "idw4 at {u}");
    let tie = by_dot.len() > 4 && (by_dot[3].0 - by_dot[4].0).abs() < 1e-12;
    for &(cam, x) in w.iter() {
        let v = cam_vertex[&cam];
        assert!(want.contains(&v) || tie, "idw4 at {u}: vertex {v}");
        assert!(x > 0.0 && x <= 1.0);
    }
    if w.len() > 1 {
        // Weights ∝ 1 / angle.
        let inv: Vec<f64> = w.iter().map(|p| 1.0 / angle(u, dirs[cam_vertex[&p.0]])).collect();
        let s: f64 = inv.iter().sum();
        for (p, i) in w.iter().zip(&inv) {
            assert!((p.1 - i / s).abs() < 1e-12);
        }
    }
    cross_check_continuous(sel, u);
}

/// Continuous: the returned triangle contains u, and a containing triangle found over all triangles
/// gives the same weights.
fn cross_check_continuous(sel: &Selection, u: DVec3) {
    let t = sel.find_triangle(u).unwrap();
    assert!(min3(edge_values(sel, t, u)) >= -1e-12, "continuous at {u}");
    let w = sel.select(SelectionMode::Continuous, u);
    assert!((w.iter().map(|p| p.1).sum::<f64>() - 1.0).abs() < 1e-12);
    let brute = (0..sel.triangles().len())
        .filter(|&k| !sel.is_folded(k))
        .find(|&k| min3(edge_values(sel, k, u)) >= -1e-12)
        .unwrap();
    assert!(
        l1_change(&dense(&w), &triangle_weights(sel, brute, u)) < 1e-9,
        "continuous at {u}"
    );
}

#[test]
fn brute_force_cross_check_on_random_directions() {
    let sets = [
        ("fibonacci", layout_set(Layout::Fibonacci { count: 1500 }, 0)),
        (
            "rigo",
            layout_set(
                Layout::Rigo {
                    per_hemisphere: 600,
                    overlap_deg: 2.0,
                    jitter_deg: 0.3,
                },
                9,
            ),
        ),
    ];
    for (name, set) in &sets {
        let sel = build(set);
        let cam_vertex = camera_to_vertex(&sel);
        let mut rng = SplitMix64::new(1234);
        for _ in 0..20_000 {
            cross_check(&sel, &cam_vertex, random_unit(&mut rng));
        }
        // At and right beside the vertices (exact ties of the weights).
        for (v, d) in sel.vertex_directions().iter().enumerate().step_by(7) {
            cross_check(&sel, &cam_vertex, *d);
            let w = sel.select(SelectionMode::Idw4, *d);
            assert_eq!(w.as_slice(), &[(sel.vertex_camera()[v], 1.0)], "{name}");
            cross_check(&sel, &cam_vertex, (*d + DVec3::new(1e-9, -2e-9, 1e-9)).normalize());
        }
    }
}

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

#[test]
fn continuous_weights_are_continuous_and_nearest_jumps() {
    let sel = build(&layout_set(Layout::Fibonacci { count: 2000 }, 0));
    // The barycentric gradient is bounded by 1 / (smallest altitude); allow the 3 weights and margin.
    let min_alt = (0..sel.triangles().len())
        .map(|t| {
            let [a, b, c] = corners(&sel, t);
            [(a, b, c), (b, c, a), (c, a, b)]
                .iter()
                .map(|&(p, q, r)| {
                    let n = q.cross(r).normalize();
                    p.dot(n).abs().asin()
                })
                .fold(f64::MAX, f64::min)
        })
        .fold(f64::MAX, f64::min);
    let step = 1e-5;
    let bound = 6.0 / min_alt * step;
    assert!(bound < 0.05, "the bound {bound} must be far below a jump");
    let mut rng = SplitMix64::new(99);
    let mut nearest_jumps = 0;
    let mut worst: f64 = 0.0;
    for _ in 0..3 {
        let a = random_unit(&mut rng);
        let axis = a.cross(random_unit(&mut rng)).normalize();
        let b = axis.cross(a);
        let steps = 30_000;
        let mut prev: Option<(BTreeMap<u32, f64>, BTreeMap<u32, f64>)> = None;
        for k in 0..=steps {
            let s = k as f64 * step;
            let u = a * s.cos() + b * s.sin();
            let cont = dense(&sel.select(SelectionMode::Continuous, u));
            let near = dense(&sel.select(SelectionMode::Nearest, u));
            if let Some((pc, pn)) = &prev {
                let d = l1_change(pc, &cont);
                worst = worst.max(d);
                assert!(d <= bound, "continuous jumps by {d} at {u}");
                if l1_change(pn, &near) >= 1.0 {
                    nearest_jumps += 1;
                }
            }
            prev = Some((cont, near));
        }
    }
    println!("largest continuous change per step {worst:.2e} (bound {bound:.2e}); nearest jumps {nearest_jumps}");
    assert!(nearest_jumps > 3, "Nearest must jump (the test can fail)");
}

#[test]
fn interpolation_is_exact_for_linear_data() {
    let sel = build(&layout_set(
        Layout::Rigo {
            per_hemisphere: 500,
            overlap_deg: 2.0,
            jitter_deg: 0.2,
        },
        4,
    ));
    let cam_vertex = camera_to_vertex(&sel);
    let dirs = sel.vertex_directions();
    let g = DVec3::new(0.3, -1.7, 2.2);
    let mut rng = SplitMix64::new(6);
    for _ in 0..10_000 {
        let u = random_unit(&mut rng);
        let w = sel.select(SelectionMode::Continuous, u);
        let t = sel.find_triangle(u).unwrap();
        let s: DVec3 = w.iter().map(|&(c, x)| dirs[cam_vertex[&c]] * x).sum();
        // Σ wᵢ dᵢ is the point where the ray u meets the triangle's plane: along u, inside the triangle.
        let [a, b, c] = corners(&sel, t);
        let n = (b - a).cross(c - a);
        let p = u * (n.dot(a) / n.dot(u));
        assert!((s - p).length() < 1e-12, "{u}: {s} vs {p}");
        assert!((s.normalize() - u).length() < 1e-12);
        assert!(min3(edge_values(&sel, t, s.normalize())) >= -1e-12);
        // A linear function of the direction is reproduced exactly at that point.
        let f: f64 = w.iter().map(|&(c, x)| x * g.dot(dirs[cam_vertex[&c]])).sum();
        assert!((f - g.dot(p)).abs() < 1e-12, "{u}");
    }
}

#[test]
fn large_rigo_build() {
    let t0 = Instant::now();
    let set = layout_set(
        Layout::Rigo {
            per_hemisphere: 28_000,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        },
        0,
    );
    let t_layout = t0.elapsed();
    let t1 = Instant::now();
    let sel = build(&set);
    let t_build = t1.elapsed();
    let s = sel.stats();
    println!(
        "56k rigo: layout {:.2} s, selection build {:.2} s\n{s}",
        t_layout.as_secs_f64(),
        t_build.as_secs_f64()
    );
    assert!(s.cameras > 55_000);
    assert_eq!((s.holes, s.folded, s.merged_groups), (0, 0, 2));
    assert_eq!(s.triangles, 2 * s.vertices - 4);
    for (what, mean) in [
        ("triangles", s.tri_list_mean),
        ("nearest", s.near1_list_mean),
        ("4-nearest", s.near4_list_mean),
    ] {
        assert!(mean <= 8.5, "{what}: mean list length {mean}");
    }
    // A sample of queries against brute force.
    let cam_vertex = camera_to_vertex(&sel);
    let mut rng = SplitMix64::new(1);
    for _ in 0..300 {
        cross_check(&sel, &cam_vertex, random_unit(&mut rng));
    }
}

fn expect_invalid(set: &RayImageSet, name: &str) {
    match Selection::build(set, &SelectionOptions::default()) {
        Err(NearfieldError::InvalidArgument { name: n, message }) => {
            assert_eq!(n, name, "{message}");
            println!("{name}: {message}");
        }
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("accepted"),
    }
}

#[test]
fn bad_input_is_an_error_naming_the_argument() {
    // Fewer than 4 cameras.
    expect_invalid(&dirs_set(&[DVec3::X, DVec3::Y, DVec3::Z]), "cameras");
    expect_invalid(&dirs_set(&[]), "cameras");
    // All cameras at one direction (5 cameras, 1 vertex), or at 3 directions.
    expect_invalid(&dirs_set(&[DVec3::X; 5]), "cameras");
    expect_invalid(
        &dirs_set(&[DVec3::X, DVec3::Y, DVec3::X, DVec3::Z, DVec3::new(1.0, 1e-9, 0.0)]),
        "cameras",
    );
    // NaN and infinite positions; a camera at the centre.
    for bad in [DVec3::new(f64::NAN, 0.0, 0.0), DVec3::new(0.0, f64::INFINITY, 0.0)] {
        let mut set = layout_set(Layout::Fibonacci { count: 20 }, 0);
        set.cameras[7].position_m = bad;
        expect_invalid(&set, "cameras");
    }
    let mut set = layout_set(Layout::Fibonacci { count: 20 }, 0);
    set.cameras[3].position_m = set.sphere.centre_m;
    expect_invalid(&set, "cameras");
    let mut set = layout_set(Layout::Fibonacci { count: 20 }, 0);
    set.sphere.centre_m.y = f64::NAN;
    expect_invalid(&set, "capture sphere");
    // All on one great circle: no triangulation.
    let ring: Vec<DVec3> = (0..12).map(|k| direction_deg(30.0 * k as f64, 90.0)).collect();
    expect_invalid(&dirs_set(&ring), "cameras");
    // The smallest valid set: a tetrahedron.
    let tet = [
        DVec3::new(1.0, 1.0, 1.0),
        DVec3::new(1.0, -1.0, -1.0),
        DVec3::new(-1.0, 1.0, -1.0),
        DVec3::new(-1.0, -1.0, 1.0),
    ];
    let sel = build(&dirs_set(&tet.map(|d| d.normalize())));
    assert_eq!(sel.triangles().len(), 4);
    check_structure(&sel, true);
    for mode in MODES {
        assert!(!sel.select(mode, DVec3::new(0.2, 0.3, -0.9)).is_empty());
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
