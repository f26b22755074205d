//! Cost of the sustained-contact solver (`solve_contacts`) on resting stacks of n = 2…32
//! blocks (4 corner contacts per interface), at steady state: each measured step adds one step
//! of gravity (h = 1 ms) and solves warm-started from the previous step's impulses, as an
//! island at rest would be stepped. Criterion's throughput column gives contacts per second;
//! the sweeps a step needs are printed once per size (to the default tolerance 1e-9 m/s).
//! A second group times the first step of each stack from a cold start (the direct solve).
//! Run: `cargo bench -p impulse-response --bench contact`.
//!
//! What it showed (2026-12-02, release, loaded 2-core machine): 4.7 / 8.3 / 86 µs per step
//! for 2 / 4 / 8 blocks, but 16 and 32 blocks hit the 1000-sweep cap on every step even warm
//! (3.3 and 13.9 ms per step): from a cold start plain Gauss–Seidel needs 10 855 / 134 980 /
//! 1 656 584 sweeps for 8 / 16 / 32 blocks to reach 1e-9 m/s, in either contact order —
//! about n^3.6. See `docs/sustained-contact.md`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::{DMat3, DVec3};
use impulse_response::{Body, Contact, IslandBody, SolverSettings, solve_contacts};
use std::hint::black_box;

const G: f64 = 9.81;
const H: f64 = 1e-3;
/// Steps taken before measuring, so that the warm start has settled.
const SETTLE_STEPS: usize = 200;

/// A stack of `n` 10 × 7.5 × 5 cm blocks of 1.5 kg on the floor.
fn stack(n: usize) -> (Vec<IslandBody>, Vec<Contact>) {
    let (m, half) = (1.5, DVec3::new(0.05, 0.0375, 0.025));
    let s = half * half;
    let inertia = DMat3::from_diagonal(DVec3::new(s.y + s.z, s.x + s.z, s.x + s.y) * (m / 3.0));
    let mut bodies = Vec::new();
    let mut contacts = Vec::new();
    for k in 0..n {
        let com = DVec3::new(0.0, 0.0, (2 * k + 1) as f64 * half.z);
        bodies.push(IslandBody {
            body: Body::moving(m, inertia).expect("valid mass properties"),
            com,
            velocity: DVec3::ZERO,
            omega: DVec3::ZERO,
        });
        for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            contacts.push(Contact {
                body1: k,
                body2: k.checked_sub(1),
                point: com + DVec3::new(sx * half.x, sy * half.y, -half.z),
                normal: DVec3::Z,
                friction: 0.6,
                target_normal_velocity: 0.0,
                velocity_bias: DVec3::ZERO,
                lever_arms: None,
                impulse: DVec3::ZERO,
            });
        }
    }
    (bodies, contacts)
}

/// One step: gravity, then the contact solve; returns the sweeps it took.
fn step(bodies: &mut [IslandBody], contacts: &mut [Contact], settings: &SolverSettings) -> usize {
    for b in bodies.iter_mut() {
        b.velocity.z -= G * H;
    }
    let report = solve_contacts(bodies, contacts, settings).expect("valid island");
    report.iterations
}

fn bench_stacks(c: &mut Criterion) {
    let settings = SolverSettings::default();
    let mut group = c.benchmark_group("contact_stack_step");
    for n in [2usize, 4, 8, 16, 32] {
        let (mut bodies, mut contacts) = stack(n);
        let cold = step(&mut bodies, &mut contacts, &settings);
        for _ in 0..SETTLE_STEPS {
            step(&mut bodies, &mut contacts, &settings);
        }
        let warm = step(&mut bodies, &mut contacts, &settings);
        eprintln!("stack of {n}: {cold} sweeps on the first step, {warm} once warm");
        group.throughput(Throughput::Elements(contacts.len() as u64));
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| black_box(step(&mut bodies, &mut contacts, &settings)));
        });
    }
    group.finish();
}

/// The first step of a stack at rest from a cold start (no warm start): Gauss–Seidel cannot
/// carry the loads down a tall stack within its sweeps, so this times the direct solve
/// (`impulse_response::contact::DENSE_UP_TO`: dense LU for small systems, sparse beyond). Each
/// iteration solves a fresh copy.
fn bench_cold(c: &mut Criterion) {
    let settings = SolverSettings::default();
    let mut group = c.benchmark_group("contact_stack_cold");
    group.sample_size(10);
    for n in [8usize, 16, 32, 64] {
        let fresh = stack(n);
        group.throughput(Throughput::Elements(fresh.1.len() as u64));
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                let (mut bodies, mut contacts) = fresh.clone();
                black_box(step(&mut bodies, &mut contacts, &settings))
            });
        });
    }
    group.finish();
}

criterion_group!(benches, bench_stacks, bench_cold);
criterion_main!(benches);
