//! Tests of `step_until` itself: the quiet path a world at rest takes.

use glam::DVec3;

use crate::scene::{BodyDesc, ShapeDesc};
use crate::world::{World, WorldSettings};

/// Polling rate of the quiet-path test (calls of `step_until` per simulated second), as a
/// program drawing frames would call it.
const POLL_RATE: f64 = 100.0;

/// Half size of the cubes of [`add_touching_stack`] (m).
pub(super) const STACK_HALF: f64 = 0.05;

/// Adds a fixed floor and `n` cubes of half size [`STACK_HALF`] (density 700, named
/// `block0`, `block1`, …) stacked on it, each touching the one below.
pub(super) fn add_touching_stack(world: &mut World, n: u32) {
    world
        .add_body(
            &BodyDesc::fixed("floor", ShapeDesc::cuboid([0.5, 0.5, 0.05])).at([0.0, 0.0, -0.05]),
        )
        .expect("free space");
    let h = STACK_HALF;
    for k in 0..n {
        world
            .add_body(
                &BodyDesc::new(format!("block{k}"), ShapeDesc::cuboid([h, h, h]))
                    .at([0.0, 0.0, h + 2.0 * h * f64::from(k)])
                    .with_density(700.0),
            )
            .expect("free space");
    }
}

/// The bit patterns of a vector's components, for comparisons that must be exact.
fn bits(v: DVec3) -> [u64; 3] {
    v.to_array().map(f64::to_bits)
}

/// A stack of four blocks placed in contact, which sleeps, polled at [`POLL_RATE`] for 2 s;
/// then a ball added just above it lands on it and wakes it, and the run goes on to 3 s.
/// With the quiet path (calls while nothing moves and nothing is due only move the clock)
/// every body's final state, the clock and the loop's counters are bit for bit those of the
/// same run stepped by the event loop at every call, and the quiet path was taken for most
/// of the sleeping second.
#[test]
fn a_world_at_rest_steps_exactly_as_the_loop_would() {
    let run = |quiet: bool| {
        let mut settings = WorldSettings::new(1e-4);
        settings.default_contact.friction = 0.5;
        settings.default_contact.restitution = 0.3;
        let mut world = World::new(settings).expect("valid settings");
        world.faults.no_quiet_path = !quiet;
        add_touching_stack(&mut world, 4);
        let h = STACK_HALF;
        let mut k = 1u32;
        let mut poll_to = |world: &mut World, end: f64| {
            while f64::from(k) / POLL_RATE <= end {
                world.step_until(f64::from(k) / POLL_RATE).expect("runs");
                k += 1;
            }
        };
        poll_to(&mut world, 2.0);
        assert!(
            world
                .bodies()
                .all(|(_, b)| !b.is_dynamic() || b.is_asleep()),
            "the stack sleeps by 2 s"
        );
        world
            .add_body(
                &BodyDesc::new("ball", ShapeDesc::sphere(0.03))
                    .at([0.01, 0.0, 8.0 * h + 0.05])
                    .with_density(2000.0),
            )
            .expect("free space");
        poll_to(&mut world, 3.0);
        world
    };
    let (quiet, loop_only) = (run(true), run(false));
    assert!(
        quiet.faults.quiet_calls >= 100,
        "quiet path taken {} times",
        quiet.faults.quiet_calls
    );
    assert_eq!(loop_only.faults.quiet_calls, 0);
    assert_eq!(quiet.time().to_bits(), loop_only.time().to_bits());
    assert_eq!(quiet.counters(), loop_only.counters());
    let woken = quiet
        .bodies()
        .any(|(_, b)| b.is_dynamic() && !b.is_asleep())
        || quiet.counters().sleeps > 1;
    assert!(woken, "the ball woke the stack");
    for ((_, a), (_, b)) in quiet.bodies().zip(loop_only.bodies()) {
        assert_eq!(
            bits(a.pose.translation),
            bits(b.pose.translation),
            "{}",
            a.name
        );
        assert_eq!(bits(a.velocity), bits(b.velocity), "{}", a.name);
        assert_eq!(bits(a.omega), bits(b.omega), "{}", a.name);
        assert_eq!(a.is_asleep(), b.is_asleep(), "{}", a.name);
    }
}

/// A world with few moving bodies and its own pool (`set_threads`) brings them to the end of
/// each call on the calling thread: handing a few bodies to the pool costs more than their
/// work. With `set_parallel_min_bodies(0)` every call hands them to the pool, and the
/// trajectory is bit for bit the same.
#[test]
fn a_small_world_on_its_own_pool_stays_on_the_calling_thread() {
    let run = |threads: usize, min_bodies: Option<usize>| {
        let mut world = World::new(WorldSettings::new(1e-4)).expect("valid settings");
        world.set_threads(threads).expect("pool");
        if let Some(n) = min_bodies {
            world.set_parallel_min_bodies(n);
        }
        world
            .add_body(
                &BodyDesc::fixed("floor", ShapeDesc::cuboid([0.5, 0.5, 0.05]))
                    .at([0.0, 0.0, -0.05]),
            )
            .expect("free space");
        for k in 0..3 {
            world
                .add_body(
                    &BodyDesc::new(format!("cube{k}"), ShapeDesc::cuboid([0.02, 0.03, 0.04]))
                        .at([0.1 * f64::from(k), 0.0, 0.1])
                        .with_angular_velocity([1.0, 2.0 + f64::from(k), 3.0]),
                )
                .expect("free space");
        }
        // Every body is brought to the end of each call (`sync.rs`): 300 calls.
        for k in 1..=300 {
            world.step_until(f64::from(k) * 1e-3).expect("runs");
        }
        world
    };
    let (own, pooled) = (run(2, None), run(2, Some(0)));
    assert_eq!(
        own.faults.pool_steps, 0,
        "no step of 3 bodies enters the pool"
    );
    assert!(own.counters().steps > 10, "{} steps", own.counters().steps);
    assert!(
        pooled.faults.pool_steps > 100,
        "{} steps on the pool",
        pooled.faults.pool_steps
    );
    assert_eq!(own.counters(), pooled.counters());
    for ((_, a), (_, b)) in own.bodies().zip(pooled.bodies()) {
        assert_eq!(
            bits(a.pose.translation),
            bits(b.pose.translation),
            "{}",
            a.name
        );
        assert_eq!(bits(a.omega), bits(b.omega), "{}", a.name);
    }
}

/// `--profile`'s shares are of a total that holds every timed part: the bodies brought to
/// the requested time at the end of each `step_until` (a tumbling brick alone in space,
/// polled at 10 kHz: nothing but that bringing happens) are in the total too. Before, that
/// part was timed but left out of the total, and a bullet scene printed "rigid bodies
/// 787.6 %".
#[test]
fn profile_parts_fit_in_the_total() {
    let mut world = World::new(WorldSettings::new(1e-4)).expect("valid settings");
    world
        .add_body(
            &BodyDesc::new("brick", ShapeDesc::cuboid([0.03, 0.02, 0.01]))
                .with_angular_velocity([300.0, 20.0, 5.0]),
        )
        .expect("free space");
    world.set_profiling(true);
    for k in 1..=200 {
        world.step_until(f64::from(k) * 1e-4).expect("runs");
    }
    let p = world.profile().expect("profiling is on");
    assert!(p.rigid_bodies > std::time::Duration::ZERO, "nothing timed");
    let timed =
        p.multibody_dynamics + p.rigid_bodies + p.detection + p.response + p.islands + p.control;
    assert!(timed <= p.total, "timed {timed:?} > total {:?}", p.total);
    let sum: f64 = p.shares().iter().map(|(_, s)| s).sum();
    assert!((sum - 1.0).abs() < 1e-9, "shares sum to {sum}");
}
