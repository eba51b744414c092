//! The photometric solid: closed and outward with the right radii for every fixture, a sphere's solid
//! outward everywhere, its errors, the glTF (read back with the gltf crate) and OBJ files, and the
//! `lumiview solid` command with its errors.

use std::collections::HashMap;

use lumiview::photometry::lut::c_mean;
use lumiview::photometry::solid::{to_gltf_axes, PhotometricSolid, SolidOptions};
use lumiview::photometry::web::direction;
use lumiview::photometry::{PhotometricWeb, PhotometryError};

use crate::common::{fixtures, lumiview, open, tmp, ASA, BEGA};

/// Every undirected edge in exactly two triangles, and each directed edge once (so the two
/// triangles sharing an edge are wound consistently).
fn check_closed(mesh: &PhotometricSolid) {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for t in mesh.indices().chunks_exact(3) {
        assert!(
            t[0] != t[1] && t[1] != t[2] && t[0] != t[2],
            "topologically degenerate triangle {t:?}"
        );
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *directed.entry((a, b)).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        assert_eq!(n, 1, "directed edge {a}->{b} used {n} times");
        assert_eq!(directed.get(&(b, a)), Some(&1), "edge {a}-{b} has no opposite");
    }
    let edges = directed.len() / 2;
    let (v, f) = (mesh.vertex_count(), mesh.triangle_count());
    assert_eq!(edges * 2, f * 3);
    assert_eq!(
        v as i64 - edges as i64 + f as i64,
        2,
        "Euler characteristic of a sphere"
    );
    assert!(mesh.indices().iter().all(|&i| (i as usize) < v));
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f64 {
    (0..3).map(|k| f64::from(a[k]) * f64::from(b[k])).sum()
}

fn len(a: [f32; 3]) -> f64 {
    dot(a, a).sqrt()
}

#[test]
fn solid_is_closed_outward_and_has_the_right_radii() {
    for f in fixtures() {
        let p = open(&f);
        let (max, _, _) = p.web.max_intensity();
        for (nc, ng, scale) in [(72, 36, 1.0), (16, 7, 2.5), (3, 2, 0.1)] {
            let opts = SolidOptions {
                c_steps: nc,
                gamma_steps: ng,
                scale_m: scale,
            };
            let mesh = PhotometricSolid::new(&p.web, &opts).unwrap();
            assert_eq!(mesh.vertex_count(), 2 + nc * (ng - 1));
            assert_eq!(mesh.triangle_count(), 2 * nc * (ng - 1));
            assert_eq!(mesh.normals().len(), mesh.vertex_count());
            assert_eq!(mesh.max_cd(), max);
            check_closed(&mesh);
            for (k, (&pos, &n)) in mesh.positions().iter().zip(mesh.normals()).enumerate() {
                assert!((len(n) - 1.0).abs() < 1e-5, "{f}: normal {k} {n:?}");
                let (c, g) = mesh.vertex_angles(k).unwrap();
                let i_cd = if k == 0 || k == mesh.vertex_count() - 1 {
                    c_mean(&p.web, g)
                } else {
                    p.web.sample(c, g)
                };
                let r = len(pos);
                assert!(
                    (r - scale * i_cd / max).abs() <= 1e-6 * scale,
                    "{f}: vertex {k} r {r} vs {}",
                    scale * i_cd / max
                );
                if r > 1e-9 * scale {
                    // On its ray, and the normal points out.
                    let d = direction(c, g);
                    let along = (0..3).map(|q| f64::from(pos[q]) * d[q]).sum::<f64>();
                    assert!((along - r).abs() <= 1e-6 * scale);
                    assert!(
                        dot(n, pos) >= -1e-6 * r,
                        "{f}: vertex {k} normal {n:?} points in at {pos:?}"
                    );
                }
            }
            // Faces wound counter-clockwise seen from outside: face normal · centroid ≥ 0.
            let pp = mesh.positions();
            for t in mesh.indices().chunks_exact(3) {
                let [a, b, c] = [pp[t[0] as usize], pp[t[1] as usize], pp[t[2] as usize]].map(|v| v.map(f64::from));
                let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                let fnrm = [
                    e1[1] * e2[2] - e1[2] * e2[1],
                    e1[2] * e2[0] - e1[0] * e2[2],
                    e1[0] * e2[1] - e1[1] * e2[0],
                ];
                let cen = [
                    (a[0] + b[0] + c[0]) / 3.0,
                    (a[1] + b[1] + c[1]) / 3.0,
                    (a[2] + b[2] + c[2]) / 3.0,
                ];
                let s: f64 = (0..3).map(|q| fnrm[q] * cen[q]).sum();
                assert!(s >= -1e-9 * scale * scale * scale, "{f}: inward face {t:?}: {s}");
            }
        }
    }
}

#[test]
fn solid_of_a_sphere_is_outward_everywhere() {
    // Isotropic: every face and vertex normal points out strictly; the nadir pole is −Z.
    let web = PhotometricWeb::from_grid(vec![0.0, 360.0], vec![0.0, 180.0], vec![50.0; 4]).unwrap();
    let mesh = PhotometricSolid::new(&web, &SolidOptions::default()).unwrap();
    check_closed(&mesh);
    for (&p, &n) in mesh.positions().iter().zip(mesh.normals()) {
        assert!(dot(n, p) / len(p) > 0.99);
    }
    assert_eq!(mesh.positions()[0], [0.0, 0.0, -1.0]);
    assert_eq!(*mesh.positions().last().unwrap(), [0.0, 0.0, 1.0]);
}

#[test]
fn solid_errors() {
    let zero = PhotometricWeb::from_grid(vec![0.0, 360.0], vec![0.0, 180.0], vec![0.0; 4]).unwrap();
    assert!(matches!(
        PhotometricSolid::new(&zero, &SolidOptions::default()),
        Err(PhotometryError::InvalidArgument { .. })
    ));
    let p = open(BEGA);
    for (c, g, s) in [
        (0, 10, 1.0),
        (2, 10, 1.0),
        (10, 0, 1.0),
        (10, 1, 1.0),
        (100_000, 10, 1.0),
        (10, 10, 0.0),
        (10, 10, f64::INFINITY),
        (10, 10, -2.0),
    ] {
        let opts = SolidOptions {
            c_steps: c,
            gamma_steps: g,
            scale_m: s,
        };
        assert!(
            matches!(
                PhotometricSolid::new(&p.web, &opts),
                Err(PhotometryError::InvalidArgument { .. })
            ),
            "{c} {g} {s}"
        );
    }
}

fn check_glb(bytes: &[u8], mesh: &PhotometricSolid) {
    let gltf = gltf::Gltf::from_slice(bytes).unwrap();
    assert_eq!(gltf.document.meshes().count(), 1);
    assert_eq!(gltf.document.nodes().count(), 1);
    assert_eq!(gltf.document.scenes().count(), 1);
    let m = gltf.document.meshes().next().unwrap();
    let prims: Vec<_> = m.primitives().collect();
    assert_eq!(prims.len(), 1);
    let prim = &prims[0];
    assert_eq!(prim.mode(), gltf::mesh::Mode::Triangles);
    let pos_acc = prim.get(&gltf::Semantic::Positions).unwrap();
    let nrm_acc = prim.get(&gltf::Semantic::Normals).unwrap();
    let idx_acc = prim.indices().unwrap();
    assert_eq!(pos_acc.count(), mesh.vertex_count());
    assert_eq!(nrm_acc.count(), mesh.vertex_count());
    assert_eq!(idx_acc.count(), mesh.indices().len());
    assert_eq!(idx_acc.data_type(), gltf::accessor::DataType::U32);
    let blob = gltf.blob.as_deref();
    let reader = prim.reader(|b| if b.index() == 0 { blob } else { None });
    let pos: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
    let nrm: Vec<[f32; 3]> = reader.read_normals().unwrap().collect();
    let idx: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
    assert_eq!(idx, mesh.indices());
    let want: Vec<[f32; 3]> = mesh.positions().iter().map(|&p| to_gltf_axes(p)).collect();
    assert_eq!(pos, want);
    let want_n: Vec<[f32; 3]> = mesh.normals().iter().map(|&n| to_gltf_axes(n)).collect();
    assert_eq!(nrm, want_n);
    // min/max of POSITION are exact.
    let b = prim.bounding_box();
    for k in 0..3 {
        assert_eq!(b.min[k], pos.iter().map(|p| p[k]).fold(f32::INFINITY, f32::min));
        assert_eq!(b.max[k], pos.iter().map(|p| p[k]).fold(f32::NEG_INFINITY, f32::max));
    }
    // Nadir down in Y-up glTF.
    assert!(pos[0][1] <= 0.0 && pos[0][0] == 0.0);
}

#[test]
fn glb_parses_with_the_gltf_crate() {
    for f in [ASA, BEGA, "tests/data/photometric-viewer/ldt/no_symmetry.ldt"] {
        let p = open(f);
        let mesh = PhotometricSolid::new(
            &p.web,
            &SolidOptions {
                c_steps: 48,
                gamma_steps: 24,
                scale_m: 3.0,
            },
        )
        .unwrap();
        let bytes = mesh.to_glb().unwrap();
        assert_eq!(&bytes[0..4], b"glTF");
        assert_eq!(bytes.len() % 4, 0);
        assert_eq!(
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            bytes.len()
        );
        check_glb(&bytes, &mesh);
    }
}

fn obj_counts(text: &str) -> (usize, usize, usize) {
    let count = |p: &str| text.lines().filter(|l| l.starts_with(p)).count();
    (count("v "), count("vn "), count("f "))
}

#[test]
fn obj_has_the_right_lines() {
    let p = open(BEGA);
    let mesh = PhotometricSolid::new(&p.web, &SolidOptions::default()).unwrap();
    let obj = mesh.to_obj();
    assert_eq!(
        obj_counts(&obj),
        (mesh.vertex_count(), mesh.vertex_count(), mesh.triangle_count())
    );
    // Faces are 1-based v//vn and match the index buffer.
    let first_face = obj.lines().find(|l| l.starts_with("f ")).unwrap();
    let t = &mesh.indices()[0..3];
    assert_eq!(
        first_face,
        format!("f {a}//{a} {b}//{b} {c}//{c}", a = t[0] + 1, b = t[1] + 1, c = t[2] + 1)
    );
    let first_v: Vec<f32> = obj.lines().find(|l| l.starts_with("v ")).unwrap()[2..]
        .split(' ')
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(first_v, mesh.positions()[0].to_vec());
}

#[test]
fn cli_solid_writes_obj_and_glb() {
    let p = open(ASA);
    let obj_path = tmp("asa.obj");
    let out = lumiview(&[
        "solid",
        ASA,
        "-o",
        obj_path.to_str().unwrap(),
        "--resolution",
        "36x18",
        "--scale",
        "2",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("614 vertices") && stdout.contains("1224 triangles"),
        "{stdout}"
    );
    let mesh = PhotometricSolid::new(
        &p.web,
        &SolidOptions {
            c_steps: 36,
            gamma_steps: 18,
            scale_m: 2.0,
        },
    )
    .unwrap();
    assert_eq!(mesh.vertex_count(), 614);
    let text = std::fs::read_to_string(&obj_path).unwrap();
    assert_eq!(obj_counts(&text), (614, 614, 1224));
    assert_eq!(text, mesh.to_obj());

    let glb_path = tmp("asa.glb");
    let out = lumiview(&[
        "solid",
        ASA,
        "-o",
        glb_path.to_str().unwrap(),
        "--resolution",
        "36x18",
        "--scale",
        "2",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    check_glb(&std::fs::read(&glb_path).unwrap(), &mesh);

    let glb_default = tmp("bega_default.glb");
    let out = lumiview(&["solid", BEGA, "-o", glb_default.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let mesh = PhotometricSolid::new(&open(BEGA).web, &SolidOptions::default()).unwrap();
    check_glb(&std::fs::read(&glb_default).unwrap(), &mesh);
}

#[test]
fn cli_solid_rejects_bad_arguments() {
    let cases: &[(&[&str], &str)] = &[
        (&["-o", "x.stl"], "x.stl"),
        (&["-o", "x"], "unknown output extension"),
        (&["-o", "x.obj", "--resolution", "72"], "--resolution"),
        (&["-o", "x.obj", "--resolution", "2x10"], "c_steps"),
        (&["-o", "x.obj", "--scale", "0"], "scale"),
        (&["-o", "x.obj", "--scale", "nan"], "scale"),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["solid", BEGA];
        args.extend_from_slice(extra);
        let out = lumiview(&args);
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
    let out = lumiview(&["solid", "tests/data/misc/missing.ldt", "-o", "x.glb"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.ldt"));
    let dir_out = tmp("no_such_dir/x.obj");
    let out = lumiview(&["solid", BEGA, "-o", dir_out.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("x.obj"));
}
