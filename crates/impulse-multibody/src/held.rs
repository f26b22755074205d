//! What a contact solver holding a multibody's links in contact needs of it: each link's
//! Jacobian and its impulse response (the maps of an island's jointed system), the
//! multibody's acceleration without contact, and a generalized contact force held constant
//! over a step.
//!
//! A world whose contact islands hold links solves an island step as for rigid bodies
//! (velocity-level time stepping): the free velocity at the step's end, v + h·v̇, the contact
//! impulses P that make the contacts obey their laws through the maps J and M⁻¹Jᵀ, then the
//! step itself integrated with the generalized force Jᵀ·P/h held over it
//! ([`Simulation::set_contact_forces`]), so that the integrator's end velocity is the solved
//! one to first order in h and the links move along the multibody's own dynamics.
//!
//! **Must not know** how contacts were found or solved.

use glam::DVec3;
use impulse_geom::Wrench;

use crate::collision::ImpulseDynamics;
use crate::control::{Rhs, Simulation};
use crate::dynamics::Workspace;
use crate::error::MultibodyError;
use crate::integrate::Accel;
use crate::limit::InverseMass;
use crate::model::{LinkId, Model, check_len};

/// One link's maps, per generalized velocity k (nv entries each): `jacobian[k]` the velocity
/// of the link frame's origin and the link's angular velocity for unit v_k (world), and
/// `response[k]` Δv_k per unit force at the link frame's origin along each world axis and
/// per unit couple about each world axis (row k of M⁻¹Jᵀ, thesis Fig. 5.10's propagation of
/// a unit impulse).
#[derive(Clone, Debug, PartialEq)]
pub struct LinkMaps {
    /// Column k of the link's 6 × nv Jacobian: (origin velocity, angular velocity).
    pub jacobian: Vec<(DVec3, DVec3)>,
    /// Row k of M⁻¹Jᵀ: (per unit force, per unit couple).
    pub response: Vec<(DVec3, DVec3)>,
}

/// The maps of `links` at configuration `q`: nv velocity evaluations for the Jacobians
/// (O(nv·n)) and six impulse propagations per link (O(n) each).
///
/// # Errors
/// [`MultibodyError::DimensionMismatch`] for a wrong length of `q`;
/// [`MultibodyError::UnknownName`] for a link of another model;
/// [`MultibodyError::SingularInertia`] for a configuration the recursion cannot invert.
pub fn link_maps(
    model: &Model,
    q: &[f64],
    links: &[LinkId],
) -> Result<Vec<LinkMaps>, MultibodyError> {
    check_len("q", model.nq(), q.len())?;
    let nv = model.nv();
    let mut ws = Workspace::new(model);
    let mut maps: Vec<LinkMaps> = links
        .iter()
        .map(|_| LinkMaps {
            jacobian: Vec::with_capacity(nv),
            response: vec![(DVec3::ZERO, DVec3::ZERO); nv],
        })
        .collect();
    // Poses at q (any velocity).
    let mut unit = vec![0.0; nv];
    ws.update_kinematics(model, q, &unit)?;
    let poses: Vec<_> = links.iter().map(|&l| ws.link_pose(model, l)).collect();
    for k in 0..nv {
        unit[k] = 1.0;
        ws.update_kinematics(model, q, &unit)?;
        unit[k] = 0.0;
        for ((m, &l), pose) in maps.iter_mut().zip(links).zip(&poses) {
            // The twist's linear part is the velocity of the body point at the world origin.
            let t = ws.link_twist_world(model, l);
            m.jacobian.push((t.v + t.w.cross(pose.translation), t.w));
        }
    }
    let mut imp = ImpulseDynamics::new(model, q)?;
    let mut dv = vec![0.0; nv];
    for ((m, &l), pose) in maps.iter_mut().zip(links).zip(&poses) {
        for a in 0..3 {
            let e = DVec3::AXES[a];
            imp.propagate_impulse(model, l, pose.translation, e, &mut dv)?;
            for (r, d) in m.response.iter_mut().zip(&dv) {
                r.0[a] = *d;
            }
            // A couple about world axis a, in the link's frame (a couple is the same about
            // every point).
            let couple = Wrench::new(DVec3::ZERO, pose.rotation.inverse() * e);
            imp.propagate_wrench_impulse(model, l, &couple, &mut dv)?;
            for (r, d) in m.response.iter_mut().zip(&dv) {
                r.1[a] = *d;
            }
        }
    }
    Ok(maps)
}

/// Every link's acceleration at `(q, v)` when every generalized acceleration is zero and
/// there is no gravity (in link order, as [`crate::LinkKinematics`]: the pose, velocity and
/// angular velocity now, and as `acceleration` and `angular_acceleration` the velocity-product
/// terms J̇·v of the link frame's origin and of its angular velocity). A point fixed in the
/// link at x has the acceleration J̇_x·v = a + α × (x − o) + ω × (ω × (x − o)), o the frame
/// origin: what a velocity-level contact step misses when it reads a link point's velocity at
/// the step's end through the Jacobian at its start, J(q + h v)·v ≈ J(q)·v + h·J̇·v. One
/// forward pass of the Newton–Euler recursion (the velocity products c_i of eq. 4.30, the
/// base's acceleration zero).
///
/// # Errors
/// [`MultibodyError::DimensionMismatch`] for wrong lengths of `q` or `v`.
pub fn velocity_product_accelerations(
    model: &Model,
    ws: &mut Workspace,
    q: &[f64],
    v: &[f64],
) -> Result<Vec<crate::travel::LinkKinematics>, MultibodyError> {
    let mut h = vec![0.0; model.nv()];
    // Zero accelerations: the forward pass leaves each body's a = −g (the falling frame)
    // plus its velocity products; the kinematics add g back.
    crate::dynamics::bias_forces(model, ws, q, v, &mut h)?;
    Ok(crate::travel::kinematics(model, ws))
}

impl Simulation {
    /// [`velocity_product_accelerations`] at the current state.
    ///
    /// # Errors
    /// As [`velocity_product_accelerations`].
    pub fn velocity_product_accelerations(
        &mut self,
    ) -> Result<Vec<crate::travel::LinkKinematics>, MultibodyError> {
        velocity_product_accelerations(&self.model, &mut self.ws, &self.q, &self.v)
    }

    /// [`link_maps`] at the current configuration, for a multibody with joints resting on a
    /// stop ([`crate::limit`]): the stop holds such a joint (its constraint force keeps its
    /// velocity at zero as long as the load presses it on), so an impulse's response is the
    /// constrained one, Δv = (M⁻¹ − M⁻¹Sᵀ(S M⁻¹ Sᵀ)⁻¹ S M⁻¹)·Jᵀ with S the resting joints'
    /// rows: a plank resting on its stop does not give way under a ball.
    ///
    /// # Errors
    /// As [`link_maps`].
    pub fn link_maps(&mut self, links: &[LinkId]) -> Result<Vec<LinkMaps>, MultibodyError> {
        let mut maps = link_maps(&self.model, &self.q, links)?;
        if self.resting.is_empty() {
            return Ok(maps);
        }
        let joints: Vec<usize> = self.resting.iter().map(|s| s.joint).collect();
        let zeros = vec![0.0; joints.len()];
        let minv = InverseMass::new(&self.model, &mut self.ws, &self.q)?;
        let nv = self.model.nv();
        let mut column = vec![0.0; nv];
        for map in &mut maps {
            for c in 0..6 {
                let at = |r: &(DVec3, DVec3)| if c < 3 { r.0[c] } else { r.1[c - 3] };
                for (x, r) in column.iter_mut().zip(&map.response) {
                    *x = at(r);
                }
                minv.constrain(&mut column, &joints, &zeros);
                for (r, x) in map.response.iter_mut().zip(&column) {
                    if c < 3 {
                        r.0[c] = *x;
                    } else {
                        r.1[c - 3] = *x;
                    }
                }
            }
        }
        Ok(maps)
    }

    /// Replaces the velocity (nv) after an impulse an island applied, keeping the joints
    /// that rest on a stop resting there (their velocity stays zero: an island's response
    /// through [`Simulation::link_maps`] does not move them). [`Simulation::set_state`]
    /// instead starts afresh, every joint off its stop until it strikes one.
    ///
    /// # Errors
    /// [`MultibodyError::DimensionMismatch`] for a wrong length,
    /// [`MultibodyError::InvalidArgument`] for a non-finite entry; nothing changes then.
    pub fn set_velocity(&mut self, v: &[f64]) -> Result<(), MultibodyError> {
        check_len("v", self.model.nv(), v.len())?;
        if !v.iter().all(|x| x.is_finite()) {
            return Err(MultibodyError::InvalidArgument {
                what: "velocity",
                reason: "not finite".to_owned(),
            });
        }
        self.v.copy_from_slice(v);
        let vo = self.model.base_dofs();
        for s in &self.resting {
            self.v[vo + s.joint] = 0.0;
        }
        Ok(())
    }

    /// Sets the generalized contact forces (nv) held from now until they are set again: added
    /// to the applied forces and the controllers' outputs in every derivative evaluation, and
    /// in [`Simulation::link_kinematics`]'s accelerations. A world's contact island sets them
    /// to Jᵀ·P/h for its step (module documentation); zero by default.
    ///
    /// # Errors
    /// [`MultibodyError::DimensionMismatch`] for a wrong length,
    /// [`MultibodyError::InvalidArgument`] for a non-finite entry; nothing changes then.
    pub fn set_contact_forces(&mut self, tau: &[f64]) -> Result<(), MultibodyError> {
        check_len("contact forces", self.model.nv(), tau.len())?;
        if !tau.iter().all(|x| x.is_finite()) {
            return Err(MultibodyError::InvalidArgument {
                what: "contact forces",
                reason: "not finite".to_owned(),
            });
        }
        for ((h, c), new) in self.held.iter_mut().zip(&mut self.contact).zip(tau) {
            *h += new - *c;
            *c = *new;
        }
        Ok(())
    }

    /// The generalized contact forces held now ([`Simulation::set_contact_forces`]).
    #[must_use]
    pub fn contact_forces(&self) -> &[f64] {
        &self.contact
    }

    /// The acceleration v̇ (nv) now without the held contact forces: gravity, passive joint
    /// elements, applied forces and the controllers' held outputs, with joints resting on a
    /// stop held there ([`crate::limit`]), as the integrator's derivative evaluations see them.
    ///
    /// # Errors
    /// [`MultibodyError::SingularInertia`] for a state the dynamics cannot evaluate.
    pub fn free_acceleration(&mut self) -> Result<Vec<f64>, MultibodyError> {
        let held: Vec<f64> = self
            .held
            .iter()
            .zip(&self.contact)
            .map(|(h, c)| h - c)
            .collect();
        let mut vdot = vec![0.0; self.model.nv()];
        let mut rhs = Rhs {
            model: &self.model,
            ws: &mut self.ws,
            held: &held,
            tau: &mut self.tau,
            resting: &self.resting,
            track: None,
        };
        rhs.accel(self.t, &self.q, &self.v, &mut vdot)?;
        Ok(vdot)
    }
}

#[cfg(test)]
mod tests;
