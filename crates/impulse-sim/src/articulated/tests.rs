//! Link collisions against conservation laws and the dense joint-space reference.

use glam::{DMat3, DQuat, DVec3};
use impulse_geom::{Pose, SpatialInertia};
use impulse_multibody::{
    BaseKind, JointSpec, LinkId, Mat, Model, ModelBuilder, Workspace, mass_matrix,
};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use super::*;

/// Momentum balances and the joint-space reference, relative to their scale: the
/// recursions and the dense solve differ only in rounding.
const REL: f64 = 1e-10;

fn unit(r: &mut Xoshiro256PlusPlus) -> DVec3 {
    loop {
        let v = DVec3::new(
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
        );
        if (0.1..1.0).contains(&v.length()) {
            return v.normalize();
        }
    }
}

/// A random tree of 1–6 moving links on a floating base: revolute and prismatic joints about
/// random axes, random offsets and inertias; with a random state.
fn random_tree(r: &mut Xoshiro256PlusPlus) -> (Model, Vec<f64>, Vec<f64>) {
    let n = r.random_range(1..=6);
    let mut b = ModelBuilder::new(BaseKind::Floating);
    let inertia = |r: &mut Xoshiro256PlusPlus| {
        let m = r.random_range(0.2..5.0);
        let d = DVec3::new(
            r.random_range(0.01..0.2),
            r.random_range(0.01..0.2),
            r.random_range(0.01..0.2),
        ) * m;
        let rot = DMat3::from_quat(DQuat::from_axis_angle(unit(r), r.random_range(0.0..3.0)));
        let com = unit(r) * r.random_range(0.0..0.2);
        SpatialInertia::new(m, com, rot * DMat3::from_diagonal(d) * rot.transpose())
    };
    let base = inertia(r);
    b.link("l0", base);
    for i in 1..=n {
        let parent = r.random_range(0..i);
        let origin = Pose::new(
            DQuat::from_axis_angle(unit(r), r.random_range(0.0..3.0)),
            unit(r) * r.random_range(0.05..0.5),
        );
        let (p, c) = (format!("l{parent}"), format!("l{i}"));
        let joint = if r.random_bool(0.7) {
            JointSpec::revolute(&format!("j{i}"), &p, &c, origin, unit(r))
        } else {
            JointSpec::prismatic(&format!("j{i}"), &p, &c, origin, unit(r))
        };
        let li = inertia(r);
        b.link(&c, li).joint(joint);
    }
    let model = b.build().expect("a valid random tree");
    let mut q = model.neutral_configuration();
    let rot = DQuat::from_axis_angle(unit(r), r.random_range(0.0..3.0));
    let pos = unit(r) * r.random_range(0.0..1.0);
    q[..7].copy_from_slice(&[pos.x, pos.y, pos.z, rot.x, rot.y, rot.z, rot.w]);
    for x in &mut q[7..] {
        *x = r.random_range(-1.0..1.0);
    }
    let v: Vec<f64> = (0..model.nv()).map(|_| r.random_range(-2.0..2.0)).collect();
    (model, q, v)
}

/// Linear momentum and angular momentum about the world origin of a multibody.
fn momentum(model: &Model, q: &[f64], v: &[f64]) -> (DVec3, DVec3) {
    let mut ws = Workspace::new(model);
    ws.update_kinematics(model, q, v).unwrap();
    let m = ws.momentum(model);
    (m.f, m.tau)
}

fn kinetic(model: &Model, q: &[f64], v: &[f64]) -> f64 {
    let mut ws = Workspace::new(model);
    ws.update_kinematics(model, q, v).unwrap();
    ws.kinetic_energy(model)
}

/// M⁻¹·Jᵀ·p from the dense joint-space mass matrix (CRBA) and the contact Jacobian J of the
/// point `x` on `link` (its columns are the point's velocities for unit joint velocities).
fn dense_response(model: &Model, q: &[f64], link: LinkId, x: DVec3, p: DVec3) -> Vec<f64> {
    let nv = model.nv();
    let mut ws = Workspace::new(model);
    let mut rhs = vec![0.0; nv];
    for (k, out) in rhs.iter_mut().enumerate() {
        let mut e = vec![0.0; nv];
        e[k] = 1.0;
        ws.update_kinematics(model, q, &e).unwrap();
        *out = ws.point_velocity(model, link, x).dot(p);
    }
    dense_solve(model, q, rhs)
}

/// M⁻¹·rhs with M the dense joint-space mass matrix (CRBA) at `q`.
fn dense_solve(model: &Model, q: &[f64], rhs: Vec<f64>) -> Vec<f64> {
    let nv = model.nv();
    let mut ws = Workspace::new(model);
    let mut m = Mat::<f64>::zeros(nv, nv);
    mass_matrix(model, &mut ws, q, &mut m).unwrap();
    let a: Vec<Vec<f64>> = (0..nv)
        .map(|i| (0..nv).map(|j| m[(i, j)]).collect())
        .collect();
    gauss_solve(a, rhs)
}

/// `a⁻¹·rhs` by Gaussian elimination with partial pivoting (small dense systems: the
/// references of tests).
pub(crate) fn gauss_solve(mut a: Vec<Vec<f64>>, mut rhs: Vec<f64>) -> Vec<f64> {
    let nv = rhs.len();
    for col in 0..nv {
        let piv = (col..nv)
            .max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))
            .unwrap();
        a.swap(col, piv);
        rhs.swap(col, piv);
        let pivot_row = a[col].clone();
        for row in col + 1..nv {
            let f = a[row][col] / pivot_row[col];
            for (x, p) in a[row][col..].iter_mut().zip(&pivot_row[col..]) {
                *x -= f * p;
            }
            rhs[row] -= f * rhs[col];
        }
    }
    let mut x_out = vec![0.0; nv];
    for row in (0..nv).rev() {
        let s: f64 = (row + 1..nv).map(|k| a[row][k] * x_out[k]).sum();
        x_out[row] = (rhs[row] - s) / a[row][row];
    }
    x_out
}

fn close(a: &[f64], b: &[f64]) -> bool {
    let scale = b.iter().fold(1e-12_f64, |m, x| m.max(x.abs()));
    a.iter().zip(b).all(|(x, y)| (x - y).abs() <= REL * scale)
}

fn close3(a: DVec3, b: DVec3, scale: f64) -> bool {
    (a - b).length() <= REL * scale.max(1e-12)
}

/// A point near a random link, and that link.
fn contact_on(model: &Model, q: &[f64], r: &mut Xoshiro256PlusPlus) -> (LinkId, DVec3) {
    let link = model
        .link_id(&format!("l{}", r.random_range(0..model.link_count())))
        .unwrap();
    let mut ws = Workspace::new(model);
    ws.update_kinematics(model, q, &vec![0.0; model.nv()])
        .unwrap();
    let at = ws.link_pose(model, link).translation + unit(r) * r.random_range(0.0..0.2);
    (link, at)
}

#[test]
fn random_link_ball_collisions_conserve_momentum_and_match_the_dense_reference() {
    let mut r = Xoshiro256PlusPlus::seed_from_u64(5);
    let mut worst_energy = f64::NEG_INFINITY;
    for case in 0..8000 {
        let (model, q, v0) = random_tree(&mut r);
        let (link, x) = contact_on(&model, &q, &mut r);
        let n = unit(&mut r);
        let (mass, radius) = (r.random_range(0.1..10.0), r.random_range(0.02..0.2));
        let inertia = DMat3::IDENTITY * (0.4 * mass * radius * radius);
        let com = x - n * radius;
        let mut velocity = unit(&mut r) * r.random_range(0.0..3.0);
        let mut omega = unit(&mut r) * r.random_range(0.0..10.0);
        // Make the contact approach: the link's point moves toward the ball along −n.
        let mut ws = Workspace::new(&model);
        ws.update_kinematics(&model, &q, &v0).unwrap();
        let u = ws.point_velocity(&model, link, x) - (velocity + omega.cross(x - com));
        let s = u.dot(n) + r.random_range(0.05..2.0);
        velocity += n * s;
        let (mu, e) = (r.random_range(0.0..2.0), r.random_range(0.0..=1.0));

        let ball = |v: DVec3, w: DVec3| (mass * v, com.cross(mass * v) + inertia * w);
        let (l0, h0) = momentum(&model, &q, &v0);
        let (bl0, bh0) = ball(velocity, omega);
        let e0 = kinetic(&model, &q, &v0)
            + 0.5 * mass * velocity.length_squared()
            + 0.5 * omega.dot(inertia * omega);
        let mut v = v0.clone();
        let hit = {
            let mut a = Collider::Link {
                model: &model,
                q: &q,
                v: &mut v,
                link,
            };
            let mut b = Collider::Rigid {
                mass,
                inertia,
                com,
                velocity: &mut velocity,
                omega: &mut omega,
            };
            collide(&mut a, &mut b, x, n, mu, e).unwrap_or_else(|err| panic!("case {case}: {err}"))
        };
        let p = hit.impulse_world();
        let (l1, h1) = momentum(&model, &q, &v);
        let (bl1, bh1) = ball(velocity, omega);
        let scale = p.length() * (1.0 + x.length())
            + l0.length()
            + h0.length()
            + bl0.length()
            + bh0.length();
        assert!(
            close3(l1 + bl1, l0 + bl0, scale),
            "case {case}: linear momentum"
        );
        assert!(
            close3(h1 + bh1, h0 + bh0, scale),
            "case {case}: angular momentum"
        );
        assert!(
            close3(l1 - l0, p, scale),
            "case {case}: the tree's linear momentum change is not p"
        );
        assert!(
            close3(h1 - h0, x.cross(p), scale),
            "case {case}: the tree's angular momentum change is not x × p"
        );
        let e1 = kinetic(&model, &q, &v)
            + 0.5 * mass * velocity.length_squared()
            + 0.5 * omega.dot(inertia * omega);
        worst_energy = worst_energy.max((e1 - e0) / e0);
        assert!(e1 <= e0 * (1.0 + 1e-9), "case {case}: energy {e0} -> {e1}");
        let dv: Vec<f64> = v.iter().zip(&v0).map(|(a, b)| a - b).collect();
        let reference = dense_response(&model, &q, link, x, p);
        assert!(
            close(&dv, &reference),
            "case {case}: Δv {dv:?} against M⁻¹Jᵀp {reference:?}"
        );
    }
    eprintln!("8000 link–ball collisions: largest relative energy change {worst_energy:e}");
}

#[test]
fn random_link_link_collisions_conserve_momentum_and_match_the_dense_reference() {
    let mut r = Xoshiro256PlusPlus::seed_from_u64(6);
    for case in 0..2000 {
        let (ma, qa, va0) = random_tree(&mut r);
        let (mb, qb, vb0) = random_tree(&mut r);
        let (la, x) = contact_on(&ma, &qa, &mut r);
        let lb = mb
            .link_id(&format!("l{}", r.random_range(0..mb.link_count())))
            .unwrap();
        let n = unit(&mut r);
        let mut vb = vb0.clone();
        // Approach: give tree b's base a velocity along n (its point then moves with it).
        let point = |m: &Model, q: &[f64], v: &[f64], l: LinkId| {
            let mut ws = Workspace::new(m);
            ws.update_kinematics(m, q, v).unwrap();
            ws.point_velocity(m, l, x)
        };
        let u = point(&ma, &qa, &va0, la) - point(&mb, &qb, &vb, lb);
        let s = u.dot(n) + r.random_range(0.05..2.0);
        // The base's linear velocity is in base coordinates (v[..3]).
        let base_rot = DQuat::from_xyzw(qb[3], qb[4], qb[5], qb[6]);
        let push = base_rot.inverse() * (n * s);
        vb[0] += push.x;
        vb[1] += push.y;
        vb[2] += push.z;
        let vb0 = vb.clone();
        let (mu, e) = (r.random_range(0.0..2.0), r.random_range(0.0..=1.0));
        let (la0, ha0) = momentum(&ma, &qa, &va0);
        let (lb0, hb0) = momentum(&mb, &qb, &vb0);
        let e0 = kinetic(&ma, &qa, &va0) + kinetic(&mb, &qb, &vb0);
        let mut va = va0.clone();
        let hit = {
            let mut a = Collider::Link {
                model: &ma,
                q: &qa,
                v: &mut va,
                link: la,
            };
            let mut b = Collider::Link {
                model: &mb,
                q: &qb,
                v: &mut vb,
                link: lb,
            };
            match collide(&mut a, &mut b, x, n, mu, e) {
                Ok(hit) => hit,
                // A link welded to nothing that moves cannot be struck; none here (floating
                // bases), so any error is a failure.
                Err(err) => panic!("case {case}: {err}"),
            }
        };
        let p = hit.impulse_world();
        let (la1, ha1) = momentum(&ma, &qa, &va);
        let (lb1, hb1) = momentum(&mb, &qb, &vb);
        let scale = p.length() * (1.0 + x.length())
            + la0.length()
            + ha0.length()
            + lb0.length()
            + hb0.length();
        assert!(
            close3(la1 + lb1, la0 + lb0, scale),
            "case {case}: linear momentum"
        );
        assert!(
            close3(ha1 + hb1, ha0 + hb0, scale),
            "case {case}: angular momentum"
        );
        let e1 = kinetic(&ma, &qa, &va) + kinetic(&mb, &qb, &vb);
        assert!(e1 <= e0 * (1.0 + 1e-9), "case {case}: energy {e0} -> {e1}");
        let dva: Vec<f64> = va.iter().zip(&va0).map(|(a, b)| a - b).collect();
        let dvb: Vec<f64> = vb.iter().zip(&vb0).map(|(a, b)| a - b).collect();
        assert!(
            close(&dva, &dense_response(&ma, &qa, la, x, p)),
            "case {case}: tree a"
        );
        assert!(
            close(&dvb, &dense_response(&mb, &qb, lb, x, -p)),
            "case {case}: tree b"
        );
    }
}

/// A random tree on a fixed base: as [`random_tree`], but its root link is jointed to the
/// ground by a revolute joint (so every link moves and no momentum is conserved).
fn random_fixed_tree(r: &mut Xoshiro256PlusPlus) -> (Model, Vec<f64>, Vec<f64>) {
    let (floating, _, _) = random_tree(r);
    let n = floating.link_count();
    let mut b = ModelBuilder::new(BaseKind::Fixed);
    b.link("ground", SpatialInertia::ZERO);
    let inertia = SpatialInertia::new(
        r.random_range(0.2..3.0),
        unit(r) * 0.1,
        DMat3::from_diagonal(DVec3::new(0.05, 0.06, 0.07)),
    );
    for i in 0..n {
        let parent = if i == 0 {
            "ground".to_owned()
        } else {
            format!("l{}", r.random_range(0..i))
        };
        let origin = Pose::new(
            DQuat::from_axis_angle(unit(r), r.random_range(0.0..3.0)),
            unit(r) * r.random_range(0.05..0.5),
        );
        let c = format!("l{i}");
        b.link(&c, inertia).joint(JointSpec::revolute(
            &format!("j{i}"),
            &parent,
            &c,
            origin,
            unit(r),
        ));
    }
    let model = b.build().expect("a valid random tree");
    let q: Vec<f64> = (0..model.nq()).map(|_| r.random_range(-1.0..1.0)).collect();
    let v: Vec<f64> = (0..model.nv()).map(|_| r.random_range(-2.0..2.0)).collect();
    (model, q, v)
}

/// Two distinct moving links `l<a>`, `l<b>` of a tree with at least two (not adjacent, as
/// the world pairs them, when `apart`), and a point near the first; `None` when the tree has
/// no such pair.
fn two_links(
    model: &Model,
    q: &[f64],
    r: &mut Xoshiro256PlusPlus,
    apart: bool,
) -> Option<(LinkId, LinkId, DVec3)> {
    let moving: Vec<LinkId> = (0..model.link_count())
        .map_while(|k| model.link_id(&format!("l{k}")))
        .collect();
    let pairs: Vec<(LinkId, LinkId)> = moving
        .iter()
        .flat_map(|&a| moving.iter().map(move |&b| (a, b)))
        .filter(|&(a, b)| a != b && !(apart && model.links_adjacent(a, b).unwrap()))
        .collect();
    if pairs.is_empty() {
        return None;
    }
    let (a, b) = pairs[r.random_range(0..pairs.len())];
    let mut ws = Workspace::new(model);
    ws.update_kinematics(model, q, &vec![0.0; model.nv()])
        .unwrap();
    let x = ws.link_pose(model, a).translation + unit(r) * r.random_range(0.0..0.3);
    Some((a, b, x))
}

/// The dense reference `(J_a − J_b) M⁻¹ (J_a − J_b)ᵀ` in the collision frame `axes`: M by
/// CRBA, solved by Gaussian elimination ([`dense_solve`]); the columns of J_a − J_b are the
/// relative velocities of the point for unit joint velocities.
fn dense_self_k(model: &Model, q: &[f64], a: LinkId, b: LinkId, x: DVec3, axes: DMat3) -> DMat3 {
    let nv = model.nv();
    let mut ws = Workspace::new(model);
    // Rows: collision axes; columns: joint velocities.
    let mut jrel = vec![DVec3::ZERO; nv];
    for (k, col) in jrel.iter_mut().enumerate() {
        let mut e = vec![0.0; nv];
        e[k] = 1.0;
        ws.update_kinematics(model, q, &e).unwrap();
        *col = axes.transpose() * (ws.point_velocity(model, a, x) - ws.point_velocity(model, b, x));
    }
    let mut cols = [DVec3::ZERO; 3];
    for (c, out) in cols.iter_mut().enumerate() {
        let rhs: Vec<f64> = jrel.iter().map(|j| j[c]).collect();
        let y = dense_solve(model, q, rhs);
        *out = jrel.iter().zip(&y).map(|(j, yk)| *j * *yk).sum();
    }
    DMat3::from_cols(cols[0], cols[1], cols[2])
}

fn max_abs(m: &DMat3) -> f64 {
    m.to_cols_array().iter().fold(0.0, |s, x| s.max(x.abs()))
}

/// Energy may rise by rounding only: this fraction of its value before.
const ENERGY_ROUNDING_REL: f64 = 1e-9;
/// The sum of the two links' own K's must miss the one-tree reference by more than this
/// (relative) for the test to tell them apart: far above [`REL`].
const SUM_MISS_MIN_REL: f64 = 1e3 * REL;
/// Largest fraction of random frictional self-collisions the chapter-3 integrator may fail to
/// resolve (singular K; measured 0.04).
const MAX_UNRESOLVED_FRACTION: f64 = 0.1;

/// (a) K of a contact between two links of one tree equals the dense reference
/// `(J_a − J_b) M⁻¹ (J_a − J_b)ᵀ` (CRBA) to [`REL`] of its largest entry, on random floating
/// and fixed trees and random links, points and frames; the sum of the two links' own K's
/// (right only for independent bodies) does not.
#[test]
fn self_collision_matrix_matches_the_dense_reference() {
    let mut r = Xoshiro256PlusPlus::seed_from_u64(13);
    let (mut worst, mut sum_miss) = (0.0f64, f64::INFINITY);
    let mut cases = 0;
    while cases < 1000 {
        let (model, q, _) = if cases % 2 == 0 {
            random_tree(&mut r)
        } else {
            random_fixed_tree(&mut r)
        };
        let Some((a, b, x)) = two_links(&model, &q, &mut r, false) else {
            continue;
        };
        cases += 1;
        let axes = DMat3::from_quat(DQuat::from_axis_angle(
            unit(&mut r),
            r.random_range(0.0..3.0),
        ));
        let k = self_collision_matrix(&model, &q, a, b, x, axes).unwrap();
        let reference = dense_self_k(&model, &q, a, b, x, axes);
        let scale = max_abs(&reference);
        worst = worst.max(max_abs(&(k - reference)) / scale);
        let mut imp = ImpulseDynamics::new(&model, &q).unwrap();
        let sum = imp.collision_matrix_world(&model, a, x, axes).unwrap()
            + imp.collision_matrix_world(&model, b, x, axes).unwrap();
        sum_miss = sum_miss.min(max_abs(&(sum - reference)) / scale);
    }
    eprintln!(
        "self-collision K vs dense: {worst:.2e}; K_a + K_b misses by at least {sum_miss:.2e}"
    );
    assert!(worst <= REL, "K misses the dense reference by {worst:e}");
    assert!(
        sum_miss > SUM_MISS_MIN_REL,
        "the sum of the sides' K's is not told apart"
    );
}

/// (b) Frictionless collisions between two links of one floating tree, random restitution:
/// the tree's linear and angular momentum do not change (an internal impulse) to [`REL`],
/// kinetic energy does not rise, and the relative normal velocity after is −e times before
/// (the closed form of a frictionless collision); with friction, momentum and energy as
/// well. Frictional ones the integrator cannot resolve (its gap on a singular K) are taken
/// frictionless, as the world takes them, and counted ([`MAX_UNRESOLVED_FRACTION`]). Everything
/// is read from the states before and after. The links are never adjacent, as the world
/// pairs them.
#[test]
fn self_collisions_are_internal_and_obey_the_frictionless_closed_form() {
    let mut r = Xoshiro256PlusPlus::seed_from_u64(14);
    let mut cases = 0u32;
    let (mut worst_mom, mut worst_un) = (0.0f64, 0.0f64);
    let mut failed = 0;
    while cases < 2000 {
        let (model, q, v0) = random_tree(&mut r);
        let Some((a, b, x)) = two_links(&model, &q, &mut r, true) else {
            continue;
        };
        let rel = |v: &[f64]| {
            let mut ws = Workspace::new(&model);
            ws.update_kinematics(&model, &q, v).unwrap();
            ws.point_velocity(&model, a, x) - ws.point_velocity(&model, b, x)
        };
        let u0 = rel(&v0);
        // A normal that approaches by at least a tenth of the relative speed.
        let mut n = unit(&mut r);
        if u0.dot(n) > -0.1 * u0.length() {
            n = -u0.normalize();
        }
        cases += 1;
        let mut frictionless = cases % 2 == 0;
        let mut law = Law {
            friction: if frictionless {
                0.0
            } else {
                r.random_range(0.0..1.5)
            },
            restitution: r.random_range(0.0..=1.0),
            micro: None,
            settings: impulse_response::Settings::default(),
        };
        let (l0, h0) = momentum(&model, &q, &v0);
        let e0 = kinetic(&model, &q, &v0);
        let mut v = v0.clone();
        let mut hit = |law: &Law| {
            let mut contact = SelfContact {
                model: &model,
                q: &q,
                v: &mut v,
                a,
                b,
            };
            collide_self(&mut contact, x, n, law)
        };
        let hit = match hit(&law) {
            Ok(hit) => hit,
            // The chapter-3 integrator's known gap: with friction on the rank-deficient K of
            // two links a few joints apart, unstable sticking may have no diverging ray
            // (Theorem 16 needs K positive definite), or the integration its step cap. The
            // world then falls back to a frictionless impulse: so does this test, which
            // counts them and bounds their number below.
            Err(err) if !frictionless => {
                failed += 1;
                eprintln!("case {cases}: {err}");
                (frictionless, law.friction) = (true, 0.0);
                hit(&law).unwrap_or_else(|err| panic!("case {cases}, frictionless: {err}"))
            }
            Err(err) => panic!("case {cases}: {err}"),
        };
        let p = hit.impulse_world();
        let (l1, h1) = momentum(&model, &q, &v);
        let scale = p.length() * (1.0 + x.length()) + l0.length() + h0.length();
        worst_mom = worst_mom.max(((l1 - l0).length() + (h1 - h0).length()) / scale);
        assert!(
            close3(l1, l0, scale),
            "case {cases}: linear momentum {l0} -> {l1}"
        );
        assert!(
            close3(h1, h0, scale),
            "case {cases}: angular momentum {h0} -> {h1}"
        );
        let e1 = kinetic(&model, &q, &v);
        assert!(
            e1 <= e0 * (1.0 + ENERGY_ROUNDING_REL),
            "case {cases}: energy {e0} -> {e1}"
        );
        if frictionless {
            let (un0, un1) = (u0.dot(n), rel(&v).dot(n));
            let want = -law.restitution * un0;
            worst_un = worst_un.max((un1 - want).abs() / un0.abs());
            assert!(
                (un1 - want).abs() <= REL * un0.abs(),
                "case {cases}: normal velocity {un0} -> {un1}, e = {}",
                law.restitution
            );
        }
    }
    eprintln!(
        "self-collisions: momentum {worst_mom:.2e}, u_n after vs −e u_n {worst_un:.2e}, \
         {failed} frictional ones unresolved"
    );
    assert!(
        failed as f64 <= MAX_UNRESOLVED_FRACTION * f64::from(cases),
        "{failed} of {cases} frictional collisions unresolved"
    );
}

/// Adjacency as self-collision excludes it: one rigid body (welded by fixed joints) and
/// parent–child of a moving joint; siblings and grandparent–grandchild are not adjacent;
/// an unknown link is an error. Two links of one tree given to [`collide`] are refused
/// (their responses are coupled), and a link cannot strike itself.
#[test]
fn adjacency_and_refusals() {
    let i = SpatialInertia::new(1.0, DVec3::ZERO, DMat3::IDENTITY * 0.01);
    let o = Pose::from_translation(DVec3::X * 0.3);
    let mut b = ModelBuilder::new(BaseKind::Fixed);
    b.link("ground", SpatialInertia::ZERO);
    for name in ["a", "a2", "b", "c", "s"] {
        b.link(name, i);
    }
    b.joint(JointSpec::revolute("ja", "ground", "a", o, DVec3::Y))
        .joint(JointSpec::fixed("weld", "a", "a2", o))
        .joint(JointSpec::revolute("jb", "a2", "b", o, DVec3::Y))
        .joint(JointSpec::revolute("jc", "b", "c", o, DVec3::Y))
        .joint(JointSpec::revolute("js", "a", "s", o, DVec3::Z));
    let model = b.build().unwrap();
    let id = |n: &str| model.link_id(n).unwrap();
    let adj = |x: &str, y: &str| model.links_adjacent(id(x), id(y)).unwrap();
    // Welded, parent–child (through the weld too), jointed to the ground.
    assert!(adj("a", "a2") && adj("a", "b") && adj("a2", "b") && adj("b", "c"));
    assert!(adj("a", "s") && adj("ground", "a") && adj("c", "c"));
    // Grandparent–grandchild, siblings, cousins.
    assert!(!adj("a", "c") && !adj("a2", "c") && !adj("b", "s") && !adj("s", "c"));
    assert!(!adj("ground", "b"));
    // A link id of a bigger model names no link of this one.
    let mut big = ModelBuilder::new(BaseKind::Fixed);
    big.link("ground", SpatialInertia::ZERO);
    for k in 0..9 {
        big.link(&format!("x{k}"), i).joint(JointSpec::revolute(
            &format!("j{k}"),
            "ground",
            &format!("x{k}"),
            o,
            DVec3::Y,
        ));
    }
    let stranger = big.build().unwrap().link_id("x8").unwrap();
    assert!(model.links_adjacent(id("a"), stranger).is_err());
    assert!(
        self_collision_matrix(
            &model,
            &[0.0; 4],
            id("a"),
            stranger,
            DVec3::ZERO,
            DMat3::IDENTITY
        )
        .is_err()
    );
    let q = vec![0.1, 0.2, 0.3, 0.4];
    let mut v = vec![1.0; 4];
    let mut w = v.clone();
    let err = collide(
        &mut Collider::Link {
            model: &model,
            q: &q,
            v: &mut v,
            link: id("a"),
        },
        &mut Collider::Link {
            model: &model,
            q: &q,
            v: &mut w,
            link: id("c"),
        },
        DVec3::ZERO,
        DVec3::Z,
        0.0,
        0.5,
    )
    .unwrap_err();
    assert!(err.to_string().contains("one multibody"), "{err}");
    let err = self_collision_matrix(&model, &q, id("c"), id("c"), DVec3::ZERO, DMat3::IDENTITY)
        .unwrap_err();
    assert!(err.to_string().contains("\"c\""), "{err}");
}
