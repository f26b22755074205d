//! Tests of the program-facing world API, each against a closed form, a conservation law or
//! an independent measurement (the penetration monitor, not the loop's counters).

use glam::{DQuat, DVec3};

use crate::contact::ContactKind;
use crate::monitor::PenetrationMonitor;
use crate::scene::{BodyDesc, ShapeDesc};
use crate::{BodyHandle, Load, SimError, World, WorldSettings};

const EPS: f64 = 1e-4;
const G: f64 = 9.81;

fn world() -> World {
    World::new(WorldSettings::new(EPS)).unwrap()
}

/// A floor whose top is z = 0.
fn floor() -> BodyDesc {
    BodyDesc::fixed("floor", ShapeDesc::cuboid([2.0, 2.0, 0.1])).at([0.0, 0.0, -0.1])
}

/// Steps `w` to `t` in frames of `dt`, sampling an independent monitor at each frame; returns
/// its largest penetration depth.
fn run_monitored(w: &mut World, t: f64, dt: f64) -> f64 {
    let mut m = PenetrationMonitor::new();
    m.sample(w);
    while w.time() < t {
        w.step_until((w.time() + dt).min(t)).unwrap();
        m.sample(w);
    }
    m.report().max_depth
}

/// A box and a ball placed exactly on the floor (touching, distance zero): accepted, they stay
/// at rest within a few ε_c over 5 s, and the independent monitor never sees them deeper than
/// ε_c; both start as contacts (the normal from the separating axis at zero distance).
#[test]
fn bodies_placed_touching_the_floor_rest_there() {
    let mut w = world();
    w.add_body(&floor()).unwrap();
    let cube = w
        .add_body(
            &BodyDesc::new("box", ShapeDesc::cuboid([0.1, 0.1, 0.1]))
                .at([0.0, 0.0, 0.1])
                .with_density(700.0),
        )
        .unwrap();
    let ball = w
        .add_body(
            &BodyDesc::new("ball", ShapeDesc::sphere(0.05))
                .at([0.5, 0.0, 0.05])
                .with_density(7800.0),
        )
        .unwrap();
    w.set_checking(true);
    let depth = run_monitored(&mut w, 5.0, 0.01);
    let (b, s) = (w.state(cube).unwrap(), w.state(ball).unwrap());
    let (drift_box, drift_ball) = (
        (b.position - DVec3::new(0.0, 0.0, 0.1)).length(),
        (s.position - DVec3::new(0.5, 0.0, 0.05)).length(),
    );
    let checked = w.checked_penetration().unwrap().max_depth;
    eprintln!(
        "touching at start: drift box {:.2} ε_c, ball {:.2} ε_c; monitor {:.3} ε_c (frames), {:.3} ε_c (every step)",
        drift_box / EPS,
        drift_ball / EPS,
        depth / EPS,
        checked / EPS
    );
    assert!(drift_box < 3.0 * EPS && drift_ball < 3.0 * EPS);
    assert!(depth <= EPS && checked <= EPS);
    assert!(b.rotation.angle_between(DQuat::IDENTITY) < 1e-3);
    // Resting contact is resolved: held by an island (the default switching model) or by
    // microcollisions (the impulse model).
    let c = w.counters();
    assert!(
        c.island_steps + c.microcollisions > 0,
        "resting contact was never resolved"
    );
}

/// Four blocks built in code, each exactly touching the next and the bottom one the floor:
/// the stack stands for 2 s (top block drift below a few ε_c) and nothing penetrates deeper
/// than ε_c by the monitor.
#[test]
fn a_stack_built_touching_stands() {
    let mut w = world();
    w.add_body(&floor()).unwrap();
    let h = [0.05, 0.0375, 0.025];
    let mut top = None;
    for k in 0..4 {
        let z = h[2] * (1.0 + 2.0 * k as f64);
        top = Some(
            w.add_body(
                &BodyDesc::new(format!("block{k}"), ShapeDesc::cuboid(h))
                    .at([0.0, 0.0, z])
                    .with_density(700.0),
            )
            .unwrap(),
        );
    }
    let top = top.unwrap();
    let start = w.state(top).unwrap().position;
    let depth = run_monitored(&mut w, 2.0, 0.01);
    let drift = (w.state(top).unwrap().position - start).length();
    eprintln!(
        "touching stack of 4: top drift {:.2} ε_c, monitor {:.3} ε_c, {:?}",
        drift / EPS,
        depth / EPS,
        w.counters()
    );
    assert!(drift < 5.0 * EPS, "top block drifted {drift}");
    assert!(depth <= EPS);
}

/// A real overlap deeper than ε_c is refused, naming both bodies and the depth (exact for a
/// box face sunk into a floor); an overlap shallower than ε_c is contact and accepted.
#[test]
fn only_a_real_overlap_is_refused() {
    let mut w = world();
    w.add_body(&floor()).unwrap();
    let sunk = |depth: f64| {
        BodyDesc::new("box", ShapeDesc::cuboid([0.1, 0.1, 0.1])).at([0.0, 0.0, 0.1 - depth])
    };
    match w.add_body(&sunk(3.0 * EPS)) {
        Err(SimError::Overlap { a, b, depth, .. }) => {
            assert_eq!((a.as_str(), b.as_str()), ("floor", "box"));
            assert!((depth - 3.0 * EPS).abs() < 1e-12, "{depth}");
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(w.len(), 1, "a refused body leaves nothing behind");
    w.add_body(&sunk(0.5 * EPS)).unwrap();
    let message = World::new(WorldSettings::new(EPS))
        .and_then(|mut w| {
            w.add_body(&floor())?;
            w.add_body(&sunk(0.01))
        })
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("\"floor\"")
            && message.contains("\"box\"")
            && message.contains("1.000e-2"),
        "{message}"
    );
}

/// A deliberately wrong time-of-impact bound (every bound tripled: checks come late) lets a
/// dropped box sink into the floor between checks; the independent monitor sees it, deeper
/// than ε_c, while with the true bounds it sees nothing beyond ε_c.
#[test]
fn the_monitor_catches_a_wrong_bound() {
    let drop = |scale: f64| {
        let mut w = world();
        w.faults.toi_scale = scale;
        w.add_body(&floor()).unwrap();
        w.add_body(
            &BodyDesc::new("box", ShapeDesc::cuboid([0.05, 0.05, 0.05]))
                .at([0.0, 0.0, 0.5])
                .with_angular_velocity([1.0, 2.0, 0.5]),
        )
        .unwrap();
        w.set_checking(true);
        let frames = run_monitored(&mut w, 1.0, 0.01);
        (frames, w.checked_penetration().unwrap().max_depth)
    };
    let (good_frames, good_steps) = drop(1.0);
    let (bad_frames, bad_steps) = drop(3.0);
    eprintln!(
        "monitor: true bounds {:.3} / {:.3} ε_c, tripled bounds {:.1} / {:.1} ε_c (frames / every step)",
        good_frames / EPS,
        good_steps / EPS,
        bad_frames / EPS,
        bad_steps / EPS
    );
    assert!(good_frames <= EPS && good_steps <= EPS);
    assert!(bad_steps > EPS, "the monitor missed the penetration");
}

/// The response is made to fail on one pair of a 20-body scene (19 balls dropped on a floor,
/// far apart): the run finishes, the failure is reported (event, counter, message), the
/// failing ball is resolved by the fallback and stays out of the floor, and every other ball's
/// trajectory equals the one of a run without the fault (to rounding: the event times differ).
#[test]
fn one_failing_pair_does_not_end_the_run() {
    let build = |fail: bool| -> (World, Vec<BodyHandle>) {
        let mut w = world();
        w.set_event_log(true);
        w.add_body(
            &BodyDesc::fixed("floor", ShapeDesc::cuboid([5.0, 5.0, 0.1])).at([0.0, 0.0, -0.1]),
        )
        .unwrap();
        let balls: Vec<BodyHandle> = (0..19)
            .map(|k| {
                let (x, y) = ((k % 5) as f64 * 0.5 - 1.0, (k / 5) as f64 * 0.5 - 1.0);
                w.add_body(
                    &BodyDesc::new(format!("ball{k}"), ShapeDesc::sphere(0.05))
                        .at([x, y, 0.1 + 0.02 * k as f64])
                        .with_velocity([0.1, 0.0, 0.0]),
                )
                .unwrap()
            })
            .collect();
        if fail {
            w.faults.fail_pair = Some((0, balls[3].index()));
        }
        (w, balls)
    };
    let (mut ok, balls) = build(false);
    let (mut bad, _) = build(true);
    let mut worst = 0.0f64;
    let mut m = PenetrationMonitor::new();
    for k in 1..=100 {
        let t = 0.01 * k as f64;
        ok.step_until(t).unwrap();
        bad.step_until(t).unwrap();
        m.sample(&bad);
        for (i, &h) in balls.iter().enumerate() {
            if i == 3 {
                continue;
            }
            let (a, b) = (ok.state(h).unwrap(), bad.state(h).unwrap());
            worst = worst
                .max((a.position - b.position).length())
                .max((a.velocity - b.velocity).length());
        }
    }
    let c = bad.counters();
    eprintln!(
        "fault on one pair: {} unresolved, other balls differ by {worst:.2e}; first failure: {}",
        c.unresolved,
        bad.failures()[0].message
    );
    assert!(c.unresolved > 0 && bad.failures().len() as u64 == c.unresolved.min(1000));
    assert_eq!(bad.failures()[0].b, balls[3]);
    assert!(
        bad.events()
            .iter()
            .any(|e| e.kind == ContactKind::Fallback && e.b == balls[3])
    );
    assert_eq!(ok.counters().unresolved, 0);
    assert!(worst < 1e-9, "other balls changed by {worst}");
    assert!(m.report().max_depth <= EPS, "{:?}", m.report());
    assert!(bad.state(balls[3]).unwrap().position.z > 0.0);
}

/// Handles stay valid when other bodies are removed; a removed body's handle names nothing,
/// and a slot reused by a new body does not revive it.
#[test]
fn handles_survive_removals() {
    let mut w = world();
    let f = w.add_body(&floor()).unwrap();
    let a = w
        .add_body(&BodyDesc::new("a", ShapeDesc::sphere(0.05)).at([0.0, 0.0, 0.5]))
        .unwrap();
    let b = w
        .add_body(&BodyDesc::new("b", ShapeDesc::sphere(0.05)).at([0.5, 0.0, 0.5]))
        .unwrap();
    w.step_until(0.1).unwrap();
    let removed = w.remove_body(a).unwrap();
    assert_eq!(removed.name, "a");
    assert!(matches!(w.state(a), Err(SimError::UnknownBody { .. })));
    assert!(matches!(
        w.remove_body(a),
        Err(SimError::UnknownBody { .. })
    ));
    let c = w
        .add_body(&BodyDesc::new("c", ShapeDesc::sphere(0.05)).at([-0.5, 0.0, 0.5]))
        .unwrap();
    assert_eq!(c.index(), a.index(), "the slot is reused");
    assert!(w.state(a).is_err(), "…but the old handle stays dead");
    w.step_until(2.0).unwrap();
    assert_eq!(w.body(b).unwrap().name, "b");
    assert_eq!(w.handle("c"), Some(c));
    assert_eq!(w.handle("a"), None);
    // b and c fell 0.45 m onto the floor: both rest on it.
    for h in [b, c] {
        assert!((w.state(h).unwrap().position.z - 0.05).abs() < 5.0 * EPS);
    }
    assert_eq!(w.len(), 3);
    assert_eq!(w.handles(), vec![f, c, b]);
}

/// A constant force adds f/m to gravity exactly (closed-form parabola), and a constant torque
/// about a principal axis spins a body up at τ/I (ω = τt/I, angle ½τt²/I), in free flight.
#[test]
fn constant_loads_follow_the_closed_forms() {
    let mut w = World::new(WorldSettings {
        gravity: DVec3::new(0.0, 0.0, -G),
        ..WorldSettings::new(EPS)
    })
    .unwrap();
    let h = [0.1, 0.2, 0.3];
    let body = w
        .add_body(
            &BodyDesc::new("brick", ShapeDesc::cuboid(h))
                .with_mass(2.0)
                .with_velocity([1.0, 0.0, 0.0]),
        )
        .unwrap();
    let (force, torque) = (DVec3::new(0.0, 3.0, 19.62), DVec3::new(0.0, 0.0, 0.5));
    w.set_load(body, Load { force, torque }).unwrap();
    let t = 1.5;
    w.step_until(t).unwrap();
    let s = w.state(body).unwrap();
    let acc = DVec3::new(0.0, 0.0, -G) + force / 2.0;
    let x = DVec3::new(1.0, 0.0, 0.0) * t + acc * (0.5 * t * t);
    assert!((s.com - x).length() < 1e-12, "{} vs {x}", s.com);
    // Box of mass 2, about z: m(a² + b²)/3 with half extents a, b.
    let iz = 2.0 * (h[0] * h[0] + h[1] * h[1]) / 3.0;
    assert!(
        (s.omega - torque * (t / iz)).length() < 1e-9 * s.omega.length(),
        "{}",
        s.omega
    );
    let angle = 0.5 * torque.z * t * t / iz;
    let expected = DQuat::from_rotation_z(angle);
    assert!(
        s.rotation.angle_between(expected) < 1e-8,
        "{} vs {angle}",
        s.rotation
    );
}

/// A load function is evaluated now and then every 1/rate exactly (the times it saw), and
/// holding a constant from a function equals setting it (bit for bit).
#[test]
fn load_functions_run_at_their_rate() {
    use std::sync::{Arc, Mutex};
    let seen = Arc::new(Mutex::new(Vec::new()));
    let run = |with_fn: bool| {
        let mut w = world();
        let h = w
            .add_body(&BodyDesc::new("b", ShapeDesc::sphere(0.1)).at([0.0, 0.0, 1.0]))
            .unwrap();
        let push = Load::force(DVec3::new(1.0, 0.0, 0.0));
        if with_fn {
            let seen = Arc::clone(&seen);
            w.set_load_fn(h, 50.0, move |t, _| {
                seen.lock().unwrap().push(t);
                push
            })
            .unwrap();
        } else {
            w.set_load(h, push).unwrap();
        }
        w.step_until(0.3).unwrap();
        (w.state(h).unwrap(), w.counters().load_evaluations)
    };
    let (with_fn, evaluations) = run(true);
    let (constant, _) = run(false);
    let times = seen.lock().unwrap().clone();
    assert_eq!(evaluations, 16, "{times:?}"); // t = 0, 0.02, …, 0.30
    for (k, t) in times.iter().enumerate() {
        assert!((t - k as f64 / 50.0).abs() < 1e-12, "{times:?}");
    }
    assert!((with_fn.com - constant.com).length() < 1e-12);
}

/// `apply_impulse` changes momentum by p and angular momentum by (x − com) × p; contacts()
/// lists the step's contacts (a dropped ball's landing, with the floor, normal up).
#[test]
fn impulses_and_contacts() {
    let mut w = world();
    let f = w.add_body(&floor()).unwrap();
    let h = w
        .add_body(
            &BodyDesc::new("ball", ShapeDesc::sphere(0.05))
                .at([0.0, 0.0, 0.2])
                .with_mass(2.0),
        )
        .unwrap();
    let (p, x) = (DVec3::new(0.4, 0.0, 0.0), DVec3::new(0.0, 0.0, 0.25));
    let l0 = w.body(h).unwrap().angular_momentum();
    w.apply_impulse(h, p, x).unwrap();
    let after = w.body(h).unwrap();
    assert!((after.linear_momentum() - p).length() < 1e-15);
    assert!((after.angular_momentum() - l0 - x.cross(p)).length() < 1e-15);
    assert!(matches!(
        w.apply_impulse(f, p, x),
        Err(SimError::Invalid { .. })
    ));
    // The ball falls 0.15 m: it lands at √(2·0.15/g) = 0.175 s.
    let r1 = w.step_until(0.1).unwrap();
    assert_eq!((r1.contacts, w.contacts().len()), (0, 0));
    let r2 = w.step_until(0.2).unwrap();
    assert!(r2.contacts >= 1 && r2.counters.collisions >= 1, "{r2:?}");
    let landing = w.contacts()[0];
    assert_eq!((landing.a, landing.b), (f, h));
    assert!((landing.normal + DVec3::Z).length() < 1e-9, "{landing:?}");
    assert!((landing.time - (0.3f64 / G).sqrt()).abs() < 1e-3);
}

/// A ball over a floor, run to 0.2 s, under a load function that returns NaN from t = 0.5 s:
/// the next step past 0.5 s fails.
fn failing_at_half_a_second() -> (World, BodyHandle) {
    let mut w = world();
    w.add_body(&floor()).unwrap();
    let h = w
        .add_body(&BodyDesc::new("b", ShapeDesc::sphere(0.1)).at([0.0, 0.0, 0.6]))
        .unwrap();
    w.set_load_fn(h, 100.0, |t, _| {
        Load::force(DVec3::new(if t < 0.5 { 0.0 } else { f64::NAN }, 0.0, 0.0))
    })
    .unwrap();
    w.step_until(0.2).unwrap();
    (w, h)
}

/// An error in a step leaves the world exactly as it was: a load function that returns NaN at
/// t ≥ 0.5 fails the step to 1 s, and time, states and counters are those before the call.
#[test]
fn a_failed_step_changes_nothing() {
    let (mut w, h) = failing_at_half_a_second();
    let (time, state, counters) = (w.time(), w.state(h).unwrap(), w.counters());
    let err = w.step_until(1.0).unwrap_err();
    assert!(err.to_string().contains("load function"), "{err}");
    assert_eq!(
        (w.time(), w.state(h).unwrap(), w.counters()),
        (time, state, counters)
    );
    assert!(matches!(
        w.step_until(f64::NAN),
        Err(SimError::Invalid { .. })
    ));
}

/// With rollback off ([`World::set_rollback`]), the same failing step leaves the world where
/// the failure was found (later than before the call: the load function was evaluated at
/// 0.5 s), and [`crate::run_streaming`], which turns rollback off for its steps, fails the
/// same way and hands the setting back as it found it.
#[test]
fn without_rollback_a_failed_step_stops_where_it_failed() {
    let failing = || failing_at_half_a_second().0;
    let mut w = failing();
    assert!(w.rollback());
    w.set_rollback(false);
    let err = w.step_until(1.0).unwrap_err();
    assert!(err.to_string().contains("load function"), "{err}");
    assert!(
        w.time() > 0.2 && w.time() <= 0.5 + 1e-12,
        "t = {}",
        w.time()
    );
    let mut w = failing();
    let streamed = crate::run_streaming(&mut w, 1.0, 100.0, 2, |_| Ok(true), |_| {});
    assert!(streamed.is_err());
    assert!(w.rollback(), "run_streaming left rollback off");
    assert!(w.time() > 0.2, "t = {}", w.time());
}

/// A body whose angular velocity cannot be bounded (its energy overflows) is never assumed
/// still: the step refuses to move past it, and the world is unchanged.
#[test]
fn an_unboundable_body_stops_the_step_not_the_checks() {
    let mut w = world();
    w.add_body(&floor()).unwrap();
    let h = w
        .add_body(&BodyDesc::new("box", ShapeDesc::cuboid([0.1, 0.2, 0.3])).at([0.0, 0.0, 1.0]))
        .unwrap();
    w.set_velocity(h, DVec3::ZERO, DVec3::new(1e308, 0.0, 1e308))
        .unwrap();
    let motion = w.body(h).unwrap().motion(w.gravity());
    assert!(
        matches!(motion, impulse_collide::Motion::Unbounded { .. }),
        "{motion:?}"
    );
    let err = w.step_until(0.1).unwrap_err().to_string();
    assert!(err.contains("cannot be bounded"), "{err}");
    assert_eq!(w.time(), 0.0);
}

/// Moving a body: its own frame lands where asked (for a body whose centre of mass is not its
/// frame origin too), and a move into a deep overlap is refused.
#[test]
fn set_pose_places_the_own_frame() {
    let mut w = world();
    w.add_body(&floor()).unwrap();
    let hammer = w
        .add_body(
            &BodyDesc::new(
                "hammer",
                ShapeDesc::compound(vec![
                    crate::scene::PartDesc::new(ShapeDesc::cuboid([0.1, 0.01, 0.01])),
                    crate::scene::PartDesc::new(ShapeDesc::cuboid([0.02, 0.03, 0.03]))
                        .at([0.1, 0.0, 0.0]),
                ]),
            )
            .at([0.0, 0.0, 0.5]),
        )
        .unwrap();
    let s0 = w.state(hammer).unwrap();
    assert_eq!(s0.position, DVec3::new(0.0, 0.0, 0.5));
    assert!(s0.rotation.angle_between(DQuat::IDENTITY) < 1e-12);
    assert!(
        s0.com.x > 0.05,
        "the head pulls the centre of mass along x: {}",
        s0.com
    );
    let q = DQuat::from_rotation_z(0.7);
    w.set_pose(hammer, DVec3::new(0.3, 0.2, 0.8), q).unwrap();
    let s = w.state(hammer).unwrap();
    assert!((s.position - DVec3::new(0.3, 0.2, 0.8)).length() < 1e-15);
    assert!(s.rotation.angle_between(q) < 1e-12);
    assert!(matches!(
        w.set_pose(hammer, DVec3::new(0.3, 0.2, 0.0), q),
        Err(SimError::Overlap { .. })
    ));
    assert_eq!(w.state(hammer).unwrap(), s);
}
