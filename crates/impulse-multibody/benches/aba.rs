//! Articulated-body forward dynamics on serial chains of 10, 50, 100 and 400 revolute links
//! with alternating axes (y, z, y, …), as in Pinocchio's benchmark; also inverse dynamics
//! (RNEA), the mass matrix (CRBA) and the multibody collision pieces for comparison.
//!
//! Reference: Pinocchio 4.1's ABA took 3.4, 18.3, 36.4 and 149 µs for 10, 50, 100 and 400
//! links (about 0.36 µs per joint); the project's target is at most 1.5× those.
//! Run: `cargo bench -p impulse-multibody`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use faer::Mat;
use glam::{DMat3, DQuat, DVec3};
use impulse_geom::{Pose, SpatialInertia};
use impulse_multibody::{
    BaseKind, ImpulseDynamics, JointSpec, Model, ModelBuilder, Workspace, forward_dynamics,
    inverse_dynamics, mass_matrix,
};
use std::hint::black_box;

/// A chain of `n` revolute links, axes alternating y and z, each link 0.2 m long along x with
/// a slightly rotated joint frame so no transform is trivial.
fn chain(n: usize) -> Model {
    let mut b = ModelBuilder::new(BaseKind::Fixed);
    let inertia = SpatialInertia::new(
        1.0,
        DVec3::new(0.1, 0.01, -0.02),
        DMat3::from_diagonal(DVec3::new(1e-3, 4e-3, 4.5e-3)),
    );
    b.link("ground", SpatialInertia::ZERO);
    let mut parent = "ground".to_owned();
    for k in 0..n {
        let name = format!("l{k}");
        let origin = Pose::new(
            DQuat::from_rotation_x(0.05),
            if k == 0 {
                DVec3::ZERO
            } else {
                DVec3::new(0.2, 0.0, 0.0)
            },
        );
        let axis = if k % 2 == 0 { DVec3::Y } else { DVec3::Z };
        b.link(&name, inertia).joint(JointSpec::revolute(
            &format!("j{k}"),
            &parent,
            &name,
            origin,
            axis,
        ));
        parent = name;
    }
    b.build().expect("valid chain")
}

fn state(n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let q = (0..n).map(|i| 0.1 * ((i * 7) % 13) as f64 - 0.6).collect();
    let v = (0..n)
        .map(|i| 0.05 * ((i * 5) % 11) as f64 - 0.25)
        .collect();
    let tau = (0..n).map(|i| 0.2 * ((i * 3) % 7) as f64 - 0.6).collect();
    (q, v, tau)
}

fn dynamics(c: &mut Criterion) {
    let mut group = c.benchmark_group("chain");
    for n in [10usize, 50, 100, 400] {
        let model = chain(n);
        let mut ws = Workspace::new(&model);
        let (q, v, tau) = state(n);
        let mut out = vec![0.0; n];
        group.throughput(Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::new("aba", n), &n, |b, _| {
            b.iter(|| {
                forward_dynamics(
                    &model,
                    &mut ws,
                    black_box(&q),
                    black_box(&v),
                    black_box(&tau),
                    None,
                    &mut out,
                )
                .expect("dimensions match");
                black_box(&out);
            })
        });
        group.bench_with_input(BenchmarkId::new("rnea", n), &n, |b, _| {
            b.iter(|| {
                inverse_dynamics(
                    &model,
                    &mut ws,
                    black_box(&q),
                    black_box(&v),
                    black_box(&tau),
                    None,
                    &mut out,
                )
                .expect("dimensions match");
                black_box(&out);
            })
        });
        let mut m = Mat::<f64>::zeros(n, n);
        group.bench_with_input(BenchmarkId::new("crba", n), &n, |b, _| {
            b.iter(|| {
                mass_matrix(&model, &mut ws, black_box(&q), &mut m).expect("dimensions match");
                black_box(&m);
            })
        });
        let mut imp = ImpulseDynamics::new(&model, &q).expect("dimensions match");
        let tip = model.link_id(&format!("l{}", n - 1)).expect("tip link");
        group.bench_with_input(BenchmarkId::new("collision_matrix", n), &n, |b, _| {
            b.iter(|| {
                imp.update(&model, black_box(&q)).expect("dimensions match");
                black_box(
                    imp.collision_matrix(&model, tip, DVec3::new(0.2, 0.0, 0.0), DMat3::IDENTITY)
                        .expect("valid link"),
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, dynamics);
criterion_main!(benches);
