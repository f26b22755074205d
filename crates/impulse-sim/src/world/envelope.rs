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
