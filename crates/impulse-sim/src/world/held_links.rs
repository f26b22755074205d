//! Multibody links held in contact islands (the switching model, [`crate::sustained`]).
//!
//! A link in a held pair joins its island with every other held link of its multibody: the
//! island's solve takes the multibody as one jointed system ([`impulse_response::System`]),
//! each of its links in the island a member given by the link's Jacobian and impulse response
//! (`impulse_multibody::held::link_maps`, the impulse-space articulated-body recursion of
//! thesis §5.3). The step is the rigid bodies' velocity-level step:
//!
//! 1. the free velocity at the step's end, v + h·v̇, v̇ the multibody's acceleration without
//!    contact (gravity, joint springs and dampers, the controllers' held outputs);
//! 2. the solve, as for rigid bodies: each contact's impulse through the maps;
//! 3. the contact impulses P held over the step as the generalized force Jᵀ·P/h
//!    ([`impulse_multibody::Simulation::set_contact_forces`]), which the multibody's own
//!    integrator carries through the step: its end velocity is the solved one to first order,
//!    and its links move along its dynamics (as a rigid body's held force and torque are
//!    carried by its ballistic motion).
//!
//! An impulsive solve of a struck island changes the multibody's velocity at once
//! (`Simulation::set_velocity`, which keeps joints resting on their stops there; the maps are
//! projected through those stops, so a plank resting on its stop does not give way under a
//! ball). A loop step of a held multibody ends at a joint stop's strike, and its island steps
//! at that instant (`hybrid_step.rs`). Held links' predictions allow at least the sleep speed
//! ([`HELD_LINK_SPEED_FLOOR`]). An island holding a link never takes the long rest step and
//! never sleeps: the multibody is integrated by its own integrator whatever its islands do.

use glam::DVec3;
use impulse_collide::Motion;
use impulse_collide::motion::SeenSpeeds;
use impulse_geom::Aabb;
use impulse_response::{Contact, IslandBody, Member, System};

use super::World;
use crate::error::SimError;

/// The speed (in units of the sleep speed, [`crate::sustained::SustainedSettings`]) a held
/// multibody's link predictions allow at least, in every direction and, over the link's
/// reach, in rotation (`World::floor_link_predictions`). Default `1.0`: a hundred times the
/// solve's tolerance with the defaults, and a bound it gives a pair 1 mm apart is
/// seconds long at ε_c = 0.1 mm.
pub const HELD_LINK_SPEED_FLOOR: f64 = 1.0;

/// The multibody behind each jointed system of an island, and its acceleration without
/// contact.
pub(super) struct SystemSource {
    /// Index of the multibody.
    multibody: usize,
    /// Its acceleration without contact (nv).
    free: Vec<f64>,
}

impl World {
    /// The bodies a change of body `i`'s motion moves: every link of its multibody for a
    /// link, else `i` alone.
    pub(super) fn moved_with(&self, i: u32) -> Vec<u32> {
        match self.b(i).link {
            Some((m, _)) => self.link_slots(m as usize),
            None => vec![i],
        }
    }

    /// The jointed systems of an island whose bodies are `ids` (the solver's body order):
    /// one per multibody with a link among them, its members those links, with its
    /// acceleration without contact.
    ///
    /// # Errors
    /// [`SimError::Runtime`] naming the multibody when its state cannot be evaluated.
    pub(super) fn island_systems(
        &mut self,
        ids: &[u32],
    ) -> Result<(Vec<System>, Vec<SystemSource>), SimError> {
        let mut by_multibody: Vec<(usize, Vec<(usize, impulse_multibody::LinkId)>)> = Vec::new();
        for (k, &i) in ids.iter().enumerate() {
            if let Some((m, link)) = self.b(i).link {
                let m = m as usize;
                match by_multibody.iter_mut().find(|(x, _)| *x == m) {
                    Some((_, v)) => v.push((k, link)),
                    None => by_multibody.push((m, vec![(k, link)])),
                }
            }
        }
        by_multibody.sort_by_key(|(m, _)| *m);
        let mut systems = Vec::with_capacity(by_multibody.len());
        let mut sources = Vec::with_capacity(by_multibody.len());
        for (m, links) in by_multibody {
            let member = &mut self.multibodies[m];
            let fail = |e: impulse_multibody::MultibodyError| SimError::Runtime {
                time: self.time,
                message: format!("multibody {}: held contact: {e}", member.name),
            };
            let ids: Vec<_> = links.iter().map(|&(_, l)| l).collect();
            let maps = member.sim.link_maps(&ids).map_err(fail)?;
            let free = member.sim.free_acceleration().map_err(fail)?;
            systems.push(System {
                velocity: member.sim.v().to_vec(),
                members: links
                    .iter()
                    .zip(maps)
                    .map(|(&(body, _), map)| Member {
                        body,
                        jacobian: map.jacobian,
                        response: map.response,
                    })
                    .collect(),
            });
            sources.push(SystemSource { multibody: m, free });
        }
        Ok((systems, sources))
    }

    /// Sets the multibodies of an island after its step of length `h`: the velocity the
    /// impulsive solve left (`after_jolt`), and the contact impulses of `solution` held over
    /// the step as generalized forces; then its links' predictions and bounds.
    ///
    /// # Errors
    /// [`SimError::Runtime`] naming the multibody when its new state or forces are refused.
    pub(super) fn hold_link_loads(
        &mut self,
        sources: &[SystemSource],
        after_jolt: &[System],
        bodies: &[IslandBody],
        solution: &[Contact],
        h: f64,
    ) -> Result<(), SimError> {
        for (source, system) in sources.iter().zip(after_jolt) {
            let m = source.multibody;
            let mut tau = vec![0.0; system.velocity.len()];
            for c in solution {
                let p = impulse_response::ContactFrame::from_normal(c.normal)
                    .map_err(|e| self.runtime(format!("held contact normal: {e}")))?
                    .to_world(c.impulse);
                let arms = c.lever_arms;
                let sides = [
                    (Some(c.body1), 1.0, arms.map(|a| a.0)),
                    (c.body2, -1.0, arms.map(|a| a.1)),
                ];
                for (body, sign, arm) in sides {
                    let Some(k) = body else { continue };
                    let Some(index) = system.members.iter().position(|x| x.body == k) else {
                        continue;
                    };
                    let com = bodies[k].com;
                    let at = arm.map_or(c.point, |r| com + r);
                    system.add_generalized_force(index, com, at, p * (sign / h), &mut tau);
                }
            }
            let name = self.multibodies[m].name.clone();
            let sim = &mut self.multibodies[m].sim;
            if sim.v() != system.velocity.as_slice() {
                sim.set_velocity(&system.velocity)
                    .map_err(|e| self.runtime(format!("multibody {name}: {e}")))?;
            }
            let sim = &mut self.multibodies[m].sim;
            sim.set_contact_forces(&tau)
                .map_err(|e| self.runtime(format!("multibody {name}: held contact: {e}")))?;
            self.sync_links(m)?;
            self.floor_link_predictions(m)?;
            for i in self.link_slots(m) {
                if !self.stale.contains(&i) {
                    self.stale.push(i);
                }
            }
        }
        Ok(())
    }

    /// Widens the predictions of multibody `m`'s links (just made from its state) to speeds
    /// at least the sleep speed in every direction ([`HELD_LINK_SPEED_FLOOR`]): a held
    /// multibody at rest has a predicted acceleration near zero (its held contact force
    /// balances its weight), so its pairs' bounds allow almost no travel, and the speed noise
    /// of each step's solve (its tolerance) broke them (standing rover: 440 slack violations
    /// and 215 redone steps in 5 s).
    ///
    /// # Errors
    /// [`SimError::Runtime`] naming the link for a non-finite state.
    fn floor_link_predictions(&mut self, m: usize) -> Result<(), SimError> {
        let s = HELD_LINK_SPEED_FLOOR
            * self.islands.settings.sleep_speed_factor
            * (2.0 * self.gravity.length() * self.collision_epsilon()).sqrt();
        if s <= 0.0 {
            return Ok(());
        }
        for i in self.link_slots(m) {
            let name = self.name(i).to_owned();
            let time = self.time;
            let b = self.b_mut(i);
            let Some(Motion::Link(motion)) = b.script else {
                continue;
            };
            let spin = s / b.r_max.max(f64::MIN_POSITIVE);
            let seen = SeenSpeeds {
                velocity_min: b.velocity - DVec3::splat(s),
                velocity_max: b.velocity + DVec3::splat(s),
                omega_abs_max: b.omega.abs() + DVec3::splat(spin),
                path: Aabb::new(motion.origin(), motion.origin()),
            };
            let widened = motion.with_seen(seen).map_err(|e| SimError::Runtime {
                time,
                message: format!("link body {name}: {e}"),
            })?;
            b.script = Some(Motion::Link(widened));
        }
        Ok(())
    }

    /// Clears the held contact forces of link `i`'s multibody (a pair of it was released):
    /// its other held pairs get them back at their island's next step, which is now.
    pub(super) fn release_link(&mut self, i: u32) {
        let Some((m, _)) = self.b(i).link else {
            return;
        };
        let m = m as usize;
        let nv = self.multibodies[m].sim.model().nv();
        if self.multibodies[m]
            .sim
            .contact_forces()
            .iter()
            .all(|&x| x == 0.0)
        {
            return;
        }
        // Zeros are finite and of the right length.
        let _ = self.multibodies[m].sim.set_contact_forces(&vec![0.0; nv]);
        // A state that cannot be evaluated fails the next step, naming the multibody.
        let _ = self.sync_links(m);
        for j in self.link_slots(m) {
            if self.is_held_body(j) {
                self.step_now(j);
            }
            if !self.stale.contains(&j) {
                self.stale.push(j);
            }
        }
    }
}

/// The free velocities of an island's systems after a step of length `h`: v + h·v̇.
pub(super) fn predict_systems(systems: &mut [System], sources: &[SystemSource], h: f64) {
    for (system, source) in systems.iter_mut().zip(sources) {
        for (v, a) in system.velocity.iter_mut().zip(&source.free) {
            *v += a * h;
        }
    }
}

/// A rigid body's velocity is its own; a member's, its system's (after a prediction).
pub(super) fn write_members(systems: &[System], bodies: &mut [IslandBody]) {
    for s in systems {
        s.write_members(bodies);
    }
}
