//! Jointed systems in an island: bodies of the island that are links of one mechanism (a
//! multibody) and move with its generalized velocity.
//!
//! The solver stays blind to how a mechanism moves: for each of its links in the island it
//! takes the link's twist per unit generalized velocity (J, the link's Jacobian about its centre
//! of mass) and the generalized velocity's response to a unit wrench on the link at its
//! centre of mass (M⁻¹Jᵀ, which a caller computes by propagating unit impulses through its
//! articulated-body recursion, thesis Fig. 5.10). A contact on a link then reads its velocity
//! as Jₚ·q̇ and applies its impulse as Δq̇ = M⁻¹Jₚᵀ·p, Jₚ the contact point's Jacobian, and its
//! collision matrix is Jₚ·M⁻¹·Jₚᵀ (thesis eq. 5.14 for the link's K, summed with the other
//! side's as eq. 5.15 sums two multibodies'; two links of one mechanism give
//! (J₁ − J₂)·M⁻¹·(J₁ − J₂)ᵀ, with the coupling terms).

use glam::{DMat3, DVec3};

use super::IslandBody;
use crate::ResponseError;
use crate::body::Body;

/// A jointed mechanism some bodies of an island belong to (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct System {
    /// Generalized velocity q̇ (n entries), changed in place by the solve.
    pub velocity: Vec<f64>,
    /// The island bodies that are its links.
    pub members: Vec<Member>,
}

/// A link of a [`System`] standing as a body of the island. The island body must be
/// [`Body::Fixed`] (its motion is the system's, not its own), with `com` the link's centre of
/// mass; the solver sets its `velocity` and `omega` from the system's velocity on entry and
/// on return ([`System::write_members`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Member {
    /// Index of the island body.
    pub body: usize,
    /// Per generalized velocity k, the link's twist for unit q̇ₖ (column k of J): the
    /// velocity of its centre of mass and its angular velocity (world).
    pub jacobian: Vec<(DVec3, DVec3)>,
    /// Per generalized velocity k, row k of M⁻¹Jᵀ: Δq̇ₖ per unit force at the centre of mass
    /// along each world axis, and per unit couple about each world axis.
    pub response: Vec<(DVec3, DVec3)>,
}

impl System {
    /// The twist (velocity of the centre of mass, angular velocity) of member `m` at the
    /// system's velocity.
    #[must_use]
    pub fn member_twist(&self, m: usize) -> (DVec3, DVec3) {
        let member = &self.members[m];
        member
            .jacobian
            .iter()
            .zip(&self.velocity)
            .fold((DVec3::ZERO, DVec3::ZERO), |(v, w), ((jv, jw), &q)| {
                (v + *jv * q, w + *jw * q)
            })
    }

    /// Sets every member body's velocity and angular velocity from the system's velocity.
    pub fn write_members(&self, bodies: &mut [IslandBody]) {
        for (m, member) in self.members.iter().enumerate() {
            let (v, w) = self.member_twist(m);
            if let Some(b) = bodies.get_mut(member.body) {
                b.velocity = v;
                b.omega = w;
            }
        }
    }

    /// The generalized force Jₚᵀ·f of a force `force` (world) acting at `point` on member
    /// `m` (whose centre of mass is `com`), added into `tau` (n entries).
    pub fn add_generalized_force(
        &self,
        m: usize,
        com: DVec3,
        point: DVec3,
        force: DVec3,
        tau: &mut [f64],
    ) {
        let r = point - com;
        let torque = r.cross(force);
        for (t, (jv, jw)) in tau.iter_mut().zip(&self.members[m].jacobian) {
            *t += jv.dot(force) + jw.dot(torque);
        }
    }
}

/// Where each island body stands: `None` for a rigid body, else (system, member).
pub(super) type Membership = Vec<Option<(usize, usize)>>;

/// Checks the systems against the bodies and returns which body is which system's member.
pub(super) fn membership(
    bodies: &[IslandBody],
    systems: &[System],
) -> Result<Membership, ResponseError> {
    let mut of = vec![None; bodies.len()];
    for (s, system) in systems.iter().enumerate() {
        let n = system.velocity.len();
        if !system.velocity.iter().all(|x| x.is_finite()) {
            return Err(ResponseError::NonFinite {
                what: "system velocity",
            });
        }
        for (m, member) in system.members.iter().enumerate() {
            let Some(body) = bodies.get(member.body) else {
                return Err(ResponseError::InvalidParameter {
                    name: "system member body index",
                    value: member.body as f64,
                    requirement: "below the number of island bodies",
                });
            };
            if of[member.body].is_some() {
                return Err(ResponseError::InvalidParameter {
                    name: "system member body index",
                    value: member.body as f64,
                    requirement: "a body of one system, listed once",
                });
            }
            if !matches!(body.body, Body::Fixed) {
                return Err(ResponseError::InvalidParameter {
                    name: "system member body",
                    value: member.body as f64,
                    requirement: "Body::Fixed (a member moves with its system)",
                });
            }
            if member.jacobian.len() != n || member.response.len() != n {
                return Err(ResponseError::InvalidParameter {
                    name: "system member Jacobian or response length",
                    value: member.jacobian.len().min(member.response.len()) as f64,
                    requirement: "the length of the system's velocity",
                });
            }
            let finite = |(a, b): &(DVec3, DVec3)| a.is_finite() && b.is_finite();
            if !(member.jacobian.iter().all(finite) && member.response.iter().all(finite)) {
                return Err(ResponseError::NonFinite {
                    what: "system member Jacobian or response",
                });
            }
            of[member.body] = Some((s, m));
        }
    }
    Ok(of)
}

/// One side of a contact on a member, in the contact's frame.
pub(super) struct LinkSide {
    system: usize,
    /// +1 for body 1 (it receives +p), −1 for body 2.
    sign: f64,
    /// Per generalized velocity k: the contact point's velocity for unit q̇ₖ (contact frame).
    jac: Vec<DVec3>,
    /// Per generalized velocity k: Δq̇ₖ per unit contact-frame impulse.
    resp: Vec<DVec3>,
}

/// The member sides of a contact (at least one).
pub(super) struct LinkRows {
    sides: Vec<LinkSide>,
}

impl LinkRows {
    /// The member sides of a contact whose bodies are `body1` (lever arm `r1`) and `body2`
    /// (`r2`), in the frame whose axes are the columns of `axes`; `None` when neither is a
    /// member.
    pub(super) fn new(
        systems: &[System],
        of: &Membership,
        (body1, r1): (usize, DVec3),
        body2: Option<(usize, DVec3)>,
        axes: DMat3,
    ) -> Option<Self> {
        let to_contact = axes.transpose();
        let side = |(body, r): (usize, DVec3), sign: f64| -> Option<LinkSide> {
            let (s, m) = of[body]?;
            let member = &systems[s].members[m];
            // A point at r from the centre of mass: v + ω × r per unit q̇ₖ; and a force f
            // there is f at the centre with the couple r × f, so Δq̇ₖ = (R_vₖ + R_ωₖ × r)·f.
            let jac = member
                .jacobian
                .iter()
                .map(|(jv, jw)| to_contact * (*jv + jw.cross(r)))
                .collect();
            let resp = member
                .response
                .iter()
                .map(|(rv, rw)| to_contact * (*rv + rw.cross(r)))
                .collect();
            Some(LinkSide {
                system: s,
                sign,
                jac,
                resp,
            })
        };
        let sides: Vec<LinkSide> = [side((body1, r1), 1.0), body2.and_then(|b| side(b, -1.0))]
            .into_iter()
            .flatten()
            .collect();
        (!sides.is_empty()).then_some(Self { sides })
    }

    /// The members' part of the contact's collision matrix (contact frame): per system,
    /// Σₖ (Σ σ·jacₖ) ⊗ (Σ σ·respₖ) over its sides — with one side, Jₚ·M⁻¹·Jₚᵀ; with two
    /// sides on one system, (J₁ − J₂)·M⁻¹·(J₁ − J₂)ᵀ.
    pub(super) fn matrix(&self) -> DMat3 {
        let mut k = DMat3::ZERO;
        let mut done: Vec<usize> = Vec::new();
        for side in &self.sides {
            if done.contains(&side.system) {
                continue;
            }
            done.push(side.system);
            let on: Vec<&LinkSide> = self
                .sides
                .iter()
                .filter(|s| s.system == side.system)
                .collect();
            for q in 0..side.jac.len() {
                let jac: DVec3 = on.iter().map(|s| s.jac[q] * s.sign).sum();
                let resp: DVec3 = on.iter().map(|s| s.resp[q] * s.sign).sum();
                k += DMat3::from_cols(jac * resp.x, jac * resp.y, jac * resp.z);
            }
        }
        k
    }

    /// The members' part of the relative contact velocity (contact frame).
    #[inline]
    pub(super) fn velocity(&self, systems: &[System]) -> DVec3 {
        let mut u = DVec3::ZERO;
        for side in &self.sides {
            let qd = &systems[side.system].velocity;
            let v: DVec3 = side.jac.iter().zip(qd).map(|(j, &q)| *j * q).sum();
            u += v * side.sign;
        }
        u
    }

    /// Applies the contact-frame impulse `dp` (+dp on body 1, −dp on body 2) to the systems.
    #[inline]
    pub(super) fn apply(&self, systems: &mut [System], dp: DVec3) {
        for side in &self.sides {
            let qd = &mut systems[side.system].velocity;
            for (q, r) in qd.iter_mut().zip(&side.resp) {
                *q += side.sign * r.dot(dp);
            }
        }
    }
}
