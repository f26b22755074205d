//! The multibodies' part of a step of the event loop (thesis §5.2, Figs. 5.3 and 5.4).
//!
//! A link's swept box and time-of-impact coefficients are predictions, not bounds
//! ([`impulse_collide::motion::LinkMotion`]). So each step integrates every multibody on a
//! copy first, recording the range of each link's states at every derivative evaluation, and
//! checks the predictions against it:
//!
//! - **box**: the link's seen path must lie in the swept box the broad phase was given;
//! - **slack**: for every heap pair of the link, its travel toward the other body since the
//!   pair's bound was computed (δ, accumulated step by step from Fig. 5.4's worst-case speed
//!   along the pair's direction) must not exceed what the pair's coefficients allowed,
//!   `A (t − t_b)² + B (t − t_b)`.
//!
//! When every check passes, the copies become the multibodies. Otherwise the step is undone
//! (the copies are dropped: the world has not moved), each failing link's prediction is
//! widened by the motion now known (its seen speeds and path), its box is replaced, new close
//! pairs are promoted and its pairs get new bounds from the widened prediction; the step is
//! then done again to the heap's top, which can only have come earlier. A redone step whose
//! end did not move sees the same motion, which the widened predictions cover. Every
//! violation and redo is counted ([`super::Counters`]).

use glam::DVec3;
use impulse_collide::Motion;
use impulse_collide::motion::SeenSpeeds;
use impulse_geom::Aabb;
use impulse_multibody::{LinkTravel, TravelSample};

use super::World;
use crate::error::SimError;

/// Redos of one step before its result is taken unchecked (and counted in
/// [`super::Counters::unchecked_steps`]). Each redo widens a failing link's prediction to the
/// motion seen, so a second redo is rare; the cap guards the loop. Default `16`.
pub const MAX_STEP_REDOS: u32 = 16;

/// How far a link's recorded states may leave the box predicted for it before its step is
/// redone, at least (fraction of ε_c). The states are recorded at every derivative
/// evaluation, and a Runge–Kutta stage state is an extrapolation off the true path by up to
/// about ½·|a|·h² (a wheel bouncing on microcollisions, near the top of each hop, left its
/// padded box by 3e-10 m at ε_c = 1e-4 at most steps: 57 663 box violations and 34 201
/// redone steps in 3 s of a rover driving). The allowance is that bound for the step, at
/// least this fraction of ε_c and at most [`BOX_STAGE_MAX_FRACTION`] of it. Default `0.01`.
pub const BOX_STAGE_FRACTION: f64 = 0.01;

/// The largest allowance of [`BOX_STAGE_FRACTION`]'s kind (fraction of ε_c): the box the
/// broad phase holds is grown by ε_c on every body, so a link outside its box by less than
/// half of it is still found close to every body within ε_c. Default `0.5`.
pub const BOX_STAGE_MAX_FRACTION: f64 = 0.5;

/// Padding of the acceleration in the stage allowance (dimensionless), as the box pads it.
const LINK_STAGE_PADDING: f64 = 1.1;

/// Rounding allowance of a slack check, relative to the travel compared (dimensionless):
/// the accumulated travel and the allowance are sums of a few products. Default `1e-9`.
pub const SLACK_ROUNDING_REL: f64 = 1e-9;

/// The slack structure of one side of a pair (thesis §5.2.2): the prediction a pair's bound
/// was made from, and the travel seen since.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Slack {
    /// Direction of this side's travel toward the other body (world, unit).
    d: DVec3,
    /// Reach of rotation on the piece (m).
    reach: f64,
    /// The coefficients the bound used for this side.
    a: f64,
    b: f64,
    /// When the bound was made.
    t_b: f64,
    /// Worst-case travel along `d` since `t_b`.
    delta: f64,
    /// When `delta` was last brought up to date.
    t_l: f64,
}

impl Slack {
    /// The travel the bound allowed by time `t`.
    fn allowance(&self, t: f64) -> f64 {
        let s = t - self.t_b;
        self.a * s * s + self.b * s
    }

    /// `delta` brought from `t_l` up to `t` along the sampled states `path` (world times,
    /// in order), and whether it stayed within the allowance at every sample (thesis Fig.
    /// 5.4 updateSlack). Fig. 5.4 adds the largest speed seen times the whole interval, which
    /// for a link under constant acceleration exceeds the 1.2-padded ½a τ² of the bound
    /// whenever the interval is longer than v₀/(2a): a link resting by microcollisions failed
    /// its slack at almost every step (80 000 redos per simulated second, measured). Here the
    /// per-instant speed bound `v·d̂ + r Σ|ω_c|‖e_c × d̂‖` is integrated over the samples by
    /// the trapezoid rule instead, and checked at each sample, not only at the end: still
    /// "conservative with respect to the sampled values", as the thesis says of its own.
    fn update(&self, path: &[TravelSample], t: f64) -> (f64, bool) {
        let mut delta = self.delta;
        let mut ok = true;
        let mut prev: Option<(f64, f64)> = None;
        let check = |delta: f64, at: f64, speed: f64, span: f64| {
            let allow = self.allowance(at);
            let tol = SLACK_ROUNDING_REL
                * (delta.abs() + allow.abs() + (speed.abs() + self.b.abs()) * span.abs());
            delta <= allow + tol
        };
        for s in path.iter().filter(|s| s.t >= self.t_l && s.t <= t) {
            let k = s.speed_along(self.d, self.reach);
            let (tp, kp) = prev.unwrap_or((self.t_l, k));
            delta += 0.5 * (k + kp) * (s.t - tp);
            ok &= check(delta, s.t, k, s.t - self.t_l);
            prev = Some((s.t, k));
        }
        if let Some((tp, kp)) = prev {
            delta += kp * (t - tp).max(0.0);
            ok &= check(delta, t, kp, t - self.t_l);
        }
        (delta, ok)
    }
}

/// The travel a link's side of a pair took over a trial step, as its slack check found it.
struct SlackTaken {
    pair: (u32, u32),
    slot: u32,
    delta: f64,
}

/// One multibody's trial step: its simulation at the step's end, every link's travel over
/// the step, and its links' kinematics at the end.
type Trial = (
    impulse_multibody::Simulation,
    Vec<LinkTravel>,
    Vec<impulse_multibody::LinkKinematics>,
);

/// Fig. 5.4's view of a recorded travel.
fn seen(t: &LinkTravel) -> SeenSpeeds {
    SeenSpeeds {
        velocity_min: t.velocity_min,
        velocity_max: t.velocity_max,
        omega_abs_max: t.omega_abs_max,
        path: Aabb {
            min: t.origin_min,
            max: t.origin_max,
        },
    }
}

impl World {
    /// Records, for each link side of pair `(a, b)` just given a bound from its closest
    /// piece pair (`pieces`, normal `n` from b toward a, the two `motions`), the prediction
    /// the bound rests on; clears it when there is no normal (the pair is due now).
    pub(super) fn note_slack(
        &mut self,
        (a, b): (u32, u32),
        n: Option<DVec3>,
        pieces: (usize, usize),
        motions: (Motion, Motion),
        gap: f64,
    ) {
        let (la, lb) = (self.b(a).is_link(), self.b(b).is_link());
        if !(la || lb) {
            return;
        }
        let time = self.time;
        let side = |w: &World, i: u32, piece: usize, motion: &Motion, d: Option<DVec3>| {
            let d = d?;
            let reach = w.b(i).reach[piece];
            let (ca, cb) = motion.toi_coefficients(d, reach, gap);
            Some(Slack {
                d,
                reach,
                a: ca,
                b: cb,
                t_b: time,
                delta: 0.0,
                t_l: time,
            })
        };
        let sa = if la {
            side(self, a, pieces.0, &motions.0, n.map(|n| -n))
        } else {
            None
        };
        let sb = if lb {
            side(self, b, pieces.1, &motions.1, n)
        } else {
            None
        };
        if let Some(state) = self.pairs.get_mut(&(a, b)) {
            state.slack = [sa, sb];
        }
    }

    /// The next joint-controller update of any multibody after `t0` (world time; ∞ without
    /// one). A loop step ends there (thesis §5.4: control updates are events in the heap), so
    /// each step's link predictions start from the torques that hold over it. (Measured on a
    /// rover driving with 200 Hz wheel loops, this alone did not change its redone steps:
    /// those came from the integrator's stage states, [`BOX_STAGE_FRACTION`].)
    pub(super) fn next_multibody_control(&self, t0: f64) -> f64 {
        self.multibodies
            .iter()
            .map(|m| m.offset + m.sim.next_control_time())
            .filter(|&t| t > t0)
            .fold(f64::INFINITY, f64::min)
    }

    /// One multibody's trial step from `t0` to `t_end` on a copy, with the states it passes
    /// through; `strike`: stop at the first joint stop struck (the time reached is then
    /// earlier, and returned).
    fn multibody_trial(
        &self,
        mi: usize,
        t0: f64,
        t_end: f64,
        strike: bool,
    ) -> Result<(Trial, f64), SimError> {
        let m = &self.multibodies[mi];
        let fail = |e: impulse_multibody::MultibodyError| {
            self.runtime(format!("multibody {}: {e}", m.name))
        };
        let mut sim = m.sim.clone();
        let _ = sim.take_travel();
        let local = m.local(t_end);
        let reached = if strike {
            let at = sim.run_until_strike(local).map_err(fail)?;
            if at < local { m.offset + at } else { t_end }
        } else {
            sim.run_until(local).map_err(fail)?;
            t_end
        };
        let end = sim.link_kinematics().map_err(fail)?;
        let mut travel = sim.take_travel().unwrap_or_default();
        for &(id, slot) in &m.links {
            let (k, b) = (&end[id.index()], self.b(slot));
            let t = &mut travel[id.index()];
            // World times, in order, with the step's two ends.
            for s in &mut t.path {
                s.t += m.offset;
            }
            t.add(reached, k.pose.translation, k.velocity, k.omega);
            t.add(t0, b.pose.translation, b.velocity, b.omega);
            t.path.sort_by(|x, y| x.t.total_cmp(&y.t));
        }
        Ok(((sim, travel, end), reached))
    }

    /// The multibodies' part of the step from `t0` to `t_end` (module documentation): may
    /// bring `t_end` earlier. Leaves every multibody and its link bodies at `t_end`.
    ///
    /// A multibody some of whose links an island holds ends the step at its first joint stop
    /// struck (`held_links.rs`): the strike changes its velocity at once, and its island
    /// steps at that instant, before its held loads, solved for the velocity before, act on
    /// (the see-saw's plank bouncing on its stop under a held ball sank it 0.15 ε_c).
    ///
    /// # Errors
    /// [`SimError::Runtime`] when a multibody cannot be integrated (naming it), or from the
    /// broad phase and the heap.
    pub(super) fn advance_multibodies(&mut self, t0: f64, t_end: &mut f64) -> Result<(), SimError> {
        if self.multibodies.is_empty() {
            return Ok(());
        }
        let g = self.gravity;
        let mut redos = 0;
        let held: Vec<bool> = (0..self.multibodies.len())
            .map(|mi| {
                self.multibodies[mi]
                    .links
                    .iter()
                    .any(|&(_, slot)| self.is_held_body(slot))
            })
            .collect();
        let mut struck: Vec<usize> = Vec::new();
        loop {
            if *t_end <= t0 {
                return Ok(());
            }
            // The trial: each multibody on a copy, with the states it passes through; a held
            // one up to its first strike, which ends the step for all.
            let mut trials = Vec::with_capacity(self.multibodies.len());
            let mut reached = Vec::with_capacity(self.multibodies.len());
            for (mi, &strike) in held.iter().enumerate() {
                let (trial, at) = self.multibody_trial(mi, t0, *t_end, strike)?;
                trials.push(trial);
                reached.push(at);
            }
            let earliest = reached.iter().copied().fold(*t_end, f64::min);
            struck.clear();
            if earliest < *t_end {
                *t_end = earliest;
                for mi in 0..trials.len() {
                    if reached[mi] == earliest {
                        struck.push(mi);
                    } else {
                        trials[mi] = self.multibody_trial(mi, t0, earliest, false)?.0;
                    }
                }
            }
            // The checks; the travel each pair's slack takes is kept for the commit.
            let mut widen = Vec::new();
            let mut taken: Vec<SlackTaken> = Vec::new();
            let (mut boxes, mut slacks) = (0, 0);
            for (mi, (_, travel, _)) in trials.iter().enumerate() {
                for &(id, slot) in &self.multibodies[mi].links {
                    let t = &travel[id.index()];
                    let motion = self.b(slot).motion(g);
                    let eps = self.collision_epsilon();
                    // The stage states' error for this step: ½·|a|·h², padded as the box is.
                    let stage = match motion {
                        Motion::Link(m) => {
                            0.5 * LINK_STAGE_PADDING
                                * m.acceleration().length()
                                * self.box_span.powi(2)
                        }
                        _ => 0.0,
                    };
                    let allowance = stage
                        .max(BOX_STAGE_FRACTION * eps)
                        .min(BOX_STAGE_MAX_FRACTION * eps);
                    let predicted = motion.swept_com_aabb(self.box_span).expanded(allowance);
                    let boxed = predicted.contains_point(t.origin_min)
                        && predicted.contains_point(t.origin_max);
                    // A held pair has no bound to keep (the islands hold it).
                    let mut slacked = true;
                    for p in self.heap.pairs_of(slot).filter(|p| !self.is_held(*p)) {
                        if let Some(s) = self.slack_of(p, slot) {
                            let (delta, ok) = s.update(&t.path, *t_end);
                            taken.push(SlackTaken {
                                pair: p,
                                slot,
                                delta,
                            });
                            slacked &= ok;
                        }
                    }
                    boxes += u64::from(!boxed);
                    slacks += u64::from(!slacked);
                    if !(boxed && slacked) {
                        widen.push((slot, seen(t)));
                    }
                }
            }
            if widen.is_empty() || redos >= MAX_STEP_REDOS {
                if !widen.is_empty() {
                    self.counters.unchecked_steps += 1;
                }
                self.commit_multibodies(trials, *t_end, &taken)?;
                // A struck multibody's islands step now, from its velocity after the strike.
                for &mi in &struck {
                    for slot in self.link_slots(mi) {
                        if self.is_held_body(slot) {
                            self.step_now(slot);
                        }
                    }
                }
                return Ok(());
            }
            redos += 1;
            self.counters.rollbacks += 1;
            self.counters.box_violations += boxes;
            self.counters.slack_violations += slacks;
            // Undo: the copies are dropped. Widen each failing link's prediction by what it
            // did, and give its pairs (and any pair its true box makes close) new bounds.
            let slots: Vec<u32> = widen.iter().map(|&(s, _)| s).collect();
            for (slot, seen) in widen {
                let name = self.name(slot).to_owned();
                let b = self.b_mut(slot);
                if let Some(Motion::Link(m)) = b.script {
                    let m = m.with_seen(seen).map_err(|e| SimError::Runtime {
                        time: t0,
                        message: format!("link body {name}: {e}"),
                    })?;
                    b.script = Some(Motion::Link(m));
                }
                let bx = self.swept_box(slot, self.box_span);
                self.hash_mut()
                    .update(slot, bx)
                    .map_err(|e| self.runtime(format!("broad phase, body {name}: {e}")))?;
            }
            self.promote_new_pairs()?;
            self.rekey(&slots, None)?;
            if let Some((_, k)) = self.heap.peek() {
                *t_end = t_end.min(k).max(t0);
            }
        }
    }

    /// The slack of `slot`'s side of heap pair `p`.
    fn slack_of(&self, p: (u32, u32), slot: u32) -> Option<Slack> {
        let side = usize::from(p.0 != slot);
        self.pairs.get(&p).and_then(|s| s.slack[side])
    }

    /// Makes the trial the multibodies' state at `t_end`: every link pair's slack takes the
    /// step's travel (as the checks found it, `taken`, in the order they visited the
    /// pairs, or found now for the pairs they skipped), and the link bodies move to their
    /// links (at the kinematics the trial ended with).
    fn commit_multibodies(
        &mut self,
        trials: Vec<Trial>,
        t_end: f64,
        taken: &[SlackTaken],
    ) -> Result<(), SimError> {
        let mut taken = taken.iter().peekable();
        for (mi, (sim, travel, end)) in trials.into_iter().enumerate() {
            for k in 0..self.multibodies[mi].links.len() {
                let (id, slot) = self.multibodies[mi].links[k];
                let t = &travel[id.index()];
                let pairs: Vec<(u32, u32)> = self.heap.pairs_of(slot).collect();
                for p in pairs {
                    let side = usize::from(p.0 != slot);
                    let checked = taken
                        .next_if(|k| k.pair == p && k.slot == slot)
                        .map(|k| k.delta);
                    if let Some(state) = self.pairs.get_mut(&p) {
                        if let Some(s) = &mut state.slack[side] {
                            s.delta = checked.unwrap_or_else(|| s.update(&t.path, t_end).0);
                            s.t_l = t_end;
                        }
                    }
                }
            }
            self.multibodies[mi].sim = sim;
            self.place_links(mi, &end)?;
        }
        Ok(())
    }
}
