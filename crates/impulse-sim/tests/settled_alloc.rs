//! A settled world costs nothing to step: a stack asleep allocates nothing (counted by dhat's
//! counting global allocator, in this test binary only), and the settled part sorter takes
//! no loop steps.

use impulse_sim::scene::{BodyDesc, ContactDesc, ShapeDesc};
use impulse_sim::{Scene, SceneDesc, World};

#[global_allocator]
static ALLOC: dhat::Alloc = dhat::Alloc;

/// Allocations made by `f` (blocks allocated, reallocations included).
fn allocations(f: impl FnOnce()) -> u64 {
    let _profiler = dhat::Profiler::builder().testing().build();
    let before = dhat::HeapStats::get().total_blocks;
    f();
    dhat::HeapStats::get().total_blocks - before
}

/// The allocator counts every thread's allocations, and dhat allows one profiler at a time:
/// the checks of this binary run one after another in this one test, so that no other test's
/// work is counted.
#[test]
fn settled_worlds() {
    the_counter_sees_an_allocation();
    a_sleeping_stack_steps_without_allocating();
    the_settled_part_sorter_takes_no_steps();
}

/// A stack of three blocks asleep on a floor: 1 000 steps, no allocation.
fn a_sleeping_stack_steps_without_allocating() {
    let eps = 1e-4;
    let mut desc = SceneDesc::new()
        .with_collision_epsilon(eps)
        .with_gravity([0.0, 0.0, -9.81])
        .with_default_contact(ContactDesc::new(0.5, 0.2))
        .with_body(
            BodyDesc::fixed("floor", ShapeDesc::cuboid([1.0, 1.0, 0.05])).at([0.0, 0.0, -0.05]),
        );
    for k in 0..3 {
        desc = desc.with_body(
            BodyDesc::new(format!("block{k}"), ShapeDesc::cuboid([0.05, 0.05, 0.05]))
                .at([
                    0.0,
                    0.0,
                    0.05 + 0.5 * eps + f64::from(k) * (0.1 + 0.5 * eps),
                ])
                .with_density(700.0),
        );
    }
    let mut world = World::from_scene(&Scene::new(desc, ".")).expect("a valid scene");
    world.set_rollback(false);
    world.step_until(3.0).expect("runs");
    let handles: Vec<_> = (0..3)
        .map(|k| world.handle(&format!("block{k}")).unwrap())
        .collect();
    assert!(
        handles.iter().all(|&h| world.body(h).unwrap().is_asleep()),
        "not asleep"
    );
    let made = allocations(|| {
        let mut t = 3.0;
        for _ in 0..1000 {
            t += 1e-3;
            world.step_until(t).expect("runs");
        }
    });
    println!("sleeping stack: {made} allocations in 1000 steps");
    assert_eq!(made, 0);
}

/// The counter counts: a vector made inside is one allocation.
fn the_counter_sees_an_allocation() {
    let made = allocations(|| {
        std::hint::black_box(vec![1.0_f64; 16]);
    });
    assert_eq!(made, 1);
}

/// The part sorter at its end: the parts asleep in their bins, the trap doors shut on their
/// stops. A multibody every joint of which rests on its stop is a fixed point of its motion,
/// and predicts none: a second of it takes a handful of loop steps, and the doors do not
/// move (their state is the same to the bit). When its links' predictions carried the
/// stopless acceleration, the pairs of the flaps with the track 0.5 mm away fell due 1 543
/// times a second.
fn the_settled_part_sorter_takes_no_steps() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/scenes/part-sorter.ron");
    let scene = Scene::read(&path).expect("the bundled scene");
    let mut world = World::from_scene(&scene).expect("a valid scene");
    world.step_until(6.0).expect("runs");
    let doors = |w: &World| -> Vec<f64> {
        w.multibody_handles()
            .into_iter()
            .flat_map(|h| {
                let sim = w.multibody(h).expect("live");
                sim.q().iter().chain(sim.v()).copied().collect::<Vec<_>>()
            })
            .collect()
    };
    let before = doors(&world);
    let steps = world.step_until(7.0).expect("runs").counters.steps;
    println!("settled part sorter: {steps} loop steps in 1 s");
    assert_eq!(doors(&world), before);
    assert!(steps <= 10, "{steps} loop steps");
}
