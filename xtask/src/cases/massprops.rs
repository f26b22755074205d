//! Validation cases V1–V4 of the chapter-6 digest: exact mass properties of polyhedra.
//!
//! - V1: the ten volume integrals of Table 6.1 (cube of side 20, corner tetrahedron).
//! - V2: the assembled mass, centre of mass and centroidal inertia of the same bodies, against
//!   closed forms.
//! - V3: Table 6.2, geodesic approximations 1–6 of the unit sphere: counts, T₁ and T_x² to the
//!   printed digits, vanishing odd integrals, and T₁, T_x² between the inscribed and the
//!   circumscribed sphere's values.
//! - V4: invariance under rigid motion (translations up to 10³ body sizes), face reordering,
//!   start-vertex rotation and triangulation of polygon faces.

use glam::{DMat3, DQuat, DVec3};
use impulse_geom::{ConvexPolyhedron, PolyMesh, Pose, primitives};
use impulse_massprops::{MassProperties, VolumeIntegrals};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use crate::validate::case::{Case, Check, Metric};

/// Relative agreement with exact values (the thesis found ≥ 15 significant figures).
const EXACT_REL: f64 = 1e-12;
/// Absolute bound on integrals whose exact value is zero, for bodies of size ~20 (Table 6.1's
/// cube has second moments ~3e5, so this is ~1e-15 relative).
const ZERO_ABS: f64 = 1e-9;
/// Bound on the odd integrals of the geodesic spheres (exactly 0 by symmetry; size ~1).
const SPHERE_ZERO_ABS: f64 = 1e-13;
/// Invariance under rigid motions and re-meshing, relative (digest V4).
const INVARIANCE_REL: f64 = 1e-10;

/// The mass-property cases.
pub fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "V1-table-6.1",
            description: "ten volume integrals of the cube (side 20) and the tetrahedron (0, 5i, 4j, 3k) vs thesis Table 6.1",
            run: Box::new(v1_table_6_1),
        },
        Case {
            name: "V2-assembled",
            description: "mass, centre of mass and centroidal inertia of the Table 6.1 bodies vs closed forms",
            run: Box::new(v2_assembled),
        },
        Case {
            name: "V3-table-6.2",
            description: "geodesic spheres 1-6 vs thesis Table 6.2 (printed digits), odd integrals 0, inscribed < T < circumscribed",
            run: Box::new(v3_table_6_2),
        },
        Case {
            name: "V4-invariance",
            description: "mass properties invariant under rigid motion (1e3 sizes away), face order, start vertex, triangulation",
            run: Box::new(v4_invariance),
        },
    ]
}

fn tetrahedron() -> Result<PolyMesh, String> {
    primitives::corner_tetrahedron_mesh(DVec3::new(5.0, 4.0, 3.0)).map_err(|e| e.to_string())
}

fn cube20() -> Result<PolyMesh, String> {
    primitives::cuboid_mesh(DVec3::splat(10.0)).map_err(|e| e.to_string())
}

/// The ten integrals in Table 6.1's column order.
const COLUMNS: [&str; 10] = [
    "T1", "Tx", "Ty", "Tz", "Tx2", "Ty2", "Tz2", "Txy", "Tyz", "Tzx",
];

/// A metric judged relatively, or absolutely when the reference is zero.
fn near(name: String, value: f64, reference: f64) -> Metric {
    let check = if reference == 0.0 {
        Check::Abs(ZERO_ABS)
    } else {
        Check::Rel(EXACT_REL)
    };
    Metric::new(name, value, reference, check)
}

fn v1_table_6_1() -> Result<Vec<Metric>, String> {
    let table: [(&str, PolyMesh, [f64; 10]); 2] = [
        (
            "cube",
            cube20()?,
            [
                8000.0,
                0.0,
                0.0,
                0.0,
                800_000.0 / 3.0,
                800_000.0 / 3.0,
                800_000.0 / 3.0,
                0.0,
                0.0,
                0.0,
            ],
        ),
        (
            "tetra",
            tetrahedron()?,
            [10.0, 12.5, 10.0, 7.5, 25.0, 16.0, 9.0, 10.0, 6.0, 7.5],
        ),
    ];
    let mut out = Vec::new();
    for (body, mesh, want) in table {
        let got = VolumeIntegrals::of_mesh(&mesh)
            .map_err(|e| e.to_string())?
            .to_array();
        for k in 0..10 {
            out.push(near(format!("{body}.{}", COLUMNS[k]), got[k], want[k]));
        }
    }
    Ok(out)
}

/// The six independent entries of a symmetric tensor, named.
fn tensor_entries(m: DMat3) -> [(&'static str, f64); 6] {
    [
        ("Ixx", m.x_axis.x),
        ("Iyy", m.y_axis.y),
        ("Izz", m.z_axis.z),
        ("Ixy", m.y_axis.x),
        ("Iyz", m.z_axis.y),
        ("Izx", m.x_axis.z),
    ]
}

fn v2_assembled() -> Result<Vec<Metric>, String> {
    let mut out = Vec::new();
    // Corner tetrahedron with legs (a, b, c), ρ = 1: m = abc/6, r = (a, b, c)/4,
    // I_xx = 3m(b² + c²)/80 (cyclic), tensor off-diagonals +m·ab/80, +m·bc/80, +m·ca/80.
    let (a, b, c) = (5.0, 4.0, 3.0);
    let m = a * b * c / 6.0;
    let tetra_i = DMat3::from_cols(
        DVec3::new(
            3.0 * m * (b * b + c * c) / 80.0,
            m * a * b / 80.0,
            m * c * a / 80.0,
        ),
        DVec3::new(
            m * a * b / 80.0,
            3.0 * m * (c * c + a * a) / 80.0,
            m * b * c / 80.0,
        ),
        DVec3::new(
            m * c * a / 80.0,
            m * b * c / 80.0,
            3.0 * m * (a * a + b * b) / 80.0,
        ),
    );
    // Cube of side s = 20: m = s³, I = m·s²/6 on the diagonal.
    let cube_m = 8000.0;
    let cube_i = DMat3::from_diagonal(DVec3::splat(cube_m * 400.0 / 6.0));
    let bodies = [
        (
            "tetra",
            tetrahedron()?,
            m,
            DVec3::new(a, b, c) / 4.0,
            tetra_i,
        ),
        ("cube", cube20()?, cube_m, DVec3::ZERO, cube_i),
    ];
    for (body, mesh, mass, com, inertia) in bodies {
        let p = MassProperties::from_mesh(&mesh, 1.0).map_err(|e| e.to_string())?;
        out.push(near(format!("{body}.mass"), p.mass, mass));
        for k in 0..3 {
            out.push(near(
                format!("{body}.com.{}", ["x", "y", "z"][k]),
                p.com[k],
                com[k],
            ));
        }
        for ((name, got), (_, want)) in tensor_entries(p.inertia)
            .into_iter()
            .zip(tensor_entries(inertia))
        {
            out.push(near(format!("{body}.{name}"), got, want));
        }
    }
    Ok(out)
}

fn v3_table_6_2() -> Result<Vec<Metric>, String> {
    // Thesis Table 6.2: (verts, edges, faces, T_1, T_x²) for approximations 1–6.
    const TABLE: [(u32, f64, f64, f64, f64, f64); 6] = [
        (1, 12.0, 30.0, 20.0, 2.536, 0.3670),
        (2, 42.0, 120.0, 80.0, 3.659, 0.6692),
        (3, 162.0, 480.0, 320.0, 4.047, 0.7911),
        (4, 642.0, 1920.0, 1280.0, 4.153, 0.8258),
        (5, 2562.0, 7680.0, 5120.0, 4.180, 0.8347),
        (6, 10242.0, 30720.0, 20480.0, 4.187, 0.8370),
    ];
    // Half a unit in the last printed digit: T_1 has 3 decimals, T_x² has 4.
    const T1_PRINTED: f64 = 5e-4;
    const TX2_PRINTED: f64 = 5e-5;
    let sphere_t1 = |r: f64| 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    let sphere_tx2 = |r: f64| sphere_t1(r) * r * r / 5.0;
    let mut out = Vec::new();
    for (level, verts, edges, faces, t1, tx2) in TABLE {
        let poly = primitives::geodesic_sphere(level, 1.0).map_err(|e| e.to_string())?;
        let mesh = poly.mesh();
        let t = VolumeIntegrals::of_mesh(mesh).map_err(|e| e.to_string())?;
        let name = |s: &str| format!("approx{level}.{s}");
        out.push(Metric::new(
            name("verts"),
            poly.vertices().len() as f64,
            verts,
            Check::Exact,
        ));
        out.push(Metric::new(
            name("edges"),
            poly.edges().len() as f64,
            edges,
            Check::Exact,
        ));
        out.push(Metric::new(
            name("faces"),
            poly.face_count() as f64,
            faces,
            Check::Exact,
        ));
        out.push(Metric::new(
            name("T1"),
            t.volume,
            t1,
            Check::Abs(T1_PRINTED),
        ));
        out.push(Metric::new(
            name("Tx2"),
            t.second.x,
            tx2,
            Check::Abs(TX2_PRINTED),
        ));
        out.push(Metric::new(
            name("Tx"),
            t.first.x,
            0.0,
            Check::Abs(SPHERE_ZERO_ABS),
        ));
        out.push(Metric::new(
            name("Tyz"),
            t.products.y,
            0.0,
            Check::Abs(SPHERE_ZERO_ABS),
        ));
        // The polyhedron lies between its inscribed sphere (radius = least face distance) and
        // the unit sphere through its vertices; T_1 and T_x² are monotone in the body.
        let r_in = poly
            .planes()
            .iter()
            .map(|p| p.offset)
            .fold(f64::INFINITY, f64::min);
        out.push(Metric::new(
            name("T1.bracket"),
            t.volume,
            sphere_t1(1.0),
            Check::Between(sphere_t1(r_in), sphere_t1(1.0)),
        ));
        out.push(Metric::new(
            name("Tx2.bracket"),
            t.second.x,
            sphere_tx2(1.0),
            Check::Between(sphere_tx2(r_in), sphere_tx2(1.0)),
        ));
    }
    Ok(out)
}

/// Largest relative difference between two mass properties (mass, centre of mass relative to
/// its magnitude or the body size, inertia relative to its largest entry).
fn deviation(a: &MassProperties, b: &MassProperties, size: f64) -> f64 {
    let scale = b
        .inertia
        .to_cols_array()
        .iter()
        .fold(0.0f64, |m, x| m.max(x.abs()));
    let di = (a.inertia - b.inertia)
        .to_cols_array()
        .iter()
        .fold(0.0f64, |m, x| m.max(x.abs()))
        / scale;
    let dm = (a.mass - b.mass).abs() / b.mass;
    let dc = a.com.distance(b.com) / b.com.length().max(size);
    di.max(dm).max(dc)
}

fn remesh(mesh: &PolyMesh, f: impl Fn(Vec<Vec<u32>>) -> Vec<Vec<u32>>) -> Result<PolyMesh, String> {
    let faces = f(mesh.faces().map(<[u32]>::to_vec).collect());
    PolyMesh::new(mesh.vertices().to_vec(), faces).map_err(|e| e.to_string())
}

fn v4_invariance() -> Result<Vec<Metric>, String> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(4);
    let hull_points: Vec<DVec3> = (0..60)
        .map(|_| DVec3::new(rng.random(), rng.random(), rng.random()) * DVec3::new(3.0, 2.0, 1.0))
        .collect();
    let hull = ConvexPolyhedron::hull(&hull_points).map_err(|e| e.to_string())?;
    // Triangles (tetrahedron, random hull) and polygons (prism, frame), convex and not.
    let prism = primitives::regular_prism_mesh(12, 1.5, 0.4).map_err(|e| e.to_string())?;
    let bodies = [
        ("tetra", tetrahedron()?),
        ("hull60", hull.mesh().clone()),
        ("prism12", prism),
        ("frame", frame()?),
    ];
    let mut out = Vec::new();
    for (body, mesh) in bodies {
        let props = |m: &PolyMesh| MassProperties::from_mesh(m, 1.0).map_err(|e| e.to_string());
        let base = props(&mesh)?;
        let size = mesh.diameter();
        // Rigid motions: 100 random rotations, translations up to 10³ body sizes.
        let mut worst: f64 = 0.0;
        for _ in 0..100 {
            let q = DQuat::from_xyzw(
                rng.random::<f64>() - 0.5,
                rng.random::<f64>() - 0.5,
                rng.random::<f64>() - 0.5,
                rng.random::<f64>() - 0.5,
            )
            .normalize();
            let t = (DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * 2e3 * size;
            let pose = Pose::new(q, t);
            let moved = mesh
                .map_vertices(|v| pose.transform_point(v))
                .map_err(|e| e.to_string())?;
            worst = worst.max(deviation(&props(&moved)?, &base.transformed(&pose), size));
        }
        out.push(Metric::new(
            format!("{body}.rigid_motion"),
            worst,
            0.0,
            Check::Abs(INVARIANCE_REL),
        ));
        // Faces in reverse order.
        let reordered = remesh(&mesh, |mut f| {
            f.reverse();
            f
        })?;
        out.push(Metric::new(
            format!("{body}.face_order"),
            deviation(&props(&reordered)?, &base, size),
            0.0,
            Check::Abs(INVARIANCE_REL),
        ));
        // Every face loop started at a different vertex.
        let rotated = remesh(&mesh, |f| {
            f.into_iter()
                .enumerate()
                .map(|(i, mut l)| {
                    let k = i % l.len();
                    l.rotate_left(k);
                    l
                })
                .collect()
        })?;
        out.push(Metric::new(
            format!("{body}.start_vertex"),
            deviation(&props(&rotated)?, &base, size),
            0.0,
            Check::Abs(INVARIANCE_REL),
        ));
        // Every polygon split into a triangle fan.
        let triangulated = remesh(&mesh, |f| {
            f.into_iter()
                .flat_map(|l| (1..l.len() - 1).map(move |k| vec![l[0], l[k], l[k + 1]]))
                .collect()
        })?;
        out.push(Metric::new(
            format!("{body}.triangulated"),
            deviation(&props(&triangulated)?, &base, size),
            0.0,
            Check::Abs(INVARIANCE_REL),
        ));
    }
    Ok(out)
}

/// The square frame of `fixtures/meshes/frame.obj` (genus 1, non-convex), read from the file so
/// the bundled fixture is exercised too.
fn frame() -> Result<PolyMesh, String> {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/meshes/frame.obj");
    impulse_geom::obj::read(&path).map_err(|e| e.to_string())
}
