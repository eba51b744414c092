//! The spherical Delaunay triangulation: its structure (Euler, every vertex used, every edge shared,
//! tiling the sphere) and empty circumcaps, pole duplicates merged, holes over an unmeasured cap, the
//! folded far side of a cap-only scan, cocircular grid layouts, and the input it refuses.

use std::collections::HashMap;
use std::f64::consts::PI;

use glam::DVec3;

use lumiview::nearfield::layout::{direction_deg, Layout, SplitMix64};
use lumiview::nearfield::select::{Selection, SelectionMode, SelectionOptions};
use lumiview::nearfield::{Camera, Hemisphere, NearfieldError, RayImageSet};

use crate::common::{angle, build, corners, dirs_set, edge_values, layout_set, min3, random_unit, set_of, MODES};

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
