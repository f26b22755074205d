use glam::DVec3;
use rand::RngExt;

use crate::testutil::{alternating_base, random_spec, random_state, rng, unit};
use crate::{AdaptiveRk4, Integrator, JointPd, LinkId, LinkTravel, Simulation, Workspace};

/// A tight integrator, so that finite differences of its trajectory measure the derivative.
fn tight() -> Integrator {
    Integrator::AdaptiveRk4(AdaptiveRk4 {
        rel_tol: 1e-13,
        abs_tol: 1e-13,
        ..AdaptiveRk4::default()
    })
}

/// Velocity of every link's frame origin, from the workspace's own kinematics (an independent
/// path: `update_kinematics` + `point_velocity`, not the travel module).
fn origin_velocities(sim: &mut Simulation) -> Vec<(DVec3, DVec3, DVec3)> {
    let model = sim.model().clone();
    let ws: &Workspace = sim.kinematics().unwrap();
    (0..model.link_count())
        .map(|l| {
            let p = ws.link_pose(&model, LinkId(l)).translation;
            let w = ws.link_twist_world(&model, LinkId(l)).w;
            (p, ws.point_velocity(&model, LinkId(l), p), w)
        })
        .collect()
}

#[test]
fn link_accelerations_match_finite_differences_of_the_trajectory() {
    let mut r = rng(41);
    for case in 0..40 {
        let n = 1 + case % 6;
        let spec = random_spec(&mut r, n, alternating_base(case), case % 3 == 0, true);
        let model = spec.model();
        let (q, v) = random_state(&mut r, &model);
        let mut sim = Simulation::new(model, q, v, tight()).unwrap();
        let kin = sim.link_kinematics().unwrap();
        let h = 1e-4;
        let v0 = origin_velocities(&mut sim);
        sim.run_until(h).unwrap();
        let v1 = origin_velocities(&mut sim);
        sim.run_until(2.0 * h).unwrap();
        let v2 = origin_velocities(&mut sim);
        for (l, k) in kin.iter().enumerate() {
            assert!(
                (k.pose.translation - v0[l].0).length() < 1e-12,
                "case {case}"
            );
            assert!((k.velocity - v0[l].1).length() < 1e-12, "case {case}");
            // Second-order one-sided difference of the origin's velocity (the origin is a
            // point fixed in the link, so this is the classical acceleration of that point).
            let fd = (-3.0 * v0[l].1 + 4.0 * v1[l].1 - v2[l].1) / (2.0 * h);
            let scale = 1.0 + k.acceleration.length();
            assert!(
                (fd - k.acceleration).length() < 1e-4 * scale,
                "case {case} link {l}: {} vs finite difference {fd}",
                k.acceleration
            );
            let fw = (-3.0 * v0[l].2 + 4.0 * v1[l].2 - v2[l].2) / (2.0 * h);
            let scale = 1.0 + k.angular_acceleration.length();
            assert!(
                (fw - k.angular_acceleration).length() < 1e-4 * scale,
                "case {case} link {l}: α {} vs finite difference {fw}",
                k.angular_acceleration
            );
        }
    }
}

#[test]
fn tracked_travel_bounds_every_sampled_state_and_the_motion_between() {
    let mut r = rng(42);
    for case in 0..40 {
        let n = 1 + case % 5;
        let spec = random_spec(&mut r, n, alternating_base(case), case % 2 == 0, true);
        let model = spec.model();
        let (q, v) = random_state(&mut r, &model);
        let mut sim = Simulation::new(model, q, v, Integrator::default()).unwrap();
        sim.set_tracking(true);
        let start = origin_velocities(&mut sim);
        let dt = 0.02;
        sim.run_until(dt).unwrap();
        let travel = sim.take_travel().unwrap();
        let end = origin_velocities(&mut sim);
        for (l, t) in travel.iter().enumerate() {
            assert!(t.samples > 0);
            // The end state is the last stage's state of the last step, so it lies within the
            // sampled positions up to that stage's distance from it.
            let d = unit(&mut r);
            let shift = (end[l].0 - start[l].0).dot(d);
            let k = t.speed_along(d, 0.0);
            // Mean speed along d over the interval is at most the largest sampled one (up to the
            // sampling: the samples are dense, RK4 stages every few ms).
            assert!(
                shift <= k * dt + 0.05 * k.abs() * dt + 1e-9,
                "case {case} link {l}: moved {shift} along d, bound {}",
                k * dt
            );
            // A point at distance `reach` moves along d at most as fast as the bound says, at
            // the sampled start state.
            let reach = r.random_range(0.0..2.0);
            let kin = sim.link_kinematics().unwrap();
            let (vel, w) = (kin[l].velocity, kin[l].omega);
            for _ in 0..20 {
                let arm = unit(&mut r) * reach;
                let mut sample = LinkTravel::EMPTY;
                sample.add(0.0, kin[l].pose.translation, vel, w);
                let sample = LinkTravel::EMPTY.union(&sample);
                assert!((vel + w.cross(arm)).dot(d) <= sample.speed_along(d, reach) + 1e-12);
            }
        }
        // Taking resets the ranges.
        assert!(sim.take_travel().unwrap().iter().all(|t| t.samples == 0));
    }
}

#[test]
fn a_copied_simulation_with_controllers_runs_the_same_trajectory() {
    let mut r = rng(43);
    let spec = random_spec(&mut r, 3, crate::BaseKind::Fixed, true, false);
    let model = spec.model();
    let (q, v) = random_state(&mut r, &model);
    let mut sim = Simulation::new(model, q, v, Integrator::default()).unwrap();
    let id = sim
        .add_controller(Box::new(JointPd::new(1, 5.0, 0.5, 0.01)))
        .unwrap();
    sim.run_until(0.1).unwrap();
    let mut copy = sim.clone();
    sim.run_until(0.5).unwrap();
    copy.run_until(0.5).unwrap();
    assert_eq!(sim.q(), copy.q());
    assert_eq!(sim.v(), copy.v());
    // And the copy's controller is its own: changing it leaves the original alone.
    copy.controller_mut::<JointPd>(id).unwrap().kp = 50.0;
    copy.run_until(0.6).unwrap();
    sim.run_until(0.6).unwrap();
    assert_ne!(sim.q(), copy.q());
}

/// A sample's speed bound is exact: the largest `(v + ω × arm)·d` over arms of length r,
/// found by brute force over many arms, reaches it (to the sampling) and never exceeds it.
#[test]
fn a_samples_speed_bound_is_the_largest_point_speed() {
    let mut r = rng(44);
    for _ in 0..200 {
        let s = crate::TravelSample {
            t: 0.0,
            origin: DVec3::ZERO,
            velocity: unit(&mut r) * r.random_range(0.0..3.0),
            omega: unit(&mut r) * r.random_range(0.0..20.0),
        };
        let d = unit(&mut r);
        let reach = r.random_range(0.0..1.0);
        let bound = s.speed_along(d, reach);
        let mut best = f64::NEG_INFINITY;
        for _ in 0..4000 {
            let arm = unit(&mut r) * reach;
            best = best.max((s.velocity + s.omega.cross(arm)).dot(d));
        }
        assert!(best <= bound + 1e-12);
        assert!(
            best >= bound - 0.02 * (1.0 + s.omega.length() * reach),
            "{best} vs {bound}"
        );
    }
}
