//! The event loop: one step of thesis §2.4.3's `advance` at a time (module documentation of
//! [`super`]).

use impulse_broadphase::BroadphaseError;
use impulse_collide::Motion;

use super::profile::Part;
use super::{Counters, MAX_CHECKS_WITHOUT_PROGRESS, MAX_STALLS_PER_INSTANT, StepReport, World};
use crate::body::BodyKind;
use crate::error::SimError;

impl World {
    /// Advances the world by `dt` (s) of simulated time ([`World::step_until`]).
    ///
    /// # Errors
    /// As [`World::step_until`].
    pub fn step(&mut self, dt: f64) -> Result<StepReport, SimError> {
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(SimError::Invalid {
                what: "step".into(),
                field: "dt".into(),
                problem: format!("{dt} must be finite and ≥ 0"),
            });
        }
        self.step_until(self.time + dt)
    }

    /// Advances the world to time `t` (nothing happens if `t` is not later than now) and
    /// reports what happened; [`World::contacts`] then lists the contacts resolved.
    ///
    /// A contact the response cannot resolve does not stop the run (see the module
    /// documentation of [`super`]).
    ///
    /// # Errors
    /// [`SimError::Invalid`] for a `t` that is not finite; [`SimError::Runtime`] when a body's
    /// state stops being finite (or its motion cannot be bounded), a load function returns a
    /// non-finite load, or the broad phase cannot hold a body. The world is then exactly as it
    /// was before the call (unless [`World::set_rollback`] turned that off: then it is where
    /// the failure was found).
    pub fn step_until(&mut self, t: f64) -> Result<StepReport, SimError> {
        if !t.is_finite() {
            return Err(SimError::Invalid {
                what: "step_until".into(),
                field: "t".into(),
                problem: format!("{t} is not a finite time"),
            });
        }
        let start = self.time;
        let before = self.counters();
        let checked_before = self.checked_penetration().map(|r| r.max_depth);
        if self.is_quiet_until(t) {
            // Nothing moves and nothing is due before `t`: the loop would take one step that
            // changes only the clock, and nothing in it can fail, so no backup is needed (a
            // world at rest costs no copy of itself per call).
            #[cfg(test)]
            {
                self.faults.quiet_calls += 1;
            }
            self.recent.clear();
            self.time = t;
            self.counters.steps += 1;
            self.stalled_checks = 0;
            self.stalls = 0;
            if let Some(mut monitor) = self.checking.take() {
                monitor.sample(self);
                self.checking = Some(monitor);
            }
            return Ok(self.report_since(start, &before, checked_before));
        }
        let backup = self.rollback.then(|| self.clone());
        self.recent.clear();
        let run = |w: &mut World| -> Result<(), SimError> {
            w.refuse_unbounded()?;
            w.rekey_stale()?;
            while w.time < t {
                w.loop_step(t)?;
            }
            // Every body at the time the program sees (`sync.rs`).
            // Charged to the total as well: the shares of `--profile` are of the total.
            let moving = w.tick();
            w.sync_all()?;
            w.charge(Part::Rigid, moving);
            w.charge_total(moving);
            Ok(())
        };
        if let Err(e) = run(self) {
            if let Some(backup) = backup {
                *self = backup;
            }
            return Err(e);
        }
        Ok(self.report_since(start, &before, checked_before))
    }

    /// What a `step_until` call that started at `start` with the counters `before` (and the
    /// checking monitor's depth `checked_before`, when it was on) did.
    fn report_since(
        &self,
        start: f64,
        before: &Counters,
        checked_before: Option<f64>,
    ) -> StepReport {
        StepReport {
            start,
            end: self.time,
            counters: difference(&self.counters(), before),
            contacts: self.recent.len(),
            checked_penetration: self
                .checked_penetration()
                .map(|r| r.max_depth)
                .filter(|_| checked_before.is_some()),
        }
    }

    /// Whether the world is quiet until `t`: later than now, no body moves (every one fixed or
    /// asleep; a scripted body moves), and nothing is due before `t` (no stale pair, no pair
    /// that became close, no heap key, load function or island step at or before `t`). The
    /// event loop would then take one step that only moves the clock.
    fn is_quiet_until(&self, t: f64) -> bool {
        #[cfg(test)]
        if self.faults.no_quiet_path {
            return false;
        }
        t > self.time
            && self.stale.is_empty()
            && self.slots.iter().all(|s| {
                s.body
                    .as_ref()
                    .is_none_or(|b| b.kind == BodyKind::Fixed || (b.is_dynamic() && b.asleep))
            })
            && self
                .hash
                .as_ref()
                .is_none_or(|(h, _)| !h.has_pending_changes())
            && self.heap.peek().is_none_or(|(_, key)| key > t)
            && self.next_load_time() > t
            && self.next_controller_time() > t
            && self.islands.next_step > t
    }

    /// Refuses a moving body whose motion cannot be bounded (its angular velocity's energy
    /// overflows, say, after the program set it): no time may pass with it. The loop checks the
    /// bodies that move at every step that moves them; a step that ends where it starts skips
    /// that, so the state the program left is checked here first.
    fn refuse_unbounded(&self) -> Result<(), SimError> {
        for slot in &self.slots {
            let Some(b) = &slot.body else { continue };
            if b.kind == BodyKind::Fixed || b.asleep {
                continue;
            }
            if let Motion::Unbounded { .. } = b.motion(self.gravity) {
                return Err(self.runtime(format!(
                    "body {}: its motion cannot be bounded (velocity {}, angular velocity {})",
                    b.name, b.velocity, b.omega
                )));
            }
        }
        Ok(())
    }

    /// Tight box of a fixed body, swept box of a moving one over `dt` from now; grown by ε_c so
    /// pairs within ε_c are close.
    pub(super) fn swept_box(&self, i: u32, dt: f64) -> impulse_geom::Aabb {
        let b = self.b(i);
        if b.kind == BodyKind::Fixed {
            return self.static_box(i);
        }
        b.motion(self.gravity)
            .swept_com_aabb(dt)
            .expanded(b.r_max + self.collision_epsilon())
    }

    pub(super) fn static_box(&self, i: u32) -> impulse_geom::Aabb {
        let b = self.b(i);
        if b.kind == BodyKind::Fixed {
            b.shape.aabb(&b.pose).expanded(self.collision_epsilon())
        } else {
            self.swept_box(i, 0.0)
        }
    }

    /// The next time a load function is due (∞ without any).
    fn next_load_time(&self) -> f64 {
        self.loads
            .iter()
            .map(super::LoadSchedule::next_time)
            .fold(f64::INFINITY, f64::min)
    }

    /// One step of the `advance` algorithm (module documentation of [`super`]), ending no
    /// later than `limit`.
    fn loop_step(&mut self, limit: f64) -> Result<(), SimError> {
        let started = self.tick();
        let result = self.loop_step_inner(limit);
        self.charge_total(started);
        result
    }

    fn loop_step_inner(&mut self, limit: f64) -> Result<(), SimError> {
        let t0 = self.time;
        let mut t_end = self
            .heap
            .peek()
            .map_or(limit, |(_, k)| k.min(limit))
            .min(self.next_load_time())
            .min(self.next_controller_time())
            .min(self.next_multibody_control(t0))
            .min(self.islands.next_step.max(t0));
        // 2. Boxes in the broad phase for every body whose box does not cover the step
        // (`sync.rs`), and the pairs that became close. A step that ends where it starts (a
        // pair due now, an island step now) moves nothing: the boxes cover this instant.
        let detecting = self.tick();
        let instant = t_end <= t0;
        if !instant {
            self.refresh_boxes(t0, &mut t_end)?;
            self.promote_new_pairs()?;
        }
        self.box_span = (t_end - t0).max(0.0);
        self.charge(Part::Detection, detecting);
        if let Some((_, k)) = self.heap.peek() {
            t_end = t_end.min(k);
        }
        t_end = t_end.max(t0);
        // 3. Dynamic evolution: the multibodies first, since checking their predictions may
        // bring the end of the step earlier (thesis §5.2); then every other body.
        let integrating = self.tick();
        self.advance_multibodies(t0, &mut t_end)?;
        self.charge(Part::Multibody, integrating);
        // The other bodies move when something reads or changes them (`sync.rs`).
        if t_end > t0 {
            self.stalled_checks = 0;
            self.stalls = 0;
        }
        self.time = t_end;
        self.counters.steps += 1;
        // Loads due now change the bodies' motions: new bounds for their pairs.
        if self.next_load_time() <= self.time {
            self.evaluate_due_loads()?;
            self.rekey_stale()?;
        }
        // High-level controllers due now (scheduled as the loads are).
        if self.next_controller_time() <= self.time {
            let controlling = self.tick();
            self.sync_all()?;
            self.update_due_controllers()?;
            self.rekey_stale()?;
            self.charge(Part::Control, controlling);
        }
        // Island steps due now (the switching contact model) set new held loads, once every
        // pair due at this instant has been checked: pairs found touching at one instant (a
        // stack placed in contact, a cluster of collisions) join their islands first, and
        // each island takes one solve instead of one per pair.
        let pair_due = self.heap.peek().is_some_and(|(_, key)| key <= self.time);
        if self.islands.next_step <= self.time && !pair_due {
            let stepping = self.tick();
            self.island_step()?;
            let until = self.islands.next_step;
            self.precheck_until(until)?;
            self.charge(Part::Islands, stepping);
        }
        // 4. Check the top pair if it is due.
        if let Some((pair, key)) = self.heap.peek() {
            if key <= self.time {
                self.stalled_checks += 1;
                if self.stalled_checks > MAX_CHECKS_WITHOUT_PROGRESS {
                    self.stalls += 1;
                    if self.stalls > MAX_STALLS_PER_INSTANT {
                        return Err(self.runtime(format!(
                            "the run is stuck: {MAX_STALLS_PER_INSTANT} stalls of \
                             {MAX_CHECKS_WITHOUT_PROGRESS} checks at one instant (last pair {} / {})",
                            self.name(pair.0),
                            self.name(pair.1)
                        )));
                    }
                    self.break_stall(pair)?;
                } else {
                    let responded = self.profile.map(|p| p.response);
                    let checking = self.tick();
                    self.check_top(pair)?;
                    // The check's time less the response's within it.
                    if let (Some(p), Some(s), Some(r0)) = (&mut self.profile, checking, responded) {
                        p.detection += s.elapsed().saturating_sub(p.response - r0);
                    }
                }
            }
        }
        if self.checking.is_some() {
            self.sync_all()?;
            if let Some(mut monitor) = self.checking.take() {
                monitor.sample(self);
                self.checking = Some(monitor);
            }
        }
        Ok(())
    }

    /// Replaces the broad-phase box of every moving body whose box does not cover the step
    /// `[t0, t_end]`: a dynamic or scripted body's over [`super::BOX_HORIZON`] or the step,
    /// whichever is longer (it is brought to now first), a link's over the step (its
    /// multibody's check reads the box of the step); `box_until` records how far it covers.
    /// Halves the step while a box would cover too many tiles even over the step alone.
    fn refresh_boxes(&mut self, t0: f64, t_end: &mut f64) -> Result<(), SimError> {
        let (g, eps) = (self.gravity, self.collision_epsilon());
        for i in self.boxes_expiring(*t_end) {
            let Some(b) = &self.slots[i as usize].body else {
                continue;
            };
            // A sleeping body does not move: its box stays the one it fell asleep with, as a
            // fixed body's does (waking expires it).
            if b.kind == BodyKind::Fixed || b.asleep {
                continue;
            }
            let link = b.is_link();
            if !link {
                self.sync(i)?;
            }
            let b = self.b(i);
            let motion = b.motion(g);
            if let Motion::Unbounded { .. } = motion {
                return Err(self.runtime(format!(
                    "body {}: its motion cannot be bounded (velocity {}, angular velocity {})",
                    b.name, b.velocity, b.omega
                )));
            }
            let grow = b.r_max + eps;
            // Over the horizon, else over the step alone, else over half the step (for every
            // body after it too: a box made for a longer step covers a shorter one).
            loop {
                let step = *t_end - t0;
                let long = if link {
                    step
                } else {
                    step.max(super::BOX_HORIZON)
                };
                let mut covered = None;
                for span in [long, step] {
                    let bx = motion.swept_com_aabb(span).expanded(grow);
                    match self.hash_mut().update(i, bx) {
                        Ok(()) => {
                            covered = Some(span);
                            break;
                        }
                        Err(BroadphaseError::TooManyCells { .. }) => {}
                        Err(e) => {
                            return Err(
                                self.runtime(format!("broad phase, body {}: {e}", self.name(i)))
                            );
                        }
                    }
                }
                match covered {
                    Some(span) => {
                        if !link {
                            self.set_box_until(i, t0 + span);
                        }
                        break;
                    }
                    None if step > 0.0 => *t_end = t0 + 0.5 * step,
                    None => {
                        return Err(self.runtime(format!(
                            "broad phase, body {}: its box covers too many tiles",
                            self.name(i)
                        )));
                    }
                }
            }
        }
        Ok(())
    }

    /// Inserts every pair that became close (thesis §2.4.3, 0→1) into the heap.
    pub(super) fn promote_new_pairs(&mut self) -> Result<(), SimError> {
        let Some((hash, _)) = &mut self.hash else {
            return Ok(());
        };
        for (a, b) in hash.take_new_close_pairs() {
            if !self.pair_matters(a, b) || self.heap.contains((a, b)) {
                continue;
            }
            let key = self.bound((a, b))?;
            self.heap
                .insert((a, b), key)
                .map_err(|e| self.runtime(format!("collision heap: {e}")))?;
            self.counters.pairs_promoted += 1;
        }
        Ok(())
    }

    /// Evaluates every load function that is due now and holds its load until the next
    /// evaluation.
    pub(super) fn evaluate_due_loads(&mut self) -> Result<(), SimError> {
        for k in 0..self.loads.len() {
            let (i, due) = (self.loads[k].body, self.loads[k].next_time());
            if due > self.time {
                continue;
            }
            self.sync(i)?;
            let state = self.b(i).state();
            let load = (self.loads[k].f)(self.time, &state);
            if !(load.force.is_finite() && load.torque.is_finite()) {
                return Err(self.runtime(format!(
                    "the load function of body {} gave {load:?}",
                    self.name(i)
                )));
            }
            let l = &mut self.loads[k];
            // Skip evaluations that fell between two steps (a rate above the loop's).
            while l.next_time() <= self.time {
                l.evaluations += 1;
            }
            self.counters.load_evaluations += 1;
            let b = self.b_mut(i);
            b.force = load.force;
            b.torque = load.torque;
            self.mark_stale(i);
        }
        Ok(())
    }

    /// Checks now every heap pair due within the coming island pass, up to `until` (the next
    /// island step), instead of one loop step each at its key: checking a pair early is
    /// conservative (its new bound is a bound from now), and each check at its key would cost
    /// a step of the whole loop — every moving body advanced — for a pair that mostly turns
    /// out still apart. A pair's key becomes the later of its old and new bounds (both are
    /// lower bounds on when it can close its gap), or now when the check finds it to hold
    /// at once ([`World::bound`]); a pair that can still close within the pass keeps a key
    /// inside it and is checked at its key, as before. Pairs due now are left to the top.
    fn precheck_until(&mut self, until: f64) -> Result<(), SimError> {
        let now = self.time;
        if !(until > now && until.is_finite()) {
            return Ok(());
        }
        for (pair, old) in self.heap.due_before(until) {
            if old <= now || self.is_held(pair) {
                continue;
            }
            let Some(fresh) = self.rebound(pair)? else {
                continue;
            };
            let key = fresh.max(old);
            self.heap
                .set_toi(pair, key)
                .map_err(|e| self.runtime(format!("collision heap: {e}")))?;
        }
        Ok(())
    }

    /// New bounds for every heap pair of the bodies the program (or a load) changed.
    fn rekey_stale(&mut self) -> Result<(), SimError> {
        let stale = std::mem::take(&mut self.stale);
        self.rekey(&stale, None)
    }
}

/// `a − b` for the counters that count (the extremes are taken from `a`).
fn difference(a: &Counters, b: &Counters) -> Counters {
    Counters {
        steps: a.steps - b.steps,
        pair_checks: a.pair_checks - b.pair_checks,
        cached_bounds: a.cached_bounds - b.cached_bounds,
        collisions: a.collisions - b.collisions,
        microcollisions: a.microcollisions - b.microcollisions,
        reversing: a.reversing - b.reversing,
        unresolved: a.unresolved - b.unresolved,
        pairs_promoted: a.pairs_promoted - b.pairs_promoted,
        heap_operations: a.heap_operations - b.heap_operations,
        load_evaluations: a.load_evaluations - b.load_evaluations,
        touching_checks: a.touching_checks - b.touching_checks,
        min_distance: a.min_distance,
        max_penetration: a.max_penetration,
        island_steps: a.island_steps - b.island_steps,
        long_steps: a.long_steps - b.long_steps,
        turning_steps: a.turning_steps - b.turning_steps,
        struck_steps: a.struck_steps - b.struck_steps,
        fitted_steps: a.fitted_steps - b.fitted_steps,
        located_steps: a.located_steps - b.located_steps,
        rounded_transitions: a.rounded_transitions - b.rounded_transitions,
        transients: a.transients - b.transients,
        sleeps: a.sleeps - b.sleeps,
        island_solves: a.island_solves - b.island_solves,
        island_sweeps: a.island_sweeps - b.island_sweeps,
        unconverged_solves: a.unconverged_solves - b.unconverged_solves,
        direct_solves: a.direct_solves - b.direct_solves,
        patch_jumps: a.patch_jumps - b.patch_jumps,
        rollbacks: a.rollbacks - b.rollbacks,
        box_violations: a.box_violations - b.box_violations,
        slack_violations: a.slack_violations - b.slack_violations,
        unchecked_steps: a.unchecked_steps - b.unchecked_steps,
        link_contacts: a.link_contacts - b.link_contacts,
        controller_updates: a.controller_updates - b.controller_updates,
    }
}
