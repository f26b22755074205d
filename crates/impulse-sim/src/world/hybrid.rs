//! Multibodies as members of the world (thesis chapter 5, hybrid simulation).
//!
//! A multibody joins the world with [`World::add_multibody`]: its
//! [`impulse_multibody::Simulation`] (model, state, integrator, controllers, joint limits)
//! and a collision shape for each link that should collide. Each such link becomes a body of
//! kind [`BodyKind::Link`] in the world's body table, so the broad phase, the collision heap,
//! the closest-feature checks and the penetration monitor treat it as any other body; what
//! differs is how it moves and how it takes an impulse:
//!
//! - **Motion** (§5.2): between events, every multibody is integrated by its own integrator
//!   (adaptive RK4 by default) to the top of the heap; its links' swept boxes and
//!   time-of-impact coefficients are the thesis's padded predictions
//!   ([`impulse_collide::motion::LinkMotion`]), checked after the integration against the
//!   motion actually seen: a link outside its box, or one that travelled toward another body
//!   farther than its pair's bound allowed (the slack structure, Fig. 5.4), makes the step be
//!   done again, shorter, from its start (`hybrid_step.rs`).
//! - **Collisions** (§5.3): K of a contact on a link from the impulse-space articulated-body
//!   recursion, summed with the other side's, the impulse from `impulse-response` (the same
//!   code as rigid bodies, microcollisions included), propagated through the tree
//!   ([`crate::articulated`]).
//!
//! Links of one multibody do not collide with each other (self-collision is not supported).
//! Contacts of links are always impulses: the switching model never holds a pair with a link
//! (resting links are microcollisions, the thesis's pure model).

use crate::scene::ShapeDesc;
use impulse_collide::motion::LinkMotion;
use impulse_multibody::{LinkId, LinkKinematics, Simulation};

use super::{BodyHandle, World};
use crate::body::{Body, BodyKind};
use crate::error::SimError;

/// A multibody of a world (its index in the order multibodies were added).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct MultibodyHandle(pub(crate) u32);

impl MultibodyHandle {
    /// The multibody's position in the order multibodies were added.
    #[must_use]
    pub fn index(self) -> u32 {
        self.0
    }
}

/// A collision shape for one link of a multibody added to a world.
#[derive(Clone, Debug)]
pub struct LinkShape {
    /// The link's name in the multibody's model.
    pub link: String,
    /// The shape, in the link's frame (as a body's shape is given: primitives, convex OBJ
    /// files relative to the world's base directory, compounds).
    pub shape: ShapeDesc,
    /// The material name (contact properties: [`World::set_material_pair`]).
    pub material: String,
}

/// A multibody in the world.
#[derive(Clone)]
pub(crate) struct Member {
    pub(crate) name: String,
    /// Its simulation, on its own clock: world time = `offset` + simulation time.
    pub(crate) sim: Simulation,
    pub(crate) offset: f64,
    /// The links with shapes, and their bodies' slots.
    pub(crate) links: Vec<(LinkId, u32)>,
}

impl Member {
    /// The multibody's clock for world time `t`.
    pub(crate) fn local(&self, t: f64) -> f64 {
        (t - self.offset).max(self.sim.time())
    }
}

fn invalid(what: &str, field: &str, problem: String) -> SimError {
    SimError::Invalid {
        what: what.into(),
        field: field.into(),
        problem,
    }
}

impl World {
    /// Adds a multibody: its simulation (model, state, integrator, controllers and joint
    /// limits as built) and a collision shape for each link that collides. Its clock starts
    /// now, and its model's gravity becomes the world's. Each shaped link becomes a body named `"<name>/<link>"` of kind
    /// [`BodyKind::Link`] (see [`World::link_body`]).
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the multibody or link: an empty or taken name, a link
    /// not in the model or given two shapes, a link welded to the ground that is not
    /// moving (give it to the world as a fixed body instead); [`SimError::Overlap`] when a
    /// link overlaps another body by more than ε_c; [`SimError::Runtime`] when the state
    /// cannot be evaluated. The world is then unchanged.
    pub fn add_multibody(
        &mut self,
        name: &str,
        mut sim: Simulation,
        shapes: Vec<LinkShape>,
    ) -> Result<MultibodyHandle, SimError> {
        let what = format!("multibody \"{name}\"");
        if name.is_empty() || self.multibodies.iter().any(|m| m.name == name) {
            return Err(invalid(
                &what,
                "name",
                "must be non-empty and not another multibody's".into(),
            ));
        }
        sim.model_mut().set_gravity(self.gravity);
        let kin = sim
            .link_kinematics()
            .map_err(|e| invalid(&what, "state", e.to_string()))?;
        let model = sim.model().clone();
        let mut bodies = Vec::new();
        let mut links = Vec::new();
        let mut materials = self.materials.clone();
        for s in shapes {
            let lwhat = format!("{what}, link \"{}\"", s.link);
            let id = model
                .link_id(&s.link)
                .ok_or_else(|| invalid(&lwhat, "link", "no such link in the model".into()))?;
            if links.iter().any(|&(l, _)| l == id) {
                return Err(invalid(&lwhat, "link", "has two shapes".into()));
            }
            let body_name = format!("{name}/{}", s.link);
            if self.names.contains_key(&body_name) {
                return Err(invalid(
                    &lwhat,
                    "name",
                    format!("a body is already called \"{body_name}\""),
                ));
            }
            let shape =
                crate::build::shape(&s.shape, &self.base_dir).map_err(|e| SimError::Geometry {
                    body: body_name.clone(),
                    message: e,
                })?;
            let k = kin[id.index()];
            let motion = link_motion(&k).map_err(|e| invalid(&lwhat, "state", e))?;
            let material = materials.index(&s.material);
            let mut body = Body::new(
                body_name,
                shape,
                BodyKind::Link,
                k.pose,
                k.velocity,
                k.omega,
                None,
                material,
                Some(motion),
            );
            body.link = Some((self.multibodies.len() as u32, id));
            links.push((id, 0));
            bodies.push(body);
        }
        self.check_overlaps(&bodies)?;
        let old = (self.materials.clone(), self.hash.clone());
        self.materials = materials;
        let ids: Vec<u32> = bodies.into_iter().map(|b| self.insert(b)).collect();
        for (l, &i) in links.iter_mut().zip(&ids) {
            l.1 = i;
        }
        if let Err(e) = self
            .sync_broadphase(&ids)
            .and_then(|()| self.promote_new_pairs())
        {
            for &i in &ids {
                self.unregister(i);
            }
            (self.materials, self.hash) = old;
            return Err(e);
        }
        sim.set_tracking(true);
        self.multibodies.push(Member {
            name: name.to_owned(),
            sim,
            offset: self.time,
            links,
        });
        Ok(MultibodyHandle(self.multibodies.len() as u32 - 1))
    }

    /// The multibodies' handles, in the order they were added.
    #[must_use]
    pub fn multibody_handles(&self) -> Vec<MultibodyHandle> {
        (0..self.multibodies.len() as u32)
            .map(MultibodyHandle)
            .collect()
    }

    /// The multibody called `name`.
    #[must_use]
    pub fn multibody_handle(&self, name: &str) -> Option<MultibodyHandle> {
        self.multibodies
            .iter()
            .position(|m| m.name == name)
            .map(|i| MultibodyHandle(i as u32))
    }

    /// A multibody's simulation: its state, model, controllers and counters. Its clock
    /// ([`Simulation::time`]) counts from when it was added ([`World::multibody_clock`]).
    #[must_use]
    pub fn multibody(&self, h: MultibodyHandle) -> Option<&Simulation> {
        self.multibodies.get(h.0 as usize).map(|m| &m.sim)
    }

    /// The world time at which a multibody's clock reads zero.
    #[must_use]
    pub fn multibody_clock(&self, h: MultibodyHandle) -> Option<f64> {
        self.multibodies.get(h.0 as usize).map(|m| m.offset)
    }

    /// The body standing for link `link` of a multibody in the broad phase and the collision
    /// heap (`None` for a link without a shape).
    #[must_use]
    pub fn link_body(&self, h: MultibodyHandle, link: &str) -> Option<BodyHandle> {
        let m = self.multibodies.get(h.0 as usize)?;
        let id = m.sim.model().link_id(link)?;
        m.links
            .iter()
            .find(|&&(l, _)| l == id)
            .map(|&(_, i)| self.handle_of(i))
    }

    /// Kinetic and gravitational potential energy of every multibody (J; potential zero at
    /// the world origin, as for rigid bodies).
    pub(crate) fn multibody_energies(&self) -> (f64, f64) {
        let mut kinetic = 0.0;
        let mut potential = 0.0;
        for m in &self.multibodies {
            let model = m.sim.model();
            let mut ws = impulse_multibody::Workspace::new(model);
            if ws.update_kinematics(model, m.sim.q(), m.sim.v()).is_ok() {
                kinetic += ws.kinetic_energy(model);
                potential += ws.potential_energy(model);
            }
        }
        (kinetic, potential)
    }

    /// Puts every shaped link of multibody `m` where its simulation's state says, with a
    /// fresh prediction of its motion.
    ///
    /// # Errors
    /// [`SimError::Runtime`] when the state cannot be evaluated (not finite).
    pub(crate) fn sync_links(&mut self, m: usize) -> Result<(), SimError> {
        let kin = self.multibodies[m]
            .sim
            .link_kinematics()
            .map_err(|e| self.runtime(format!("multibody {}: {e}", self.multibodies[m].name)))?;
        self.place_links(m, &kin)
    }

    /// Puts every shaped link of multibody `m` where `kin` (its links' kinematics now, in
    /// link order) says, with a fresh prediction of its motion.
    ///
    /// # Errors
    /// [`SimError::Runtime`] when a prediction cannot be made (not finite).
    pub(crate) fn place_links(
        &mut self,
        m: usize,
        kin: &[impulse_multibody::LinkKinematics],
    ) -> Result<(), SimError> {
        for k in 0..self.multibodies[m].links.len() {
            let (id, slot) = self.multibodies[m].links[k];
            let lk = kin[id.index()];
            let motion = link_motion(&lk).map_err(|e| {
                self.runtime(format!(
                    "multibody {}, link body {}: {e}",
                    self.multibodies[m].name,
                    self.name(slot)
                ))
            })?;
            let b = self.b_mut(slot);
            b.pose = lk.pose;
            b.velocity = lk.velocity;
            b.omega = lk.omega;
            b.script = Some(motion);
        }
        Ok(())
    }

    /// The slots of every shaped link of multibody `m`.
    pub(crate) fn link_slots(&self, m: usize) -> Vec<u32> {
        self.multibodies[m].links.iter().map(|&(_, i)| i).collect()
    }

    /// Refuses a change to a link's body through the rigid-body API: a link moves with its
    /// multibody.
    pub(crate) fn refuse_link(&self, i: u32, what: &str) -> Result<(), SimError> {
        match self.b(i).link {
            Some((m, _)) => Err(invalid(
                &format!("body \"{}\"", self.name(i)),
                what,
                format!(
                    "is a link of multibody \"{}\": change the multibody's state instead",
                    self.multibodies[m as usize].name
                ),
            )),
            None => Ok(()),
        }
    }
}

/// The thesis's prediction of a link's motion from its kinematics now.
pub(crate) fn link_motion(k: &LinkKinematics) -> Result<impulse_collide::Motion, String> {
    LinkMotion::new(k.pose.translation, k.velocity, k.acceleration, k.omega)
        .and_then(|m| m.with_angular_acceleration(k.angular_acceleration))
        .map(impulse_collide::Motion::Link)
        .map_err(|e| e.to_string())
}
