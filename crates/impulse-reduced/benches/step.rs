//! FORK⁻¹S step cost (Table 1): end-effector step plus every internal link's pose, on 1 and 2
//! threads, for the bundled helix, ladder and robot arm; and the blended step (Table 2) with
//! 1, 2 and 4 models on the helix-200. `helix-400 previous/N=…` times the internal-link
//! update as it was before the batched kernel, in the same run as the current one.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use impulse_geom::Pose;
use impulse_reduced::blend::BlendedModel;
use impulse_reduced::reference::{Configuration, Load, StaticOptions, solve_statics};
use impulse_reduced::{ConstructOptions, ReducedModel, ReducedSim, scenes};

#[path = "common/previous.rs"]
mod previous;

fn single(c: &mut Criterion) {
    let cases = [
        ("helix-50", scenes::helix(50)),
        ("helix-100", scenes::helix(100)),
        ("helix-400", scenes::helix(400)),
        ("ladder-48", scenes::ladder(48)),
        ("robot-arm-20", scenes::robot_arm(20)),
    ];
    for (name, desc) in cases {
        let m = desc.build().unwrap();
        let model = ReducedModel::build(
            &m,
            &Configuration::rest(&m),
            &[],
            &ConstructOptions::default(),
        )
        .unwrap();
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut s = ReducedSim::new(&m, model.clone(), 1e-3).unwrap();
            s.external[0] = 1.0;
            let mut out = vec![Pose::IDENTITY; s.model.internal.len()];
            // Each timed batch runs inside the pool: a step's parallel section then costs what
            // it costs in a simulation loop, not a cross-thread hand-off per iteration.
            c.bench_function(&format!("{name}/N={threads}"), |b| {
                b.iter_custom(|iters| {
                    pool.install(|| {
                        let t = std::time::Instant::now();
                        for _ in 0..iters {
                            s.step();
                            s.internal_poses(&mut out);
                        }
                        t.elapsed()
                    })
                });
            });
            if name == "helix-400" {
                c.bench_function(&format!("{name} previous/N={threads}"), |b| {
                    b.iter_custom(|iters| {
                        pool.install(|| {
                            let t = std::time::Instant::now();
                            for _ in 0..iters {
                                s.step();
                                previous::update_internal_links(
                                    &s.model,
                                    &s.xi,
                                    &Pose::IDENTITY,
                                    &mut out,
                                );
                            }
                            t.elapsed()
                        })
                    });
                });
            }
        }
    }
}

/// The linearisation points need not be converged to round-off for a timing.
const BENCH_STATIC_TOLERANCE: f64 = 1e-9;

fn blended(c: &mut Criterion) {
    let m = scenes::helix(200).build().unwrap();
    let link = m.end_effectors[0];
    let mut models = vec![
        ReducedModel::build(
            &m,
            &Configuration::rest(&m),
            &[],
            &ConstructOptions::default(),
        )
        .unwrap(),
    ];
    for s in [5.0, 10.0, 15.0] {
        let load = Load {
            link,
            force: DVec3::new(s, 0.0, 0.0),
            torque: DVec3::ZERO,
        };
        let options = StaticOptions {
            load_steps: 4,
            tolerance: BENCH_STATIC_TOLERANCE,
            ..Default::default()
        };
        let sol = solve_statics(&m, &[load], None, &options).unwrap();
        models.push(
            ReducedModel::build(&m, &sol.config, &[load], &ConstructOptions::default()).unwrap(),
        );
    }
    let rest: Vec<Pose> = m.end_effectors.iter().map(|&e| m.links[e].rest).collect();
    for k in [1, 2, 4] {
        let set =
            BlendedModel::new(models[..k].to_vec(), rest.clone(), m.bounding_radius()).unwrap();
        let ee = vec![rest[0] * Pose::from_translation(DVec3::new(0.01, 0.0, 0.0))];
        c.bench_function(&format!("helix-200 blended/{k} models"), |b| {
            b.iter(|| {
                let blend = set.blend(&ee).unwrap();
                set.internal_poses_of(&ee, &blend)
            });
        });
    }
}

criterion_group!(benches, single, blended);
criterion_main!(benches);
