//! Load envelopes of island bodies: heap keys that survive an island step.
//!
//! An island step ([`crate::sustained`]) gives each of its bodies a new held contact load, so
//! the body's motion model changes and every time-of-impact bound of its heap pairs, computed
//! for the old load, would be stale (thesis §2.4.3 re-keys a body's pairs after every change
//! of its motion). Re-keying all of them at every step — a closest-features query and a bound
//! per pair, for every pair of every island body, every millisecond — was most of the cost of
//! a pile (65 % of a pile of 216 boxes, by `perf`).
//!
//! Instead, an island body's keys are computed for a *set* of loads: its acceleration anywhere
//! within a ball of radius `accel_pad` about `accel`, and its torque no larger than
//! `torque_max` in magnitude ([`Envelope`]; the motion model is
//! [`impulse_collide::motion::Ballistic::with_acceleration_pad`] with the momentum bound on ‖ω‖
//! growing at `torque_max`/I_min). A key computed so bounds every path whose loads stay in the
//! set, whatever they do within it, so an island step whose new load stays inside needs no
//! new keys; one that leaves it (or changes a velocity, as an impulsive solve does) gets a new
//! envelope about its new load and re-keys the body's pairs. Keys computed for a set are
//! shorter than for one load; the pads trade that against how often a step leaves the set
//! ([`ENVELOPE_ACCEL_FLOOR`], [`ENVELOPE_GROWTH`]).
//!
//! The invariant: a body with an envelope has its actual load inside it, and every heap key of
//! its pairs was computed with it. Whatever sets a body's loads outside an island step (load
//! functions, the program, release from an island, sleep) clears the envelope and re-keys.

use glam::DVec3;

use crate::body::Body;

/// The least radius of the acceleration ball, relative to ‖g‖: a body resting on a pile has a
/// net acceleration near zero that its solver moves by a little at every step. Default `0.1`.
pub const ENVELOPE_ACCEL_FLOOR: f64 = 0.1;

/// The least torque bound, relative to m·‖g‖·r_max (the torque of the body's weight at its
/// farthest point). Default `0.1`.
pub const ENVELOPE_TORQUE_FLOOR: f64 = 0.1;

/// An envelope is tightened (`Envelope::tightened`, `FarEnvelope::tightened`) when it is this
/// many times looser than one made about the body's motion now would be. Tightening to a
/// subset costs nothing (every key computed for the looser one holds for the subset), so a
/// body whose load was large once (a landing) does not keep short keys for ever. Default
/// `2.0`.
pub const ENVELOPE_TIGHTEN: f64 = 2.0;

/// A new envelope's radius is this many times the change of acceleration (or its torque bound
/// this many times the new torque) that left the old one, when that exceeds the floor: a
/// body whose load moves by a lot keeps moving by about as much. Default `2.0`.
pub const ENVELOPE_GROWTH: f64 = 2.0;

/// The loads an island body's heap keys hold for (module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Envelope {
    /// Centre of the ball of accelerations (world, m/s²).
    pub(crate) accel: DVec3,
    /// Its radius (m/s²).
    pub(crate) accel_pad: f64,
    /// Bound on the magnitude of the total torque (N·m).
    pub(crate) torque_max: f64,
}

impl Envelope {
    /// Whether acceleration `a` and torque `tau` lie inside.
    pub(crate) fn holds(&self, a: DVec3, tau: DVec3) -> bool {
        a.distance(self.accel) <= self.accel_pad && tau.length() <= self.torque_max
    }

    /// A tighter envelope inside this one about `b`'s current load, when this one is more than
    /// [`ENVELOPE_TIGHTEN`] times looser than the floors (or the load's torque) ask: its ball
    /// lies inside this ball and its torque bound below this one, so every key computed for
    /// this one holds for it. `None` when this one is tight enough, or the load is outside.
    pub(crate) fn tightened(&self, b: &Body, g: DVec3) -> Option<Envelope> {
        let (a, tau) = (b.acceleration(g), b.total_torque());
        if !self.holds(a, tau) {
            return None;
        }
        let weight = b.mass.map_or(0.0, |m| m.mass) * g.length();
        let want_pad = ENVELOPE_ACCEL_FLOOR * g.length();
        let want_torque =
            (ENVELOPE_TORQUE_FLOOR * weight * b.r_max).max(ENVELOPE_GROWTH * tau.length());
        let off = a.distance(self.accel);
        let loose_pad = self.accel_pad > ENVELOPE_TIGHTEN * (want_pad + off);
        let loose_torque = self.torque_max > ENVELOPE_TIGHTEN * want_torque;
        if !(loose_pad || loose_torque) {
            return None;
        }
        let (accel, accel_pad) = if loose_pad {
            // The ball of radius `want_pad` about `a` lies inside: off + want_pad ≤ pad.
            (a, want_pad.max(f64::MIN_POSITIVE))
        } else {
            (self.accel, self.accel_pad)
        };
        Some(Envelope {
            accel,
            accel_pad,
            torque_max: if loose_torque {
                want_torque
            } else {
                self.torque_max
            },
        })
    }

    /// An envelope about `b`'s current load (gravity `g`), sized from how far that load moved
    /// from `previous` (the envelope it leaves, if any).
    pub(crate) fn about(b: &Body, g: DVec3, previous: Option<&Envelope>) -> Envelope {
        let a = b.acceleration(g);
        let tau = b.total_torque();
        let weight = b.mass.map_or(0.0, |m| m.mass) * g.length();
        let accel_floor = ENVELOPE_ACCEL_FLOOR * g.length();
        let torque_floor = ENVELOPE_TORQUE_FLOOR * weight * b.r_max;
        let moved = previous.map_or(0.0, |e| a.distance(e.accel));
        Envelope {
            accel: a,
            accel_pad: accel_floor.max(ENVELOPE_GROWTH * moved),
            torque_max: torque_floor.max(ENVELOPE_GROWTH * tau.length()),
        }
    }
}

/// The least speed bound of a far envelope, relative to √(‖g‖·r_max) (the speed of a fall
/// through the body's own radius). Default `0.1`.
pub const FAR_SPEED_FLOOR: f64 = 0.1;

/// The least acceleration bound of a far envelope, relative to ‖g‖: a body at rest may be let
/// go and fall at g, and its far pairs keep their keys then. Default `1.5`.
pub const FAR_ACCEL_FLOOR: f64 = 1.5;

/// Bounds on a body's centre-of-mass motion that the keys of its far pairs (bounded by their
/// spheres, `World::far_bound`) hold for: its speed at time t at most
/// `speed + accel·(t − since)` and its acceleration at most `accel` in magnitude. A far key
/// needs no direction and no load, so it stays valid through everything that keeps the body
/// inside these bounds — island steps, landings, held loads — and a pile's far pairs (most of
/// its heap: every body within the broad phase's tiles) are re-keyed only when a body moves
/// faster than its bounds allow, or teleports (the program), or wakes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct FarEnvelope {
    /// When the speed bound was `speed` (s).
    pub(crate) since: f64,
    /// Speed bound at `since` (m/s).
    pub(crate) speed: f64,
    /// Acceleration bound (m/s²).
    pub(crate) accel: f64,
}

impl FarEnvelope {
    /// The speed bound at time `t`.
    pub(crate) fn speed_at(&self, t: f64) -> f64 {
        self.speed + self.accel * (t - self.since).max(0.0)
    }

    /// Whether a centre moving at `v` with acceleration `a` at time `t` is inside. A body an
    /// island holds (`held`) is checked for speed alone: its island step checks the speed its
    /// held load reaches within each step, however large the load.
    pub(crate) fn holds(&self, t: f64, v: DVec3, a: DVec3, held: bool) -> bool {
        v.length() <= self.speed_at(t) && (held || a.length() <= self.accel)
    }

    /// The envelope about `b`'s motion now ([`FarEnvelope::about`]) when this one is more than
    /// [`ENVELOPE_TIGHTEN`] times looser in speed or acceleration and contains it from now on
    /// (its speed bound now and its acceleration bound no larger): every key computed for this
    /// one holds for it. `None` otherwise.
    pub(crate) fn tightened(&self, b: &Body, t: f64, g: DVec3) -> Option<FarEnvelope> {
        let new = FarEnvelope::about(b, t, g);
        let contained = new.speed <= self.speed_at(t) && new.accel <= self.accel;
        let loose = self.speed_at(t) > ENVELOPE_TIGHTEN * new.speed
            || self.accel > ENVELOPE_TIGHTEN * new.accel;
        (contained && loose).then_some(new)
    }

    /// An envelope about `b`'s current motion at time `t` (gravity `g`): twice its speed and
    /// its free acceleration ([`ENVELOPE_GROWTH`]), at least the floors. The acceleration
    /// bound is for the body in free flight; an island's held load may exceed it (its island
    /// step checks speeds instead).
    pub(crate) fn about(b: &Body, t: f64, g: DVec3) -> FarEnvelope {
        let (v, a) = if b.asleep {
            (0.0, 0.0)
        } else {
            let free = g + b.mass.map_or(DVec3::ZERO, |m| b.force / m.mass);
            (b.velocity.length(), free.length())
        };
        FarEnvelope {
            since: t,
            speed: (ENVELOPE_GROWTH * v).max(FAR_SPEED_FLOOR * (g.length() * b.r_max).sqrt()),
            accel: (ENVELOPE_GROWTH * a).max(FAR_ACCEL_FLOOR * g.length()),
        }
    }
}
