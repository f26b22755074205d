//! Tests of a held compound pair's step: the clearance bound ([`World::clearance_step`]) keeps
//! the piece pairs that do not touch apart by the step alone (they are not in the collision
//! heap while the pair is held), and a sphere piece turns without bringing any feature
//! (`TurnSide::of_piece`); judged by the independent penetration monitor and closed forms
//! (a block sliding under Coulomb friction, a dumbbell rolling).

use crate::monitor::PenetrationMonitor;
use crate::scene::{BodyDesc, ContactDesc, PartDesc, Scene, SceneDesc, ShapeDesc};
use crate::sustained::{ContactMode, SustainedSettings};
use crate::world::World;

/// Collision envelope ε_c (m).
const EPS: f64 = 1e-4;

/// Gravity (m/s²).
const G: f64 = 9.81;

/// Friction coefficient of the floor: the block slides into the ledge, slowed.
const MU: f64 = 0.05;

/// The block's launch speed (m/s), toward the ledge: held (below the rotation limit of
/// `hold.rs` at this ε_c) and fast enough to cross ε_c within a nominal step.
const V0: f64 = 0.3;

/// Half extents of the block (m).
const BLOCK: [f64; 3] = [0.02, 0.02, 0.01];

/// Where the ledge's face stands (x, m), and where the block's front face starts.
const LEDGE_X: f64 = 0.15;
const FRONT_X0: f64 = 0.10;

/// How often the independent monitor looks (s): the block moves ¾ ε_c between looks.
const LOOK: f64 = 2.5e-4;

/// A fixed floor made of two pieces, a plate and a ledge standing on it at `LEDGE_X`, and a
/// block sliding on the plate toward the ledge at `V0`, resting half the envelope up.
fn ledge_scene() -> SceneDesc {
    let floor = ShapeDesc::compound(vec![
        PartDesc::new(ShapeDesc::cuboid([0.5, 0.2, 0.01])).at([0.0, 0.0, -0.01]),
        PartDesc::new(ShapeDesc::cuboid([0.05, 0.2, 0.01])).at([LEDGE_X + 0.05, 0.0, 0.01]),
    ]);
    SceneDesc::new()
        .with_collision_epsilon(EPS)
        .with_contact_model(ContactMode::Switching)
        .with_gravity([0.0, 0.0, -G])
        .with_default_contact(ContactDesc::new(MU, 0.0))
        .with_body(BodyDesc::fixed("floor", floor))
        .with_body(
            BodyDesc::new("block", ShapeDesc::cuboid(BLOCK))
                .at([FRONT_X0 - BLOCK[0], 0.0, BLOCK[2] + 0.5 * EPS])
                .with_velocity([V0, 0.0, 0.0])
                .with_density(1000.0),
        )
}

/// A block sliding on a compound floor toward a ledge of the same body reaches it as the
/// closed form says (decelerating at μg from `V0`), stops against it (restitution 0), and
/// never enters it by more than ε_c (the independent monitor, every [`LOOK`], and the block's
/// own front face against the ledge's plane). While it slides it is held with long steps:
/// sliding along the plate brings no feature of the touching pieces closer, and the ledge's
/// clearance bounds the step only as it comes near (each step takes at most half of what is
/// left). With the step judged by the whole sliding speed, as before the bound, it took
/// 1 066 island steps before it neared the ledge (29 now, steady steps); with the clearance
/// bound removed, the long steps carried it 1.9 ε_c into the ledge.
#[test]
fn a_block_sliding_into_a_ledge_of_its_floor_is_stopped_at_its_face() {
    let mut world = World::from_scene(&Scene::new(ledge_scene(), ".")).expect("a valid scene");
    let block = world.handle("block").expect("named");
    // Closed form: the front face reaches the ledge at t₁ with speed v₁.
    let a = MU * G;
    let d = LEDGE_X - FRONT_X0;
    let v1 = (V0 * V0 - 2.0 * a * d).sqrt();
    let t1 = (V0 - v1) / a;
    let mut monitor = PenetrationMonitor::new();
    let mut steps_before = 0;
    let mut deepest_front: f64 = f64::NEG_INFINITY;
    let mut t = 0.0;
    while t < t1 + 0.1 {
        t += LOOK;
        let report = world.step_until(t).expect("runs");
        if t < t1 - 0.01 {
            steps_before += report.counters.island_steps;
            // On the way, the closed form of sliding holds.
            let x = world.state(block).expect("live").position.x + BLOCK[0];
            let reference = FRONT_X0 + V0 * t - 0.5 * a * t * t;
            assert!(
                (x - reference).abs() < 1e-3 * d,
                "t {t:.4}: front at {x:.6}, closed form {reference:.6}"
            );
        }
        monitor.sample(&world);
        deepest_front = deepest_front.max(world.state(block).expect("live").position.x + BLOCK[0]);
    }
    let end = world.state(block).expect("live");
    let front = end.position.x + BLOCK[0];
    println!(
        "ledge: {steps_before} island steps before {:.3} s, front at {:.3e} ε_c from the ledge, deepest {:.3e} ε_c, monitor {:.3e}",
        t1 - 0.01,
        (front - LEDGE_X) / EPS,
        (deepest_front - LEDGE_X) / EPS,
        monitor.report().max_depth / EPS
    );
    assert!(monitor.report().max_depth <= EPS, "{:?}", monitor.report());
    assert!(
        deepest_front <= LEDGE_X + EPS,
        "front reached {deepest_front}"
    );
    // It got there, and stopped.
    assert!(front >= LEDGE_X - 2.0 * EPS, "front at {front}");
    assert!(
        end.velocity.length() < 1e-3 * v1,
        "still moving at {}",
        end.velocity
    );
    // Held with long steps while sliding: at most a step per nominal step, and a few more.
    let nominal = (t1 - 0.01) / SustainedSettings::default().step;
    assert!(
        f64::from(u32::try_from(steps_before).expect("counted")) <= 1.1 * nominal + 10.0,
        "{steps_before} island steps for {nominal:.0} nominal ones"
    );
}

/// A dumbbell (two balls of radius 2 cm on an axle, 0.1 m from its centre each way) rolling
/// on a level floor at 5 cm/s about its axle: rolling without slip on a level plane keeps its
/// speed and its height (closed form), and its island steps at the nominal rate, since each
/// ball turns about its own centre without bringing any feature and the axle is far above
/// the floor (136 island steps in the second: steady steps). Judged by its whole reach times
/// ‖ω‖ (0.3 m/s of turning), it took 5 566, against 1 000 nominal ones.
#[test]
fn a_rolling_dumbbell_keeps_its_speed_and_the_nominal_step() {
    let (r, d, v0) = (0.02, 0.1, 0.05);
    let ball = |y: f64| PartDesc::new(ShapeDesc::sphere(r)).at([0.0, y, 0.0]);
    let dumbbell = ShapeDesc::compound(vec![
        ball(-d),
        ball(d),
        PartDesc::new(ShapeDesc::cuboid([0.004, d, 0.004])),
    ]);
    let desc = SceneDesc::new()
        .with_collision_epsilon(EPS)
        .with_contact_model(ContactMode::Switching)
        .with_gravity([0.0, 0.0, -G])
        .with_default_contact(ContactDesc::new(0.5, 0.0))
        .with_body(
            BodyDesc::fixed("floor", ShapeDesc::cuboid([1.0, 1.0, 0.01])).at([0.0, 0.0, -0.01]),
        )
        .with_body(
            BodyDesc::new("dumbbell", dumbbell)
                .at([0.0, 0.0, r + 0.5 * EPS])
                .with_velocity([v0, 0.0, 0.0])
                .with_angular_velocity([0.0, v0 / r, 0.0])
                .with_density(7800.0),
        );
    let mut world = World::from_scene(&Scene::new(desc, ".")).expect("a valid scene");
    let body = world.handle("dumbbell").expect("named");
    let mut monitor = PenetrationMonitor::new();
    let (mut steps, mut worst_speed, mut lowest): (u64, f64, f64) = (0, 0.0, f64::INFINITY);
    let mut t = 0.0;
    while t < 1.0 {
        t += LOOK;
        steps += world.step_until(t).expect("runs").counters.island_steps;
        monitor.sample(&world);
        let s = world.state(body).expect("live");
        worst_speed = worst_speed.max((s.velocity.length() - v0).abs());
        lowest = lowest.min(s.position.z - r);
    }
    println!(
        "dumbbell: {steps} island steps, speed off by {worst_speed:.3e}, lowest {:.3e} ε_c",
        lowest / EPS
    );
    assert!(worst_speed <= 1e-6 * v0, "speed off by {worst_speed}");
    assert!(lowest >= -EPS, "the balls sank {lowest}");
    assert!(monitor.report().max_depth <= EPS, "{:?}", monitor.report());
    let nominal = 1.0 / SustainedSettings::default().step;
    assert!(
        steps as f64 <= 1.1 * nominal + 10.0,
        "{steps} island steps for {nominal:.0} nominal ones"
    );
}

/// Simulated time (s) of the bundled feeder chute (all of it) that
/// [`the_fast_way_ends_early_only_where_the_manifolds_would_fail_it`] runs.
const CHUTE_SPAN: f64 = 3.5;

/// The fast way of holding a compound pair ends before making the manifolds at its reach
/// when the piece pairs measured beyond that reach already bound the clearance too low
/// (`hold.rs`). That must never change a decision: the bundled feeder chute's caps (two-piece
/// compounds sliding and tumbling down the tray) run bit for bit as when the manifolds are
/// always made, and the bound did end the fast way early.
#[test]
fn the_fast_way_ends_early_only_where_the_manifolds_would_fail_it() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/scenes/feeder-chute.ron");
    let scene = Scene::read(&path).expect("the bundled feeder chute");
    let run = |bounded: bool| {
        let mut w = World::from_scene(&scene).expect("valid");
        w.faults.no_clearance_bound = !bounded;
        w.step_until(CHUTE_SPAN).unwrap();
        let exits = w
            .faults
            .clearance_bound_exits
            .load(std::sync::atomic::Ordering::Relaxed);
        let bits: Vec<u64> = w
            .states()
            .iter()
            .flat_map(|s| [s.position, s.velocity, s.omega])
            .flat_map(|v| v.to_array())
            .map(f64::to_bits)
            .collect();
        (bits, exits)
    };
    let (bounded, exits) = run(true);
    let (full, none) = run(false);
    assert_eq!(none, 0);
    assert!(
        exits > 100,
        "the bound ended the fast way early {exits} times"
    );
    assert_eq!(bounded, full, "a decision changed");
}
