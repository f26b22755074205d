//! What a program does to a world between steps: add and remove bodies, move them, change
//! their velocities, push them with impulses and loads, set material pairs.
//!
//! Every change is checked first and either happens whole or not at all (an `Err` leaves the
//! world as it was). Pairs of a body the program moved or pushed get new time-of-impact
//! bounds before the next step, so the collision guarantees hold across changes.

use std::path::PathBuf;
use std::sync::Arc;

use glam::{DQuat, DVec3};
use impulse_broadphase::{CoherentHash, DEFAULT_ALPHA, DEFAULT_BETA, Levels};
use impulse_collide::depth;
use impulse_geom::Pose;

use super::{BodyHandle, BodyState, LoadSchedule, Material, SWEEP_ALLOWANCE, Slot, World};
use crate::body::{Body, BodyKind};
use crate::build;
use crate::error::SimError;
use crate::monitor::close_pairs;
use crate::scene::{BodyDesc, MAX_EPSILON_REL, shape_thickness};

/// A force through the centre of mass and a torque, both in world coordinates, acting on a
/// body until changed (persistent, unlike an impulse).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Load {
    /// Force (world).
    pub force: DVec3,
    /// Torque about the centre of mass (world). A force `f` at a world point `x` is the force
    /// `f` with the torque `(x − com) × f`.
    pub torque: DVec3,
}

impl Load {
    /// No load.
    pub const ZERO: Self = Self {
        force: DVec3::ZERO,
        torque: DVec3::ZERO,
    };

    /// A force through the centre of mass.
    #[must_use]
    pub fn force(force: DVec3) -> Self {
        Self {
            force,
            torque: DVec3::ZERO,
        }
    }

    /// A force applied at world point `point` of a body whose centre of mass is `com`: the
    /// force plus its moment about the centre of mass.
    #[must_use]
    pub fn force_at(force: DVec3, point: DVec3, com: DVec3) -> Self {
        Self {
            force,
            torque: (point - com).cross(force),
        }
    }

    fn is_finite(&self) -> bool {
        self.force.is_finite() && self.torque.is_finite()
    }
}

/// A load that depends on time and on the body's state, evaluated at a fixed rate and held
/// constant between evaluations (a controller, a spring to a point, drag).
pub type LoadFn = Arc<dyn Fn(f64, &BodyState) -> Load + Send + Sync>;

impl World {
    /// Sets the directory that relative paths of bodies added later (OBJ files) resolve
    /// against.
    pub fn set_base_dir(&mut self, dir: impl Into<PathBuf>) {
        self.base_dir = dir.into();
    }

    /// Sets the friction and restitution of materials `a` and `b` (either order; names not
    /// used yet are added).
    ///
    /// # Errors
    /// [`SimError::Invalid`] for μ < 0 or e outside [0, 1].
    pub fn set_material_pair(&mut self, a: &str, b: &str, m: Material) -> Result<(), SimError> {
        m.validate().map_err(|problem| SimError::Invalid {
            what: format!("material pair {a} / {b}"),
            field: "contact".into(),
            problem,
        })?;
        self.materials.set(a, b, m);
        Ok(())
    }

    /// Adds a body (see [`BodyDesc`] and its builder methods); returns its handle.
    ///
    /// # Errors
    /// [`SimError::Invalid`] for a bad field or a name already in use,
    /// [`SimError::Geometry`] when its shape cannot be built, [`SimError::Overlap`] when it
    /// overlaps another body by more than ε_c. The world is then unchanged.
    pub fn add_body(&mut self, desc: &BodyDesc) -> Result<BodyHandle, SimError> {
        let handles = self.add_bodies(std::slice::from_ref(desc))?;
        Ok(handles[0])
    }

    /// Adds several bodies at once, all or none (cheaper than one by one: the broad phase is
    /// sized once and overlaps are found by one sweep).
    ///
    /// # Errors
    /// As [`World::add_body`], for the first body that fails; the world is then unchanged.
    pub fn add_bodies(&mut self, descs: &[BodyDesc]) -> Result<Vec<BodyHandle>, SimError> {
        let eps = self.collision_epsilon();
        let mut seen = rustc_hash::FxHashSet::default();
        let mut built = Vec::with_capacity(descs.len());
        let mut materials = self.materials.clone();
        for (k, desc) in descs.iter().enumerate() {
            desc.validate(k)?;
            if self.names.contains_key(&desc.name) || !seen.insert(desc.name.as_str()) {
                return Err(SimError::Invalid {
                    what: format!("body \"{}\"", desc.name),
                    field: "name".into(),
                    problem: "another body has the same name".into(),
                });
            }
            if desc.motion == crate::scene::MotionDesc::Dynamic {
                if let Some(size) = shape_thickness(&desc.shape) {
                    if eps > MAX_EPSILON_REL * size {
                        return Err(SimError::Invalid {
                            what: format!("body \"{}\"", desc.name),
                            field: "shape".into(),
                            problem: format!(
                                "its half-size {size:e} is less than ε_c = {eps:e} / \
                                 {MAX_EPSILON_REL}: it would be in contact with everything \
                                 near it (make ε_c smaller)"
                            ),
                        });
                    }
                }
            }
            let material = materials.index(&desc.material);
            built.push(build::body(desc, material, &self.base_dir)?);
        }
        self.check_overlaps(&built)?;
        // Only the broad phase can still fail (a body far too large for its levels): then
        // the bodies come out again and the old broad phase is put back.
        let old = (self.materials.clone(), self.hash.clone());
        self.materials = materials;
        let ids: Vec<u32> = built.into_iter().map(|body| self.insert(body)).collect();
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
        Ok(ids.iter().map(|&i| self.handle_of(i)).collect())
    }

    /// Takes body `i` out of the body table, the heap and the pair table (a body just
    /// inserted whose addition failed).
    pub(super) fn unregister(&mut self, i: u32) {
        let slot = &mut self.slots[i as usize];
        if let Some(body) = slot.body.take() {
            self.names.remove(&body.name);
        }
        slot.generation += 1;
        self.free.push(i);
        for p in self.heap.pairs_of(i).collect::<Vec<_>>() {
            self.heap.remove(p);
        }
        self.pairs.retain(|&(a, b), _| a != i && b != i);
        self.far_keyed.retain(|&(a, b)| a != i && b != i);
    }

    /// Refuses new bodies that overlap one another or a body of the world by more than ε_c.
    /// Touching, or overlapping by less, is contact: the event loop takes it from there.
    pub(super) fn check_overlaps(&self, new: &[Body]) -> Result<(), SimError> {
        let eps = self.collision_epsilon();
        let old: Vec<&Body> = self.bodies().map(|(_, b)| b).collect();
        let all: Vec<&Body> = old.iter().copied().chain(new.iter()).collect();
        let boxes: Vec<_> = all
            .iter()
            .map(|b| b.shape.aabb(&b.pose).expanded(eps))
            .collect();
        for (i, j) in close_pairs(&boxes) {
            let (i, j) = (i as usize, j as usize);
            let never = matches!(
                (all[i].link, all[j].link),
                (Some(a), Some(b)) if !self.links_collide(a, b)
            );
            if j < old.len() || !(all[i].takes_impulses() || all[j].takes_impulses()) || never {
                // Two old bodies, or two that never collide (fixed walls may overlap; links of
                // one multibody touch at their joints, and collide only with its
                // self-collision on and not adjacent).
                continue;
            }
            refuse_overlap(all[i], all[j], eps)?;
        }
        Ok(())
    }

    /// Puts a built body in a free slot.
    pub(super) fn insert(&mut self, mut body: Body) -> u32 {
        let name = body.name.clone();
        body.synced = self.time;
        body.box_until = f64::NEG_INFINITY;
        let i = if let Some(i) = self.free.pop() {
            self.slots[i as usize].body = Some(body);
            i
        } else {
            self.slots.push(Slot {
                generation: 0,
                body: Some(body),
            });
            (self.slots.len() - 1) as u32
        };
        self.names.insert(name, i);
        self.expire_box(i);
        i
    }

    /// The size the broad phase sizes its levels by: the diameter of a moving body's sphere,
    /// the box size of a fixed one.
    fn broadphase_size(&self, i: u32) -> f64 {
        let b = self.b(i);
        if b.kind == BodyKind::Fixed {
            impulse_broadphase::box_size(&b.shape.aabb(&b.pose))
        } else {
            2.0 * b.r_max
        }
    }

    /// Inserts bodies `new` in the broad phase, rebuilding its levels when a size falls
    /// outside the range they were made for.
    pub(super) fn sync_broadphase(&mut self, new: &[u32]) -> Result<(), SimError> {
        let sizes: Vec<f64> = new.iter().map(|&i| self.broadphase_size(i)).collect();
        let fits = |(lo, hi): (f64, f64)| sizes.iter().all(|&s| s >= lo && s <= hi);
        match &self.hash {
            Some((_, range)) if fits(*range) => {
                for &i in new {
                    let b = self.static_box(i);
                    self.hash_mut().insert(i, b).map_err(|e| {
                        self.runtime(format!("broad phase, body {}: {e}", self.name(i)))
                    })?;
                }
                Ok(())
            }
            _ => self.rebuild_broadphase(),
        }
    }

    /// New broad-phase levels for the sizes of every body, and every body inserted again.
    /// Pairs already in the heap keep their keys; the hash reports every close pair as new,
    /// and those not in the heap are promoted by the caller.
    fn rebuild_broadphase(&mut self) -> Result<(), SimError> {
        let ids: Vec<u32> = self.bodies().map(|(h, _)| h.index).collect();
        if ids.is_empty() {
            self.hash = None;
            return Ok(());
        }
        let sizes: Vec<f64> = ids.iter().map(|&i| self.broadphase_size(i)).collect();
        let lo = sizes.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = sizes.iter().copied().fold(0.0, f64::max);
        let eps = self.collision_epsilon();
        let levels = Levels::from_size_range(
            lo.max(eps),
            (hi * SWEEP_ALLOWANCE).max(lo.max(eps)),
            DEFAULT_ALPHA,
            DEFAULT_BETA,
        )
        .map_err(|e| self.runtime(format!("broad phase: {e}")))?;
        self.hash = Some((CoherentHash::new(levels), (lo, hi)));
        for i in ids {
            let b = self.static_box(i);
            self.hash_mut()
                .insert(i, b)
                .map_err(|e| self.runtime(format!("broad phase, body {}: {e}", self.name(i))))?;
        }
        Ok(())
    }

    /// Removes a body; returns it. Its handle, and every copy of it, names nothing afterwards.
    ///
    /// # Errors
    /// [`SimError::UnknownBody`] for a handle whose body is already gone.
    pub fn remove_body(&mut self, h: BodyHandle) -> Result<Body, SimError> {
        let i = self.index_of(h)?;
        self.refuse_link(i, "remove")?;
        for p in self.heap.pairs_of(i).collect::<Vec<_>>() {
            self.heap.remove(p);
        }
        self.release_all_of(i)?;
        self.pairs.retain(|&(a, b), _| a != i && b != i);
        self.far_keyed.retain(|&(a, b)| a != i && b != i);
        self.loads.retain(|l| l.body != i);
        self.stale.retain(|&s| s != i);
        if let Some((hash, _)) = &mut self.hash {
            // The body was inserted when it was added; an error here would mean it was not.
            let _ = hash.remove(i);
        }
        let slot = &mut self.slots[i as usize];
        let body = slot.body.take().expect("a live handle names a body");
        slot.generation += 1;
        self.free.push(i);
        self.names.remove(&body.name);
        Ok(body)
    }

    /// Places the body's own frame at `position` with orientation `rotation` (world),
    /// keeping its velocities.
    ///
    /// # Errors
    /// [`SimError::UnknownBody`]; [`SimError::Invalid`] for non-finite input or a scripted
    /// body (it follows its script); [`SimError::Overlap`] when the body would overlap another
    /// by more than ε_c. The world is then unchanged.
    pub fn set_pose(
        &mut self,
        h: BodyHandle,
        position: DVec3,
        rotation: DQuat,
    ) -> Result<(), SimError> {
        let i = self.index_of(h)?;
        self.refuse_link(i, "pose")?;
        let b = self.b(i);
        let bad = |field: &str, problem: String| SimError::Invalid {
            what: format!("body \"{}\"", b.name),
            field: field.into(),
            problem,
        };
        if !position.is_finite() {
            return Err(bad("position", format!("{position} is not finite")));
        }
        let Some(rotation) = rotation
            .is_finite()
            .then(|| rotation.normalize())
            .filter(|q| q.is_finite())
        else {
            return Err(bad(
                "rotation",
                format!("{rotation} is not a finite, non-zero quaternion"),
            ));
        };
        if b.kind == BodyKind::Scripted {
            return Err(bad("pose", "a scripted body follows its script".into()));
        }
        let mut moved = b.clone();
        moved.pose = Pose::new(rotation, position) * b.frame.inverse();
        let others: Vec<u32> = self
            .bodies()
            .map(|(h, _)| h.index)
            .filter(|&j| j != i)
            .collect();
        let eps = self.collision_epsilon();
        for j in others {
            let o = self.b(j);
            if !(moved.takes_impulses() || o.takes_impulses())
                || !moved
                    .shape
                    .aabb(&moved.pose)
                    .expanded(eps)
                    .overlaps(&o.shape.aabb(&o.pose))
            {
                continue;
            }
            refuse_overlap(&moved, o, eps)?;
        }
        let fixed = moved.kind == BodyKind::Fixed;
        *self.b_mut(i) = moved;
        self.forget_pair_states(i)?;
        if fixed {
            let b = self.static_box(i);
            self.hash_mut()
                .update(i, b)
                .map_err(|e| self.runtime(format!("broad phase, body {}: {e}", self.name(i))))?;
        }
        self.mark_stale(i);
        Ok(())
    }

    /// Sets the velocity of the centre of mass and the angular velocity (world) of a dynamic
    /// body.
    ///
    /// # Errors
    /// [`SimError::UnknownBody`]; [`SimError::Invalid`] for non-finite input or a body that is
    /// not dynamic.
    pub fn set_velocity(
        &mut self,
        h: BodyHandle,
        velocity: DVec3,
        omega: DVec3,
    ) -> Result<(), SimError> {
        let i = self.dynamic_index(h, "velocity")?;
        self.check_velocity(i, velocity, omega)?;
        let b = self.b_mut(i);
        b.velocity = velocity;
        b.omega = omega;
        self.mark_stale(i);
        Ok(())
    }

    /// Sets pose and velocities at once ([`World::set_pose`], then [`World::set_velocity`];
    /// the state's `com` is ignored: it follows from the pose).
    ///
    /// # Errors
    /// As those two; the world is unchanged on error.
    pub fn set_state(&mut self, h: BodyHandle, state: &BodyState) -> Result<(), SimError> {
        let i = self.dynamic_index(h, "state")?;
        self.check_velocity(i, state.velocity, state.omega)?;
        self.set_pose(h, state.position, state.rotation)?;
        self.set_velocity(h, state.velocity, state.omega)
    }

    /// Applies an impulse (world) at a world point of a dynamic body: Δv = p/m,
    /// ΔL = (x − com) × p.
    ///
    /// # Errors
    /// [`SimError::UnknownBody`]; [`SimError::Invalid`] for non-finite input or a body that is
    /// not dynamic.
    pub fn apply_impulse(
        &mut self,
        h: BodyHandle,
        impulse: DVec3,
        point: DVec3,
    ) -> Result<(), SimError> {
        let i = self.dynamic_index(h, "impulse")?;
        if !(impulse.is_finite() && point.is_finite()) {
            let problem = format!("impulse {impulse} at {point} must be finite");
            return Err(self.invalid(i, "impulse", problem));
        }
        self.b_mut(i).apply_impulse(impulse, point);
        self.mark_stale(i);
        Ok(())
    }

    /// Sets a constant load (force through the centre of mass and torque, world) on a dynamic
    /// body, replacing any load or load function; [`Load::ZERO`] removes it. Between
    /// collisions the body's centre of mass then follows the parabola of `g + f/m` exactly,
    /// and its angular momentum grows as `L₀ + τ·t`.
    ///
    /// # Errors
    /// [`SimError::UnknownBody`]; [`SimError::Invalid`] for non-finite input or a body that is
    /// not dynamic.
    pub fn set_load(&mut self, h: BodyHandle, load: Load) -> Result<(), SimError> {
        let i = self.dynamic_index(h, "load")?;
        if !load.is_finite() {
            return Err(SimError::Invalid {
                what: format!("body \"{}\"", self.name(i)),
                field: "load".into(),
                problem: format!("{load:?} must be finite"),
            });
        }
        self.loads.retain(|l| l.body != i);
        let b = self.b_mut(i);
        b.force = load.force;
        b.torque = load.torque;
        self.mark_stale(i);
        Ok(())
    }

    /// Sets a load function on a dynamic body: `f(t, state)` is evaluated now and then every
    /// `1/rate` seconds of simulated time, and the load it returns is held constant in
    /// between (exactly integrated, as [`World::set_load`]). Replaces any load.
    ///
    /// # Errors
    /// [`SimError::UnknownBody`]; [`SimError::Invalid`] for a rate that is not positive and
    /// finite, a body that is not dynamic, or a first evaluation that is not finite.
    pub fn set_load_fn(
        &mut self,
        h: BodyHandle,
        rate: f64,
        f: impl Fn(f64, &BodyState) -> Load + Send + Sync + 'static,
    ) -> Result<(), SimError> {
        let i = self.dynamic_index(h, "load")?;
        if !(rate.is_finite() && rate > 0.0) {
            return Err(SimError::Invalid {
                what: format!("body \"{}\"", self.name(i)),
                field: "load rate".into(),
                problem: format!("{rate} must be finite and > 0"),
            });
        }
        let first = f(self.time, &self.b(i).state());
        if !first.is_finite() {
            return Err(SimError::Invalid {
                what: format!("body \"{}\"", self.name(i)),
                field: "load".into(),
                problem: format!("the load function gave {first:?} at t = {}", self.time),
            });
        }
        self.loads.retain(|l| l.body != i);
        self.loads.push(LoadSchedule {
            body: i,
            rate,
            start: self.time,
            evaluations: 1,
            f: Arc::new(f),
        });
        self.counters.load_evaluations += 1;
        let b = self.b_mut(i);
        b.force = first.force;
        b.torque = first.torque;
        self.mark_stale(i);
        Ok(())
    }

    /// Removes any load or load function from a body.
    ///
    /// # Errors
    /// [`SimError::UnknownBody`].
    pub fn clear_load(&mut self, h: BodyHandle) -> Result<(), SimError> {
        let i = self.index_of(h)?;
        self.loads.retain(|l| l.body != i);
        let b = self.b_mut(i);
        if b.force != DVec3::ZERO || b.torque != DVec3::ZERO {
            b.force = DVec3::ZERO;
            b.torque = DVec3::ZERO;
            self.mark_stale(i);
        }
        Ok(())
    }

    /// An invalid-input error about body `i`'s `field`.
    fn invalid(&self, i: u32, field: &str, problem: String) -> SimError {
        SimError::Invalid {
            what: format!("body \"{}\"", self.name(i)),
            field: field.into(),
            problem,
        }
    }

    /// Refuses a non-finite velocity or angular velocity for body `i`.
    fn check_velocity(&self, i: u32, velocity: DVec3, omega: DVec3) -> Result<(), SimError> {
        if velocity.is_finite() && omega.is_finite() {
            Ok(())
        } else {
            Err(self.invalid(
                i,
                "velocity",
                format!("velocity {velocity} and angular velocity {omega} must be finite"),
            ))
        }
    }

    /// The slot of a live handle.
    fn index_of(&self, h: BodyHandle) -> Result<u32, SimError> {
        self.body(h).map(|_| h.index).ok_or(SimError::UnknownBody {
            handle: h.to_string(),
        })
    }

    /// The slot of a live handle naming a dynamic body (`what` names the change refused).
    fn dynamic_index(&self, h: BodyHandle, what: &str) -> Result<u32, SimError> {
        let i = self.index_of(h)?;
        if self.b(i).is_dynamic() {
            Ok(i)
        } else {
            Err(SimError::Invalid {
                what: format!("body \"{}\"", self.name(i)),
                field: what.into(),
                problem:
                    "only a dynamic body takes this (fixed and scripted bodies have infinite mass)"
                        .into(),
            })
        }
    }

    /// The body's pairs need new bounds before the next step.
    pub(super) fn mark_stale(&mut self, i: u32) {
        if !self.stale.contains(&i) {
            self.stale.push(i);
        }
        // Its keys are computed again for its exact load, its far pairs' too (`envelope.rs`).
        let b = self.b_mut(i);
        b.envelope = None;
        b.far = None;
        // A change by the program (or a load) wakes a sleeping island and is a transient for
        // an awake one: its island steps now.
        self.wake(i);
        if self.is_held_body(i) {
            self.step_now(i);
        }
    }

    /// Forgets the cached features and normals of every pair of body `i` (it was moved).
    fn forget_pair_states(&mut self, i: u32) -> Result<(), SimError> {
        self.release_all_of(i)?;
        for (pair, state) in &mut self.pairs {
            if pair.0 == i || pair.1 == i {
                *state = super::PairState::default();
            }
        }
        Ok(())
    }

    pub(super) fn hash_mut(&mut self) -> &mut CoherentHash {
        &mut self
            .hash
            .as_mut()
            .expect("a world with bodies has a broad phase")
            .0
    }
}

#[cfg(test)]
mod tests;

/// [`SimError::Overlap`] naming `a` and `b` if they overlap by more than `eps` (touching, or
/// overlapping by less, is contact).
fn refuse_overlap(a: &Body, b: &Body, eps: f64) -> Result<(), SimError> {
    match depth::shape_penetration(&a.shape, &a.pose, &b.shape, &b.pose) {
        Some((p, _)) if p.depth > eps => Err(SimError::Overlap {
            a: a.name.clone(),
            b: b.name.clone(),
            depth: p.depth,
            collision_epsilon: eps,
        }),
        _ => Ok(()),
    }
}
