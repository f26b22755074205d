//! Collision response cost per collision, by outcome: frictionless (closed form), sliding
//! throughout (numerical integration only), stable sticking (integration up to sticking, closed
//! form after it), unstable sticking (sliding resumes on the diverging ray), and the reversing
//! microcollision impulse (no integration). Each benchmark resolves a fixed set of `SET` random
//! collisions (random SPD K, u₀, μ, e; Stronge restitution; default settings), so the time per
//! collision is the reported time divided by `SET` (criterion's throughput column gives
//! collisions per second). `build_k` times eq. (3.4) for two rigid bodies plus validation.
//! Run: `cargo bench -p impulse-response`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::{DMat3, DVec3};
use impulse_response::{
    Body, CollisionMatrix, ContactFrame, MicrocollisionParams, ResponseKind, Restitution, Settings,
    resolve, resolve_with_microcollisions,
};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use std::hint::black_box;

/// Collisions per benchmark set.
const SET: usize = 64;

struct Case {
    k: CollisionMatrix,
    u0: DVec3,
    mu: f64,
    e: f64,
}

fn random_case(rng: &mut Xoshiro256PlusPlus) -> Case {
    let mut a = DMat3::ZERO;
    for c in 0..3 {
        *a.col_mut(c) = DVec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
    }
    let k = a * a.transpose() + DMat3::IDENTITY * rng.random_range(1e-3..0.5);
    let mut u0 = DVec3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        -rng.random_range(0.1..1.0),
    );
    if rng.random_range(0..4) == 0 {
        (u0.x, u0.y) = (0.0, 0.0); // from tangential rest: sticking or a ray from the start
    }
    Case {
        k: CollisionMatrix::new(k).expect("SPD by construction"),
        u0,
        mu: rng.random_range(0.0..1.5),
        e: rng.random_range(0.0..=1.0),
    }
}

/// `SET` random cases whose outcome satisfies `keep`.
fn cases(
    seed: u64,
    frictionless: bool,
    keep: impl Fn(&impulse_response::Response) -> bool,
) -> Vec<Case> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let s = Settings::default();
    let mut out = Vec::new();
    while out.len() < SET {
        let mut c = random_case(&mut rng);
        if frictionless {
            c.mu = 0.0;
        }
        if let Ok(r) = resolve(&c.k, c.u0, c.mu, c.e, Restitution::Stronge, &s)
            && keep(&r)
        {
            out.push(c);
        }
    }
    out
}

fn collisions(c: &mut Criterion) {
    let s = Settings::default();
    let sets = [
        ("frictionless", cases(1, true, |_| true)),
        (
            "sliding",
            cases(2, false, |r| {
                r.sticking.is_none() && r.stats.ray_approaches == 0
            }),
        ),
        (
            "sticking",
            cases(3, false, |r| r.sticking.is_some_and(|s| s.stable)),
        ),
        (
            "unstable_sticking",
            cases(4, false, |r| r.sticking.is_some_and(|s| !s.stable)),
        ),
    ];
    let mut group = c.benchmark_group("resolve");
    group.throughput(Throughput::Elements(SET as u64));
    for (name, set) in &sets {
        let (mut attempts, mut evals) = (0usize, 0usize);
        for cs in set {
            let r = resolve(&cs.k, cs.u0, cs.mu, cs.e, Restitution::Stronge, &s).expect("ok");
            attempts += r.stats.attempts;
            evals += r.stats.evaluations;
        }
        eprintln!(
            "{name}: mean RK step attempts {:.1}, mean RHS evaluations {:.1} per collision",
            attempts as f64 / SET as f64,
            evals as f64 / SET as f64
        );
        group.bench_with_input(BenchmarkId::new(*name, SET), set, |b, set| {
            b.iter(|| {
                for cs in set {
                    let r = resolve(
                        &cs.k,
                        black_box(cs.u0),
                        cs.mu,
                        cs.e,
                        Restitution::Stronge,
                        &s,
                    );
                    black_box(r.ok());
                }
            })
        });
    }
    // Microcollisions: resting contact, the reversing impulse (inside the cone).
    let params = MicrocollisionParams::default();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
    let mut micro = Vec::new();
    while micro.len() < SET {
        let mut cs = random_case(&mut rng);
        // Slow (a candidate, 0.05 < √(2·9.81·1e-3) = 0.14) and mostly normal: reversible.
        cs.u0 = DVec3::new(0.01, -0.01, -0.05);
        cs.mu = 2.0;
        let r = resolve_with_microcollisions(&cs.k, cs.u0, cs.mu, cs.e, 5e-4, &params, &s);
        if r.is_ok_and(|r| r.kind == ResponseKind::Reversing) {
            micro.push(cs);
        }
    }
    group.bench_with_input(BenchmarkId::new("microcollision", SET), &micro, |b, set| {
        b.iter(|| {
            for cs in set {
                let r = resolve_with_microcollisions(
                    &cs.k,
                    black_box(cs.u0),
                    cs.mu,
                    cs.e,
                    5e-4,
                    &params,
                    &s,
                );
                black_box(r.ok());
            }
        })
    });
    group.finish();
}

fn build_k(c: &mut Criterion) {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(6);
    let inertia = |rng: &mut Xoshiro256PlusPlus| {
        let d = DVec3::new(
            rng.random_range(0.1..1.0),
            rng.random_range(0.1..1.0),
            rng.random_range(0.1..1.0),
        );
        let q = DMat3::from_axis_angle(
            DVec3::new(0.3, -0.5, 0.8).normalize(),
            rng.random_range(0.0..6.0),
        );
        q * DMat3::from_diagonal(d) * q.transpose()
    };
    let b1 = Body::moving(2.0, inertia(&mut rng)).expect("valid");
    let b2 = Body::moving(0.5, inertia(&mut rng)).expect("valid");
    let frame = ContactFrame::from_normal(DVec3::new(0.2, 0.3, 0.9)).expect("valid");
    let (r1, r2) = (DVec3::new(0.1, -0.4, -0.5), DVec3::new(-0.2, 0.3, 0.4));
    c.bench_function("build_k", |b| {
        b.iter(|| CollisionMatrix::rigid(&b1, black_box(r1), &b2, black_box(r2), &frame))
    });
}

criterion_group!(benches, collisions, build_k);
criterion_main!(benches);
