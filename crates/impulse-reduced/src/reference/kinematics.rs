//! Kinematics of the full model in joint coordinates θ.
//!
//! A joint's motion in its own frame is `E(θ) = (exp(φ), t)` with rotation vector
//! `φ = Σ θ_k a_k` over its rotational directions and translation `t = Σ θ_k a_k` over its
//! translational ones (a weld translates, then rotates about the moved anchor). A link placed by
//! tree joint j is at `H_c = H_p · P · E(θ_j) · Q⁻¹` (P, Q: the joint frame in parent and child).
//! At θ = 0 every link is at rest. Jacobians are body Jacobians: column k of `J_l` is the
//! body-frame twist of link l per unit of coordinate k (`δH_l = H_l·(J_l δθ)^`).

use faer::Mat;
use glam::{DMat3, DVec3};
use impulse_geom::pose::so3_right_jacobian;
use impulse_geom::se3::so3_exp;
use impulse_geom::{Mat6, Pose, Twist};

use crate::mechanism::{Direction, Joint, Mechanism};

/// A configuration of the full model: the base pose and every joint coordinate.
#[derive(Clone, Debug, PartialEq)]
pub struct Configuration {
    /// Pose of the base link (world); its rest pose for a fixed base.
    pub base: Pose,
    /// Stacked joint coordinates θ (length `Mechanism::ndof`, joint `offset`s).
    pub theta: Vec<f64>,
}

impl Configuration {
    /// The rest configuration: base at rest, θ = 0.
    #[must_use]
    pub fn rest(m: &Mechanism) -> Self {
        Configuration {
            base: m.links[m.base].rest,
            theta: vec![0.0; m.ndof],
        }
    }
}

/// Rotation vector and translation of a joint at coordinates `theta` (the joint's own slice).
fn split(joint: &Joint, theta: &[f64]) -> (DVec3, DVec3) {
    let (mut phi, mut t) = (DVec3::ZERO, DVec3::ZERO);
    for ((d, a), &q) in joint.directions.iter().zip(theta) {
        match d {
            Direction::Rotation => phi += *a * q,
            Direction::Translation => t += *a * q,
        }
    }
    (phi, t)
}

/// The joint's relative motion `E(θ)` (child joint frame in parent joint frame).
#[must_use]
pub fn joint_motion(joint: &Joint, theta: &[f64]) -> Pose {
    let (phi, t) = split(joint, theta);
    Pose {
        rotation: so3_exp(phi),
        translation: t,
    }
}

/// Body Jacobian of `E(θ)` (columns: twists of the child joint frame in its own coordinates per
/// unit coordinate): `(Rᵀa, 0)` for a translation, `(0, J_r(φ)a)` for a rotation.
#[must_use]
pub fn joint_jacobian(joint: &Joint, theta: &[f64]) -> Vec<Twist> {
    let (phi, _) = split(joint, theta);
    let rt = DMat3::from_quat(so3_exp(phi)).transpose();
    let jr = so3_right_jacobian(phi);
    joint
        .directions
        .iter()
        .map(|(d, a)| match d {
            Direction::Translation => Twist::new(rt * *a, DVec3::ZERO),
            Direction::Rotation => Twist::new(DVec3::ZERO, jr * *a),
        })
        .collect()
}

/// World poses of all links at configuration `q` (walk order, tree joints).
#[must_use]
pub fn link_poses(m: &Mechanism, q: &Configuration) -> Vec<Pose> {
    let mut poses = vec![Pose::IDENTITY; m.links.len()];
    poses[m.base] = q.base;
    for &l in &m.order[1..] {
        let Some(ji) = m.tree_joint[l] else { continue };
        let j = &m.joints[ji];
        let th = &q.theta[j.offset..j.offset + j.dof()];
        poses[l] = poses[j.parent] * j.in_parent * joint_motion(j, th) * j.in_child.inverse();
    }
    poses
}

/// Body Jacobian of link `l` (6 × ndof, linear rows on top) at configuration `q` with link
/// poses `poses` (from [`link_poses`]). Only the tree joints on the path to the base appear.
#[must_use]
pub fn body_jacobian(m: &Mechanism, q: &Configuration, poses: &[Pose], l: usize) -> Mat<f64> {
    let mut jac = Mat::<f64>::zeros(6, m.ndof);
    let inv_l = poses[l].inverse();
    let mut k = l;
    while let Some(ji) = m.tree_joint[k] {
        let j = &m.joints[ji];
        // Child-side joint frame of j, in world; its twists move link l rigidly.
        let frame = poses[j.child] * j.in_child;
        let to_l = inv_l * frame;
        let th = &q.theta[j.offset..j.offset + j.dof()];
        for (c, s) in joint_jacobian(j, th).iter().enumerate() {
            let col = to_l.transform_twist(s).to_array();
            jac.col_as_slice_mut(j.offset + c).copy_from_slice(&col);
        }
        k = j.parent;
    }
    jac
}

/// The loop-closure residual of loop joint `ji`: `log((H_p P E(θ_j))⁻¹ · H_c Q)`, the twist
/// (parent-side joint frame) that separates the two sides of the joint. Zero when closed.
#[must_use]
pub fn loop_residual(m: &Mechanism, q: &Configuration, poses: &[Pose], ji: usize) -> Twist {
    let j = &m.joints[ji];
    let th = &q.theta[j.offset..j.offset + j.dof()];
    let a = poses[j.parent] * j.in_parent * joint_motion(j, th);
    let b = poses[j.child] * j.in_child;
    (a.inverse() * b).log()
}

/// Jacobian (6 × ndof) of the loop closure of joint `ji`: the body twist of the child-side joint
/// frame minus that of the parent-side frame moved by the joint, both in the parent-side frame.
/// It is the exact derivative of [`loop_residual`] wherever the loop is closed.
#[must_use]
pub fn loop_jacobian(m: &Mechanism, q: &Configuration, poses: &[Pose], ji: usize) -> Mat<f64> {
    let j = &m.joints[ji];
    let th = &q.theta[j.offset..j.offset + j.dof()];
    let e = joint_motion(j, th);
    let a = poses[j.parent] * j.in_parent * e;
    let b = poses[j.child] * j.in_child;
    let jc = body_jacobian(m, q, poses, j.child);
    let jp = body_jacobian(m, q, poses, j.parent);
    // Express both in the frame `a` (equal to `b` where closed).
    let ad_c = (a.inverse() * poses[j.child]).adjoint();
    let ad_p = (a.inverse() * poses[j.parent]).adjoint();
    let mut g = mat6_times(&ad_c, &jc);
    let gp = mat6_times(&ad_p, &jp);
    for c in 0..g.ncols() {
        for (x, &y) in g.col_as_slice_mut(c).iter_mut().zip(gp.col_as_slice(c)) {
            *x -= y;
        }
    }
    let _ = b;
    for (c, s) in joint_jacobian(j, th).iter().enumerate() {
        let col = s.to_array();
        for (r, x) in col.iter().enumerate() {
            g[(r, j.offset + c)] -= *x;
        }
    }
    g
}

/// `a · b` for a 6×6 `a` and a 6×n faer matrix `b`.
#[must_use]
pub fn mat6_times(a: &Mat6, b: &Mat<f64>) -> Mat<f64> {
    // Column by column through slices: the same products and sums as indexing element by
    // element, without faer's per-element index calls (not inlined in the test profile, where
    // they were most of the full statics' time).
    // A column of +0.0 (a body Jacobian is zero off the link's path to the base) gives, as
    // the sum below would, -0.0 in row r when every a[r][k] has its sign bit set and +0.0
    // otherwise (for a finite `a`): copied rather than computed, bit for bit the same.
    let rows = a.to_rows();
    let finite = rows.iter().flatten().all(|x| x.is_finite());
    let zero_image = rows.map(|row| {
        if row.iter().all(|x| x.is_sign_negative()) {
            -0.0
        } else {
            0.0
        }
    });
    let mut out = Mat::<f64>::zeros(6, b.ncols());
    for c in 0..b.ncols() {
        let col = b.col_as_slice(c);
        if finite && col.iter().all(|x| x.to_bits() == 0) {
            out.col_as_slice_mut(c).copy_from_slice(&zero_image);
            continue;
        }
        for (x, row) in out.col_as_slice_mut(c).iter_mut().zip(&rows) {
            // As `Iterator::sum` for f64: from -0.0, in order.
            let mut acc = -0.0;
            for (a, b) in row.iter().zip(col) {
                acc += a * b;
            }
            *x = acc;
        }
    }
    out
}
