//! Where a run's wall time goes (thesis Table 7.2: forward dynamics, collision detection,
//! collision response): [`World::set_profiling`] turns on timers around the parts of the event
//! loop, [`World::profile`] reads them.

use std::time::{Duration, Instant};

use super::World;

/// Wall time spent in each part of the event loop since profiling was turned on.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Profile {
    /// Integrating the multibodies (their forward dynamics, passive elements and controller
    /// updates; thesis Table 7.2's "dynamics"), including redone steps.
    pub multibody_dynamics: Duration,
    /// Moving the free rigid bodies (closed-form flight, rotation integration).
    pub rigid_bodies: Duration,
    /// Collision detection: swept boxes and the broad phase, pair checks and their
    /// time-of-impact bounds.
    pub detection: Duration,
    /// Collision response: impulses of collisions and microcollisions (links included).
    pub response: Duration,
    /// The switching model's island steps (sustained contact as constraints).
    pub islands: Duration,
    /// High-level controllers' updates and the new bounds their commands need
    /// ([`World::add_controller`]; thesis Table 7.2's "control"; the joint controllers run
    /// inside their multibodies' integration and count as dynamics).
    pub control: Duration,
    /// Everything else in the loop (load functions, the checking monitor, bookkeeping).
    pub other: Duration,
    /// The whole of the loop's steps, and the bringing of every body to the requested time
    /// at the end of each [`World::step_until`] (timed as `rigid_bodies`): every part is
    /// inside it.
    pub total: Duration,
}

impl Profile {
    /// Each part's share of the total, in the order of the fields, with its name.
    #[must_use]
    pub fn shares(&self) -> [(&'static str, f64); 7] {
        let t = self.total.as_secs_f64().max(f64::MIN_POSITIVE);
        let s = |d: Duration| d.as_secs_f64() / t;
        [
            ("multibody dynamics", s(self.multibody_dynamics)),
            ("rigid bodies", s(self.rigid_bodies)),
            ("collision detection", s(self.detection)),
            ("collision response", s(self.response)),
            ("sustained contact (islands)", s(self.islands)),
            ("control", s(self.control)),
            ("other", s(self.other)),
        ]
    }
}

/// Which part a timer charges.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Part {
    Multibody,
    Rigid,
    Detection,
    Response,
    Islands,
    Control,
}

impl World {
    /// Turns the timers on (from zero) or off. Off by default: each costs two clock reads.
    pub fn set_profiling(&mut self, on: bool) {
        self.profile = on.then(Profile::default);
    }

    /// The timings so far (`None` unless [`World::set_profiling`] is on). `other` is the
    /// loop's total less the timed parts.
    #[must_use]
    pub fn profile(&self) -> Option<Profile> {
        self.profile.map(|mut p| {
            let timed = p.multibody_dynamics
                + p.rigid_bodies
                + p.detection
                + p.response
                + p.islands
                + p.control;
            p.other = p.total.saturating_sub(timed);
            p
        })
    }

    /// A clock reading when profiling is on.
    pub(crate) fn tick(&self) -> Option<Instant> {
        self.profile.is_some().then(Instant::now)
    }

    /// Charges the time since `start` to `part`.
    pub(crate) fn charge(&mut self, part: Part, start: Option<Instant>) {
        if let (Some(p), Some(s)) = (&mut self.profile, start) {
            let d = s.elapsed();
            match part {
                Part::Multibody => p.multibody_dynamics += d,
                Part::Rigid => p.rigid_bodies += d,
                Part::Detection => p.detection += d,
                Part::Response => p.response += d,
                Part::Islands => p.islands += d,
                Part::Control => p.control += d,
            }
        }
    }

    /// Charges the time since `start` to the loop's total.
    pub(crate) fn charge_total(&mut self, start: Option<Instant>) {
        if let (Some(p), Some(s)) = (&mut self.profile, start) {
            p.total += s.elapsed();
        }
    }
}
