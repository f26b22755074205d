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
//! **Self-collision** is an option of each multibody ([`MultibodyOptions::self_collision`],
//! `self_collision: true` in a scene file), off by default: links of one multibody then
//! collide with each other, except adjacent ones ([`impulse_multibody::Model::links_adjacent`]:
//! links welded into one rigid body by fixed joints, and the two rigid bodies of every moving
//! joint, parent and child). Two links of one tree share one velocity vector, so their
//! collision matrix is the relative one, `K = (J₁ − J₂) M⁻¹ (J₁ − J₂)ᵀ`, not a sum
//! ([`crate::articulated::collide_self`]). Off, no pair of one multibody's links is ever
//! considered: neither the event loop nor the penetration monitor looks at them.
//!
//! A link's collisions are impulses in the event loop; in the switching contact model its
//! slow contacts are held in contact islands with its multibody as one jointed system
//! (`held_links.rs`), in the pure impulse model they are microcollisions (the thesis's).

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

/// How a multibody takes part in the world, beyond its simulation and shapes
/// ([`World::add_multibody_with`]). The default is what [`World::add_multibody`] uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MultibodyOptions {
    /// Whether its links collide with each other (self-collision), adjacent links excepted
    /// ([`impulse_multibody::Model::links_adjacent`]: welded into one rigid body, or parent
    /// and child of a moving joint). Default `false`: links of one multibody never collide.
    pub self_collision: bool,
}

impl MultibodyOptions {
    /// These options with self-collision on or off.
    #[must_use]
    pub fn with_self_collision(mut self, on: bool) -> Self {
        self.self_collision = on;
        self
    }
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
    /// Whether its non-adjacent links collide with each other.
    pub(crate) self_collision: bool,
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
        sim: Simulation,
        shapes: Vec<LinkShape>,
    ) -> Result<MultibodyHandle, SimError> {
        self.add_multibody_with(name, sim, shapes, MultibodyOptions::default())
    }

    /// [`World::add_multibody`] with options: with [`MultibodyOptions::self_collision`], its
    /// non-adjacent links collide with each other, and two of them overlapping by more than
    /// ε_c at the start are refused as any two bodies are.
    ///
    /// # Errors
    /// As [`World::add_multibody`].
    pub fn add_multibody_with(
        &mut self,
        name: &str,
        mut sim: Simulation,
        shapes: Vec<LinkShape>,
        options: MultibodyOptions,
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
        sim.set_tracking(true);
        // The member first: which of its link pairs matter (overlaps, new close pairs) depends
        // on it. Removed again on error.
        self.multibodies.push(Member {
            name: name.to_owned(),
            sim,
            offset: self.time,
            links: Vec::new(),
            self_collision: options.self_collision,
        });
        if let Err(e) = self.check_overlaps(&bodies) {
            self.multibodies.pop();
            return Err(e);
        }
        let old = (self.materials.clone(), self.hash.clone());
        self.materials = materials;
        let ids: Vec<u32> = bodies.into_iter().map(|b| self.insert(b)).collect();
        for (l, &i) in links.iter_mut().zip(&ids) {
            l.1 = i;
        }
        let m = self.multibodies.len() - 1;
        self.multibodies[m].links = links;
        if let Err(e) = self
            .sync_broadphase(&ids)
            .and_then(|()| self.promote_new_pairs())
        {
            for &i in &ids {
                self.unregister(i);
            }
            (self.materials, self.hash) = old;
            self.multibodies.pop();
            return Err(e);
        }
        Ok(MultibodyHandle(m as u32))
    }

    /// Whether a multibody's non-adjacent links collide with each other
    /// ([`MultibodyOptions::self_collision`]).
    #[must_use]
    pub fn self_collision(&self, h: MultibodyHandle) -> Option<bool> {
        self.multibodies.get(h.0 as usize).map(|m| m.self_collision)
    }

    /// Whether two link bodies (their multibodies and links, as [`Body::link`] gives them)
    /// can ever collide: links of two multibodies always; links of one multibody only with
    /// its self-collision on and when they are not adjacent
    /// ([`impulse_multibody::Model::links_adjacent`]).
    pub(crate) fn links_collide(&self, (ma, la): (u32, LinkId), (mb, lb): (u32, LinkId)) -> bool {
        if ma != mb {
            return true;
        }
        let Some(m) = self.multibodies.get(ma as usize) else {
            return false;
        };
        // An id outside the model names no link of it: nothing to collide.
        m.self_collision && matches!(m.sim.model().links_adjacent(la, lb), Ok(false))
    }

    /// Names of the multibodies' generalized coordinates, in the order of
    /// [`World::joint_values`]: for each multibody (the order added), its configuration `q`
    /// then its velocity `v` (the layout of `impulse_multibody`: a floating base's
    /// `base.x, base.y, base.z, base.qx, base.qy, base.qz, base.qw` first in `q` and
    /// `base.vx … base.wz` (base coordinates) first in `v`), each name prefixed by the
    /// multibody's: `arm/elbow.q`, `arm/elbow.qd`.
    #[must_use]
    pub fn joint_columns(&self) -> Vec<String> {
        let mut names = Vec::new();
        for m in &self.multibodies {
            let model = m.sim.model();
            let base = |cols: &[&str], names: &mut Vec<String>| {
                if model.is_floating() {
                    names.extend(cols.iter().map(|c| format!("{}/base.{c}", m.name)));
                }
            };
            base(&["x", "y", "z", "qx", "qy", "qz", "qw"], &mut names);
            for j in model.joint_names() {
                names.push(format!("{}/{j}.q", m.name));
            }
            base(&["vx", "vy", "vz", "wx", "wy", "wz"], &mut names);
            for j in model.joint_names() {
                names.push(format!("{}/{j}.qd", m.name));
            }
        }
        names
    }

    /// The multibodies' generalized coordinates now, named by [`World::joint_columns`].
    #[must_use]
    pub fn joint_values(&self) -> Vec<f64> {
        let mut values = Vec::new();
        for m in &self.multibodies {
            values.extend_from_slice(m.sim.q());
            values.extend_from_slice(m.sim.v());
        }
        values
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

    /// A multibody's name, as its scene or [`World::add_multibody`] gave it.
    #[must_use]
    pub fn multibody_name(&self, h: MultibodyHandle) -> Option<&str> {
        self.multibodies.get(h.0 as usize).map(|m| m.name.as_str())
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
