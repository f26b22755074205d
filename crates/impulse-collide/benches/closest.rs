//! Closest-feature queries, warm (coherent) and cold (thesis §2.2.1, Figure 2.5).
//!
//! A geodesic sphere turns about an axis parallel to the nearest face of a fixed cube by a
//! fixed angle per query (1°, 5°, 20°), at two resolutions 16× apart in feature count (levels 2
//! and 4: 242 and 3,842 features). `warm` starts each query from the previous answer; `cold`
//! starts from vertex 0. Also printed: the mean number of feature steps per query.
//!
//! `smooth`: the rattleback's query, an ellipsoid (10 × 3 × 2 cm) spinning 1° per query and
//! rocking 1° just above a table (gap 5e-5 m): the exact ellipsoid by GJK against the inscribed
//! polyhedron (geodesic level 4) by V-Clip, both warm-started. Also printed: mean GJK
//! iterations and the polyhedron's distance error against the exact one.
//! Run: `cargo bench -p impulse-collide --bench closest`.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use glam::{DQuat, DVec3};
use impulse_collide::gjk::{self, SupportBody};
use impulse_collide::{FeaturePair, vclip};
use impulse_geom::{ConvexPolyhedron, Ellipsoid, Pose, primitives};

/// Queries per revolution sample.
const POSES: usize = 360;

fn closest(c: &mut Criterion) {
    let cube = primitives::cuboid(DVec3::splat(0.5)).expect("cube");
    let mut group = c.benchmark_group("closest");
    for level in [2u32, 4] {
        let ball = primitives::geodesic_sphere(level, 0.4).expect("sphere");
        for degrees in [1.0f64, 5.0, 20.0] {
            // The sphere's centre sits 1 unit from the cube's centre along x; it spins about z.
            let poses: Vec<Pose> = (0..POSES)
                .map(|i| {
                    let q = DQuat::from_rotation_z((degrees * i as f64).to_radians());
                    Pose::new(q, DVec3::new(1.0, 0.1, 0.05))
                })
                .collect();
            let (mut cache, mut warm_steps, mut cold_steps) = (FeaturePair::default(), 0u64, 0u64);
            for p in &poses {
                let w = vclip::closest(&cube, &Pose::IDENTITY, &ball, p, cache);
                cache = w.features;
                warm_steps += u64::from(w.steps);
                cold_steps += u64::from(
                    vclip::closest(&cube, &Pose::IDENTITY, &ball, p, FeaturePair::default()).steps,
                );
            }
            let features = ball.vertices().len() + ball.edges().len() + ball.face_count();
            eprintln!(
                "level {level} ({features} features), {degrees}°/query: steps/query warm {:.2}, cold {:.2}",
                warm_steps as f64 / POSES as f64,
                cold_steps as f64 / POSES as f64
            );
            let id = format!("L{level}/{degrees}deg");
            group.bench_function(BenchmarkId::new("warm", &id), |b| {
                let mut k = 0;
                let mut cache = FeaturePair::default();
                b.iter(|| {
                    let c = vclip::closest(&cube, &Pose::IDENTITY, &ball, &poses[k % POSES], cache);
                    cache = c.features;
                    k += 1;
                    black_box(c.distance)
                })
            });
            group.bench_function(BenchmarkId::new("cold", &id), |b| {
                let mut k = 0;
                b.iter(|| {
                    let c = vclip::closest(
                        &cube,
                        &Pose::IDENTITY,
                        &ball,
                        &poses[k % POSES],
                        FeaturePair::default(),
                    );
                    k += 1;
                    black_box(c.distance)
                })
            });
        }
    }
    group.finish();
}

fn smooth(c: &mut Criterion) {
    let axes = DVec3::new(0.1, 0.03, 0.02);
    let egg = Ellipsoid::new(axes).expect("ellipsoid");
    let mesh = primitives::geodesic_sphere_mesh(4, 1.0).expect("mesh");
    let pts: Vec<DVec3> = mesh.vertices().iter().map(|v| *v * axes).collect();
    let faceted = ConvexPolyhedron::hull(&pts).expect("hull");
    let table = primitives::cuboid(DVec3::new(0.6, 0.6, 0.02)).expect("table");
    let table_pose = Pose::from_translation(DVec3::new(0.0, 0.0, -0.02));
    let gap = 5e-5;
    let poses: Vec<Pose> = (0..POSES)
        .map(|i| {
            let a = (i as f64).to_radians();
            let q = DQuat::from_rotation_z(a) * DQuat::from_rotation_x(a.sin().to_radians());
            let drop = (q.inverse() * DVec3::Z * axes).length();
            Pose::new(q, DVec3::new(0.0, 0.0, drop + gap))
        })
        .collect();
    let (mut hints, mut iterations, mut worst) = (FeaturePair::default(), 0u64, 0.0f64);
    let mut vhints = FeaturePair::default();
    for p in &poses {
        let g = gjk::closest(
            &SupportBody::Ellipsoid(&egg, p),
            &SupportBody::Polyhedron(&table, &table_pose),
            hints,
        );
        hints = g.features;
        iterations += u64::from(g.steps);
        let v = vclip::closest(&faceted, p, &table, &table_pose, vhints);
        vhints = v.features;
        worst = worst.max((v.distance - g.distance).abs());
    }
    eprintln!(
        "smooth: GJK iterations/query {:.2}; faceted (level 4) distance error up to {worst:.2e} m at a {gap:e} m gap",
        iterations as f64 / POSES as f64
    );
    let mut group = c.benchmark_group("smooth");
    group.bench_function("gjk ellipsoid", |b| {
        let (mut k, mut hints) = (0, FeaturePair::default());
        b.iter(|| {
            let r = gjk::closest(
                &SupportBody::Ellipsoid(&egg, &poses[k % POSES]),
                &SupportBody::Polyhedron(&table, &table_pose),
                hints,
            );
            hints = r.features;
            k += 1;
            black_box(r.distance)
        })
    });
    group.bench_function("vclip faceted", |b| {
        let (mut k, mut hints) = (0, FeaturePair::default());
        b.iter(|| {
            let r = vclip::closest(&faceted, &poses[k % POSES], &table, &table_pose, hints);
            hints = r.features;
            k += 1;
            black_box(r.distance)
        })
    });
    group.finish();
}

criterion_group!(benches, closest, smooth);
criterion_main!(benches);
