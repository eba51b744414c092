//! The selection at a direction: all three modes against brute force on random directions and at
//! the vertices, the Continuous weights continuous (and Nearest jumping), exact interpolation of
//! linear data, and the 56,000-camera build checked the same way.

use std::collections::{BTreeMap, HashMap};
use std::f64::consts::PI;
use std::time::Instant;

use glam::DVec3;

use lumiview::nearfield::layout::{Layout, SplitMix64};
use lumiview::nearfield::select::{Selection, SelectionMode, Weights};

use crate::common::{angle, build, corners, edge_values, layout_set, min3, random_unit};

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
