//! Where a helix-400 step's time goes: the end-effector step, the equivalent wrenches, the
//! twist maps and the exponential map, each alone.

use criterion::{Criterion, criterion_group, criterion_main};
use impulse_geom::{Pose, Twist};
use impulse_reduced::internal::{equivalent_wrenches, link_twist, place};
use impulse_reduced::reference::Configuration;
use impulse_reduced::{ConstructOptions, ReducedModel, ReducedSim, scenes};

fn parts(c: &mut Criterion) {
    let m = scenes::helix(400).build().unwrap();
    let model = ReducedModel::build(
        &m,
        &Configuration::rest(&m),
        &[],
        &ConstructOptions::default(),
    )
    .unwrap();
    let mut s = ReducedSim::new(&m, model.clone(), 1e-3).unwrap();
    s.external[0] = 1.0;
    c.bench_function("helix-400 parts/end-effector step", |b| b.iter(|| s.step()));
    let w = equivalent_wrenches(&model, &s.xi);
    c.bench_function("helix-400 parts/twist maps", |b| {
        b.iter(|| {
            (0..model.internal.len())
                .map(|k| link_twist(&model, k, &w))
                .fold(Twist::ZERO, |a, t| a + t)
        })
    });
    let twists: Vec<Twist> = (0..model.internal.len())
        .map(|k| link_twist(&model, k, &w))
        .collect();
    c.bench_function("helix-400 parts/exp and compose", |b| {
        b.iter(|| {
            twists
                .iter()
                .zip(&model.internal_reference)
                .map(|(t, h)| *h * Pose::exp(t))
                .fold(0.0, |a, p| a + p.translation.x)
        })
    });
    c.bench_function("helix-400 parts/fast_exp and place", |b| {
        b.iter(|| {
            twists
                .iter()
                .zip(&model.internal_reference)
                .map(|(t, h)| place(h, t))
                .fold(0.0, |a, p| a + p.translation.x)
        })
    });
    let mut out = vec![Pose::IDENTITY; model.internal.len()];
    c.bench_function("helix-400 parts/whole step, 1 thread", |b| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        pool.install(|| {
            b.iter(|| {
                s.step();
                s.internal_poses(&mut out);
            })
        })
    });
}

criterion_group!(benches, parts);
criterion_main!(benches);
