//! Forward dynamics (articulated-body algorithm), inverse dynamics (recursive Newton–Euler),
//! the joint-space mass matrix (composite rigid bodies), kinematics, energy and momentum.

use faer::Mat;
use glam::{DMat3, DQuat, DVec3};
use impulse_geom::{Pose, Twist, Wrench};

use crate::error::MultibodyError;
use crate::model::{BodyJoint, LinkId, Model, check_len};
use crate::spatial::{Sym6, Xform, axis_angle, rt_mul};

/// Per-body scratch data of the recursions.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BodyWork {
    /// Body frame in the parent body's frame (the thesis's `_hX̂_i` and its inverse).
    pub x: Xform,
    /// Spatial velocity `v̂_i` (body coordinates).
    pub v: Twist,
    /// Velocity-product acceleration `ĉ_i` (Def. 10, spatial form).
    pub c: Twist,
    /// Articulated inertia `Î_i^A` (or composite inertia in CRBA).
    pub ia: Sym6,
    /// Articulated bias force `Ẑ_i^A` (or the body force in RNEA).
    pub pa: Wrench,
    /// `U_i = Î_i^A ŝ_i`.
    pub u: Wrench,
    /// `1 / D_i`, `D_i = ŝ_i' Î_i^A ŝ_i`.
    pub inv_d: f64,
    /// `u_i = Q_i − ŝ_i'(Ẑ_i^A)` (the numerator term of eq. 4.27 without the parent part).
    pub uu: f64,
    /// Spatial acceleration `â_i` (with the fictitious gravity offset).
    pub a: Twist,
}

impl BodyWork {
    const ZERO: BodyWork = BodyWork {
        x: Xform::IDENTITY,
        v: Twist::ZERO,
        c: Twist::ZERO,
        ia: Sym6::ZERO,
        pa: Wrench::ZERO,
        u: Wrench::ZERO,
        inv_d: 0.0,
        uu: 0.0,
        a: Twist::ZERO,
    };
}

/// Preallocated scratch space for the recursions of one [`Model`]: [`forward_dynamics`],
/// [`inverse_dynamics`] and [`mass_matrix`] allocate nothing when given a workspace.
///
/// After [`Workspace::update_kinematics`] it also answers kinematic queries (link poses,
/// velocities, energies, momentum) for the configuration and velocity it was given.
#[derive(Clone, Debug)]
pub struct Workspace {
    pub(crate) bodies: Vec<BodyWork>,
    /// World pose of each body (filled by `update_kinematics`).
    pub(crate) world: Vec<Xform>,
}

impl Workspace {
    /// Scratch space sized for `model`.
    #[must_use]
    pub fn new(model: &Model) -> Self {
        Workspace {
            bodies: vec![BodyWork::ZERO; model.body_count()],
            world: vec![Xform::IDENTITY; model.body_count()],
        }
    }

    /// A workspace made for another model is a dimension error, not a panic.
    fn check(&self, model: &Model) -> Result<(), MultibodyError> {
        check_len("workspace bodies", model.body_count(), self.bodies.len())
    }

    /// Computes the world pose and spatial velocity (body coordinates) of every body for
    /// configuration `q` and velocity `v` (thesis Fig. 4.11, compTreeLinkVelocities).
    ///
    /// # Errors
    /// [`MultibodyError::DimensionMismatch`] for wrong lengths.
    pub fn update_kinematics(
        &mut self,
        model: &Model,
        q: &[f64],
        v: &[f64],
    ) -> Result<(), MultibodyError> {
        check_len("q", model.nq(), q.len())?;
        check_len("v", model.nv(), v.len())?;
        self.check(model)?;
        velocities(model, &mut self.bodies, q, v);
        for i in 0..model.body_count() {
            let x = self.bodies[i].x;
            self.world[i] = match model.bodies[i].parent {
                Some(p) => self.world[p].compose(&x),
                None => x,
            };
        }
        Ok(())
    }

    /// World pose of a link (after [`Workspace::update_kinematics`]).
    #[must_use]
    pub fn link_pose(&self, model: &Model, link: LinkId) -> Pose {
        self.link_xform(model, link).to_pose()
    }

    pub(crate) fn link_xform(&self, model: &Model, link: LinkId) -> Xform {
        let info = &model.links[link.0];
        match info.body {
            Some(b) => self.world[b].compose(&info.offset),
            None => info.offset,
        }
    }

    /// World-frame velocity (m/s) of the point `point` (world coordinates) moving with `link`
    /// (after [`Workspace::update_kinematics`]).
    #[must_use]
    pub fn point_velocity(&self, model: &Model, link: LinkId, point: DVec3) -> DVec3 {
        match model.links[link.0].body {
            None => DVec3::ZERO,
            Some(b) => {
                let w = &self.world[b];
                let t = w.motion_to_parent(&self.bodies[b].v);
                t.v + t.w.cross(point)
            }
        }
    }

    /// World-frame spatial velocity of a link: linear part = velocity of the body point at the
    /// world origin, angular part = angular velocity, world axes.
    #[must_use]
    pub fn link_twist_world(&self, model: &Model, link: LinkId) -> Twist {
        match model.links[link.0].body {
            None => Twist::ZERO,
            Some(b) => self.world[b].motion_to_parent(&self.bodies[b].v),
        }
    }

    /// Kinetic energy `Σ ½ v̂_i' Î_i v̂_i` (J) for the state of the last
    /// [`Workspace::update_kinematics`].
    #[must_use]
    pub fn kinetic_energy(&self, model: &Model) -> f64 {
        model
            .bodies
            .iter()
            .zip(&self.bodies)
            .map(|(b, w)| b.inertia.kinetic_energy(&w.v))
            .sum()
    }

    /// Gravitational potential energy `−Σ m_i g·c_i` (J), zero when every centre of mass is
    /// at the world origin.
    #[must_use]
    pub fn potential_energy(&self, model: &Model) -> f64 {
        model
            .bodies
            .iter()
            .zip(&self.world)
            .map(|(b, w)| -b.inertia.mass * model.gravity.dot(w.point_to_parent(b.inertia.com)))
            .sum()
    }

    /// Total momentum of the moving bodies in world coordinates: linear momentum (kg·m/s) and
    /// angular momentum about the world origin (kg·m²/s).
    #[must_use]
    pub fn momentum(&self, model: &Model) -> Wrench {
        model
            .bodies
            .iter()
            .zip(&self.bodies)
            .zip(&self.world)
            .fold(Wrench::ZERO, |acc, ((b, w), x)| {
                acc + x.force_to_parent(&b.inertia.mul_twist(&w.v))
            })
    }

    /// World-frame centre of mass of the moving bodies (m); NaN for a model without moving
    /// bodies.
    #[must_use]
    pub fn center_of_mass(&self, model: &Model) -> DVec3 {
        let (m, s) =
            model
                .bodies
                .iter()
                .zip(&self.world)
                .fold((0.0, DVec3::ZERO), |(m, s), (b, w)| {
                    (
                        m + b.inertia.mass,
                        s + w.point_to_parent(b.inertia.com) * b.inertia.mass,
                    )
                });
        s / m
    }
}

/// Body frame in its parent's frame for joint position `qi` (URDF semantics: the joint origin,
/// then the joint motion).
#[inline]
pub(crate) fn joint_xform(
    origin: &Xform,
    joint: BodyJoint,
    axis_in_parent: DVec3,
    qi: f64,
) -> Xform {
    match joint {
        BodyJoint::Revolute(u) => Xform {
            r: origin.r * axis_angle(u, qi),
            p: origin.p,
        },
        BodyJoint::Prismatic(_) => Xform {
            r: origin.r,
            p: origin.p + axis_in_parent * qi,
        },
        BodyJoint::Floating => origin.to_owned(),
    }
}

/// The floating base's pose from `q[0..7] = [x, y, z, qx, qy, qz, qw]` (quaternion normalised).
#[inline]
pub(crate) fn base_xform(q: &[f64]) -> Xform {
    let rot = DQuat::from_xyzw(q[3], q[4], q[5], q[6]).normalize();
    Xform {
        r: DMat3::from_quat(rot),
        p: DVec3::new(q[0], q[1], q[2]),
    }
}

/// `S q̇` for a 1-DOF joint: `ŝ = (0, u)` revolute, `(u, 0)` prismatic (Def. 9, at the joint
/// frame origin, so the thesis's `u × d` term vanishes).
#[inline]
fn joint_motion(joint: BodyJoint, qd: f64) -> Twist {
    match joint {
        BodyJoint::Revolute(u) => Twist::new(DVec3::ZERO, u * qd),
        BodyJoint::Prismatic(u) => Twist::new(u * qd, DVec3::ZERO),
        BodyJoint::Floating => Twist::ZERO,
    }
}

/// `ŝ' f` (Lemma 7: the joint force carried by the spatial force f).
#[inline]
fn joint_force(joint: BodyJoint, f: &Wrench) -> f64 {
    match joint {
        BodyJoint::Revolute(u) => u.dot(f.tau),
        BodyJoint::Prismatic(u) => u.dot(f.f),
        BodyJoint::Floating => 0.0,
    }
}

/// `U = Î ŝ` for a 1-DOF joint.
#[inline]
fn inertia_times_axis(joint: BodyJoint, ia: &Sym6) -> Wrench {
    match joint {
        BodyJoint::Revolute(u) => Wrench::new(ia.b * u, ia.c * u),
        BodyJoint::Prismatic(u) => Wrench::new(ia.a * u, rt_mul(&ia.b, u)),
        BodyJoint::Floating => Wrench::ZERO,
    }
}

/// Pass 1, base to tip: transforms, velocities (4.16)/(4.12) in spatial form, velocity-product
/// terms ĉ (Def. 10). Returns nothing; fills `x`, `v`, `c`.
fn velocities(model: &Model, ws: &mut [BodyWork], q: &[f64], v: &[f64]) {
    let nb = model.first_joint_body();
    let (qo, vo) = (model.nq() - model.joint_count(), model.base_dofs());
    if nb == 1 {
        let w = &mut ws[0];
        w.x = base_xform(q);
        w.v = Twist::from_array([v[0], v[1], v[2], v[3], v[4], v[5]]);
        w.c = Twist::ZERO;
    }
    for i in nb..model.body_count() {
        let body = &model.bodies[i];
        let j = i - nb;
        let (qi, qdi) = (q[qo + j], v[vo + j]);
        let x = joint_xform(&body.origin, body.joint, body.axis_in_parent, qi);
        let sq = joint_motion(body.joint, qdi);
        let (vi, ci) = match body.parent {
            Some(p) => {
                let vp = x.motion_to_child(&ws[p].v);
                let vi = vp + sq;
                // ĉ_i = v̂_i × ŝ_i q̇_i (spatial form of Def. 10).
                (vi, vi.cross_motion(&sq))
            }
            None => (sq, Twist::ZERO),
        };
        let w = &mut ws[i];
        w.x = x;
        w.v = vi;
        w.c = ci;
    }
}

/// Gravity as the fictitious base acceleration `−g` (Featherstone's device: every spatial
/// acceleration below is offset by −g, which leaves joint accelerations unchanged), in world
/// coordinates.
#[inline]
fn gravity_accel(model: &Model) -> Twist {
    Twist::new(-model.gravity, DVec3::ZERO)
}

/// Forward dynamics by the articulated-body algorithm (thesis Fig. 4.14 treeFwdDynamics, with
/// the floating-base bootstrap of §4.6): given `q` (nq), `v` (nv), the generalized forces `tau`
/// (nv: joint forces/torques; with a floating base the first six entries are a wrench on the
/// base in base coordinates) and optional external wrenches `f_ext` (one per body, in the body
/// frame, about its origin), writes `vdot = v̇` (nv). O(n), allocation-free.
///
/// Passive joint elements are *not* included; add them to `tau` first
/// ([`Model::add_passive_forces`]) or use [`crate::Simulation`].
///
/// # Errors
/// [`MultibodyError::DimensionMismatch`] for wrong lengths (or a workspace made for another
/// model); [`MultibodyError::SingularInertia`]
/// if the floating base's articulated inertia is not positive definite (non-finite input).
pub fn forward_dynamics(
    model: &Model,
    ws: &mut Workspace,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    f_ext: Option<&[Wrench]>,
    vdot: &mut [f64],
) -> Result<(), MultibodyError> {
    check_dynamics_inputs(model, ws, q, v, tau, f_ext)?;
    check_len("vdot", model.nv(), vdot.len())?;
    let wb = &mut ws.bodies[..];
    let nb = model.first_joint_body();
    let vo = model.base_dofs();
    let n = model.body_count();

    // Pass 1 (Figs. 4.11 and 4.13): velocities, ĉ, isolated inertias and z.a. forces.
    velocities(model, wb, q, v);
    for (i, (w, body)) in wb.iter_mut().zip(&model.bodies).enumerate() {
        w.ia = body.inertia6;
        // Isolated z.a. force Ẑ_i = v̂ ×* Î v̂ − f_ext (Def. 13 in spatial form; gravity is
        // carried by the base acceleration).
        let h = body.inertia.mul_twist(&w.v);
        w.pa = w.v.cross_force(&h);
        if let Some(f) = f_ext {
            w.pa -= f[i];
        }
    }
    if nb == 1 {
        // Applied base wrench acts like an external force on body 0.
        wb[0].pa -= Wrench::from_array([tau[0], tau[1], tau[2], tau[3], tau[4], tau[5]]);
    }

    // Pass 2, tip to base: articulated inertias and z.a. forces, eqs. (4.33), (4.34).
    for i in (nb..n).rev() {
        let body = &model.bodies[i];
        let (head, tail) = wb.split_at_mut(i);
        let w = &mut tail[0];
        let u = inertia_times_axis(body.joint, &w.ia);
        let d = joint_force(body.joint, &u);
        w.u = u;
        w.inv_d = 1.0 / d;
        // u_i = Q_i − ŝ_i'Ẑ_i^A (the thesis's Q − ŝ'(Ẑ^A + Î^Aĉ) with Î^Aĉ moved to pass 3,
        // as Featherstone does; the sum is the same).
        w.uu = tau[vo + i - nb] - joint_force(body.joint, &w.pa);
        if let Some(p) = body.parent {
            // Î^a = Î^A − U Uᵀ / D (eq. 4.33, bracket).
            let ia = w.ia.minus_outer(&u, w.inv_d);
            // Ẑ^a = Ẑ^A + Î^a ĉ + U u / D (eq. 4.34, bracket).
            let pa = w.pa + ia.mul(&w.c) + u * (w.uu * w.inv_d);
            let parent = &mut head[p];
            parent.ia.add_assign(&ia.to_parent(&w.x));
            parent.pa += w.x.force_to_parent(&pa);
        }
    }

    // Pass 3, base to tip: accelerations (4.27)/(4.32) and (4.30).
    let g = gravity_accel(model);
    if nb == 1 {
        // â_1 = −(Î_1^A)^{-1} Ẑ_1^A (§4.6), in the freely falling frame.
        let w = &mut wb[0];
        let a =
            w.ia.solve(&(-w.pa))
                .ok_or_else(|| MultibodyError::SingularInertia {
                    link: model.body_name(0).to_owned(),
                })?;
        w.a = a;
        // True base acceleration = fictitious one + gravity, in base coordinates.
        let ab = a - w.x.motion_to_child(&g);
        vdot[..6].copy_from_slice(&ab.to_array());
    }
    for i in nb..n {
        let body = &model.bodies[i];
        let (head, tail) = wb.split_at_mut(i);
        let w = &mut tail[0];
        let ap = match body.parent {
            Some(p) => w.x.motion_to_child(&head[p].a),
            None => w.x.motion_to_child(&g),
        } + w.c;
        // q̈_i = (u_i − U_i'(_iX̂_h â_h + ĉ_i)) / D_i (eq. 4.27).
        let qdd = (w.uu - w.u.power(&ap)) * w.inv_d;
        // â_i = _iX̂_h â_h + ĉ_i + q̈_i ŝ_i (eq. 4.30).
        w.a = ap + joint_motion(body.joint, qdd);
        vdot[vo + i - nb] = qdd;
    }
    Ok(())
}

/// Inverse dynamics by the recursive Newton–Euler algorithm: the generalized forces `tau` (nv)
/// that produce the accelerations `vdot` (nv) at `(q, v)` under gravity and the external
/// wrenches `f_ext` (per body, body frame). With a floating base, `tau[0..6]` is the wrench the
/// base would need (zero when `vdot` is the free motion). `M(q) v̇ + h(q, v) = τ`; computed
/// torque (thesis eq. 5.16) is this function. O(n), allocation-free.
///
/// # Errors
/// [`MultibodyError::DimensionMismatch`] for wrong lengths.
pub fn inverse_dynamics(
    model: &Model,
    ws: &mut Workspace,
    q: &[f64],
    v: &[f64],
    vdot: &[f64],
    f_ext: Option<&[Wrench]>,
    tau: &mut [f64],
) -> Result<(), MultibodyError> {
    check_len("vdot", model.nv(), vdot.len())?;
    rnea(model, ws, q, v, Some(vdot), f_ext, tau)
}

/// The checks ABA and RNEA share: lengths of `q` (nq), `v` and `tau` (nv) and `f_ext` (one
/// wrench per body), and a workspace made for `model`.
fn check_dynamics_inputs(
    model: &Model,
    ws: &Workspace,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    f_ext: Option<&[Wrench]>,
) -> Result<(), MultibodyError> {
    check_len("q", model.nq(), q.len())?;
    check_len("v", model.nv(), v.len())?;
    check_len("tau", model.nv(), tau.len())?;
    if let Some(f) = f_ext {
        check_len("f_ext", model.body_count(), f.len())?;
    }
    ws.check(model)
}

/// RNEA with `vdot = None` meaning zero acceleration.
fn rnea(
    model: &Model,
    ws: &mut Workspace,
    q: &[f64],
    v: &[f64],
    vdot: Option<&[f64]>,
    f_ext: Option<&[Wrench]>,
    tau: &mut [f64],
) -> Result<(), MultibodyError> {
    check_dynamics_inputs(model, ws, q, v, tau, f_ext)?;
    let acc = |k: usize| vdot.map_or(0.0, |a| a[k]);
    let wb = &mut ws.bodies[..];
    let nb = model.first_joint_body();
    let vo = model.base_dofs();
    let n = model.body_count();
    velocities(model, wb, q, v);
    let g = gravity_accel(model);
    for i in 0..n {
        let body = &model.bodies[i];
        let (head, tail) = wb.split_at_mut(i);
        let w = &mut tail[0];
        w.a = if i < nb {
            // Base: the given acceleration, moved into the falling frame.
            Twist::from_array([acc(0), acc(1), acc(2), acc(3), acc(4), acc(5)])
                + w.x.motion_to_child(&g)
        } else {
            let ap = match body.parent {
                Some(p) => w.x.motion_to_child(&head[p].a),
                None => w.x.motion_to_child(&g),
            };
            // (4.30)
            ap + w.c + joint_motion(body.joint, acc(vo + i - nb))
        };
        // Newton–Euler for the body: f = Î â + v̂ ×* Î v̂ − f_ext.
        let h = body.inertia.mul_twist(&w.v);
        w.pa = body.inertia.mul_twist(&w.a) + w.v.cross_force(&h);
        if let Some(f) = f_ext {
            w.pa -= f[i];
        }
    }
    for i in (0..n).rev() {
        let body = &model.bodies[i];
        let (head, tail) = wb.split_at_mut(i);
        let w = &tail[0];
        if i < nb {
            tau[..6].copy_from_slice(&w.pa.to_array());
        } else {
            // Q_i = ŝ_i' f̂_i^I (Lemma 7).
            tau[vo + i - nb] = joint_force(body.joint, &w.pa);
        }
        if let Some(p) = body.parent {
            // f̂_h^I += _hX̂_i f̂_i^I (action–reaction, §4.4).
            head[p].pa += w.x.force_to_parent(&w.pa);
        }
    }
    Ok(())
}

/// The bias forces `h(q, v) = C(q, v) v + G(q)` (nv): inverse dynamics at zero acceleration.
/// Allocation-free.
///
/// # Errors
/// [`MultibodyError::DimensionMismatch`] for wrong lengths.
pub fn bias_forces(
    model: &Model,
    ws: &mut Workspace,
    q: &[f64],
    v: &[f64],
    h: &mut [f64],
) -> Result<(), MultibodyError> {
    rnea(model, ws, q, v, None, None, h)
}

/// The joint-space mass matrix `M(q)` (nv × nv, symmetric positive definite) by the
/// composite-rigid-body algorithm. With a floating base the leading 6×6 block is the composite
/// inertia of the whole system in base coordinates (linear on top). O(n·depth).
///
/// # Errors
/// [`MultibodyError::DimensionMismatch`] for wrong lengths of `q` or `m`.
pub fn mass_matrix(
    model: &Model,
    ws: &mut Workspace,
    q: &[f64],
    m: &mut Mat<f64>,
) -> Result<(), MultibodyError> {
    check_len("q", model.nq(), q.len())?;
    check_len("mass matrix rows", model.nv(), m.nrows())?;
    check_len("mass matrix columns", model.nv(), m.ncols())?;
    ws.check(model)?;
    let nb = model.first_joint_body();
    let vo = model.base_dofs();
    let n = model.body_count();
    let qo = model.nq() - model.joint_count();
    let wb = &mut ws.bodies[..];
    for i in 0..n {
        let body = &model.bodies[i];
        wb[i].x = if i < nb {
            base_xform(q)
        } else {
            joint_xform(
                &body.origin,
                body.joint,
                body.axis_in_parent,
                q[qo + i - nb],
            )
        };
        wb[i].ia = body.inertia6;
    }
    for r in 0..m.nrows() {
        for c in 0..m.ncols() {
            m[(r, c)] = 0.0;
        }
    }
    for i in (0..n).rev() {
        let body = &model.bodies[i];
        let (head, tail) = wb.split_at_mut(i);
        let w = &tail[0];
        if let Some(p) = body.parent {
            // Composite inertia of the subtree, moved to the parent.
            head[p].ia.add_assign(&w.ia.to_parent(&w.x));
        }
        if i < nb {
            let full = w.ia.to_mat6().to_rows();
            for (r, row) in full.iter().enumerate() {
                for (c, x) in row.iter().enumerate() {
                    m[(r, c)] = *x;
                }
            }
            continue;
        }
        let ci = vo + i - nb;
        let mut f = inertia_times_axis(body.joint, &w.ia);
        m[(ci, ci)] = joint_force(body.joint, &f);
        let mut j = i;
        while let Some(p) = model.bodies[j].parent {
            f = wb[j].x.force_to_parent(&f);
            j = p;
            if j < nb {
                for (r, x) in f.to_array().iter().enumerate() {
                    m[(r, ci)] = *x;
                    m[(ci, r)] = *x;
                }
            } else {
                let cj = vo + j - nb;
                let x = joint_force(model.bodies[j].joint, &f);
                m[(cj, ci)] = x;
                m[(ci, cj)] = x;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{BaseKind, JointSpec, ModelBuilder};
    use crate::testutil::*;
    use faer::Side;
    use faer::linalg::solvers::Solve;
    use impulse_geom::SpatialInertia;
    use rand::RngExt;

    /// Bound on the relative residual of `M v̇ + h = τ` for ABA's `v̇` (M by CRBA, h by RNEA) and
    /// on RNEA(ABA(τ)) − τ: independent recursions for the same dynamics, so only rounding.
    const ABA_REL: f64 = 1e-10;
    /// CRBA against the Jacobian reference `Σ Jᵀ M_l J`, relative to max |M|: both are exact
    /// formulas, so only rounding (O(n·ε) through the depth of the tree) separates them.
    const CRBA_REL: f64 = 1e-11;
    /// RNEA's bias against the Lagrangian reference with central differences of M
    /// (step `FD_STEP`: truncation ~ε_fd² ≈ 1e-12, rounding ~ε/ε_fd ≈ 1e-10, times the scale).
    const FD_REL: f64 = 1e-7;
    const FD_STEP: f64 = 1e-5;
    /// Closed forms (pendulum, planar arm, single free body) evaluated two ways.
    const CLOSED_FORM: f64 = 1e-12;

    fn solve(m: &Mat<f64>, b: &[f64]) -> Vec<f64> {
        let llt = m.llt(Side::Lower).expect("M is positive definite");
        let rhs = Mat::<f64>::from_fn(b.len(), 1, |r, _| b[r]);
        let x = llt.solve(&rhs);
        (0..b.len()).map(|r| x[(r, 0)]).collect()
    }

    /// ≥ 1000 random chains and trees, 1–60 moving joints, fixed and floating, with gravity:
    /// ABA's v̇ satisfies `M(q) v̇ + h(q, v) = τ` (M by CRBA, h by RNEA) and RNEA(ABA(τ)) = τ.
    #[test]
    fn aba_agrees_with_crba_and_rnea() {
        let mut rng = rng(6001);
        let (mut worst, mut worst_inv, mut worst_sol) = (0.0f64, 0.0f64, 0.0f64);
        let mut cases = 0;
        for case in 0..1200 {
            let n = 1 + (case * 7919) % 60;
            let base = if case % 3 == 0 {
                BaseKind::Floating
            } else {
                BaseKind::Fixed
            };
            let chain = case % 2 == 0;
            let spec = random_spec(&mut rng, n, base, chain, true);
            let model = spec.model();
            let mut ws = Workspace::new(&model);
            let (q, v) = random_state(&mut rng, &model);
            let tau: Vec<f64> = (0..model.nv())
                .map(|_| rng.random_range(-5.0..5.0))
                .collect();
            let mut vdot = vec![0.0; model.nv()];
            forward_dynamics(&model, &mut ws, &q, &v, &tau, None, &mut vdot).unwrap();
            let mut m = Mat::<f64>::zeros(model.nv(), model.nv());
            mass_matrix(&model, &mut ws, &q, &mut m).unwrap();
            let mut h = vec![0.0; model.nv()];
            bias_forces(&model, &mut ws, &q, &v, &mut h).unwrap();
            let mv = mat_vec(&m, &vdot);
            let res: Vec<f64> = (0..model.nv()).map(|i| mv[i] + h[i] - tau[i]).collect();
            let scale = max_abs(&tau).max(max_abs(&mv)).max(max_abs(&h));
            worst = worst.max(max_abs(&res) / scale);
            let mut tau2 = vec![0.0; model.nv()];
            inverse_dynamics(&model, &mut ws, &q, &v, &vdot, None, &mut tau2).unwrap();
            let d: Vec<f64> = tau2.iter().zip(&tau).map(|(a, b)| a - b).collect();
            worst_inv = worst_inv.max(max_abs(&d) / scale);
            // Informative: the dense solve M⁻¹(τ − h), relative to |v̇| (depends on cond M).
            let rhs: Vec<f64> = tau.iter().zip(&h).map(|(a, b)| a - b).collect();
            let x = solve(&m, &rhs);
            let e: Vec<f64> = x.iter().zip(&vdot).map(|(a, b)| a - b).collect();
            worst_sol = worst_sol.max(max_abs(&e) / max_abs(&vdot).max(1.0));
            cases += 1;
        }
        println!(
            "ABA vs CRBA+RNEA over {cases} models: residual {worst:.2e}, RNEA(ABA) {worst_inv:.2e}, \
             |v̇ − M⁻¹(τ−h)| {worst_sol:.2e}"
        );
        assert!(cases >= 1000);
        assert!(
            worst <= ABA_REL && worst_inv <= ABA_REL,
            "{worst:e} {worst_inv:e}"
        );
    }

    /// CRBA equals `Σ Jᵀ M_l J` from independent world kinematics, for fixed and floating bases.
    #[test]
    fn crba_matches_jacobian_reference() {
        let mut rng = rng(6002);
        let mut worst = 0.0f64;
        for case in 0..300 {
            let base = alternating_base(case);
            let spec = random_spec(&mut rng, 1 + case % 15, base, case % 3 == 0, true);
            let model = spec.model();
            let mut ws = Workspace::new(&model);
            let (q, v) = random_state(&mut rng, &model);
            let mut m = Mat::<f64>::zeros(model.nv(), model.nv());
            mass_matrix(&model, &mut ws, &q, &mut m).unwrap();
            let r = reference(&spec, &model, &q);
            let mref = reference_mass_matrix(&spec, &r);
            worst = worst.max(mat_max_abs(&(&m - &mref)) / mat_max_abs(&mref));
            // Kinetic energy ½ vᵀMv equals the sum over bodies, and link poses agree.
            ws.update_kinematics(&model, &q, &v).unwrap();
            let t = 0.5
                * v.iter()
                    .zip(mat_vec(&mref, &v))
                    .map(|(a, b)| a * b)
                    .sum::<f64>();
            worst = worst.max((ws.kinetic_energy(&model) - t).abs() / t.max(1.0));
            for (l, pose) in r.poses.iter().enumerate() {
                let p = ws.link_pose(&model, LinkId(l));
                worst = worst.max((p.translation - pose.translation).abs().max_element());
                worst = worst.max((p.rotation.dot(pose.rotation).abs() - 1.0).abs());
            }
        }
        println!("CRBA vs Σ JᵀMJ: {worst:.2e}");
        assert!(worst <= CRBA_REL, "{worst:e}");
    }

    /// RNEA's `h = C(q, q̇)q̇ + G` against the Lagrangian form
    /// `Ṁq̇ − ½ ∂(q̇ᵀMq̇)/∂q + G`, with M from the Jacobian reference differentiated centrally
    /// and G from centre-of-mass Jacobians (fixed base, where q is a vector space).
    #[test]
    fn bias_matches_lagrangian_reference() {
        let mut rng = rng(6003);
        let mut worst = 0.0f64;
        for case in 0..25 {
            let spec = random_spec(&mut rng, 1 + case % 8, BaseKind::Fixed, case % 2 == 0, true);
            let model = spec.model();
            let mut ws = Workspace::new(&model);
            let (q, v) = random_state(&mut rng, &model);
            let n = model.nv();
            let m_at = |q: &[f64]| reference_mass_matrix(&spec, &reference(&spec, &model, q));
            let shift = |dir: &[f64], s: f64| -> Vec<f64> {
                q.iter().zip(dir).map(|(a, b)| a + s * b).collect()
            };
            // Ṁ q̇ = d/dε M(q + ε q̇) q̇.
            let mdot = &m_at(&shift(&v, FD_STEP)) - &m_at(&shift(&v, -FD_STEP));
            let mdot_v: Vec<f64> = mat_vec(&mdot, &v)
                .iter()
                .map(|x| x / (2.0 * FD_STEP))
                .collect();
            let mut href = reference_gravity(&spec, &reference(&spec, &model, &q));
            for i in 0..n {
                let mut e = vec![0.0; n];
                e[i] = 1.0;
                let dm = &m_at(&shift(&e, FD_STEP)) - &m_at(&shift(&e, -FD_STEP));
                let quad: f64 = v.iter().zip(mat_vec(&dm, &v)).map(|(a, b)| a * b).sum();
                href[i] += mdot_v[i] - 0.5 * quad / (2.0 * FD_STEP);
            }
            let mut h = vec![0.0; n];
            bias_forces(&model, &mut ws, &q, &v, &mut h).unwrap();
            let d: Vec<f64> = h.iter().zip(&href).map(|(a, b)| a - b).collect();
            worst = worst.max(max_abs(&d) / max_abs(&href).max(1.0));
        }
        println!("RNEA bias vs Lagrangian finite differences: {worst:.2e}");
        assert!(worst <= FD_REL, "{worst:e}");
    }

    /// Static balance (digest test 13): with τ = G(q) = RNEA(q, 0, 0), ABA returns v̇ = 0.
    #[test]
    fn gravity_compensation_holds_still() {
        let mut rng = rng(6004);
        for case in 0..50 {
            let spec = random_spec(&mut rng, 1 + case % 20, BaseKind::Fixed, false, true);
            let model = spec.model();
            let mut ws = Workspace::new(&model);
            let (q, _) = random_state(&mut rng, &model);
            let zero = vec![0.0; model.nv()];
            let mut g = vec![0.0; model.nv()];
            bias_forces(&model, &mut ws, &q, &zero, &mut g).unwrap();
            let r = reference(&spec, &model, &q);
            let gref = reference_gravity(&spec, &r);
            let d: Vec<f64> = g.iter().zip(&gref).map(|(a, b)| a - b).collect();
            assert!(max_abs(&d) <= 1e-12 * max_abs(&gref).max(1.0));
            let mut a = vec![0.0; model.nv()];
            forward_dynamics(&model, &mut ws, &q, &zero, &g, None, &mut a).unwrap();
            assert!(max_abs(&a) <= 1e-10, "{a:?}");
        }
    }

    /// Sibling order does not matter (digest test 9): the same tree with children added in
    /// reverse order gives the same accelerations, permuted.
    #[test]
    fn numbering_does_not_change_the_dynamics() {
        let mut rng = rng(6005);
        for case in 0..20 {
            let spec = random_spec(&mut rng, 2 + case % 12, BaseKind::Fixed, false, true);
            let mut rev = spec.clone();
            rev.joints.reverse();
            // Keep parents before children: sort by child index (stable), reversed siblings.
            rev.joints.sort_by_key(|(p, _, _)| *p);
            let (m1, m2) = (spec.model(), rev.model());
            let (q, v) = random_state(&mut rng, &m1);
            let perm: Vec<usize> = m2
                .joint_names()
                .iter()
                .map(|n| m1.joint_index(n).unwrap())
                .collect();
            let q2: Vec<f64> = perm.iter().map(|&k| q[k]).collect();
            let v2: Vec<f64> = perm.iter().map(|&k| v[k]).collect();
            let tau = vec![0.3; m1.nv()];
            let (mut a1, mut a2) = (vec![0.0; m1.nv()], vec![0.0; m1.nv()]);
            forward_dynamics(&m1, &mut Workspace::new(&m1), &q, &v, &tau, None, &mut a1).unwrap();
            forward_dynamics(&m2, &mut Workspace::new(&m2), &q2, &v2, &tau, None, &mut a2).unwrap();
            for (i, &k) in perm.iter().enumerate() {
                assert!((a2[i] - a1[k]).abs() <= 1e-10 * (1.0 + a1[k].abs()));
            }
        }
    }

    fn rod(m: f64, l: f64) -> SpatialInertia {
        // Thin-ish rod along x from the joint, centre at l/2; small radial inertia keeps it PD.
        let ic = DMat3::from_diagonal(DVec3::new(1e-3, m * l * l / 12.0, m * l * l / 12.0));
        SpatialInertia::new(m, DVec3::new(l / 2.0, 0.0, 0.0), ic)
    }

    /// Single pendulum and planar two-link arm against their Lagrangian equations of motion.
    #[test]
    fn pendulum_and_planar_arm_closed_forms() {
        let g = 9.81;
        let (m1, l1, m2, l2) = (1.3, 0.7, 0.8, 0.5);
        let mut b = ModelBuilder::new(BaseKind::Fixed);
        b.gravity(DVec3::new(0.0, -g, 0.0))
            .link("ground", SpatialInertia::ZERO)
            .link("a", rod(m1, l1))
            .link("b", rod(m2, l2))
            .joint(JointSpec::revolute(
                "j1",
                "ground",
                "a",
                Pose::IDENTITY,
                DVec3::Z,
            ))
            .joint(JointSpec::revolute(
                "j2",
                "a",
                "b",
                Pose::from_translation(DVec3::new(l1, 0.0, 0.0)),
                DVec3::Z,
            ));
        let model = b.build().unwrap();
        let mut ws = Workspace::new(&model);
        let (i1, i2) = (m1 * l1 * l1 / 12.0, m2 * l2 * l2 / 12.0);
        let (c1, c2) = (l1 / 2.0, l2 / 2.0);
        let cases: [([f64; 2], [f64; 2], [f64; 2]); 3] = [
            ([0.3, -0.7], [1.1, -0.4], [0.5, -0.2]),
            ([2.0, 1.0], [-3.0, 2.5], [0.0, 0.0]),
            ([-1.2, 0.1], [0.0, 0.0], [1.0, 3.0]),
        ];
        for (q, v, tau) in cases {
            // Standard planar two-link equations (angles from +x, gravity −y).
            let cos2 = q[1].cos();
            let m11 = i1 + i2 + m1 * c1 * c1 + m2 * (l1 * l1 + c2 * c2 + 2.0 * l1 * c2 * cos2);
            let m12 = i2 + m2 * (c2 * c2 + l1 * c2 * cos2);
            let m22 = i2 + m2 * c2 * c2;
            let hh = -m2 * l1 * c2 * q[1].sin();
            let cor = [hh * (2.0 * v[0] * v[1] + v[1] * v[1]), -hh * v[0] * v[0]];
            let grav = [
                (m1 * c1 + m2 * l1) * g * q[0].cos() + m2 * c2 * g * (q[0] + q[1]).cos(),
                m2 * c2 * g * (q[0] + q[1]).cos(),
            ];
            let r = [tau[0] - cor[0] - grav[0], tau[1] - cor[1] - grav[1]];
            let det = m11 * m22 - m12 * m12;
            let want = [
                (m22 * r[0] - m12 * r[1]) / det,
                (m11 * r[1] - m12 * r[0]) / det,
            ];
            let mut a = [0.0; 2];
            forward_dynamics(&model, &mut ws, &q, &v, &tau, None, &mut a).unwrap();
            assert!(
                (a[0] - want[0]).abs() < CLOSED_FORM * 100.0,
                "{a:?} {want:?}"
            );
            assert!(
                (a[1] - want[1]).abs() < CLOSED_FORM * 100.0,
                "{a:?} {want:?}"
            );
        }
        // Single pendulum: q̈ = (τ − m g c cos q) / (I + m c²).
        let mut b = ModelBuilder::new(BaseKind::Fixed);
        b.gravity(DVec3::new(0.0, -g, 0.0))
            .link("ground", SpatialInertia::ZERO)
            .link("a", rod(m1, l1))
            .joint(JointSpec::revolute(
                "j1",
                "ground",
                "a",
                Pose::IDENTITY,
                DVec3::Z,
            ));
        let model = b.build().unwrap();
        let mut ws = Workspace::new(&model);
        for q in [-2.0, 0.0, 0.4, 1.5] {
            let mut a = [0.0];
            forward_dynamics(&model, &mut ws, &[q], &[0.7], &[0.2], None, &mut a).unwrap();
            let want = (0.2 - m1 * g * c1 * q.cos()) / (i1 + m1 * c1 * c1);
            assert!((a[0] - want).abs() < CLOSED_FORM, "{} {want}", a[0]);
        }
    }

    /// Thesis Fig. 4.3: one revolute link turning at constant rate; in the link frame its
    /// centre of mass has velocity (0, q̇d) and classical acceleration (−q̇²d, 0).
    #[test]
    fn planar_single_link_kinematics_fig_4_3() {
        let d = 0.8;
        let mut b = ModelBuilder::new(BaseKind::Fixed);
        b.gravity(DVec3::ZERO)
            .link("ground", SpatialInertia::ZERO)
            .link("a", rod(1.0, 2.0 * d))
            .joint(JointSpec::revolute(
                "j",
                "ground",
                "a",
                Pose::IDENTITY,
                DVec3::Z,
            ));
        let model = b.build().unwrap();
        let mut ws = Workspace::new(&model);
        let (q, qd) = (0.6, 1.7);
        let mut a = [0.0];
        // Hold q̈ = 0 with the torque RNEA gives (zero here: no gravity, axis through a
        // principal axis).
        let mut tau = [0.0];
        inverse_dynamics(&model, &mut ws, &[q], &[qd], &[0.0], None, &mut tau).unwrap();
        forward_dynamics(&model, &mut ws, &[q], &[qd], &tau, None, &mut a).unwrap();
        assert!(a[0].abs() < CLOSED_FORM);
        let w = &ws.bodies[0];
        let c = DVec3::new(d, 0.0, 0.0);
        let vc = w.v.v + w.v.w.cross(c);
        // Classical acceleration of the c.o.m. = spatial a + ω × v_c (spatial accel. at c).
        let a_c = w.a.v + w.a.w.cross(c) + w.v.w.cross(vc);
        assert!((vc - DVec3::new(0.0, qd * d, 0.0)).length() < CLOSED_FORM);
        assert!((a_c - DVec3::new(-qd * qd * d, 0.0, 0.0)).length() < CLOSED_FORM);
    }

    /// A single floating link obeys Newton–Euler: m a_c = F + m g, I ω̇ + ω × Iω = τ_c.
    #[test]
    fn single_floating_body_is_newton_euler() {
        let mut rng = rng(6006);
        for _ in 0..50 {
            let i = inertia(&mut rng);
            let mut b = ModelBuilder::new(BaseKind::Floating);
            b.gravity(DVec3::new(0.0, 0.0, -9.81)).link("body", i);
            let model = b.build().unwrap();
            let mut ws = Workspace::new(&model);
            let (q, v) = random_state(&mut rng, &model);
            let tau: Vec<f64> = (0..6).map(|_| rng.random_range(-3.0..3.0)).collect();
            let mut a = vec![0.0; 6];
            forward_dynamics(&model, &mut ws, &q, &v, &tau, None, &mut a).unwrap();
            let x = base_xform(&q);
            let (vb, wb) = (DVec3::new(v[0], v[1], v[2]), DVec3::new(v[3], v[4], v[5]));
            let (ab, alpha) = (DVec3::new(a[0], a[1], a[2]), DVec3::new(a[3], a[4], a[5]));
            // Force and torque about the c.o.m., body coordinates.
            let f = DVec3::new(tau[0], tau[1], tau[2]);
            let tc = DVec3::new(tau[3], tau[4], tau[5]) - i.com.cross(f);
            let g_body = rt_mul(&x.r, model.gravity());
            // Body-frame derivative of the c.o.m. velocity v_c = v + ω × c, plus ω × v_c, is
            // the classical acceleration in body coordinates.
            let vc = vb + wb.cross(i.com);
            let acc_c = ab + alpha.cross(i.com) + wb.cross(vc);
            let e1 = (acc_c * i.mass - (f + g_body * i.mass)).length();
            let e2 = (i.inertia_com * alpha + wb.cross(i.inertia_com * wb) - tc).length();
            assert!(e1 < 1e-12 * 100.0 && e2 < 1e-12 * 100.0, "{e1:e} {e2:e}");
        }
    }

    #[test]
    fn dimension_errors_are_typed() {
        let mut rng = rng(6007);
        let model = random_spec(&mut rng, 3, BaseKind::Fixed, true, false).model();
        let mut ws = Workspace::new(&model);
        let mut out = vec![0.0; 3];
        let e = forward_dynamics(
            &model, &mut ws, &[0.0; 2], &[0.0; 3], &[0.0; 3], None, &mut out,
        );
        assert_eq!(
            e,
            Err(MultibodyError::DimensionMismatch {
                what: "q",
                expected: 3,
                got: 2
            })
        );
    }
}
