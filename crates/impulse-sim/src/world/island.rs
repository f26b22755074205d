//! Contact islands of the switching model ([`crate::sustained`]): holding and releasing pairs,
//! the island step (manifolds, solve, held contact loads, slip → stick in time), sleeping and
//! waking.

use glam::{DQuat, DVec3};
use impulse_collide::feature::Feature;
use impulse_collide::manifold::{
    self, Clearances, ContactPoint, MAX_POINTS, Manifold, ManifoldCache,
};
use impulse_collide::shape::Convex;
use impulse_response::{
    Contact, ContactFrame, IslandBody, SolveReport, SolverSettings, System, solve_island,
};
use rustc_hash::FxHashMap;

use super::World;
use super::envelope::Envelope;
use super::held::{DueTimes, HeldSet, Island};
use super::held_links::SystemSource;
use super::held_links::{predict_systems, write_members};
use super::hold::PairContact;
use super::hold::{TurnSide, approach_speed, clearance_bound, clearance_closing};
use super::patch::{patch_plane_fit, patch_ranges, patch_targets};
use crate::contact::response_body;
use crate::error::SimError;
use crate::sustained::{
    ContactMode, MIN_STEP_FRACTION, SLIP_FRACTION, STICK_FRACTION, SustainedSettings,
};

/// Most solves of one island step that locate a slip → stick transition (each cuts the step
/// to the fraction the last solve found). Default `4`.
const MAX_LOCATE_SOLVES: usize = 4;

/// A step whose speculative point would dip through its gap within the step is cut to this
/// fraction of the length that reaches the gap (the dip is about proportional to the step, and
/// the re-solve changes the end speed). Default `0.5`.
const DIP_CUT: f64 = 0.5;

/// A located step is final when its patches' friction fills this fraction of their cones.
/// Default `0.999`.
const LOCATE_DONE: f64 = 0.999;

/// A held contact approaching faster than this fraction of the switching speed at the start
/// of an island step was struck (an impulse or a new load reached its island): the island
/// first reacts by an impulsive solve. Resting and sliding contacts start a step at the end
/// speed the previous step solved for, so mostly only a change from outside crosses it.
/// Default `1e-2`: with `1.0` (only collision speeds) the held loads answered strikes over a
/// step instead of at once, and the validation scenes penetrated (coins 72 ε_c, dish 10 ε_c,
/// dominos 3.6 ε_c).
const STRUCK_FRACTION: f64 = 1e-2;

/// A held contact approaching at u_n at the start of an island step of length h is left to
/// the step's constant load (no impulsive solve) when that load, bringing its speed to the
/// step's target linearly, lets it close at most this fraction of the rest gap,
/// |u_n|·h/2 ≤ this·g_r: the turning of a held pair drifts its points' speeds by about
/// ω²·r·h a step, which is not a strike. Default `0.25`.
const ABSORB_GAP_FRACTION: f64 = 0.25;

/// An island whose direct solve on the active set (`impulse_response::contact`) failed at
/// k steps in a row goes without one for its next 2^k − 1 steps, up to this many: a failed
/// attempt costs up to 2·16 factorisations and changes nothing, and an island whose attempt
/// failed (a loop of contacts whose targets no rigid motion meets, a set of classes that
/// cycles) mostly fails again at its next step. One that succeeds clears the count. Default
/// `15`: on the plank bridge (a plank rocking on two blocks, a ball rolling on it) 2 875 of
/// its direct solves failed at the round limit, 81 % of its run.
const DIRECT_BACKOFF_MAX: u32 = 15;

/// An island at rest takes steps this many nominal steps long, ending on their grid: its
/// bodies move slower than the sleep speed, no load function acts on them, every body they
/// touch is fixed, and no contact's gap lies below the rest band, so the step asks for
/// nothing but the weight it held (a strike, a program's change or a new held pair makes it
/// step at once). At the sleep speed the longer step moves a point by
/// `REST_STEP_MULTIPLE`·h·v_sleep, 0.08 ε_c with the defaults; a gap above the rest band is
/// closed at β per nominal step, so 8·β per long step. Default `8`: the dominos' standing
/// row and fallen pile took 1 900 of their 3 300 island steps before they slept (1 436
/// steps in all with it).
pub(super) const REST_STEP_MULTIPLE: f64 = 8.0;

/// After an island's impulsive solve (a strike), its step may let the strike's change of
/// speed (‖Δv‖ + ‖Δω‖·r, the largest over its bodies) carry a surface this fraction of the
/// envelope left above the rest gap, and no more (at least the shortest step). Default
/// `0.125`: the coins' deepest overlap by the checking monitor was 1.12 ε_c with `0.5`, 0.36
/// with `0.25`, 0.19 with `0.125` (0.24 with the shortest step after every strike, which made
/// the dropped block 6.6 times slower).
const STRIKE_STEP_FRACTION: f64 = 0.125;

/// An island step ending within this fraction of the nominal step of a grid point of the
/// island-step grid ended on it (rounding). Default `1e-6`.
const GRID_SLACK: f64 = 1e-6;

/// Solver tolerance, in units of the microcollision speed, of an island holding a pair that
/// turns too fast to be held by its points within ε_c alone ([`World::pair_contact`]).
/// Such an island's step lets the curvature of its motion use up to [`super::hold::TURN_STEP_SAFETY`] of
/// the envelope; a speed error of `1e-3`·√(2·g·ε_c) over a 1 ms step moves a contact by
/// about 1e-3 of ε_c (for ε_c = 20 μm), far below that. Default `1e-3`: with the default
/// `1e-4` the dominos took twice the sweeps (0.32 million against 0.10); with `1e-2` a
/// solve that stops that early left four caps of the feeder chute jammed in its funnel.
const FAST_TOLERANCE_FACTOR: f64 = 1e-3;

/// Most projected Gauss–Seidel sweeps of a solve of such an island (fewer than
/// [`SustainedSettings::max_sweeps`]). Its solves that do not reach the tolerance stall just
/// above it: on the leaning dominos the residual falls to a few times the tolerance within
/// 20–40 sweeps and stays there to 200 and beyond (a loop of sliding contacts whose
/// Gauss–Seidel iterate drifts), 1e-5 to 3e-4 m/s — over a 1 ms step 3e-7 m at most, 0.015
/// of the dominos' ε_c, against the half envelope the step's curvature may use. Sweeps past
/// that bought nothing and were a third of the dominos' sweeps. Default `50`.
const FAST_MAX_SWEEPS: usize = 50;

/// A pair the islands hold: its manifolds of the last step and the impulse each point carried
/// (the warm start of the next step), in world axes: a contact frame is built from its
/// normal, and for a normal along a world axis its tangents turn by 90° with the normal's
/// rounding (`ContactFrame::from_normal` picks the axis least aligned with it), so an
/// impulse kept in frame coordinates would return with its friction pointing elsewhere.
#[derive(Clone, Debug, Default)]
pub(super) struct HeldPair {
    pub(super) manifolds: Vec<Manifold>,
    /// Per manifold, the vertex–face points of vertices outside its contact features (a
    /// fast-turning pair's, [`World::pair_contact`]); each is a patch of its own, starts cold
    /// and keeps no impulse.
    outside: Vec<Vec<ContactPoint>>,
    /// How close the piece pairs of two compounds that do not touch are
    /// ([`World::clearance_step`]): the step is cut to keep them apart.
    near: Clearances,
    impulses: Vec<[DVec3; MAX_POINTS]>,
    cache: ManifoldCache,
    /// Length of the step the impulses were solved for (s), to scale the warm start to the
    /// next step; 0 before the first.
    span: f64,
    /// Held because the pair was struck again at the instant of its last collision, and not
    /// yet stepped: its approach is the strike its island's impulsive solve is about to stop,
    /// not a motion of the coming step, so only rotation counts toward releasing it.
    struck: bool,
    /// The last step was cut short by a slip → stick transition.
    cut: bool,
}

impl HeldPair {
    /// Each manifold point with its manifold's normal and the impulse it carried over the last
    /// step ([`HeldPair::span`]; on the pair's second body, world).
    pub(super) fn points_with_impulses(
        &self,
    ) -> impl Iterator<Item = (&ContactPoint, DVec3, DVec3)> + '_ {
        self.manifolds
            .iter()
            .zip(&self.impulses)
            .flat_map(|(m, imp)| {
                m.points()
                    .iter()
                    .zip(imp)
                    .map(move |(p, j)| (p, m.normal, *j))
            })
    }

    /// Length of the step the impulses were solved for (s); 0 before the first.
    pub(super) fn span(&self) -> f64 {
        self.span
    }
}

/// Where a held contact's impulse acts, given whether each body of the pair takes impulses:
/// against a fixed or scripted body, at the moving body's surface (its lever arm exact,
/// whatever the gap); between two moving bodies, midway.
pub(super) fn acting_point(point: &ContactPoint, moving: (bool, bool)) -> DVec3 {
    match moving {
        (true, false) => point.point_a,
        (false, true) => point.point_b,
        _ => point.midpoint(),
    }
}

/// What planning an island step counted ([`World::plan_island`]), added to the world's
/// [`super::Counters`] in island order.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct PlanCounts {
    transients: u64,
    struck_steps: u64,
    long_steps: u64,
    fitted_steps: u64,
    located_steps: u64,
    rounded_transitions: u64,
    island_solves: u64,
    island_sweeps: u64,
    unconverged_solves: u64,
    direct_solves: u64,
    patch_jumps: u64,
}

impl PlanCounts {
    /// Adds these counts to the world's.
    fn add_to(&self, c: &mut super::Counters) {
        c.transients += self.transients;
        c.struck_steps += self.struck_steps;
        c.long_steps += self.long_steps;
        c.fitted_steps += self.fitted_steps;
        c.located_steps += self.located_steps;
        c.rounded_transitions += self.rounded_transitions;
        c.island_solves += self.island_solves;
        c.island_sweeps += self.island_sweeps;
        c.unconverged_solves += self.unconverged_solves;
        c.direct_solves += self.direct_solves;
        c.patch_jumps += self.patch_jumps;
    }
}

/// An island's step as planned ([`World::plan_island`]), to be applied
/// ([`World::apply_island`]).
pub(super) struct IslandPlan {
    /// The step's length.
    h: f64,
    /// The solver's bodies (world ids) and their velocities after the step.
    ids: Vec<u32>,
    bodies: Vec<IslandBody>,
    /// Their velocities after the step without contact.
    predicted: Vec<IslandBody>,
    /// Their velocities after the impulsive solve of a strike (before the step).
    after_jolt: Vec<IslandBody>,
    /// The island's multibodies after that solve, and where each came from.
    systems_after_jolt: Vec<System>,
    sources: Vec<SystemSource>,
    /// The contacts with their impulses over the step, and each one's pair, manifold and point.
    solution: Vec<Contact>,
    origin: Vec<((u32, u32), usize, usize)>,
    /// Whether a direct solve was tried and held.
    direct_outcome: Option<bool>,
    /// The island's key body and its direct-solve backoff before the step.
    key: u32,
    backoff: Option<(u32, f64)>,
}

/// The islands' state in a world.
#[derive(Clone, Debug)]
pub(super) struct Islands {
    pub(super) mode: ContactMode,
    pub(super) settings: SustainedSettings,
    /// Held pairs (slot indices, as in the heap), with each body's partners.
    pub(super) held: HeldSet<HeldPair>,
    /// When the next island step is due (∞ with no awake island): the earliest of [`Self::due`].
    pub(super) next_step: f64,
    /// When each awake island body's island is next due (each island steps at its own rate);
    /// a sleeping island's bodies are not listed.
    due: DueTimes,
    /// Since when each awake island body has moved slower than the sleep speed.
    still_since: FxHashMap<u32, f64>,
    /// Islands (by their first body) whose direct solves failed at their last steps: how
    /// many in a row, and until when their solves go without one ([`DIRECT_BACKOFF_MAX`]).
    direct_backoff: FxHashMap<u32, (u32, f64)>,
    /// Per island body, how much its last island step changed its held load: the change of
    /// its centre's acceleration plus that of its angular acceleration times its reach
    /// (∞ when the step was a strike's or its first). Read by [`World::is_steady`].
    pub(super) load_change: FxHashMap<u32, f64>,
    /// Bodies whose last island step left their load envelope or changed their velocity
    /// (`world/envelope.rs`): their heap pairs need new keys. Drained by each island step.
    moved: Vec<u32>,
}

impl Islands {
    pub(super) fn new(mode: ContactMode, settings: SustainedSettings) -> Self {
        Self {
            mode,
            settings,
            held: HeldSet::default(),
            next_step: f64::INFINITY,
            due: DueTimes::default(),
            still_since: FxHashMap::default(),
            direct_backoff: FxHashMap::default(),
            load_change: FxHashMap::default(),
            moved: Vec::new(),
        }
    }
}

impl World {
    /// Whether the switching contact model is on.
    pub(super) fn switching(&self) -> bool {
        self.islands.mode == ContactMode::Switching
    }

    /// The microcollision speed √(2·g·ε_c) (thesis eq. 3.18).
    fn micro_speed(&self) -> f64 {
        (2.0 * self.gravity.length() * self.collision_epsilon()).sqrt()
    }

    /// Contacts approaching slower than this are held (module documentation of
    /// [`crate::sustained`]).
    pub(super) fn switch_speed(&self) -> f64 {
        self.islands.settings.switch_speed_factor * self.micro_speed()
    }

    /// Whether an island is at rest ([`REST_STEP_MULTIPLE`]): its bodies slower than the sleep
    /// speed, none under a load function, and every other body of its pairs fixed.
    fn at_rest(&self, island: &Island) -> bool {
        island.bodies.iter().all(|&i| self.is_still(i))
            && island.pairs.iter().all(|&(a, b)| {
                [a, b].iter().all(|&i| {
                    self.b(i).is_dynamic() || self.b(i).kind == crate::body::BodyKind::Fixed
                })
            })
    }

    /// Whether body `i` moves slower than the sleep speed (its points: ‖v‖ + ‖ω‖·r_max) under
    /// no load function: what resting ([`Self::at_rest`]) and sleeping
    /// ([`Self::sleep_if_still`]) ask of each body.
    fn is_still(&self, i: u32) -> bool {
        let v_sleep = self.islands.settings.sleep_speed_factor * self.micro_speed();
        let b = self.b(i);
        // A link moves with its multibody, which its islands do not put to sleep.
        !b.is_link()
            && b.velocity.length() + b.omega.length() * b.r_max < v_sleep
            && !self.loads.iter().any(|l| l.body == i)
    }

    /// The step of an island at rest: to the next multiple of [`REST_STEP_MULTIPLE`] nominal
    /// steps in absolute time, at least one nominal step.
    fn rest_step(&self) -> f64 {
        let long = REST_STEP_MULTIPLE * self.islands.settings.step;
        let t = self.time;
        let mut next = ((t / long).floor() + 1.0) * long;
        if next - t < self.islands.settings.step {
            next += long;
        }
        next - t
    }

    /// A full island step that ends on the world's grid of island steps (the multiples of
    /// [`SustainedSettings::step`]): islands whose steps end at one instant take them in one
    /// loop step, which advances every moving body once, instead of one loop step each.
    /// At most the nominal step; an island off the grid (it joined late, or a transition cut
    /// its last step) takes a shorter step back to it.
    fn aligned_step(&self) -> f64 {
        let step = self.islands.settings.step;
        let t = self.time;
        let mut next = ((t / step).floor() + 1.0) * step;
        // A step that ended on the grid ends a rounding away from it.
        if next - t <= GRID_SLACK * step {
            next += step;
        }
        // Back to the grid in one step of at least half the nominal one, or in two equal
        // steps (a tiny step costs a solve like any other, and its warm start is scaled from
        // a step a thousand times longer).
        let left = (next - t).min(step);
        if left >= 0.5 * step {
            left
        } else {
            0.5 * (left + step)
        }
    }

    /// The end-of-step normal speed a held contact of gap `gap` is asked for (module
    /// documentation of [`crate::sustained`]): β·(g_r − gap)/h below the rest gap, nothing
    /// inside the rest band [g_r, g_pull], β·(g_pull − gap)/h above it, and on top
    /// the rest of an overlap (gap < 0) within the nominal step h. Turning within a step
    /// drives a sliding, turning contact (a domino's edge on its neighbour's face) inward by
    /// about ½·ω²·r·h² a step, which the rate β alone would let settle β⁻¹ times deeper.
    fn stabilisation_speed(&self, gap: f64) -> f64 {
        let s = &self.islands.settings;
        let eps = self.collision_epsilon();
        let rest_gap = self.rest_gap();
        let pull_gap = s.pull_gap_fraction * eps;
        let error = if gap < rest_gap {
            rest_gap - gap
        } else {
            (pull_gap - gap).min(0.0)
        };
        (s.stabilisation * error + (1.0 - s.stabilisation) * (-gap).max(0.0)) / s.step
    }

    /// The gap g_r at which a held contact rests.
    fn rest_gap(&self) -> f64 {
        self.islands.settings.rest_gap_fraction * self.collision_epsilon()
    }

    pub(super) fn is_held(&self, pair: (u32, u32)) -> bool {
        self.islands.held.contains_key(&pair)
    }

    /// Whether body `i` is in a held pair.
    pub(super) fn is_held_body(&self, i: u32) -> bool {
        self.islands.held.holds_body(i)
    }

    /// Holds a pair: the islands take it over from the event loop (its heap key is set to ∞
    /// by the caller) and an island step is due now.
    pub(super) fn hold(&mut self, pair: (u32, u32)) {
        self.islands.held.hold(pair);
        self.islands.load_change.remove(&pair.0);
        self.islands.load_change.remove(&pair.1);
        self.step_now(pair.0);
        self.step_now(pair.1);
    }

    /// Holds a pair struck again at the instant of its last collision ([`Self::hold`]; the
    /// rule is documented in [`crate::sustained`]).
    pub(super) fn hold_struck(&mut self, pair: (u32, u32)) {
        self.hold(pair);
        if let Some(held) = self.islands.held.get_mut(&pair) {
            held.struck = true;
        }
    }

    /// Body `i`'s island steps now (it was struck, changed, woken or joined). A body that
    /// joins no island (fixed, scripted) has no clock.
    pub(super) fn step_now(&mut self, i: u32) {
        if self.b(i).takes_impulses() {
            self.islands.due.insert(i, self.time);
        }
        self.islands.next_step = self.islands.next_step.min(self.time);
    }

    /// Releases a held pair to the event loop: both bodies' heap pairs get new bounds, and a
    /// body left in no held pair loses its held contact load (from now: both are brought to
    /// now first, under the load they had).
    ///
    /// # Errors
    /// A body whose state stops being finite on its way to now.
    fn release(&mut self, pair: (u32, u32)) -> Result<(), SimError> {
        self.sync_pair(pair)?;
        self.islands.held.remove(&pair);
        self.islands.load_change.remove(&pair.0);
        self.islands.load_change.remove(&pair.1);
        for i in [pair.0, pair.1] {
            self.release_link(i);
            if !self.islands.held.holds_body(i) {
                let b = self.b_mut(i);
                b.held_force = DVec3::ZERO;
                b.held_torque = DVec3::ZERO;
                b.envelope = None;
                if b.asleep {
                    self.wake_body(i);
                }
                self.islands.still_since.remove(&i);
                self.islands.due.remove(i);
            }
            if !self.stale.contains(&i) {
                self.stale.push(i);
            }
        }
        Ok(())
    }

    /// Forgets every held pair of body `i` (it was moved or removed).
    ///
    /// # Errors
    /// As [`World::release`].
    pub(super) fn release_all_of(&mut self, i: u32) -> Result<(), SimError> {
        let mine = self.islands.held.pairs_of(i);
        self.wake(i);
        for p in mine {
            self.release(p)?;
        }
        Ok(())
    }

    /// Wakes the island of body `i` if it sleeps (every body joined to it by held pairs),
    /// schedules an island step now, and returns the bodies woken (their heap pairs need new
    /// bounds: they were fixed).
    pub(super) fn wake(&mut self, i: u32) -> Vec<u32> {
        if !self.slots[i as usize]
            .body
            .as_ref()
            .is_some_and(|b| b.asleep)
        {
            return Vec::new();
        }
        let mut woken = vec![i];
        let mut seen: rustc_hash::FxHashSet<u32> = std::iter::once(i).collect();
        let mut k = 0;
        while k < woken.len() {
            let j = woken[k];
            k += 1;
            for &o in self.islands.held.partners(j) {
                if self.b(o).is_dynamic() && seen.insert(o) {
                    woken.push(o);
                }
            }
        }
        for &j in &woken {
            self.wake_body(j);
            self.islands.still_since.remove(&j);
            if !self.stale.contains(&j) {
                self.stale.push(j);
            }
            self.step_now(j);
        }
        woken
    }

    /// One island step (module documentation of [`crate::sustained`]).
    pub(super) fn island_step(&mut self) -> Result<(), SimError> {
        let t = self.time;
        let settings = self.islands.settings;
        let eps = self.collision_epsilon();
        // 1. Manifolds of the pairs of the islands due now (a body of theirs is due); lift-off
        // releases a pair. Each island steps at its own rate.
        let due = self.islands.due.due_by(t);
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        for island in self.islands_of(&due) {
            pairs.extend(&island.pairs);
        }
        pairs.sort_unstable();
        // Their bodies (and the scripted bodies they touch) at now (`sync.rs`).
        for &(a, b) in &pairs {
            self.sync_pair((a, b))?;
        }
        let mut released = Vec::new();
        let mut spinning: Vec<u32> = Vec::new();
        // Awake held pairs and how fast another of their features can approach.
        let mut turning: Vec<((u32, u32), f64, bool)> = Vec::new();
        for &p in &pairs {
            let live = "internal ids name live bodies";
            let ba = self.slots[p.0 as usize].body.as_ref().expect(live);
            let bb = self.slots[p.1 as usize].body.as_ref().expect(live);
            let sleeping = |b: &crate::body::Body| b.asleep || !b.takes_impulses();
            if sleeping(ba) && sleeping(bb) {
                continue;
            }
            let struck = self.islands.held[&p].struck;
            let mut cache =
                std::mem::take(&mut self.islands.held.get_mut(&p).expect("listed above").cache);
            let contact = self.pair_contact(p, struck, 1.0, &mut cache);
            let held = self.islands.held.get_mut(&p).expect("listed above");
            held.cache = cache;
            let (live, outside, step, fast) = match contact? {
                PairContact::Apart => {
                    released.push(p);
                    continue;
                }
                // A body turning so fast that even the shortest step would carry a feature
                // through the envelope is not in static contact: all its pairs go back to
                // the event loop, which bounds them (a body half held, half hit by
                // microcollisions would be pressed by a held load the microcollisions do not
                // know of).
                PairContact::TooFast => {
                    for i in [p.0, p.1] {
                        if self.b(i).takes_impulses() {
                            spinning.push(i);
                        }
                    }
                    released.push(p);
                    continue;
                }
                PairContact::Held {
                    manifolds,
                    outside,
                    near,
                    step,
                    fast,
                } => {
                    self.islands.held.get_mut(&p).expect("listed above").near = near;
                    (manifolds, outside, step, fast)
                }
            };
            turning.push((p, step, fast));
            let held = self.islands.held.get_mut(&p).expect("listed above");
            let mut impulses = vec![[DVec3::ZERO; MAX_POINTS]; live.len()];
            for (k, m) in live.iter().enumerate() {
                let old = held.manifolds.iter().position(|o| o.pieces == m.pieces);
                if let Some(j) = old {
                    let map = manifold::match_points(&held.manifolds[j], m, eps);
                    for (q, o) in map.iter().enumerate() {
                        if let Some(o) = o {
                            impulses[k][q] = held.impulses[j][*o];
                        }
                    }
                }
            }
            held.manifolds = live;
            held.outside = outside;
            held.impulses = impulses;
        }
        spinning.sort_unstable();
        spinning.dedup();
        for i in spinning {
            released.extend(
                self.islands
                    .held
                    .keys()
                    .filter(|q| q.0 == i || q.1 == i)
                    .copied(),
            );
        }
        released.sort_unstable();
        released.dedup();
        for p in released {
            self.release(p)?;
        }
        // 2. Each awake island with a body due: wake the whole of a partly sleeping one, step
        // it as long as its fastest-turning pair allows (the warm start is each pair's last
        // impulses scaled to that step), solve, hold.
        let mut touched: Vec<u32> = Vec::new();
        // Stepping changes no island's pairs (only impulses and sleep), so the islands found
        // here also schedule the next step.
        let islands = self.islands_of(&due);
        let turn_of: FxHashMap<(u32, u32), (f64, bool)> = turning
            .iter()
            .map(|&(p, step, fast)| (p, (step, fast)))
            .collect();
        for island in &islands {
            let is_due = |w: &World, i: u32| w.islands.due.get(i).is_some_and(|d| d <= t);
            if island.bodies.iter().all(|&i| self.b(i).asleep)
                || !island.bodies.iter().any(|&i| is_due(self, i))
            {
                continue;
            }
            for &i in &island.bodies {
                if self.b(i).asleep {
                    self.wake_body(i);
                }
            }
            let h0 = island
                .pairs
                .iter()
                .filter_map(|p| turn_of.get(p))
                .map(|&(step, _)| step)
                .fold(settings.step, f64::min);
            // A full step ends on the island-step grid, unless the island's last step was
            // cut by a transition (it is in the middle of one: realigning would cost a step
            // at every cut).
            let was_cut = island
                .pairs
                .iter()
                .any(|p| self.islands.held.get(p).is_some_and(|held| held.cut));
            let h0 = if h0 >= settings.step && !was_cut {
                self.aligned_step()
            } else {
                h0
            };
            for p in &island.pairs {
                let held = self
                    .islands
                    .held
                    .get_mut(p)
                    .expect("an island's pairs are held");
                if held.span > 0.0 {
                    let scale = h0 / held.span;
                    for imp in held.impulses.iter_mut().flatten() {
                        *imp *= scale;
                    }
                }
            }
            let fast = island
                .pairs
                .iter()
                .any(|p| turn_of.get(p).is_some_and(|&(_, fast)| fast));
            let rest = (h0 >= settings.step
                && !was_cut
                && !fast
                && (self.at_rest(island) || self.is_steady(island)))
            .then(|| self.rest_step());
            let fast_pairs: Vec<(u32, u32)> = island
                .pairs
                .iter()
                .filter(|p| turn_of.get(p).is_some_and(|&(_, fast)| fast))
                .copied()
                .collect();
            if h0 < settings.step * (1.0 - 1e-12) && !was_cut {
                self.counters.turning_steps += 1;
            }
            let h = self.step_island(island, h0, fast, &fast_pairs, rest)?;
            for p in &island.pairs {
                if let Some(held) = self.islands.held.get_mut(p) {
                    held.span = h;
                    held.cut = h < h0 * (1.0 - 1e-12);
                    held.struck = false;
                }
            }
            for &i in &island.bodies {
                self.islands.due.insert(i, t + h);
            }
            // A dynamic body's keys hold while its load stays in its envelope; a link's
            // motion is its multibody's, re-keyed with it.
            touched.extend(island.bodies.iter().filter(|&&i| !self.b(i).is_dynamic()));
            touched.append(&mut self.islands.moved);
            self.counters.island_steps += 1;
            self.sleep_if_still(island);
        }
        // The next island step: the earliest due body of an awake island (a sleeping island's
        // bodies are not listed).
        self.islands.next_step = self.islands.due.earliest();
        touched.sort_unstable();
        touched.dedup();
        let mut stale = std::mem::take(&mut self.stale);
        stale.extend(touched);
        stale.sort_unstable();
        stale.dedup();
        self.rekey(&stale, None)
    }

    /// Solves one island's contacts over the coming step of length `h0`, sets its bodies' held
    /// contact loads, and returns the step's length (shortened to a slip → stick transition).
    fn step_island(
        &mut self,
        island: &Island,
        h0: f64,
        fast: bool,
        fast_pairs: &[(u32, u32)],
        rest: Option<f64>,
    ) -> Result<f64, SimError> {
        let order = self.island_ids(island);
        let systems = self.island_systems(&order.1)?;
        let mut counts = PlanCounts::default();
        let plan = self.plan_island(
            island,
            order,
            h0,
            fast,
            fast_pairs,
            rest,
            systems,
            &mut counts,
        );
        counts.add_to(&mut self.counters);
        self.apply_island(plan?)
    }

    /// The island's bodies in the solver's order (its own, then the fixed and scripted ones
    /// its pairs touch, in pair order), and each one's place.
    fn island_ids(&self, island: &Island) -> (FxHashMap<u32, usize>, Vec<u32>) {
        let mut index: FxHashMap<u32, usize> = FxHashMap::default();
        let mut ids: Vec<u32> = Vec::new();
        for &i in island
            .bodies
            .iter()
            .chain(island.pairs.iter().flat_map(|p| [&p.0, &p.1]))
        {
            index.entry(i).or_insert_with(|| {
                ids.push(i);
                ids.len() - 1
            });
        }
        (index, ids)
    }

    /// The read-only part of [`Self::step_island`]: the island's contacts solved over the
    /// coming step (the step located, cut to fit), with its bodies in the order `(index, ids)`
    /// of [`Self::island_ids`] and `systems` its multibodies' jointed systems
    /// ([`Self::island_systems`]); what it counted goes to `counts`. It reads only its own
    /// island's bodies and pairs and the fixed bodies they touch.
    #[allow(clippy::too_many_arguments)]
    fn plan_island(
        &self,
        island: &Island,
        (index, ids): (FxHashMap<u32, usize>, Vec<u32>),
        mut h0: f64,
        fast: bool,
        fast_pairs: &[(u32, u32)],
        rest: Option<f64>,
        (mut systems, sources): (Vec<System>, Vec<SystemSource>),
        counts: &mut PlanCounts,
    ) -> Result<IslandPlan, SimError> {
        let settings = self.islands.settings;
        let v_micro = self.micro_speed();
        let v_s = self.switch_speed();
        // A fast-turning island's geometry moves by up to half the envelope over a step (the
        // curvature its step allows): a solve far tighter than that buys nothing.
        let tolerance_factor = if fast {
            settings.solver_tolerance_factor.max(FAST_TOLERANCE_FACTOR)
        } else {
            settings.solver_tolerance_factor
        };
        let mut solver = SolverSettings {
            max_iterations: if fast {
                settings.max_sweeps.min(FAST_MAX_SWEEPS)
            } else {
                settings.max_sweeps
            },
            tolerance: (tolerance_factor * v_micro).max(f64::MIN_POSITIVE),
            direct_after: Some(settings.direct_after),
            acceleration: settings.acceleration,
        };
        let key = island.bodies[0];
        let backoff = self.islands.direct_backoff.get(&key).copied();
        if backoff.is_some_and(|(_, until)| self.time < until) {
            solver.direct_after = None;
        }
        let mut direct_outcome: Option<bool> = None;
        // Bodies: the island's dynamic bodies, then the fixed and scripted ones it touches.
        let mut bodies: Vec<IslandBody> = ids
            .iter()
            .map(|&i| {
                let b = self.b(i);
                IslandBody {
                    body: response_body(b),
                    com: b.pose.translation,
                    velocity: b.velocity,
                    omega: b.omega,
                }
            })
            .collect();
        let mut contacts: Vec<Contact> = Vec::new();
        let mut material: Vec<(bool, bool)> = Vec::new();
        let mut gaps: Vec<f64> = Vec::new();
        let mut origin: Vec<((u32, u32), usize, usize)> = Vec::new();
        for &p in &island.pairs {
            let (ka, kb) = (index[&p.0], index[&p.1]);
            let friction = self.material(p.0, p.1).friction;
            let (dyn_a, dyn_b) = (self.b(p.0).takes_impulses(), self.b(p.1).takes_impulses());
            let held = &self.islands.held[&p];
            // A manifold's points, each manifold a patch; then the outside points, each a
            // patch of its own (they are vertices at different heights, which no plane of
            // gaps fits), with no warm start.
            let mut lone = 0;
            let outside = held
                .outside
                .iter()
                .enumerate()
                .flat_map(|(m, o)| o.iter().map(move |point| (m, point)));
            let listed = held
                .manifolds
                .iter()
                .zip(&held.impulses)
                .enumerate()
                .flat_map(|(m, (man, imp))| {
                    man.points()
                        .iter()
                        .enumerate()
                        .map(move |(q, point)| (m, man.normal, point, Some(imp[q]), q))
                })
                .chain(outside.map(|(m, point)| (m, held.manifolds[m].normal, point, None, 0)));
            for (m, normal, point, warm, q) in listed {
                // Whether each body's side of the point is a polyhedron's vertex, a material
                // point that turns with the body. A face's side is not (the point moves over
                // the face with the other body's vertex: a ball rolling on a turning platter),
                // nor is an edge crossing (it slides along both edges), nor a smooth piece's
                // support point (a ball turning about its centre keeps its distance).
                let pieces = held.manifolds[m].pieces;
                let vertex = |i: u32, piece: u32, feature: Feature| {
                    matches!(feature, Feature::Vertex(_))
                        && matches!(
                            self.b(i).shape.pieces()[piece as usize].convex,
                            Convex::Polyhedron(_)
                        )
                };
                material.push((
                    vertex(p.1, pieces.1, point.id.b),
                    vertex(p.0, pieces.0, point.id.a),
                ));
                let m = if warm.is_some() {
                    m
                } else {
                    lone += 1;
                    usize::MAX - lone
                };
                let at = acting_point(point, (dyn_a, dyn_b));
                // The manifold's normal points from a to b: body 1 is b, body 2 is a.
                contacts.push(Contact {
                    body1: kb,
                    body2: Some(ka),
                    point: at,
                    normal,
                    friction,
                    target_normal_velocity: 0.0,
                    velocity_bias: DVec3::ZERO,
                    lever_arms: None,
                    impulse: self
                        .contact_frame(normal)?
                        .to_contact(warm.unwrap_or_default()),
                });
                gaps.push(point.gap);
                origin.push((p, m, q));
            }
        }
        // The stabilisation asks each point for the gap of the plane fitted to its patch's gaps:
        // the part of the gap error a rigid relative motion can correct. Four corners of a
        // face have one more gap than a plane has parameters; a warp between them (rounding,
        // a step's drift) asked of the points one by one is a target no motion meets, and the
        // solver answers it with huge opposite impulses on redundant corners.
        let patches = patch_ranges(&origin);
        let eps = self.collision_epsilon();
        // The multibodies of the island's links, as jointed systems (`held_links.rs`).
        write_members(&systems, &mut bodies);
        // Points beyond the envelope are speculative: they only keep the step from closing
        // their gap (below).
        let speculative: Vec<bool> = gaps.iter().map(|&g| g > eps).collect();
        let raw_gaps = gaps.clone();
        let gaps = patch_plane_fit(&contacts, &patches, &gaps);
        // Transients: a held contact approaching (faster than STRUCK_FRACTION·v_s) gets an
        // impulsive solve of its island first (e = 0 between held contacts): the island reacts
        // to a strike at once, through its constraints, not over a step.
        let mut struck = false;
        let approach = contacts
            .iter()
            .zip(&speculative)
            .filter(|(_, s)| !**s)
            .map(|(c, _)| normal_speed(&bodies, c))
            .fold(f64::INFINITY, f64::min);
        let absorbed = 2.0 * ABSORB_GAP_FRACTION * self.rest_gap() / h0;
        if approach < -(STRUCK_FRACTION * v_s).max(absorbed) {
            let before = bodies.clone();
            let targets = patch_targets(&contacts, &patches, &gaps, |g| {
                self.stabilisation_speed(g).max(0.0)
            });
            // Speculative points take part (targets at least 0, e = 0): a strike that sends a
            // far edge down at once would otherwise leave it to the step's constant load, which
            // stops a fast approach only by dipping below ε_c mid-step (leaving them out, the
            // coins sank 7 ε_c by the checking monitor).
            let mut jolt = contacts.clone();
            for (c, &target) in jolt.iter_mut().zip(&targets) {
                c.impulse = DVec3::ZERO;
                c.target_normal_velocity = target;
            }
            self.solve(&mut bodies, &mut systems, &mut jolt, &solver, counts)?;
            counts.transients += 1;
            struck = true;
            // The step was chosen from the speeds before the strike: it must not let what the
            // strike changed carry a surface through the rest of the envelope (a coin struck
            // by another falling on it went 4 ε_c into the plate within the 0.4 ms chosen
            // before). The next step is chosen from the speeds after it.
            let change = ids
                .iter()
                .zip(before.iter().zip(&bodies))
                .map(|(&i, (b0, b1))| {
                    (b1.velocity - b0.velocity).length()
                        + (b1.omega - b0.omega).length() * self.b(i).max_reach()
                })
                .fold(0.0, f64::max);
            if change > 0.0 {
                let allowed = STRIKE_STEP_FRACTION * self.envelope_left() / change;
                if allowed < h0 {
                    counts.struck_steps += 1;
                }
                h0 = h0.min(allowed.max(settings.min_step));
            }
        }
        // An island at rest whose contacts ask for no push (no gap below the rest band, no
        // speculative point, no strike) takes the long step, its warm start scaled to it.
        if let Some(long) = rest {
            let asks = patch_targets(&contacts, &patches, &gaps, |g| self.stabilisation_speed(g));
            if !struck
                && !speculative.iter().any(|&s| s)
                && asks.iter().all(|&a| a <= solver.tolerance)
            {
                for c in &mut contacts {
                    c.impulse *= long / h0;
                }
                h0 = long;
                counts.long_steps += 1;
            }
        }
        let after_jolt = bodies.clone();
        let systems_after_jolt = systems.clone();
        // The step: predict, solve, and locate a slip → stick transition.
        let mut h = h0;
        let mut solved;
        let mut tries = 0;
        let mut located = false;
        loop {
            tries += 1;
            bodies.clone_from(&after_jolt);
            systems.clone_from(&systems_after_jolt);
            self.predict(&ids, &mut bodies, h);
            predict_systems(&mut systems, &sources, h);
            write_members(&systems, &mut bodies);
            let predicted = bodies.clone();
            // The stabilisation's rate is that of the nominal step: a step cut short by a
            // transition must not push harder.
            let targets =
                patch_targets(&contacts, &patches, &gaps, |g| self.stabilisation_speed(g));
            // The bodies turn over the step, and the contact vertices and edges of polyhedra
            // with them. The load is held constant over the step, so its torque is the mean
            // of the turning arms': the arms at mid-step, to second order ([`mid_arms`]; with
            // the arms at the start a box tipping over its edge came late by 1.5·‖ω‖·h
            // relative). The law holds for the points' velocity at the step's end, which the
            // arms' turn from mid-step to the end changes ([`Contact::velocity_bias`]):
            // without it a pivoting edge climbs off its support by ½·h²·ω²·r a step.
            // A speculative point may close its gap to ε_c within the step and no further:
            // its mean normal speed over the step (the held load is constant, so the speed
            // changes linearly) must not close more than the gap beyond ε_c, widened by what
            // the turning of its arms moves it. It keeps the arms at the start: with arms at
            // mid-step a domino slapping flat on the table sank 8 ε_c.
            for (k, c) in contacts.iter_mut().enumerate() {
                c.target_normal_velocity = targets[k];
                if speculative[k] {
                    c.lever_arms = None;
                    c.velocity_bias = DVec3::ZERO;
                    let n = c.normal.normalize();
                    let beyond =
                        raw_gaps[k] - eps + turning_drift(&after_jolt, c, material[k], h, n);
                    let start = normal_speed(&after_jolt, c);
                    c.target_normal_velocity = (-beyond / h).max(-2.0 * beyond / h - start);
                } else {
                    let (mut arms, mut bias) = mid_arms(&after_jolt, c, material[k], h);
                    // A turning smooth body's contact point runs over its surface: its arm
                    // at mid-step is its support point at the mid-step pose, and the law
                    // holds for the support point's velocity at the step's end.
                    let n = c.normal.normalize();
                    let smooth = |k: usize, dir: DVec3| -> Option<(DVec3, DVec3)> {
                        let (b, w) = (self.b(ids[k]), after_jolt[k].omega);
                        if b.max_reach() == 0.0 || w == DVec3::ZERO {
                            return None;
                        }
                        let turned = |t: f64| DQuat::from_scaled_axis(w * t) * b.pose.rotation;
                        let mid = b.support_arm(turned(0.5 * h), dir)?;
                        let end = b.support_arm(turned(h), dir)?;
                        Some((mid, w.cross(end - mid)))
                    };
                    if let Some((mid, b1)) = smooth(c.body1, -n) {
                        arms.0 = mid;
                        bias += b1;
                    }
                    if let Some((mid, b2)) = c.body2.and_then(|k2| smooth(k2, n)) {
                        arms.1 = mid;
                        bias -= b2;
                    }
                    c.lever_arms = Some(arms);
                    c.velocity_bias = bias;
                }
            }
            let mut trial = contacts.clone();
            let report = self.solve(&mut bodies, &mut systems, &mut trial, &solver, counts)?;
            // A direct solve that failed on this island fails again on the same contacts cut
            // to a shorter step: the re-solves that locate a transition go without it.
            // A patch jump counts as a direct solve that succeeded.
            if report.direct_tried {
                let taken = report.direct || report.jumped;
                direct_outcome.get_or_insert(taken);
                if !taken {
                    solver.direct_after = None;
                }
            }
            solved = (predicted, trial);
            // The step was chosen from the turn speeds at its start; the held load may turn
            // the bodies faster within it (a coin held by one side of its face tips over
            // those points, and its other side falls toward the plate with no point to stop
            // it). Under the constant load the speeds change linearly, so over the step a
            // feature outside the manifold closes at most the mean of the start and end turn
            // speeds times h: past the envelope left above the rest gap, the step is cut to
            // fit it and solved again. A fast pair's speculative points are in the solve; a slow
            // pair is checked so even in a fast island, whose step its fast pairs chose: a coin
            // resting on a plate by two rim points, in the island of another coin tumbling on
            // it, was turned by the step's load and its far rim went 1.3 ε_c into the plate
            // within the 1 ms step (the checking monitor).
            let mut fit = 1.0_f64;
            let closing = contacts
                .iter()
                .zip(&origin)
                .filter(|(_, (p, _, _))| fast_pairs.binary_search(p).is_err())
                .map(|(c, &(p, m, _))| {
                    let pieces = self.islands.held[&p].manifolds[m].pieces;
                    let turn = |v: &[IslandBody]| self.contact_turn(&ids, v, c, pieces);
                    0.5 * (turn(&after_jolt) + turn(&bodies)) * h
                })
                .fold(0.0, f64::max);
            if closing > 0.0 {
                fit = fit.min(self.envelope_left() / closing);
            }
            // Likewise the piece pairs of two compounds that do not touch: each may close over
            // the step by at most its clearance above the rest gap.
            fit = fit.min(self.clearance_fit(island, &index, (&after_jolt, &bodies), h));
            // A speculative point's solve holds its mean speed over the step, which keeps its
            // gap at the end: a load that turns its approach around within the step (speed
            // u₀ < 0 at the start, u₁ > 0 at the end, changing linearly) takes the gap down to
            // its low point u₀²·h / (2·(u₁ − u₀)) below the start first. Past the gap, the
            // step is cut to half the length that reaches it and solved again: a coin's rim
            // slapping onto a plate at 0.12 m/s from 3.6 ε_c dipped 1.5 ε_c into the plate
            // within a 0.68 ms step whose every end-of-step gap was at ε_c or above.
            for (k, c) in contacts.iter().enumerate().filter(|(k, _)| speculative[*k]) {
                let (u0, u1) = (normal_speed(&after_jolt, c), normal_speed(&bodies, c));
                if u0 < 0.0 && u1 > 0.0 {
                    let dip = u0 * u0 * h / (2.0 * (u1 - u0));
                    if dip > raw_gaps[k] {
                        fit = fit.min(DIP_CUT * raw_gaps[k] / dip);
                    }
                }
            }
            if fit < 1.0 && tries <= MAX_LOCATE_SOLVES && h > settings.min_step {
                if tries == 1 {
                    counts.fitted_steps += 1;
                }
                let cut = (h * fit).max(settings.min_step);
                for (c, sol) in contacts.iter_mut().zip(&solved.1) {
                    c.impulse = sol.impulse * (cut / h);
                }
                h = cut;
                continue;
            }
            // A fast-turning island's contact points move over its bodies by up to half the
            // envelope a step: a slip → stick transition is not located within it.
            if tries > MAX_LOCATE_SOLVES || fast {
                break;
            }
            // Per manifold (its points share the normal and frame): the fraction of the step
            // that sliding friction on the whole patch takes to deliver the friction impulse
            // that stopped the slip, |Σ p_t| / (μ Σ p_n), for a patch slipping at the start of
            // the step and sticking at its end.
            // A transition whose rounding to the step's end moves its contact point by less
            // than the step tolerance is not located (module documentation of
            // [`crate::sustained`]): that is ½·u₀·h·(1 − s) for the slip u₀ at the start,
            // bounded by ½·u₀·h (the fraction s read from the impulses overestimates the
            // slip's time where a load outlasts it: a block stopping on a ramp, held by
            // friction for the rest of the step).
            let slip_tol = SLIP_FRACTION * v_micro;
            let drift_tol = settings.step_tolerance * eps;
            let mut s = 1.0_f64;
            let mut rounded = 0;
            for range in &patches {
                let (c0, c) = (&contacts[range.clone()], &solved.1[range.clone()]);
                let slip = c0
                    .iter()
                    .map(|c| tangential_speed(&after_jolt, c))
                    .fold(0.0, f64::max);
                let sticks = c.iter().all(|c| {
                    c.impulse.truncate().length() < STICK_FRACTION * c.friction * c.impulse.z
                });
                let total: DVec3 = c.iter().map(|c| c.impulse).sum();
                let cone = c[0].friction * total.z;
                if slip > slip_tol && sticks && cone > 0.0 {
                    let at = total.truncate().length() / cone;
                    if 0.5 * slip * h > drift_tol {
                        s = s.min(at);
                    } else {
                        rounded += 1;
                    }
                }
            }
            // Cut again while a patch still sticks inside its cone (several points share
            // a patch's load unevenly, so one cut may stop short).
            if s >= LOCATE_DONE {
                counts.rounded_transitions += rounded;
                break;
            }
            if !located {
                located = true;
                counts.located_steps += 1;
            }
            h = (s * h).max(MIN_STEP_FRACTION * settings.step);
            for (c, sol) in contacts.iter_mut().zip(&solved.1) {
                c.impulse = sol.impulse * s;
            }
        }
        let (predicted, solution) = solved;
        Ok(IslandPlan {
            h,
            ids,
            bodies,
            predicted,
            after_jolt,
            systems_after_jolt,
            sources,
            solution,
            origin,
            direct_outcome,
            key,
            backoff,
        })
    }

    /// The writing part of [`Self::step_island`]: the plan's direct-solve outcome, its
    /// bodies' velocities and held loads, its links' loads, its impulses for the next warm
    /// start; returns the step's length.
    fn apply_island(&mut self, plan: IslandPlan) -> Result<f64, SimError> {
        let IslandPlan {
            h,
            ids,
            bodies,
            predicted,
            after_jolt,
            systems_after_jolt,
            sources,
            solution,
            origin,
            direct_outcome,
            key,
            backoff,
        } = plan;
        match direct_outcome {
            Some(true) => {
                self.islands.direct_backoff.remove(&key);
            }
            Some(false) => {
                let failures = backoff.map_or(1, |(k, _)| k + 1);
                let skip = (2u32.pow(failures.min(8)) - 1).min(DIRECT_BACKOFF_MAX);
                let until = self.time + f64::from(skip) * h;
                self.islands.direct_backoff.insert(key, (failures, until));
            }
            None => {}
        }
        // Held loads: the impulse of the step spread over it.
        for (k, &i) in ids.iter().enumerate() {
            let b = self.b(i);
            if !b.is_dynamic() {
                continue;
            }
            let force = b.mass.map_or(DVec3::ZERO, |m| {
                m.mass * (bodies[k].velocity - predicted[k].velocity) / h
            });
            let torque = b.inertia_world() * (bodies[k].omega - predicted[k].omega) / h;
            let (v, w) = (after_jolt[k].velocity, after_jolt[k].omega);
            let (g, self_time) = (self.gravity, self.time);
            let b = self.b_mut(i);
            // An impulsive solve changed the velocity: every key of the body is stale.
            let jolted = b.velocity != v || b.omega != w;
            let change = if jolted {
                f64::INFINITY
            } else {
                b.mass
                    .map_or(0.0, |m| (force - b.held_force).length() / m.mass)
                    + (b.inverse_inertia_world() * (torque - b.held_torque)).length()
                        * b.max_reach()
            };
            b.velocity = v;
            b.omega = w;
            b.held_force = force;
            b.held_torque = torque;
            let (a, tau) = (b.acceleration(g), b.total_torque());
            let mut moved = false;
            if jolted || !b.envelope.is_some_and(|e| e.holds(a, tau)) {
                let e = Envelope::about(b, g, b.envelope.as_ref());
                b.envelope = Some(e);
                moved = true;
            } else if let Some(tight) = b.envelope.and_then(|e| e.tightened(b, g)) {
                // A subset of the envelope its keys hold for: they hold for it too.
                b.envelope = Some(tight);
            }
            // The held load is constant over the step, so the centre's speed within it is at
            // most the larger of its speeds at the ends: inside the far envelope's bound (as
            // it stands now: the bound only grows), the far pairs' keys hold through the step,
            // however hard the load pushes (a landing).
            let v_end = bodies[k].velocity;
            if b.far
                .is_some_and(|f| v.length().max(v_end.length()) > f.speed_at(self_time))
            {
                b.far = None;
                moved = true;
            }
            if moved {
                self.islands.moved.push(i);
            }
            self.islands.load_change.insert(i, change);
        }
        self.hold_link_loads(&sources, &systems_after_jolt, &after_jolt, &solution, h)?;
        // Keep each point's impulse for the next step's warm start.
        for (c, &(p, m, q)) in solution.iter().zip(&origin) {
            let world = self.contact_frame(c.normal)?.to_world(c.impulse);
            if let Some(held) = self.islands.held.get_mut(&p) {
                // Outside points keep no impulse.
                if m < held.impulses.len() {
                    held.impulses[m][q] = world;
                }
            }
        }
        Ok(h)
    }

    /// How fast another feature of a held contact's pair can approach with the island's
    /// bodies at velocities `v` (`ids`: their world ids), as [`super::hold::turn_speed`]
    /// measures a pair.
    /// `pieces`: the pieces of its manifold (body 2's, body 1's: the pair's order).
    fn contact_turn(&self, ids: &[u32], v: &[IslandBody], c: &Contact, pieces: (u32, u32)) -> f64 {
        let side = |k: usize, piece: u32| {
            TurnSide::of_piece(self.b(ids[k]), piece, v[k].velocity, v[k].omega)
        };
        let other = c.body2.map_or(TurnSide::NONE, |k| side(k, pieces.0));
        approach_speed(&side(c.body1, pieces.1), &other, Some(c.normal))
    }

    /// The fraction of a step of length `h` that keeps every island pair's piece pairs that
    /// do not touch ([`HeldPair::near`]) apart, their closing speed taken as the mean of the
    /// step's start and end (`v`: the island's velocities at both; `index`: world id to island
    /// body), each allowed its clearance above the rest gap; at least 1 when nothing closes.
    fn clearance_fit(
        &self,
        island: &Island,
        index: &FxHashMap<u32, usize>,
        v: (&[IslandBody], &[IslandBody]),
        h: f64,
    ) -> f64 {
        let rest = self.islands.settings.rest_gap_fraction * self.collision_epsilon();
        let mut fit = f64::INFINITY;
        for p in &island.pairs {
            let near = &self.islands.held[p].near;
            if near.measured.is_empty() && !near.unmeasured.is_finite() {
                continue;
            }
            let sides = |v: &[IslandBody]| {
                let side = |i: u32| {
                    let k = index[&i];
                    TurnSide::of(self.b(i), v[k].velocity, v[k].omega)
                };
                (side(p.0), side(p.1))
            };
            let ((a0, b0), (a1, b1)) = (sides(v.0), sides(v.1));
            fit = fit.min(clearance_bound(near, rest, 1.0, |d| {
                0.5 * (clearance_closing(&a0, &b0, d) + clearance_closing(&a1, &b1, d)) * h
            }));
        }
        fit
    }

    /// The solver's frame of a contact with this normal ([`Contact::impulse`] is in its
    /// axes).
    fn contact_frame(&self, normal: DVec3) -> Result<ContactFrame, SimError> {
        ContactFrame::from_normal(normal)
            .map_err(|e| self.runtime(format!("held contact normal: {e}")))
    }

    /// Velocities after a step of length `h` without contact: gravity, loads (the gyroscopic
    /// term is left to the rotation integrator).
    fn predict(&self, ids: &[u32], bodies: &mut [IslandBody], h: f64) {
        for (k, &i) in ids.iter().enumerate() {
            let b = self.b(i);
            let Some(m) = b.mass.filter(|_| b.is_dynamic()) else {
                continue;
            };
            bodies[k].velocity += (self.gravity + b.force / m.mass) * h;
            bodies[k].omega += b.inverse_inertia_world() * b.torque * h;
        }
    }

    /// Solves an island's contacts and counts what the solve did.
    fn solve(
        &self,
        bodies: &mut [IslandBody],
        systems: &mut [System],
        contacts: &mut [Contact],
        solver: &SolverSettings,
        c: &mut PlanCounts,
    ) -> Result<SolveReport, SimError> {
        let report = solve_island(bodies, systems, contacts, solver)
            .map_err(|e| self.runtime(format!("island contact solve: {e}")))?;
        c.island_solves += 1;
        c.island_sweeps += report.iterations as u64;
        c.unconverged_solves += u64::from(!report.converged);
        c.direct_solves += u64::from(report.direct);
        c.patch_jumps += u64::from(report.jumped);
        Ok(report)
    }

    /// Puts an island to sleep when all its bodies have moved slower than the sleep speed for
    /// the sleep time (bodies under load functions never sleep).
    fn sleep_if_still(&mut self, island: &Island) {
        let settings = self.islands.settings;
        let t = self.time;
        let mut all = true;
        for &i in &island.bodies {
            if self.is_still(i) {
                let since = *self.islands.still_since.entry(i).or_insert(t);
                all &= t - since >= settings.sleep_time;
            } else {
                self.islands.still_since.remove(&i);
                all = false;
            }
        }
        if all {
            for &i in &island.bodies {
                // A sleeping island has no clock until it wakes.
                self.islands.due.remove(i);
                let b = self.b_mut(i);
                b.asleep = true;
                b.velocity = DVec3::ZERO;
                b.omega = DVec3::ZERO;
                b.held_force = DVec3::ZERO;
                b.held_torque = DVec3::ZERO;
                b.envelope = None;
            }
            self.counters.sleeps += 1;
        }
    }
}

/// Relative normal speed of a contact (positive apart).
fn normal_speed(bodies: &[IslandBody], c: &Contact) -> f64 {
    relative_velocity(bodies, c).dot(c.normal.normalize())
}

/// Each body's side of a contact as a material point (`turns`: body 1's, body 2's) turning
/// with the body over a step of length `h` at its angular velocity ω: the lever arms at
/// mid-step, R(ω·h/2)·r, and what the arms' further turn to the step's end adds to body 1's
/// point velocity relative to body 2's, ω×(R(ω·h)·r − R(ω·h/2)·r). A smooth piece's contact
/// point is not material (a ball turning about its centre keeps its distance): its arm stays.
fn mid_arms(
    bodies: &[IslandBody],
    c: &Contact,
    turns: (bool, bool),
    h: f64,
) -> ((DVec3, DVec3), DVec3) {
    let side = |b: &IslandBody, material: bool| {
        let r = c.point - b.com;
        if !material {
            return (r, DVec3::ZERO);
        }
        let mid = DQuat::from_scaled_axis(b.omega * (0.5 * h)) * r;
        let end = DQuat::from_scaled_axis(b.omega * h) * r;
        (mid, b.omega.cross(end - mid))
    };
    let (arm1, bias1) = side(&bodies[c.body1], turns.0);
    let (arm2, bias2) = c
        .body2
        .map_or((DVec3::ZERO, DVec3::ZERO), |k| side(&bodies[k], turns.1));
    ((arm1, arm2), bias1 - bias2)
}

/// How far the turning of a contact's bodies moves body 1's point away from body 2's along
/// `n` over a step of length `h`, beyond what their velocities with the arms at the start
/// carry it: ½·h²·n·(ω₁×(ω₁×r₁) − ω₂×(ω₂×r₂)), for the material sides ([`mid_arms`]).
fn turning_drift(bodies: &[IslandBody], c: &Contact, turns: (bool, bool), h: f64, n: DVec3) -> f64 {
    let inward = |b: &IslandBody, material: bool| {
        if material {
            b.omega.cross(b.omega.cross(c.point - b.com))
        } else {
            DVec3::ZERO
        }
    };
    let a1 = inward(&bodies[c.body1], turns.0);
    let a2 = c.body2.map_or(DVec3::ZERO, |k| inward(&bodies[k], turns.1));
    0.5 * h * h * (a1 - a2).dot(n)
}

/// Relative tangential speed of a contact.
fn tangential_speed(bodies: &[IslandBody], c: &Contact) -> f64 {
    let n = c.normal.normalize();
    let u = relative_velocity(bodies, c);
    (u - n * u.dot(n)).length()
}

/// Velocity of body 1's point relative to body 2's at the contact point.
fn relative_velocity(bodies: &[IslandBody], c: &Contact) -> DVec3 {
    let at = |b: &IslandBody| b.velocity + b.omega.cross(c.point - b.com);
    let v1 = at(&bodies[c.body1]);
    let v2 = c.body2.map_or(DVec3::ZERO, |k| at(&bodies[k]));
    v1 - v2
}
