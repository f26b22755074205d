//! Closest-feature queries, warm (coherent) and cold (thesis §2.2.1, Figure 2.5).
//!
//! A geodesic sphere turns about an axis parallel to the nearest face of a fixed cube by a
//! fixed angle per query (1°, 5°, 20°), at two resolutions 16× apart in feature count (levels 2
//! and 4: 242 and 3,842 features). `warm` starts each query from the previous answer; `cold`
//! starts from vertex 0. Also printed: the mean number of feature steps per query.
//! Run: `cargo bench -p impulse-collide --bench closest`.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use glam::{DQuat, DVec3};
use impulse_collide::{FeaturePair, vclip};
use impulse_geom::{Pose, primitives};

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

criterion_group!(benches, closest);
criterion_main!(benches);
