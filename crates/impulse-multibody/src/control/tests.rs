//! Tests of the controllers and the simulation loop that schedules them.

use super::*;
use crate::integrate::AdaptiveRk4;
use crate::model::{BaseKind, JointPassive, JointSpec, ModelBuilder};
use glam::{DMat3, DVec3};
use impulse_geom::{Pose, SpatialInertia};

/// Settled positions against their analytic values (after many time constants).
const SETTLED: f64 = 1e-6;
/// Piecewise-polynomial motion that RK4 integrates exactly, up to rounding.
const EXACT: f64 = 1e-10;

fn block(m: f64) -> SpatialInertia {
    SpatialInertia::new(m, DVec3::ZERO, DMat3::IDENTITY * (0.1 * m))
}

/// A mass `m` on a prismatic joint along +z under gravity −z (thesis Fig. 5.14).
fn slider(m: f64) -> Model {
    let mut b = ModelBuilder::new(BaseKind::Fixed);
    b.link("ground", SpatialInertia::ZERO)
        .link("piston", block(m))
        .joint(JointSpec::prismatic(
            "slide",
            "ground",
            "piston",
            Pose::IDENTITY,
            DVec3::Z,
        ));
    b.build().unwrap()
}

fn tight() -> Integrator {
    Integrator::AdaptiveRk4(AdaptiveRk4 {
        rel_tol: 1e-10,
        abs_tol: 1e-10,
        ..AdaptiveRk4::default()
    })
}

/// A 2 kg wheel of inertia `i_axle` about its axle (z), on a revolute joint to a fixed
/// chassis, without gravity, at rest.
fn wheel(i_axle: f64) -> Simulation {
    let mut b = ModelBuilder::new(BaseKind::Fixed);
    b.gravity(DVec3::ZERO)
        .link("chassis", SpatialInertia::ZERO)
        .link(
            "wheel",
            SpatialInertia::new(
                2.0,
                DVec3::ZERO,
                DMat3::from_diagonal(DVec3::new(0.03, 0.03, i_axle)),
            ),
        )
        .joint(JointSpec::revolute(
            "axle",
            "chassis",
            "wheel",
            Pose::IDENTITY,
            DVec3::Z,
        ));
    Simulation::new(b.build().unwrap(), vec![0.0], vec![0.0], tight()).unwrap()
}

/// PD at 1 kHz holding a prismatic joint that carries m·g settles at `q_des − m g / k_p`
/// (thesis §5.4.1); PID at the same rate removes the offset.
#[test]
fn pd_settles_at_static_deflection_and_pid_removes_it() {
    let (m, kp, kv, q_des) = (2.0, 1000.0, 60.0, 0.25);
    let mut sim = Simulation::new(slider(m), vec![0.0], vec![0.0], tight()).unwrap();
    let mut pd = JointPd::new(0, kp, kv, 1e-3);
    pd.q_des = q_des;
    sim.add_controller(Box::new(pd)).unwrap();
    sim.run_until(4.0).unwrap();
    let want = q_des - m * 9.81 / kp;
    println!("PD slider: q = {:.9}, analytic {want:.9}", sim.q()[0]);
    assert!((sim.q()[0] - want).abs() < SETTLED && sim.v()[0].abs() < SETTLED);

    let mut sim = Simulation::new(slider(m), vec![0.0], vec![0.0], tight()).unwrap();
    let mut pid = JointPid::new(0, kp, kv, 2000.0, 1e-3);
    pid.pd.q_des = q_des;
    sim.add_controller(Box::new(pid)).unwrap();
    sim.run_until(12.0).unwrap();
    println!("PID slider: q = {:.9}", sim.q()[0]);
    assert!((sim.q()[0] - q_des).abs() < SETTLED);
}

/// A PD-held revolute arm under its own weight settles where `k_p (q_des − q) = m g c cos q`
/// (solved by Newton's method here).
#[test]
fn pd_holds_an_arm_at_the_analytic_deflection() {
    let (m, c, kp, kv) = (1.5, 0.4, 80.0, 6.0);
    let mut b = ModelBuilder::new(BaseKind::Fixed);
    let rod = SpatialInertia::new(m, DVec3::new(c, 0.0, 0.0), DMat3::IDENTITY * 0.02);
    b.gravity(DVec3::new(0.0, -9.81, 0.0))
        .link("ground", SpatialInertia::ZERO)
        .link("arm", rod)
        .joint(JointSpec::revolute(
            "shoulder",
            "ground",
            "arm",
            Pose::IDENTITY,
            DVec3::Z,
        ));
    let mut sim = Simulation::new(b.build().unwrap(), vec![0.0], vec![0.0], tight()).unwrap();
    sim.add_controller(Box::new(JointPd::new(0, kp, kv, 1e-3)))
        .unwrap();
    sim.run_until(8.0).unwrap();
    let mut q = 0.0f64;
    for _ in 0..50 {
        let f = kp * (0.0 - q) - m * 9.81 * c * q.cos();
        let df = -kp + m * 9.81 * c * q.sin();
        q -= f / df;
    }
    println!("PD arm: q = {:.9}, analytic {q:.9}", sim.q()[0]);
    assert!((sim.q()[0] - q).abs() < SETTLED);
}

/// Records its update times and outputs a torque that depends on the update count.
#[derive(Clone)]
struct Recorder {
    period: f64,
    times: Vec<f64>,
    amplitude: f64,
}

impl Controller for Recorder {
    fn period(&self) -> f64 {
        self.period
    }
    fn update(&mut self, input: &ControlInput<'_>, output: &mut [f64]) {
        let k = self.times.len();
        self.times.push(input.time);
        output[0] = self.amplitude * if k % 2 == 0 { 1.0 } else { -0.5 };
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// Updates happen exactly at t₀ + k·period for two interleaved rates; the output is held
/// between updates: a free rotor driven by the two piecewise-constant torques follows the
/// exact piecewise-quadratic motion (RK4 is exact on each interval, so any step that
/// straddled an update would show). Disabling a controller removes its contribution.
#[test]
fn controllers_run_on_schedule_with_zero_order_hold() {
    let mut b = ModelBuilder::new(BaseKind::Fixed);
    b.gravity(DVec3::ZERO)
        .link("ground", SpatialInertia::ZERO)
        .link("rotor", block(1.0))
        .joint(JointSpec::revolute(
            "spin",
            "ground",
            "rotor",
            Pose::IDENTITY,
            DVec3::Z,
        ));
    let inertia = 0.1;
    let mut sim = Simulation::new(
        b.build().unwrap(),
        vec![0.0],
        vec![0.0],
        Integrator::Rk4 { step: 3e-4 },
    )
    .unwrap();
    let fast = sim
        .add_controller(Box::new(Recorder {
            period: 1e-3,
            times: vec![],
            amplitude: 2.0,
        }))
        .unwrap();
    let slow = sim
        .add_controller(Box::new(Recorder {
            period: 1e-2,
            times: vec![],
            amplitude: 0.7,
        }))
        .unwrap();
    sim.run_until(0.05).unwrap();
    let ft = sim.controller_mut::<Recorder>(fast).unwrap().times.clone();
    let st = sim.controller_mut::<Recorder>(slow).unwrap().times.clone();
    assert_eq!(ft.len(), 51);
    assert_eq!(st.len(), 6);
    for (k, t) in ft.iter().enumerate() {
        assert_eq!(*t, k as f64 * 1e-3);
    }
    for (k, t) in st.iter().enumerate() {
        assert_eq!(*t, k as f64 * 1e-2);
    }
    // Exact motion under the held torques.
    let torque = |t: f64| {
        let kf = (t / 1e-3 + 1e-9).floor() as usize;
        let ks = (t / 1e-2 + 1e-9).floor() as usize;
        2.0 * if kf % 2 == 0 { 1.0 } else { -0.5 } + 0.7 * if ks % 2 == 0 { 1.0 } else { -0.5 }
    };
    let (mut q, mut w) = (0.0, 0.0);
    for k in 0..50 {
        let a = torque(k as f64 * 1e-3 + 5e-4) / inertia;
        q += w * 1e-3 + 0.5 * a * 1e-6;
        w += a * 1e-3;
    }
    println!("ZOH rotor: q = {:.12} vs exact {q:.12}", sim.q()[0]);
    assert!((sim.q()[0] - q).abs() < EXACT && (sim.v()[0] - w).abs() < EXACT);
    // The fast controller's output is held; disabling it zeroes it.
    assert_eq!(sim.controller_output(fast).unwrap()[0], 2.0);
    sim.set_enabled(fast, false).unwrap();
    assert_eq!(sim.controller_output(fast).unwrap()[0], 0.0);
    let w0 = sim.v()[0];
    sim.run_until(0.06).unwrap();
    // Only the slow controller acted on [0.05, 0.06): its output at t = 0.05 (k = 5, odd).
    let expect = w0 + 0.7 * -0.5 / inertia * 0.01;
    assert!((sim.v()[0] - expect).abs() < EXACT);
    assert_eq!(
        sim.controller_mut::<Recorder>(fast).unwrap().times.len(),
        51
    );
    // Re-enabled, it resumes on its own grid.
    sim.set_enabled(fast, true).unwrap();
    sim.run_until(0.0625).unwrap();
    let ft = &sim.controller_mut::<Recorder>(fast).unwrap().times;
    assert_eq!(ft[51..], [0.06, 61.0 * 1e-3, 62.0 * 1e-3]);
}

/// Computed torque (eq. 5.16): right after an update, forward dynamics gives q̈ = q̈_des;
/// it then tracks a reference.
#[test]
fn computed_torque_gives_the_commanded_acceleration() {
    let mut rng = crate::testutil::rng(6301);
    let mut spec = crate::testutil::random_spec(&mut rng, 5, BaseKind::Fixed, true, true);
    for (_, _, j) in spec.joints.iter_mut() {
        j.passive = JointPassive {
            stiffness: 3.0,
            damping: 0.5,
            ..JointPassive::default()
        };
    }
    let model = spec.model();
    let n = model.nv();
    let (q, v) = crate::testutil::random_state(&mut rng, &model);
    let mut ct = ComputedTorque::new(&model, 0.0, 0.0, 1e-3).unwrap();
    ct.qdd_ref = (0..n).map(|k| 0.3 * k as f64 - 0.5).collect();
    let mut out = vec![0.0; n];
    ct.update(
        &ControlInput {
            time: 0.0,
            model: &model,
            q: &q,
            v: &v,
        },
        &mut out,
    );
    model.add_passive_forces(&q, &v, &mut out).unwrap();
    let mut a = vec![0.0; n];
    forward_dynamics(
        &model,
        &mut Workspace::new(&model),
        &q,
        &v,
        &out,
        None,
        &mut a,
    )
    .unwrap();
    for (x, y) in a.iter().zip(&ct.qdd_ref) {
        assert!((x - y).abs() < EXACT * (1.0 + y.abs()), "{a:?}");
    }
    // Tracking: hold the reference pose from a disturbed start.
    let mut ct = ComputedTorque::new(&model, 400.0, 40.0, 1e-3).unwrap();
    ct.q_ref = vec![0.2; n];
    let mut sim = Simulation::new(model.clone(), q, v, tight()).unwrap();
    sim.add_controller(Box::new(ct)).unwrap();
    sim.run_until(3.0).unwrap();
    for x in sim.q() {
        assert!((x - 0.2).abs() < SETTLED, "{:?}", sim.q());
    }
    assert!(ComputedTorque::new(&model, 1.0, 1.0, 0.0).is_err());
}

/// A passive spring is evaluated at every derivative evaluation: a spring-loaded rotor is
/// the exact harmonic oscillator; with a damper its energy decays monotonically.
#[test]
fn passive_spring_and_damper() {
    let (k, inertia) = (4.0, 0.1);
    let mut b = ModelBuilder::new(BaseKind::Fixed);
    b.gravity(DVec3::ZERO)
        .link("ground", SpatialInertia::ZERO)
        .link("rotor", block(1.0))
        .joint(
            JointSpec::revolute("spin", "ground", "rotor", Pose::IDENTITY, DVec3::Z)
                .with_passive(JointPassive::spring(k, 0.1)),
        );
    let model = b.build().unwrap();
    let mut sim = Simulation::new(model.clone(), vec![0.6], vec![0.0], tight()).unwrap();
    let w = (k / inertia).sqrt();
    for step in 1..=20 {
        let t = 0.1 * step as f64;
        sim.run_until(t).unwrap();
        let want = 0.1 + 0.5 * (w * t).cos();
        assert!(
            (sim.q()[0] - want).abs() < 1e-8,
            "t = {t}: {} vs {want}",
            sim.q()[0]
        );
    }
    let mut damped = model;
    damped
        .set_passive(
            0,
            JointPassive {
                damping: 0.2,
                ..JointPassive::spring(k, 0.1)
            },
        )
        .unwrap();
    let mut sim = Simulation::new(damped, vec![0.6], vec![0.0], tight()).unwrap();
    let energy = |s: &mut Simulation| s.energy().unwrap() + 0.5 * k * (s.q()[0] - 0.1).powi(2);
    let mut last = energy(&mut sim);
    for step in 1..=50 {
        sim.run_until(0.05 * step as f64).unwrap();
        let e = energy(&mut sim);
        assert!(e < last, "energy rose at step {step}");
        last = e;
    }
}

#[test]
fn bad_arguments_are_errors() {
    let model = slider(1.0);
    assert!(Simulation::new(model.clone(), vec![0.0, 1.0], vec![0.0], tight()).is_err());
    assert!(Simulation::new(model.clone(), vec![f64::NAN], vec![0.0], tight()).is_err());
    assert!(
        Simulation::new(
            model.clone(),
            vec![0.0],
            vec![0.0],
            Integrator::Rk4 { step: -1.0 }
        )
        .is_err()
    );
    let mut sim = Simulation::new(model, vec![0.0], vec![0.0], tight()).unwrap();
    assert!(
        sim.add_controller(Box::new(JointPd::new(0, 1.0, 1.0, 0.0)))
            .is_err()
    );
    sim.run_until(0.1).unwrap();
    assert!(sim.run_until(0.05).is_err());
    assert!(sim.run_until(f64::NAN).is_err());
}

/// A controller that does not fit the simulation's model is refused when it is added, naming
/// the joint, instead of indexing out of range (a panic) or feeding NaN to the integrator.
#[test]
fn controllers_that_do_not_fit_the_model_are_refused_naming_the_joint() {
    let mut sim = Simulation::new(slider(1.0), vec![0.0], vec![0.0], tight()).unwrap();
    let err = sim
        .add_controller(Box::new(JointPd::new(3, 1.0, 1.0, 1e-3)))
        .unwrap_err()
        .to_string();
    assert!(err.contains("index 3") && err.contains("1 joints"), "{err}");
    let err = sim
        .add_controller(Box::new(JointPd::new(0, f64::NAN, 1.0, 1e-3)))
        .unwrap_err()
        .to_string();
    assert!(err.contains("slide") && err.contains("k_p"), "{err}");
    let mut pid = JointPid::new(0, 1.0, 1.0, 1.0, 1e-3);
    pid.pd.q_des = f64::INFINITY;
    let err = sim.add_controller(Box::new(pid)).unwrap_err().to_string();
    assert!(err.contains("slide") && err.contains("q_des"), "{err}");
    // Computed torque made for a model of two joints, added to one of one.
    let mut b = ModelBuilder::new(BaseKind::Fixed);
    b.link("ground", SpatialInertia::ZERO)
        .link("a", SpatialInertia::new(1.0, DVec3::X, DMat3::IDENTITY))
        .link("b", SpatialInertia::new(1.0, DVec3::X, DMat3::IDENTITY))
        .joint(JointSpec::revolute(
            "ja",
            "ground",
            "a",
            Pose::IDENTITY,
            DVec3::Z,
        ))
        .joint(JointSpec::revolute(
            "jb",
            "a",
            "b",
            Pose::IDENTITY,
            DVec3::Z,
        ));
    let two = b.build().unwrap();
    let ct = ComputedTorque::new(&two, 10.0, 5.0, 1e-3).unwrap();
    let err = sim.add_controller(Box::new(ct)).unwrap_err().to_string();
    assert!(err.contains("2 joints") && err.contains("of 1"), "{err}");
    // Nothing was added: the simulation still runs.
    sim.run_until(0.01).unwrap();
}

/// A PD velocity loop (k_p = 0) on a wheel of inertia I about its axle, updated every h with
/// zero-order hold, reaches its commanded speed along the closed form of the held torques:
/// over each period the torque k_v·(ω_des − ω_k) is constant, so ω_{k+1} = ω_k + (h·k_v/I)·
/// (ω_des − ω_k), i.e. ω_k = ω_des·(1 − (1 − h·k_v/I)^k) at the update times (RK4 integrates a
/// constant torque exactly).
#[test]
fn a_pd_velocity_loop_drives_a_wheel_to_its_commanded_speed_along_the_held_torques() {
    let (i_axle, kv, h, w_des) = (0.05, 0.4, 1e-2, 12.0);
    let mut sim = wheel(i_axle);
    let mut pd = JointPd::new(0, 0.0, kv, h);
    pd.qd_des = w_des;
    sim.add_controller(Box::new(pd)).unwrap();
    let decay = 1.0 - h * kv / i_axle;
    for k in 1..=400 {
        sim.run_until(k as f64 * h).unwrap();
        let want = w_des * (1.0 - decay.powi(k));
        assert!(
            (sim.v()[0] - want).abs() <= EXACT * w_des,
            "update {k}: ω = {} against {want}",
            sim.v()[0]
        );
    }
    assert!(
        (sim.v()[0] - w_des).abs() < 1e-6 * w_des,
        "not at its commanded speed"
    );
}

/// Targets set after the controllers were added ([`Simulation::set_joint_targets`]) reach
/// every PD and PID on the joint: a wheel with one velocity PD and one velocity PID (k_p =
/// k_i = 0), both commanded by the call, follows the closed form of the held torques with
/// the sum of their gains, ω_k = ω_des·(1 − (1 − 2·h·k_v/I)^k).
#[test]
fn joint_targets_set_later_reach_every_pd_and_pid_on_the_joint() {
    let (i_axle, kv, h, w_des) = (0.05, 0.4, 1e-2, -7.0);
    let mut sim = wheel(i_axle);
    sim.add_controller(Box::new(JointPd::new(0, 0.0, kv, h)))
        .unwrap();
    sim.add_controller(Box::new(JointPid::new(0, 0.0, kv, 0.0, h)))
        .unwrap();
    // Before the first update: both controllers hold target 0, so nothing moves.
    assert_eq!(sim.set_joint_targets(0, 0.0, w_des).unwrap(), 2);
    let decay = 1.0 - 2.0 * h * kv / i_axle;
    for k in 1..=100 {
        sim.run_until(k as f64 * h).unwrap();
        let want = w_des * (1.0 - decay.powi(k));
        assert!(
            (sim.v()[0] - want).abs() <= EXACT * w_des.abs(),
            "update {k}: ω = {} against {want}",
            sim.v()[0]
        );
    }
    assert!(matches!(
        sim.set_joint_targets(1, 0.0, 0.0),
        Err(MultibodyError::UnknownName { .. })
    ));
    assert!(matches!(
        sim.set_joint_targets(0, f64::NAN, 0.0),
        Err(MultibodyError::InvalidJoint { .. })
    ));
}
