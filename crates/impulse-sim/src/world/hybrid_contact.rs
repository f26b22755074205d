//! Resolving a contact that involves a multibody link (thesis §5.3) inside the event loop:
//! the sides as [`crate::articulated::Collider`]s, the same microcollision model as rigid
//! bodies, the impulse propagated through each multibody, the link bodies moved to their new
//! velocities. Two links of one multibody (self-collision) share its one velocity vector and
//! are resolved together ([`crate::articulated::collide_self`]).

use glam::DVec3;
use impulse_multibody::{LinkId, Simulation, Workspace};
use impulse_response::{MicrocollisionParams, ResponseKind, Settings};

use super::{ContactFailure, World};
use crate::articulated::{Collider, Law, LinkCollision, SelfContact, collide_self, collide_with};
use crate::body::{Body, BodyKind};
use crate::contact::{APPROACH_FLOOR_REL, ContactKind};
use crate::error::SimError;

/// Kinetic energy and linear momentum of a multibody.
fn multibody_energy(sim: &Simulation) -> (f64, DVec3) {
    let model = sim.model();
    let mut ws = Workspace::new(model);
    match ws.update_kinematics(model, sim.q(), sim.v()) {
        Ok(()) => (ws.kinetic_energy(model), ws.momentum(model).f),
        Err(_) => (f64::NAN, DVec3::NAN),
    }
}

/// What a resolved link contact changes.
enum Outcome {
    /// Two independent sides, each with its new velocity, and its body.
    Sides(Box<[(Owned, u32); 2]>),
    /// Two links of multibody `m`: its new velocity.
    Tree { m: usize, v: Vec<f64> },
}

/// One side of a link contact, owned while the collision is resolved (a link's model and
/// configuration are borrowed from the world; only its velocity is copied, to be changed).
enum Owned {
    Link {
        m: usize,
        link: impulse_multibody::LinkId,
        v: Vec<f64>,
    },
    Rigid {
        mass: f64,
        inertia: glam::DMat3,
        com: DVec3,
        velocity: DVec3,
        omega: DVec3,
    },
    Kinematic(DVec3),
    Fixed,
}

impl Owned {
    fn collider<'a>(&'a mut self, world: &'a World) -> Collider<'a> {
        match self {
            Owned::Link { m, link, v } => {
                let sim = &world.multibodies[*m].sim;
                Collider::Link {
                    model: sim.model(),
                    q: sim.q(),
                    v,
                    link: *link,
                }
            }
            Owned::Rigid {
                mass,
                inertia,
                com,
                velocity,
                omega,
            } => Collider::Rigid {
                mass: *mass,
                inertia: *inertia,
                com: *com,
                velocity,
                omega,
            },
            Owned::Kinematic(v) => Collider::Kinematic { velocity: *v },
            Owned::Fixed => Collider::Fixed,
        }
    }
}

impl World {
    fn owned_side(&self, i: u32, x: DVec3) -> Owned {
        let b: &Body = self.b(i);
        if let Some((m, link)) = b.link {
            return Owned::Link {
                m: m as usize,
                link,
                v: self.multibodies[m as usize].sim.v().to_vec(),
            };
        }
        match (b.kind, b.mass) {
            (BodyKind::Dynamic, Some(mass)) => Owned::Rigid {
                mass: mass.mass,
                inertia: b.inertia_world(),
                com: b.pose.translation,
                velocity: b.velocity,
                omega: b.omega,
            },
            (BodyKind::Scripted, _) => Owned::Kinematic(b.point_velocity(x)),
            _ => Owned::Fixed,
        }
    }

    /// Kinetic energy and linear momentum of what body `i` belongs to (its multibody for a
    /// link).
    pub(super) fn side_energy(&self, i: u32) -> (f64, DVec3) {
        let b = self.b(i);
        match b.link {
            Some((m, _)) => multibody_energy(&self.multibodies[m as usize].sim),
            None => (b.kinetic_energy(), b.linear_momentum()),
        }
    }

    /// Kinetic energy and linear momentum of the two sides of a contact together (once for
    /// two links of one multibody).
    pub(super) fn pair_energy(&self, i: u32, j: u32) -> (f64, DVec3) {
        if let (Some((ma, _)), Some((mb, _))) = (self.b(i).link, self.b(j).link) {
            if ma == mb {
                return self.side_energy(i);
            }
        }
        let (ea, pa) = self.side_energy(i);
        let (eb, pb) = self.side_energy(j);
        (ea + eb, pa + pb)
    }

    /// Resolves a contact of pair `(i, j)`, at least one a link, at `x` with normal `n` (from
    /// j toward i) and separation `d`; returns whether an impulse was applied. A response that
    /// fails is retried without friction, the rigid bodies' fallback ([`ContactKind::Fallback`],
    /// reported as a contact failure); only when that fails too is nothing applied (reported,
    /// and the pair is checked again).
    pub(super) fn resolve_link(&mut self, (i, j): (u32, u32), x: DVec3, n: DVec3, d: f64) -> bool {
        let (eps, gravity) = (self.collision_epsilon(), self.gravity);
        let g = gravity.length();
        let u = self.b(i).point_velocity(x) - self.b(j).point_velocity(x);
        if u.dot(n) >= -APPROACH_FLOOR_REL * (2.0 * g * eps).sqrt() {
            return false;
        }
        let mat = self.material(i, j);
        let law = Law {
            friction: mat.friction,
            restitution: mat.restitution,
            micro: (g > 0.0).then(|| {
                (
                    MicrocollisionParams {
                        gravity: g,
                        normal_gravity: gravity.dot(n).abs(),
                        collision_epsilon: eps,
                        max_restitution: self.model.max_restitution,
                        reversing: self.model.reversing,
                    },
                    d,
                )
            }),
            settings: Settings {
                rtol: self.model.collision_tolerance,
                ..Settings::default()
            },
        };
        let (energy, momentum) = self.pair_energy(i, j);
        let before = (energy, momentum, u.dot(n));
        let one_tree = match (self.b(i).link, self.b(j).link) {
            (Some((ma, la)), Some((mb, lb))) if ma == mb => Some((ma as usize, (la, lb))),
            _ => None,
        };
        let result = match one_tree {
            Some((m, links)) => self.resolve_self(m, links, x, n, &law),
            None => self.resolve_sides((i, j), x, n, &law),
        };
        let micro = g > 0.0 && -u.dot(n) < (2.0 * g * eps).sqrt();
        let mut fallback = None;
        let (collision, outcome) = match result {
            Ok((c, outcome)) if c.impulse_world().is_finite() => (c, outcome),
            failed => {
                let why = match failed {
                    Err(e) => e.to_string(),
                    Ok(_) => "the impulse is not finite".to_string(),
                };
                // The world's fallback for rigid bodies, a frictionless impulse along the
                // normal (restitution 1 for a microcollision, eq. 3.18, as the reversing
                // impulse would). The chapter-3 integrator can fail with friction on a
                // rank-deficient K (sticking unstable and no diverging ray: Theorem 16 needs K
                // positive definite): two links of one tree few joints apart, and also one
                // link of a chain against a fixed body (a point of a three-link pendulum's
                // middle link has fewer than three directions of motion). Without it, such a
                // link sank through the floor unresolved (found by the scene fuzz target).
                let plain = Law {
                    friction: 0.0,
                    restitution: if micro { 1.0 } else { mat.restitution },
                    micro: None,
                    ..law
                };
                let retry = match one_tree {
                    Some((m, links)) => self.resolve_self(m, links, x, n, &plain),
                    None => self.resolve_sides((i, j), x, n, &plain),
                };
                match retry {
                    Ok((c, outcome)) if c.impulse_world().is_finite() => {
                        fallback = Some(why);
                        (c, outcome)
                    }
                    _ => {
                        self.unresolved(i, j, format!("{why}; no impulse applied"));
                        return false;
                    }
                }
            }
        };
        match outcome {
            Outcome::Tree { m, v } => self.set_multibody_velocity((i, j), m, &v),
            Outcome::Sides(sides) => {
                for (side, body) in *sides {
                    match side {
                        Owned::Link { m, v, .. } => self.set_multibody_velocity((i, j), m, &v),
                        Owned::Rigid {
                            velocity, omega, ..
                        } => {
                            let b = self.b_mut(body);
                            b.velocity = velocity;
                            b.omega = omega;
                        }
                        Owned::Kinematic(_) | Owned::Fixed => {}
                    }
                }
            }
        }
        let kind = match collision.response.kind {
            _ if fallback.is_some() => ContactKind::Fallback,
            ResponseKind::Reversing => ContactKind::Reversing,
            _ if micro => ContactKind::Microcollision,
            _ => ContactKind::Collision,
        };
        if let Some(why) = fallback {
            let p = collision.impulse_world().length();
            self.unresolved(
                i,
                j,
                format!("{why}; resolved by a frictionless impulse {p:.6e} along the normal"),
            );
        }
        self.counters.link_contacts += 1;
        self.record_contact((i, j), kind, collision.impulse_world(), x, n, before);
        true
    }

    /// A contact of pair `(i, j)` between two sides that move independently (at most one link
    /// of any multibody): K summed, each side's new velocity.
    fn resolve_sides(
        &self,
        (i, j): (u32, u32),
        x: DVec3,
        n: DVec3,
        law: &Law,
    ) -> Result<(LinkCollision, Outcome), SimError> {
        let (mut a, mut b) = (self.owned_side(i, x), self.owned_side(j, x));
        let c = collide_with(&mut a.collider(self), &mut b.collider(self), x, n, law)?;
        Ok((c, Outcome::Sides(Box::new([(a, i), (b, j)]))))
    }

    /// A contact between links `la` (side i, the normal toward it) and `lb` of multibody `m`
    /// (self-collision): the relative K of one tree, one new velocity vector.
    fn resolve_self(
        &self,
        m: usize,
        (la, lb): (LinkId, LinkId),
        x: DVec3,
        n: DVec3,
        law: &Law,
    ) -> Result<(LinkCollision, Outcome), SimError> {
        let sim = &self.multibodies[m].sim;
        let mut v = sim.v().to_vec();
        let mut contact = SelfContact {
            model: sim.model(),
            q: sim.q(),
            v: &mut v,
            a: la,
            b: lb,
        };
        let c = collide_self(&mut contact, x, n, law).map_err(|e| {
            SimError::LinkCollision(format!("multibody {}: {e}", self.multibodies[m].name))
        })?;
        Ok((c, Outcome::Tree { m, v }))
    }

    /// Gives multibody `m` velocity `v` after an impulse on pair `(i, j)` and moves its link
    /// bodies; a velocity the simulation refuses is reported as a contact failure.
    fn set_multibody_velocity(&mut self, (i, j): (u32, u32), m: usize, v: &[f64]) {
        let name = self.multibodies[m].name.clone();
        let q = self.multibodies[m].sim.q().to_vec();
        if let Err(e) = self.multibodies[m].sim.set_state(&q, v) {
            self.failures.push(ContactFailure {
                time: self.time,
                a: self.handle_of(i),
                b: self.handle_of(j),
                message: format!("multibody {name}: {e}"),
            });
        }
        // A state that cannot be evaluated fails the next step, naming the multibody.
        let _ = self.sync_links(m);
    }
}
