//! Contact manifolds: the cost of one manifold per touching pair, as an island solver would
//! ask for it every step.
//!
//! - `box_on_floor`: a box lying on a floor face to face (four points), the normal known
//!   (`manifold_along`, the solver's path) and found from the closest features
//!   (`convex_manifold`: at a gap of ε_c/2 from the closest points, just touching from the
//!   separating axis).
//! - `octagon`: a block turned 45° on an equal block: eight clipped corners reduced to four.
//! - `edge`: a box tilted onto its low edge (two points).
//! - `ball`: a geodesic sphere (level 3, 642 vertices) resting on a box, its supporting vertex
//!   searched from the last contact (`warm`) and from vertex 0 (`cold`); an exact sphere.
//!
//! Run: `cargo bench -p impulse-collide --bench manifold`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{DQuat, DVec3};
use impulse_collide::manifold::{convex_manifold, manifold_along};
use impulse_collide::shape::convex_closest;
use impulse_collide::{Convex, Feature, FeaturePair};
use impulse_geom::{Pose, Sphere, primitives};

/// ε_c of the scenes (m).
const TOL: f64 = 1e-4;

fn cuboid(h: DVec3) -> Convex {
    Convex::Polyhedron(primitives::cuboid(h).expect("box"))
}

fn manifolds(c: &mut Criterion) {
    let mut group = c.benchmark_group("manifold");
    let floor = cuboid(DVec3::new(1.0, 1.0, 0.1));
    let pf = Pose::from_translation(DVec3::new(0.0, 0.0, -0.1));
    let bx = cuboid(DVec3::new(0.1, 0.05, 0.02));
    let flat = Pose::new(DQuat::from_rotation_z(0.3), DVec3::new(0.1, 0.2, 0.02));
    let n = -DVec3::Z;
    let warm = FeaturePair::default();
    group.bench_function("box_on_floor/along", |b| {
        b.iter(|| manifold_along(&bx, black_box(&flat), &floor, &pf, n, warm, TOL))
    });
    for (name, lift) in [("points", 0.5 * TOL), ("axis", 0.0)] {
        let pb = Pose::new(flat.rotation, flat.translation + DVec3::Z * lift);
        let closest = convex_closest(&bx, &pb, &floor, &pf, warm);
        group.bench_function(format!("box_on_floor/closest_{name}"), |b| {
            b.iter(|| convex_manifold(&bx, black_box(&pb), &floor, &pf, &closest, TOL))
        });
    }
    let block = cuboid(DVec3::new(0.05, 0.05, 0.025));
    let lower = Pose::from_translation(DVec3::new(0.0, 0.0, -0.025));
    let upper = Pose::new(
        DQuat::from_rotation_z(std::f64::consts::FRAC_PI_4),
        DVec3::new(0.0, 0.0, 0.025),
    );
    group.bench_function("octagon/along", |b| {
        b.iter(|| manifold_along(&block, black_box(&upper), &block, &lower, n, warm, TOL))
    });
    let theta: f64 = 0.2;
    let tilted = Pose::new(
        DQuat::from_rotation_x(theta),
        DVec3::new(0.0, 0.0, 0.05 * theta.sin() + 0.02 * theta.cos()),
    );
    group.bench_function("edge/along", |b| {
        b.iter(|| manifold_along(&bx, black_box(&tilted), &floor, &pf, n, warm, TOL))
    });
    let ball = Convex::Polyhedron(primitives::geodesic_sphere(3, 0.1).expect("ball"));
    let Convex::Polyhedron(p) = &ball else {
        unreachable!()
    };
    let lowest = p.vertex(p.support(-DVec3::Z));
    let pb = Pose::from_translation(DVec3::new(0.0, 0.0, -lowest.z));
    let m = manifold_along(&ball, &pb, &floor, &pf, n, warm, TOL)
        .expect("input")
        .expect("touching");
    let near = FeaturePair {
        a: m.points()[0].id.a,
        b: m.points()[0].id.b,
    };
    let cold = FeaturePair {
        a: Feature::Vertex(0),
        b: Feature::Vertex(0),
    };
    for (name, start) in [("warm", near), ("cold", cold)] {
        group.bench_function(format!("ball/geodesic3_{name}"), |b| {
            b.iter(|| manifold_along(&ball, black_box(&pb), &floor, &pf, n, start, TOL))
        });
    }
    let sphere = Convex::Sphere(Sphere::new(0.1).expect("sphere"));
    let ps = Pose::from_translation(DVec3::new(0.0, 0.0, 0.1));
    group.bench_function("ball/exact", |b| {
        b.iter(|| manifold_along(&sphere, black_box(&ps), &floor, &pf, n, warm, TOL))
    });
    group.finish();
}

criterion_group!(benches, manifolds);
criterion_main!(benches);
