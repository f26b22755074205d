//! End-to-end tests of `impulse massprops`: the binary on bundled and generated OBJ files,
//! against analytic values.

mod common;

use std::path::{Path, PathBuf};

use common::{Output, impulse};

use impulse_geom::{DVec3, PolyMesh, obj, primitives};

/// Relative agreement with closed forms for meshes that are exact (a box is its own mesh).
const EXACT: f64 = 1e-12;

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/meshes")
}

/// A scratch directory for one test's files (removed when the test ends).
fn scratch(test: &str) -> common::Scratch {
    common::Scratch::new(&format!("massprops-{test}"))
}

fn run(args: &[&str]) -> Output {
    impulse(args)
}

fn num(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn box_matches_the_closed_form_exactly() {
    let path = fixtures().join("cube20.obj");
    let out = run(&["massprops", path.to_str().unwrap(), "--density", "2.5"]);
    assert!(out.ok, "{}", out.stderr);
    let j = out.json.unwrap();
    // Side 20: V = 8000, m = ρV, I = m(20² + 20²)/12 about every axis, no products.
    let m = 2.5 * 8000.0;
    assert!(rel(num(&j["volume"]), 8000.0) < EXACT);
    assert!(rel(num(&j["mass"]), m) < EXACT);
    for r in 0..3 {
        assert!(num(&j["com"][r]).abs() < EXACT);
        assert!(rel(num(&j["principal_moments"][r]), m * 800.0 / 12.0) < EXACT);
        for c in 0..3 {
            let want = if r == c { m * 800.0 / 12.0 } else { 0.0 };
            assert!((num(&j["inertia"][r][c]) - want).abs() < EXACT * m * 800.0 / 12.0);
        }
    }
}

#[test]
fn non_convex_genus_one_frame_matches_box_minus_hole() {
    let path = fixtures().join("frame.obj");
    let out = run(&["massprops", path.to_str().unwrap(), "--mass", "24"]);
    assert!(out.ok, "{}", out.stderr);
    let j = out.json.unwrap();
    // Outer 4×4×1 minus a 2×2×1 hole, density 2: I_zz = ρ(16·32 − 4·8)/12, I_xx = ρ(16·17 − 4·5)/12.
    assert!(rel(num(&j["volume"]), 12.0) < EXACT);
    assert!(rel(num(&j["inertia"][2][2]), 2.0 * 480.0 / 12.0) < EXACT);
    assert!(rel(num(&j["inertia"][0][0]), 2.0 * 252.0 / 12.0) < EXACT);
}

#[test]
fn geodesic_sphere_level_6_is_within_the_polyhedral_error() {
    let mesh = primitives::geodesic_sphere_mesh(6, 1.0).unwrap();
    let dir = scratch("geodesic");
    let path = dir.join("geodesic6.obj");
    obj::write(&mesh, &path).unwrap();
    let out = run(&["massprops", path.to_str().unwrap()]);
    assert!(out.ok, "{}", out.stderr);
    let j = out.json.unwrap();
    // The polyhedron lies between its inscribed sphere (radius = smallest face distance) and
    // the unit sphere through its vertices, so its volume and moments lie between theirs.
    let r_in = (0..mesh.face_count())
        .map(|f| {
            mesh.face_area_vector(f)
                .normalize()
                .dot(mesh.vertices()[mesh.face(f)[0] as usize])
        })
        .fold(f64::INFINITY, f64::min);
    let sphere_volume = |r: f64| 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    let sphere_moment = |r: f64| 0.4 * sphere_volume(r) * r * r;
    let v = num(&j["volume"]);
    assert!(sphere_volume(r_in) < v && v < sphere_volume(1.0), "{v}");
    for k in 0..3 {
        let i = num(&j["principal_moments"][k]);
        assert!(sphere_moment(r_in) < i && i < sphere_moment(1.0), "{i}");
        assert!(num(&j["com"][k]).abs() < 1e-13);
    }
    // Thesis Table 6.2, approximation 6: T_1 = 4.187 (to its printed digits).
    assert!((v - 4.187).abs() <= 5e-4, "{v}");
    std::fs::remove_file(path).ok();
}

#[test]
fn an_open_mesh_is_refused_naming_the_problem() {
    let cube = primitives::cuboid_mesh(DVec3::ONE).unwrap();
    let open = PolyMesh::new(cube.vertices().to_vec(), cube.faces().take(5)).unwrap();
    let dir = scratch("open");
    let path = dir.join("open.obj");
    obj::write(&open, &path).unwrap();
    let out = run(&["massprops", path.to_str().unwrap()]);
    assert!(!out.ok);
    assert!(out.json.is_none());
    assert!(
        out.stderr.contains("open") && out.stderr.contains("edge"),
        "{}",
        out.stderr
    );
    std::fs::remove_file(path).ok();
}

#[test]
fn bad_arguments_and_files_are_errors_not_panics() {
    let cube = fixtures().join("cube20.obj");
    let cube = cube.to_str().unwrap();
    for (args, needle) in [
        (vec!["massprops", cube, "--density", "-1"], "density"),
        (vec!["massprops", cube, "--density", "NaN"], "density"),
        (vec!["massprops", cube, "--mass", "0"], "mass"),
        (vec!["massprops", "no/such/file.obj"], "no/such/file.obj"),
    ] {
        let out = run(&args);
        assert!(!out.ok, "{args:?}");
        assert!(out.stderr.contains(needle), "{args:?}: {}", out.stderr);
        assert!(!out.stderr.contains("panicked"), "{}", out.stderr);
    }
    let dir = scratch("bad");
    let bad = dir.join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n").unwrap();
    let out = run(&["massprops", bad.to_str().unwrap()]);
    assert!(
        !out.ok && out.stderr.contains("bad.obj:4:"),
        "{}",
        out.stderr
    );
    std::fs::remove_file(bad).ok();
}
