//! Where a helix-400 step's time goes: the end-effector step, the twist maps and the
//! exponential map each alone, the internal links' kernel, and the whole 1-thread step; the
//! `previous/` cases time the update as it was before the batched kernel, in the same run.

use criterion::{Criterion, criterion_group, criterion_main};
use impulse_geom::{Pose, Twist};
use impulse_reduced::internal::{
    EXP_POLY_ANGLE, InternalLinks, equivalent_wrenches, link_twist, place,
};
use impulse_reduced::reference::Configuration;
use impulse_reduced::{ConstructOptions, ReducedModel, ReducedSim, scenes};

#[path = "common/previous.rs"]
mod previous;

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
    // The state the Table 1 bench runs in: the held 1 N load, stepped from rest for 20 s (the
    // linear model then turns most links by more than a radian, the exponential's
    // trigonometric side).
    let mut s = ReducedSim::new(&m, model.clone(), 1e-3).unwrap();
    s.external[0] = 1.0;
    for _ in 0..20_000 {
        s.step();
    }
    let w = equivalent_wrenches(&model, &s.xi);
    let angles: Vec<f64> = (0..model.internal.len())
        .map(|k| link_twist(&model, k, &w).w.length())
        .collect();
    println!(
        "helix-400 after 20 s under 1 N: link angles up to {:.2} rad, {} of {} above {} rad",
        angles.iter().fold(0.0_f64, |a, &x| a.max(x)),
        angles.iter().filter(|&&x| x >= EXP_POLY_ANGLE).count(),
        angles.len(),
        EXP_POLY_ANGLE
    );
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
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    // Times `iters` calls of `f` inside the 1-thread pool.
    let timed = |iters: u64, f: &mut (dyn FnMut() + Send)| {
        pool.install(|| {
            let t = std::time::Instant::now();
            for _ in 0..iters {
                f();
            }
            t.elapsed()
        })
    };
    let kernel = InternalLinks::new(&model);
    let mut out = vec![Pose::IDENTITY; model.internal.len()];
    c.bench_function("helix-400 parts/internal links, 1 thread", |b| {
        b.iter_custom(|iters| {
            timed(iters, &mut || {
                kernel.update(&s.xi, &Pose::IDENTITY, &mut out)
            })
        })
    });
    c.bench_function("helix-400 parts/previous/internal links, 1 thread", |b| {
        b.iter_custom(|iters| {
            timed(iters, &mut || {
                previous::update_internal_links(&model, &s.xi, &Pose::IDENTITY, &mut out);
            })
        })
    });
    c.bench_function("helix-400 parts/whole step, 1 thread", |b| {
        b.iter_custom(|iters| {
            timed(iters, &mut || {
                s.step();
                s.internal_poses(&mut out);
            })
        })
    });
    c.bench_function("helix-400 parts/previous/whole step, 1 thread", |b| {
        b.iter_custom(|iters| {
            timed(iters, &mut || {
                s.step();
                previous::update_internal_links(&s.model, &s.xi, &Pose::IDENTITY, &mut out);
            })
        })
    });
}

criterion_group!(benches, parts);
criterion_main!(benches);
