//! Tests of the island maps and the held contact forces against independent references: the
//! test utilities' Jacobians (link poses composed joint by joint) and mass matrix
//! (Σ Jᵀ M_l J), statics of an arm, and the first-order effect of a held force.

use super::*;
use crate::control::JointPd;
use crate::integrate::{AdaptiveRk4, Integrator};
use crate::model::{BaseKind, JointSpec, ModelBuilder};
use crate::testutil::{
    alternating_base, random_spec, random_state, reference, reference_mass_matrix, rng,
};
use faer::linalg::solvers::Solve;
use glam::DMat3;
use impulse_geom::{Pose, SpatialInertia};

/// Each link's Jacobian equals the reference's; its response R satisfies M·R = Jᵀ with the
/// reference mass matrix, on 60 random chains and trees (fixed and floating bases, revolute,
/// prismatic and welded joints).
#[test]
fn link_maps_are_the_jacobian_and_m_inverse_j_transpose() {
    let mut r = rng(41);
    for case in 0..60 {
        let spec = random_spec(
            &mut r,
            1 + case % 6,
            alternating_base(case),
            case % 3 == 0,
            true,
        );
        let model = spec.model();
        let (q, _) = random_state(&mut r, &model);
        let mut q = q;
        crate::integrate::normalize_config(&model, &mut q);
        let reference_kin = reference(&spec, &model, &q);
        let m = reference_mass_matrix(&spec, &reference_kin);
        let names: Vec<LinkId> = spec
            .links
            .iter()
            .map(|(n, _)| model.link_id(n).unwrap())
            .collect();
        let maps = link_maps(&model, &q, &names).unwrap();
        let nv = model.nv();
        for (l, map) in maps.iter().enumerate() {
            let j = &reference_kin.jacobians[l];
            for k in 0..nv {
                let (v, w) = map.jacobian[k];
                for a in 0..3 {
                    assert!(
                        (v[a] - j[(a, k)]).abs() < 1e-10 * (1.0 + j[(a, k)].abs()),
                        "case {case}, link {l}, dof {k}: J_v {v:?}"
                    );
                    assert!(
                        (w[a] - j[(3 + a, k)]).abs() < 1e-10 * (1.0 + j[(3 + a, k)].abs()),
                        "case {case}, link {l}, dof {k}: J_ω {w:?}"
                    );
                }
            }
            // M·R column c = (Jᵀ) column c = row c of J.
            for c in 0..6 {
                let col: Vec<f64> = map
                    .response
                    .iter()
                    .map(|(f, t)| if c < 3 { f[c] } else { t[c - 3] })
                    .collect();
                let scale = 1.0 + (0..nv).map(|k| j[(c, k)].abs()).fold(0.0, f64::max);
                for row in 0..nv {
                    let mr: f64 = (0..nv).map(|k| m[(row, k)] * col[k]).sum();
                    assert!(
                        (mr - j[(c, row)]).abs() < 1e-8 * scale,
                        "case {case}, link {l}, wrench axis {c}, dof {row}: M·R {mr} vs Jᵀ {}",
                        j[(c, row)]
                    );
                }
            }
        }
    }
}

fn tight() -> Integrator {
    Integrator::AdaptiveRk4(AdaptiveRk4 {
        rel_tol: 1e-10,
        abs_tol: 1e-10,
        ..AdaptiveRk4::default()
    })
}

/// A horizontal arm (mass m, centre at c from its hinge) held up by a contact force set as
/// the generalized force of a vertical support at its tip, F = m g c / L (statics): it stays
/// at rest over 0.2 s while a controller (zero gains) updates at 1 kHz, whose updates
/// recompute the held forces. Without the support it falls.
#[test]
fn a_held_contact_force_holds_an_arm_through_controller_updates() {
    let (m, c, l, g) = (1.5, 0.4, 0.6, 9.81);
    let mut b = ModelBuilder::new(BaseKind::Fixed);
    b.gravity(DVec3::new(0.0, 0.0, -g))
        .link("ground", SpatialInertia::ZERO)
        .link(
            "arm",
            SpatialInertia::new(m, DVec3::new(c, 0.0, 0.0), DMat3::IDENTITY * 0.02),
        )
        .joint(JointSpec::revolute(
            "shoulder",
            "ground",
            "arm",
            Pose::IDENTITY,
            DVec3::Y,
        ));
    let model = b.build().unwrap();
    let arm = model.link_id("arm").unwrap();
    let mut sim = Simulation::new(model.clone(), vec![0.0], vec![0.0], tight()).unwrap();
    sim.add_controller(Box::new(JointPd::new(0, 0.0, 0.0, 1e-3)))
        .unwrap();
    // Jᵀ·F of the upward force m g c / L at the tip (L, 0, 0).
    let maps = link_maps(&model, sim.q(), &[arm]).unwrap();
    let force = DVec3::new(0.0, 0.0, m * g * c / l);
    let tip = DVec3::new(l, 0.0, 0.0);
    let (jv, jw) = maps[0].jacobian[0];
    let tau = (jv + jw.cross(tip)).dot(force);
    sim.set_contact_forces(&[tau]).unwrap();
    assert!(
        sim.free_acceleration().unwrap()[0].abs() > 1.0,
        "falls without it"
    );
    sim.run_until(0.2).unwrap();
    assert!(sim.q()[0].abs() < 1e-9, "q = {}", sim.q()[0]);
    assert!(sim.v()[0].abs() < 1e-9, "v = {}", sim.v()[0]);
    assert_eq!(sim.contact_forces(), &[tau]);
    // Unheld, it falls as the free acceleration says.
    sim.set_contact_forces(&[0.0]).unwrap();
    let a = sim.free_acceleration().unwrap()[0];
    // m g c = (I_hinge) α, I_hinge = 0.02 + m c² about the y axis; the arm's +x tip goes
    // down, a positive turn about +y.
    let analytic = m * g * c / (0.02 + m * c * c);
    assert!((a - analytic).abs() < 1e-10 * analytic, "{a} vs {analytic}");
    assert!(sim.set_contact_forces(&[f64::NAN]).is_err());
    assert!(sim.set_contact_forces(&[0.0, 1.0]).is_err());
}

/// Over a short interval h from random states, the velocity changes by h·(v̇_free +
/// M⁻¹·τ_c) to first order: the held contact force acts through the mass matrix (reference
/// M), and `free_acceleration` leaves it out.
#[test]
fn a_held_contact_force_accelerates_through_the_mass_matrix() {
    let mut r = rng(7);
    for case in 0..30 {
        let spec = random_spec(&mut r, 1 + case % 5, alternating_base(case), false, true);
        let model = spec.model();
        let (q, v) = random_state(&mut r, &model);
        let mut sim = Simulation::new(model.clone(), q, v, tight()).unwrap();
        let nv = model.nv();
        let tau: Vec<f64> = (0..nv).map(|k| ((k * 7 + case) % 5) as f64 - 2.0).collect();
        sim.set_contact_forces(&tau).unwrap();
        let free = sim.free_acceleration().unwrap();
        let kin = reference(&spec, &model, sim.q());
        let m = reference_mass_matrix(&spec, &kin);
        let dv_tau = m
            .llt(faer::Side::Lower)
            .expect("M is positive definite")
            .solve(&crate::Mat::from_fn(nv, 1, |i, _| tau[i]));
        let v0 = sim.v().to_vec();
        let h = 1e-6;
        sim.run_until(h).unwrap();
        for k in 0..nv {
            let seen = (sim.v()[k] - v0[k]) / h;
            let expect = free[k] + dv_tau[(k, 0)];
            assert!(
                (seen - expect).abs() < 1e-3 * (1.0 + expect.abs()),
                "case {case}, dof {k}: {seen} vs {expect}"
            );
        }
    }
}

/// A two-link arm whose shoulder rests on its stop (it fell onto it, slower than the rest
/// speed) answers an impulse on its forearm as if the shoulder were welded: the shoulder's
/// Δv is zero and the elbow's is (Jᵀf)_elbow / M_elbow,elbow (the Schur complement of the
/// fixed joint, read from the reference mass matrix); and `set_velocity` keeps the shoulder
/// resting, where `set_state` lifts it off.
#[test]
fn a_joint_resting_on_its_stop_does_not_give_way_to_an_impulse() {
    use crate::limit::JointLimit;
    let rod = |m: f64| SpatialInertia::new(m, DVec3::new(0.2, 0.0, 0.0), DMat3::IDENTITY * 0.01);
    let mut b = ModelBuilder::new(BaseKind::Fixed);
    b.gravity(DVec3::new(0.0, 0.0, -9.81))
        .link("ground", SpatialInertia::ZERO)
        .link("upper", rod(1.0))
        .link("fore", rod(0.5))
        .joint(
            JointSpec::revolute("shoulder", "ground", "upper", Pose::IDENTITY, DVec3::Y)
                .with_limit(JointLimit::new(-1.0, 0.0, 0.0)),
        )
        .joint(JointSpec::revolute(
            "elbow",
            "upper",
            "fore",
            Pose::from_translation(DVec3::new(0.4, 0.0, 0.0)),
            DVec3::Z,
        ));
    let model = b.build().unwrap();
    // Gravity turns the horizontal upper arm down, +y rotation: onto its upper stop at 0.
    let mut sim =
        Simulation::new(model.clone(), vec![-1e-4, 0.0], vec![0.0, 0.0], tight()).unwrap();
    sim.run_until(0.2).unwrap();
    assert!(sim.limit_stats().rests >= 1, "{:?}", sim.limit_stats());
    let fore = model.link_id("fore").unwrap();
    let free = link_maps(&model, sim.q(), &[fore]).unwrap();
    let held = sim.link_maps(&[fore]).unwrap();
    let mut m = crate::Mat::<f64>::zeros(2, 2);
    crate::mass_matrix(&model, &mut Workspace::new(&model), sim.q(), &mut m).unwrap();
    for c in 0..6 {
        let at = |r: &(DVec3, DVec3)| if c < 3 { r.0[c] } else { r.1[c - 3] };
        // Jᵀ's column c, row k: the c-th component of the link's twist per unit v_k.
        let jt = |k: usize| {
            let (v, w) = held[0].jacobian[k];
            if c < 3 { v[c] } else { w[c - 3] }
        };
        assert!(at(&held[0].response[0]).abs() < 1e-12, "shoulder moves");
        let elbow = jt(1) / m[(1, 1)];
        assert!(
            (at(&held[0].response[1]) - elbow).abs() < 1e-10 * (1.0 + elbow.abs()),
            "axis {c}: {} vs {elbow}",
            at(&held[0].response[1])
        );
        // Unconstrained, the shoulder gives way (for some axis).
        let _ = at(&free[0].response[0]);
    }
    assert!(
        free[0]
            .response
            .iter()
            .take(1)
            .any(|(f, t)| f.length() + t.length() > 1e-3)
    );
    sim.set_velocity(&[0.3, 2.0]).unwrap();
    assert_eq!(sim.v(), &[0.0, 2.0], "a resting joint keeps still");
    let q = sim.q().to_vec();
    sim.set_state(&q, &[0.0, 2.0]).unwrap();
    sim.set_velocity(&[0.3, 2.0]).unwrap();
    assert_eq!(sim.v(), &[0.3, 2.0], "after set_state nothing rests");
    assert!(sim.set_velocity(&[f64::NAN, 0.0]).is_err());
}

/// The velocity-product accelerations of a point fixed in each link, a + α × r + ω × (ω × r),
/// equal the derivative of its velocity along the path q(t) = q + t·v at constant v (q̈ = 0),
/// taken by central differences of the test utilities' Jacobians and poses (composed joint by
/// joint) — on 40 random spinning chains and trees (revolute and prismatic joints, rates up
/// to 20 rad/s).
#[test]
fn velocity_products_are_the_derivative_of_a_points_velocity_at_constant_rates() {
    /// Central differences' step along the path (s).
    const STEP: f64 = 1e-6;
    /// Their truncation (≈ STEP²·ω³·r, ~1e-10 of ω²·r here) and rounding (≈ 1e-16·v/STEP):
    /// relative to the acceleration scale ω²·r + 1.
    const REL: f64 = 1e-8;
    let mut r = rng(43);
    for case in 0..40 {
        let spec = random_spec(&mut r, 1 + case % 6, BaseKind::Fixed, case % 2 == 0, true);
        let model = spec.model();
        let (q, v) = random_state(&mut r, &model);
        let v: Vec<f64> = v.iter().map(|x| 10.0 * x).collect();
        let mut ws = Workspace::new(&model);
        let kin = velocity_product_accelerations(&model, &mut ws, &q, &v).unwrap();
        let at = |t: f64| -> Vec<f64> { q.iter().zip(&v).map(|(a, b)| a + t * b).collect() };
        for (l, (name, _)) in spec.links.iter().enumerate() {
            let id = model.link_id(name).unwrap();
            let local = DVec3::new(0.3, -0.2, 0.5);
            // The point's velocity at configuration q′ with rates v.
            let velocity = |qq: &[f64]| -> DVec3 {
                let rk = reference(&spec, &model, qq);
                let (pose, j) = (rk.poses[l], &rk.jacobians[l]);
                let (mut lin, mut ang) = (DVec3::ZERO, DVec3::ZERO);
                for (c, rate) in v.iter().enumerate() {
                    lin += DVec3::new(j[(0, c)], j[(1, c)], j[(2, c)]) * *rate;
                    ang += DVec3::new(j[(3, c)], j[(4, c)], j[(5, c)]) * *rate;
                }
                lin + ang.cross(pose.transform_point(local) - pose.translation)
            };
            let fd = (velocity(&at(STEP)) - velocity(&at(-STEP))) / (2.0 * STEP);
            let k = &kin[id.index()];
            let arm = k.pose.transform_point(local) - k.pose.translation;
            let ours = k.acceleration
                + k.angular_acceleration.cross(arm)
                + k.omega.cross(k.omega.cross(arm));
            let scale = k.omega.length_squared() * arm.length() + 1.0;
            assert!(
                (ours - fd).length() <= REL * scale,
                "case {case} link {name}: {ours:?} vs {fd:?}"
            );
        }
    }
}
