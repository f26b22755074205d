//! The world: its bodies, and the event loop that moves them (thesis §1.2, §2.3.1, §2.4.3).
//!
//! A [`World`] is built from a scene ([`World::from_scene`]) or in code ([`World::new`], then
//! [`World::add_body`]); bodies are named by [`BodyHandle`]s that stay valid while other bodies
//! come and go. Between steps a program may move bodies, change their velocities, push them
//! with impulses and loads, and read what happened (see the methods' groups below and
//! `api.rs`).
//!
//! One step of the event loop ([`World::step_until`], `step.rs`) is the `advance` algorithm
//! of thesis §2.4.3:
//!
//! 1. `t_end` ← the earliest key of the collision heap (capped by the caller's time limit and
//!    the next evaluation of a load function).
//! 2. Every moving body whose box in the broad phase does not cover `[t, t_end]` gets the box
//!    enclosing its swept volume over a horizon (its motion's swept centre-of-mass box grown
//!    by r_max + ε_c; `sync.rs`); the coherent spatial hash updates its close counters, and
//!    every pair that became close (0→1) is checked and inserted in the heap. A new pair may
//!    have an earlier key: `t_end` shrinks (the boxes still cover it).
//! 3. The clock moves to `t_end`. A body moves when something reads or changes it: a check of
//!    one of its pairs, an island step, a load; every body is brought to the end of each
//!    [`World::step_until`] call, in parallel with rayon (`sync.rs`: each body's result does not
//!    depend on the thread count, so runs are deterministic).
//! 4. If the top pair is due, it is checked (`check.rs`): closer than ε_c and approaching means
//!    a collision, resolved by `impulse-response` (a microcollision at low approach speed,
//!    §3.5); the pair and, after an impulse, every heap pair of the two bodies get new
//!    time-of-impact bounds; the pair leaves the heap only here, at the top, when it is no
//!    longer close (hysteresis).
//!
//! When to check a pair again is `impulse_collide::schedule`'s policy: a separated pair when
//! it could come within half of ε_c, a pair just checked at the top never sooner than a gap
//! floor allows, a pair leaving contact when it could be back. Rotation in the bounds uses
//! each piece's rotational reach ([`Body::reach`]): a ball's distance to anything moves only
//! with its centre, so its bound is exact.
//!
//! **Touching at the start is contact.** Bodies may be placed touching, or overlapping by up
//! to ε_c; only a deeper overlap is refused ([`SimError::Overlap`], with the depth).
//! Pairs at zero distance get their normal from `impulse_collide::depth`.
//!
//! **No run is lost to one pair.** A collision the response cannot resolve (its step cap, a
//! degenerate collision matrix, a non-finite result) is resolved by a frictionless Newton
//! impulse along the normal instead ([`ContactKind::Fallback`]), reported in the contact log,
//! the counters ([`Counters::unresolved`]) and [`World::failures`], and the run goes on.
//! [`World::step_until`] fails only for invalid input or a state that is no longer finite,
//! and then leaves the world exactly as it was.

mod api;
mod check;
mod control;
pub(crate) mod envelope;
mod held;
mod held_links;
mod hold;
mod hybrid;
mod hybrid_contact;
mod hybrid_step;
mod island;
mod materials;
mod patch;
mod profile;
mod quick_bounds;
mod steady;
mod step;
mod sync;

use std::path::PathBuf;
use std::sync::Arc;

use glam::DVec3;
use impulse_broadphase::CoherentHash;
use impulse_collide::schedule::Schedule;
use impulse_collide::{CollisionHeap, FeaturePair};
use rustc_hash::FxHashMap;

pub use api::{Load, LoadFn};
pub use control::{Control, ControllerHandle, WorldController, WorldControllerClone};
pub use hybrid::{LinkShape, MultibodyHandle, MultibodyOptions};
pub use hybrid_step::{
    BOX_STAGE_FRACTION, BOX_STAGE_MAX_FRACTION, MAX_STEP_REDOS, SLACK_ROUNDING_REL,
};
pub use materials::Material;
pub use profile::Profile;
pub use sync::BOX_HORIZON;

use crate::body::{Body, Integrator};
use crate::contact::{ContactKind, ContactModel};
use crate::error::SimError;
use crate::monitor::PenetrationMonitor;
use crate::scene::{Scene, SceneDesc};
use crate::sustained::{ContactMode, SustainedSettings};
use materials::Materials;

/// Checks in a row that may happen without simulated time advancing before the loop gives the
/// pair it keeps checking a separating push (a stall, see [`Counters::unresolved`]). A legal
/// cascade of simultaneous contacts (a stack settling) takes a few checks per pair. Default
/// `10_000`.
pub const MAX_CHECKS_WITHOUT_PROGRESS: u64 = 10_000;

/// Stalls broken at one instant before the run is declared stuck: an error, and the world is
/// left as it was before the step (a scene far outside what the loop can resolve, e.g.
/// gravity of 1e308). Default `3`.
pub const MAX_STALLS_PER_INSTANT: u64 = 3;

/// Swept boxes of moving bodies are sized for steps up to this many of their own radii of
/// travel when the tile sizes are chosen (thesis §2.4.3: "tile sizes based on the bodies'
/// maximum radii"). Default `4.0`.
pub const SWEEP_ALLOWANCE: f64 = 4.0;

/// Below this many moving bodies, a step advances its bodies on the calling thread: handing
/// a few bodies to a pool costs more than their work (on the dominos, `--threads 1` with
/// every step handed to its pool took 11 s of wall time against 2.4 s). The default of
/// [`World::set_parallel_min_bodies`]. Default `64`.
pub const PARALLEL_MIN_BODIES: usize = 64;

/// Most contact failures [`World::failures`] keeps (the counter counts them all). Default
/// `1000`.
pub const MAX_FAILURES_KEPT: usize = 1000;

/// A body of a world: stays valid while other bodies are added and removed, and names nothing
/// once its own body is removed (a new body never reuses it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BodyHandle {
    index: u32,
    generation: u32,
}

impl BodyHandle {
    /// A handle that names no body of any world (slot `u32::MAX`): a stand-in where a
    /// description is checked before its world exists.
    pub(crate) const PLACEHOLDER: Self = Self {
        index: u32::MAX,
        generation: u32::MAX,
    };

    /// The body's slot in the world (slots of removed bodies are reused, with a new
    /// generation).
    #[must_use]
    pub fn index(self) -> u32 {
        self.index
    }
}

impl std::fmt::Display for BodyHandle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "#{}.{}", self.index, self.generation)
    }
}

/// Event counters of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Counters {
    /// Steps of the event loop (integrations of every body to the next event).
    pub steps: u64,
    /// Pair checks (closest-feature queries followed by a time-of-impact bound).
    pub pair_checks: u64,
    /// Time-of-impact bounds of pairs re-keyed from their last query's distance less how far
    /// the two bodies have moved since, without a query (`check.rs`: `World::cached_bound`).
    pub cached_bounds: u64,
    /// Ordinary collisions resolved.
    pub collisions: u64,
    /// Microcollisions (resting contact, thesis §3.5) resolved.
    pub microcollisions: u64,
    /// Microcollisions resolved by the reversing impulse.
    pub reversing: u64,
    /// Contacts the response could not resolve, handled by the fallback impulse (see the
    /// module documentation), and stalls broken by a separating push.
    pub unresolved: u64,
    /// Pairs that entered the collision heap from the broad phase.
    pub pairs_promoted: u64,
    /// Heap operations (inserts, removals, key changes).
    pub heap_operations: u64,
    /// Evaluations of load functions.
    pub load_evaluations: u64,
    /// Checks that found the bodies touching or penetrating (distance 0).
    pub touching_checks: u64,
    /// Smallest distance seen at any check (length; 0 when touching or penetrating).
    pub min_distance: f64,
    /// Largest penetration depth the loop itself found at a check (length). A diagnostic of
    /// the loop; the guarantee is measured from outside by [`PenetrationMonitor`].
    pub max_penetration: f64,
    /// Island steps taken (the switching contact model, [`crate::sustained`]; one per awake
    /// island).
    pub island_steps: u64,
    /// Island steps taken eight nominal steps long (`REST_STEP_MULTIPLE`, `world/island.rs`): of islands at
    /// rest, or steady (`world/steady.rs`).
    pub long_steps: u64,
    /// Island steps shorter than [`SustainedSettings::step`] because a body of the island
    /// turns (`world/hold.rs`).
    pub turning_steps: u64,
    /// Island steps shortened after a strike changed their bodies' speeds.
    pub struck_steps: u64,
    /// Island steps cut within the step: a feature outside the manifold or a speculative
    /// point would have closed past the envelope over the step chosen at its start.
    pub fitted_steps: u64,
    /// Island steps cut to a located slip → stick transition.
    pub located_steps: u64,
    /// Slip → stick transitions taken at the step's end: rounding them moved their contact
    /// points by less than [`SustainedSettings::step_tolerance`]·ε_c.
    pub rounded_transitions: u64,
    /// Transients resolved by an impulsive solve of an island.
    pub transients: u64,
    /// Islands put to sleep.
    pub sleeps: u64,
    /// Contact solves of the islands: each island step's solve, its re-solves while it
    /// locates a slip → stick transition, and the impulsive solves of transients.
    pub island_solves: u64,
    /// Gauss–Seidel sweeps over all island solves.
    pub island_sweeps: u64,
    /// Island solves that stopped at the sweep cap ([`SustainedSettings::max_sweeps`]) short
    /// of the solver tolerance: their impulses are the last sweep's, not a solution. Many of
    /// them mark a scene the switching model runs slowly (`docs/sustained-contact.md`,
    /// Open).
    pub unconverged_solves: u64,
    /// Direct solves on the sweeps' active set that were accepted.
    pub direct_solves: u64,
    /// Patch jumps taken in island solves (`impulse_response::SolveReport::jumped`: each
    /// patch of three or more contacts between two bodies solved as one wrench, all
    /// sticking, and the sweeps continued from there).
    pub patch_jumps: u64,
    /// Steps of the multibodies undone and done again because a link's prediction failed
    /// (thesis §5.2: a box or slack violation).
    pub rollbacks: u64,
    /// Links found outside the swept box they were predicted to stay in.
    pub box_violations: u64,
    /// Links found to have travelled toward another body farther than their pair's bound
    /// allowed (the slack structure, thesis Fig. 5.4).
    pub slack_violations: u64,
    /// Steps taken although a prediction still failed after
    /// [`hybrid_step::MAX_STEP_REDOS`] redos (a collision may have been missed).
    pub unchecked_steps: u64,
    /// Collisions and microcollisions involving a multibody link (also counted in
    /// `collisions` or `microcollisions`).
    pub link_contacts: u64,
    /// Updates of high-level controllers ([`World::add_controller`]).
    pub controller_updates: u64,
}

/// One resolved contact ([`World::contacts`], [`World::set_event_log`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactEvent {
    /// Simulated time.
    pub time: f64,
    /// The first body; the impulse acts on `a`, −impulse on `b`.
    pub a: BodyHandle,
    /// The second body.
    pub b: BodyHandle,
    /// What kind of contact it was.
    pub kind: ContactKind,
    /// The impulse on body `a` (world).
    pub impulse: DVec3,
    /// The contact point (world).
    pub point: DVec3,
    /// The contact normal (world, unit, from `b` toward `a`).
    pub normal: DVec3,
    /// Kinetic energy of the two bodies before the impulse.
    pub energy_before: f64,
    /// Kinetic energy of the two bodies after the impulse.
    pub energy_after: f64,
    /// Linear momentum of the two bodies before the impulse.
    pub momentum_before: DVec3,
    /// Linear momentum of the two bodies after the impulse.
    pub momentum_after: DVec3,
    /// The normal relative velocity at the contact point before the impulse,
    /// (v_a(x) − v_b(x))·n: negative while the bodies approach (eq. 3.3).
    pub normal_speed_before: f64,
    /// The normal relative velocity after the impulse: −e times the speed before for a
    /// frictionless collision of restitution e (thesis §3.4, the work-based restitution of
    /// eq. 3.16 in general).
    pub normal_speed_after: f64,
}

/// A contact the response could not resolve, and what was done instead.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactFailure {
    /// Simulated time.
    pub time: f64,
    /// The first body.
    pub a: BodyHandle,
    /// The second body.
    pub b: BodyHandle,
    /// Why the response failed, and what the fallback did.
    pub message: String,
}

/// What one call of [`World::step`] or [`World::step_until`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Simulated time at the start of the call.
    pub start: f64,
    /// Simulated time at the end.
    pub end: f64,
    /// The counters' increase over the call.
    pub counters: Counters,
    /// Contacts resolved during the call (see [`World::contacts`]).
    pub contacts: usize,
    /// The largest penetration the checking mode measured during the call (length; `None`
    /// unless [`World::set_checking`] is on).
    pub checked_penetration: Option<f64>,
}

/// One point of a pair the switching model holds ([`World::held_contacts`]), as the last
/// island step that solved the pair used it (thesis §5.3's contact forces, here impulses over
/// a step of sustained contact).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeldContact {
    /// The pair's bodies, in [`World::held_pairs`]' order.
    pub bodies: (BodyHandle, BodyHandle),
    /// Where the impulse acted (world, at the start of that step): on the moving body's
    /// surface against a fixed or scripted body, else midway between the two surfaces.
    pub point: DVec3,
    /// Unit contact normal (world), from the first body toward the second.
    pub normal: DVec3,
    /// The impulse on the second body over that step (world; the first receives its
    /// negative): divided by [`HeldContact::span`], the point's mean force over the step.
    pub impulse: DVec3,
    /// Length of that step (s); 0 for a pair held but not stepped yet (its impulses are 0).
    pub span: f64,
}

/// The state of one body at one time, as a program sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyState {
    /// Origin of the body's own frame (the position it was placed at, moved by the motion;
    /// world).
    pub position: DVec3,
    /// Orientation of the body's own frame (world).
    pub rotation: glam::DQuat,
    /// Velocity of the centre of mass (world).
    pub velocity: DVec3,
    /// Angular velocity (world).
    pub omega: DVec3,
    /// Centre of mass (world).
    pub com: DVec3,
}

/// Settings of a world built in code ([`World::new`]); a scene file's fields map to them.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldSettings {
    /// Gravitational acceleration (world).
    pub gravity: DVec3,
    /// Collision epsilon ε_c (length).
    pub collision_epsilon: f64,
    /// Contact properties of material pairs not set otherwise.
    pub default_contact: Material,
    /// The rotation integrator.
    pub integrator: Integrator,
    /// The contact model (collision tolerance, microcollision parameters).
    pub contact_model: ContactModel,
    /// Impulses only, or impulses for impacts and constraints for sustained contact
    /// ([`crate::sustained`]).
    pub contact_mode: ContactMode,
    /// Settings of the switching contact model.
    pub sustained: SustainedSettings,
    /// Directory that relative paths of bodies added later (OBJ files) resolve against.
    pub base_dir: PathBuf,
}

impl WorldSettings {
    /// Gravity 9.81 down z, the given ε_c, μ = 0.3 and e = 0.5, default solver settings.
    #[must_use]
    pub fn new(collision_epsilon: f64) -> Self {
        Self {
            gravity: DVec3::new(0.0, 0.0, -9.81),
            collision_epsilon,
            default_contact: Material {
                friction: 0.3,
                restitution: 0.5,
            },
            integrator: Integrator::default(),
            contact_model: ContactModel::default(),
            contact_mode: ContactMode::default(),
            sustained: SustainedSettings::default(),
            base_dir: PathBuf::from("."),
        }
    }

    /// The settings a scene description gives.
    #[must_use]
    pub fn from_desc(desc: &SceneDesc) -> Self {
        Self {
            gravity: DVec3::from_array(desc.gravity),
            collision_epsilon: desc.collision_epsilon,
            default_contact: Material {
                friction: desc.default_contact.friction,
                restitution: desc.default_contact.restitution,
            },
            integrator: Integrator {
                rotation_tolerance: desc.accuracy.rotation_tolerance,
            },
            contact_model: ContactModel {
                collision_tolerance: desc.accuracy.collision_tolerance,
                max_restitution: desc.accuracy.max_restitution,
                reversing: desc.accuracy.reversing,
            },
            contact_mode: desc.contact_model,
            sustained: SustainedSettings {
                step_tolerance: desc.accuracy.step_tolerance,
                ..SustainedSettings::default()
            },
            base_dir: PathBuf::from("."),
        }
    }
}

/// Per-pair state kept between checks.
#[derive(Clone, Debug, Default)]
struct PairState {
    /// Cached closest features of every piece pair (coherence), `[i * pieces_b + j]`.
    features: Vec<FeaturePair>,
    /// Last contact normal seen per piece pair (world, from the second body toward the first).
    normals: Vec<Option<DVec3>>,
    /// When the pair last took a collision impulse (the switching model holds a pair struck
    /// twice at one instant: `check_top`).
    last_hit: Option<f64>,
    /// The slack structure of each side that is a multibody link (`hybrid_step.rs`).
    slack: [Option<hybrid_step::Slack>; 2],
    /// The pair's last query (`check.rs`: `World::cached_bound`): when, where both bodies
    /// were, the closest piece pair's distance and normal.
    last: Option<quick_bounds::LastQuery>,
    /// What the last query found of each piece pair of two bodies of several pieces,
    /// `[i * pieces_b + j]` (`quick_bounds.rs`: a compound pair's cached bound).
    gaps: Vec<quick_bounds::SlotGap>,
}

/// One slot of the body table.
#[derive(Clone, Debug)]
struct Slot {
    generation: u32,
    body: Option<Body>,
}

/// A load function and when it is evaluated next.
#[derive(Clone)]
struct LoadSchedule {
    body: u32,
    rate: f64,
    start: f64,
    evaluations: u64,
    f: LoadFn,
}

impl LoadSchedule {
    fn next_time(&self) -> f64 {
        self.start + self.evaluations as f64 / self.rate
    }
}

/// Faults a test can inject to show that a guarantee is measured from outside the loop.
#[cfg(test)]
#[derive(Clone, Debug)]
pub(crate) struct Faults {
    /// Every time-of-impact bound is multiplied by this (1: none; > 1: not conservative).
    pub toi_scale: f64,
    /// The response fails on this pair (slot indices, either order).
    pub fail_pair: Option<(u32, u32)>,
    /// `step_until` never takes its quiet path (a world at rest stepped by the loop).
    pub no_quiet_path: bool,
    /// How many `step_until` calls took the quiet path.
    pub quiet_calls: u64,
    /// How many steps handed their bodies' advance to the world's own pool.
    pub pool_steps: u64,
    /// The fast way of holding a compound pair never ends early on the clearance bound of
    /// its piece pairs measured within ε_c (`hold.rs`): it always makes the manifolds.
    pub no_clearance_bound: bool,
    /// How many times that bound ended the fast way early (shared by a world's clones).
    pub clearance_bound_exits: std::sync::Arc<std::sync::atomic::AtomicU64>,
    /// A compound pair's cached bound computes every piece pair's bound
    /// (`quick_bounds.rs`): none is skipped by the direction-free coefficients.
    pub no_free_skip: bool,
    /// How many piece pairs' bounds were skipped so (shared by a world's clones).
    pub free_skips: std::sync::Arc<std::sync::atomic::AtomicU64>,
}

#[cfg(test)]
impl Default for Faults {
    fn default() -> Self {
        Self {
            toi_scale: 1.0,
            fail_pair: None,
            no_quiet_path: false,
            quiet_calls: 0,
            pool_steps: 0,
            no_clearance_bound: false,
            clearance_bound_exits: std::sync::Arc::default(),
            no_free_skip: false,
            free_skips: std::sync::Arc::default(),
        }
    }
}

/// A simulated world.
#[derive(Clone)]
pub struct World {
    slots: Vec<Slot>,
    free: Vec<u32>,
    names: FxHashMap<String, u32>,
    gravity: DVec3,
    schedule: Schedule,
    integrator: Integrator,
    model: ContactModel,
    materials: Materials,
    base_dir: PathBuf,
    time: f64,
    heap: CollisionHeap,
    /// The broad phase and the range of body sizes its levels were made for (`None` until
    /// the first body).
    hash: Option<(CoherentHash, (f64, f64))>,
    pairs: FxHashMap<(u32, u32), PairState>,
    /// The heap pairs whose key was computed from their bounding spheres and their bodies'
    /// far envelopes ([`World::far_bound`]): they keep it while both envelopes hold.
    far_keyed: rustc_hash::FxHashSet<(u32, u32)>,
    /// When each moving body's box in the broad phase expires, earliest first (`sync.rs`).
    box_queue: std::collections::BinaryHeap<std::cmp::Reverse<(u64, u32)>>,
    counters: Counters,
    stalled_checks: u64,
    /// Stalls broken since time last advanced.
    stalls: u64,
    pool: Option<Arc<rayon::ThreadPool>>,
    /// Fewest moving bodies for which a step advances them in parallel.
    parallel_min_bodies: usize,
    events: Option<Vec<ContactEvent>>,
    recent: Vec<ContactEvent>,
    failures: Vec<ContactFailure>,
    loads: Vec<LoadSchedule>,
    /// High-level controllers (`None`: removed), in the order they were added.
    controllers: Vec<Option<control::ControllerSlot>>,
    /// Bodies whose heap pairs need new bounds before the next step (moved, pushed or loaded
    /// by the program).
    stale: Vec<u32>,
    /// The checking mode's monitor ([`World::set_checking`]).
    checking: Option<PenetrationMonitor>,
    /// Whether a failing [`World::step_until`] restores the world as it was before the call
    /// ([`World::set_rollback`]).
    rollback: bool,
    /// Contact islands of the switching model.
    islands: island::Islands,
    /// The multibodies (thesis ch. 5), in the order they were added.
    multibodies: Vec<hybrid::Member>,
    /// The span the moving bodies' swept boxes were made for in the current step (s).
    box_span: f64,
    /// Wall-time profile of the loop's parts, when on ([`World::set_profiling`]).
    profile: Option<Profile>,
    #[cfg(test)]
    pub(crate) faults: Faults,
}

impl std::fmt::Debug for World {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("World")
            .field("time", &self.time)
            .field("bodies", &self.len())
            .field("collision_epsilon", &self.schedule.collision_epsilon)
            .field("counters", &self.counters)
            .finish_non_exhaustive()
    }
}

impl World {
    /// An empty world.
    ///
    /// # Errors
    /// [`SimError::Invalid`] for a non-finite gravity or an ε_c that is not positive and
    /// finite, a bad default contact or solver setting.
    pub fn new(settings: WorldSettings) -> Result<Self, SimError> {
        let bad = |field: &str, problem: String| SimError::Invalid {
            what: "world".into(),
            field: field.into(),
            problem,
        };
        if !settings.gravity.is_finite() {
            return Err(bad(
                "gravity",
                format!("{} is not finite", settings.gravity),
            ));
        }
        let eps = settings.collision_epsilon;
        if !(eps.is_finite() && eps > 0.0) {
            return Err(bad(
                "collision_epsilon",
                format!("{eps} must be finite and > 0"),
            ));
        }
        settings
            .default_contact
            .validate()
            .map_err(|p| bad("default_contact", p))?;
        let tol = settings.integrator.rotation_tolerance;
        if !(tol.is_finite() && tol > 0.0) {
            return Err(bad(
                "rotation_tolerance",
                format!("{tol} must be finite and > 0"),
            ));
        }
        settings
            .contact_model
            .validate()
            .map_err(|p| bad("contact_model", p))?;
        settings
            .sustained
            .validate()
            .map_err(|p| bad("sustained", p))?;
        Ok(Self {
            slots: Vec::new(),
            free: Vec::new(),
            names: FxHashMap::default(),
            gravity: settings.gravity,
            schedule: Schedule::new(eps),
            integrator: settings.integrator,
            model: settings.contact_model,
            materials: Materials::new(settings.default_contact),
            base_dir: settings.base_dir,
            time: 0.0,
            heap: CollisionHeap::new(),
            hash: None,
            pairs: FxHashMap::default(),
            far_keyed: rustc_hash::FxHashSet::default(),
            box_queue: std::collections::BinaryHeap::new(),
            counters: Counters {
                min_distance: f64::INFINITY,
                ..Counters::default()
            },
            stalled_checks: 0,
            stalls: 0,
            pool: None,
            parallel_min_bodies: PARALLEL_MIN_BODIES,
            events: None,
            recent: Vec::new(),
            failures: Vec::new(),
            loads: Vec::new(),
            controllers: Vec::new(),
            stale: Vec::new(),
            checking: None,
            rollback: true,
            islands: island::Islands::new(settings.contact_mode, settings.sustained),
            multibodies: Vec::new(),
            box_span: 0.0,
            profile: None,
            #[cfg(test)]
            faults: Faults::default(),
        })
    }

    /// Builds a world from a scene: validates it, builds every body, refuses bodies that
    /// overlap by more than ε_c (touching is contact), and schedules the first checks.
    ///
    /// # Errors
    /// [`SimError::Invalid`], [`SimError::Geometry`] or [`SimError::Overlap`], naming the
    /// body and what is wrong.
    pub fn from_scene(scene: &Scene) -> Result<Self, SimError> {
        let desc = &scene.desc;
        desc.validate()?;
        let mut settings = WorldSettings::from_desc(desc);
        settings.base_dir.clone_from(&scene.base_dir);
        let mut world = Self::new(settings)?;
        for c in &desc.contacts {
            world.set_material_pair(
                &c.a,
                &c.b,
                Material {
                    friction: c.friction,
                    restitution: c.restitution,
                },
            )?;
        }
        world.add_bodies(&desc.bodies)?;
        for m in &desc.multibodies {
            let (sim, shapes) = m.build(world.gravity, &scene.base_dir)?;
            let options = MultibodyOptions::default().with_self_collision(m.self_collision);
            world.add_multibody_with(&m.name, sim, shapes, options)?;
        }
        for c in &desc.controllers {
            c.add_to(&mut world)?;
        }
        Ok(world)
    }

    /// Runs the per-body work on a pool of `threads` threads (the default is rayon's global
    /// pool). Results do not depend on the thread count. A step with fewer moving bodies than
    /// [`World::set_parallel_min_bodies`] asks stays on the calling thread either way.
    ///
    /// # Errors
    /// [`SimError::Invalid`] for zero threads or more than [`crate::threads::max_threads`],
    /// [`SimError::Runtime`] if the pool cannot be built.
    pub fn set_threads(&mut self, threads: usize) -> Result<(), SimError> {
        let pool = crate::threads::pool(threads, "world")?;
        self.pool = Some(Arc::new(pool));
        Ok(())
    }

    /// Sets the fewest moving bodies for which a step advances its bodies on the pool
    /// (default [`PARALLEL_MIN_BODIES`]); below it they are advanced on the calling thread.
    /// Results do not depend on it. `0` sends every step to the pool, as a check that a run's
    /// trajectory does not depend on its thread count needs.
    pub fn set_parallel_min_bodies(&mut self, bodies: usize) {
        self.parallel_min_bodies = bodies;
    }

    /// Starts (or stops) recording every resolved contact in an event log kept for the whole
    /// run ([`World::events`]); [`World::contacts`] keeps those of the last step either way.
    pub fn set_event_log(&mut self, on: bool) {
        self.events = if on { Some(Vec::new()) } else { None };
    }

    /// The event log (empty unless [`World::set_event_log`] turned it on).
    #[must_use]
    pub fn events(&self) -> &[ContactEvent] {
        self.events.as_deref().unwrap_or(&[])
    }

    /// The contacts resolved during the last call of [`World::step`] or
    /// [`World::step_until`].
    #[must_use]
    pub fn contacts(&self) -> &[ContactEvent] {
        &self.recent
    }

    /// Contacts the response could not resolve (at most [`MAX_FAILURES_KEPT`], the first
    /// ones), with what was done instead.
    #[must_use]
    pub fn failures(&self) -> &[ContactFailure] {
        &self.failures
    }

    /// Whether a failing [`World::step_until`] leaves the world exactly as it was before the
    /// call (on, the default: each call that moves something keeps a copy of the world to
    /// restore), or where the failure was found (off: no copy, for a caller that stops at its
    /// first error, such as [`crate::run_streaming`]; a pool break recorded at 1 kHz spent a
    /// third of its time copying and dropping the world).
    pub fn set_rollback(&mut self, on: bool) {
        self.rollback = on;
    }

    /// Whether a failing [`World::step_until`] restores the world ([`World::set_rollback`]).
    #[must_use]
    pub fn rollback(&self) -> bool {
        self.rollback
    }

    /// Turns the checking mode on or off: after every step of the event loop, an independent
    /// [`PenetrationMonitor`] measures the exact distance of every close pair (slow: for
    /// validation). Its findings: [`World::checked_penetration`], [`StepReport`].
    pub fn set_checking(&mut self, on: bool) {
        self.checking = on.then(PenetrationMonitor::new);
    }

    /// What the checking mode has measured so far (`None` when it is off).
    #[must_use]
    pub fn checked_penetration(&self) -> Option<&crate::monitor::PenetrationReport> {
        self.checking.as_ref().map(PenetrationMonitor::report)
    }

    /// Current simulated time.
    #[must_use]
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Gravity (world).
    #[must_use]
    pub fn gravity(&self) -> DVec3 {
        self.gravity
    }

    /// The collision epsilon ε_c.
    #[must_use]
    pub fn collision_epsilon(&self) -> f64 {
        self.schedule.collision_epsilon
    }

    /// The pairs the switching model holds as constraints now (empty in the impulse model), in
    /// slot order: the contacts an island step solves, not the event loop.
    #[must_use]
    pub fn held_pairs(&self) -> Vec<(BodyHandle, BodyHandle)> {
        let mut pairs: Vec<(u32, u32)> = self.islands.held.keys().copied().collect();
        pairs.sort_unstable();
        pairs
            .into_iter()
            .map(|(a, b)| (self.handle_of(a), self.handle_of(b)))
            .collect()
    }

    /// Every point of the pairs the switching model holds ([`World::held_pairs`], in that
    /// order; each pair's points in its manifolds' order) with the impulse the last island step
    /// gave it. Read-only: the island's own record, the warm start of its next step. Empty in
    /// the impulse model. The vertices of a fast-turning pair solved outside its manifolds
    /// keep no impulse and are not listed.
    #[must_use]
    pub fn held_contacts(&self) -> Vec<HeldContact> {
        let mut pairs: Vec<(u32, u32)> = self.islands.held.keys().copied().collect();
        pairs.sort_unstable();
        let mut out = Vec::new();
        for p in pairs {
            let held = &self.islands.held[&p];
            let moving = (self.b(p.0).takes_impulses(), self.b(p.1).takes_impulses());
            let bodies = (self.handle_of(p.0), self.handle_of(p.1));
            out.extend(
                held.points_with_impulses()
                    .map(|(point, normal, impulse)| HeldContact {
                        bodies,
                        point: island::acting_point(point, moving),
                        normal,
                        impulse,
                        span: held.span(),
                    }),
            );
        }
        out
    }

    /// Event counters so far.
    #[must_use]
    pub fn counters(&self) -> Counters {
        let mut c = self.counters;
        let h = self.heap.stats();
        c.heap_operations = h.inserts + h.removals + h.key_changes;
        c
    }

    /// Number of bodies.
    #[must_use]
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// True for a world without bodies.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// Every body with its handle, in slot order.
    pub fn bodies(&self) -> impl Iterator<Item = (BodyHandle, &Body)> {
        self.slots.iter().enumerate().filter_map(|(i, s)| {
            s.body.as_ref().map(|b| {
                (
                    BodyHandle {
                        index: i as u32,
                        generation: s.generation,
                    },
                    b,
                )
            })
        })
    }

    /// The handles of every body, in slot order.
    #[must_use]
    pub fn handles(&self) -> Vec<BodyHandle> {
        self.bodies().map(|(h, _)| h).collect()
    }

    /// The body a handle names (`None` once it is removed).
    #[must_use]
    pub fn body(&self, h: BodyHandle) -> Option<&Body> {
        self.slots
            .get(h.index as usize)
            .filter(|s| s.generation == h.generation)
            .and_then(|s| s.body.as_ref())
    }

    /// The handle of the body called `name`.
    #[must_use]
    pub fn handle(&self, name: &str) -> Option<BodyHandle> {
        self.names.get(name).map(|&i| self.handle_of(i))
    }

    /// The state of a body.
    ///
    /// # Errors
    /// [`SimError::UnknownBody`] for a handle whose body was removed.
    pub fn state(&self, h: BodyHandle) -> Result<BodyState, SimError> {
        self.body(h).map(Body::state).ok_or(SimError::UnknownBody {
            handle: h.to_string(),
        })
    }

    /// The state of every body, in slot order (as [`World::handles`]).
    #[must_use]
    pub fn states(&self) -> Vec<BodyState> {
        self.bodies().map(|(_, b)| b.state()).collect()
    }

    /// Total kinetic energy of the dynamic bodies and the multibodies.
    #[must_use]
    pub fn kinetic_energy(&self) -> f64 {
        self.bodies().map(|(_, b)| b.kinetic_energy()).sum::<f64>() + self.multibody_energies().0
    }

    /// Total potential energy of the dynamic bodies and the multibodies in gravity (zero at
    /// the world origin).
    #[must_use]
    pub fn potential_energy(&self) -> f64 {
        self.bodies()
            .map(|(_, b)| b.potential_energy(self.gravity))
            .sum::<f64>()
            + self.multibody_energies().1
    }

    fn handle_of(&self, i: u32) -> BodyHandle {
        BodyHandle {
            index: i,
            generation: self.slots[i as usize].generation,
        }
    }

    /// The live body in slot `i` (an internal id from the heap, hash or pair table, which hold
    /// live bodies only).
    fn b(&self, i: u32) -> &Body {
        self.slots[i as usize]
            .body
            .as_ref()
            .expect("internal ids name live bodies")
    }

    fn b_mut(&mut self, i: u32) -> &mut Body {
        self.slots[i as usize]
            .body
            .as_mut()
            .expect("internal ids name live bodies")
    }

    fn name(&self, i: u32) -> &str {
        &self.b(i).name
    }

    fn runtime(&self, message: String) -> SimError {
        SimError::Runtime {
            time: self.time,
            message,
        }
    }

    /// Whether the pair can ever need a collision (at least one body is dynamic).
    fn pair_matters(&self, a: u32, b: u32) -> bool {
        let (ba, bb) = (self.b(a), self.b(b));
        if let (Some(la), Some(lb)) = (ba.link, bb.link) {
            // Links of one multibody collide only with its self-collision on, and never
            // adjacent ones.
            return self.links_collide(la, lb);
        }
        ba.takes_impulses() || bb.takes_impulses()
    }
}

#[cfg(test)]
mod clearance_tests;
#[cfg(test)]
mod island_tests;
#[cfg(test)]
mod keys_tests;

#[cfg(test)]
mod control_tests;
#[cfg(test)]
mod hybrid_tests;
#[cfg(test)]
mod impact_tests;

#[cfg(test)]
mod self_collision_tests;
#[cfg(test)]
mod step_tests;
#[cfg(test)]
mod turning_tests;
