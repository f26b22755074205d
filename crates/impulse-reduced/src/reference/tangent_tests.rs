//! The statics' equations against the body-Jacobian form, and their tangent against central
//! differences, on random mechanisms (every joint kind, loops) at random configurations.

use glam::DVec3;
use impulse_geom::pose::so3_right_jacobian;
use rand::RngExt;

use super::*;
use crate::reference::kinematics::{body_jacobian, loop_jacobian, loop_residual};
use crate::testutil::{random_mechanism, rng};

/// Relative step of the central differences the tangent is checked against (times
/// `1 + |θ|`): truncation ~h² ≈ 1e-12, rounding ~ε/h ≈ 2e-10 of the residual's scale.
const FD_STEP: f64 = 1e-6;

/// Agreement of the analytic tangent with central differences, relative to the largest
/// entry of the column's scale (the differences' own error is ~1e-9 of it).
const FD_TOL: f64 = 1e-6;

/// Agreement of the screw form of the equations with the body-Jacobian form, relative to the
/// force scale (two orders of the same sums).
const FORM_TOL: f64 = 1e-12;

fn random_vec3(rng: &mut rand::rngs::Xoshiro256PlusPlus, s: f64) -> DVec3 {
    DVec3::new(
        rng.random_range(-s..s),
        rng.random_range(-s..s),
        rng.random_range(-s..s),
    )
}

#[test]
fn right_jacobian_derivative_matches_differences() {
    let mut rng = rng(21);
    let mut worst = 0.0_f64;
    for case in 0..2000 {
        // Angles from 1e-8 to 3 rad, across the series threshold.
        let t = 10f64.powf(rng.random_range(-8.0..0.5));
        let phi = random_vec3(&mut rng, 1.0).normalize() * t;
        let (a, b) = (random_vec3(&mut rng, 1.0), random_vec3(&mut rng, 1.0));
        let h = FD_STEP;
        let fd =
            (so3_right_jacobian(phi + b * h) * a - so3_right_jacobian(phi - b * h) * a) / (2.0 * h);
        let an = right_jacobian_derivative(phi, b, a);
        let err = (fd - an).length() / (a.length() * b.length());
        worst = worst.max(err);
        assert!(err < FD_TOL, "case {case}: |φ| {t:e}: {an} vs {fd}");
    }
    println!("DJ_r: worst error {worst:e}");
}

/// The mechanisms of the checks: trees and loops with every joint kind.
fn mechanisms() -> Vec<Mechanism> {
    let mut rng = rng(33);
    (0..40)
        .map(|k| {
            random_mechanism(&mut rng, 2 + k % 9, k % 3, 2, 3.0)
                .build()
                .unwrap()
        })
        .collect()
}

/// A random configuration (angles up to ~1.5 rad), multipliers and loads on the end
/// effectors (forces and torques).
fn state(
    m: &Mechanism,
    rng: &mut rand::rngs::Xoshiro256PlusPlus,
) -> (Configuration, Vec<f64>, Vec<Load>) {
    let mut q = Configuration::rest(m);
    for x in &mut q.theta {
        *x = rng.random_range(-0.5..0.5);
    }
    let lambda = (0..6 * m.loop_joints.len())
        .map(|_| rng.random_range(-50.0..50.0))
        .collect();
    let loads = m
        .end_effectors
        .iter()
        .map(|&e| Load {
            link: e,
            force: random_vec3(rng, 20.0),
            torque: random_vec3(rng, 2.0),
        })
        .collect();
    (q, lambda, loads)
}

#[test]
fn screw_form_equals_the_body_jacobian_form() {
    let mut rng = rng(5);
    for (case, m) in mechanisms().iter().enumerate() {
        let topo = Topology::new(m);
        let (q, lambda, loads) = state(m, &mut rng);
        let scale = 0.7;
        let e = evaluate(m, &topo, &q, &lambda, &loads, scale, false);
        // Independently: −Kθ + s Σ J_lᵀ w_l + Σ G_kᵀ λ_k, and r_k.
        let poses = link_poses(m, &q);
        let n = m.ndof;
        let mut f: Vec<f64> = m
            .joints
            .iter()
            .flat_map(|j| (0..j.dof()).map(move |k| (j, k)))
            .map(|(j, k)| -q.theta[j.offset + k] / j.compliance[k])
            .collect();
        for l in &loads {
            let w = l.body_wrench(&poses[l.link]).to_array();
            let jac = body_jacobian(m, &q, &poses, l.link);
            for (c, x) in f.iter_mut().enumerate() {
                *x += scale * (0..6).map(|r| jac[(r, c)] * w[r]).sum::<f64>();
            }
        }
        for (k, &ji) in m.loop_joints.iter().enumerate() {
            let g = loop_jacobian(m, &q, &poses, ji);
            for (c, x) in f.iter_mut().enumerate() {
                *x += (0..6).map(|r| g[(r, c)] * lambda[6 * k + r]).sum::<f64>();
            }
            let r = loop_residual(m, &q, &poses, ji).to_array();
            for (row, x) in r.iter().enumerate() {
                assert!((e.values[n + 6 * k + row] - x).abs() < FORM_TOL);
            }
        }
        for (c, x) in f.iter().enumerate() {
            assert!(
                (e.values[c] - x).abs() <= FORM_TOL * e.force_scale.max(1.0),
                "case {case} coordinate {c}: {} vs {x}",
                e.values[c]
            );
        }
    }
}

/// Every θ-column of the tangent against central differences of the equations at a random
/// configuration (off closure: the force rows are exact there too), and the λ-columns.
#[test]
fn tangent_matches_central_differences() {
    let mut rng = rng(8);
    let mut worst = 0.0_f64;
    for (case, m) in mechanisms().iter().enumerate() {
        let topo = Topology::new(m);
        let (q, lambda, loads) = state(m, &mut rng);
        let e = evaluate(m, &topo, &q, &lambda, &loads, 1.0, true);
        let t = e.tangent.unwrap();
        let n = m.ndof;
        let dim = e.values.len();
        for c in 0..dim {
            let (plus, minus, h) = if c < n {
                let h = FD_STEP * (1.0 + q.theta[c].abs());
                let (mut qp, mut qm) = (q.clone(), q.clone());
                qp.theta[c] += h;
                qm.theta[c] -= h;
                (
                    evaluate(m, &topo, &qp, &lambda, &loads, 1.0, false),
                    evaluate(m, &topo, &qm, &lambda, &loads, 1.0, false),
                    h,
                )
            } else {
                let h = FD_STEP * (1.0 + lambda[c - n].abs());
                let (mut lp, mut lm) = (lambda.clone(), lambda.clone());
                lp[c - n] += h;
                lm[c - n] -= h;
                (
                    evaluate(m, &topo, &q, &lp, &loads, 1.0, false),
                    evaluate(m, &topo, &q, &lm, &loads, 1.0, false),
                    h,
                )
            };
            // Force rows only: the closure rows' G is exact only where the loop is closed.
            let fd: Vec<f64> = (0..n)
                .map(|r| (plus.values[r] - minus.values[r]) / (2.0 * h))
                .collect();
            let size = fd
                .iter()
                .chain((0..n).map(|r| &t[(r, c)]))
                .fold(1.0_f64, |a, x| a.max(x.abs()));
            for (r, x) in fd.iter().enumerate() {
                let err = (t[(r, c)] - x).abs() / size;
                worst = worst.max(err);
                assert!(
                    err < FD_TOL,
                    "case {case} ({} loops): ∂f_{r}/∂x_{c}: analytic {} vs differences {x}",
                    m.loop_joints.len(),
                    t[(r, c)]
                );
            }
        }
    }
    println!("tangent: worst relative error {worst:e}");
}

/// Where the loops are closed (rest), the closure rows are the exact derivative of r.
#[test]
fn closure_rows_are_the_derivative_of_the_closure_where_closed() {
    let mut checked = 0;
    for m in mechanisms().iter().filter(|m| !m.loop_joints.is_empty()) {
        let topo = Topology::new(m);
        let q = Configuration::rest(m);
        let lambda = vec![0.0; 6 * m.loop_joints.len()];
        let e = evaluate(m, &topo, &q, &lambda, &[], 1.0, true);
        let t = e.tangent.unwrap();
        let n = m.ndof;
        for c in 0..n {
            let h = FD_STEP;
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp.theta[c] += h;
            qm.theta[c] -= h;
            let p = evaluate(m, &topo, &qp, &lambda, &[], 1.0, false);
            let mn = evaluate(m, &topo, &qm, &lambda, &[], 1.0, false);
            for r in n..e.values.len() {
                let fd = (p.values[r] - mn.values[r]) / (2.0 * h);
                assert!(
                    (t[(r, c)] - fd).abs() < FD_TOL * (1.0 + fd.abs()),
                    "∂r/∂θ_{c} row {r}: {} vs {fd}",
                    t[(r, c)]
                );
            }
        }
        checked += 1;
    }
    assert!(checked > 5);
}
