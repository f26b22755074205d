//! The world and its event loop (thesis §1.2, §2.3.1, §2.4.3).
//!
//! One step of [`World::step_until`] is the `advance` algorithm of thesis §2.4.3:
//!
//! 1. `t_end` ← the earliest key of the collision heap (capped by the caller's time limit).
//! 2. Every moving body gets the box enclosing its swept volume over `[t, t_end]` (its motion's
//!    swept centre-of-mass box grown by r_max + ε_c); the coherent spatial hash updates its
//!    close counters, and every pair that became close (0→1) is checked and inserted in the
//!    heap. A new pair may have an earlier key: `t_end` shrinks (the boxes still cover it).
//! 3. Every body advances to `t_end`, independently (in parallel with rayon; each body's result
//!    does not depend on the thread count, so runs are deterministic).
//! 4. If the top pair is due, it is checked: closer than ε_c and approaching means a collision,
//!    resolved by `impulse-response` (a microcollision at low approach speed, §3.5); the pair
//!    and, after an impulse, every heap pair of the two bodies get new time-of-impact bounds;
//!    the pair leaves the heap only here, at the top, when it is no longer close (hysteresis).
//!
//! **Time-of-impact targets.** A pair farther apart than ε_c is scheduled for the time it
//! could first come within ε_c/2 ([`TOI_TARGET_FRACTION`]), so checks happen at a positive gap
//! and bodies never interpenetrate. A pair already within ε_c but not approaching is scheduled
//! for when it could have closed half its gap. Right after a pair is checked at the top of the
//! heap, a pair that may be approaching gets a gap of at least [`GAP_FLOOR_FRACTION`]·ε_c, so
//! the run cannot stall on a pair that touches (the price: a penetration of about that much,
//! which the counters measure); a pair surely separating from contact is due when it could be
//! back at contact, so a penetration heals instead of growing bounce by bounce; everywhere
//! else the bound stays conservative.
//!
//! **Rotation in the bounds.** The rotational term of a piece pair's bound uses each piece's
//! rotational reach ([`Body::reach`]): a ball's distance to anything moves only with its
//! centre, so a ball about its centre of mass contributes no rotational term, and its bound
//! is exact (thesis eq. 2.3 charges it r_max·ω_max, which made a rolling ball's checks
//! thousands of times more frequent than its bounces).

use glam::DVec3;
use impulse_broadphase::{BroadphaseError, CoherentHash, DEFAULT_ALPHA, DEFAULT_BETA, Levels};
use impulse_collide::{Closest, CollisionHeap, FeaturePair, Motion, PairCache, shape, toi};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

use crate::body::{Body, Integrator};
use crate::build;
use crate::contact::{self, ContactKind, ContactModel, Material};
use crate::error::SimError;
use crate::scene::Scene;

/// Pairs farther apart than ε_c are scheduled for the time they could come within this
/// fraction of ε_c (thesis §2.2: a collision is declared below ε_c; aiming below it makes the
/// one-sided iteration of §2.3 end in finitely many checks). Default `0.5`.
pub const TOI_TARGET_FRACTION: f64 = 0.5;

/// Smallest gap, as a fraction of ε_c, a time-of-impact bound is computed for (see the module
/// documentation). Default `0.01`.
pub const GAP_FLOOR_FRACTION: f64 = 0.01;

/// Checks in a row that may happen without simulated time advancing before the run is declared
/// stalled (a pair that keeps colliding at the same instant). Default `100_000`.
pub const MAX_CHECKS_WITHOUT_PROGRESS: u64 = 100_000;

/// Swept boxes of moving bodies are sized for steps up to this many of their own radii of
/// travel when the tile sizes are chosen (thesis §2.4.3: "tile sizes based on the bodies'
/// maximum radii"). Default `4.0`.
pub const SWEEP_ALLOWANCE: f64 = 4.0;

/// Below this many bodies, a world on rayon's global pool advances its bodies on the calling
/// thread (spawning costs more than the work). Default `64`.
pub const PARALLEL_MIN_BODIES: usize = 64;

/// Event counters of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Counters {
    /// Steps of the event loop (integrations of every body to the next event).
    pub steps: u64,
    /// Pair checks (closest-feature queries followed by a time-of-impact bound).
    pub pair_checks: u64,
    /// Ordinary collisions resolved.
    pub collisions: u64,
    /// Microcollisions (resting contact, thesis §3.5) resolved.
    pub microcollisions: u64,
    /// Microcollisions resolved by the reversing impulse.
    pub reversing: u64,
    /// Pairs that entered the collision heap from the broad phase.
    pub pairs_promoted: u64,
    /// Heap operations (inserts, removals, key changes).
    pub heap_operations: u64,
    /// Checks that found the bodies touching or penetrating (distance 0).
    pub touching_checks: u64,
    /// Smallest distance seen at any check (length; 0 when touching or penetrating).
    pub min_distance: f64,
    /// Largest penetration depth measured at a check that found the bodies touching or
    /// overlapping (length; an upper bound for sphere–polyhedron pieces). The promise is that
    /// it never exceeds ε_c.
    pub max_penetration: f64,
}

/// One resolved contact, as recorded by the event log ([`World::set_event_log`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactEvent {
    /// Simulated time.
    pub time: f64,
    /// The two bodies (indices into [`World::bodies`]); the impulse acts on `a`, −impulse on `b`.
    pub a: usize,
    /// Second body.
    pub b: usize,
    /// What kind of contact it was.
    pub kind: ContactKind,
    /// The impulse on body `a` (world).
    pub impulse: DVec3,
    /// The contact point (world).
    pub point: DVec3,
    /// Kinetic energy of the two bodies before the impulse.
    pub energy_before: f64,
    /// Kinetic energy of the two bodies after the impulse.
    pub energy_after: f64,
    /// Linear momentum of the two bodies before the impulse.
    pub momentum_before: DVec3,
    /// Linear momentum of the two bodies after the impulse.
    pub momentum_after: DVec3,
}

/// Per-pair state kept between checks.
#[derive(Clone, Debug, Default)]
struct PairState {
    /// Cached closest features of every piece pair (coherence), `[i * pieces_b + j]`.
    features: Vec<FeaturePair>,
    /// Last contact normal seen per piece pair (world, from the second body toward the first).
    normals: Vec<Option<DVec3>>,
}

/// The result of checking a pair: the closest piece pair, and the distance and normal of
/// every piece pair examined (for the time-of-impact bound, eq. 2.1).
struct Scan {
    /// Smallest distance (0 when touching or penetrating).
    distance: f64,
    /// Closest point on the first body (world).
    point_a: DVec3,
    /// Closest point on the second body (world).
    point_b: DVec3,
    /// Contact normal of the closest piece pair, from the second body toward the first.
    normal: Option<DVec3>,
    /// Smallest key of the piece pairs other than the closest one (absolute time).
    others_key: f64,
    /// The closest piece pair (piece indices of the two bodies).
    pieces: (usize, usize),
    /// How deep the bodies interpenetrate when touching (an upper bound; 0 otherwise).
    depth: f64,
    /// The two bodies' motions at the check (for their time-of-impact bound).
    motions: (Motion, Motion),
}

/// A simulated world.
pub struct World {
    bodies: Vec<Body>,
    gravity: DVec3,
    eps_c: f64,
    integrator: Integrator,
    model: ContactModel,
    /// Material pair table, indexed `[a * n + b]`.
    materials: Vec<Material>,
    material_count: usize,
    time: f64,
    heap: CollisionHeap,
    hash: CoherentHash,
    pairs: FxHashMap<(u32, u32), PairState>,
    counters: Counters,
    stalled_checks: u64,
    pool: Option<rayon::ThreadPool>,
    events: Option<Vec<ContactEvent>>,
}

/// The state of one body at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyState {
    /// Centre of mass (world).
    pub position: DVec3,
    /// Orientation of the body frame (principal frame for dynamic bodies).
    pub rotation: glam::DQuat,
    /// Centre-of-mass velocity (world).
    pub velocity: DVec3,
    /// Angular velocity (world).
    pub omega: DVec3,
}

impl World {
    /// Builds a world from a scene: validates it, builds every body, refuses overlapping
    /// bodies, and schedules the first checks.
    ///
    /// # Errors
    /// [`SimError::Invalid`], [`SimError::Geometry`] or [`SimError::InitialOverlap`], naming the
    /// body and what is wrong.
    pub fn from_scene(scene: &Scene) -> Result<Self, SimError> {
        let desc = &scene.desc;
        desc.validate()?;
        // Materials: "default" first, then in order of first use.
        let mut names: Vec<String> = vec!["default".into()];
        for b in &desc.bodies {
            if !names.contains(&b.material) {
                names.push(b.material.clone());
            }
        }
        let n = names.len();
        let default = Material {
            friction: desc.default_contact.friction,
            restitution: desc.default_contact.restitution,
        };
        let mut materials = vec![default; n * n];
        for c in &desc.contacts {
            let a = names.iter().position(|m| *m == c.a).unwrap_or(0);
            let b = names.iter().position(|m| *m == c.b).unwrap_or(0);
            let m = Material {
                friction: c.friction,
                restitution: c.restitution,
            };
            materials[a * n + b] = m;
            materials[b * n + a] = m;
        }
        let bodies = desc
            .bodies
            .iter()
            .map(|b| {
                let m = names.iter().position(|x| *x == b.material).unwrap_or(0);
                build::body(b, m, &scene.base_dir)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let gravity = DVec3::from_array(desc.gravity);
        let model = ContactModel {
            collision_tolerance: desc.accuracy.collision_tolerance,
            ..ContactModel::default()
        };
        let integrator = Integrator {
            rotation_tolerance: desc.accuracy.rotation_tolerance,
        };
        Self::new(
            bodies,
            gravity,
            desc.collision_epsilon,
            integrator,
            model,
            materials,
            n,
        )
    }

    /// A world from bodies already built.
    fn new(
        bodies: Vec<Body>,
        gravity: DVec3,
        eps_c: f64,
        integrator: Integrator,
        model: ContactModel,
        materials: Vec<Material>,
        material_count: usize,
    ) -> Result<Self, SimError> {
        let sizes: Vec<f64> = bodies
            .iter()
            .map(|b| {
                if b.is_dynamic() {
                    2.0 * b.r_max
                } else {
                    impulse_broadphase::box_size(&b.shape.aabb(&b.pose))
                }
            })
            .collect();
        let lo = sizes
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
            .max(eps_c);
        let hi = sizes.iter().copied().fold(0.0, f64::max) * SWEEP_ALLOWANCE;
        let levels =
            Levels::from_size_range(lo, hi.max(lo), DEFAULT_ALPHA, DEFAULT_BETA).map_err(|e| {
                SimError::Runtime {
                    time: 0.0,
                    message: format!("broad phase: {e}"),
                }
            })?;
        let mut world = Self {
            bodies,
            gravity,
            eps_c,
            integrator,
            model,
            materials,
            material_count,
            time: 0.0,
            heap: CollisionHeap::new(),
            hash: CoherentHash::new(levels),
            pairs: FxHashMap::default(),
            counters: Counters {
                min_distance: f64::INFINITY,
                ..Counters::default()
            },
            stalled_checks: 0,
            pool: None,
            events: None,
        };
        world.check_initial_overlaps()?;
        for i in 0..world.bodies.len() {
            let b = world.static_box(i);
            world
                .hash
                .insert(i as u32, b)
                .map_err(|e| world.runtime(format!("broad phase, body {}: {e}", world.name(i))))?;
        }
        world.promote_new_pairs()?;
        Ok(world)
    }

    /// Runs the per-body work on a pool of `threads` threads (the default is rayon's global
    /// pool). Results do not depend on the thread count.
    ///
    /// # Errors
    /// [`SimError::Runtime`] if the pool cannot be built.
    pub fn set_threads(&mut self, threads: usize) -> Result<(), SimError> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| self.runtime(format!("thread pool: {e}")))?;
        self.pool = Some(pool);
        Ok(())
    }

    /// Starts (or stops) recording every resolved contact in an event log.
    pub fn set_event_log(&mut self, on: bool) {
        self.events = if on { Some(Vec::new()) } else { None };
    }

    /// The event log (empty unless [`World::set_event_log`] turned it on).
    #[must_use]
    pub fn events(&self) -> &[ContactEvent] {
        self.events.as_deref().unwrap_or(&[])
    }

    /// Current simulated time.
    #[must_use]
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The bodies.
    #[must_use]
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// Gravity (world).
    #[must_use]
    pub fn gravity(&self) -> DVec3 {
        self.gravity
    }

    /// The collision epsilon ε_c.
    #[must_use]
    pub fn collision_epsilon(&self) -> f64 {
        self.eps_c
    }

    /// Event counters so far.
    #[must_use]
    pub fn counters(&self) -> Counters {
        let mut c = self.counters;
        let h = self.heap.stats();
        c.heap_operations = h.inserts + h.removals + h.key_changes;
        c
    }

    /// The state of every body.
    #[must_use]
    pub fn states(&self) -> Vec<BodyState> {
        self.bodies
            .iter()
            .map(|b| BodyState {
                position: b.pose.translation,
                rotation: b.pose.rotation,
                velocity: b.velocity,
                omega: b.omega,
            })
            .collect()
    }

    /// Total kinetic energy of the dynamic bodies.
    #[must_use]
    pub fn kinetic_energy(&self) -> f64 {
        self.bodies.iter().map(Body::kinetic_energy).sum()
    }

    /// Total potential energy of the dynamic bodies in gravity (zero at the world origin).
    #[must_use]
    pub fn potential_energy(&self) -> f64 {
        self.bodies
            .iter()
            .map(|b| b.potential_energy(self.gravity))
            .sum()
    }

    /// Index of the body called `name`.
    #[must_use]
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.name == name)
    }

    fn name(&self, i: usize) -> &str {
        &self.bodies[i].name
    }

    fn runtime(&self, message: String) -> SimError {
        SimError::Runtime {
            time: self.time,
            message,
        }
    }

    /// Advances the world to time `t` (no-op if `t` is not later than now).
    ///
    /// # Errors
    /// [`SimError::Runtime`] when the run cannot continue (a body's state is no longer finite,
    /// the loop stalls, a contact cannot be resolved), naming the bodies.
    pub fn step_until(&mut self, t: f64) -> Result<(), SimError> {
        if !t.is_finite() {
            return Err(self.runtime(format!("step_until({t}): time is not finite")));
        }
        while self.time < t {
            self.step(t)?;
        }
        Ok(())
    }

    /// Tight box of a fixed body, swept box of a moving one over `dt` from now; grown by ε_c so
    /// pairs within ε_c are close.
    fn swept_box(&self, i: usize, dt: f64) -> impulse_geom::Aabb {
        let b = &self.bodies[i];
        if b.kind == crate::body::BodyKind::Fixed {
            return self.static_box(i);
        }
        b.motion(self.gravity)
            .swept_com_aabb(dt)
            .expanded(b.r_max + self.eps_c)
    }

    fn static_box(&self, i: usize) -> impulse_geom::Aabb {
        let b = &self.bodies[i];
        if b.kind == crate::body::BodyKind::Fixed {
            b.shape.aabb(&b.pose).expanded(self.eps_c)
        } else {
            self.swept_box(i, 0.0)
        }
    }

    /// One step of the `advance` algorithm (module documentation), ending no later than
    /// `limit`.
    fn step(&mut self, limit: f64) -> Result<(), SimError> {
        let t0 = self.time;
        let mut t_end = self.heap.peek().map_or(limit, |(_, k)| k.min(limit));
        // 2. Swept boxes; halve the step while a box would cover too many tiles.
        'boxes: loop {
            for i in 0..self.bodies.len() {
                if self.bodies[i].kind == crate::body::BodyKind::Fixed {
                    continue;
                }
                let b = self.swept_box(i, t_end - t0);
                match self.hash.update(i as u32, b) {
                    Ok(()) => {}
                    Err(BroadphaseError::TooManyCells { .. }) if t_end - t0 > 0.0 => {
                        t_end = t0 + 0.5 * (t_end - t0);
                        continue 'boxes;
                    }
                    Err(e) => {
                        return Err(
                            self.runtime(format!("broad phase, body {}: {e}", self.name(i)))
                        );
                    }
                }
            }
            break;
        }
        self.promote_new_pairs()?;
        if let Some((_, k)) = self.heap.peek() {
            t_end = t_end.min(k);
        }
        t_end = t_end.max(t0);
        // 3. Dynamic evolution.
        let dt = t_end - t0;
        if dt > 0.0 {
            self.advance_bodies(dt)?;
            self.stalled_checks = 0;
        }
        self.time = t_end;
        self.counters.steps += 1;
        // 4. Check the top pair if it is due.
        if let Some((pair, key)) = self.heap.peek() {
            if key <= self.time {
                self.stalled_checks += 1;
                if self.stalled_checks > MAX_CHECKS_WITHOUT_PROGRESS {
                    return Err(self.runtime(format!(
                        "the run stalled: {MAX_CHECKS_WITHOUT_PROGRESS} checks without time advancing (last pair {} / {})",
                        self.name(pair.0 as usize),
                        self.name(pair.1 as usize)
                    )));
                }
                self.check_top(pair)?;
            }
        }
        Ok(())
    }

    fn advance_bodies(&mut self, dt: f64) -> Result<(), SimError> {
        let (g, integ) = (self.gravity, self.integrator);
        // With a pool set by `set_threads`, always go parallel (the determinism check needs
        // the parallel path); on the global pool, only when there is enough work.
        let serial = self.pool.is_none() && self.bodies.len() < PARALLEL_MIN_BODIES;
        let run = |bodies: &mut [Body]| -> Vec<Option<String>> {
            if serial {
                bodies
                    .iter_mut()
                    .map(|b| b.advance(dt, g, &integ).err().map(|e| e.to_string()))
                    .collect()
            } else {
                bodies
                    .par_iter_mut()
                    .map(|b| b.advance(dt, g, &integ).err().map(|e| e.to_string()))
                    .collect()
            }
        };
        let errors = match &self.pool {
            Some(pool) => pool.install(|| run(&mut self.bodies)),
            None => run(&mut self.bodies),
        };
        if let Some((i, e)) = errors
            .into_iter()
            .enumerate()
            .find_map(|(i, e)| e.map(|e| (i, e)))
        {
            return Err(self.runtime(format!("body {}: {e}", self.name(i))));
        }
        Ok(())
    }

    /// Whether the pair can ever need a collision (at least one body is dynamic).
    fn pair_matters(&self, a: u32, b: u32) -> bool {
        self.bodies[a as usize].is_dynamic() || self.bodies[b as usize].is_dynamic()
    }

    /// Inserts every pair that became close (thesis §2.4.3, 0→1) into the heap.
    fn promote_new_pairs(&mut self) -> Result<(), SimError> {
        for (a, b) in self.hash.take_new_close_pairs() {
            if !self.pair_matters(a, b) || self.heap.contains((a, b)) {
                continue;
            }
            let key = self.bound((a, b));
            self.heap
                .insert((a, b), key)
                .map_err(|e| self.runtime(format!("collision heap: {e}")))?;
            self.counters.pairs_promoted += 1;
        }
        Ok(())
    }

    /// Checks a pair now, piece pair by piece pair (thesis eq. 2.1): the closest piece pair
    /// decides contact, and every piece pair gets its own time-of-impact bound along its own
    /// separating direction, since a non-convex body can approach another at several places in
    /// different directions. Piece pairs whose bounding spheres cannot come within reach
    /// before the smallest bound so far are skipped (for fixed and ballistic bodies, whose
    /// speed has a direction-free bound).
    fn query(&mut self, (a, b): (u32, u32)) -> Scan {
        let (ba, bb) = (&self.bodies[a as usize], &self.bodies[b as usize]);
        let (pieces_a, pieces_b) = (ba.shape.pieces(), bb.shape.pieces());
        let (na, nb) = (pieces_a.len(), pieces_b.len());
        let (motion_a, motion_b) = (ba.motion(self.gravity), bb.motion(self.gravity));
        let free = free_bound(ba, &motion_a).zip(free_bound(bb, &motion_b));
        let state = self.pairs.entry((a, b)).or_default();
        if state.features.len() != na * nb {
            state.features = vec![FeaturePair::default(); na * nb];
            state.normals = vec![None; na * nb];
        }
        // Piece pairs by increasing bounding-sphere lower bound on their distance.
        let mut order: Vec<(f64, usize, usize)> = Vec::with_capacity(na * nb);
        for (i, pa) in pieces_a.iter().enumerate() {
            let ca = ba.pose.transform_point(pa.center);
            for (j, pb) in pieces_b.iter().enumerate() {
                let lb = ca.distance(bb.pose.transform_point(pb.center)) - pa.radius - pb.radius;
                order.push((lb, i, j));
            }
        }
        order.sort_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
        let mut best: Option<(f64, Closest, usize)> = None;
        let mut keys: Vec<(usize, f64)> = Vec::with_capacity(order.len());
        let mut min_key = f64::INFINITY;
        let mut checks = 0u64;
        for &(lb, i, j) in &order {
            if let Some(((a1, b1), (a2, b2))) = free {
                let gap = target_gap(lb, self.eps_c);
                let reach = best.as_ref().is_none_or(|bst| lb < bst.0);
                if gap > 0.0
                    && !reach
                    && self.time + toi::pair_toi(gap, (a1, b1), (a2, b2)) >= min_key
                {
                    continue;
                }
            }
            let (pa, pb) = (&pieces_a[i], &pieces_b[j]);
            let slot = i * nb + j;
            let c = shape::convex_closest(
                &pa.convex,
                &(ba.pose * pa.pose),
                &pb.convex,
                &(bb.pose * pb.pose),
                state.features[slot],
            );
            checks += 1;
            state.features[slot] = c.features;
            if let Some(dir) = c.direction() {
                state.normals[slot] = Some(-dir);
            }
            let d = if c.penetrating { 0.0 } else { c.distance };
            let key = match state.normals[slot] {
                None => self.time,
                Some(n) => {
                    self.time
                        + piece_toi(
                            d,
                            0.0,
                            n,
                            self.eps_c,
                            false,
                            &motion_a,
                            ba.reach[i],
                            &motion_b,
                            bb.reach[j],
                        )
                }
            };
            min_key = min_key.min(key);
            keys.push((slot, key));
            if best.as_ref().is_none_or(|bst| d < bst.0) {
                best = Some((d, c, slot));
            }
        }
        self.counters.pair_checks += checks.max(1);
        let Some((d, c, slot)) = best else {
            unreachable!("a shape has at least one piece")
        };
        let others_key = keys
            .iter()
            .filter(|(s, _)| *s != slot)
            .map(|(_, k)| *k)
            .fold(f64::INFINITY, f64::min);
        let normal = state.normals[slot];
        let mut depth = 0.0;
        if d <= 0.0 {
            self.counters.touching_checks += 1;
            depth = penetration_depth(ba, bb);
            self.counters.max_penetration = self.counters.max_penetration.max(depth);
        }
        self.counters.min_distance = self.counters.min_distance.min(d);
        Scan {
            distance: d,
            point_a: c.point_a,
            point_b: c.point_b,
            normal,
            others_key,
            pieces: (slot / nb, slot % nb),
            depth,
            motions: (motion_a, motion_b),
        }
    }

    /// A check plus a conservative time-of-impact bound (absolute time); no response. Used
    /// for pairs that are not at the top of the heap (new pairs, re-keyed pairs).
    fn bound(&mut self, pair: (u32, u32)) -> f64 {
        let scan = self.query(pair);
        self.key_for(pair, &scan, false)
    }

    /// The key of a pair: the earliest time any of its piece pairs could close the gap to the
    /// target (module documentation). Only the closest piece pair of a pair just checked at
    /// the top of the heap (`at_top`) gets the gap floor, which guarantees progress;
    /// elsewhere the bound stays conservative, so a pair re-keyed while touching comes back
    /// to the top at once.
    fn key_for(&self, (a, b): (u32, u32), scan: &Scan, at_top: bool) -> f64 {
        let Some(n) = scan.normal else {
            return self.time; // touching with no known normal: check again now.
        };
        let (ba, bb) = (&self.bodies[a as usize], &self.bodies[b as usize]);
        let tau = piece_toi(
            scan.distance,
            scan.depth,
            n,
            self.eps_c,
            at_top,
            &scan.motions.0,
            ba.reach[scan.pieces.0],
            &scan.motions.1,
            bb.reach[scan.pieces.1],
        );
        (self.time + tau).min(scan.others_key)
    }

    /// Checks the top pair, resolves a collision, re-keys, and applies the hysteresis rule.
    fn check_top(&mut self, pair: (u32, u32)) -> Result<(), SimError> {
        let scan = self.query(pair);
        let (d, pa, pb, normal) = (scan.distance, scan.point_a, scan.point_b, scan.normal);
        let mut hit = false;
        if d < self.eps_c {
            let Some(n) = normal else {
                return Err(self.runtime(format!(
                    "bodies {} and {} touch with no known contact normal",
                    self.name(pair.0 as usize),
                    self.name(pair.1 as usize)
                )));
            };
            let x = 0.5 * (pa + pb);
            let (i, j) = (pair.0 as usize, pair.1 as usize);
            let mat = self.material(i, j);
            let (bi, bj) = two_mut(&mut self.bodies, i, j);
            let before = (
                bi.kinetic_energy() + bj.kinetic_energy(),
                bi.linear_momentum() + bj.linear_momentum(),
            );
            let outcome = contact::resolve(
                bi,
                bj,
                x,
                n,
                d,
                self.eps_c,
                self.gravity.length(),
                mat,
                &self.model,
            )
            .map_err(|e| SimError::Runtime {
                time: self.time,
                message: format!(
                    "collision of {} and {}: {e}",
                    self.bodies[i].name, self.bodies[j].name
                ),
            })?;
            if let Some((kind, impulse)) = outcome {
                hit = true;
                if let Some(log) = &mut self.events {
                    let (bi, bj) = (&self.bodies[i], &self.bodies[j]);
                    log.push(ContactEvent {
                        time: self.time,
                        a: i,
                        b: j,
                        kind,
                        impulse,
                        point: x,
                        energy_before: before.0,
                        energy_after: bi.kinetic_energy() + bj.kinetic_energy(),
                        momentum_before: before.1,
                        momentum_after: bi.linear_momentum() + bj.linear_momentum(),
                    });
                }
                match kind {
                    ContactKind::Collision => self.counters.collisions += 1,
                    ContactKind::Microcollision => self.counters.microcollisions += 1,
                    ContactKind::Reversing => {
                        self.counters.microcollisions += 1;
                        self.counters.reversing += 1;
                    }
                }
            }
        }
        if hit {
            // Every other heap pair of the two bodies is stale (thesis §2.4.3) — of the bodies
            // whose motion the impulse changed: a fixed or scripted body's pairs stay valid.
            let moved = |b: u32| self.bodies[b as usize].is_dynamic();
            let mut others: Vec<(u32, u32)> = [pair.0, pair.1]
                .into_iter()
                .filter(|&b| moved(b))
                .flat_map(|b| self.heap.pairs_of(b))
                .filter(|p| *p != pair)
                .collect();
            others.sort_unstable();
            others.dedup();
            for p in others {
                let key = self.bound(p);
                self.heap
                    .set_toi(p, key)
                    .map_err(|e| self.runtime(format!("collision heap: {e}")))?;
            }
        }
        let key = if hit {
            let scan = self.query(pair);
            self.key_for(pair, &scan, true)
        } else {
            self.key_for(pair, &scan, true)
        };
        let still_close = self.hash.is_close(pair.0, pair.1).unwrap_or(false);
        self.heap
            .settle_after_check(pair, still_close, key)
            .map_err(|e| self.runtime(format!("collision heap: {e}")))?;
        if !still_close {
            self.pairs.remove(&pair);
        }
        Ok(())
    }

    fn material(&self, i: usize, j: usize) -> Material {
        let (a, b) = (self.bodies[i].material, self.bodies[j].material);
        self.materials[a * self.material_count + b]
    }

    /// Refuses bodies that overlap at the start (closer than zero: penetrating).
    fn check_initial_overlaps(&mut self) -> Result<(), SimError> {
        let n = self.bodies.len();
        let boxes: Vec<_> = (0..n)
            .map(|i| {
                let b = &self.bodies[i];
                b.shape.aabb(&b.pose)
            })
            .collect();
        for i in 0..n {
            for j in i + 1..n {
                if !self.pair_matters(i as u32, j as u32) || !boxes[i].overlaps(&boxes[j]) {
                    continue;
                }
                let (bi, bj) = (&self.bodies[i], &self.bodies[j]);
                let c = shape::closest(
                    &bi.shape,
                    &bi.pose,
                    &bj.shape,
                    &bj.pose,
                    &mut PairCache::default(),
                );
                if c.closest.penetrating {
                    return Err(SimError::InitialOverlap {
                        a: bi.name.clone(),
                        b: bj.name.clone(),
                        problem: "overlap".into(),
                    });
                }
            }
        }
        Ok(())
    }
}

/// The gap a time-of-impact bound aims to close for a piece pair at distance `d`: down to
/// [`TOI_TARGET_FRACTION`]·ε_c when farther than ε_c, else half the distance.
fn target_gap(d: f64, eps_c: f64) -> f64 {
    if d > eps_c {
        d - TOI_TARGET_FRACTION * eps_c
    } else {
        0.5 * d
    }
}

/// Time (s from now) before which a piece pair at distance `d` with contact normal `n` (from
/// the second body toward the first) cannot close its target gap. With `at_top`, a pair that
/// may be approaching gets a gap of at least [`GAP_FLOOR_FRACTION`]·ε_c (progress); a pair
/// that is surely separating (its closing-speed bound is negative) keeps its own target, and
/// from contact — interpenetrating by `depth` — it is due when it could be back at contact
/// (or, if it cannot rise that far, back where it is). The floor alone would let each bounce
/// of a body whose bound is exact (a ball, which rotation cannot move) end deeper, and a
/// penetration, once made, would never heal.
#[allow(clippy::too_many_arguments)]
fn piece_toi(
    d: f64,
    depth: f64,
    n: DVec3,
    eps_c: f64,
    at_top: bool,
    motion_a: &Motion,
    r_a: f64,
    motion_b: &Motion,
    r_b: f64,
) -> f64 {
    // d̂ points from body a toward body b: the opposite of the normal.
    let d_hat = -n;
    let gap = target_gap(d, eps_c);
    if at_top {
        let floor = GAP_FLOOR_FRACTION * eps_c;
        let floored = gap.max(floor);
        let c1 = motion_a.toi_coefficients(d_hat, r_a, floored);
        let c2 = motion_b.toi_coefficients(-d_hat, r_b, floored);
        let (a, b) = (c1.0 + c2.0, c1.1 + c2.1);
        // Surely separating, by more than half the floor before turning back (the bound's
        // apex b²/4a; a body reversed after falling through the floor rises to the floor), or
        // never turning back.
        let separating = b < 0.0 && (a <= 0.0 || b * b > 2.0 * a * floor);
        if !separating {
            // Possibly approaching, or barely leaving: the floor guarantees progress (the
            // coefficients above are this gap's: `toi::toi_lower_bound` without recomputing).
            return toi::pair_toi(floored, c1, c2);
        } else if gap <= 0.0 {
            if a <= 0.0 {
                return f64::INFINITY;
            }
            // Leaving contact: a·τ² + b·τ = −depth at the bound's return to contact (the
            // later root), else its return to the current depth, τ = −b/a (at least
            // √(2·floor/a) by the apex condition).
            let disc = b * b - 4.0 * a * depth.max(0.0);
            return if disc > 0.0 {
                (-b + disc.sqrt()) / (2.0 * a)
            } else {
                -b / a
            };
        }
    }
    toi::toi_lower_bound(gap, d_hat, motion_a, r_a, motion_b, r_b)
}

/// Direction-free TOI coefficients `(A, B)` of a body: along any unit direction, none of its
/// pieces closes a distance by more than `A·τ² + B·τ` in time τ. Fixed: `(0, 0)`; ballistic:
/// `(½|g|, |v| + reach·ω_max)` (eqs. 2.2, 2.3 with |d̂| = 1, reach ≤ r_max the largest
/// rotational reach of its pieces); scripted bodies: `None` (no pruning).
fn free_bound(body: &Body, motion: &Motion) -> Option<(f64, f64)> {
    match motion {
        Motion::Fixed { .. } => Some((0.0, 0.0)),
        Motion::Ballistic(m) => Some((
            0.5 * m.gravity().length(),
            m.velocity().length() + body.max_reach() * m.omega_max(),
        )),
        _ => None,
    }
}

/// How deep two bodies that touch or overlap interpenetrate: the largest over their piece
/// pairs of the separating-axis depth (polyhedra, exact), `r1 + r2 − |c1 − c2|` (spheres,
/// exact), or `r − (largest face-plane distance of the centre)` (sphere and polyhedron, an
/// upper bound). Zero when no piece pair overlaps.
fn penetration_depth(a: &Body, b: &Body) -> f64 {
    use impulse_collide::Convex;
    let mut depth = 0.0f64;
    for pa in a.shape.pieces() {
        let pose_a = a.pose * pa.pose;
        for pb in b.shape.pieces() {
            let pose_b = b.pose * pb.pose;
            let d = match (&pa.convex, &pb.convex) {
                (Convex::Polyhedron(x), Convex::Polyhedron(y)) => {
                    -impulse_collide::brute::sat_separation(x, &pose_a, y, &pose_b)
                }
                (Convex::Sphere(x), Convex::Sphere(y)) => {
                    x.radius() + y.radius() - pose_a.translation.distance(pose_b.translation)
                }
                (Convex::Sphere(x), Convex::Polyhedron(y)) => {
                    sphere_depth(x.radius(), pose_a.translation, y, &pose_b)
                }
                (Convex::Polyhedron(y), Convex::Sphere(x)) => {
                    sphere_depth(x.radius(), pose_b.translation, y, &pose_a)
                }
                (Convex::Ellipsoid(_), _) | (_, Convex::Ellipsoid(_)) => {
                    support_depth(&pa.convex, &pose_a, &pb.convex, &pose_b)
                }
            };
            depth = depth.max(d);
        }
    }
    depth
}

/// An upper bound on the penetration depth of two convex pieces: the smallest overlap of
/// their projections, h_A(u) + h_B(−u), over the candidate axes u (the face normals of
/// polyhedral pieces and the line of centres). Exact when the deepest axis is a face normal,
/// as for a smooth body resting on a flat face.
pub(crate) fn support_depth(
    a: &impulse_collide::Convex,
    pose_a: &impulse_geom::Pose,
    b: &impulse_collide::Convex,
    pose_b: &impulse_geom::Pose,
) -> f64 {
    use impulse_collide::Convex;
    let (sa, sb) = (a.placed(pose_a), b.placed(pose_b));
    let mut axes: Vec<DVec3> = Vec::new();
    for (c, pose) in [(a, pose_a), (b, pose_b)] {
        if let Convex::Polyhedron(p) = c {
            axes.extend(p.planes().iter().map(|pl| pose.rotation * pl.normal));
        }
    }
    if let Some(u) = (pose_b.translation - pose_a.translation).try_normalize() {
        axes.push(u);
    }
    let overlap = |u: DVec3| sa.support_point(u).dot(u) - sb.support_point(-u).dot(u);
    axes.into_iter()
        .flat_map(|u| [u, -u])
        .map(overlap)
        .fold(f64::INFINITY, f64::min)
        .max(0.0)
}

fn sphere_depth(
    r: f64,
    centre: DVec3,
    poly: &impulse_geom::ConvexPolyhedron,
    pose: &impulse_geom::Pose,
) -> f64 {
    let c = pose.inverse_transform_point(centre);
    let outside = poly
        .planes()
        .iter()
        .map(|p| p.signed_distance(c))
        .fold(f64::NEG_INFINITY, f64::max);
    r - outside
}

/// Two distinct elements of a slice, mutably.
fn two_mut<T>(v: &mut [T], i: usize, j: usize) -> (&mut T, &mut T) {
    assert_ne!(i, j, "a pair is two different bodies");
    if i < j {
        let (lo, hi) = v.split_at_mut(j);
        (&mut lo[i], &mut hi[0])
    } else {
        let (lo, hi) = v.split_at_mut(i);
        (&mut hi[0], &mut lo[j])
    }
}
