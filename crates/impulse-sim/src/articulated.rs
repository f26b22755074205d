//! Collisions involving links of articulated bodies (thesis §5.3): a contact on a link of a
//! multibody against a free rigid body, a fixed body, a link of another multibody, or another
//! link of the same multibody (self-collision).
//!
//! The collision matrix of the contact is the sum of the two sides' (eq. 5.14 for a link:
//! three test impulses through the impulse-space articulated-body recursion of
//! `impulse_multibody::ImpulseDynamics`; eq. 3.4 for a rigid body). The impulse is integrated
//! through the collision by the same chapter-3 code as rigid bodies (`impulse_response`, Coulomb
//! friction, Stronge's restitution), blind to how K was made, and then spread over each
//! multibody's tree (Fig. 5.10 propagateImpulse) or applied to the rigid body (eqs. 3.1, 3.2).
//!
//! **Self-collision** ([`collide_self`]): two links of *one* multibody share one velocity
//! vector, so their responses are coupled and the sum of two sides' K's is wrong. With `J₁`,
//! `J₂` the Jacobians of the contact point on each link (`u_i = J_i q̇`), the impulse `+p` on
//! link 1 and `−p` on link 2 changes the velocities by `Δq̇ = M⁻¹(J₁ − J₂)ᵀ p`, and the
//! relative velocity `u = u₁ − u₂` by `K p` with `K = (J₁ − J₂) M⁻¹ (J₁ − J₂)ᵀ` (eq. 5.2 for
//! one tree: the cross terms `−J₁M⁻¹J₂ᵀ − J₂M⁻¹J₁ᵀ` are what the sum `K₁ + K₂` leaves out).
//! K is built from three pairs of test impulses propagated through the tree (Fig. 5.10),
//! the impulse from the same chapter-3 code, and applied as `+p` at link 1 and `−p` at link 2
//! into the one velocity vector.
//!
//! **Must not know** how contacts are found (that is the world's) or how a multibody is
//! integrated between collisions.

use glam::{DMat3, DVec3};
use impulse_multibody::{ImpulseDynamics, LinkId, Model, Workspace};
use impulse_response::{
    Body, CollisionMatrix, ContactFrame, MicrocollisionParams, Response, Restitution, Settings,
};

use crate::error::SimError;

/// One side of a collision.
#[derive(Debug)]
pub enum Collider<'a> {
    /// A link of a multibody at configuration `q` with velocity `v` (changed in place).
    Link {
        /// The multibody.
        model: &'a Model,
        /// Its configuration (nq).
        q: &'a [f64],
        /// Its velocity (nv), changed by the impulse.
        v: &'a mut [f64],
        /// The link struck.
        link: LinkId,
    },
    /// A free rigid body (velocities changed in place).
    Rigid {
        /// Mass (kg).
        mass: f64,
        /// Inertia tensor about the centre of mass, world axes (kg·m²).
        inertia: DMat3,
        /// Centre of mass (world).
        com: DVec3,
        /// Velocity of the centre of mass.
        velocity: &'a mut DVec3,
        /// Angular velocity (world).
        omega: &'a mut DVec3,
    },
    /// An immovable body (the ground, a wall).
    Fixed,
    /// A body of infinite mass moving on its own (a scripted body), with the velocity of its
    /// point at the contact.
    Kinematic {
        /// Velocity of the body's point at the contact (world).
        velocity: DVec3,
    },
}

/// The collision law of [`collide_with`]: friction, restitution and, for resting contact, the
/// microcollision model (thesis §3.5) the world uses for rigid bodies.
#[derive(Clone, Copy, Debug)]
pub struct Law {
    /// Coulomb friction coefficient μ.
    pub friction: f64,
    /// Stronge's restitution e.
    pub restitution: f64,
    /// The microcollision model with the pair's current separation (`None`: every contact is
    /// an ordinary collision).
    pub micro: Option<(MicrocollisionParams, f64)>,
    /// The collision integrator's settings.
    pub settings: Settings,
}

/// A resolved collision: the chapter-3 response (impulse on side `a`, collision frame) and its
/// frame.
#[derive(Debug)]
pub struct LinkCollision {
    /// The collision integrator's result.
    pub response: Response,
    /// The collision frame (its z axis the normal, from side `b` toward side `a`).
    pub frame: ContactFrame,
}

impl LinkCollision {
    /// The impulse on side `a` in world axes (side `b` receives its negative).
    #[must_use]
    pub fn impulse_world(&self) -> DVec3 {
        self.response.impulse_world(&self.frame)
    }
}

/// What one side contributes: its contact-point velocity (world), its K (collision-frame
/// axes), and what applies the impulse to it (prepared once, used once).
struct Side {
    velocity: DVec3,
    k: DMat3,
    response: SideResponse,
}

/// How a side takes the impulse: the articulated inertias of its configuration, or its mass
/// properties.
enum SideResponse {
    Link(Box<ImpulseDynamics>),
    Rigid(Body),
    Fixed,
}

fn bad(what: &str, e: impl std::fmt::Display) -> SimError {
    SimError::LinkCollision(format!("{what}: {e}"))
}

impl Collider<'_> {
    fn side(&self, x: DVec3, frame: &ContactFrame) -> Result<Side, SimError> {
        match self {
            Collider::Link { model, q, v, link } => {
                let mut ws = Workspace::new(model);
                ws.update_kinematics(model, q, v)
                    .map_err(|e| bad("kinematics", e))?;
                let mut imp = ImpulseDynamics::new(model, q).map_err(|e| bad("K", e))?;
                let k = imp
                    .collision_matrix_world(model, *link, x, frame.axes())
                    .map_err(|e| bad("K", e))?;
                Ok(Side {
                    velocity: ws.point_velocity(model, *link, x),
                    k,
                    response: SideResponse::Link(Box::new(imp)),
                })
            }
            Collider::Rigid {
                mass,
                inertia,
                com,
                velocity,
                omega,
            } => {
                let body = Body::moving(*mass, *inertia).map_err(|e| bad("rigid body", e))?;
                let r = x - *com;
                Ok(Side {
                    velocity: **velocity + omega.cross(r),
                    k: frame.matrix_to_contact(body.point_compliance(r)),
                    response: SideResponse::Rigid(body),
                })
            }
            Collider::Fixed => Ok(Side {
                velocity: DVec3::ZERO,
                k: DMat3::ZERO,
                response: SideResponse::Fixed,
            }),
            Collider::Kinematic { velocity } => Ok(Side {
                velocity: *velocity,
                k: DMat3::ZERO,
                response: SideResponse::Fixed,
            }),
        }
    }

    /// Applies impulse `p` (world) at `x` through the side prepared by [`Self::side`].
    fn apply(&mut self, side: Side, x: DVec3, p: DVec3) -> Result<(), SimError> {
        match (self, side.response) {
            (Collider::Link { model, v, link, .. }, SideResponse::Link(mut imp)) => {
                let mut dv = vec![0.0; model.nv()];
                imp.propagate_impulse(model, *link, x, p, &mut dv)
                    .map_err(|e| bad("propagation", e))?;
                for (vi, d) in v.iter_mut().zip(&dv) {
                    *vi += d;
                }
            }
            (
                Collider::Rigid {
                    com,
                    velocity,
                    omega,
                    ..
                },
                SideResponse::Rigid(body),
            ) => {
                let (dv, dw) = body.velocity_change(x - *com, p);
                **velocity += dv;
                **omega += dw;
            }
            _ => {}
        }
        Ok(())
    }
}

/// Resolves a collision at world point `x` with normal `normal` (from `b` toward `a`), friction
/// `mu` and restitution `e` (Stronge's law): K = K_a + K_b, the impulse integrated through the
/// collision, +p applied to `a` and −p to `b`. The two sides must not be links of one
/// multibody (their responses are coupled: use [`collide_self`]).
///
/// # Errors
/// [`SimError::LinkCollision`] naming what failed: a bad normal, a rigid body's mass properties, a
/// link of another model, two links of one model, a contact that does not approach, or the
/// collision integrator's own errors. Nothing is changed on error.
pub fn collide(
    a: &mut Collider<'_>,
    b: &mut Collider<'_>,
    x: DVec3,
    normal: DVec3,
    mu: f64,
    e: f64,
) -> Result<LinkCollision, SimError> {
    let law = Law {
        friction: mu,
        restitution: e,
        micro: None,
        settings: Settings::default(),
    };
    collide_with(a, b, x, normal, &law)
}

/// [`collide`] under a full [`Law`]: with a microcollision model, a slow approach is a
/// microcollision (the reversing impulse or boosted restitution, thesis §3.5, the same
/// `impulse_response` code as rigid bodies use).
///
/// # Errors
/// As [`collide`].
pub fn collide_with(
    a: &mut Collider<'_>,
    b: &mut Collider<'_>,
    x: DVec3,
    normal: DVec3,
    law: &Law,
) -> Result<LinkCollision, SimError> {
    if let (Collider::Link { model: ma, .. }, Collider::Link { model: mb, .. }) = (&*a, &*b) {
        if std::ptr::eq(*ma, *mb) {
            return Err(SimError::LinkCollision(
                "two links of one multibody: their responses are coupled (use collide_self)".into(),
            ));
        }
    }
    let frame = ContactFrame::from_normal(normal).map_err(|err| bad("normal", err))?;
    let (sa, sb) = (a.side(x, &frame)?, b.side(x, &frame)?);
    let u0 = frame.to_contact(sa.velocity - sb.velocity);
    let response = respond(sa.k + sb.k, u0, law)?;
    let p = response.impulse_world(&frame);
    a.apply(sa, x, p)?;
    b.apply(sb, x, -p)?;
    Ok(LinkCollision { response, frame })
}

/// The chapter-3 impulse for collision matrix `k` and relative contact velocity `u0`
/// (collision frame) under `law`: Stronge's restitution, or a microcollision (§3.5).
fn respond(k: DMat3, u0: DVec3, law: &Law) -> Result<Response, SimError> {
    let k = CollisionMatrix::new(k).map_err(|err| bad("collision matrix", err))?;
    let (mu, e) = (law.friction, law.restitution);
    match &law.micro {
        Some((params, separation)) => impulse_response::resolve_with_microcollisions(
            &k,
            u0,
            mu,
            e,
            separation.max(0.0),
            params,
            &law.settings,
        ),
        None => impulse_response::resolve(&k, u0, mu, e, Restitution::Stronge, &law.settings),
    }
    .map_err(|err| bad("response", err))
}

/// Two links of one multibody in contact with each other (self-collision): the multibody at
/// configuration `q` with velocity `v`, which both links share.
#[derive(Debug)]
pub struct SelfContact<'a> {
    /// The multibody.
    pub model: &'a Model,
    /// Its configuration (nq).
    pub q: &'a [f64],
    /// Its velocity (nv), changed by the impulse.
    pub v: &'a mut [f64],
    /// Side `a`, which takes `+p` (the normal points toward it).
    pub a: LinkId,
    /// Side `b`, which takes `−p`.
    pub b: LinkId,
}

/// Checks that `a` and `b` are two links of `model` that can strike each other: each exists
/// and moves, and they are not one rigid body ([`Model::links_adjacent`] excludes more, the
/// world's choice; a joint between them does not make K singular).
fn check_self_pair(model: &Model, a: LinkId, b: LinkId) -> Result<(), SimError> {
    for l in [a, b] {
        if l.index() >= model.link_count() {
            return Err(bad(
                "self-collision",
                format!("no link {} in the model", l.index()),
            ));
        }
    }
    let name = |l: LinkId| model.link_name(l).unwrap_or("?").to_owned();
    if a == b {
        return Err(bad(
            "self-collision",
            format!("link \"{}\" cannot strike itself", name(a)),
        ));
    }
    Ok(())
}

/// The relative collision matrix of a contact at world point `x` between links `a` and `b` of
/// one multibody at configuration `q`, in the collision frame whose axes (world) are the
/// columns of `axes` (the third the normal, toward `a`):
/// `K = (J_a − J_b) M⁻¹ (J_a − J_b)ᵀ` (module documentation). Column `c` is the change of the
/// relative contact velocity `u_a − u_b` when the unit impulse `+e_c` acts on `a` and `−e_c`
/// on `b`: `M⁻¹J_aᵀe_c` and `−M⁻¹J_bᵀe_c` from impulse propagation (Fig. 5.10), summed, then
/// both points' velocities for that joint velocity (eqs. 5.13, 5.14 for a pair of links).
/// O(n) per column.
///
/// # Errors
/// [`SimError::LinkCollision`] for a link not in the model, `a == b`, `q` of the wrong
/// length or not finite, a singular floating base.
pub fn self_collision_matrix(
    model: &Model,
    q: &[f64],
    a: LinkId,
    b: LinkId,
    x: DVec3,
    axes: DMat3,
) -> Result<DMat3, SimError> {
    check_self_pair(model, a, b)?;
    let mut imp = ImpulseDynamics::new(model, q).map_err(|e| bad("K", e))?;
    let mut ws = Workspace::new(model);
    self_matrix(model, q, &mut imp, &mut ws, (a, b), x, axes)
}

/// [`self_collision_matrix`] with the articulated inertias and a workspace given.
fn self_matrix(
    model: &Model,
    q: &[f64],
    imp: &mut ImpulseDynamics,
    ws: &mut Workspace,
    (a, b): (LinkId, LinkId),
    x: DVec3,
    axes: DMat3,
) -> Result<DMat3, SimError> {
    let nv = model.nv();
    let (mut da, mut db) = (vec![0.0; nv], vec![0.0; nv]);
    let mut cols = [DVec3::ZERO; 3];
    for (c, col) in cols.iter_mut().enumerate() {
        let f = axes.col(c);
        // Δq̇ = M⁻¹ (J_a − J_b)ᵀ f: +f at a, −f at b (Fig. 5.10, twice).
        imp.propagate_impulse(model, a, x, f, &mut da)
            .map_err(|e| bad("K", e))?;
        imp.propagate_impulse(model, b, x, -f, &mut db)
            .map_err(|e| bad("K", e))?;
        for (x, y) in da.iter_mut().zip(&db) {
            *x += y;
        }
        // Δu = (J_a − J_b) Δq̇, in collision-frame axes (eq. 5.13).
        ws.update_kinematics(model, q, &da)
            .map_err(|e| bad("K", e))?;
        let du = ws.point_velocity(model, a, x) - ws.point_velocity(model, b, x);
        *col = axes.transpose() * du;
    }
    Ok(DMat3::from_cols(cols[0], cols[1], cols[2]))
}

/// Resolves a collision between two links of one multibody (self-collision) at world point
/// `x` with normal `normal` (toward side `a`): `K = (J_a − J_b) M⁻¹ (J_a − J_b)ᵀ`
/// ([`self_collision_matrix`]), the impulse from the same chapter-3 code as every other
/// collision under `law` (microcollisions included), `+p` propagated at `a` and `−p` at `b`
/// into the one velocity vector. An internal impulse: the multibody's momentum does not
/// change.
///
/// # Errors
/// As [`self_collision_matrix`] and [`collide`]: a bad normal, a singular K (two links
/// that cannot move relative to each other at the point: welded ones), the integrator's own
/// errors. Nothing is changed on error.
pub fn collide_self(
    contact: &mut SelfContact<'_>,
    x: DVec3,
    normal: DVec3,
    law: &Law,
) -> Result<LinkCollision, SimError> {
    let (model, q, a, b) = (contact.model, contact.q, contact.a, contact.b);
    check_self_pair(model, a, b)?;
    let frame = ContactFrame::from_normal(normal).map_err(|err| bad("normal", err))?;
    let mut ws = Workspace::new(model);
    ws.update_kinematics(model, q, contact.v)
        .map_err(|e| bad("kinematics", e))?;
    let u0 = frame.to_contact(ws.point_velocity(model, a, x) - ws.point_velocity(model, b, x));
    let mut imp = ImpulseDynamics::new(model, q).map_err(|e| bad("K", e))?;
    let k = self_matrix(model, q, &mut imp, &mut ws, (a, b), x, frame.axes())?;
    let response = respond(k, u0, law)?;
    let p = response.impulse_world(&frame);
    let nv = model.nv();
    let (mut da, mut db) = (vec![0.0; nv], vec![0.0; nv]);
    imp.propagate_impulse(model, a, x, p, &mut da)
        .map_err(|e| bad("propagation", e))?;
    imp.propagate_impulse(model, b, x, -p, &mut db)
        .map_err(|e| bad("propagation", e))?;
    for ((vi, x), y) in contact.v.iter_mut().zip(&da).zip(&db) {
        *vi += x + y;
    }
    Ok(LinkCollision { response, frame })
}

#[cfg(test)]
pub(crate) mod tests;
