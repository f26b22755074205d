//! Tests of high-level controllers in the world ([`super::control`], [`crate::controllers`]),
//! each against a closed form or the controller's physics, measured on the bodies.

use glam::DVec3;

use crate::controllers::{Goal, Launch, Steer, SteerGains, yaw_of};
use crate::error::SimError;
use crate::scene::{BodyDesc, ShapeDesc};
use crate::world::{BodyHandle, Control, Load, World, WorldController, WorldSettings};

/// Agreement with a closed form of free flight (m, m/s): rounding of a few hundred steps.
const CLOSED_FORM: f64 = 1e-9;

fn world(gravity: DVec3) -> World {
    let mut s = WorldSettings::new(1e-4);
    s.gravity = gravity;
    World::new(s).expect("valid settings")
}

fn ball(w: &mut World, name: &str, at: [f64; 3]) -> BodyHandle {
    w.add_body(
        &BodyDesc::new(name, ShapeDesc::sphere(0.05))
            .at(at)
            .with_density(1000.0),
    )
    .expect("free space")
}

/// Records the time and the centre of mass of a body at every update.
#[derive(Clone)]
struct Recorder {
    body: BodyHandle,
    period: f64,
    seen: Vec<(f64, DVec3)>,
}

impl WorldController for Recorder {
    fn period(&self) -> f64 {
        self.period
    }
    fn update(&mut self, control: &mut Control<'_>) -> Result<(), SimError> {
        let com = control.world().state(self.body)?.com;
        self.seen.push((control.time(), com));
        Ok(())
    }
}

/// A controller is an event of the loop: stepped in calls that end off its grid (every
/// 37 ms), a 100 Hz controller is updated exactly at every multiple of 10 ms, and sees a
/// falling ball where free fall puts it at that instant.
#[test]
fn controllers_see_the_world_at_every_multiple_of_their_period() {
    let g = DVec3::new(0.0, 0.0, -9.81);
    let mut w = world(g);
    let b = ball(&mut w, "ball", [0.0, 0.0, 10.0]);
    let period = 0.01;
    let h = w
        .add_controller(
            "recorder",
            Box::new(Recorder {
                body: b,
                period,
                seen: Vec::new(),
            }),
        )
        .expect("valid controller");
    let mut t = 0.0;
    while t < 1.0 {
        t = (t + 0.037_f64).min(1.0);
        w.step_until(t).expect("runs");
    }
    let seen = &w.controller::<Recorder>(h).expect("a recorder").seen;
    assert_eq!(seen.len(), 101, "updates at 0, 0.01, …, 1.0");
    for (k, &(t, com)) in seen.iter().enumerate() {
        let want_t = k as f64 * period;
        assert!((t - want_t).abs() <= 1e-12, "update {k} at {t}");
        let want = DVec3::new(0.0, 0.0, 10.0) + 0.5 * g * want_t * want_t;
        assert!(
            (com - want).length() <= CLOSED_FORM,
            "update {k}: the ball at {com}, free fall puts it at {want}"
        );
    }
    assert_eq!(w.counters().controller_updates, 101);
}

/// Pushes a body with a constant force until `until`, then lets go.
#[derive(Clone)]
struct Push {
    body: BodyHandle,
    force: DVec3,
    until: f64,
}

impl WorldController for Push {
    fn period(&self) -> f64 {
        0.1
    }
    fn update(&mut self, control: &mut Control<'_>) -> Result<(), SimError> {
        if control.time() < self.until {
            control.set_load(self.body, Load::force(self.force))
        } else {
            control.clear_load(self.body)
        }
    }
}

/// A force a controller holds for 0.5 s in zero gravity gives the closed form: x(1) =
/// x₀ + ½·a·0.5² + a·0.5·0.5 and v(1) = a·0.5, a = F/m.
#[test]
fn a_force_a_controller_holds_moves_the_body_as_the_closed_form() {
    let mut w = world(DVec3::ZERO);
    let b = ball(&mut w, "ball", [0.0, 0.0, 0.0]);
    let m = w.body(b).and_then(|b| b.mass).expect("dynamic").mass;
    let force = DVec3::new(3.0, -1.0, 2.0);
    let push = Push {
        body: b,
        force,
        until: 0.5,
    };
    w.add_controller("push", Box::new(push)).expect("valid");
    w.step_until(1.0).expect("runs");
    let a = force / m;
    let s = w.state(b).expect("body");
    let want_x = 0.5 * a * 0.25 + a * 0.5 * 0.5;
    assert!(
        (s.com - want_x).length() <= CLOSED_FORM,
        "{} against {want_x}",
        s.com
    );
    assert!((s.velocity - a * 0.5).length() <= CLOSED_FORM);
}

/// The launch of the furniture scene's bottle: a velocity overwritten at t = 0.2 s sends the
/// ball's centre along the parabola to the target, reached at t = 0.2 + T exactly.
#[test]
fn a_launch_lands_the_centre_of_mass_on_its_target() {
    let g = DVec3::new(0.0, 0.0, -9.81);
    let mut w = world(g);
    let b = ball(&mut w, "bottle", [0.0, 0.0, 1.0]);
    let target = DVec3::new(1.5, -0.5, 1.3);
    let (at, flight) = (0.2, 0.45);
    let launch = Launch::new(b, None, target, at, flight, 50.0).expect("valid");
    let h = w.add_controller("launch", Box::new(launch)).expect("valid");
    w.step_until(at + flight).expect("runs");
    assert_eq!(
        w.controller::<Launch>(h).and_then(Launch::launched),
        Some(at)
    );
    let com = w.state(b).expect("body").com;
    assert!(
        (com - target).length() <= CLOSED_FORM,
        "{com} against {target}"
    );
}

/// Fails from time `from` on.
#[derive(Clone)]
struct FailLater {
    from: f64,
}

impl WorldController for FailLater {
    fn period(&self) -> f64 {
        0.05
    }
    fn update(&mut self, control: &mut Control<'_>) -> Result<(), SimError> {
        if control.time() >= self.from {
            return Err(SimError::Invalid {
                what: "test".into(),
                field: "update".into(),
                problem: "gave up".into(),
            });
        }
        Ok(())
    }
}

/// A controller's error stops the step: the world is returned as it was before the call,
/// and the error names the controller. Bad names and periods are refused.
#[test]
fn a_failing_controller_leaves_the_world_as_it_was_and_is_named() {
    let mut w = world(DVec3::new(0.0, 0.0, -9.81));
    let b = ball(&mut w, "ball", [0.0, 0.0, 1.0]);
    w.add_controller("flaky", Box::new(FailLater { from: 0.3 }))
        .expect("fine at first");
    w.step_until(0.2).expect("runs");
    let before = w.state(b).expect("body");
    let err = w.step_until(0.5).expect_err("fails at 0.3");
    assert!(err.to_string().contains("controller \"flaky\""), "{err}");
    assert_eq!(w.time(), 0.2);
    assert_eq!(w.state(b).expect("body"), before);
    // Taken names, bad periods, and a first update that fails are refused, changing nothing.
    assert!(
        w.add_controller("flaky", Box::new(FailLater { from: 9.0 }))
            .is_err()
    );
    assert!(
        w.add_controller("now", Box::new(FailLater { from: 0.0 }))
            .is_err()
    );
    assert!(w.controller_handle("now").is_none());
    let bad = Push {
        body: b,
        force: DVec3::NAN,
        until: 1.0,
    };
    let err = w
        .add_controller("nan", Box::new(bad))
        .expect_err("a NaN load");
    assert!(err.to_string().contains("ball"), "{err}");
}

/// A box of 40 × 30 × 20 cm (density 500) on a floor with μ = 0.3, steered by [`Steer`] to
/// two goals with yaws, reaches both: measured on the box, its final position and yaw are
/// within the reach of the last goal. With a reach tighter than friction allows, it stops
/// short of the first goal, at rest, by at most μ·g/ω_n² (where the PD pull equals sliding
/// friction) and never reaches it.
#[test]
fn steering_reaches_its_goals_and_stops_short_at_most_by_the_friction_offset() {
    let goals = vec![
        Goal {
            position: DVec3::new(0.8, 0.3, 0.1),
            yaw: Some(0.6),
        },
        Goal {
            position: DVec3::new(0.2, -0.5, 0.1),
            yaw: Some(-1.0),
        },
    ];
    let flat = DVec3::new(1.0, 1.0, 0.0);
    let run = |gains: SteerGains, end: f64| {
        let mut s = WorldSettings::new(1e-4);
        s.default_contact.friction = 0.3;
        s.default_contact.restitution = 0.2;
        let mut w = World::new(s).expect("valid");
        w.add_body(
            &BodyDesc::fixed("floor", ShapeDesc::cuboid([3.0, 3.0, 0.05])).at([0.0, 0.0, -0.05]),
        )
        .expect("free");
        let b = w
            .add_body(
                &BodyDesc::new("box", ShapeDesc::cuboid([0.2, 0.15, 0.1]))
                    .at([0.0, 0.0, 0.1])
                    .with_density(500.0),
            )
            .expect("free");
        let steer = Steer::new(b, None, goals.clone(), gains, 50.0, 0.0).expect("valid");
        let h = w.add_controller("steer", Box::new(steer)).expect("valid");
        w.step_until(end).expect("runs");
        let st = w.state(b).expect("box");
        let reached = w.controller::<Steer>(h).expect("steer").reached().to_vec();
        (st, reached)
    };
    let gains = SteerGains::default();
    let (st, reached) = run(gains, 8.0);
    assert_eq!(reached.len(), 2, "reached at {reached:?}");
    let last = goals[1];
    let e = ((last.position - st.position) * flat).length();
    assert!(e <= gains.reach, "{e} from the last goal");
    let yaw_err = yaw_of(st.rotation) - last.yaw.expect("yaw");
    assert!(yaw_err.abs() <= gains.reach_angle, "yaw off by {yaw_err}");
    let tight = SteerGains {
        frequency: 6.0,
        reach: 1e-4,
        ..gains
    };
    let (st, reached) = run(tight, 6.0);
    assert!(reached.is_empty(), "reached {reached:?}");
    let offset = ((goals[0].position - st.position) * flat).length();
    let bound = 0.3 * 9.81 / (tight.frequency * tight.frequency);
    assert!(
        st.velocity.length() < 1e-6,
        "still moving at {}",
        st.velocity
    );
    assert!(
        offset > tight.reach && offset <= bound * (1.0 + 1e-3),
        "stopped {offset} short; friction allows up to {bound}"
    );
}
