//! Bodies that move only when something looks at them.
//!
//! Thesis §2.4.3's `advance` moves every body to the end of every step of the loop. With n
//! bodies and events in proportion to n (a pile: a landing, a held pair, a check per body),
//! that is n² work: a pile of 216 boxes took 16 000 loop steps in its first simulated second,
//! each advancing all 216. A ballistic body's motion between its events is known in closed
//! form (its centre's parabola) or by its own integrator (its rotation), so it need not be
//! moved until something reads or changes its state.
//!
//! Each dynamic or scripted body keeps the time its state refers to (`Body::synced`), and
//! [`World::sync`] brings it to the world's time on demand. Every step of the loop that reads
//! or changes a body's state syncs it first: a pair's check and bound (both bodies), an
//! island step (every body of its pairs), a load function's evaluation, and, before anything
//! that reads every body (a controller's update, the checking monitor), all of them. A call
//! of [`World::step_until`] ends with every body at its time ([`World::sync_all`], in
//! parallel), so a program never sees a body behind. Fixed bodies and links (moved by their
//! multibody at every step) never lag; a sleeping body does not move, and is marked current
//! when it wakes.
//!
//! The broad phase does not need every body either: a body's box covers its motion up to a
//! horizon (`Body::box_until`: at least [`BOX_HORIZON`] ahead), computed from the motion its
//! keys assume (with an island body's load envelope, `envelope.rs`), and is replaced only when
//! the loop passes the horizon or the body's motion changes (every change that re-keys a
//! body's pairs also expires its box).
//!
//! Results depend only on the order of events, never on the thread count: a body advanced in
//! several pieces is advanced by the same pieces whatever runs in parallel.

use rayon::prelude::*;

use super::World;
use crate::body::{Body, BodyKind};
use crate::error::SimError;

/// How far ahead (s) a body's box in the broad phase covers its motion when it is replaced:
/// one nominal island step, so that a resting or sliding island body's box is replaced about
/// once per island step at most, and a box grows by what the body moves in a millisecond.
/// Default `1e-3`.
pub const BOX_HORIZON: f64 = 1e-3;

/// A time as a key that orders as the time does (every f64 but NaN, both signs, ±∞).
pub(super) fn order_key(t: f64) -> u64 {
    let bits = t.to_bits();
    if bits >> 63 == 1 {
        !bits
    } else {
        bits | (1 << 63)
    }
}

/// Whether `b` moves of itself between events, and so may lag behind the world's time.
fn lags(b: &Body) -> bool {
    matches!(b.kind, BodyKind::Dynamic | BodyKind::Scripted) && !b.asleep
}

impl World {
    /// Brings body `i` to the world's time.
    ///
    /// # Errors
    /// [`SimError::Runtime`] when its state stops being finite.
    pub(super) fn sync(&mut self, i: u32) -> Result<(), SimError> {
        let (t, g, integ) = (self.time, self.gravity, self.integrator);
        let b = self.b_mut(i);
        let dt = t - b.synced;
        if dt > 0.0 && lags(b) {
            if let Err(e) = b.advance(dt, g, &integ) {
                return Err(self.runtime(format!("body {}: {e}", self.name(i))));
            }
        }
        self.b_mut(i).synced = t;
        Ok(())
    }

    /// Brings both bodies of a pair to the world's time.
    ///
    /// # Errors
    /// As [`World::sync`].
    pub(super) fn sync_pair(&mut self, (a, b): (u32, u32)) -> Result<(), SimError> {
        self.sync(a)?;
        self.sync(b)
    }

    /// Brings every body to the world's time, in parallel when at least
    /// [`World::set_parallel_min_bodies`] of them lag (each body's result does not depend
    /// on the others or on the thread count).
    ///
    /// # Errors
    /// As [`World::sync`], naming the first body (in slot order) that failed.
    pub(super) fn sync_all(&mut self) -> Result<(), SimError> {
        let (t, g, integ) = (self.time, self.gravity, self.integrator);
        let lagging = self
            .slots
            .iter()
            .filter(|s| s.body.as_ref().is_some_and(|b| lags(b) && b.synced < t))
            .count();
        let step = |b: &mut Body| -> Option<String> {
            let dt = t - b.synced;
            let result = if dt > 0.0 && lags(b) {
                b.advance(dt, g, &integ).err().map(|e| e.to_string())
            } else {
                None
            };
            b.synced = t;
            result
        };
        let one_thread = self
            .pool
            .as_ref()
            .is_some_and(|p| p.current_num_threads() == 1);
        let serial = one_thread || lagging < self.parallel_min_bodies;
        let run = |slots: &mut [super::Slot]| -> Vec<Option<String>> {
            if serial {
                slots
                    .iter_mut()
                    .map(|s| s.body.as_mut().and_then(step))
                    .collect()
            } else {
                slots
                    .par_iter_mut()
                    .map(|s| s.body.as_mut().and_then(step))
                    .collect()
            }
        };
        // A serial pass never enters the pool: `install` alone waits on the pool's thread.
        let errors = match &self.pool {
            Some(pool) if !serial => {
                #[cfg(test)]
                {
                    self.faults.pool_steps += 1;
                }
                pool.install(|| run(&mut self.slots))
            }
            _ => run(&mut self.slots),
        };
        match errors
            .into_iter()
            .enumerate()
            .find_map(|(i, e)| e.map(|e| (i, e)))
        {
            Some((i, e)) => Err(self.runtime(format!("body {}: {e}", self.name(i as u32)))),
            None => Ok(()),
        }
    }

    /// Whether body `i`'s state is at the world's time (always, for a body that does not move
    /// of itself).
    pub(super) fn is_synced(&self, i: u32) -> bool {
        let b = self.b(i);
        !lags(b) || b.synced == self.time
    }

    /// Wakes body `i` (it was asleep, at rest): its state is the world's time's.
    pub(super) fn wake_body(&mut self, i: u32) {
        let t = self.time;
        let b = self.b_mut(i);
        b.asleep = false;
        b.synced = t;
        // Its far pairs' keys counted on it not moving.
        b.far = None;
        self.expire_box(i);
    }

    /// Body `i`'s motion changed: its box in the broad phase is replaced at the next step.
    pub(super) fn expire_box(&mut self, i: u32) {
        self.set_box_until(i, f64::NEG_INFINITY);
    }

    /// Body `i`'s box covers its motion up to `t`; the loop replaces it once it passes `t`
    /// (the queue of expiries: an entry whose time is no longer the body's is skipped).
    pub(super) fn set_box_until(&mut self, i: u32, t: f64) {
        self.b_mut(i).box_until = t;
        self.box_queue.push(std::cmp::Reverse((order_key(t), i)));
    }

    /// The bodies whose boxes do not cover up to `t_end`, in slot order, and every link (a
    /// multibody's check reads its link boxes of every step); taken off the queue.
    pub(super) fn boxes_expiring(&mut self, t_end: f64) -> Vec<u32> {
        let end = order_key(t_end);
        let mut due = Vec::new();
        while let Some(&std::cmp::Reverse((k, i))) = self.box_queue.peek() {
            if k >= end {
                break;
            }
            self.box_queue.pop();
            let current = self
                .slots
                .get(i as usize)
                .and_then(|s| s.body.as_ref())
                .is_some_and(|b| order_key(b.box_until) == k && !b.is_link() && lags(b));
            if current {
                due.push(i);
            }
        }
        for m in &self.multibodies {
            due.extend(m.links.iter().map(|&(_, slot)| slot));
        }
        due.sort_unstable();
        due.dedup();
        due
    }
}
